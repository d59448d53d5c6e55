"""Residual model classes tried on top of the joint model of the real UR10 (issue 37), for the benchmarks only.

None of them is in trajcomp: on the UR10's held-out planes and campaign
slabs they win too little to pay for what they cost (bench_accuracy.py
``ur10fields``, bench_recalibrate.py's floors; docs/benchmarks.md); the
field over the position and the wrist angles that beat them is
(`trajcomp.model.interpolate.GaussianField`). Kept here so that the
figures in the docs come with the code that printed them.

- `JointKriging`: the kriging mean of the residual over the commanded
  joints (an orientation-aware field: the data set measures up to 23
  orientations at each position, which a field over positions cannot tell
  apart), its length and nugget chosen on held-out slabs of the training
  rows (`choose_on_slabs`);
- `bending_features`: gravity compliance of each joint's bearing about the
  two axes normal to the joint (what the joint model's ``grav`` terms do
  about the joint axis itself), linear in its coefficients.
"""

import numpy as np
from scipy.linalg import cho_factor, cho_solve
from scipy.spatial.distance import cdist

from trajcomp.arm.kinematics import fk, link_frames
from trajcomp.calibration.identify import region_folds

LENGTHS_DEG = (10.0, 20.0, 40.0, 80.0)  # correlation lengths tried, deg of joint angle (all six joints alike)
NUGGETS = (0.3, 1.0, 3.0)  # noise-to-signal variance ratios tried
SLABS = 4  # held-out slabs of the training rows the length and nugget are chosen on


class JointKriging:
    """Simple kriging (zero prior mean) of residuals (N, 3) mm over commanded joints (N, 6) rad.

    Squared-exponential correlation of the joint angles in deg over
    ``length`` deg, plus ``nugget`` times the signal on the diagonal.
    """

    def __init__(self, joints, residuals, length, nugget):
        self.points, self.length = np.degrees(joints) / length, length
        correlation = np.exp(-0.5 * cdist(self.points, self.points, "sqeuclidean"))
        self.weights = cho_solve(cho_factor(correlation + nugget * np.eye(len(joints))), residuals)

    def evaluate(self, joints):
        """The field (M, 3) mm at joints (M, 6) rad."""
        return np.exp(-0.5 * cdist(np.degrees(joints) / self.length, self.points, "sqeuclidean")) @ self.weights


def choose_on_slabs(position, joints, residuals, lengths=LENGTHS_DEG, nuggets=NUGGETS, slabs=SLABS):
    """``(length, nugget, held_out_mm)``: the `JointKriging` options of the least mean |error| on ``slabs`` slabs
    of the commanded positions (N, 3) mm (`region_folds`), each predicted from the others' residuals (N, 3) mm."""
    regions, _ = region_folds(position, slabs)
    scores = {}
    for length in lengths:
        for nugget in nuggets:
            errors = []
            for rows in regions:
                train = np.setdiff1d(np.arange(len(joints)), rows)
                field = JointKriging(joints[train], residuals[train], length, nugget)
                errors.append(np.linalg.norm(residuals[rows] - field.evaluate(joints[rows]), axis=1))
            scores[length, nugget] = float(np.concatenate(errors).mean())
    best = min(scores, key=scores.get)
    return (*best, scores[best])


def bending_features(robot, joints):
    """Displacement (N, 3, 54) mm of the TCP per unit coefficient of each bending term.

    Term (j, u, k): frame j's bearing (the frame joint j + 1 turns about;
    j = 0 the base) turns about its axis u (x or y, normal to the joint
    axis) by the coefficient times the torque about u of a unit weight at
    the origin of DH frame k > j or at the TCP (m of lever), gravity along
    -z of the base: 7 - j lumps for frame j, 54 terms.
    """
    frames = link_frames(robot, joints)
    tcp = fk(robot, joints)[:, :3, 3]
    gravity = np.array([0.0, 0.0, -1.0])
    columns = []
    for j in range(6):
        origin = frames[:, j, :3, 3]
        lumps = [frames[:, k, :3, 3] for k in range(j + 1, 7)] + [tcp]
        for axis in (0, 1):
            u = frames[:, j, :3, axis]
            lever = np.cross(u, tcp - origin)
            for point in lumps:
                torque = np.einsum("ni,ni->n", u, np.cross(point - origin, gravity)) / 1000.0
                columns.append(lever * torque[:, None])
    return np.stack(columns, axis=2)


def fit_bending(features, residuals):
    """Coefficients (P,) of `bending_features` (N, 3, P) fitting residuals (N, 3) mm by least squares (a 1e-6
    ridge on the columns scaled to unit norm: their exact redundancies)."""
    matrix = features.reshape(-1, features.shape[2])
    scale = np.linalg.norm(matrix, axis=0) + 1e-12
    scaled = matrix / scale
    return np.linalg.solve(scaled.T @ scaled + 1e-6 * np.eye(len(scale)), scaled.T @ residuals.ravel()) / scale
