"""The joint path of a continuous run, fitted for TOPP-RA within a stated tolerance.

A run is a chain of motions the arm passes without stopping, or one
motion from rest to rest. Its samples come from `trajcomp.timing.samples`
(the controller's interpolation); then:

1. Parameter: s = joint-space arc length (rad) of the samples; duplicated
   and zero-length waypoints collapse onto one sample.
2. Fit: the cubic spline through the samples. The samples are the
   programmed geometry, blends included, so a single motion and a run
   with a sampled blend are interpolated. Otherwise (corners kept, or
   blends that stay within the tolerance of their corner: a CAM path's
   dense points) the samples' noise (IK solutions of rounded numbers) may
   make the interpolating spline need more than `SMOOTHING_GAIN` times the
   acceleration of a thinned one, which makes TOPP-RA crawl: the thinned
   spline is then taken, a least-squares cubic B-spline with knots on
   every `KNOT_STRIDE` samples, refined where it leaves the tolerance (and
   samples the finest knots still miss weighted more): within `TOLERANCE`
   mm of every sample's TCP and ``TOLERANCE * ROTATION_PER_MM`` rad of its
   orientation (linearized with the Jacobian) and of each joint. The
   tolerance keeps the compensated positions.
3. `JointPath` wraps the spline for TOPP-RA; grid points are every sample,
   subdivided to at least `MIN_GRID` intervals (`STOP_GRID` for a single
   motion from rest to rest: it accelerates, cruises and brakes), and
   refined towards both ends, where the arm starts and stops.
"""

import dataclasses

import numpy as np

from trajcomp.arm.kinematics import fk_and_jacobian, frame_columns, in_blocks
from trajcomp.programs.items import JOINT
from trajcomp.timing.options import TOLERANCE
from trajcomp.timing.samples import run_samples

ROTATION_PER_MM = 1e-3  # rad of orientation tolerance per mm of position tolerance
MIN_GRID = 200  # fewest TOPP-RA grid intervals of a run
STOP_GRID = 50  # fewest grid intervals of a single motion from rest to rest (accelerate, cruise, brake)
END_REFINEMENT = 10  # halvings of the first and last grid interval (rest at both ends)
KNOT_STRIDE = 16  # samples per knot interval of the first thinned fit
SMOOTHING_GAIN = 1.1  # a thinned path is taken when the exact one needs this much more acceleration
_DUPLICATE = 1e-9  # rad, joint distance under which two samples are one
_SAME_JACOBIAN = 1e-7  # rad: a fitted path this close to its samples takes their Jacobians
_NARROWEST = 2  # samples per knot interval at the finest
_PULL, _PULLS = 4.0, 8  # weight factor on samples the finest knots leave outside the tolerance, and how often


class JointPath:
    """A joint path q(s), s in rad of joint-space arc length (toppra's path interface: the tests time it with toppra).

    A spline of `FEWEST_KEPT` to `KEPT_DERIVATIVES` coefficients keeps its
    derivative splines (faster to evaluate: about 15 %); a longer one (a
    path through every sample of a long window) evaluates them from its
    own coefficients, so a timed long run holds one set of coefficients,
    not three, and so does a short one (a motion between two stops, whose
    derivative splines cost as much as its fit and more than they save).

    Parameters
    ----------
    spline : scipy.interpolate.BSpline or scipy.interpolate.PPoly
        Cubic, values (6,).
    """

    KEPT_DERIVATIVES = 4096
    FEWEST_KEPT = 64

    def __init__(self, spline):
        self.spline = spline
        self._derivatives = None
        knots = getattr(spline, "t", None)  # a BSpline's; a PPoly has breakpoints x
        if knots is not None and self.FEWEST_KEPT <= len(spline.c) <= self.KEPT_DERIVATIVES:
            self._derivatives = (spline, spline.derivative(1), spline.derivative(2))
        ends = spline.x if knots is None else knots[spline.k : len(knots) - spline.k]
        self._interval = (ends[0], ends[-1])

    def __call__(self, s, order=0):
        """q (order 0), dq/ds (1) or d2q/ds2 (2) at path positions s (N,): shape (N, 6)."""
        if self._derivatives is None:
            return self.spline(s, order)
        return self._derivatives[order](s)

    @property
    def dof(self):
        return 6

    @property
    def path_interval(self):
        return np.array(self._interval)

class CubicPieces:
    """Cubic joint paths laid end to end, evaluated together (motions from rest to rest: thousands of short paths).

    Path r is the pieces ``offsets[r] .. offsets[r + 1] - 1``, piece i the
    cubic ``c[i, 0] d^3 + c[i, 1] d^2 + c[i, 2] d + c[i, 3]`` of
    d = s - ``start[i]``, s the path's own position (0 at its start,
    ``ends[r]`` at its end).

    Parameters
    ----------
    start : ndarray, shape (P,)
        Path position where each piece begins, rad.
    c : ndarray, shape (P, 4, 6)
        Coefficients, highest power first.
    counts : ndarray of int, shape (R,)
        Pieces of each path (at least one).
    ends : ndarray, shape (R,)
        Length of each path, rad.
    """

    def __init__(self, start, c, counts, ends):
        self.start, self.c, self.ends = start, c, ends
        self.offsets = np.r_[0, np.cumsum(counts)]
        self._shift = np.r_[0.0, np.cumsum(ends + 1.0)[:-1]]  # paths apart on one axis, for the piece lookup
        self._key = start + np.repeat(self._shift, counts)
        self._by_power = None  # c as (4, P, 6), and each path's breakpoints followed by its end: for `ppoly`
        self._breaks = np.empty(len(start) + len(ends))
        self._breaks[np.arange(len(start)) + np.repeat(np.arange(len(ends)), counts)] = start
        self._breaks[self.offsets[1:] + np.arange(len(ends))] = ends

    def __call__(self, path, s, order=0):
        """q (order 0), dq/ds (1) or d2q/ds2 (2), shape (N, 6), of paths ``path`` (N,) at their positions s (N,)."""
        return self.derivatives(path, s, (order,))[0]

    def derivatives(self, path, s, orders=(0, 1, 2)):
        """`__call__` of each order in ``orders``: a list of (N, 6), the pieces looked up once."""
        i = np.searchsorted(self._key, s + self._shift[path], side="right") - 1
        i = np.clip(i, self.offsets[path], self.offsets[path + 1] - 1)
        d = (s - self.start[i])[:, None]
        c = self.c[i]
        c0, c1, c2, c3 = c[:, 0], c[:, 1], c[:, 2], c[:, 3]
        out = []
        for order in orders:
            if order == 0:
                out.append(((c0 * d + c1) * d + c2) * d + c3)
            elif order == 1:
                out.append((3.0 * c0 * d + 2.0 * c1) * d + c2)
            else:
                out.append(6.0 * c0 * d + 2.0 * c1)
        return out

    def ppoly(self, r):
        """Path r as a scipy PPoly."""
        from scipy.interpolate import PPoly

        if self._by_power is None:
            self._by_power = np.ascontiguousarray(self.c.transpose(1, 0, 2))
        lo, hi = self.offsets[r], self.offsets[r + 1]
        return PPoly.construct_fast(self._by_power[:, lo:hi], self._breaks[lo + r : hi + r + 1])

    @classmethod
    def joined(cls, parts, paths):
        """Pieces of several `CubicPieces` in one, path ``paths[j][r]`` of the result being path r of ``parts[j]``."""
        label = np.concatenate([np.repeat(p, np.diff(part.offsets)) for part, p in zip(parts, paths)])
        order = np.argsort(label, kind="stable")
        ends = np.empty(sum(len(p) for p in paths))
        for part, p in zip(parts, paths):
            ends[p] = part.ends
        return cls(np.concatenate([part.start for part in parts])[order],
                   np.concatenate([part.c for part in parts])[order], np.bincount(label, minlength=len(ends)), ends)


@dataclasses.dataclass(frozen=True, eq=False)
class RunPath:
    """The fitted path of waypoints ``first..last`` of a `Moves`.

    Attributes
    ----------
    path : JointPath or None
        None when the run has no length (all waypoints equal).
    s_waypoints : ndarray, shape (last - first + 1,)
        Path position of each waypoint, rad.
    grid : ndarray, shape (G,)
        TOPP-RA grid points: every sample, subdivided.
    first, last : int
    tcp_lengths : ndarray, shape (last - first + 1,)
        TCP path length of the motion into each waypoint, mm (0 for the first).
    grid_rate : ndarray, shape (G,)
        |dp/ds| on the grid: mm of TCP travel per rad of path, each motion with its tool.
    deviation : float
        Largest TCP deviation (mm, linearized) of the path from a sample
        (the programmed geometry).
    track : scipy.interpolate.BSpline or None
        On a moving track, its position e(s) (mm; ``track(s, 1)``,
        ``track(s, 2)``: its derivatives) through the samples' track
        positions (`trajcomp.timing.samples.run_samples`: blended as the
        controller blends the position); None otherwise or for a run of
        motions from rest to rest built together (`stop_paths`: the
        track's share of each motion's progress, `trajcomp.timing.track`).
    """

    path: JointPath
    s_waypoints: np.ndarray
    grid: np.ndarray
    first: int
    last: int
    tcp_lengths: np.ndarray
    grid_rate: np.ndarray
    deviation: float
    track: object = None

    @property
    def length(self):
        return float(self.s_waypoints[-1])

    def motion_at(self, s, side="left"):
        """Waypoint index k of the motion (into waypoint k) each path position s (N,) lies on.

        At a waypoint, ``side="left"`` gives the motion ending there, ``"right"`` the one starting there.
        """
        inner = np.searchsorted(self.s_waypoints, s, side=side)
        return self.first + np.clip(inner, 1, len(self.s_waypoints) - 1)

    def speed_bound(self, moves, velocity_scale=1.0, speed_scale=1.0, dq=None, *, times=True):
        """Largest squared path speed x = sd^2 (G,) on the grid, and the joint velocity limits (G, 6) used.

        A grid point obeys the joint velocity limits and the programmed TCP
        speed (or, for a linear / circular motion with a programmed time,
        its TCP length over that time; for a joint motion with one, its
        path length over that time: `time_limits`), and on a moving track
        its velocity limit (`track`), of the motions it belongs to (both,
        at a waypoint). ``dq`` (G, 6): q' on the grid,
        when already evaluated; ``times=False``: without `time_limits` (a
        ruckig law takes the programmed time as its minimum duration).
        """
        grid = self.grid
        dq = self.path(grid, 1) if dq is None else dq
        near = np.stack([self.motion_at(grid), self.motion_at(grid, "right")])
        if moves.velocity.strides[0] == 0:  # the same limits for every motion (a broadcast view): no gather
            velocity = np.broadcast_to(moves.velocity[0] * velocity_scale, (len(grid), 6))
        else:
            velocity = np.min(moves.velocity[near], axis=0) * velocity_scale
        k, motion = np.arange(self.first + 1, self.last + 1), near - self.first - 1
        tcp = tcp_limits(moves, k, self.tcp_lengths[1:])
        x = squared_speed_bound(dq, self.grid_rate, velocity, np.min(tcp[motion], axis=0) * speed_scale)
        if times:
            x = np.minimum(x, np.min(time_limits(moves, k, np.diff(self.s_waypoints))[motion], axis=0) ** 2)
        if self.track is not None:
            with np.errstate(divide="ignore"):
                x = np.minimum(x, (np.min(moves.track_velocity[near], axis=0) / np.abs(self.track(grid, 1))) ** 2)
        return x, velocity

    def refined(self, moves, robot, s):
        """This run with grid points added at path positions s (n,) inside it (their TCP rates computed).

        Parameters
        ----------
        moves : Moves
            The sequence the run's waypoint indices refer to (its tools).
        robot : Robot
            The nominal robot (the TCP Jacobian).
        s : ndarray, shape (n,)
            Path positions, rad; those already on the grid are ignored.
        """
        added = np.setdiff1d(s, self.grid)
        grid = np.union1d(self.grid, added)
        rate = np.empty(len(grid))
        new = np.isin(grid, added, assume_unique=True)
        rate[~new], rate[new] = self.grid_rate, tcp_rates(robot, moves, self.motion_at(added), self.path, added)
        return dataclasses.replace(self, grid=grid, grid_rate=rate)


def tcp_limits(moves, k, lengths):
    """TCP speed limit (n,) of motions k (n,) with TCP lengths (n,) mm: the programmed speed, or for a linear /
    circular motion with a programmed time, its length over that time if lower; mm/s (``inf``: none)."""
    tcp = moves.tcp_speed[k]
    timed = (moves.min_duration[k] > 0) & (moves.kind[k] != JOINT)
    tcp[timed] = np.minimum(tcp[timed], lengths[timed] / moves.min_duration[k[timed]])
    return tcp


def time_limits(moves, k, spans):
    """Path speed limit (n,) of motions k (n,) whose path spans ``spans`` (n,) rad: for a joint motion with a
    programmed time, its span over that time (it takes that time at least, as the controller runs it); 1/s
    (``inf``: none). A linear or circular motion's time bounds its TCP speed (`tcp_limits`)."""
    timed = (moves.min_duration[k] > 0) & (moves.kind[k] == JOINT)
    with np.errstate(divide="ignore"):
        return np.where(timed, spans / np.where(timed, moves.min_duration[k], 1.0), np.inf)


def squared_speed_bound(dq, rate, velocity, tcp):
    """Largest squared path speed x = sd^2 (G,) at points with q' ``dq`` (G, 6) and TCP rate |dp/ds| ``rate``
    (G,) under joint velocity limits ``velocity`` (G, 6) and TCP speed limits ``tcp`` (G,)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        x_joint = np.min((velocity / np.abs(dq)) ** 2, axis=1)
        x_tcp = (tcp / rate) ** 2
    return np.minimum(x_joint, np.nan_to_num(x_tcp, nan=np.inf))


def run_path(moves, robot, first, last, tolerance=TOLERANCE, *, part=None):
    """Build and fit the joint path of waypoints ``first..last``.

    Parameters
    ----------
    moves : Moves
    robot : Robot
        The nominal robot (the controller's interpolation).
    first, last : int
        Waypoint indices; the motions are first + 1 .. last.
    tolerance : float
        Largest deviation of the fitted path from every sample, mm.
    part : (int, int), optional
        Waypoints ``a..b`` (first <= a < b <= last) whose part of the path
        is returned, its path position 0 at waypoint a; the motions around
        it are fitted too, so that the part is the path a fit of the whole
        would give there (see `trajcomp.timing.windows`). Default: all.

    Returns
    -------
    RunPath

    Raises
    ------
    TimingError
        From `trajcomp.timing.samples.run_samples`.
    """
    a, b = part or (first, last)
    q, owner, s, waypoint_rows, known, curved, track = _collapsed(moves, robot, first, last)
    s_waypoints = s[waypoint_rows]
    s_a, s_b = s_waypoints[a - first], s_waypoints[b - first]
    if s_b <= s_a:
        return _no_path(a, b)
    grid = _grid(s, STOP_GRID if last == first + 1 else MIN_GRID)  # every sample is a grid point
    k = first + np.clip(np.searchsorted(s_waypoints, grid), 1, len(s_waypoints) - 1)
    at_sample = np.full(len(grid), -1)
    at_sample[np.searchsorted(grid, s)] = np.arange(len(s))
    motion = np.maximum(owner, first + 1)  # of each sample, for its tool (the first sample: the first motion)
    jac, positions = tcp_jacobians(robot, moves, motion, q, known)
    travel = _travel(positions)
    tcp_lengths = np.diff(travel[waypoint_rows], prepend=0.0)
    acceleration = np.min(moves.acceleration[first + 1 : last + 1], axis=0)
    spline, deviation = _fit(s, q, jac, np.full(len(s), tolerance), acceleration, smooth=last > first + 1 and not curved)
    inside = (grid >= s_a) & (grid <= s_b)
    grid = grid[inside]
    rate = _grid_rates(robot, moves, k[inside], spline(grid), spline(grid, 1), at_sample[inside], (q, motion, jac))
    path = JointPath(_moved(spline, s_a))
    lengths = tcp_lengths[a - first : b - first + 1].copy()
    lengths[0] = 0.0
    if track is not None:
        from scipy.interpolate import make_interp_spline

        track = _moved(make_interp_spline(s, track, k=min(3, len(s) - 1)), s_a)
    return RunPath(path, s_waypoints[a - first : b - first + 1] - s_a, grid - s_a, a, b, lengths, rate, deviation,
                   track)


@dataclasses.dataclass(frozen=True, eq=False)
class StopPaths:
    """The paths of consecutive motions from rest to rest (`stop_paths`), and their grids laid end to end.

    Attributes
    ----------
    runs : list of RunPath
        One per motion, in order.
    moving : ndarray of int, shape (R,)
        Index in `runs` of each motion that has a path; path r below is ``runs[moving[r]]``.
    pieces : CubicPieces
        The R paths.
    motion : ndarray of int, shape (R,)
        The motion (waypoint index k) of each path.
    tcp_length : ndarray, shape (R,)
        TCP length of each path, mm.
    sizes : ndarray of int, shape (R,)
        Grid points of each path.
    grid : ndarray, shape (G,)
        The paths' grids, each from 0 (its own path positions), laid end to end.
    dq, ddq : ndarray, shape (G, 6)
        q' and q'' at the grid points.
    rate : ndarray, shape (G,)
        |dp/ds| at the grid points, mm/rad.
    """

    runs: list
    moving: np.ndarray
    pieces: CubicPieces
    motion: np.ndarray
    tcp_length: np.ndarray
    sizes: np.ndarray
    grid: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    rate: np.ndarray

    def points(self, paths):
        """Rows (n,) of the grid points of paths ``paths`` (m,) in the laid-out arrays, path by path."""
        offsets = np.cumsum(self.sizes) - self.sizes
        sizes = self.sizes[paths]
        return np.arange(sizes.sum()) + np.repeat(offsets[paths] - (np.cumsum(sizes) - sizes), sizes)


def stop_paths(moves, robot, first, last):
    """The paths of motions first + 1 .. last, each from rest to rest (every waypoint an exact stop), built together.

    One sampling, one Jacobian batch, one grid construction and one
    interpolation of every motion's samples (`_through_samples`, one
    banded system for all): a single motion's samples are its programmed
    geometry, interpolated as `run_path` does for that motion alone.

    Returns
    -------
    StopPaths
    """
    q, owner, s, waypoint_rows, known, _, _ = _collapsed(moves, robot, first, last)
    k = np.arange(first + 1, last + 1)
    lo, hi = waypoint_rows[:-1], waypoint_rows[1:]
    moving = np.flatnonzero(hi > lo)
    runs = [_no_path(m - 1, m) for m in k.tolist()]
    if not moving.size:
        none = np.zeros(0, dtype=int)
        return StopPaths(runs, moving, None, none, np.zeros(0), none, np.zeros(0), np.zeros((0, 6)), np.zeros((0, 6)),
                         np.zeros(0))
    lo, hi, k = lo[moving], hi[moving], k[moving]
    counts = hi - lo + 1  # samples of each path (consecutive paths share the waypoint between them)
    rows = np.arange(counts.sum()) + np.repeat(lo - (np.cumsum(counts) - counts), counts)
    path_of_row = np.repeat(np.arange(len(counts)), counts)
    local = s[rows] - s[lo][path_of_row]  # each path's positions from 0
    grid, sizes, at = _grids(local, counts, STOP_GRID)
    owner = np.maximum(owner, first + 1)  # the first sample: the first motion's tool
    jac, positions = tcp_jacobians(robot, moves, owner, q, known)
    travel = _travel(positions)
    lengths = travel[hi] - travel[lo]  # TCP length of each path, mm
    pieces = _through_samples(local, q[rows], counts)
    path_of_point = np.repeat(np.arange(len(k)), sizes)
    q_grid, dq, ddq = pieces.derivatives(path_of_point, grid)
    at_sample = np.full(len(grid), -1)  # the sample each grid point is, -1 between samples
    at_sample[at] = rows
    rates = _grid_rates(robot, moves, k[path_of_point], q_grid, dq, at_sample, (q, owner, jac))
    offsets = np.r_[0, np.cumsum(sizes)]
    for r, i in enumerate(moving.tolist()):
        o, p = offsets[r], offsets[r + 1]
        runs[i] = RunPath(JointPath(pieces.ppoly(r)), np.array([0.0, pieces.ends[r]]), grid[o:p], k[r] - 1, k[r],
                          np.array([0.0, lengths[r]]), rates[o:p], 0.0)
    return StopPaths(runs, moving, pieces, k, lengths, sizes, grid, dq, ddq, rates)


def _collapsed(moves, robot, first, last):
    """Samples of waypoints first..last with duplicates collapsed.

    Returns
    -------
    q (n, 6), owner (n,), s (n,) joint arc length (rad), waypoint_rows (W,) the sample of each waypoint,
    known : (rows (r,), flange (r, 4, 4), flange Jacobians (r, 6, 6)) of samples that are waypoints,
    curved : bool, track : ndarray (n,) or None (`trajcomp.timing.samples.run_samples`).
    """
    q, owner, (waypoint, flange, flange_jac), curved, track = run_samples(moves, robot, first, last)
    keep = np.ones(len(q), dtype=bool)
    keep[1:] = np.linalg.norm(np.diff(q, axis=0), axis=1) > _DUPLICATE
    kept = np.cumsum(keep) - 1
    waypoint_rows = kept[np.r_[np.flatnonzero(np.diff(owner)), len(owner) - 1]]
    q, owner, waypoint = q[keep], owner[keep], waypoint[keep]
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))]
    at = np.flatnonzero(waypoint >= 0)
    return (q, owner, s, waypoint_rows, (at, flange[waypoint[at]], flange_jac[waypoint[at]]), curved,
            None if track is None else track[keep])


def _no_path(a, b):
    """The RunPath of waypoints a..b that do not move."""
    return RunPath(None, np.zeros(b - a + 1), np.zeros(1), a, b, np.zeros(b - a + 1), np.zeros(1), 0.0)


def _moved(spline, ds):
    """The same BSpline or PPoly with its path positions moved by ``-ds`` (rad): it starts ``ds`` earlier."""
    if getattr(spline, "t", None) is None:
        return type(spline).construct_fast(spline.c, spline.x - ds)
    return type(spline).construct_fast(spline.t - ds, spline.c, spline.k)


def _grid_rates(robot, moves, owner, q_path, dq, at_sample, samples):
    """|dp/ds| (G,) of a fitted path at its grid points, mm/rad: the TCP rate the timing bounds.

    Parameters
    ----------
    robot : Robot
    moves : Moves
    owner : ndarray of int, shape (G,)
        The motion of each grid point (its tool).
    q_path, dq : ndarray, shape (G, 6)
        The path's q and q' at the grid points.
    at_sample : ndarray of int, shape (G,)
        The sample each grid point is (-1 between samples).
    samples : (ndarray (n, 6), ndarray of int (n,), ndarray (n, 6, 6))
        The samples' joints, motions and TCP Jacobians: a grid point on a
        sample of a motion with the same tool, which the path passes within
        `_SAME_JACOBIAN`, takes its Jacobian; every other one (between
        samples, in a blended corner the path cuts) is computed on the path.
    """
    q_samples, sample_owner, jac_samples = samples
    rate = np.empty(len(q_path))
    reuse = at_sample >= 0
    row = at_sample[reuse]
    reuse[reuse] = ((np.max(np.abs(q_path[reuse] - q_samples[row]), axis=1) <= _SAME_JACOBIAN)
                    & (moves.tool[owner[reuse]] == moves.tool[sample_owner[row]]))
    rate[reuse] = np.linalg.norm(np.einsum("nij,nj->ni", jac_samples[at_sample[reuse], :3], dq[reuse]), axis=1)
    other = np.flatnonzero(~reuse)
    rate[other] = tcp_speeds(robot, moves, owner[other], q_path[other], dq[other])
    return rate


def tcp_rates(robot, moves, owner, path, s):
    """|J_pos(q(s)) q'(s)| (n,): mm of TCP travel per rad of path at path positions s (n,) of motions ``owner`` (n,)."""
    return tcp_speeds(robot, moves, owner, path(s), path(s, 1))


def tcp_speeds(robot, moves, owner, q, qd):
    """|J_pos(q) qd| (n,): the TCP speed of configurations q (n, 6) moving at qd (n, 6), each with the tool
    of its motion ``owner`` (n,); mm per unit of qd's time (rad/s: mm/s).

    The velocity of the TCP point summed over the DH axes, z_i x (p - o_i)
    times the axis rate, from the DH frames (`trajcomp.arm.kinematics.frame_columns`)
    without forming the Jacobians.
    """
    if not len(owner):
        return np.zeros(0)
    flange = robot.T_link6_flange

    def speeds(owner, q, qd):
        columns = frame_columns(robot, q)  # (7, 4, 3, n): column k (axes, origin) of DH frame i
        to_tcp = flange[:3, 3, None] + flange[:3, :3] @ moves.tools[moves.tool[owner], :3, 3].T  # (3, n), link 6
        tcp = columns[6, 3] + np.einsum("kcn,kn->cn", columns[6, :3], to_tcp)
        turning, lever = columns[:6, 2] * (robot.joint_map @ qd.T)[:, None], tcp[None] - columns[:6, 3]  # (6, 3, n)
        x, y, z = (np.sum(turning[:, a] * lever[:, b] - turning[:, b] * lever[:, a], axis=0)
                   for a, b in ((1, 2), (2, 0), (0, 1)))  # the cross products' components, summed over the axes
        return (np.sqrt(x * x + y * y + z * z),)

    return in_blocks(speeds, np.asarray(owner), np.asarray(q, dtype=float), np.asarray(qd, dtype=float))[0]


def _travel(positions):
    """TCP path length (n,) from the first sample, mm, of samples at TCP positions (n, 3): the sum of their
    chords (a line's length exactly; a programmed time over it is the speed the controller reads)."""
    return np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(positions, axis=0), axis=1))]


def _grid(s, intervals=MIN_GRID):
    """Grid points of one path's samples s (n,) from 0 (`_grids`)."""
    return _grids(s, np.array([len(s)]), intervals)[0]


def _grids(s, counts, intervals):
    """Grid points of paths laid end to end: every sample, intervals longer than 1/``intervals`` of the path
    subdivided evenly.

    The first and last intervals are also halved `END_REFINEMENT` times
    towards the ends: the path speed is constant-acceleration from rest to
    the first grid point, so a coarse first interval would slow the start.

    Parameters
    ----------
    s : ndarray, shape (n,)
        Path positions of the paths' samples, each path's from 0, increasing.
    counts : ndarray of int, shape (R,)
        Samples of each path (at least 2).
    intervals : int

    Returns
    -------
    grid : ndarray, shape (G,)
        The paths' grids laid end to end.
    sizes : ndarray of int, shape (R,)
        Grid points of each path.
    at : ndarray of int, shape (n,)
        Index in ``grid`` of each sample.
    """
    ends = np.cumsum(counts) - 1  # last sample of each path
    length = s[ends]
    within = np.ones(len(s) - 1, dtype=bool)
    within[ends[:-1]] = False  # sample intervals inside a path
    ds = np.diff(s)[within]
    path = np.repeat(np.arange(len(counts)), counts - 1)
    pieces = np.maximum(np.ceil(ds / (length / intervals)[path]).astype(int), 1)
    part = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces)  # 0 .. p-1 in each interval
    points = np.repeat(np.delete(s, ends), pieces) + part / np.repeat(pieces, pieces) * np.repeat(ds, pieces)
    per_path = np.bincount(path, weights=pieces, minlength=len(counts)).astype(int)  # points before the end
    e = END_REFINEMENT
    sizes = per_path + 1 + 2 * e
    offsets = np.cumsum(sizes) - sizes
    before = np.cumsum(per_path) - per_path  # first point of each path in ``points``
    grid = np.empty(sizes.sum())
    index = np.arange(len(points)) - np.repeat(before, per_path)  # of each point in its path's grid before merging
    grid[np.repeat(offsets, per_path) + index + e * (index >= 1)] = points
    grid[offsets + sizes - 1] = length
    halves = 0.5 ** np.arange(1, e + 1)
    second = np.where(per_path >= 2, points[np.minimum(before + 1, len(points) - 1)], length)
    penultimate = points[before + per_path - 1]  # the last point before each path's end
    grid[offsets[:, None] + 1 + np.arange(e)] = second[:, None] * halves[::-1]  # in order: inside the end intervals
    grid[offsets[:, None] + per_path[:, None] + e + np.arange(e)] = (length[:, None]
                                                                     - (length - penultimate)[:, None] * halves)
    sample = np.zeros(len(s), dtype=int)  # of each sample in its path's grid before merging: 0, then pieces summed
    first = ends - counts + 1
    later = np.ones(len(s), dtype=bool)
    later[first] = False
    sample[later] = np.cumsum(pieces) - np.repeat(before, counts - 1)
    at = np.repeat(offsets, counts) + sample + e * (sample >= 1) + e * (sample == np.repeat(per_path, counts))
    steps = np.diff(grid)
    steps[offsets[1:] - 1] = 1.0  # across paths
    bad = np.flatnonzero((per_path < 2) | (np.minimum.reduceat(steps, offsets) <= 0.0))
    if not bad.size:
        return grid, sizes, at
    paths = np.split(grid, offsets[1:])  # a coarse grid or coinciding points: sort and merge
    for r in bad:
        paths[r] = np.unique(paths[r])
    sizes = np.array([len(p) for p in paths])
    grid = np.concatenate(paths)
    at = np.repeat(np.cumsum(sizes) - sizes, counts) + np.concatenate(
        [np.searchsorted(p, s[a : b + 1]) for p, a, b in zip(paths, first, ends)])
    return grid, sizes, at


def tcp_jacobians(robot, moves, owner, q, known=None):
    """TCP Jacobians (n, 6, 6) and positions (n, 3) of configurations q (n, 6), each with the tool of its motion
    ``owner`` (n,).

    ``known``: ``(rows, flange (r, 4, 4), flange Jacobians (r, 6, 6))`` of
    rows whose flange kinematics were computed before (the waypoints).
    """
    jac, frame = np.empty((len(q), 6, 6)), np.empty((len(q), 3, 4))
    todo = np.ones(len(q), dtype=bool)
    if known is not None:
        rows, flange, flange_jac = known
        jac[rows], frame[rows], todo[rows] = flange_jac, flange[:, :3], False
    rows = np.flatnonzero(todo)
    if rows.size:
        flange, jac[rows] = fk_and_jacobian(robot, q[rows], tcp=False)
        frame[rows] = flange[:, :3]
    rotation = frame[:, :, :3]
    offset = np.einsum("nij,nj->ni", rotation, moves.tools[moves.tool[owner], :3, 3])  # flange to TCP, base frame
    w, r = jac[:, 3:], offset[:, :, None]  # each column's angular part w (n, 3, 6): v += w x offset
    jac[:, 0] += w[:, 1] * r[:, 2] - w[:, 2] * r[:, 1]
    jac[:, 1] += w[:, 2] * r[:, 0] - w[:, 0] * r[:, 2]
    jac[:, 2] += w[:, 0] * r[:, 1] - w[:, 1] * r[:, 0]
    return jac, frame[:, :, 3] + offset


def _fit(s, q, jac, tol, acceleration, *, smooth=True):
    """Cubic B-spline q(s) of samples (s (n,), q (n, 6)) within tolerances tol (n,) mm: (BSpline, deviation mm).

    The samples are interpolated unless ``smooth`` and a thinned spline
    within the tolerances needs less than 1 / SMOOTHING_GAIN of the
    acceleration at the same path speed (noise: waypoints rounded as a
    program writes them, at corners the path keeps): a clean path is taken
    exactly. A single motion, or a run with a sampled blend
    (`trajcomp.timing.samples.run_samples`' ``curved``), is interpolated:
    its samples are the programmed geometry.
    """
    from scipy.interpolate import make_interp_spline  # here: a run that does not re-time never needs scipy

    n = len(s)
    if n < 4:  # a line or a single corner
        return _through_samples(s, q, np.array([n])).ppoly(0), 0.0
    exact = make_interp_spline(s, q, k=3)
    if not smooth:
        return exact, 0.0
    demand = _demand(exact, s, acceleration)
    if n >= 4 * KNOT_STRIDE:  # is the exact path noisy?
        coarse = np.r_[np.arange(0, n - 1, KNOT_STRIDE // 2), n - 1]
        if demand <= SMOOTHING_GAIN * _demand(make_interp_spline(s[coarse], q[coarse], k=3), s, acceleration):
            return exact, 0.0  # as smooth as a spline through every eighth sample: clean
    thinned, deviation = _thinned(s, q, jac, tol)
    if thinned is None or demand <= SMOOTHING_GAIN * _demand(thinned, s, acceleration):
        return exact, 0.0
    return thinned, deviation


def _through_samples(s, q, counts):
    """The cubic splines through the samples of paths laid end to end: `_not_a_knot` (scipy's
    ``make_interp_spline``), a path of fewer than 4 samples as a line or a single corner.

    A path of 2 samples is their joint line; one of 3 interpolates the
    polyline of its samples at the samples and at every third of the path
    (a not-a-knot spline needs 4 points; on a straight piece it is the line).

    Parameters
    ----------
    s : ndarray, shape (n,)
        Path positions of the samples, each path's from 0, rad.
    q : ndarray, shape (n, 6)
        Joints of the samples, rad.
    counts : ndarray of int, shape (R,)
        Samples of each path (at least 2).

    Returns
    -------
    CubicPieces
    """
    ends = np.cumsum(counts) - 1
    line = counts == 2
    parts, paths = [], []
    if line.any():
        a, b = ends[line] - 1, ends[line]
        c = np.zeros((len(a), 4, 6))
        c[:, 2], c[:, 3] = (q[b] - q[a]) / s[b, None], q[a]
        parts.append(CubicPieces(np.zeros(len(a)), c, np.ones(len(a), dtype=int), s[b]))
        paths.append(np.flatnonzero(line))
    for group, through in ((counts == 3, _through_corners), (counts >= 4, _not_a_knot)):
        if group.any():
            rows = np.repeat(group, counts)
            parts.append(through(s[rows], q[rows], counts[group]))
            paths.append(np.flatnonzero(group))
    return CubicPieces.joined(parts, paths) if len(parts) > 1 else parts[0]


def _through_corners(s, q, counts):
    """`_through_samples` of paths of 3 samples (or more): the not-a-knot spline through the polyline of the
    samples at the samples and at every third of the path."""
    ends = np.cumsum(counts) - 1
    length = s[ends]
    path = np.repeat(np.arange(len(counts)), counts)
    thirds = np.arange(4) * (length[:, None] / 3.0)  # as np.linspace
    thirds[:, -1] = length
    x, label = np.r_[s, thirds.ravel()], np.r_[path, np.repeat(np.arange(len(counts)), 4)]
    order = np.lexsort((x, label))
    x, label = x[order], label[order]
    keep = np.r_[True, (np.diff(x) != 0.0) | (np.diff(label) != 0)]
    x, label = x[keep], label[keep]
    shift = np.r_[0.0, np.cumsum(length + 1.0)[:-1]]  # the paths apart on one axis, to find each point's samples
    j = np.searchsorted(s + shift[path], x + shift[label], side="right") - 1
    j = np.clip(j, (ends - counts + 1)[label], ends[label] - 1)
    y = q[j] + (q[j + 1] - q[j]) * ((x - s[j]) / (s[j + 1] - s[j]))[:, None]
    return _not_a_knot(x, y, np.bincount(label, minlength=len(counts)))


def _not_a_knot(x, y, counts):
    """Not-a-knot cubic splines through points (x (n,), y (n, 6)) of paths laid end to end, as scipy's
    CubicSpline builds one (the slopes from one banded system, here of all the paths): `CubicPieces`.

    ``counts`` (R,): points of each path (at least 4); x increases within a path.
    """
    from scipy.linalg import solve_banded  # here: a run that does not re-time never needs scipy

    last = np.cumsum(counts) - 1
    first = last - counts + 1
    dx = np.diff(x)
    slope = np.diff(y, axis=0) / dx[:, None]
    inner = np.ones(len(x), dtype=bool)
    inner[first], inner[last] = False, False
    i = np.flatnonzero(inner)
    A = np.zeros((3, len(x)))  # banded: A[0, j + 1] row j's upper entry, A[1, j] its diagonal, A[2, j - 1] its lower
    b = np.empty(y.shape)
    A[1, i], A[0, i + 1], A[2, i - 1] = 2.0 * (dx[i - 1] + dx[i]), dx[i - 1], dx[i]
    b[i] = 3.0 * (dx[i, None] * slope[i - 1] + dx[i - 1, None] * slope[i])
    d = x[first + 2] - x[first]
    A[1, first], A[0, first + 1] = dx[first + 1], d
    b[first] = (((dx[first] + 2.0 * d) * dx[first + 1])[:, None] * slope[first]
                + (dx[first] ** 2)[:, None] * slope[first + 1]) / d[:, None]
    d = x[last] - x[last - 2]
    A[1, last], A[2, last - 1] = dx[last - 2], d
    b[last] = ((dx[last - 1] ** 2)[:, None] * slope[last - 2]
               + ((2.0 * d + dx[last - 1]) * dx[last - 2])[:, None] * slope[last - 1]) / d[:, None]
    m = solve_banded((1, 1), A, b, overwrite_ab=True, overwrite_b=True, check_finite=False)  # slopes at the points
    piece = np.delete(np.arange(len(x) - 1), last[:-1])  # the intervals inside a path
    h, slope = dx[piece, None], slope[piece]
    t = (m[piece] + m[piece + 1] - 2.0 * slope) / h
    c = np.stack([t / h, (slope - m[piece]) / h - t, m[piece], y[piece]], axis=1)
    return CubicPieces(x[piece], c, counts - 1, x[last])


def _thinned(s, q, jac, tol):
    """Least-squares cubic spline with the fewest knots (refined where needed) within tol: (BSpline or None, mm).

    Knot intervals with a sample outside the tolerance are halved down to
    `_NARROWEST` samples; where that is not enough (a step in the samples,
    e.g. where the compensation's solution changes by a few micrometres)
    those samples are weighted `_PULL` times more, up to `_PULLS` times,
    so the fit stays smooth elsewhere.
    """
    from scipy.interpolate import make_lsq_spline  # here: a run that does not re-time never needs scipy

    n = len(s)
    knots = np.unique(np.r_[np.arange(0, n, KNOT_STRIDE), n - 1])
    weight, pulls = np.ones(n), 0
    while True:
        try:
            spline = make_lsq_spline(s, q, np.r_[[s[0]] * 4, s[knots[1:-1]], [s[-1]] * 4], k=3, w=weight,
                                     method="norm-eq")
        except (ValueError, np.linalg.LinAlgError):
            return None, 0.0
        position, rotation, joint = _deviation(spline, s, q, jac)
        bad = (position > tol) | (np.maximum(rotation, joint) > tol * ROTATION_PER_MM)
        if not bad.any():
            return spline, float(np.max(position))
        cell = np.searchsorted(knots, np.flatnonzero(bad), side="right") - 1
        cell = np.unique(np.clip(cell, 0, len(knots) - 2))
        wide = cell[knots[cell + 1] - knots[cell] >= 2 * _NARROWEST]
        if wide.size:
            knots = np.unique(np.r_[knots, (knots[wide] + knots[wide + 1]) // 2])
        elif pulls < _PULLS:
            weight[bad], pulls = weight[bad] * _PULL, pulls + 1
        else:
            return None, 0.0


def _demand(spline, s, acceleration):
    """Largest joint acceleration (share of the limit) the path needs at unit path speed: max |q''_j| / a_j."""
    return float(np.max(np.abs(spline(s, 2)) / acceleration))


def _deviation(spline, s, q, jac):
    """TCP position (mm), orientation (rad, linearized) and largest joint (rad) deviation (n,) from the samples."""
    joints = spline(s) - q
    delta = np.einsum("nij,nj->ni", jac, joints)
    return np.linalg.norm(delta[:, :3], axis=1), np.linalg.norm(delta[:, 3:], axis=1), np.abs(joints).max(axis=1)
