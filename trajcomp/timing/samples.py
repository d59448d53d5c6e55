"""Joint samples of a run as the controller interpolates it, for all its motions at once.

A LIN moves the TCP on the straight line between its end poses, the
orientation turning uniformly about one axis; a CIRC on the circle through
start, via and end point (orientation as for a LIN); both are solved with
the nominal model (the written poses are nominal-model commands), every
`STEP_MM` mm and `STEP_DEG` deg, at least `MIN_INTERVALS` times from rest
to rest. A PTP is the straight line in joint space.

A corner the arm passes without stopping (zone z > 0) is blended over
r = min(z, half of each neighbouring motion's TCP length) on both sides,
as the controllers approximate a corner: the two motions superposed, the
incoming one slowing to the corner while the outgoing one starts. With
the blend parameter u in [0, 1] (linear in the path from the point r
before the corner to the point r after it) and the quintic step's
integral Omega(u) = 2.5 u^4 - 3 u^5 + u^6, the incoming motion is at
2 r (u - Omega(u)) past its entry point and the outgoing one at
2 r Omega(u) past the corner: p = p_in + p_out - p_corner and
R = R_in R_corner^T R_out between two linear / circular motions, q =
q_in + q_out - q_corner where one is a joint motion. The blend meets the
lines with the same direction, curvature and curvature rate (C3), stays
within r of the corner, and is sampled `BLEND_SAMPLES` times (up to twice
that, the sharper the corner) on each side of its middle, the corner's
sample: the waypoint's place on the path. A blend that stays within
`BLEND_DEFLECTION` of its corner (the dense points of a CAM path) is not
sampled: the corner is, and the path's fit within the tolerance of the
samples stands for it.
On a moving track (`trajcomp.timing.track`) the track's position is
interpolated as the position is: linear in each motion's share of its way,
the two motions superposed in a blend, e = e_in + e_out - e_corner; the
samples carry it beside the joints, `TRACK_BLEND_GAIN` times as many in a blend.
Where neighbouring samples differ by more than `JUMP_DEG` in a joint the
interval is bisected (a fast wrist swing near a singularity is sampled
finely); a jump that survives down to 1e-6 of a motion is a pass through
a singularity and is refused. A linear or circular motion keeps the
arm's configuration (shoulder, elbow and wrist flags): one whose target
is declared in another configuration than its start is refused as such.
"""

import dataclasses
import itertools

import numpy as np

from trajcomp.errors import TimingError
from trajcomp.arm.ik import Configuration, branch_index, ik, ik_all, ik_family
from trajcomp.arm.kinematics import fk, fk_and_jacobian
from trajcomp.programs.items import CIRCULAR, JOINT
from trajcomp.timing.options import TOLERANCE
from trajcomp.arm.transforms import matrix_to_rotvec, rotvec_to_matrix

STEP_MM = 5.0  # mm, largest TCP step between path samples of a LIN / CIRC
STEP_DEG = 2.0  # deg, largest orientation or joint step between path samples
JUMP_DEG = 5.0  # deg, a larger joint step between neighbouring samples is bisected
MIN_INTERVALS = 4  # sample intervals of a linear / circular motion from rest to rest at least (curved in joints)
MIN_INTERVAL_MM = 0.25  # as long as they are no shorter than this
BLEND_SAMPLES = 32  # sample intervals on each half of a blended corner turning by 60 deg or less, up to twice that
# for a reversal (the spline's q'' within 0.2 % there)
TRACK_BLEND_GAIN = 4  # times the blend samples on a moving track: its position e(s), fitted through them, is then
# where the controller puts the track for the fitted joints' TCP (3e-7 mm, not 3e-5: 1.09x its acceleration limit)
BLEND_DEFLECTION = TOLERANCE  # mm: a blend that stays this close to its corner is left to the fit (the corner sampled)
AMBIGUOUS_DEG = 120.0  # deg: a linear motion turning a joint by more is followed to learn which way it turns
_MIDDLE = 2.0 * (2.5 / 16 - 3 / 32 + 1 / 64)  # |p(1/2) - corner| / (r |e_out - e_in|): 2 Omega(1/2) (lines)
_SMALLEST_FRACTION = 1e-6  # of a motion: bisection stops here (singular)


def run_samples(moves, robot, first, last):
    """Joint samples of waypoints ``first..last`` and the motions they belong to.

    Returns
    -------
    q : ndarray, shape (n, 6)
        Samples in path order, rad; the waypoints are among them.
    owner : ndarray of int, shape (n,)
        Waypoint k whose motion each sample ends (motion k covers (wp k-1, wp k]);
        ``first`` for the first sample.
    waypoint_kinematics : (ndarray (n,) of int, ndarray (W, 4, 4), ndarray (W, 6, 6))
        For each sample, the waypoint ``first + i`` it is (i; -1 for a
        sample between waypoints), and the flange poses and flange
        Jacobians of the W = last - first + 1 waypoints (computed once here,
        reused by `trajcomp.timing.path`).
    curved : bool
        A blended corner is sampled (the path must pass through the
        samples). Otherwise every blend stays within `BLEND_DEFLECTION` of
        its corner: the corner is the sample, and a path within the
        tolerance of the samples is within it of the programmed geometry
        (a blend of the dense points of a CAM path, rounded as written).
    track : ndarray, shape (n,), or None
        On a moving track (`Moves.on_track`), its position at each sample,
        mm (the controller's interpolation, blended as the position is);
        None otherwise.

    Raises
    ------
    TimingError
        A motion leaves the workspace or the joint limits between its
        waypoints, a circle is degenerate, or a LIN passes a singularity.
    """
    repeats = np.r_[False, np.all(moves.q[first + 1 : last + 1] == moves.q[first:last], axis=1)]  # (W,)
    if repeats.any() and not np.all(moves.stop[first + 1 : last]):  # a blend goes on across a repeated waypoint
        return _with_repeats(moves, robot, first, last, repeats)
    return _samples(moves, robot, first, last)


def _with_repeats(moves, robot, first, last, repeats):
    """`run_samples` of a run some of whose waypoints repeat the one before (motions that do not move).

    The run is sampled without them (a corner is blended between the
    motions that move, its zone the last repeat's, a stop if any of them
    is one); each repeat then gets a copy of the sample its waypoint is,
    after it.
    """
    head = np.cumsum(~repeats) - 1  # (W,) the kept waypoint each one is or repeats, in the kept numbering
    kept = first + np.flatnonzero(~repeats)
    group_start = np.flatnonzero(~repeats)
    group_end = np.r_[group_start[1:], len(repeats)] - 1
    taken = {f.name: getattr(moves, f.name)[kept] for f in dataclasses.fields(moves)
             if f.name not in ("tools", "labels")}
    taken["stop"] = np.logical_or.reduceat(np.asarray(moves.stop[first : last + 1]), group_start)
    taken["zone"] = moves.zone[first + group_end]
    compact = dataclasses.replace(moves, labels=[moves.labels[k] for k in kept.tolist()], **taken)
    q, owner, (waypoint, flange, flange_jac), curved, track = _samples(compact, robot, 0, len(kept) - 1)
    last_row = np.r_[0, np.flatnonzero(np.diff(owner)) + 1, len(owner)][1:] - 1  # of each kept waypoint
    last_row[0] = 0
    rows = np.r_[np.arange(len(q)), last_row[head[repeats]]]
    order = np.argsort(rows, kind="stable")
    owner_out = np.r_[kept[owner], first + np.flatnonzero(repeats)][order]
    at = np.where(waypoint >= 0, kept[np.maximum(waypoint, 0)] - first, -1)
    repeated_at = np.where(at[last_row[head[repeats]]] >= 0, np.flatnonzero(repeats), -1)
    return (q[rows[order]], owner_out, (np.r_[at, repeated_at][order], flange[head], flange_jac[head]), curved,
            None if track is None else track[rows[order]])


def _samples(moves, robot, first, last):
    """`run_samples` of a run without repeated waypoints (or of stops)."""
    geometry = _Geometry(moves, robot, first, last)
    local, fraction = geometry.sample_fractions()
    local, fraction = np.r_[0, local], np.r_[0.0, fraction]  # first: motion 0 at 0
    q = geometry.solve(local, fraction, seed=None)
    local, fraction, q = geometry.bisect_jumps(local, fraction, q)
    at_waypoint = (fraction == 1.0) & (geometry.blend_end[local] == 0.0)  # a blended corner's is not on the path
    waypoint = np.where(at_waypoint, local + 1, np.where(np.arange(len(q)) == 0, 0, -1))
    track = geometry.track(local, fraction) if moves.on_track else None
    return (q, first + np.where(fraction > 0, local + 1, local), (waypoint, geometry.flange, geometry.flange_jac),
            bool(np.any(geometry.blend_samples > 0)), track)


class _Geometry:
    """The motions first + 1 .. last of a run, vectorized; motion ``first + 1 + i`` has local index i."""

    def __init__(self, moves, robot, first, last):
        self.moves, self.robot = moves, robot
        self.k = np.arange(first + 1, last + 1)
        self.q_a, self.q_b = moves.q[self.k - 1], moves.q[self.k]
        self.joint = moves.kind[self.k] == JOINT
        self.flange, self.flange_jac = fk_and_jacobian(robot, moves.q[first : last + 1], tcp=False)  # once each
        if len(self.k) and np.all(moves.tool[self.k] == moves.tool[first + 1]):  # one tool: each waypoint's TCP pose once
            T = self.flange @ moves.tools[moves.tool[first + 1]]
            T_a, T_b = T[:-1], T[1:]
        else:
            tools = moves.tool_of(self.k)
            T_a, T_b = self.flange[:-1] @ tools, self.flange[1:] @ tools
        self.R_a, self.R_b, self.p_a, self.p_b = T_a[:, :3, :3], T_b[:, :3, :3], T_a[:, :3, 3], T_b[:, :3, 3]
        cosine = 0.5 * (np.einsum("nji,nji->n", self.R_a, self.R_b) - 1.0)  # of the turn: (trace(R_a^T R_b) - 1) / 2
        self.angle = np.arccos(np.clip(cosine, -1.0, 1.0))
        self.turn = np.full((len(self.k), 3), np.nan)  # rotation vectors, solved where samples need them
        self.length = np.linalg.norm(self.p_b - self.p_a, axis=1)
        self.circle = np.zeros(len(self.k), dtype=bool)
        self.centre, self.e1, self.e2 = np.zeros((3, len(self.k), 3))
        self.radius, self.sweep = np.zeros((2, len(self.k)))
        for i in np.flatnonzero(moves.kind[self.k] == CIRCULAR):
            via = fk(robot.replace(T_flange_tool=moves.tool_of(self.k[i])), moves.via[self.k[i]])[:3, 3]
            self._set_circle(i, via)
        self.closed_form = ik_family(robot) is not None
        self.branch = np.full(len(self.k), -1)  # configuration (branch index) of each linear / circular motion
        if self.closed_form:
            self._same_configuration(moves, first, last)
        self._set_blends(moves)

    def _set_blends(self, moves):
        """Blend radius (mm) of each inner corner and the share of each motion it takes at its start and end."""
        self.radius_at = np.zeros(len(self.k) + 1)  # of the corner at the end of motion i - 1 (0: none)
        self.blend_start, self.blend_end = np.zeros((2, len(self.k)))  # fraction of motion i in a blend
        self.blend_samples = np.zeros(len(self.k), dtype=int)  # sample intervals of half the blend at motion i's end
        corner = self.k[:-1]  # waypoint between motions i and i + 1
        if not corner.size:
            return
        blended = (~moves.stop[corner] & (moves.zone[corner] > 0.0) & (moves.tool[corner] == moves.tool[corner + 1])
                   & (self.length[:-1] > 0.0) & (self.length[1:] > 0.0))
        if not blended.any():
            return
        radius = np.minimum(moves.zone[corner], 0.5 * np.minimum(self.length[:-1], self.length[1:]))
        with np.errstate(divide="ignore", invalid="ignore"):
            direction = (self.p_b - self.p_a) / self.length[:, None]
        turn = np.nan_to_num(np.linalg.norm(direction[1:] - direction[:-1], axis=1), nan=2.0)
        deflection = np.where(self.joint[:-1] | self.joint[1:], np.inf, _MIDDLE * radius * turn)  # middle to corner
        blended &= deflection >= BLEND_DEFLECTION
        radius = np.where(blended, radius, 0.0)
        self.radius_at[1:-1] = radius
        with np.errstate(divide="ignore", invalid="ignore"):
            self.blend_end[:-1] = np.where(blended, radius / self.length[:-1], 0.0)
            self.blend_start[1:] = np.where(blended, radius / self.length[1:], 0.0)
        samples = BLEND_SAMPLES * (TRACK_BLEND_GAIN if moves.on_track else 1)
        self.blend_samples[:-1] = np.where(blended, np.ceil(samples * np.clip(turn, 1.0, 2.0)), 0)

    def _same_configuration(self, moves, first, last):
        """Refuse a linear or circular motion whose target is declared in another configuration than its start."""
        cartesian = np.flatnonzero(~self.joint)
        if not cartesian.size:
            return
        branch = branch_index(self.robot, moves.q[first : last + 1])
        self.branch[cartesian] = branch[cartesian]
        changed = cartesian[branch[cartesian] != branch[cartesian + 1]]
        if changed.size:
            i = changed[0]
            k = self.k[i]
            raise TimingError(
                f"{moves.kind[k]} motion to {moves.labels[k]}: its target is declared in configuration "
                f"{Configuration.from_index(branch[i + 1])}, its start in {Configuration.from_index(branch[i])}; a "
                "linear or circular motion keeps the arm's configuration, so the controller refuses it. Change "
                "the configuration with a joint motion"
            )

    def _set_circle(self, i, via):
        """Centre, radius, plane axes and sweep of circular motion i through ``via`` (3,)."""
        u, w = via - self.p_a[i], self.p_b[i] - self.p_a[i]
        normal = np.cross(u, w)
        if np.linalg.norm(normal) < 1e-6 * max(np.linalg.norm(u) * np.linalg.norm(w), 1e-12):
            raise TimingError(f"circular motion to {self.moves.labels[self.k[i]]}: start, via and end point "
                              "lie on one line")
        centre = self.p_a[i] + (np.dot(u, u) * np.cross(w, normal) + np.dot(w, w) * np.cross(normal, u)) / (
            2.0 * np.dot(normal, normal))
        radius = np.linalg.norm(self.p_a[i] - centre)
        e1 = (self.p_a[i] - centre) / radius
        e2 = np.cross(normal / np.linalg.norm(normal), e1)
        end = self.p_b[i] - centre
        self.sweep[i] = np.arctan2(np.dot(end, e2), np.dot(end, e1)) % (2.0 * np.pi)
        self.circle[i], self.centre[i], self.radius[i], self.e1[i], self.e2[i] = True, centre, radius, e1, e2
        self.length[i] = radius * self.sweep[i]

    def sample_fractions(self):
        """The samples of every motion after its start: motion (n,) and fraction of its way (n,), in path order.

        A motion's part outside blends gets `sample_counts` intervals (in
        proportion to its share), each half-blend `BLEND_SAMPLES`; every
        motion's last sample is its end (fraction 1).
        """
        start, end = self.blend_start, self.blend_end
        line = 1.0 - start - end
        counts = np.stack([np.where(start > 0, np.r_[0, self.blend_samples[:-1]], 0),
                           np.where(line > 0, np.ceil(self.sample_counts() * line - 1e-9), 0).astype(int),
                           np.where(end > 0, self.blend_samples, 0)], axis=1)  # (M, 3): start blend, line, end blend
        lo = np.stack([np.zeros_like(start), start, 1.0 - end], axis=1)
        width = np.stack([start, line, end], axis=1)
        n = counts.ravel()
        step = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n) + 1  # 1 .. n within a piece
        fraction = np.repeat(lo.ravel(), n) + step * np.repeat((width.ravel() / np.maximum(n, 1)), n)
        local = np.repeat(np.repeat(np.arange(len(start)), 3), n)
        ends = np.cumsum(counts.sum(axis=1)) - 1
        fraction[ends] = 1.0
        return local, fraction

    def sample_counts(self):
        """Number of sample intervals (M,) of each motion."""
        step = np.radians(STEP_DEG)
        joint_steps = np.max(np.abs(self.q_b - self.q_a), axis=1) / step
        alone = self.moves.stop[self.k - 1] & self.moves.stop[self.k]  # in a run the spline spans its neighbours
        fewest = np.where(alone, np.minimum(MIN_INTERVALS, np.ceil(self.length / MIN_INTERVAL_MM)), 1.0)
        cartesian = np.maximum(np.maximum(self.length / STEP_MM, self.angle / step), fewest)
        return np.ceil(np.maximum(np.where(self.joint, 0.0, cartesian), np.maximum(joint_steps, 1.0))).astype(int)

    def poses(self, local, fraction):
        """TCP poses (n, 4, 4) of motions ``local`` (n,) at ``fraction`` (n,) of their way."""
        T = np.tile(np.eye(4), (len(local), 1, 1))
        unknown = np.unique(local[np.isnan(self.turn[local, 0])])
        if unknown.size:
            relative = np.swapaxes(self.R_a[unknown], 1, 2) @ self.R_b[unknown]
            self.turn[unknown] = matrix_to_rotvec(relative).reshape(-1, 3)
        T[:, :3, :3] = self.R_a[local] @ rotvec_to_matrix(fraction[:, None] * self.turn[local]).reshape(-1, 3, 3)
        line = self.p_a[local] + fraction[:, None] * (self.p_b[local] - self.p_a[local])
        theta = (fraction * self.sweep[local])[:, None]
        arc = self.centre[local] + self.radius[local, None] * (np.cos(theta) * self.e1[local]
                                                                + np.sin(theta) * self.e2[local])
        T[:, :3, 3] = np.where(self.circle[local, None], arc, line)
        return T

    def solve(self, local, fraction, seed):
        """Joints (n, 6) at fractions of motions on the path: `plain` outside blends, blended inside.

        ``seed`` (n, 6): the IK seeds; None to use the joint line.
        """
        blend, incoming, f_in, f_out = self._blend_shares(local, fraction)
        if not blend.size:
            return self.plain(local, fraction, seed)
        q = np.empty((len(local), 6))
        plain = np.ones(len(local), dtype=bool)
        plain[blend] = False
        plain = np.flatnonzero(plain)
        q[plain] = self.plain(local[plain], fraction[plain], None if seed is None else seed[plain])
        q[blend] = self._blended(incoming, f_in, f_out, None if seed is None else seed[blend], local[blend],
                                 fraction[blend])
        return q

    def track(self, local, fraction):
        """The track's position (n,), mm, at fractions of motions on the path: linear in each motion's share of
        its way outside blends, the two motions' shares superposed inside (as `solve` superposes the position)."""
        e = self.moves.track_position
        e_a, e_b = e[self.k - 1], e[self.k]
        out = e_a[local] + fraction * (e_b[local] - e_a[local])
        blend, incoming, f_in, f_out = self._blend_shares(local, fraction)
        out[blend] = (e_a[incoming] + f_in * (e_b[incoming] - e_a[incoming])
                      + f_out * (e_b[incoming + 1] - e_b[incoming]))
        return out

    def _blend_shares(self, local, fraction):
        """The points of a blend among fractions of motions: their rows (b,), the motion into each one's corner
        (b,), and the shares of their way the incoming and the outgoing motion have gone there (each (b,))."""
        before = fraction < self.blend_start[local]
        after = fraction > 1.0 - self.blend_end[local]
        blend = np.flatnonzero(before | after)
        incoming = local[blend] - before[blend]  # motion i into the corner, i + 1 out of it
        r = self.radius_at[incoming + 1]
        distance = np.where(before[blend], r + fraction[blend] * self.length[local[blend]],
                            (fraction[blend] - 1.0) * self.length[local[blend]] + r)  # from the entry point, 0 .. 2 r
        u = np.clip(distance / (2.0 * r), 0.0, 1.0)
        omega = u**4 * (2.5 - 3.0 * u + u * u)
        f_in = 1.0 - (r - 2.0 * r * (u - omega)) / self.length[incoming]
        f_out = 2.0 * r * omega / self.length[incoming + 1]
        return blend, incoming, f_in, f_out

    def _blended(self, incoming, f_in, f_out, seed, local, fraction):
        """Joints (n, 6) of blend points: motions ``incoming`` (n,) at f_in and the next at f_out, superposed."""
        corner = self.q_b[incoming]
        q = (self.q_a[incoming] + f_in[:, None] * (corner - self.q_a[incoming])  # the joint lines superposed
             + f_out[:, None] * (self.q_b[incoming + 1] - corner))
        joint = np.flatnonzero(self.joint[incoming] | self.joint[incoming + 1])
        if joint.size:
            i = incoming[joint]
            seeds = None if seed is None else seed[joint]
            q[joint] = self.plain(i, f_in[joint], seeds) + self.plain(i + 1, f_out[joint], seeds) - corner[joint]
        cartesian = np.flatnonzero(~self.joint[incoming] & ~self.joint[incoming + 1])
        if not cartesian.size:
            return q
        i = incoming[cartesian]
        T_in, T_out = self.poses(i, f_in[cartesian]), self.poses(i + 1, f_out[cartesian])
        T = np.tile(np.eye(4), (len(i), 1, 1))
        T[:, :3, 3] = T_in[:, :3, 3] + T_out[:, :3, 3] - self.p_b[i]
        T[:, :3, :3] = T_in[:, :3, :3] @ np.swapaxes(self.R_b[i], 1, 2) @ T_out[:, :3, :3]
        seeds = q[cartesian] if seed is None else seed[cartesian]
        for tool, group in tool_groups(self.moves, self.k[i]):
            part = cartesian[group]
            q[part] = self._continuous(self.robot.replace(T_flange_tool=tool), T[group], seeds[group], local[part],
                                       fraction[part])
        return q

    def plain(self, local, fraction, seed):
        """Joints (n, 6) at fractions of motions without blends: ends as given, joint motions on their line,
        others by IK. ``seed`` (n, 6): the IK seeds; None to use the joint line."""
        line = self.q_a[local] + fraction[:, None] * (self.q_b[local] - self.q_a[local])
        q = line.copy()
        solve = ~self.joint[local] & (fraction > 0) & (fraction < 1)
        if not solve.any():
            return q
        seed = line if seed is None else seed
        rows = np.flatnonzero(solve)
        T = self.poses(local[rows], fraction[rows])
        for tool, group in tool_groups(self.moves, self.k[local[rows]]):
            part = rows[group]
            q[part] = self._continuous(self.robot.replace(T_flange_tool=tool), T[group], seed[part], local[part],
                                       fraction[part])
        return q

    def _continuous(self, arm, T, seed, local, fraction):
        """IK nearest ``seed`` (n, 6) in each motion's configuration, then checked against the limits.

        The controller follows the path continuously and stops at a joint
        limit, so the solution is chosen first (a Cartesian motion keeps
        the arm's configuration: shoulder, elbow and wrist flags; a pass
        through the wrist singularity shows as a jump of the wrist joints)
        and the limits are checked after. Arms without a closed form are solved
        numerically from the seed.

        Raises
        ------
        TimingError
            Naming the motion, where on it, and the joint beyond its limit
            (or that the path leaves the workspace).
        """
        free = arm.replace(q_min=np.full(6, -np.inf), q_max=np.full(6, np.inf))
        if not self.closed_form:
            solved = ik(free, T, seed=seed)
            q, found = solved.q, solved.success
        else:
            q_all, valid = ik_all(free, T, seed=seed)
            allowed = valid & (np.arange(8)[None, :] == self.branch[local][:, None])
            distance = np.where(allowed, np.sum((q_all - seed[:, None]) ** 2, axis=2), np.inf)
            best = np.argmin(distance, axis=1)
            q, found = q_all[np.arange(len(T)), best], np.isfinite(distance[np.arange(len(T)), best])
        inside = np.all((q >= arm.q_min - 1e-9) & (q <= arm.q_max + 1e-9), axis=1)
        if (found & inside).all():
            return q
        bad = int(np.flatnonzero(~(found & inside))[0])
        i = local[bad]
        what = (f"{self.moves.kind[self.k[i]]} motion to {self.moves.labels[self.k[i]]} "
                f"at {100 * fraction[bad]:.0f} % of its way")
        if not found[bad]:
            raise TimingError(f"{what}: the path leaves the workspace, or would have to change the arm's "
                              "configuration")
        j = int(np.flatnonzero((q[bad] < arm.q_min) | (q[bad] > arm.q_max))[0])
        limit = arm.q_max[j] if q[bad, j] > arm.q_max[j] else arm.q_min[j]
        raise TimingError(f"{what}: J{j + 1} would reach {np.degrees(q[bad, j]):.1f} deg, beyond its limit "
                          f"{np.degrees(limit):.1f} deg; the controller cannot run it")

    def bisect_jumps(self, local, fraction, q):
        """Samples with every interval whose joint step exceeds JUMP_DEG bisected; TimingError at a singular pass."""
        jump = np.radians(JUMP_DEG)
        while True:
            big = np.flatnonzero(np.max(np.abs(np.diff(q, axis=0)), axis=1) > jump)
            if not big.size:
                return local, fraction, q
            motion = local[big + 1]
            left = np.where(local[big] == motion, fraction[big], 0.0)
            width = fraction[big + 1] - left
            if np.any(width < _SMALLEST_FRACTION):
                self._singular(big[np.argmin(width)], motion[np.argmin(width)], left[np.argmin(width)], q)
            middle = 0.5 * (left + fraction[big + 1])
            q_middle = self.solve(motion, middle, seed=q[big])
            order = np.argsort(np.r_[np.arange(len(q)), big + 0.5], kind="stable")
            local = np.r_[local, motion][order]
            fraction = np.r_[fraction, middle][order]
            q = np.concatenate([q, q_middle])[order]

    def _singular(self, row, i, fraction, q):
        jump = np.radians(JUMP_DEG)
        turned = np.abs(q[row + 1] - q[row])
        joints = " and ".join(f"J{j + 1}" for j in np.flatnonzero(turned > jump))
        raise TimingError(
            f"{self.moves.kind[self.k[i]]} motion to {self.moves.labels[self.k[i]]} passes through a singularity "
            f"at {100 * fraction:.0f} % of its way: {joints} would turn by {np.degrees(turned.max()):.0f} deg at "
            "one point; the controller cannot follow it. Move the path away from the singularity or use a "
            "joint motion"
        )


def swept_changes(moves, robot, k, change):
    """The joint change (n, 6) of linear / circular motions k (n,) along their path, from their declared start.

    ``change`` (n, 6) is each motion's declared change wrapped to less than
    half a turn, with a joint turning by more than `AMBIGUOUS_DEG`: near a
    wrist singularity the path may turn a joint by more than half a turn,
    the other way round. The path is followed (sampled, without joint
    limits: whether it stays within them is checked when it is timed)
    towards the wrapped end, then towards the ends with some of the joints
    turning by more than `AMBIGUOUS_DEG` the other way (fewest first): the
    first the path reaches without a jump is the change. A motion no way
    reaches keeps ``change`` (its sampling reports why).
    """
    out = np.array(change, dtype=float)
    free = robot.replace(q_min=np.full(6, -np.inf), q_max=np.full(6, np.inf))
    for i, motion in enumerate(k):
        swings = np.flatnonzero(np.abs(out[i]) > np.radians(AMBIGUOUS_DEG))
        flips = np.array(sorted(itertools.product((0.0, 1.0), repeat=len(swings)), key=sum))  # fewest first
        candidates = np.tile(out[i], (len(flips), 1))
        candidates[:, swings] -= flips * np.sign(out[i, swings]) * 2.0 * np.pi
        start = moves.q[motion - 1]
        for candidate in candidates:
            two = dataclasses.replace(moves.rows(motion - 1, motion + 1), q=np.array([start, start + candidate]))
            try:
                run_samples(two, free, 0, 1)
            except TimingError:
                continue
            out[i] = candidate
            break
    return out


def tool_groups(moves, k):
    """``[(tool (4, 4), rows)]``: the distinct tools of motions k (n,) and the rows of k using each."""
    index = moves.tool[k]
    if not len(index) or np.all(index == index[0]):
        return [(moves.tools[index[0]], np.arange(len(index)))] if len(index) else []
    return [(moves.tools[t], np.flatnonzero(index == t)) for t in np.unique(index)]
