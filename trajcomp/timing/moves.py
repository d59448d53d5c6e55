"""The motion sequence re-timing works on: the joints of every waypoint and what each motion asks.

A `Moves` holds M waypoints in motion order. Waypoint k (k >= 1) is reached
by motion k from waypoint k - 1, with that motion's kind, speed, zone and
tool; waypoint 0, and every waypoint flagged ``start``, is where the arm is
when a timed stretch begins (the motion into it starts from a position the
program does not state, so it is not timed).

`moves_from_program` maps a `Program` and the joints of its targets onto
this; `Moves.from_joints` builds one for a joint path (a CAM path, tests).
"""

import dataclasses
from collections.abc import Sequence

import numpy as np

from trajcomp.arm.kinematics import fk
from trajcomp.errors import TimingError
from trajcomp.programs.frames import FrameTable
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR
from trajcomp.programs.tables import rows_of, value_codes
from trajcomp.programs.program import place_text
from trajcomp.formats.speeds import arc_length

KINDS = (JOINT, LINEAR, CIRCULAR)
CORNER_BLOCK = 8192  # motions whose corners `corner_lengths` places at once: two (4, 4) poses each at most (2 MB)


@dataclasses.dataclass(frozen=True, eq=False)
class Moves:
    """M waypoints and the motions between them.

    Per-motion limits that are the same for every motion may be read-only
    broadcast views (no memory per motion).

    Attributes
    ----------
    q : ndarray, shape (M, 6)
        Joints of each waypoint, rad.
    kind : ndarray of object, shape (M,)
        ``"joint"``, ``"linear"`` or ``"circular"``: the motion into waypoint k.
    via : ndarray, shape (M, 6)
        Joints of the via point of a circular motion k, rad; NaN elsewhere.
    stop : ndarray of bool, shape (M,)
        The program stops exactly at waypoint k (fine); the first and last
        waypoints are always stops.
    zone : ndarray, shape (M,)
        Blend radius at waypoint k, mm (0 where the arm stops or the path
        keeps its corner).
    tcp_speed : ndarray, shape (M,)
        Programmed TCP speed of motion k, mm/s; ``inf`` where none.
    min_duration : ndarray, shape (M,)
        Programmed time of motion k, s (FANUC ``sec``); 0 where none.
    velocity, acceleration : ndarray, shape (M, 6)
        Joint velocity (rad/s) and acceleration (rad/s^2) limits of motion k:
        the robot's, lowered by a programmed joint speed (% or rad/s) and a
        joint motion's programmed acceleration (UR movej ``a=``, the leading
        axis's: every axis's bound).
    tools : ndarray, shape (T, 4, 4)
        The distinct T_flange_tool the motions use, mm.
    tool : ndarray of int, shape (M,)
        Index into `tools` of motion k's tool.
    start : ndarray of bool, shape (M,)
        Waypoint k begins a timed stretch: the arm's position before it is
        not known, motion k is not timed.
    labels : Sequence[str], length M
        Waypoint names with file and line, for messages.
    motion : ndarray of int, shape (M,)
        Index into `Program.motions` of motion k (``arange(M)`` for a joint path).
    track_position, track_velocity, track_acceleration : ndarray, shape (M,)
        On a track that moves (`trajcomp.timing.track`): its position at
        waypoint k, mm, and its velocity and acceleration limits along
        motion k, mm/s and mm/s^2; NaN and ``inf`` (read-only views) on a
        fixed base.
    """

    q: np.ndarray
    kind: np.ndarray
    via: np.ndarray
    stop: np.ndarray
    zone: np.ndarray
    tcp_speed: np.ndarray
    min_duration: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    tools: np.ndarray
    tool: np.ndarray
    start: np.ndarray
    labels: Sequence
    motion: np.ndarray
    track_position: np.ndarray = None
    track_acceleration: np.ndarray = None
    track_velocity: np.ndarray = None

    def __post_init__(self):
        stop = np.array(self.stop, dtype=bool)
        if len(stop):
            stop[[0, -1]] = True
        stop[np.asarray(self.start, dtype=bool)] = True
        stop[np.flatnonzero(np.asarray(self.start, dtype=bool)) - 1] = True
        object.__setattr__(self, "stop", stop)
        object.__setattr__(self, "kind", np.asarray(self.kind, dtype=object).reshape(len(self.q)))
        if self.track_position is None:
            object.__setattr__(self, "track_position", np.broadcast_to(np.nan, (len(self.q),)))
            object.__setattr__(self, "track_acceleration", np.broadcast_to(np.inf, (len(self.q),)))
        if self.track_velocity is None:
            object.__setattr__(self, "track_velocity", np.broadcast_to(np.inf, (len(self.q),)))

    @property
    def on_track(self):
        """Whether the waypoints stand at track positions (a track that moves: a joint of the timed path)."""
        return len(self.q) > 0 and not np.isnan(self.track_position[0])

    def __len__(self):
        return len(self.q)

    def rows(self, lo, hi):
        """Waypoints lo .. hi - 1 as a `Moves` of their own: views of these rows, labels looked up on access.

        What fitting a window needs and nothing more (so a worker process
        could be sent only this). Its first and last waypoints are stops
        and its first a start, as in any `Moves`; the path fit does not use
        either.
        """
        rows = {f.name: getattr(self, f.name)[lo:hi] for f in dataclasses.fields(self)
                if f.name not in ("tools", "labels")}
        return dataclasses.replace(self, labels=_RowLabels(self.labels, lo, hi), **rows)

    def tool_of(self, k):
        """T_flange_tool (n, 4, 4) of motions k (n,)."""
        return self.tools[self.tool[k]]

    @classmethod
    def from_joints(cls, q, robot, *, kind=LINEAR, tcp_speed=np.inf, stop=False, zone=0.0, labels=None, tool=None):
        """Moves through joint waypoints (a CAM path, a test path).

        Parameters
        ----------
        q : array_like, shape (M, 6)
            Joints, rad.
        robot : Robot
            Gives the joint limits and the default tool.
        kind : str or sequence of str
            Motion kind into each waypoint.
        tcp_speed : float or array_like, shape (M,)
            Programmed TCP speed, mm/s (``inf``: none).
        stop, zone : bool / float or array_like, shape (M,)
            Exact stops and blend radii (mm) at the waypoints.
        labels : sequence of str, optional
            Default ``waypoint k``.
        tool : ndarray, shape (4, 4), optional
            T_flange_tool; default the robot's.
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        m = len(q)
        tool = robot.T_flange_tool if tool is None else np.asarray(tool, dtype=float)
        return cls(
            q=q,
            kind=np.full(m, kind, dtype=object) if isinstance(kind, str) else kind,
            via=np.broadcast_to(np.nan, (m, 6)),
            stop=np.broadcast_to(stop, (m,)),
            zone=np.broadcast_to(np.asarray(zone, dtype=float), (m,)).copy(),
            tcp_speed=np.broadcast_to(np.asarray(tcp_speed, dtype=float), (m,)).copy(),
            min_duration=np.zeros(m),
            velocity=np.broadcast_to(robot.v_max, (m, 6)),
            acceleration=np.broadcast_to(robot.a_max, (m, 6)),
            tools=tool[None],
            tool=np.zeros(m, dtype=int),
            start=np.arange(m) == 0,
            labels=labels if labels is not None else WaypointLabels(m),
            motion=np.arange(m),
        )


def corner_lengths(moves, robot, k):
    """The programmed TCP length (n,) of linear and circular motions k (n,), mm: corner to corner, the line's
    chord or the circle's arc through its via point (a blended corner's zone cuts it on the timed path)."""
    k = np.asarray(k, dtype=int)
    out = np.zeros(len(k))
    for tool_index in np.unique(moves.tool[k]).tolist():
        arm = robot.replace(T_flange_tool=moves.tools[tool_index])
        used = np.flatnonzero(moves.tool[k] == tool_index)
        for rows in (used[lo : lo + CORNER_BLOCK] for lo in range(0, len(used), CORNER_BLOCK)):
            corners = np.sort(np.r_[k[rows] - 1, k[rows]])  # a run's motions share their corners: each placed once
            corners = corners[np.r_[True, corners[1:] != corners[:-1]]]  # (np.union1d hashes them: 10x slower)
            placed = fk(arm, moves.q[corners])[:, :3, 3]
            start, end = placed[np.searchsorted(corners, k[rows] - 1)], placed[np.searchsorted(corners, k[rows])]
            out[rows] = np.linalg.norm(end - start, axis=1)
            for i in np.flatnonzero(moves.kind[k[rows]] == CIRCULAR).tolist():
                via = fk(arm, moves.via[k[rows[i]]][None])[0, :3, 3]
                out[rows[i]] = arc_length(np.array([start[i], via, end[i]]))
    return out


class _RowLabels(Sequence):
    """Labels lo .. hi - 1 of another sequence, looked up on access."""

    def __init__(self, labels, lo, hi):
        self.labels, self.lo, self.n = labels, lo, hi - lo

    def __len__(self):
        return self.n

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self.labels[self.lo + i] for i in range(self.n)[k]]
        return self.labels[self.lo + range(self.n)[k]]


class WaypointLabels(Sequence):
    """``waypoint k`` for k < n, built on access."""

    def __init__(self, n):
        self.n = n

    def __len__(self):
        return self.n

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [f"waypoint {i}" for i in range(self.n)[k]]
        return f"waypoint {range(self.n)[k]}"


def moves_from_program(program, robot, joints, *, tools=None, frames=None):
    """The `Moves` of a program whose targets' joints are known (columnar: no loop over its motions).

    Motions to positions computed at run time are not waypoints: the
    waypoint after one begins a new timed stretch; so does a motion whose
    start is not unique (`trajcomp.programs.items.Motion.start_why`).

    Parameters
    ----------
    program : Program
    robot : Robot
        Joint limits, default tool.
    joints : ndarray, shape (N, 6)
        Joints (rad) of the program's N targets (compensated, or planned in
        the declared posture), NaN where not known; joint targets use their own.
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        Tools and frames the program uses but does not define (`trajcomp.programs.frames.FrameTable`).

    Returns
    -------
    Moves

    Raises
    ------
    TimingError
        A programmed speed that is not positive, or a target without joints,
        named by line.
    """
    table, targets = program.motion_table(), program.target_table()
    rows = np.flatnonzero(table.target >= 0)
    runtime_before = np.cumsum(table.target < 0)[rows]
    start = np.r_[True, runtime_before[1:] != runtime_before[:-1]][: len(rows)]
    start |= table.start_why[rows] != ""  # reached from more than one place (`trajcomp.programs.flow`)
    known = np.asarray(joints, dtype=float)
    if targets.is_joint.any():  # joint targets use their own joints
        known = np.where(targets.is_joint[:, None], targets.joints, known)
    target, via = table.target[rows], table.via[rows]
    circular = np.flatnonzero(via >= 0)
    q = rows_of(known, target)  # the program's own array when its motions take every target in order
    for index, motion, values in ((target, rows, q), (via[circular], rows[circular], known[via[circular]])):
        missing = np.flatnonzero(np.isnan(values).any(axis=1))
        if missing.size:
            k = missing[0]
            raise TimingError(f"{program.where(int(index[k]))}: no joints known for this target "
                              f"({place_text(program.place(program.motions[int(motion[k])]))})")
    via_q = np.full((len(rows), 6), np.nan) if circular.size else np.broadcast_to(np.nan, (len(rows), 6))
    if circular.size:
        via_q[circular] = known[via[circular]]
    zone = table.zone[rows]
    used = program.usage_table()
    tool, names = value_codes(used.tool[np.searchsorted(used.index, target)])
    frame_table = FrameTable(program, robot, tools, frames)
    labels = program.labels(target)
    speeds = _speed_limits(table, rows, robot, program, labels)
    moves = Moves(
        q=q, kind=table.kind[rows], via=via_q, stop=np.isnan(zone), zone=np.nan_to_num(zone, nan=0.0),
        tools=np.array([frame_table.tool(name) for name in names]).reshape(-1, 4, 4), tool=tool, start=start,
        labels=labels, motion=rows, **speeds,
    )
    return _tcp_accelerations(moves, robot, table.acceleration[rows])


def _tcp_accelerations(moves, robot, stated):
    """``moves`` whose linear and circular motions with a programmed TCP acceleration ``stated`` (M,) mm/s^2
    (UR movel ``a=``, KRL ``$ACC.CP``; NaN: none) take no less time than the controller's ramps at it allow.

    The controller runs such a motion of programmed length L at its cruise
    speed v (the programmed TCP speed) between ramps at a, where it starts
    or ends at rest: at least L / v + v / (2 a) per end at rest, or the
    ramps alone where it cannot reach v. That time bounds the motion as a
    programmed time does (`Moves.min_duration`): the timing is no faster
    than the controller under its acceleration (the TCP's acceleration
    itself is not sampled).
    """
    k = np.flatnonzero((moves.kind != JOINT) & (stated > 0) & ~moves.start)
    if not k.size:
        return moves
    length, a, v = corner_lengths(moves, robot, k), stated[k], moves.tcp_speed[k]
    ends = moves.stop[k - 1].astype(int) + moves.stop[k].astype(int)  # ends at rest: 0, 1 or 2
    with np.errstate(divide="ignore", invalid="ignore"):
        ramp_length = ends * v**2 / (2.0 * a)  # TCP mm the ramps take to reach v
        cruising = np.where(np.isfinite(v), length / v + ends * v / (2.0 * a), 0.0)
        # ramps only: up and down (2 ends) 2 sqrt(L / a); one end sqrt(2 L / a); none: the cruise alone
        ramps = np.where(ends == 2, 2.0 * np.sqrt(length / a), np.where(ends == 1, np.sqrt(2.0 * length / a), 0.0))
    least = np.where(length >= ramp_length, cruising, np.maximum(ramps, np.nan_to_num(length / v)))
    min_duration = moves.min_duration.copy()
    min_duration[k] = np.maximum(min_duration[k], least)
    return dataclasses.replace(moves, min_duration=min_duration)


def _speed_limits(table, rows, robot, program, labels):
    """tcp_speed, min_duration, velocity and acceleration of motions ``rows`` from their programmed speeds."""
    speed, unit, kind = table.speed[rows], table.speed_unit[rows], table.kind[rows]
    given = ~np.isnan(speed)
    bad = np.flatnonzero(given & ~(np.isfinite(speed) & (speed > 0)))
    if bad.size:
        k = bad[0]
        raise TimingError(
            f"{place_text(program.place(program.motions[int(rows[k])]))}: motion to {labels[k]} asks speed "
            f"{speed[k]:g} {unit[k]}: "
            "a positive speed is needed to time it"
        )
    m = len(rows)
    percent = given & (unit == "%") & (kind == JOINT)
    absolute = given & (unit == "rad/s") & (kind == JOINT)
    velocity = np.broadcast_to(robot.v_max, (m, 6))
    if percent.any() or absolute.any():
        velocity = velocity.copy()
        velocity[percent] = robot.v_max * np.minimum(speed[percent, None], 100.0) / 100.0
        velocity[absolute] = np.minimum(robot.v_max, speed[absolute, None])
    stated, share = table.acceleration[rows], table.acceleration_share[rows]
    accelerating = (kind == JOINT) & (stated > 0)
    shared = share < 1.0
    acceleration = np.broadcast_to(robot.a_max, (m, 6))
    if accelerating.any() or shared.any():
        acceleration = acceleration.copy()
        acceleration[shared] = robot.a_max * share[shared, None]
        acceleration[accelerating] = np.minimum(acceleration[accelerating], stated[accelerating, None])
    return {
        "tcp_speed": np.where(given & (unit == "mm/s"), speed, np.inf),
        "min_duration": np.where(given & (unit == "s"), speed, 0.0),
        "velocity": velocity,
        "acceleration": acceleration,
    }
