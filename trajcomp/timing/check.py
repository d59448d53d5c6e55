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
from trajcomp.timing.path import tcp_jacobians

RATE = 1000.0  # Hz
LIMIT_TOLERANCE = 0.01  # a sampled value may exceed its limit by this share
_JACOBIAN_BLOCK = 65536  # samples whose TCP Jacobians are held at a time
MAX_SAMPLES = 1_000_000  # per run between two stops (1,000 s at 1 kHz): the check's memory grows with them


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


def dense_check(run, law, moves, robot, *, jerk, rate=RATE):
    """`segment_peaks`, and where: each sample's path position and its largest ratio to a limit.

    Returns
    -------
    peaks : Peaks
    s : ndarray, shape (N,)
        Path position of each sample, rad.
    ratio : ndarray, shape (N,)
        Largest sampled joint velocity, acceleration or TCP speed over its limit at each sample.
    """
    return dense_checks([run], [law], moves, robot, jerk=[jerk], rate=rate)[0]


def dense_checks(runs, laws, moves, robot, *, jerk, rate=RATE):
    """`dense_check` of several timed runs (a batch of exact stops), their TCP Jacobians computed together.

    Parameters
    ----------
    runs : list of RunPath
    laws : list of ConstantAcceleration or RuckigLaw
    moves : Moves
    robot : Robot
    jerk : list of bool
        Measure the jerk of each run.
    rate : float
        Hz.

    Returns
    -------
    list of (Peaks, s (N,), ratio (N,))
    """
    if not runs:
        return []
    parts = []
    for run, law in zip(runs, laws):
        if not law.duration * rate <= MAX_SAMPLES:
            first, last = run.motion_at(np.array([0.0, run.length]), side="right")
            raise TimingError(f"the motions from {moves.labels[first]} to {moves.labels[last]} last {law.duration:.4g} s "
                              f"between two stops at their programmed speeds, beyond the {MAX_SAMPLES / rate:g} s the "
                              "dense check covers: a speed no process uses (a unit or a typo?)")
        t = sample_times(law.duration, rate)
        q, qd, qdd, s, _ = evaluate(run, law, t)
        parts.append((t, q, qd, qdd, s, run.motion_at(s)))
    q, qd, k = (np.concatenate([part[i] for part in parts]) for i in (1, 2, 5))
    speed_ratios = np.split(_speed_ratios(moves, robot, k, q, qd), np.cumsum([len(part[0]) for part in parts])[:-1])
    out = []
    for (t, q, qd, qdd, s, k), speed_ratio, measure_jerk in zip(parts, speed_ratios, jerk):
        velocity_ratio, acceleration_ratio = np.abs(qd) / moves.velocity[k], np.abs(qdd) / moves.acceleration[k]
        jerk_peak = np.full(6, np.nan)
        if measure_jerk and len(t) > 1:
            jerk_peak = np.max(np.abs(np.diff(qdd, axis=0)) / np.diff(t)[:, None], axis=0)
        peaks = Peaks(
            velocity=np.abs(qd).max(axis=0),
            acceleration=np.abs(qdd).max(axis=0),
            jerk=jerk_peak,
            velocity_ratio=velocity_ratio.max(axis=0),
            acceleration_ratio=acceleration_ratio.max(axis=0),
            speed_ratio=float(speed_ratio.max(initial=0.0)),
        )
        ratio = np.maximum(np.maximum(velocity_ratio.max(axis=1), acceleration_ratio.max(axis=1)), speed_ratio)
        out.append((peaks, s, ratio))
    return out


def _speed_ratios(moves, robot, k, q, qd):
    """TCP speed |J(q) q'| over the programmed one (N,) of samples on linear / circular motions with a speed, else 0."""
    ratio = np.zeros(len(k))
    rows = np.flatnonzero((moves.kind[k] != JOINT) & np.isfinite(moves.tcp_speed[k]))
    for lo in range(0, len(rows), _JACOBIAN_BLOCK):  # the Jacobians of a block at a time: bounded memory
        part = rows[lo : lo + _JACOBIAN_BLOCK]
        jac = tcp_jacobians(robot, moves, k[part], q[part])
        speed = np.linalg.norm(np.einsum("nij,nj->ni", jac[:, :3], qd[part]), axis=1)
        ratio[part] = speed / moves.tcp_speed[k[part]]
    return ratio
