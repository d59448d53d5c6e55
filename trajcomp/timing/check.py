"""The dense check: a timed segment sampled at 1 kHz against its limits.

TOPP-RA enforces limits at grid points only, and a ruckig law on a curved
path bounds the path, not each joint: the only statement that holds
between grid points is a measured one. Each segment is sampled every
1 ms (and at its end); joint velocity and acceleration come from the path
derivatives and the time law (q' sd, q'' sd^2 + q' sdd), jerk from the
finite difference of the sampled acceleration (ruckig segments only: a
TOPP-RA law has piecewise-constant path acceleration, its jerk is not
bounded and not measured), and the TCP speed of linear and circular
motions from the Jacobian at each sample, |J(q) q'| sd, against the speed
the program asked.
"""

import dataclasses

import numpy as np

from trajcomp.errors import TimingError
from trajcomp.programs.items import JOINT
from trajcomp.timing.path import tcp_speeds

RATE = 1000.0  # Hz
LIMIT_TOLERANCE = 0.01  # a sampled value may exceed its limit by this share
BLOCK = 16384  # samples checked at a time: the check's memory does not grow with the duration
# per run between two stops: a day at 1 kHz (wire-arc additive layers run over an hour); its check takes seconds per
# million samples
MAX_SAMPLES = 86_400_000


@dataclasses.dataclass(frozen=True)
class Peaks:
    """What the dense check measured on one segment.

    Attributes
    ----------
    velocity, acceleration, jerk : ndarray, shape (6,)
        Peak |q'|, |q''| (rad/s, rad/s^2) and |q'''| (rad/s^3; NaN when not measured).
    velocity_ratio, acceleration_ratio : ndarray, shape (6,)
        Peak of the sampled value over the limit of the motion at that sample.
    speed_ratio : float
        Peak TCP speed over the programmed TCP speed, linear and circular
        motions with one (0 when none).
    """

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    velocity_ratio: np.ndarray
    acceleration_ratio: np.ndarray
    speed_ratio: float

    @classmethod
    def worst_of(cls, peaks):
        """The peaks of several parts of one segment (a non-empty list of Peaks)."""
        return cls(**{f.name: np.fmax.reduce([getattr(p, f.name) for p in peaks]) for f in dataclasses.fields(cls)})

    @property
    def worst(self):
        """The largest ratio of a sampled value over its limit."""
        return float(max(self.velocity_ratio.max(), self.acceleration_ratio.max(), self.speed_ratio))


def sample_times(duration, rate=RATE):
    """Sample times (N,) from 0 every 1/rate s, and ``duration`` itself."""
    return np.r_[np.arange(0.0, duration, 1.0 / rate), duration]


def evaluate(run, law, t):
    """Joints, velocities and accelerations (each (N, 6)) of a timed run at times t (N,), and s, sd (N,)."""
    s, sd, sdd = law(t)
    s = np.clip(s, 0.0, run.length)
    dq = run.path(s, 1)
    return run.path(s), dq * sd[:, None], run.path(s, 2) * (sd**2)[:, None] + dq * sdd[:, None], s, sd


def track_motion(run, law, t):
    """A moving track's velocity and acceleration (each (N,)), mm/s and mm/s^2, of a timed run at times t (N,),
    from the run's own track position e(s) (`trajcomp.timing.path.RunPath.track`, which it must have)."""
    s, sd, sdd = law(t)
    s = np.clip(s, 0.0, run.length)
    de = run.track(s, 1)
    return de * sd, run.track(s, 2) * sd**2 + de * sdd


def segment_peaks(run, law, moves, robot, *, jerk, rate=RATE):
    """Sample a timed run at ``rate`` and measure its peaks against the limits of each motion.

    Parameters
    ----------
    run : RunPath
    law : ConstantAcceleration or RuckigLaw
    moves : Moves
    robot : Robot
        The nominal robot (the TCP Jacobian).
    jerk : bool
        Measure the jerk (ruckig segments).

    Returns
    -------
    Peaks
    """
    return dense_check(run, law, moves, robot, jerk=jerk, rate=rate)[0]


def dense_check(run, law, moves, robot, *, jerk, over=np.inf, rate=RATE):
    """`segment_peaks`, and where the samples exceed ``over`` times a limit.

    Returns
    -------
    peaks : Peaks
    s : ndarray, shape (m,)
        Path position (rad) of each sample whose largest ratio of a joint
        velocity, acceleration, the TCP speed or a moving track's velocity
        or acceleration (`track_motion`) to its limit exceeds ``over``.
    """
    return dense_checks([run], [law], moves, robot, jerk=[jerk], over=over, rate=rate)[0]


def dense_checks(runs, laws, moves, robot, *, jerk, over=np.inf, rate=RATE):
    """`dense_check` of several timed runs (a batch of exact stops), their TCP Jacobians computed together.

    The samples of all runs are taken in blocks of `BLOCK` (consecutive
    runs share a block), so the memory is flat in the runs' duration.

    Parameters
    ----------
    runs : list of RunPath
    laws : list of ConstantAcceleration or RuckigLaw
    moves : Moves
    robot : Robot
    jerk : list of bool
        Measure the jerk of each run.
    over : float
        Ratio to a limit above which a sample's path position is returned.
    rate : float
        Hz.

    Returns
    -------
    list of (Peaks, s (m,))
    """
    step = 1.0 / rate
    counts = []  # samples of each run: every 1/rate s from 0, and the end (`sample_times`)
    for run, law in zip(runs, laws):
        if not law.duration * rate <= MAX_SAMPLES:
            first, last = run.motion_at(np.array([0.0, run.length]), side="right")
            raise TimingError(f"the motions from {moves.labels[first]} to {moves.labels[last]} last {law.duration:.4g} s "
                              f"between two stops at their programmed speeds, beyond the {MAX_SAMPLES / rate:g} s the "
                              "dense check covers: a speed no process uses (a unit or a typo?)")
        counts.append(int(np.ceil(law.duration / step)) + 1)
    found = [_Found(measure) for measure in jerk]
    for block in _blocks(counts, BLOCK):
        parts = []
        for i, lo, hi in block:
            t = np.arange(lo, hi) * step
            if hi == counts[i]:
                t[-1] = laws[i].duration
            q, qd, qdd, s, _ = evaluate(runs[i], laws[i], t)
            parts.append((t, q, qd, qdd, s, runs[i].motion_at(s)))
        q, qd, k = (np.concatenate([part[j] for part in parts]) for j in (1, 2, 5))
        speed_ratios = np.split(_speed_ratios(moves, robot, k, q, qd), np.cumsum([len(part[0]) for part in parts])[:-1])
        for (i, _, _), (t, _, qd, qdd, s, k), speed_ratio in zip(block, parts, speed_ratios):
            track = 0.0
            if runs[i].track is not None:  # its samples over a limit refine the grid as a joint's
                velocity, acceleration = track_motion(runs[i], laws[i], t)
                track = np.maximum(np.abs(velocity) / moves.track_velocity[k],
                                   np.abs(acceleration) / moves.track_acceleration[k])
            found[i].add(t, qd, qdd, s, speed_ratio, moves.velocity[k], moves.acceleration[k], over, track)
    return [(f.peaks(), f.s_over()) for f in found]


def rest_to_rest_checks(stops, paths, laws, moves, robot, *, rate=RATE):
    """`segment_peaks` of paths timed from rest to rest with constant-acceleration laws, sampled together.

    The samples of consecutive paths are taken in blocks of about `BLOCK`
    (a path with more is checked alone, by `dense_check`), evaluated and
    reduced per path at once: a program of exact stops is thousands of
    short paths.

    Parameters
    ----------
    stops : StopPaths
    paths : ndarray of int, shape (R,)
        Which of its paths (indices into ``stops.moving``).
    laws : ConstantAccelerations
        Law r: path ``paths[r]`` (`trajcomp.timing.toppra_run.rest_to_rest_laws`).
    moves : Moves
    robot : Robot
    rate : float
        Hz.

    Returns
    -------
    peaks : list of Peaks
        One per path, jerk not measured.
    worst : ndarray, shape (R,)
        `Peaks.worst` of each.
    """
    step = 1.0 / rate
    alone = ~(laws.durations * rate < BLOCK)  # long (or beyond what the check covers: dense_check says so)
    out, worst = [None] * len(paths), np.zeros(len(paths))
    for r in np.flatnonzero(alone):
        out[r] = dense_check(stops.runs[stops.moving[paths[r]]], laws.law(r), moves, robot, jerk=False, rate=rate)[0]
        worst[r] = out[r].worst
    small = np.flatnonzero(~alone)
    counts = np.zeros(len(paths), dtype=int)
    counts[small] = np.ceil(laws.durations[small] / step).astype(int) + 1  # `sample_times`: every 1/rate s, the end
    motion = stops.motion[paths]
    not_measured = np.full(6, np.nan)
    for block in np.split(small, np.flatnonzero(np.diff(np.cumsum(counts[small]) // BLOCK)) + 1):
        if not block.size:
            continue
        n = counts[block]
        law = np.repeat(block, n)
        begins = np.cumsum(n) - n
        t = (np.arange(n.sum()) - np.repeat(begins, n)) * step
        t[begins + n - 1] = laws.durations[block]
        s, sd, sdd = laws(law, t)
        path = paths[law]
        s = np.clip(s, 0.0, stops.pieces.ends[path])
        q, dq, ddq = stops.pieces.derivatives(path, s)
        qd, qdd = dq * sd[:, None], ddq * (sd**2)[:, None] + dq * sdd[:, None]
        k = motion[law]
        velocity, acceleration = np.abs(qd), np.abs(qdd)
        columns = [velocity, acceleration, velocity / moves.velocity[k], acceleration / moves.acceleration[k],
                   _speed_ratios(moves, robot, k, q, qd)[:, None]]
        peaks = [np.maximum.reduceat(column, begins) for column in columns]
        worst[block] = np.max(np.hstack(peaks[2:]), axis=1)
        for j, r in enumerate(block.tolist()):
            out[r] = Peaks(velocity=peaks[0][j], acceleration=peaks[1][j], jerk=not_measured,
                           velocity_ratio=peaks[2][j], acceleration_ratio=peaks[3][j], speed_ratio=float(peaks[4][j, 0]))
    return out, worst


def _blocks(counts, size):
    """Blocks of at most ``size`` samples of runs with ``counts`` (R,) samples: lists of (run, lo, hi)."""
    block, room = [], size
    for i, count in enumerate(counts):
        lo = 0
        while lo < count:
            hi = min(count, lo + room)
            block.append((i, lo, hi))
            room -= hi - lo
            lo = hi
            if not room:
                yield block
                block, room = [], size
    if block:
        yield block


class _Found:
    """The running peaks of one run's samples, taken block by block."""

    def __init__(self, jerk):
        self.measure_jerk = jerk
        self.velocity, self.acceleration, self.velocity_ratio, self.acceleration_ratio = np.zeros((4, 6))
        self.jerk = np.zeros(6) if jerk else np.full(6, np.nan)
        self.speed_ratio, self.over, self.last, self.samples = 0.0, [], None, 0

    def add(self, t, qd, qdd, s, speed_ratio, velocity, acceleration, over, other=0.0):
        """Samples at times t (N,): joint velocities and accelerations (N, 6), path positions s (N,), TCP
        speed ratios (N,), and the limits (N, 6) of each sample's motion; ``other`` (N,): the ratios to their
        limits of what else moves (a track), only for the positions over ``over``."""
        velocity_ratio, acceleration_ratio = np.abs(qd) / velocity, np.abs(qdd) / acceleration
        self.samples += len(t)
        np.maximum(self.velocity, np.abs(qd).max(axis=0), out=self.velocity)
        np.maximum(self.acceleration, np.abs(qdd).max(axis=0), out=self.acceleration)
        np.maximum(self.velocity_ratio, velocity_ratio.max(axis=0), out=self.velocity_ratio)
        np.maximum(self.acceleration_ratio, acceleration_ratio.max(axis=0), out=self.acceleration_ratio)
        self.speed_ratio = max(self.speed_ratio, float(speed_ratio.max(initial=0.0)))
        if self.measure_jerk:  # finite differences, across the block before too
            times, accelerations = t, qdd
            if self.last is not None:
                times, accelerations = np.r_[self.last[0], t], np.vstack([self.last[1], qdd])
            if len(times) > 1:
                jerk = np.abs(np.diff(accelerations, axis=0)) / np.diff(times)[:, None]
                np.maximum(self.jerk, jerk.max(axis=0), out=self.jerk)
            self.last = t[-1], qdd[-1]
        ratio = np.maximum(np.maximum(velocity_ratio.max(axis=1), acceleration_ratio.max(axis=1)),
                           np.maximum(speed_ratio, other))
        self.over.append(s[ratio > over])

    def peaks(self):
        """The `Peaks` of the samples added so far."""
        jerk = self.jerk if self.measure_jerk and self.samples > 1 else np.full(6, np.nan)
        return Peaks(velocity=self.velocity, acceleration=self.acceleration, jerk=jerk,
                     velocity_ratio=self.velocity_ratio, acceleration_ratio=self.acceleration_ratio,
                     speed_ratio=self.speed_ratio)

    def s_over(self):
        """Path positions (m,) of the samples added so far whose largest ratio to a limit exceeded ``over``."""
        return np.concatenate(self.over) if self.over else np.zeros(0)


def _speed_ratios(moves, robot, k, q, qd):
    """TCP speed |J(q) q'| over the programmed one (N,) of samples on linear / circular motions with a speed, else 0."""
    ratio = np.zeros(len(k))
    rows = np.flatnonzero((moves.kind[k] != JOINT) & np.isfinite(moves.tcp_speed[k]))
    ratio[rows] = tcp_speeds(robot, moves, k[rows], q[rows], qd[rows]) / moves.tcp_speed[k[rows]]
    return ratio
