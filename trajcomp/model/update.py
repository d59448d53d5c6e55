"""What a light re-calibration (`trajcomp recalibrate`) changed in a model, and the uncertainty it added.

The update's parameters are arm parameters of `trajcomp.arm.parameters`
(the tool, the joint zeros) and one thermal `SCALE` of the lengths of links
1 to `SCALED_LINKS`. A model file keeps the last update's values and
covariance in its ``report["update"]`` in display units (mm, deg, ppm).
Every target's landing estimate adds the position covariance the update
leaves (`position_covariance`): a model updated from 30 rows is less
certain than one calibrated on hundreds.
"""

import numpy as np

from trajcomp.arm.parameters import is_angle, pose_jacobian

SCALE = "scale"  # the thermal scale's name: a fraction of each length (ppm in what is shown and stored)
SCALED_LINKS = 5  # a and d of links 1..5 scale; link 6 ends in the tool
PPM = 1e-6


def to_display(names):
    """Factor (P,) from internal units (mm, rad, fraction) to display units (mm, deg, ppm)."""
    return np.array([np.degrees(1.0) if is_angle(n) else 1.0 / PPM if n == SCALE else 1.0 for n in names])


def parameter_jacobian(robot, q, names, R_tcp_target=None):
    """TCP poses (N, 4, 4) and the pose Jacobian (N, 6, P) of update parameters ``names`` at joints q (N, 6) rad.

    As `trajcomp.arm.parameters.pose_jacobian`, with `SCALE` the derivative
    of every scaled length at once (each length times its own derivative).
    """
    geometric = [n for n in names if n != SCALE]
    scaled = [f"{k}{j + 1}" for j in range(SCALED_LINKS) for k in ("a", "d")]
    T_tcp, jac = pose_jacobian(robot, q, geometric + scaled, R_tcp_target)
    std = robot.as_standard()
    lengths = np.array([getattr(std, k)[j] for j in range(SCALED_LINKS) for k in ("a", "d")])
    columns = [jac[:, :, [geometric.index(n)]] if n != SCALE else (jac[:, :, len(geometric):] @ lengths)[:, :, None]
               for n in names]
    return T_tcp, np.concatenate(columns, axis=2) if columns else np.zeros((len(q), 6, 0))


def position_covariance(model, joints, names=None, covariance=None):
    """Position covariance (N, 3, 3) mm^2 that update parameters add at commanded joints (N, 6) rad.

    ``names`` and their ``covariance`` (P, P), internal units; default the
    arm parameters of the model's last update (``report["update"]``, zero
    for a model never updated or one the rows did not change). Propagated at
    the joints the composite arm reaches.
    """
    joints = np.atleast_2d(joints)
    if names is None:
        record = (model.report or {}).get("update")
        if not isinstance(record, dict) or record.get("applied") != "update" or not record.get("arm"):
            return np.zeros((len(joints), 3, 3))
        names = list(record["arm"])
        pick = [record["names"].index(n) for n in names]
        shown = to_display(names)
        covariance = np.asarray(record["covariance"], dtype=float)[np.ix_(pick, pick)] / np.outer(shown, shown)
    if not names:
        return np.zeros((len(joints), 3, 3))
    arm = model.arm("composite", outside="clamp")
    jac = parameter_jacobian(arm.robot, arm.reached_joints(joints), names, model.R_tcp_target)[1][:, :3]
    return np.einsum("nip,pq,njq->nij", jac, covariance, jac)
