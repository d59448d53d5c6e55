"""Re-time a motion sequence: split it into segments at rest, time each, check densely.

Segments (``method="auto"``):

- a joint motion (PTP, MoveJ, movej, J) from rest to rest is a
  stop-to-stop segment timed by ruckig (jerk-limited, the straight joint
  line);
- a chain of motions joined by zones (no exact stop), and a single
  linear or circular motion, is a continuous run timed by TOPP-RA
  (`trajcomp.timing.toppra_run`), starting and ending at rest. A joint
  motion's zone is where the arm leaves its joint line for the next one.

``"toppra"`` times joint motions with TOPP-RA too (on their joint line),
``"ruckig"`` times runs with ruckig along their path (1 degree of freedom,
worst-case bounds). Every segment is then sampled at 1 kHz
(`trajcomp.timing.check`); where a sample exceeds a limit by more than
half the tolerance, that limit is lowered by the overshoot and the
segment timed again.
"""

import dataclasses

import numpy as np

from trajcomp.program import JOINT
from trajcomp.timing.check import LIMIT_TOLERANCE, Peaks, segment_peaks
from trajcomp.timing.path import TOLERANCE
from trajcomp.timing.result import Segment, TimingResult
from trajcomp.timing.windows import WINDOW, run_windows

METHODS = ("auto", "toppra", "ruckig")
_BLOCK = 65536  # waypoints per block of the per-waypoint passes over a long run
_RETRIES = 4  # timings of one segment with lowered limits before giving up
_TARGET = 1.0 + 0.5 * LIMIT_TOLERANCE  # re-time a segment whose samples exceed a limit by more than this


def retime(moves, robot, *, method="auto", tolerance=TOLERANCE):
    """Time-optimal timing of a motion sequence under the robot's limits and the programmed speeds.

    Parameters
    ----------
    moves : Moves
    robot : Robot
        The nominal robot: the controller's interpolation, joint velocity,
        acceleration and jerk limits.
    method : {"auto", "toppra", "ruckig"}
        See the module description.
    tolerance : float
        Largest deviation of the timed path from each waypoint, mm.

    Returns
    -------
    TimingResult

    Raises
    ------
    TimingError
        A motion the limits cannot be met on, named by waypoint, line and joint.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    m = len(moves)
    t = np.zeros(m)
    tcp_length = np.zeros(m)
    arrived = moves.q.copy()
    reached = dataclasses.replace(moves, q=arrived)  # filled in segment by segment
    segments, pieces, peaks, untimed, deviation = [], [], [], [], 0.0
    for kind, first, last in plan_segments(moves, method):
        if kind == "untimed":
            t[last] = t[first]
            untimed.append(last)
            continue
        _continued(arrived[first], moves.q[first : last + 1], moves.kind[first + 1 : last + 1],
                   arrived[first + 1 : last + 1])
        runs = run_windows(reached, robot, first, last, tolerance, WINDOW if kind == "toppra" else None)
        tcp_length[first + 1 : last + 1] = np.concatenate([run.tcp_lengths[1:] for run in runs])
        deviation = max(deviation, *(run.deviation for run in runs))
        if all(run.path is None for run in runs):
            t[first + 1 : last + 1] = t[first]
            segments.append(Segment(kind, first, last, 0.0))
            continue
        laws, checked = _timed(kind, runs, moves, robot)
        start = t[first]
        for run, law in zip(runs, laws):
            if law is None:
                t[run.first + 1 : run.last + 1] = start
                continue
            t[run.first + 1 : run.last + 1] = start + law.time_at(run.s_waypoints[1:])
            t[run.last] = start + law.duration
            pieces.append((start, run, law))
            start += law.duration
        segments.append(Segment(kind, first, last, start - t[first]))
        peaks.append(checked)
    return _result(moves, robot, arrived, t, segments, pieces, peaks, untimed, tcp_length, deviation)


def _continued(start, declared, kinds, out):
    """Write into ``out`` (n - 1, 6) the joints a chain of motions reaches its waypoints with from ``start`` (6,).

    ``declared`` (n, 6) are the waypoints' joints, ``kinds`` (n - 1,) the
    motions into waypoints 1 .. n - 1. A joint motion goes to the declared
    joints. Along linear and circular motions the controller keeps turning
    each joint continuously: a waypoint's declared turn (KUKA T, ABB cf4 /
    cf6, joints a revolution off) does not apply there; each joint moves by
    its declared change wrapped to less than half a turn per motion. Done
    in blocks of `_BLOCK` waypoints (bounded memory on long runs).
    """
    turn = 2.0 * np.pi
    gained = start - declared[0]  # whole turns gained since the last joint motion, (6,)
    for lo in range(1, len(declared), _BLOCK):
        hi = min(lo + _BLOCK, len(declared))
        change = declared[lo:hi] - declared[lo - 1 : hi - 1]
        total = gained + np.cumsum((change + np.pi) % turn - np.pi - change, axis=0)
        last_joint = np.maximum.accumulate(np.where(kinds[lo - 1 : hi - 1] == JOINT, np.arange(hi - lo), -1))
        offset = np.where(last_joint[:, None] >= 0, total - total[last_joint], total)
        out[lo - 1 : hi - 1] = declared[lo:hi] + np.round(offset / turn) * turn
        gained = offset[-1]


def plan_segments(moves, method="auto"):
    """``[(kind, first, last)]``: the segments of a sequence (see the module description).

    Segments run from one exact stop to the next; a waypoint that starts
    a timed stretch is reached by an untimed motion from the one before.
    """
    run_kind = "ruckig" if method == "ruckig" else "toppra"
    joint_kind = "toppra" if method == "toppra" else "ruckig"
    stops = np.flatnonzero(moves.stop)
    first, last = stops[:-1], stops[1:]
    single_joint = (last == first + 1) & (moves.kind[last] == JOINT)
    kinds = np.where(moves.start[last], "untimed", np.where(single_joint, joint_kind, run_kind))
    return list(zip(kinds.tolist(), first.tolist(), last.tolist()))


def _timed(kind, runs, moves, robot):
    """Time a run's windows, lowering the limits a sample exceeds until the dense check passes: (laws, Peaks)."""
    if kind == "toppra":
        from trajcomp.timing.toppra_run import toppra_laws as laws_of
    else:  # a ruckig run is one window
        from trajcomp.timing.ruckig_move import ruckig_law

        def laws_of(runs, *args):
            return [ruckig_law(runs[0], *args)]
    velocity, acceleration, speed = np.ones(6), np.ones(6), 1.0
    for _ in range(_RETRIES):
        laws = laws_of(runs, moves, robot, velocity, acceleration, speed)
        peaks = Peaks.worst_of([segment_peaks(run, law, moves, jerk=kind == "ruckig")
                                for run, law in zip(runs, laws) if law is not None])
        if peaks.worst <= _TARGET:
            break
        velocity = velocity / np.maximum(peaks.velocity_ratio, 1.0)
        acceleration = acceleration / np.maximum(peaks.acceleration_ratio, 1.0)
        speed = speed / max(peaks.speed_ratio, 1.0)
    return laws, peaks


def _turn_warnings(moves, arrived):
    """Messages for waypoints a LIN / CIRC reaches in another turn of a joint than declared."""
    out = []
    for lo in range(0, len(arrived), _BLOCK):
        off = np.abs(arrived[lo : lo + _BLOCK] - moves.q[lo : lo + _BLOCK]) > 1e-6
        for i in np.flatnonzero(off.any(axis=1)):
            k = lo + i
            joints = ", ".join(f"J{j + 1} at {np.degrees(arrived[k, j]):.1f} deg, not {np.degrees(moves.q[k, j]):.1f}"
                               for j in np.flatnonzero(off[i]))
            out.append(f"the {moves.kind[k]} motion reaches {moves.labels[k]} with {joints} (a linear or circular "
                       "motion turns continuously; the declared turn applies to joint motions)")
    return tuple(out)


def _result(moves, robot, arrived, t, segments, pieces, peaks, untimed, tcp_length, deviation):
    def peak(name):
        values = np.array([getattr(p, name) for p in peaks]).reshape(-1, 6)
        return np.max(np.nan_to_num(values, nan=0.0), axis=0, initial=0.0)

    velocity, acceleration = peak("velocity"), peak("acceleration")
    jerk = np.where(np.isfinite(robot.j_max), peak("jerk"), 0.0)  # measured in ruckig segments, jerk-limited
    worst = max([p.worst for p in peaks], default=0.0)
    jerk_ok = np.all(jerk <= robot.j_max * (1.0 + LIMIT_TOLERANCE))
    return TimingResult(
        t=t,
        cycle_time=float(t[-1]) if len(t) else 0.0,
        segments=tuple(segments),
        peak_velocity=velocity,
        peak_acceleration=acceleration,
        peak_jerk=jerk,
        limit_velocity=robot.v_max,
        limit_acceleration=robot.a_max,
        limit_jerk=robot.j_max,
        within_limits=bool(worst <= 1.0 + LIMIT_TOLERANCE and jerk_ok),
        peak_speed_ratio=max([p.speed_ratio for p in peaks], default=0.0),
        q=arrived,
        tcp_length=tcp_length,
        labels=moves.labels,
        motion=moves.motion,
        untimed=tuple(untimed),
        deviation=deviation,
        warnings=_turn_warnings(moves, arrived),
        pieces=tuple(pieces),
    )
