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

import numpy as np

from trajcomp.errors import TimingError
from trajcomp.frames import FrameTable
from trajcomp.program import CIRCULAR, JOINT, LINEAR

KINDS = (JOINT, LINEAR, CIRCULAR)


@dataclasses.dataclass(frozen=True, eq=False)
class Moves:
    """M waypoints and the motions between them.

    Attributes
    ----------
    q : ndarray, shape (M, 6)
        Joints of each waypoint, rad.
    kind : tuple of str, length M
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
        the robot's, lowered by a programmed joint speed (% or rad/s).
    tool : ndarray, shape (M, 4, 4)
        T_flange_tool of motion k, mm.
    start : ndarray of bool, shape (M,)
        Waypoint k begins a timed stretch: the arm's position before it is
        not known, motion k is not timed.
    labels : tuple of str, length M
        Waypoint names with file and line, for messages.
    motion : ndarray of int, shape (M,)
        Index into `Program.motions` of motion k (``arange(M)`` for a joint path).
    """

    q: np.ndarray
    kind: tuple
    via: np.ndarray
    stop: np.ndarray
    zone: np.ndarray
    tcp_speed: np.ndarray
    min_duration: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    tool: np.ndarray
    start: np.ndarray
    labels: tuple
    motion: np.ndarray

    def __post_init__(self):
        stop = np.asarray(self.stop, dtype=bool).copy()
        if len(stop):
            stop[[0, -1]] = True
        stop[np.asarray(self.start, dtype=bool)] = True
        stop[np.flatnonzero(np.asarray(self.start, dtype=bool)) - 1] = True
        object.__setattr__(self, "stop", stop)

    def __len__(self):
        return len(self.q)

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
        kinds = (kind,) * m if isinstance(kind, str) else tuple(kind)
        tool = robot.T_flange_tool if tool is None else np.asarray(tool, dtype=float)
        return cls(
            q=q,
            kind=kinds,
            via=np.full((m, 6), np.nan),
            stop=np.broadcast_to(stop, (m,)),
            zone=np.broadcast_to(np.asarray(zone, dtype=float), (m,)).copy(),
            tcp_speed=np.broadcast_to(np.asarray(tcp_speed, dtype=float), (m,)).copy(),
            min_duration=np.zeros(m),
            velocity=np.tile(robot.v_max, (m, 1)),
            acceleration=np.tile(robot.a_max, (m, 1)),
            tool=np.broadcast_to(tool, (m, 4, 4)).copy(),
            start=np.eye(1, m, dtype=bool)[0] if m else np.zeros(0, dtype=bool),
            labels=tuple(labels) if labels is not None else tuple(f"waypoint {k}" for k in range(m)),
            motion=np.arange(m),
        )


def moves_from_program(program, robot, joints, *, tools=None, frames=None):
    """The `Moves` of a program whose targets' joints are known.

    Motions to positions computed at run time are not waypoints: the
    waypoint after one begins a new timed stretch.

    Parameters
    ----------
    program : Program
    robot : Robot
        Joint limits, default tool.
    joints : Mapping[int, ndarray (6,)]
        Joints (rad) of the Cartesian targets by target index (compensated,
        or planned in the declared posture); joint targets use their own.
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        Tools and frames the program uses but does not define (`trajcomp.frames.FrameTable`).

    Returns
    -------
    Moves

    Raises
    ------
    TimingError
        A programmed speed that is not positive, or a target without joints,
        named by line.
    """
    table = FrameTable(program, robot, tools, frames)
    usage = program.usage()
    rows, start = [], True
    for m, motion in enumerate(program.motions):
        if motion.target is None:
            start = True
            continue
        rows.append((m, motion, start))
        start = False
    size = len(rows)
    out = {
        "q": np.zeros((size, 6)), "via": np.full((size, 6), np.nan), "stop": np.zeros(size, bool),
        "zone": np.zeros(size), "tcp_speed": np.full(size, np.inf), "min_duration": np.zeros(size),
        "velocity": np.tile(robot.v_max, (size, 1)), "acceleration": np.tile(robot.a_max, (size, 1)),
        "tool": np.zeros((size, 4, 4)), "start": np.zeros(size, bool), "motion": np.zeros(size, int),
    }
    kinds, labels = [], []

    def joints_of(index, motion):
        target = program.targets[index]
        value = target.joints if target.is_joint else joints.get(index)
        if value is None:
            raise TimingError(f"{program.where(index)}: no joints known for this target (line {motion.line})")
        return np.asarray(value, dtype=float)

    for k, (m, motion, start) in enumerate(rows):
        out["q"][k] = joints_of(motion.target, motion)
        if motion.via is not None:
            out["via"][k] = joints_of(motion.via, motion)
        out["stop"][k] = motion.zone is None
        out["zone"][k] = motion.zone or 0.0
        out["tool"][k] = table.tool(usage[motion.target][0])
        out["start"][k] = start
        out["motion"][k] = m
        _apply_speed(out, k, motion, robot, program.where(motion.target))
        kinds.append(motion.kind)
        labels.append(program.where(motion.target))
    return Moves(kind=tuple(kinds), labels=tuple(labels), **out)


def _apply_speed(out, k, motion, robot, where):
    """Set the limits row k from the motion's programmed speed."""
    if motion.speed is None:
        return
    if not (np.isfinite(motion.speed) and motion.speed > 0):
        raise TimingError(
            f"line {motion.line}: motion to {where} asks speed {motion.speed:g} {motion.speed_unit}: "
            "a positive speed is needed to time it"
        )
    if motion.speed_unit == "mm/s":
        out["tcp_speed"][k] = motion.speed
    elif motion.speed_unit == "%" and motion.kind == JOINT:
        out["velocity"][k] = robot.v_max * min(motion.speed, 100.0) / 100.0
    elif motion.speed_unit == "rad/s" and motion.kind == JOINT:
        out["velocity"][k] = np.minimum(robot.v_max, motion.speed)
    elif motion.speed_unit == "s":
        out["min_duration"][k] = motion.speed
