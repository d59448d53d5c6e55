"""TOPP-RA time-optimal parametrization of a run's path under joint and TCP speed limits.

TOPP-RA (Pham & Pham 2018) bounds the squared path speed x = sd^2 and the
path acceleration u = sdd on a grid; here with a grid point on every path
sample (every waypoint), solved by `trajcomp.timing.reachability` (the
same discretization as toppra's seidel solver, vectorized), and the
constant-acceleration time law: u is constant between grid points, exactly
as TOPP-RA's discretization assumes, so the time law between grid points
is the one the solver checked (a spline through the grid velocities
overshoots between grid points). Limits hold only at grid points:
`trajcomp.timing.check` verifies them densely afterwards.

Constraints per grid point s_i:

- joint velocity: ``|q'_j(s_i)| sd <= v_j`` and programmed TCP speed
  ``|J_pos q'(s_i)| sd <= v_tcp``: one bound on x;
- joint acceleration: ``|q'_j u + q''_j x| <= a_j`` (interpolation scheme).
"""

import dataclasses

import numpy as np

from trajcomp.errors import TimingError
from trajcomp.timing.path import squared_speed_bound, tcp_limits, time_limits
from trajcomp.timing.reachability import Bands, backward, forward, squared_speeds
from trajcomp.timing.track import with_track

_X_CAP = 1e12  # (rad/s)^2 ceiling of the squared path speed where no limit binds
GROUP_POINTS = 1 << 15  # grid points of consecutive windows solved as one problem at most


@dataclasses.dataclass(frozen=True, eq=False)
class ConstantAcceleration:
    """A time law s(t) with constant path acceleration between grid points.

    Attributes
    ----------
    s, sd : ndarray, shape (G,)
        Grid points (rad of path) and path speed there (1/s).
    t : ndarray, shape (G,)
        Time at each grid point, s.
    u : ndarray, shape (G - 1,)
        Path acceleration on each interval.
    """

    s: np.ndarray
    sd: np.ndarray
    t: np.ndarray
    u: np.ndarray

    @classmethod
    def from_speeds(cls, s, sd):
        """The law of grid points s (G,) and speeds sd (G,) (toppra's ParametrizeConstAccel).

        Raises
        ------
        ValueError
            The path speed is zero on a whole interval.
        """
        laws = ConstantAccelerations.from_speeds(s, sd, np.array([len(s)]))
        if laws.stuck.size:
            raise ValueError("the path speed is zero on a whole interval")
        return laws.law(0)

    @property
    def duration(self):
        return float(self.t[-1])

    def stretched(self, factor):
        """The same path run ``factor`` (>= 1) times slower: speeds / factor, accelerations / factor^2."""
        return dataclasses.replace(self, sd=self.sd / factor, t=self.t * factor, u=self.u / factor**2)

    def __call__(self, t):
        """s, sd, sdd (each (N,)) at times t (N,)."""
        i = np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.u) - 1)
        dt = t - self.t[i]
        u = self.u[i]
        return self.s[i] + self.sd[i] * dt + 0.5 * u * dt**2, self.sd[i] + u * dt, u

    def time_at(self, s):
        """Times (N,) at which the law passes path positions s (N,)."""
        i = np.clip(np.searchsorted(self.s, s, side="right") - 1, 0, len(self.u) - 1)
        ahead = np.maximum(np.asarray(s) - self.s[i], 0.0)
        root = np.sqrt(np.maximum(self.sd[i] ** 2 + 2.0 * self.u[i] * ahead, 0.0))
        with np.errstate(invalid="ignore", divide="ignore"):
            dt = np.where(ahead > 0, 2.0 * ahead / (self.sd[i] + root), 0.0)
        return self.t[i] + dt


class ConstantAccelerations:
    """Constant-acceleration laws laid end to end (motions from rest to rest: thousands of short laws).

    Law r is grid points ``offsets[r] .. offsets[r + 1] - 1`` of the
    arrays, its times from 0.

    Attributes
    ----------
    s, sd, t : ndarray, shape (G,)
        Grid points (each law's path positions), path speed and time there.
    u : ndarray, shape (G,)
        Path acceleration on the interval each grid point begins (0 at a law's last point).
    offsets : ndarray of int, shape (R + 1,)
    stuck : ndarray of int, shape (m,)
        Grid points (indices into the arrays) beginning an interval on which the path speed is zero at both
        ends (no law: the path cannot be run there).
    """

    def __init__(self, s, sd, t, u, offsets, stuck):
        self.s, self.sd, self.t, self.u, self.offsets, self.stuck = s, sd, t, u, offsets, stuck
        self.durations = t[offsets[1:] - 1]
        self._shift = np.r_[0.0, np.cumsum(self.durations + 1.0)[:-1]]  # the laws apart in time, for the lookup
        self._key = t + np.repeat(self._shift, np.diff(offsets))

    @classmethod
    def from_speeds(cls, s, sd, sizes):
        """The laws of grids s (G,) with speeds sd (G,), ``sizes`` (R,) points each (at least 2)."""
        offsets = np.r_[0, np.cumsum(sizes)]
        ds = np.diff(s)
        with np.errstate(divide="ignore", invalid="ignore"):
            dt = 2.0 * ds / (sd[:-1] + sd[1:])
            u = np.append(0.5 * np.diff(sd**2) / ds, 0.0)
        between = offsets[1:-1] - 1  # the steps from one law's last point to the next one's first
        dt[between], u[between] = 0.0, 0.0
        stuck = np.flatnonzero(~np.isfinite(dt))
        elapsed = np.r_[0.0, np.cumsum(dt)]
        return cls(s, sd, elapsed - np.repeat(elapsed[offsets[:-1]], sizes), u, offsets, stuck)

    def law(self, r):
        """Law r as a `ConstantAcceleration` (views)."""
        lo, hi = self.offsets[r], self.offsets[r + 1]
        return ConstantAcceleration(self.s[lo:hi], self.sd[lo:hi], self.t[lo:hi], self.u[lo : hi - 1])

    def __call__(self, law, t):
        """s, sd, sdd (each (N,)) of laws ``law`` (N,) at their times t (N,)."""
        i = np.searchsorted(self._key, t + self._shift[law], side="right") - 1
        i = np.clip(i, self.offsets[law], self.offsets[law + 1] - 2)
        dt = t - self.t[i]
        u = self.u[i]
        return self.s[i] + self.sd[i] * dt + 0.5 * u * dt**2, self.sd[i] + u * dt, u


def toppra_laws(runs, moves, robot):
    """The time-optimal constant-acceleration laws of a run's windows, at rest at both ends of the run.

    Consecutive windows share a grid point (a waypoint). They are solved
    in groups of up to `GROUP_POINTS` grid points, each group one problem
    (the windows' intervals laid end to end, each with its own window's
    path): the backward pass goes through the groups from the last to the
    first, each ending at the bound its successor found for the shared
    point, and the forward pass from the first to the last, each starting
    at the speed its predecessor reached there. So the path speed is
    continuous at every join and the laws are those of one TOPP-RA problem
    over the whole run, and a group's passes sweep its windows together
    (a long ramp across windows settles in one set of sweeps). A window
    without length is a rest point.

    Parameters
    ----------
    runs : list of RunPath
        Consecutive windows of one run (`trajcomp.timing.windows.run_windows`), or one run.
    moves : Moves
        Limits of each motion.
    robot : Robot
        For the TCP Jacobian.

    Returns
    -------
    list of ConstantAcceleration or None
        One per window (None for one without length).

    Raises
    ------
    TimingError
        The path speed must be zero over a whole grid interval (a singular
        or kinked path): names the waypoint, its line and the joint.
    """
    groups = _groups(runs)
    bounds, end = [None] * len(runs), 0.0
    for group in reversed(groups):
        if runs[group[0]].path is None:
            end = 0.0
            continue
        bands, offsets, x_max = _joined_problem([runs[i] for i in group], moves, with_bound=True)
        h = backward(bands, x_max, end)
        del bands  # before the next group's are made
        for i, lo, hi in zip(group, offsets[:-1], offsets[1:]):
            bounds[i] = h[lo : hi + 1]
        end = h[0]
    laws, start = [None] * len(runs), 0.0
    for group in groups:
        if runs[group[0]].path is None:
            start = 0.0
            continue
        bands, offsets, _ = _joined_problem([runs[i] for i in group], moves, with_bound=False)
        x = forward(bands, np.concatenate([bounds[group[0]], *(bounds[i][1:] for i in group[1:])]), start)
        del bands
        start = x[-1]
        for i, lo, hi in zip(group, offsets[:-1], offsets[1:]):
            run, x_run = runs[i], x[lo : hi + 1]
            try:
                laws[i] = ConstantAcceleration.from_speeds(run.grid, np.sqrt(x_run))
            except ValueError:
                stop = int(np.argmin(x_run[:-1] + x_run[1:]))
                raise _stuck(run, moves, run.grid, stop, run.path(run.grid, 1), run.speed_bound(moves)[1]) from None
    return laws


def _groups(runs):
    """Indices of consecutive windows solved together (lists): up to `GROUP_POINTS` grid points; a window
    without length alone."""
    groups, points = [], 0
    for i, run in enumerate(runs):
        alone = run.path is None
        if not groups or alone or runs[groups[-1][-1]].path is None or points + len(run.grid) > GROUP_POINTS:
            groups.append([i])
            points = len(run.grid)
        else:
            groups[-1].append(i)
            points += len(run.grid) - 1
    return groups


def _joined_problem(runs, moves, *, with_bound):
    """Consecutive windows with paths as one problem: their `Bands` laid end to end, the offsets (W + 1,)
    of each window's first grid point in it (and of the last point), and with ``with_bound`` the bound
    on x (G,) (at a shared point the lower of the two windows')."""
    offsets, bound = np.cumsum([0] + [len(run.grid) - 1 for run in runs]), []

    def paths():  # one window's path derivatives at a time
        for run in runs:
            grid, dq, ddq, acceleration = _path_problem(run, moves)
            if with_bound:
                x_max = np.minimum(run.speed_bound(moves, dq=dq[:, :6])[0], _X_CAP)
                if bound:
                    bound[-1][-1] = min(bound[-1][-1], x_max[0])
                    x_max = x_max[1:]
                bound.append(x_max)
            yield np.diff(grid), dq, ddq, acceleration

    bands = Bands.of_paths(paths(), offsets[-1])
    return bands, offsets, (np.concatenate(bound) if with_bound else None)


def rest_to_rest_laws(stops, paths, moves):
    """The time-optimal laws of independent paths, each at rest at both ends, solved as one problem.

    The paths' grids are laid end to end (a unit gap between them) with
    the path speed 0 at each path's ends, so one pair of reachability
    passes times them all (a program of exact stops: thousands of short
    runs).

    Parameters
    ----------
    stops : StopPaths
        Motions from rest to rest (`trajcomp.timing.path.stop_paths`).
    paths : ndarray of int, shape (R,)
        Which of its paths (indices into ``stops.moving``).
    moves : Moves

    Returns
    -------
    ConstantAccelerations
        Law r: path ``paths[r]``.

    Raises
    ------
    TimingError
        A path whose speed must be zero over a whole grid interval.
    """
    points, sizes, k = stops.points(paths), stops.sizes[paths], stops.motion[paths]
    grid, dq, ddq = stops.grid[points], stops.dq[points], stops.ddq[points]
    velocity = np.repeat(moves.velocity[k], sizes, axis=0)
    tcp = np.repeat(tcp_limits(moves, k, stops.tcp_length[paths]), sizes)
    timed = np.repeat(time_limits(moves, k, stops.pieces.ends[paths]) ** 2, sizes)
    x_max = np.minimum(np.minimum(squared_speed_bound(dq, stops.rate[points], velocity, tcp), timed), _X_CAP)
    ends = np.cumsum(sizes)
    shift = np.r_[0.0, np.cumsum(stops.pieces.ends[paths] + 1.0)[:-1]]
    acceleration = np.repeat(moves.acceleration[k], sizes, axis=0)[:-1]
    bands = dq, ddq, acceleration
    if moves.on_track:  # the track's position a 7th joint: paths laid end to end, none within another
        bands = with_track(moves, np.repeat(k, sizes), grid, dq, ddq, stops.rate[points], acceleration,
                           ~np.isin(np.arange(len(grid) - 1), ends[:-1] - 1))
    x = squared_speeds(grid + np.repeat(shift, sizes), *bands, x_max, np.r_[ends - sizes, ends - 1],
                       ramp=int(sizes.max()))
    laws = ConstantAccelerations.from_speeds(grid, np.sqrt(x), sizes)
    if laws.stuck.size:
        i = int(laws.stuck[0])
        r = int(np.searchsorted(ends, i, side="right"))
        lo = ends[r] - sizes[r]
        run = stops.runs[stops.moving[paths[r]]]
        raise _stuck(run, moves, run.grid, i - lo, dq[lo : ends[r]], velocity[lo : ends[r]])
    return laws


def _path_problem(run, moves):
    """What the forward pass needs of a run: grid (G,), q' and q'' there (G, n), acceleration limits (n,): the
    arm's joints, and a moving track's position (`trajcomp.timing.track.with_track`)."""
    acceleration = np.min(moves.acceleration[run.first + 1 : run.last + 1], axis=0)
    grid, dq, ddq = run.grid, run.path(run.grid, 1), run.path(run.grid, 2)
    if moves.on_track:
        track = None if run.track is None else (run.track(grid, 1), run.track(grid, 2))
        return grid, *with_track(moves, run.motion_at(grid), grid, dq, ddq, run.grid_rate, acceleration, track=track)
    return grid, dq, ddq, acceleration


def _where(run, moves, grid_s):
    """'the motion to P3 (weld.dat:4), 40 % of its way' for a path position."""
    k = int(run.motion_at(np.array([grid_s]))[0])
    lo, hi = run.s_waypoints[k - run.first - 1], run.s_waypoints[k - run.first]
    share = 0.0 if hi <= lo else 100.0 * (grid_s - lo) / (hi - lo)
    return f"the {moves.kind[k]} motion to {moves.labels[k]}, {share:.0f} % of its way"


def _stuck(run, moves, grid, i, dq, velocity):
    """TimingError for a path whose speed must be zero over a whole grid interval."""
    ratio = np.abs(dq[i]) / velocity
    j = int(np.argmax(ratio))
    return TimingError(
        f"the arm would have to stand still at {_where(run, moves, grid[i])}: J{j + 1} needs an unbounded "
        f"speed there (limit {np.degrees(velocity[i, j]):.0f} deg/s); the path is singular or kinked"
    )
