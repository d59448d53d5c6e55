"""The robot's track as a joint of the timed path: its limits bind like the arm's, the TCP speed is the world's.

On a track (`trajcomp.arm.track`) the controller moves the carriage with
the arm: along the motion into waypoint k the track position goes from
e[k-1] to e[k] in step with the motion, every axis arriving together
(KUKA's external axes in a PTP or LIN, ABB's additional axes, FANUC's
extended axis in its group's motion). The carriage moves the base by a
translation linear in e, so a linear motion's TCP seen from the carriage
also runs on a straight line (the world line less the carriage's travel),
both at fixed shares of the motion: the arm's joint path is the one the
re-timing already solves for the targets' joints in their carriages
(`trajcomp.timing.moves`). Along motion k the track is then

    e(s) = e[k-1] + (e[k] - e[k-1]) P_k(s) / P_k

with P_k(s) the motion's progress from its start along the timed path
position s: the carriage TCP's travel for a linear motion, the joint
path's length for a joint motion (a straight line in joints). Its
velocity is e'(s) sd and its acceleration e''(s) sd^2 + e'(s) sdd, with
e' = (e[k] - e[k-1]) rho(s) / P_k, e'' = (e[k] - e[k-1]) rho'(s) / P_k
and rho = dP_k/ds.

What binds, and how (`retime_on_track`):

- the programmed TCP speed is the world TCP's (what each controller
  reads for a motion with an external axis: KRL ``$VEL.CP``, RAPID
  ``v_tcp``, FANUC ``mm/sec``): the carriage TCP's bound is the
  programmed speed times L_carriage / L_world of the motion;
- the track's velocity limit along a linear motion is a TCP speed bound,
  v_track L_carriage / |e[k] - e[k-1]|; along a joint motion a bound on
  each joint, v_track |q[k]_j - q[k-1]_j| / |e[k] - e[k-1]| (and so for
  the acceleration): both exact where the path is the programmed line;
  v_track is the track's limit, or the motion's programmed speed of the
  external axes where lower (RAPID speeddata's v_leax:
  `trajcomp.programs.items.Motion.external_speed`), so the track runs no
  faster than programmed whatever field the timing writes (a ``\\T``
  replaces the speed data, v_leax too);
- the re-timed path is then sampled at 1 kHz and the track's velocity and
  acceleration measured (`TrackTiming`); a run that exceeds a track limit
  is timed again with its motions' limits lowered by the share it exceeds
  them (velocities 1 / f, accelerations 1 / f^2: the same path, f times
  slower), until none does.

Not timed, left as written and listed: a circular motion that moves the
track (the carriage TCP then runs on no circle), a motion that moves only
the track (the arm rests in its carriage) or whose TCP rests in the world
while the track moves (no TCP speed to keep). At a blended corner the
controller blends the track as the position (each motion's share of the
superposed blend), faster than the TCP's travel where the blend cuts the
corner: a run's path carries the track so blended
(`trajcomp.timing.path.RunPath.track`), whose e'(s) and e''(s) replace the
progress shares above; its velocity limit bounds the path speed as a
joint's (`RunPath.speed_bound`, ``Moves.track_velocity``) and samples
over a limit refine the grid (`trajcomp.timing.check.dense_check`).
Motions from rest to rest (no blend) keep the progress shares, exact there.
Written speeds are world TCP speeds (`cruise_speeds` converts through
``TrackTiming.world_ratio`` and bounds them by ``speed_bound``).
"""

import dataclasses

import numpy as np

from trajcomp.arm.kinematics import fk
from trajcomp.errors import TimingError
from trajcomp.programs.frames import FrameTable
from trajcomp.programs.items import CIRCULAR, JOINT
from trajcomp.timing.check import LIMIT_TOLERANCE, RATE, sample_times, track_motion
from trajcomp.timing.options import TOLERANCE

MIN_LENGTH = 1e-3  # mm (TCP) or rad (joints): a motion shorter than this while the track moves has no speed to keep
ROUNDS = 4  # timings at most: the first, then each run that exceeds a track limit slowed by its share
MARGIN = 1.002  # a slowed run's limits are lowered this much more than the share it exceeded them by


@dataclasses.dataclass(frozen=True, eq=False)
class TrackTiming:
    """The track's part of a timing.

    Attributes
    ----------
    field : str
        The program field that holds the track position (``"E1"``, ``"eax_a"``).
    values : ndarray, shape (M,)
        Track position at each waypoint, mm.
    world_ratio : ndarray, shape (M,)
        World TCP length over carriage TCP length of the motion into each waypoint (1 where either is 0).
    speed_bound : ndarray, shape (M,)
        World TCP speed, mm/s, at which the track reaches its velocity limit (or the motion's programmed speed of
        the external axes, where lower) along the (linear) motion into each waypoint; ``inf`` where the track does
        not move.
    peak_velocity, peak_acceleration : float
        Largest sampled |track velocity| (mm/s) and |acceleration| (mm/s^2).
    limit_velocity, limit_acceleration : float
        The track's limits, mm/s and mm/s^2.
    left : tuple of (int, str)
        Waypoints whose motion moves the track and is not timed (left as written), and why.
    """

    field: str
    values: np.ndarray
    world_ratio: np.ndarray
    speed_bound: np.ndarray
    peak_velocity: float
    peak_acceleration: float
    limit_velocity: float
    limit_acceleration: float
    left: tuple = ()

    @property
    def within_limits(self):
        """No sample's track velocity or acceleration exceeds its limit by more than `LIMIT_TOLERANCE`."""
        return bool(self.peak_velocity <= self.limit_velocity * (1.0 + LIMIT_TOLERANCE)
                    and self.peak_acceleration <= self.limit_acceleration * (1.0 + LIMIT_TOLERANCE))

    def lines(self, labels):
        """The track's line of the timing's table, then the motions left as written (list of str)."""
        out = [f"{self.field:<6}{self.peak_velocity:>11.1f}{self.limit_velocity:>8.0f}"
               f"{self.peak_acceleration:>13.1f}{self.limit_acceleration:>8.0f}   (track: mm/s, mm/s^2)"]
        if self.left:
            names = ", ".join(labels[k] for k, _ in self.left[:5])
            more = f" and {len(self.left) - 5} more" if len(self.left) > 5 else ""
            out.append(f"warning: not timed, left as written: {len(self.left)} motion(s) moving the track "
                       f"({self.field}): {names}{more}; first: {self.left[0][1]}")
        return out


def track_values(program, robot, moves, tools=None, frames=None):
    """Track position (M,), mm, at each waypoint of ``moves`` (of ``program``), or None when the track stands.

    None too for a robot without a track, or whose track names no field of the program's language.
    """
    if robot.track is None or robot.track.index(program.track_key) is None or not len(moves):
        return None
    target = program.motion_table().target[moves.motion]
    values = FrameTable(program, robot, tools, frames).track_positions(target)
    return values if np.ptp(values) > 0 else None


def retime_on_track(moves, robot, values, field, *, programmed=None, programmed_acceleration=None, method="auto",
                    tolerance=TOLERANCE):
    """Time a motion sequence whose waypoints stand at track positions ``values`` (M,), mm (see the module).

    Parameters
    ----------
    moves : Moves
        The waypoints' joints in their carriages.
    robot : Robot
        The nominal robot, with its ``track``.
    values : ndarray, shape (M,)
        Track position of each waypoint, mm.
    field : str
        The program field that holds it (for messages).
    programmed, programmed_acceleration : ndarray, shape (M,), optional
        The track speed and acceleration the program allows along the
        motion into each waypoint, mm/s and mm/s^2 (NaN: none; bind where
        below the track's limits: `programmed_limits`).
    method, tolerance
        As `trajcomp.timing.retiming.retime`.

    Returns
    -------
    TimingResult
        With ``track`` (`TrackTiming`), world TCP lengths in ``tcp_length`` and the track's limits in
        ``within_limits``.

    Raises
    ------
    TimingError
        A waypoint beyond the track's travel, named with its value.
    """
    track, values = robot.track, np.asarray(values, dtype=float)
    outside = np.flatnonzero((values < track.position_min) | (values > track.position_max))
    if outside.size:
        k = int(outside[0])
        raise TimingError(f"{moves.labels[k]}: {field} {values[k]:g} mm is beyond the track's travel "
                          f"{track.position_min:g} .. {track.position_max:g} mm (track.limits of the robot)")
    limited, limit, reasons, ratio, bound = track_limits(moves, robot, values, programmed, programmed_acceleration)
    from trajcomp.timing.retiming import retime  # here: retime's TOPP-RA imports `with_track` from this module

    slow = np.ones(len(moves))
    for _ in range(ROUNDS):
        result = retime(_slowed(limited, slow), robot, method=method, tolerance=tolerance)
        peaks = [_run_peaks(run, law, limited, limit) for _, run, law in result.pieces]
        over = False
        for (_, run, _), (_, share, _, acceleration_share) in zip(result.pieces, peaks):
            excess = max(share, np.sqrt(acceleration_share))
            if excess > 1.0 + 0.5 * LIMIT_TOLERANCE:
                slow[run.first + 1 : run.last + 1] *= excess * MARGIN
                over = True
        if not over:
            break
    peak_velocity, _, peak_acceleration, _ = np.max(np.reshape(peaks, (-1, 4)), axis=0, initial=0.0)
    timing = TrackTiming(field, values, ratio, bound * ratio, float(peak_velocity), float(peak_acceleration),
                         track.velocity, track.acceleration, tuple(reasons))
    return dataclasses.replace(result, track=timing, tcp_length=result.tcp_length * ratio,
                               within_limits=result.within_limits and timing.within_limits)


def programmed_limits(table, motion, track):
    """The track's speed and acceleration a program allows along its motions ``motion`` (M,) (rows of its
    `MotionTable` ``table``), mm/s and mm/s^2 (NaN: the track's own), each (M,).

    A speed data's speed of the linear external axes (RAPID v_leax:
    ``external_speed``); a joint motion's speed in % of every axis's
    maximum, at which the controller moves the track too (a KRL PTP's, the
    slowest of its axes' and external axes' ``$VEL_EXTAX``, as the arm's
    axes are timed; FANUC's J %); the share of the axes' accelerations the
    program leaves the motion (``acceleration_share``: KRL ``$ACC_AXIS``
    and ``$ACC_EXTAX``, RAPID ``AccSet``, FANUC ``ACC``), of the track's.
    """
    speed, unit, kind = (np.asarray(column)[motion] for column in (table.speed, table.speed_unit, table.kind))
    percent = (kind == JOINT) & (unit == "%") & ~np.isnan(speed.astype(float))
    share = np.where(percent, np.minimum(speed.astype(float), 100.0) / 100.0, np.nan)
    velocity = np.fmin(np.asarray(table.external_speed, dtype=float)[motion], track.velocity * share)
    return velocity, track.acceleration * np.asarray(table.acceleration_share, dtype=float)[motion]


def track_limits(moves, robot, values, programmed=None, programmed_acceleration=None):
    """The motions with the track's limits folded in, as `retime_on_track` times them (see the module).

    Parameters
    ----------
    moves : Moves
    robot : Robot
        With its ``track``.
    values : ndarray, shape (M,)
        Track position of each waypoint, mm.
    programmed, programmed_acceleration : ndarray, shape (M,), optional
        The track speed and acceleration the program allows along each motion, mm/s and mm/s^2 (NaN: none).

    Returns
    -------
    limited : Moves
        On the track (``track_position``), its limits per motion, the
        carriage TCP's speed bound, the motions not timed as starts.
    limit : ndarray, shape (M,)
        The track's velocity limit along each motion, mm/s.
    reasons : list of (int, str)
        The motions moving the track that are not timed, and why.
    ratio, bound : ndarray, shape (M,)
        World over carriage TCP length, and the carriage TCP speed at which the track reaches ``limit``, mm/s.
    """
    track = robot.track
    change = np.abs(np.diff(values, prepend=values[:1]))
    limit = track.velocity if programmed is None else np.fmin(track.velocity, programmed)  # (M,) or scalar
    limit = np.broadcast_to(limit, values.shape)
    acceleration_limit = np.broadcast_to(track.acceleration if programmed_acceleration is None
                                         else np.fmin(track.acceleration, programmed_acceleration), values.shape)
    carriage, world = _lengths(moves, robot, values)
    reasons = _not_timed(moves, change, carriage, world)
    left = np.zeros(len(moves), dtype=bool)
    left[[k for k, _ in reasons]] = True
    moving = (change > 0) & ~left
    joint = moves.kind == JOINT
    path = moving & ~joint
    joint_change = np.abs(np.diff(moves.q, axis=0, prepend=moves.q[:1]))
    leading = joint_change.argmax(axis=1)  # along a line in joints, bounding one joint's rate bounds the motion's
    share = np.full(joint_change.shape, np.inf)
    rows = np.flatnonzero(moving & joint)
    share[rows, leading[rows]] = joint_change[rows, leading[rows]] / change[rows]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(path, world / carriage, 1.0)
        bound = np.where(path, limit * carriage / change, np.inf)  # carriage TCP mm/s
    limited = dataclasses.replace(
        moves, start=np.asarray(moves.start, dtype=bool) | left, track_position=values,
        track_acceleration=acceleration_limit.copy(), track_velocity=limit.copy(),
        tcp_speed=np.minimum(moves.tcp_speed / ratio, bound),
        velocity=np.minimum(moves.velocity, limit[:, None] * share),
        acceleration=np.minimum(moves.acceleration, acceleration_limit[:, None] * share))
    return limited, limit, reasons, ratio, bound


def _lengths(moves, robot, values):
    """Carriage and world TCP lengths (each (M,)), mm, of the motion into each waypoint (0 for the first).

    The world one on the controller's own track (it interpolates what it knows), in the base frame at track
    position 0.
    """
    flange = fk(robot, moves.q, tcp=False)
    tools = moves.tool_of(np.arange(len(moves)))
    start = np.r_[flange[:1], flange[:-1]] @ tools  # each motion's start with its own tool
    end = flange @ tools
    shift = robot.track.shift(values, actual=False) @ robot.T_world_base[:3, :3]
    carriage = np.linalg.norm(end[:, :3, 3] - start[:, :3, 3], axis=1)
    moved = shift - np.r_[shift[:1], shift[:-1]]
    world = np.linalg.norm(end[:, :3, 3] - start[:, :3, 3] + moved, axis=1)
    carriage[0] = world[0] = 0.0
    return carriage, world


def _not_timed(moves, change, carriage, world):
    """``[(k, why), ...]``: the motions moving the track that are not timed, and why."""
    joint = moves.kind == JOINT
    moving = change > 0
    moving[0] = False
    still = np.r_[0.0, np.abs(np.diff(moves.q, axis=0)).max(axis=1)] < MIN_LENGTH
    out = []
    for k in np.flatnonzero(moving).tolist():
        if moves.kind[k] == CIRCULAR:
            out.append((k, "a circular motion that moves the track: seen from the carriage its TCP runs on no circle"))
        elif (joint[k] and still[k]) or (not joint[k] and carriage[k] < MIN_LENGTH):
            out.append((k, "only the track moves (the arm rests in its carriage): the controller times it"))
        elif not joint[k] and world[k] < MIN_LENGTH:
            out.append((k, "the TCP rests in the world while the track moves: no TCP speed to keep"))
    return out


def _slowed(moves, slow):
    """``moves`` with each motion's limits lowered by its factor ``slow`` (M,) >= 1: the same path, slower."""
    if np.all(slow == 1.0):
        return moves
    return dataclasses.replace(moves, tcp_speed=moves.tcp_speed / slow, velocity=moves.velocity / slow[:, None],
                               acceleration=moves.acceleration / (slow**2)[:, None],
                               track_acceleration=moves.track_acceleration / slow**2,
                               track_velocity=moves.track_velocity / slow)


def _run_peaks(run, law, moves, limit):
    """Largest |track velocity| (mm/s), its largest share of the velocity ``limit`` (M,) of the motion it lies on,
    largest |acceleration| (mm/s^2) and its largest share of the motion's ``moves.track_acceleration`` of a timed
    run, sampled at `RATE`."""
    if run.path is None:
        return 0.0, 0.0, 0.0, 0.0
    t = sample_times(law.duration, RATE)
    s, sd, sdd = law(t)
    s = np.clip(s, 0.0, run.length)
    k = run.motion_at(s)
    if run.track is not None:  # the path's own track position, blended as the controller blends it
        velocity, acceleration = track_motion(run, law, t)
    else:
        grid = run.grid
        inside = np.ones(len(grid) - 1, bool)
        per = _per_progress(moves, run.motion_at(grid), grid, run.path(grid, 1), run.grid_rate, inside)
        at = np.minimum(np.searchsorted(run.motion_at(grid), k, side="right") - 1, len(grid) - 1)  # a point of k
        rate = np.interp(s, grid, run.grid_rate)
        slope = np.interp(s, grid, _slopes(run.grid_rate, grid, inside))
        rho, drho = _progress_rate(moves.kind[k] == JOINT, run.path(s, 1), run.path(s, 2), rate, slope)
        velocity, acceleration = per[at] * rho * sd, per[at] * (drho * sd**2 + rho * sdd)
    velocity, acceleration = np.abs(velocity), np.abs(acceleration)
    return (float(np.max(velocity, initial=0.0)), float(np.max(velocity / limit[k], initial=0.0)),
            float(np.max(acceleration, initial=0.0)),
            float(np.max(acceleration / moves.track_acceleration[k], initial=0.0)))


def with_track(moves, motion, grid, dq, ddq, rate, acceleration, inside=None, track=None):
    """The path's derivatives and acceleration limits with the track's position as a 7th joint (module).

    Parameters
    ----------
    moves : Moves
        On a track (`Moves.on_track`).
    motion : ndarray of int, shape (G,)
        The motion (waypoint k) each grid point lies on; a waypoint between two motions: the one ending there.
    grid : ndarray, shape (G,)
        Path positions, increasing within each path (paths laid end to end each start again).
    dq, ddq : ndarray, shape (G, 6)
        q'(s), q''(s) at the grid points.
    rate : ndarray, shape (G,)
        |dp/ds| of the carriage TCP, mm per unit of s.
    acceleration : ndarray, shape (6,) or (G - 1, 6)
        The joints' acceleration limits (of the run, or of each interval).
    inside : ndarray of bool, shape (G - 1,), optional
        Interval i lies within one path (False between paths laid end to end); default all.
    track : (ndarray (G,), ndarray (G,)), optional
        e'(s) and e''(s) of the path's own track position (`trajcomp.timing.path.RunPath.track`: blended as the
        controller blends it); default: the track's share of each motion's progress (exact without blends).

    Returns
    -------
    dq, ddq : ndarray, shape (G, 7)
        With e'(s) and e''(s), mm per unit of s.
    acceleration : ndarray, shape (7,) or (G - 1, 7)
        With the track's, mm/s^2.
    """
    de, dde = _progress_derivatives(moves, motion, grid, dq, ddq, rate, inside) if track is None else track
    limit = moves.track_acceleration[motion]
    acceleration = (np.r_[acceleration, limit.min()] if np.ndim(acceleration) == 1
                    else np.c_[acceleration, limit[:-1]])
    return np.c_[dq, de], np.c_[ddq, dde], acceleration


def _progress_derivatives(moves, motion, grid, dq, ddq, rate, inside=None):
    """e'(s) and e''(s) (each (G,)), mm per unit of s, of the track moving with each motion's progress (module)."""
    inside = np.ones(len(grid) - 1, dtype=bool) if inside is None else inside
    per = _per_progress(moves, motion, grid, dq, rate, inside)
    rho, drho = _progress_rate(moves.kind[motion] == JOINT, dq, ddq, rate, _slopes(rate, grid, inside))
    return per * rho, per * drho


def _per_progress(moves, motion, grid, dq, rate, inside):
    """(e[k] - e[k-1]) / P_k (G,) at each grid point: the track's mm per unit of its motion's progress."""
    rho = np.where(moves.kind[motion] == JOINT, np.linalg.norm(dq, axis=1), rate)
    progress = np.r_[0.0, np.cumsum(np.where(inside, 0.5 * (rho[1:] + rho[:-1]) * np.diff(grid), 0.0))]
    starts = np.flatnonzero(np.r_[True, motion[1:] != motion[:-1]])
    ends = np.r_[starts[1:], len(grid)] - 1
    begin = np.where((starts > 0) & inside[np.maximum(starts - 1, 0)], starts - 1, starts)  # from the waypoint before
    total = progress[ends] - progress[begin]
    change = moves.track_position[motion[starts]] - moves.track_position[motion[starts] - 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        per = np.where(total > 0, change / total, 0.0)
    return np.repeat(per, ends - starts + 1)


def _slopes(values, grid, inside):
    """d values / ds (G,) at the grid points: the mean of the slopes of the intervals within a path beside each."""
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(inside, np.diff(values) / np.diff(grid), 0.0)
    weight = inside.astype(float)
    total = np.r_[0.0, slope] + np.r_[slope, 0.0]
    count = np.r_[0.0, weight] + np.r_[weight, 0.0]
    return total / np.maximum(count, 1.0)


def _progress_rate(joint, dq, ddq, rate, slope):
    """rho = dP/ds and its derivative (each (N,)): |q'| along a joint motion, the carriage TCP's rate otherwise."""
    norm = np.linalg.norm(dq, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        along = np.where(norm > 0, np.einsum("nj,nj->n", dq, ddq) / norm, 0.0)
    return np.where(joint, norm, rate), np.where(joint, along, slope)
