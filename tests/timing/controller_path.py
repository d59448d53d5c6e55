"""An independent reference for the timing: the programmed geometry sampled at 1 kHz, solved by IK.

Nothing of `trajcomp.timing`'s path construction is used here. For each
run between two stops of a program of linear motions, the controller's
path is built from the waypoints' TCP poses alone:

- outside a zone, the straight line between two waypoints, the
  orientation turning uniformly about one axis;
- a corner with zone z (not an exact stop) is blended over
  r = min(z, half of each neighbouring motion) on both sides by
  superposing the two motions (the incoming one leaving the line r before
  the corner, the outgoing one joining it r after): with
  Omega(u) = 2.5 u^4 - 3 u^5 + u^6, u in [0, 1], the incoming motion is
  at 2 r (u - Omega(u)) past its entry point, the outgoing one at
  2 r Omega(u) past the corner, and the blend is p = p_in + p_out - p_corner,
  R = R_in R_corner^T R_out.

The timing's own speed profile places the TCP on that path: each 1 ms
sample of the timed joints is taken through forward kinematics and
projected onto the path (nearest point of a 0.02 mm polyline, then onto
its segment); the exact pose there is solved by IK (the branch nearest
the timed joints), and the joint velocity and acceleration are finite
differences of those joints. The distance of the timed TCP from its
projection is the deviation from the programmed path.
"""

import dataclasses

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk

DT = 1e-3  # s
POLYLINE_MM = 0.02


def _omega(u):
    return 2.5 * u**4 - 3.0 * u**5 + u**6


class ProgrammedPath:
    """The controller's path of LIN waypoints ``poses`` (n, 4, 4) with corner radii ``zones`` (n,) (0: kept).

    Its parameter sigma runs over the pieces in order: a line piece by its
    length (mm), a blend by 2 r.
    """

    def __init__(self, poses, zones):
        p, R = poses[:, :3, 3], poses[:, :3, :3]
        self.p, self.R = p, R
        self.length = np.linalg.norm(np.diff(p, axis=0), axis=1)
        n = len(p)
        r = np.zeros(n)
        for k in range(1, n - 1):
            r[k] = min(zones[k], 0.5 * self.length[k - 1], 0.5 * self.length[k]) if zones[k] > 0 else 0.0
        self.r = r
        pieces = []  # (kind, index, span): ("line", motion m (from waypoint m to m + 1), (d0, d1)) or ("blend", k, r)
        for m in range(n - 1):
            if r[m] > 0:
                pieces.append(("blend", m, 2.0 * r[m]))
            d0, d1 = r[m], self.length[m] - r[m + 1]
            if d1 > d0:
                pieces.append(("line", m, (d0, d1)))
        self.pieces = pieces
        spans = [piece[2] if piece[0] == "blend" else piece[2][1] - piece[2][0] for piece in pieces]
        self.starts = np.r_[0.0, np.cumsum(spans)]
        self.total = float(self.starts[-1])

    def _line(self, m, d):
        """Positions (N, 3) and rotations of motion m at distances d (N,) from its start."""
        f = d / self.length[m]
        turn = Rotation.from_matrix(self.R[m].T @ self.R[m + 1]).as_rotvec()
        rotation = Rotation.from_matrix(self.R[m]) * Rotation.from_rotvec(f[:, None] * turn)
        return self.p[m] + f[:, None] * (self.p[m + 1] - self.p[m]), rotation

    def poses(self, sigma):
        """TCP poses (N, 4, 4) at parameters sigma (N,)."""
        sigma = np.clip(sigma, 0.0, self.total)
        piece = np.clip(np.searchsorted(self.starts, sigma, side="right") - 1, 0, len(self.pieces) - 1)
        T = np.tile(np.eye(4), (len(sigma), 1, 1))
        for i in np.unique(piece):
            rows = piece == i
            local = sigma[rows] - self.starts[i]
            kind, index, span = self.pieces[i]
            if kind == "line":
                position, rotation = self._line(index, span[0] + local)
            else:
                k, r = index, span / 2.0
                u = local / span
                alpha, beta = 2.0 * r * (u - _omega(u)), 2.0 * r * _omega(u)
                p_in, R_in = self._line(k - 1, self.length[k - 1] - r + alpha)
                p_out, R_out = self._line(k, beta)
                position = p_in + p_out - self.p[k]
                rotation = R_in * Rotation.from_matrix(self.R[k]).inv() * R_out
            T[rows, :3, 3], T[rows, :3, :3] = position, rotation.as_matrix()
        return T

    def coordinate(self, sigma, values):
        """An axis that moves with the path (a track), (N,) at parameters sigma (N,): linear in each motion's
        progress from waypoint value ``values[m]`` (n,) to the next, blended in a zone as the position is (the
        incoming and outgoing motions superposed)."""
        sigma = np.clip(sigma, 0.0, self.total)
        piece = np.clip(np.searchsorted(self.starts, sigma, side="right") - 1, 0, len(self.pieces) - 1)
        out = np.empty(len(sigma))

        def along(m, d):
            return values[m] + d / self.length[m] * (values[m + 1] - values[m])

        for i in np.unique(piece):
            rows = piece == i
            local = sigma[rows] - self.starts[i]
            kind, index, span = self.pieces[i]
            if kind == "line":
                out[rows] = along(index, span[0] + local)
            else:
                k, r, u = index, span / 2.0, local / span
                out[rows] = (along(k - 1, self.length[k - 1] - r + 2.0 * r * (u - _omega(u)))
                             + along(k, 2.0 * r * _omega(u)) - values[k])
        return out

    def project(self, points):
        """Parameters (N,) of the path points nearest ``points`` (N, 3), and the distances (N,), mm."""
        sigma = np.linspace(0.0, self.total, max(int(np.ceil(self.total / POLYLINE_MM)), 2) + 1)
        sigma = np.union1d(sigma, self.starts)
        vertices = self.poses(sigma)[:, :3, 3]
        _, nearest = cKDTree(vertices).query(points)
        best_sigma, best = np.zeros(len(points)), np.full(len(points), np.inf)
        for a in (nearest - 1, nearest):
            a = np.clip(a, 0, len(vertices) - 2)
            d = vertices[a + 1] - vertices[a]
            share = np.clip(np.einsum("ni,ni->n", points - vertices[a], d) / np.maximum(np.einsum("ni,ni->n", d, d),
                                                                                          1e-300), 0.0, 1.0)
            s = sigma[a] + share * (sigma[a + 1] - sigma[a])
            distance = np.linalg.norm(points - (vertices[a] + share[:, None] * d), axis=1)
            better = distance < best
            best_sigma[better], best[better] = s[better], distance[better]
        h = 1e-3
        for _ in range(3):  # Newton's steps onto the exact path: the polyline's chords are off by h^2 / (8 radius)
            here = self.poses(best_sigma)[:, :3, 3]
            tangent = (self.poses(best_sigma + h)[:, :3, 3] - self.poses(best_sigma - h)[:, :3, 3]) / (2.0 * h)
            step = np.einsum("ni,ni->n", points - here, tangent) / np.einsum("ni,ni->n", tangent, tangent)
            best_sigma = np.clip(best_sigma + step, 0.0, self.total)
        exact = np.linalg.norm(points - self.poses(best_sigma)[:, :3, 3], axis=1)
        return best_sigma, exact


@dataclasses.dataclass
class Reference:
    """What the reference measured: peaks over the limits, and the path deviation (mm)."""

    velocity_ratio: float
    acceleration_ratio: np.ndarray  # (6,)
    speed_ratio: float
    deviation: float  # largest, mm
    deviation_outside_zones: float  # largest where the path is a line, mm
    median_deviation: float

    @property
    def worst(self):
        return max(self.velocity_ratio, float(self.acceleration_ratio.max()))


def controller_check(moves, result, robot):
    """The reference check of a re-timed sequence of linear motions (`Reference`)."""
    tool = moves.tools[moves.tool[1]] if len(moves) > 1 else moves.tools[0]
    arm = robot.replace(T_flange_tool=tool)
    stops = np.flatnonzero(moves.stop)
    v_ratio, a_ratio, speed_ratio, deviations, outside = 0.0, np.zeros(6), 0.0, [], []
    for first, last in zip(stops[:-1], stops[1:]):
        poses = fk(arm, result.q[first : last + 1])
        t0, t1 = result.t[first], result.t[last]
        if t1 <= t0:
            continue
        path = ProgrammedPath(poses, moves.zone[first : last + 1])
        t = np.r_[np.arange(t0, t1, DT), t1]
        q_timed = result.at(t)[0]
        sigma, distance = path.project(fk(arm, q_timed)[:, :3, 3])
        deviations.append(distance)
        piece = np.clip(np.searchsorted(path.starts, sigma, side="right") - 1, 0, len(path.pieces) - 1)
        on_line = np.array([path.pieces[i][0] == "line" for i in piece])
        outside.append(distance[on_line])
        q = ik(arm, path.poses(sigma), seed=q_timed).raise_on_failure().q
        step = np.diff(t)
        qd = np.diff(q, axis=0) / step[:, None]
        middle = 0.5 * (step[1:] + step[:-1])
        qdd = np.diff(qd, axis=0) / middle[:, None]
        k = first + 1 + np.searchsorted(np.cumsum(path.length), sigma[1:] - 1e-9)  # motion of each step
        k = np.clip(k, first + 1, last)
        v_ratio = max(v_ratio, float(np.max(np.abs(qd) / moves.velocity[k])))
        a_ratio = np.maximum(a_ratio, np.max(np.abs(qdd) / moves.acceleration[k[1:]], axis=0))
        p = path.poses(sigma)[:, :3, 3]
        speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / step
        speed_ratio = max(speed_ratio, float(np.max(speed / moves.tcp_speed[k])))
    deviation = np.concatenate(deviations) if deviations else np.zeros(1)
    line = np.concatenate(outside) if outside else np.zeros(1)
    return Reference(v_ratio, a_ratio, speed_ratio, float(deviation.max()), float(line.max(initial=0.0)),
                     float(np.median(deviation)))
