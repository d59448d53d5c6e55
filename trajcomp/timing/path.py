"""The joint path of a continuous run, fitted for TOPP-RA within a stated tolerance.

A run is a chain of motions the arm passes without stopping, or one
motion from rest to rest. Its samples come from `trajcomp.timing.samples`
(the controller's interpolation); then:

1. Parameter: s = joint-space arc length (rad) of the samples; duplicated
   and zero-length waypoints collapse onto one sample.
2. Fit: the cubic spline through the samples, unless their noise (IK
   solutions of rounded numbers) or a blended corner makes it need more
   than `SMOOTHING_GAIN` times the acceleration of a thinned one, which
   makes TOPP-RA crawl. The thinned spline is a least-squares cubic
   B-spline with knots on every `KNOT_STRIDE` samples, refined where it
   leaves the tolerance (and samples the finest knots still miss weighted
   more): within `TOLERANCE` mm of every sample's TCP and
   ``TOLERANCE * ROTATION_PER_MM`` rad of its orientation (linearized with
   the Jacobian) and of each joint, or within the programmed zone radius
   near a blended corner. The tolerance keeps the compensated positions.
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
    spline : scipy.interpolate.BSpline
        Cubic, values (6,).
    """

    KEPT_DERIVATIVES = 4096
    FEWEST_KEPT = 64

    def __init__(self, spline):
        self.spline = spline
        self._derivatives = None
        if self.FEWEST_KEPT <= len(spline.c) <= self.KEPT_DERIVATIVES:
            self._derivatives = (spline, spline.derivative(1), spline.derivative(2))

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
        k = self.spline.k
        return np.array([self.spline.t[k], self.spline.t[-k - 1]])


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
        outside blended corners.
    """

    path: JointPath
    s_waypoints: np.ndarray
    grid: np.ndarray
    first: int
    last: int
    tcp_lengths: np.ndarray
    grid_rate: np.ndarray
    deviation: float

    @property
    def length(self):
        return float(self.s_waypoints[-1])

    def motion_at(self, s, side="left"):
        """Waypoint index k of the motion (into waypoint k) each path position s (N,) lies on.

        At a waypoint, ``side="left"`` gives the motion ending there, ``"right"`` the one starting there.
        """
        inner = np.searchsorted(self.s_waypoints, s, side=side)
        return self.first + np.clip(inner, 1, len(self.s_waypoints) - 1)

    def speed_bound(self, moves, velocity_scale=1.0, speed_scale=1.0, dq=None):
        """Largest squared path speed x = sd^2 (G,) on the grid, and the joint velocity limits (G, 6) used.

        A grid point obeys the joint velocity limits and the programmed TCP
        speed (or, for a linear / circular motion with a programmed time,
        its TCP length over that time) of the motions it belongs to (both,
        at a waypoint). ``dq`` (G, 6): q' on the grid, when already evaluated.
        """
        grid = self.grid
        dq = self.path(grid, 1) if dq is None else dq
        near = np.stack([self.motion_at(grid), self.motion_at(grid, "right")])
        if moves.velocity.strides[0] == 0:  # the same limits for every motion (a broadcast view): no gather
            velocity = np.broadcast_to(moves.velocity[0] * velocity_scale, (len(grid), 6))
        else:
            velocity = np.min(moves.velocity[near], axis=0) * velocity_scale
        k = np.arange(self.first, self.last + 1)  # tcp[i]: motion first + i (waypoint first's own is not used)
        tcp = moves.tcp_speed[k]
        timed = (moves.min_duration[k] > 0) & (moves.kind[k] != JOINT)
        timed[0] = False
        tcp[timed] = np.minimum(tcp[timed], self.tcp_lengths[timed] / moves.min_duration[k[timed]])
        with np.errstate(divide="ignore", invalid="ignore"):
            x_joint = np.min((velocity / np.abs(dq)) ** 2, axis=1)
            x_tcp = (np.min(tcp[near - self.first], axis=0) * speed_scale / self.grid_rate) ** 2
        return np.minimum(x_joint, np.nan_to_num(x_tcp, nan=np.inf)), velocity

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
    q, owner, s, waypoint_rows, known = _collapsed(moves, robot, first, last)
    s_waypoints = s[waypoint_rows]
    s_a, s_b = s_waypoints[a - first], s_waypoints[b - first]
    if s_b <= s_a:
        return _no_path(a, b)
    grid = _grid(s, STOP_GRID if last == first + 1 else MIN_GRID)  # every sample is a grid point
    k = first + np.clip(np.searchsorted(s_waypoints, grid), 1, len(s_waypoints) - 1)
    at_sample = np.full(len(grid), -1)
    at_sample[np.searchsorted(grid, s)] = np.arange(len(s))
    motion = np.maximum(owner, first + 1)  # of each sample, for its tool (the first sample: the first motion)
    jac = tcp_jacobians(robot, moves, motion, q, known)
    travel = _travel(q, jac)
    tcp_lengths = np.diff(travel[waypoint_rows], prepend=0.0)
    tol = _tolerances(moves, first, last, travel, owner, waypoint_rows, tcp_lengths, tolerance)
    spline, deviation = _fit(s, q, jac, tol, np.min(moves.acceleration[first + 1 : last + 1], axis=0))
    inside = (grid >= s_a) & (grid <= s_b)
    grid = grid[inside]
    rate = _grid_rates(robot, moves, k[inside], spline(grid), spline(grid, 1), at_sample[inside], (q, motion, jac))
    path = JointPath(type(spline)(spline.t - s_a, spline.c, spline.k))  # a BSpline moved to start at s_a
    lengths = tcp_lengths[a - first : b - first + 1].copy()
    lengths[0] = 0.0
    return RunPath(path, s_waypoints[a - first : b - first + 1] - s_a, grid - s_a, a, b, lengths, rate, deviation)


def stop_paths(moves, robot, first, last, tolerance=TOLERANCE):
    """The paths of motions first + 1 .. last, each from rest to rest (every waypoint an exact stop), built together.

    One sampling, one Jacobian batch for all the motions; each is then
    fitted on its own samples, exactly as `run_path` of that motion alone.

    Returns
    -------
    list of RunPath
        One per motion, in order.
    """
    q, owner, s, waypoint_rows, known = _collapsed(moves, robot, first, last)
    runs = []  # per motion: (k, sample rows, local path positions, grid)
    for k, r0, r1 in zip(range(first + 1, last + 1), waypoint_rows[:-1].tolist(), waypoint_rows[1:].tolist()):
        local = s[r0 : r1 + 1] - s[r0]
        runs.append((k, slice(r0, r1 + 1), local, _grid(local, STOP_GRID) if r1 > r0 else local[:0]))
    sizes = [len(grid) for *_, grid in runs]
    if not any(sizes):
        return [_no_path(k - 1, k) for k, *_ in runs]
    offsets = np.r_[0, np.cumsum(sizes)]
    at_sample = np.full(offsets[-1], -1)  # the sample each grid point (in all grids) is, -1 between samples
    for (_, rows, local, grid), offset in zip(runs, offsets):
        if len(grid):  # a motion that does not move has no grid point of its own
            at_sample[offset + np.searchsorted(grid, local)] = np.arange(rows.start, rows.stop)
    owner = np.maximum(owner, first + 1)  # the first sample: the first motion's tool
    jac = tcp_jacobians(robot, moves, owner, q, known)
    fits = []  # per motion with a grid: spline, deviation, TCP length
    for k, rows, local, grid in runs:
        if len(grid):
            spline, deviation = _fit(local, q[rows], jac[rows], np.full(len(local), tolerance), moves.acceleration[k])
            fits.append((spline, deviation, _travel(q[rows], jac[rows])[-1]))
    moving = [grid for *_, grid in runs if len(grid)]
    rates = _grid_rates(robot, moves, np.repeat(np.arange(first + 1, last + 1), sizes),
                        np.concatenate([f[0](grid) for f, grid in zip(fits, moving)]),
                        np.concatenate([f[0](grid, 1) for f, grid in zip(fits, moving)]), at_sample, (q, owner, jac))
    fits = iter(fits)
    paths = []
    for (k, rows, local, grid), offset in zip(runs, offsets):
        if not len(grid):
            paths.append(_no_path(k - 1, k))
            continue
        spline, deviation, length = next(fits)
        paths.append(RunPath(JointPath(spline), local[[0, -1]], grid, k - 1, k, np.array([0.0, length]),
                             rates[offset : offset + len(grid)], deviation))
    return paths


def _collapsed(moves, robot, first, last):
    """Samples of waypoints first..last with duplicates collapsed.

    Returns
    -------
    q (n, 6), owner (n,), s (n,) joint arc length (rad), waypoint_rows (W,) the sample of each waypoint,
    known : (rows (r,), flange (r, 4, 4), flange Jacobians (r, 6, 6)) of samples that are waypoints.
    """
    q, owner, (waypoint, flange, flange_jac) = run_samples(moves, robot, first, last)
    keep = np.ones(len(q), dtype=bool)
    keep[1:] = np.linalg.norm(np.diff(q, axis=0), axis=1) > _DUPLICATE
    kept = np.cumsum(keep) - 1
    waypoint_rows = kept[np.r_[np.flatnonzero(np.diff(owner)), len(owner) - 1]]
    q, owner, waypoint = q[keep], owner[keep], waypoint[keep]
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))]
    at = np.flatnonzero(waypoint >= 0)
    return q, owner, s, waypoint_rows, (at, flange[waypoint[at]], flange_jac[waypoint[at]])


def _no_path(a, b):
    """The RunPath of waypoints a..b that do not move."""
    return RunPath(None, np.zeros(b - a + 1), np.zeros(1), a, b, np.zeros(b - a + 1), np.zeros(1), 0.0)


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
    times the axis rate, from the DH frames (`trajcomp.kinematics.frame_columns`)
    without forming the Jacobians.
    """
    if not len(owner):
        return np.zeros(0)
    flange = robot.T_link6_flange

    def speeds(owner, q, qd):
        columns = frame_columns(robot, q)  # (7, 4, 3, n): column k (axes, origin) of DH frame i
        to_tcp = flange[:3, 3, None] + flange[:3, :3] @ moves.tools[moves.tool[owner], :3, 3].T  # (3, n), link 6
        tcp = columns[6, 3] + np.einsum("kcn,kn->cn", columns[6, :3], to_tcp)
        axes, lever = columns[:6, 2], tcp[None] - columns[:6, 3]  # (6, 3, n)
        moment = np.cross(axes, lever, axis=1)
        return (np.linalg.norm(np.einsum("icn,in->cn", moment, robot.joint_map @ qd.T), axis=0),)

    return in_blocks(speeds, np.asarray(owner), np.asarray(q, dtype=float), np.asarray(qd, dtype=float))[0]


def _travel(q, jac):
    """TCP arc length (n,) from the first sample, mm, of samples q (n, 6) with TCP Jacobians jac (n, 6, 6)."""
    steps = np.linalg.norm(np.einsum("nij,nj->ni", jac[1:, :3], np.diff(q, axis=0)), axis=1)
    return np.r_[0.0, np.cumsum(steps)]


def _grid(s, intervals=MIN_GRID):
    """Grid points: every sample s (n,), intervals longer than 1/``intervals`` of the path subdivided evenly.

    The first and last intervals are also halved `END_REFINEMENT` times
    towards the ends: the path speed is constant-acceleration from rest to
    the first grid point, so a coarse first interval would slow the start.
    """
    longest = s[-1] / intervals
    pieces = np.maximum(np.ceil(np.diff(s) / longest).astype(int), 1)
    part = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces)  # 0 .. p-1 in each interval
    grid = np.r_[np.repeat(s[:-1], pieces) + part / np.repeat(pieces, pieces) * np.repeat(np.diff(s), pieces), s[-1]]
    halves = 0.5 ** np.arange(1, END_REFINEMENT + 1)
    head, tail = grid[1] * halves[::-1], grid[-1] - (grid[-1] - grid[-2]) * halves
    merged = np.r_[grid[0], head, grid[1:-1], tail, grid[-1]]  # in order: the ends go inside the end intervals
    if len(grid) > 2 and np.all(np.diff(merged) > 0.0):
        return merged
    return np.unique(merged)  # a coarse grid or coinciding points: sort and merge


def tcp_jacobians(robot, moves, owner, q, known=None):
    """TCP Jacobians (n, 6, 6) of configurations q (n, 6), each with the tool of its motion ``owner`` (n,).

    ``known``: ``(rows, flange (r, 4, 4), flange Jacobians (r, 6, 6))`` of
    rows whose flange kinematics were computed before (the waypoints).
    """
    jac, rotation = np.empty((len(q), 6, 6)), np.empty((len(q), 3, 3))
    todo = np.ones(len(q), dtype=bool)
    if known is not None:
        rows, flange, flange_jac = known
        jac[rows], rotation[rows], todo[rows] = flange_jac, flange[:, :3, :3], False
    rows = np.flatnonzero(todo)
    if rows.size:
        flange, jac[rows] = fk_and_jacobian(robot, q[rows], tcp=False)
        rotation[rows] = flange[:, :3, :3]
    offset = np.einsum("nij,nj->ni", rotation, moves.tools[moves.tool[owner], :3, 3])  # flange to TCP, base frame
    w, r = jac[:, 3:], offset[:, :, None]  # each column's angular part w (n, 3, 6): v += w x offset
    jac[:, 0] += w[:, 1] * r[:, 2] - w[:, 2] * r[:, 1]
    jac[:, 1] += w[:, 2] * r[:, 0] - w[:, 0] * r[:, 2]
    jac[:, 2] += w[:, 0] * r[:, 1] - w[:, 1] * r[:, 0]
    return jac


def _tolerances(moves, first, last, travel, owner, waypoint_rows, tcp_lengths, tolerance):
    """Allowed TCP deviation (n,) of the path from each sample, mm: ``tolerance``, or more in blended corners.

    A corner at waypoint k with zone r (not a stop) may be cut: samples
    within r_eff = min(r, half of each neighbouring motion) of it, along the
    path, get ``r_eff - distance``.
    """
    tol = np.full(len(travel), tolerance)
    corners = np.arange(first + 1, last)
    if not corners.size or not np.any(moves.zone[corners] > 0):
        return tol
    radius = np.zeros(last - first + 1)
    inner = corners - first
    radius[inner] = np.minimum(moves.zone[corners], 0.5 * np.minimum(tcp_lengths[inner], tcp_lengths[inner + 1]))
    corner_travel = travel[waypoint_rows]
    local = owner - first
    for corner in (np.clip(local - 1, 0, None), local):
        tol = np.maximum(tol, radius[corner] - np.abs(travel - corner_travel[corner]))
    return tol


def _fit(s, q, jac, tol, acceleration):
    """Cubic B-spline q(s) of samples (s (n,), q (n, 6)) within tolerances tol (n,) mm: (BSpline, deviation mm).

    The samples are interpolated unless a thinned spline within the
    tolerances needs less than 1 / SMOOTHING_GAIN of the acceleration at
    the same path speed (noise, or a blended corner): a clean path is
    taken exactly.
    """
    from scipy.interpolate import make_interp_spline  # here: a run that does not re-time never needs scipy

    n = len(s)
    if n < 4:  # a line or a single corner: interpolate, with points added on the straight pieces
        dense = np.union1d(s, np.linspace(s[0], s[-1], 4))
        return make_interp_spline(dense, make_interp_spline(s, q, k=1)(dense), k=3), 0.0
    exact = make_interp_spline(s, q, k=3)
    demand = _demand(exact, s, acceleration)
    if n >= 4 * KNOT_STRIDE and np.all(tol <= tol.min()):  # no corner to cut: is the exact path noisy?
        coarse = np.r_[np.arange(0, n - 1, KNOT_STRIDE // 2), n - 1]
        if demand <= SMOOTHING_GAIN * _demand(make_interp_spline(s[coarse], q[coarse], k=3), s, acceleration):
            return exact, 0.0  # as smooth as a spline through every eighth sample: clean
    thinned, deviation = _thinned(s, q, jac, tol)
    if thinned is None or demand <= SMOOTHING_GAIN * _demand(thinned, s, acceleration):
        return exact, 0.0
    return thinned, deviation


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
            return spline, float(np.max(np.where(tol <= tol.min(), position, 0.0)))
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
