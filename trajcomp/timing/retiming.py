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
half the tolerance, a TOPP-RA segment's grid is refined in the grid
intervals holding such samples (the rest of the segment keeps its
timing), a ruckig segment's limit is lowered by the overshoot, and the
segment is timed again.

Consecutive single motions from rest to rest (a program of exact stops)
are built and timed together, up to `STOP_BATCH` at a time, as arrays
laid end to end: one sampling, one Jacobian batch, one grid and one fit
of their short paths (`trajcomp.timing.path.stop_paths`), one TOPP-RA
problem for their TOPP-RA laws (`trajcomp.timing.toppra_run.rest_to_rest_laws`)
and one 1 kHz check of those (`trajcomp.timing.check.rest_to_rest_checks`);
each is the timing it gets alone.
"""

import dataclasses
import functools
import itertools

import numpy as np

from trajcomp.programs.items import JOINT
from trajcomp.timing.check import (LIMIT_TOLERANCE, Peaks, dense_check, dense_checks, rest_to_rest_checks,
                                   segment_peaks)
from trajcomp.timing.moves import corner_lengths
from trajcomp.timing.options import RETIME_METHODS, TOLERANCE
from trajcomp.timing.path import stop_paths
from trajcomp.timing.result import Segment, TimingResult
from trajcomp.timing.samples import AMBIGUOUS_DEG, swept_changes
from trajcomp.timing.windows import WINDOW, run_windows

_BLOCK = 65536  # waypoints per block of the per-waypoint passes over a long run
STOP_BATCH = 500  # single motions from rest to rest timed together at most
_RETRIES = 6  # ruckig timings of one segment with lowered limits before giving up
_REFINEMENTS = 6  # local refinements of a TOPP-RA run's grid where the dense check finds an overshoot
_SPLIT = 4  # a grid interval to refine is split in this many
_CURVATURE_STEP = 0.25  # share of a joint's acceleration limit the curvature term may change by across a grid interval
_TARGET = 1.0005  # re-time a segment whose samples exceed a limit by more than this (1.000 to three digits)


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
    if method not in RETIME_METHODS:
        raise ValueError(f"method must be one of {RETIME_METHODS}, got {method!r}")
    timeline = _Timeline(moves, robot)
    reached = moves  # the joints each waypoint is reached with: moves.q until one differs, then a copy
    for batch in _batches(plan_segments(moves, method)):
        kind, first, last = batch[0]
        if kind == "untimed":
            timeline.untimed(last)
            continue
        last = batch[-1][2]
        swept = functools.partial(_swept, moves, robot, first)
        for lo, hi, block in _continued(reached.q[first], moves.q[first : last + 1], moves.kind[first + 1 : last + 1],
                                        swept):
            rows = slice(first + lo, first + hi)
            if reached is moves and np.array_equal(block, moves.q[rows]):
                continue
            if reached is moves:  # a waypoint reached in another turn than declared: the joints copied once
                reached = dataclasses.replace(moves, q=moves.q.copy())
            reached.q[rows] = block
        timeline.arrived = reached.q
        if last - first == len(batch):  # exact stops after every motion: timed together
            _time_stops(timeline, batch, stop_paths(reached, robot, first, last), moves, robot)
            continue
        runs = run_windows(reached, robot, first, last, tolerance, WINDOW if kind == "toppra" else None)
        timeline.add(kind, first, last, *_timed(kind, runs, moves, robot))
    return timeline.result()


def _batches(plan):
    """The plan's segments in lists: runs of single motions from rest to rest together (up to `STOP_BATCH`),
    every other segment alone."""
    def single(segment):
        kind, first, last = segment
        return kind != "untimed" and last == first + 1

    for together, group in itertools.groupby(plan, key=single):
        group = list(group)
        if together:
            yield from (group[i : i + STOP_BATCH] for i in range(0, len(group), STOP_BATCH))
        else:
            yield from ([segment] for segment in group)


def _time_stops(timeline, batch, stops, moves, robot):
    """Time single motions from rest to rest (`StopPaths`): TOPP-RA ones as one problem and checked together,
    ruckig ones each; a motion the dense check finds over a limit is timed again alone."""
    from trajcomp.timing.ruckig_move import ruckig_law
    from trajcomp.timing.toppra_run import rest_to_rest_laws

    runs = list(stops.runs)
    laws, peaks, worst = [None] * len(runs), [None] * len(runs), np.zeros(len(runs))
    by_toppra = np.array([r for r, i in enumerate(stops.moving.tolist()) if batch[i][0] == "toppra"], dtype=int)
    if by_toppra.size:
        timed = rest_to_rest_laws(stops, by_toppra, moves)
        checked, worst[stops.moving[by_toppra]] = rest_to_rest_checks(stops, by_toppra, timed, moves, robot)
        for r, i in enumerate(stops.moving[by_toppra].tolist()):
            laws[i], peaks[i] = timed.law(r), checked[r]
    by_ruckig = [i for i in stops.moving.tolist() if laws[i] is None]
    for i in by_ruckig:
        laws[i] = ruckig_law(runs[i], moves, robot)
    for i, (checked, _) in zip(by_ruckig, dense_checks([runs[i] for i in by_ruckig], [laws[i] for i in by_ruckig],
                                                       moves, robot, jerk=[True] * len(by_ruckig))):
        peaks[i], worst[i] = checked, checked.worst
    for i in np.flatnonzero(worst > _TARGET):  # the dense check found an overshoot: the motion timed again alone
        (runs[i],), (laws[i],), peaks[i] = _timed(batch[i][0], [runs[i]], moves, robot)
    timeline.add_stops(batch, runs, laws, peaks)


def _continued(start, declared, kinds, swept=None):
    """The joints a chain of motions reaches its waypoints with from ``start`` (6,), block by block.

    Yields ``(lo, hi, joints (hi - lo, 6))``: waypoints lo .. hi - 1 of the chain (1 <= lo).

    ``declared`` (n, 6) are the waypoints' joints, ``kinds`` (n - 1,) the
    motions into waypoints 1 .. n - 1. A joint motion goes to the declared
    joints. Along linear and circular motions the controller keeps turning
    each joint continuously: a waypoint's declared turn (KUKA T, ABB cf4 /
    cf6, joints a revolution off) does not apply there; each joint moves by
    its declared change wrapped to less than half a turn per motion, or,
    where that turns a joint by more than `AMBIGUOUS_DEG`, by the change
    ``swept(i (m,), change (m, 6))`` finds along the path of the motions
    into waypoints i (near a wrist singularity a joint may turn by more
    than half a turn). Done in blocks of `_BLOCK` waypoints (bounded memory
    on long runs).
    """
    turn = 2.0 * np.pi
    gained = start - declared[0]  # whole turns gained since the last joint motion, (6,)
    for lo in range(1, len(declared), _BLOCK):
        hi = min(lo + _BLOCK, len(declared))
        change = declared[lo:hi] - declared[lo - 1 : hi - 1]
        joint = kinds[lo - 1 : hi - 1] == JOINT
        if np.all(np.abs(change) < 0.5 * np.pi):  # no motion wraps: the turns gained hold up to the first joint motion
            reset = np.argmax(joint) if joint.any() else hi - lo
            block = declared[lo:hi].copy()
            block[:reset] += np.round(gained / turn) * turn
            gained = gained * 0.0 if joint.any() else gained
            yield lo, hi, block
            continue
        wrapped = (change + np.pi) % turn - np.pi
        ambiguous = np.flatnonzero(~joint & np.any(np.abs(wrapped) > np.radians(AMBIGUOUS_DEG), axis=1))
        if swept is not None and ambiguous.size:
            wrapped[ambiguous] = swept(lo + ambiguous, wrapped[ambiguous])
        total = gained + np.cumsum(wrapped - change, axis=0)
        last_joint = np.maximum.accumulate(np.where(joint, np.arange(hi - lo), -1))
        offset = np.where(last_joint[:, None] >= 0, total - total[last_joint], total)
        yield lo, hi, declared[lo:hi] + np.round(offset / turn) * turn
        gained = offset[-1]


def _swept(moves, robot, first, waypoints, change):
    """`trajcomp.timing.samples.swept_changes` of the motions into waypoints ``first + waypoints`` (m,)."""
    return swept_changes(moves, robot, first + waypoints, change)


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
    """Time a run's windows until the dense check passes: (runs, laws, Peaks), the runs possibly refined."""
    if kind == "toppra":
        return _toppra_timed(runs, moves, robot)
    laws, peaks = _ruckig_timed(runs[0], moves, robot)
    return runs, laws, peaks


def _toppra_timed(runs, moves, robot):
    """TOPP-RA on a run's windows, the grid refined where it is too coarse: (runs, laws, Peaks).

    TOPP-RA holds the limits at grid points, with one path acceleration per
    grid interval. Between two points the path's curvature (a blended
    corner) or its TCP rate can take a 1 kHz sample over a limit, and where
    the curvature's share of the joint acceleration changes a lot across an
    interval the one path acceleration that suits both ends is slow.
    Such grid intervals are split in `_SPLIT` and the run timed again, up
    to `_REFINEMENTS` times: the overshoot shrinks with the square of the
    interval, and the rest of the run keeps its timing. A run still over a
    limit after that (not seen on the benchmark's programs) runs its timing
    uniformly slower by the factor that brings every sample within.
    """
    from trajcomp.timing.toppra_run import toppra_laws

    for refinement in range(_REFINEMENTS + 1):
        laws = toppra_laws(runs, moves, robot)
        checks = [None if law is None else dense_check(run, law, moves, robot, jerk=False, over=_TARGET)
                  for run, law in zip(runs, laws)]
        peaks = Peaks.worst_of([check[0] for check in checks if check is not None])
        coarse = [None if law is None else _coarse(run, law, check, moves) for run, law, check in zip(runs, laws, checks)]
        if not any(c is not None and c.size for c in coarse) or refinement == _REFINEMENTS:
            break
        runs = [run if c is None or not c.size else _split(run, c, moves, robot) for run, c in zip(runs, coarse)]
    if peaks.worst > _TARGET:
        factor = _TARGET * max(np.sqrt(peaks.acceleration_ratio.max()), peaks.velocity_ratio.max(), peaks.speed_ratio)
        laws = [None if law is None else law.stretched(factor) for law in laws]
        peaks = _peaks(runs, laws, moves, robot, jerk=False)
    return runs, laws, peaks


def _coarse(run, law, check, moves):
    """Grid intervals (n,) of a timed run to split: one holding a sample over `_TARGET` (``check``: the
    `trajcomp.timing.check.dense_check` of the run with ``over=_TARGET``), or `_curved` at the law's squared
    speed."""
    _, s_over = check
    over = np.clip(np.searchsorted(run.grid, s_over, side="right") - 1, 0, len(run.grid) - 2)
    return np.union1d(over, _curved(run, law.sd**2, moves))


def _curved(run, x, moves):
    """Grid intervals (n,) across which the joint (or a moving track's) acceleration the path's curvature takes at
    squared path speeds x (G,) (q'' sd^2) changes by more than `_CURVATURE_STEP` of a limit."""
    acceleration = np.min(moves.acceleration[run.first + 1 : run.last + 1], axis=0)
    demand = np.max(np.abs(run.path(run.grid, 2)) / acceleration, axis=1)  # per unit squared path speed
    if run.track is not None:  # a moving track's too, as a joint's
        track = np.min(moves.track_acceleration[run.first + 1 : run.last + 1])
        demand = np.maximum(demand, np.abs(run.track(run.grid, 2)) / track)
    step = np.abs(np.diff(demand)) * np.maximum(x[:-1], x[1:])
    return np.flatnonzero(step > _CURVATURE_STEP)


def _split(run, intervals, moves, robot):
    """The run with grid intervals ``intervals`` (n,) each split in `_SPLIT`."""
    grid = run.grid
    split = grid[intervals, None] + np.outer(grid[intervals + 1] - grid[intervals], np.arange(1, _SPLIT) / _SPLIT)
    return run.refined(moves, robot, split.ravel())


def _ruckig_timed(run, moves, robot):
    """A ruckig law along a run, its limits lowered by what a sample exceeds until the dense check passes.

    ruckig times the path position as one degree of freedom under bounds
    that hold for the whole run, so a lower bound is the only lever.
    """
    from trajcomp.timing.ruckig_move import ruckig_law

    velocity, acceleration, speed = np.ones(6), np.ones(6), 1.0
    best = None
    for _ in range(_RETRIES):
        laws = [ruckig_law(run, moves, robot, velocity, acceleration, speed)]
        peaks = _peaks([run], laws, moves, robot, jerk=True)
        if best is None or peaks.worst < best[1].worst:
            best = laws, peaks
        if peaks.worst <= _TARGET:
            break
        velocity = velocity / np.maximum(peaks.velocity_ratio, 1.0)
        acceleration = acceleration / np.maximum(peaks.acceleration_ratio, 1.0) ** 1.5
        speed = speed / max(peaks.speed_ratio, 1.0)
    return best


def _peaks(runs, laws, moves, robot, *, jerk):
    """The dense check's worst of a run's timed windows."""
    return Peaks.worst_of([segment_peaks(run, law, moves, robot, jerk=jerk)
                           for run, law in zip(runs, laws) if law is not None])


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


def _programmed_lengths(moves, robot, timed):
    """TCP length (M,) of each motion as programmed: `corner_lengths` of the linear and circular motions with a
    blended corner at either end, the ``timed`` length (M,) of the others."""
    corner = ~moves.stop & (moves.zone > 0)
    k = np.flatnonzero(corner[:-1] | corner[1:]) + 1
    k = k[(moves.kind[k] != JOINT) & ~moves.start[k]]
    out = np.array(timed, dtype=float)
    out[k] = np.maximum(out[k], corner_lengths(moves, robot, k))
    return out


class _Timeline:
    """What re-timing has found so far, segment by segment, and the `TimingResult` it makes."""

    def __init__(self, moves, robot):
        self.moves, self.robot = moves, robot
        self.t, self.tcp_length = np.zeros(len(moves)), np.zeros(len(moves))
        self.arrived = moves.q  # replaced by a copy when a waypoint is reached in another turn
        self.segments, self.pieces, self.untimed_at, self.deviation = [], [], [], 0.0
        self.peaks, self.checked = [], []  # the dense check's Peaks and the segment of each

    def untimed(self, k):
        """Waypoint k is reached by a motion that is not timed (its start is unknown)."""
        self.t[k] = self.t[k - 1]
        self.untimed_at.append(k)

    def add(self, kind, first, last, runs, laws, peaks):
        """A segment timed in windows ``runs`` with ``laws`` (None for a window without length), checked to ``peaks``."""
        self.tcp_length[first + 1 : last + 1] = np.concatenate([run.tcp_lengths[1:] for run in runs])
        self.deviation = max(self.deviation, *(run.deviation for run in runs))
        start = self.t[first]
        for run, law in zip(runs, laws):
            if law is None:
                self.t[run.first + 1 : run.last + 1] = start
                continue
            self.t[run.first + 1 : run.last + 1] = start + law.time_at(run.s_waypoints[1:])
            self.t[run.last] = start + law.duration
            self.pieces.append((start, run, law))
            start += law.duration
        jerk_limited = kind == "ruckig" and bool(np.all(np.isfinite(self.robot.j_max)))
        self.segments.append(Segment(kind, first, last, start - self.t[first], jerk_limited=jerk_limited))
        if peaks is not None:
            self.peaks.append(peaks)
            self.checked.append(self.segments[-1])

    def add_stops(self, batch, runs, laws, peaks):
        """Single motions from rest to rest, segments ``batch`` [(kind, k - 1, k)], timed as ``runs`` with ``laws``
        (None for a motion without length), checked to ``peaks`` (None likewise)."""
        k = np.array([last for _, _, last in batch], dtype=int)
        durations = np.array([0.0 if law is None else law.duration for law in laws])
        self.tcp_length[k] = [run.tcp_lengths[-1] for run in runs]
        self.deviation = max(self.deviation, *(run.deviation for run in runs))
        self.t[k] = np.cumsum(np.r_[self.t[k[0] - 1], durations])[1:]
        jerk_limited = bool(np.all(np.isfinite(self.robot.j_max)))
        for (kind, first, last), run, law, checked in zip(batch, runs, laws, peaks):
            self.segments.append(Segment(kind, first, last, float(self.t[last] - self.t[first]),
                                         jerk_limited=jerk_limited and kind == "ruckig"))
            if law is not None:
                self.pieces.append((float(self.t[first]), run, law))
                self.peaks.append(checked)
                self.checked.append(self.segments[-1])

    def result(self):
        """The `TimingResult`."""
        moves, peaks, robot = self.moves, self.peaks, self.robot

        def peak(name):
            values = np.array([getattr(p, name) for p in peaks]).reshape(-1, 6)
            return np.fmax.reduce(values, axis=0, initial=np.nan) if len(values) else np.full(6, np.nan)

        velocity, acceleration = np.nan_to_num(peak("velocity")), np.nan_to_num(peak("acceleration"))
        limited = [p.jerk for p, s in zip(peaks, self.checked) if s.jerk_limited]
        jerk = np.fmax.reduce(np.reshape(limited, (-1, 6)), axis=0, initial=np.nan) if limited else np.full(6, np.nan)
        worst = max([p.worst for p in peaks], default=0.0)
        jerk_ok = not np.any(jerk > robot.j_max * (1.0 + LIMIT_TOLERANCE))
        return TimingResult(
            t=self.t,
            cycle_time=float(self.t[-1]) if len(self.t) else 0.0,
            segments=tuple(self.segments),
            peak_velocity=velocity,
            peak_acceleration=acceleration,
            peak_jerk=jerk,
            limit_velocity=robot.v_max,
            limit_acceleration=robot.a_max,
            limit_jerk=robot.j_max,
            within_limits=bool(worst <= 1.0 + LIMIT_TOLERANCE and jerk_ok),
            peak_speed_ratio=max([p.speed_ratio for p in peaks], default=0.0),
            q=self.arrived,
            tcp_length=self.tcp_length,
            programmed_length=_programmed_lengths(moves, robot, self.tcp_length),
            labels=moves.labels,
            motion=moves.motion,
            untimed=tuple(self.untimed_at),
            deviation=self.deviation,
            warnings=() if self.arrived is moves.q else _turn_warnings(moves, self.arrived),
            pieces=tuple(self.pieces),
        )
