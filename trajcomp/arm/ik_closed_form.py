"""Closed-form IK of the two arm families (`trajcomp.arm.ik.ik_family`): all eight branches, vectorized.

The families and the branch numbering are described in `trajcomp.arm.ik`, the
public entry point (`trajcomp.arm.ik.ik`, `trajcomp.arm.ik.ik_all`); this module
holds the family test, the solution of the DH angles of every branch and
the choice of joint turns inside the limits (`turn_towards`).
"""

import numpy as np

from trajcomp.errors import IKError
from trajcomp.arm.ik_types import BRANCHES
from trajcomp.arm.kinematics import dh_link_transforms
from trajcomp.arm.transforms import invert

_ZERO = 1e-9  # tolerance of the family tests on DH numbers (mm, rad)
_SINGULAR_SIN = 1e-10  # |sin| of joint 5 (or distance/mm on axis 1) below which a joint is free
_REACH_SLACK = 1e-9  # relative slack on cos/sin arguments before a target counts as unreachable
_LIMIT_TOL = 1e-9  # rad, as Robot.within_limits


def ik_family(robot):
    """The closed-form family of a robot: ``"ur"``, ``"spherical"`` or None (numerical IK only)."""
    std = robot.as_standard()
    a, alpha, d = std.a, std.alpha, std.d
    joint_map = robot.joint_map
    wrist_diagonal = np.diag(np.diag(joint_map)[3:])
    integral = np.allclose(joint_map, np.round(joint_map)) and np.isclose(abs(np.linalg.det(joint_map)), 1.0)
    uncoupled_wrist = (
        np.allclose(joint_map[3:, :3], 0.0)
        and np.allclose(joint_map[:3, 3:], 0.0)
        and np.allclose(joint_map[3:, 3:], wrist_diagonal)
    )

    def perpendicular(angle):
        return abs(np.cos(angle)) < _ZERO

    def parallel(angle):
        return abs(np.sin(angle)) < _ZERO and np.cos(angle) > 0

    common = (
        integral
        and uncoupled_wrist
        and not np.any(np.abs(std.beta[:5]) > _ZERO)
        and perpendicular(alpha[0])
        and parallel(alpha[1])
        and perpendicular(alpha[3])
        and perpendicular(alpha[4])
        and abs(a[3]) < _ZERO
        and abs(a[4]) < _ZERO
        and abs(a[1]) > _ZERO
        and np.hypot(a[2], d[3] * np.sin(alpha[2])) > _ZERO
    )
    if not common:
        return None
    if abs(d[4]) < _ZERO:
        return "spherical"
    if parallel(alpha[2]):
        return "ur"
    return None


def _closed_form_family(robot):
    family = ik_family(robot)
    if family is None:
        raise IKError(f"robot {robot.name}: DH table of no closed-form family; use ik_numeric or ik_near")
    return family


def _branches(robot, family, T, seed):
    """Joint angles (N, 8, 6) of all branches, reachable and inside-limits masks (N, 8)."""
    theta, reachable = _dh_branches(robot, family, T, robot.dh_angles(seed))
    q, inside = turn_towards(robot, robot.joint_angles(theta), seed[:, None, :])
    return q, reachable, inside & reachable


def _dh_branches(robot, family, T, theta_seed):
    """DH angles (N, 8, 6) of the branches in configuration order and the reachable mask (N, 8).

    The branches are held on three axes of two, (N, side, elbow, wrist),
    each quantity on those it depends on: joint 1 on the side of axis 1
    alone, so it and the rotations it gives are solved twice per target,
    not eight times; the wrist (UR family) or the planar arm (spherical
    wrist) four times.
    """
    std = robot.as_standard()
    a, alpha, d = std.a, std.alpha, std.d
    sa1, s4, s5 = np.sin(alpha[0]), np.sin(alpha[3]), np.sin(alpha[4])
    # Link 6 beyond Rz(theta6) Tz(d6) is fixed: fold it into the flange.
    link6_rest = dh_link_transforms(a[5], alpha[5], 0.0, np.zeros((1, 1)), std.beta[5])[0, 0]
    X = invert(std.T_base_link0) @ T @ invert(link6_rest @ std.T_link6_flange @ std.T_flange_tool)
    R = X[:, None, None, None, :3, :3]  # (N, 1, 1, 1, 3, 3): the branch axes broadcast
    p = X[:, :3, 3] - d[5] * X[:, :3, 2]  # origin of DH frame 5, DH frame 0
    px, py, pz = (p[:, k, None, None, None] for k in range(3))
    seed = theta_seed[:, :, None, None, None]  # (N, 6, 1, 1, 1)

    # Branch signs (see Configuration): forward side of axis 1, elbow, joint 5, each on its own axis.
    side, elbow_sign, wrist_sign = (np.array([1.0, -1.0]).reshape(shape) for shape in ((2, 1, 1), (2, 1), (2,)))
    L3 = np.hypot(a[2], d[3] * np.sin(alpha[2]))
    beta = np.arctan2(-d[3] * np.sin(alpha[2]), a[2])
    elbow_sign = elbow_sign * side * np.sign(-a[1] * sa1 * _up_sign(robot))
    wrist_sign = wrist_sign * np.sign(-np.prod(np.diag(robot.joint_map)[3:]) * s4 * s5)

    # Joint 1: the wrist point's offset along z1 is s = d2 + d3 + d4 cos(alpha3).
    s = d[1] + d[2] + d[3] * np.cos(alpha[2])
    r = np.hypot(px, py)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # r ~ 0: on the axis, handled below
        ratio = s * sa1 / r
    on_axis = r < _SINGULAR_SIN
    reachable = on_axis | (np.abs(ratio) <= 1.0 + _REACH_SLACK)
    lean = np.arcsin(np.clip(np.nan_to_num(ratio), -1.0, 1.0))
    theta1 = np.where(on_axis, seed[:, 0], np.arctan2(py, px) + np.where(side > 0, lean, np.pi - lean))
    turn1 = _cos_sin(theta1)
    forward = px * turn1[0] + py * turn1[1] - a[0]
    height = sa1 * (pz - d[0])

    if family == "spherical":
        theta2, theta3, planar_ok = _planar(forward, height, a[1], L3, beta, elbow_sign)
        turn23 = _cos_sin(theta2 + theta3)
        x36, z36 = (_into_link(turn23, alpha[2], _into_link(turn1, alpha[0], _column(R, j))) for j in (0, 2))
        r13, r23, r33 = z36  # column 2 of R_36 = R_03^T R
        sin5 = np.hypot(r13, r23)
        theta5 = np.arctan2(wrist_sign * sin5, -s4 * s5 * r33)
        toward = wrist_sign * s5
        theta4 = np.where(sin5 < _SINGULAR_SIN, seed[:, 3], np.arctan2(toward * r23, toward * r13))
        x6 = _into_link(_cos_sin(theta5), alpha[4], _into_link(_cos_sin(theta4), alpha[3], x36))
        theta6 = np.arctan2(x6[1], x6[0])
    else:
        r31, r32, r33 = (_into_link(turn1, alpha[0], _column(R, j))[2] for j in range(3))  # row 2 of R_16 = R_01^T R
        sin5 = np.hypot(r31, r32)
        theta5 = np.arctan2(wrist_sign * sin5, -s4 * s5 * r33)
        toward = wrist_sign * s4
        theta6 = np.where(sin5 < _SINGULAR_SIN, seed[:, 5], np.arctan2(-toward * r32, toward * r31))
        # theta2 + theta3 + theta4 is the angle in the arm plane of column 0 of R_14 = R_01^T R W^T,
        # W = Rx(alpha4) Rz(theta5) Rx(alpha5) Rz(theta6) the wrist's rotation.
        wrist_x = _into_link(_cos_sin(theta6), 0.0, _into_link(_cos_sin(theta5), alpha[4], (1.0, 0.0, 0.0)))
        x14 = _into_link(turn1, alpha[0], tuple(sum(R[..., i, k] * wrist_x[k] for k in range(3)) for i in range(3)))
        theta234 = np.arctan2(x14[1], x14[0])
        # Axis 4 lies d5 before the wrist point along z4 = (s4 sin, -s4 cos) in the arm plane.
        theta2, theta3, planar_ok = _planar(
            forward - d[4] * s4 * np.sin(theta234), height + d[4] * s4 * np.cos(theta234), a[1], L3, beta, elbow_sign
        )
        theta4 = theta234 - theta2 - theta3
    theta, every = np.empty((len(X), 2, 2, 2, 6)), np.empty((len(X), 2, 2, 2), dtype=bool)  # each branch's own
    for j, angle in enumerate((theta1, theta2, theta3, theta4, theta5, theta6)):
        theta[..., j] = angle
    every[...] = reachable & planar_ok
    theta, reachable = theta.reshape(len(X), BRANCHES, 6), every.reshape(len(X), BRANCHES)
    theta[~reachable] = np.nan
    return theta, reachable


def _planar(x, y, a2, L3, beta, elbow_sign):
    """Two-link planar IK: theta2, theta3 placing ``Rz(t2) [(a2, 0) + L3 Rz(t3 + beta) e_x]`` at (x, y)."""
    cos3 = (x**2 + y**2 - a2**2 - L3**2) / (2.0 * a2 * L3)
    ok = np.abs(cos3) <= 1.0 + _REACH_SLACK
    cos3 = np.clip(cos3, -1.0, 1.0)
    sin3 = elbow_sign * np.sqrt(1.0 - cos3**2)
    theta2 = np.arctan2(y, x) - np.arctan2(L3 * sin3, a2 + L3 * cos3)
    return theta2, np.arctan2(sin3, cos3) - beta, ok


def turn_towards(robot, q, ref):
    """Joints q (..., 6), rad, each moved by whole turns inside the limits nearest ``ref`` (..., 6); and the mask
    (...) of rows whose every joint has a turn inside the limits."""
    turn = 2.0 * np.pi
    with np.errstate(invalid="ignore"):
        lowest = np.ceil((robot.q_min - _LIMIT_TOL - q) / turn)
        highest = np.floor((robot.q_max + _LIMIT_TOL - q) / turn)
        k = np.clip(np.round((ref - q) / turn), lowest, highest)
        has_turn = lowest <= highest
    turned = q + turn * k
    # a turn within the tolerance may round one ulp beyond it (1e-9 + 2 pi against a limit of 2 pi): held at it
    held = np.clip(turned, robot.q_min - _LIMIT_TOL, robot.q_max + _LIMIT_TOL)
    return np.where(has_turn, held, turned), np.all(has_turn, axis=-1)


def _up_sign(robot):
    """+1 or -1: the sign making DH z0 point up (along the base z axis)."""
    return -1.0 if robot.as_standard().T_base_link0[2, 2] < 0 else 1.0


# ---------------------------------------------------------------- column arithmetic


def _cos_sin(angle):
    """(cos, sin) of angles (...), rad."""
    return np.cos(angle), np.sin(angle)


def _into_link(turn, alpha, v):
    """``(Rz(theta) Rx(alpha))^T v``: vectors v (three components (...)) in the frame of the next DH link.

    ``turn`` is (cos theta, sin theta) (...); alpha a scalar twist, rad. Column
    arithmetic instead of stacked 3x3 products (the closed forms run over N x 8 branches).
    """
    cos, sin = turn
    x, y = cos * v[0] + sin * v[1], cos * v[1] - sin * v[0]
    cos_alpha, sin_alpha = np.cos(alpha), np.sin(alpha)
    return x, cos_alpha * y + sin_alpha * v[2], cos_alpha * v[2] - sin_alpha * y


def _column(R, j):
    """Column j of rotations R (..., 3, 3) as three components (...)."""
    return R[..., 0, j], R[..., 1, j], R[..., 2, j]
