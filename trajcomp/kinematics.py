"""Forward kinematics and the geometric Jacobian, vectorized over N configurations.

Joint angles q are the controller's (rad); the robot's joint map turns them
into DH angles. Poses are homogeneous matrices in mm, expressed in the robot
base frame.
"""

import numpy as np


def dh_link_transforms(a, alpha, d, theta, beta=0.0):
    """Standard DH link transforms ``Rz(theta) Tz(d) Tx(a) Rx(alpha) Ry(beta)``.

    Parameters
    ----------
    a, alpha, d : array_like, shape (6,) or (N, 6)
        Link lengths (mm), twists (rad), offsets (mm).
    theta : ndarray, shape (N, 6)
        Joint DH angles, rad.
    beta : array_like, shape (6,) or (N, 6)
        Hayati twists about the link y axis, rad (0 for plain DH).

    Returns
    -------
    ndarray, shape (N, 6, 4, 4)
    """
    theta = np.asarray(theta, dtype=float)
    a, alpha, d = (np.broadcast_to(v, theta.shape) for v in (a, alpha, d))
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    out = np.zeros(theta.shape + (4, 4))
    out[..., 0, 0] = ct
    out[..., 0, 1] = -st * ca
    out[..., 0, 2] = st * sa
    out[..., 0, 3] = a * ct
    out[..., 1, 0] = st
    out[..., 1, 1] = ct * ca
    out[..., 1, 2] = -ct * sa
    out[..., 1, 3] = a * st
    out[..., 2, 1] = sa
    out[..., 2, 2] = ca
    out[..., 2, 3] = d
    out[..., 3, 3] = 1.0
    if np.any(beta):
        beta = np.broadcast_to(beta, theta.shape)
        cb, sb = np.cos(beta), np.sin(beta)
        rot_y = np.zeros(theta.shape + (4, 4))
        rot_y[..., 0, 0] = cb
        rot_y[..., 0, 2] = sb
        rot_y[..., 1, 1] = 1.0
        rot_y[..., 2, 0] = -sb
        rot_y[..., 2, 2] = cb
        rot_y[..., 3, 3] = 1.0
        out = out @ rot_y
    return out


def link_frames(robot, q):
    """Poses of the DH frames 0..6 in the base frame.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (N, 6) or (6,)
        Joint angles, rad.

    Returns
    -------
    ndarray, shape (N, 7, 4, 4)
        ``[:, i]`` is T_base_link{i}.
    """
    std = robot.as_standard()
    q = np.atleast_2d(np.asarray(q, dtype=float))
    links = dh_link_transforms(std.a, std.alpha, std.d, std.dh_angles(q), std.beta)
    frames = np.empty((len(q), 7, 4, 4))
    frames[:, 0] = std.T_base_link0
    for i in range(6):
        frames[:, i + 1] = frames[:, i] @ links[:, i]
    return frames


def fk(robot, q, *, tcp=True):
    """Forward kinematics.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (N, 6) or (6,)
        Joint angles, rad.
    tcp : bool
        True for T_base_tool (the TCP), False for T_base_flange.

    Returns
    -------
    ndarray, shape (N, 4, 4) or (4, 4) for a single configuration
    """
    single = np.ndim(q) == 1
    end = _end(robot, link_frames(robot, q), tcp)
    return end[0] if single else end


def jacobian(robot, q, *, tcp=True):
    """Geometric Jacobian of the TCP (or flange) in the base frame.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (N, 6)
        Joint angles, rad.
    tcp : bool
        Reference point: TCP (True) or flange origin (False).

    Returns
    -------
    ndarray, shape (N, 6, 6)
        Rows 0-2: linear velocity (mm/rad), rows 3-5: angular velocity
        (rad/rad), per unit joint angle.
    """
    return fk_and_jacobian(robot, q, tcp=tcp)[1]


def fk_and_jacobian(robot, q, *, tcp=True):
    """`fk` (N, 4, 4) and `jacobian` (N, 6, 6) of q (N, 6) from one pass over the links."""
    frames = link_frames(robot, q)
    end = _end(robot, frames, tcp)
    axes = frames[:, :6, :3, 2]
    origins = frames[:, :6, :3, 3]
    jac = np.empty((len(frames), 6, 6))
    jac[:, :3, :] = np.swapaxes(np.cross(axes, end[:, None, :3, 3] - origins), 1, 2)
    jac[:, 3:, :] = np.swapaxes(axes, 1, 2)
    return end, jac @ robot.joint_map


def _end(robot, frames, tcp):
    """Flange (or TCP) poses (N, 4, 4) from link frames (N, 7, 4, 4)."""
    end = frames[:, 6] @ robot.T_link6_flange
    return end @ robot.T_flange_tool if tcp else end
