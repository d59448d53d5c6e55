"""Forward kinematics and the geometric Jacobian, vectorized over N configurations.

Joint angles q are the controller's (rad); the robot's joint map turns them
into DH angles. Poses are homogeneous matrices in mm, expressed in the robot
base frame.
"""

import weakref

import numpy as np

BLOCK = 2048  # rows computed together: enough to vectorize, few enough to keep the arrays in cache
_CHAINS = weakref.WeakKeyDictionary()  # robot -> `_chain` (made once per robot: FK runs in blocks, many per robot)


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

    def frames(q):
        columns = _frame_columns(robot, q, tcp=False)[:7]
        out = np.zeros((columns.shape[-1], 7, 4, 4))
        out[:, :, :3, :] = columns.transpose(3, 0, 2, 1)
        out[:, :, 3, 3] = 1.0
        return (out,)

    return in_blocks(frames, np.atleast_2d(q))[0]


def frame_columns(robot, q, *, tcp=False):
    """The DH frames 0..6 of configurations q (N, 6), rad, as columns with N last: what `link_frames` holds.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (N, 6)
        Joint angles, rad.
    tcp : bool
        Also the TCP frame, as frame 7 (what `fk` gives).

    Returns
    -------
    ndarray, shape (7, 4, 3, N), or (8, 4, 3, N) with ``tcp``
        ``[i, k]``: column k (x, y, z axis, origin in mm) of DH frame i in
        the base frame. Cheaper than `link_frames` for measures over many
        configurations (no 4 x 4 matrix laid out per row); pass blocks of
        rows (`in_blocks`): it takes 672 bytes a row (768 with ``tcp``).
    """
    return _frame_columns(robot, q, tcp=True) if tcp else _frame_columns(robot, q, tcp=False)[:7]


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
    (end,) = in_blocks(lambda q: (_poses(_frame_columns(robot, q, tcp)[7]),), np.atleast_2d(q))
    return end[0] if np.ndim(q) == 1 else end


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
    return in_blocks(lambda q: _fk_and_jacobian(robot, q, tcp), np.atleast_2d(q))


def in_blocks(compute, *arrays):
    """Apply ``compute`` to blocks of `BLOCK` rows of ``arrays`` and join its outputs.

    Parameters
    ----------
    compute : callable
        ``compute(*blocks) -> tuple of arrays`` with one row per input row.
    *arrays : ndarray, each of length N

    Returns
    -------
    tuple of ndarray, each of length N
    """
    n = len(arrays[0])
    parts = [compute(*(arr[i : i + BLOCK] for arr in arrays)) for i in range(0, max(n, 1), BLOCK)]
    return parts[0] if len(parts) == 1 else tuple(np.concatenate(columns) for columns in zip(*parts))


def _fk_and_jacobian(robot, q, tcp):
    columns = _frame_columns(robot, q, tcp)
    axes, origins, end = columns[:6, 2], columns[:6, 3], columns[7, 3]
    lever = end - origins
    # Per DH axis i (joint i + 1 before the joint map): column i of the Jacobian, (6 axes, 6 rows, N).
    per_axis = np.empty((6, 6, columns.shape[-1]))
    for row, (u, v) in enumerate(((1, 2), (2, 0), (0, 1))):
        per_axis[:, row] = axes[:, u] * lever[:, v] - axes[:, v] * lever[:, u]  # axis x lever
    per_axis[:, 3:] = axes
    per_joint = (robot.joint_map.T @ per_axis.reshape(6, -1)).reshape(per_axis.shape)
    return _poses(columns[7]), np.ascontiguousarray(per_joint.transpose(2, 1, 0))


def _frame_columns(robot, q, tcp):
    """The DH frames 0..6 and the end frame (flange or TCP) of q, as columns with N last.

    Chained link by link as ``R_i = R_{i-1} Rz(theta_i) Rx(alpha_i)
    Ry(beta_i)``, ``p_i = p_{i-1} + d_i z_{i-1} + a_i x'`` on (3, N) column
    arrays: a few element-wise operations per link instead of N small 4 x 4
    products (several times faster in numpy).

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (N, 6) or (6,)
        Joint angles, rad.
    tcp : bool
        End frame: TCP (True) or flange (False).

    Returns
    -------
    ndarray, shape (8, 4, 3, N)
        ``[i, k]``: column k (x, y, z axis, origin in mm) of DH frame i
        (i = 0..6) or of the end frame (i = 7), base frame.
    """
    std, twists = _chain(robot)
    theta = std.dh_angles(np.atleast_2d(q)).T
    cos, sin = _cos_sin(theta)
    columns = np.empty((8, 4, 3, theta.shape[1]))
    columns[0] = std.T_base_link0[:3].T[:, :, None]
    turned = np.empty((3, 3, theta.shape[1]))  # frame i - 1 turned by Rz(theta_i)
    for i in range(6):
        x, y, z, origin = columns[i]
        np.multiply(cos[i], x, out=turned[0])
        turned[0] += sin[i] * y
        np.multiply(cos[i], y, out=turned[1])
        turned[1] -= sin[i] * x
        turned[2] = z
        np.matmul(twists[i], turned.reshape(3, -1), out=columns[i + 1, :3].reshape(3, -1))
        columns[i + 1, 3] = origin + std.d[i] * z + std.a[i] * turned[0]
    end = robot.T_link6_flange @ robot.T_flange_tool if tcp else robot.T_link6_flange
    rotation6 = columns[6, :3].reshape(3, -1)
    np.matmul(end[:3, :3].T, rotation6, out=columns[7, :3].reshape(3, -1))
    columns[7, 3] = columns[6, 3] + (end[:3, 3] @ rotation6).reshape(3, -1)
    return columns


def _chain(robot):
    """The standard DH table of ``robot`` (`Robot.as_standard`) and its links' fixed rotations, transposed (6, 3, 3)."""
    chain = _CHAINS.get(robot)
    if chain is None:
        std = robot.as_standard()
        chain = _CHAINS[robot] = std, np.array([_twist(std.alpha[i], std.beta[i]).T for i in range(6)])
    return chain


def _twist(alpha, beta):
    """The fixed rotation ``Rx(alpha) Ry(beta)`` (3, 3) of a DH link."""
    ca, sa, cb, sb = np.cos(alpha), np.sin(alpha), np.cos(beta), np.sin(beta)
    return np.array([[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]]) @ np.array(
        [[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]]
    )


def _cos_sin(angle):
    """cos and sin of angles (any shape), to 1 ulp, from the half-angle tangent.

    numpy vectorizes float64 ``tan`` with SIMD but not ``sin`` and ``cos``:
    one tan and a few products are about seven times faster than the pair,
    and this is the largest cost of forward kinematics.
    """
    t = np.tan(0.5 * angle)
    t2 = t * t
    w = 1.0 / (1.0 + t2)
    return (1.0 - t2) * w, 2.0 * t * w


def _poses(columns):
    """Homogeneous poses (N, 4, 4) of frame columns (4, 3, N)."""
    poses = np.zeros((columns.shape[-1], 4, 4))
    poses[:, :3, :] = columns.transpose(2, 1, 0)
    poses[:, 3, 3] = 1.0
    return poses


def shoulder_and_reach(robot, samples=4096):
    """Origin of the joint-2 axis (3,) mm and the farthest TCP distance from it, mm.

    The reach is the maximum over ``samples`` seeded random configurations
    within the joint limits (each joint's range clipped to one turn).
    """
    rng = np.random.default_rng(0)
    q = rng.uniform(np.maximum(robot.q_min, -np.pi), np.minimum(robot.q_max, np.pi), (samples, 6))
    shoulder = link_frames(robot, np.zeros(6))[0, 1, :3, 3]
    return shoulder, float(np.linalg.norm(fk(robot, q)[:, :3, 3] - shoulder, axis=1).max())
