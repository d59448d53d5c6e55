"""Numerical IK: damped Gauss-Newton on the full pose (`ik_numeric`) and the pose error it minimizes.

Used for arms of no closed-form family, and to refine the nominal
closed-form solution on an identified arm (`trajcomp.arm.ik.ik_near`).
`ik_numeric` and `pose_error` are re-exported by `trajcomp.arm.ik`.
"""

import numpy as np

from trajcomp.arm.ik_types import (
    JOINT_LIMITS,
    NOT_CONVERGED,
    POS_TOL,
    ROT_TOL,
    SINGULAR,
    UNREACHABLE,
    IKResult,
    _pose_stack,
)
from trajcomp.arm.kinematics import fk_and_jacobian, in_blocks, jacobian

_ROT_SCALE = 1000.0  # mm/rad, weight of orientation against position error in Gauss-Newton
_MAX_STEP = 0.3  # rad, largest joint step of one Gauss-Newton iteration


def ik_numeric(robot, T_base_tcp, q0, *, tol_pos=POS_TOL, tol_rot=ROT_TOL, max_iter=30):
    """Damped Gauss-Newton IK on the full pose, all targets iterating together.

    Meant for identified models close to a nominal arm: from a start within a
    few mm / tenths of a degree it converges quadratically, in 2-4 iterations.
    The damping (the weighted error squared, Sugihara 2011) keeps steps
    bounded near singularities and vanishes at the solution.

    Parameters
    ----------
    robot : Robot
    T_base_tcp : array_like, shape (N, 4, 4) or (4, 4)
        Target TCP poses, base frame, mm.
    q0 : array_like, shape (N, 6) or (6,)
        Start joint angles, rad (e.g. the nominal closed-form solution).
        Rows with NaN fail at once with reason "unreachable".
    tol_pos, tol_rot : float
        Convergence tolerances, mm and rad.
    max_iter : int

    Returns
    -------
    IKResult
        Failure reasons: "not converged" ("singular" when the Jacobian at the
        last iterate is rank deficient), "joint limits" when the converged
        solution leaves the limits, "unreachable" for a NaN start.
    """
    T = _pose_stack(T_base_tcp)
    q0 = np.broadcast_to(np.asarray(q0, dtype=float), (len(T), 6))

    def solve(T, q):
        q = q.copy()
        started = np.all(np.isfinite(q), axis=1)
        res_pos = np.full(len(T), np.nan)
        res_rot = np.full(len(T), np.nan)
        active = np.flatnonzero(started)
        for iteration in range(max_iter + 1):
            pose, jac = fk_and_jacobian(robot, q[active])
            error = pose_error(pose, T[active])
            res_pos[active] = _norm(error[:, :3])
            res_rot[active] = _norm(error[:, 3:])
            done = (res_pos[active] < tol_pos) & (res_rot[active] < tol_rot)
            active, error, jac = active[~done], error[~done], jac[~done]
            if not active.size or iteration == max_iter:
                break
            q[active] += _gauss_newton_step(jac, error)
        converged = started & (res_pos < tol_pos) & (res_rot < tol_rot)
        inside = robot.within_limits(q)
        reason = np.full(len(T), "", dtype=object)
        reason[~started] = UNREACHABLE
        if active.size:
            sv = np.linalg.svd(_scaled(jacobian(robot, q[active])), compute_uv=False)
            reason[active] = np.where(sv[:, -1] < 1e-8 * sv[:, 0], SINGULAR, NOT_CONVERGED)
        reason[converged & ~inside] = JOINT_LIMITS
        success = converged & inside
        return np.where(success[:, None], q, np.nan), success, res_pos, res_rot, reason.astype(str)

    return IKResult(*in_blocks(solve, T, q0))


def _scaled(jac):
    """Jacobian (N, 6, 6) with the orientation rows in mm (times `_ROT_SCALE`)."""
    return jac * np.array([1.0, 1.0, 1.0, _ROT_SCALE, _ROT_SCALE, _ROT_SCALE])[:, None]


def _gauss_newton_step(jac, error):
    """Damped Gauss-Newton joint step (N, 6) for pose errors (N, 6)."""
    jac = _scaled(jac)
    error = error * np.array([1.0, 1.0, 1.0, _ROT_SCALE, _ROT_SCALE, _ROT_SCALE])
    jt = np.swapaxes(jac, 1, 2)
    damping = 0.5 * np.einsum("ni,ni->n", error, error) + 1e-12
    normal = jt @ jac + damping[:, None, None] * np.eye(6)
    step = np.linalg.solve(normal, (jt @ error[:, :, None]))[:, :, 0]
    largest = np.max(np.abs(step), axis=1, keepdims=True)
    return step * np.minimum(1.0, _MAX_STEP / np.maximum(largest, 1e-300))


def pose_error(T_current, T_target):
    """Pose error (N, 6): target minus current position (mm), rotation vector of R_t R_c^T (rad).

    The rotation vector is computed here rather than with scipy: four times
    faster on this hot path, NaN-tolerant, and exact for the small angles
    that matter (atan2 of the skew part, not arccos of the trace).
    """
    err = np.empty((len(T_current), 6))
    err[:, :3] = T_target[:, :3, 3] - T_current[:, :3, 3]
    current, target = T_current[:, :3, :3], T_target[:, :3, :3]
    axis = err[:, 3:]  # half the skew part of R_t R_c^T: the sum over columns k of current_k x target_k, halved
    for i, (u, v) in enumerate(((1, 2), (2, 0), (0, 1))):
        axis[:, i] = _dot(current[:, u], target[:, v]) - _dot(current[:, v], target[:, u])
    axis *= 0.5
    sin = _norm(axis)
    angle = np.arctan2(sin, 0.5 * (np.einsum("nij,nij->n", current, target) - 1.0))
    axis *= np.where(sin > 0.0, angle / np.where(sin > 0.0, sin, 1.0), 1.0)[:, None]
    return err


# ---------------------------------------------------------------- row-wise arithmetic


def _dot(u, v):
    """Row-wise dot products (N,) of (N, 3) arrays (einsum: faster than sums of products on 3 columns)."""
    return np.einsum("ni,ni->n", u, v)


def _norm(u):
    """Row-wise Euclidean norms (N,) of an (N, 3) array."""
    return np.sqrt(_dot(u, u))
