"""Pose and rotation conversions, vectorized over stacks of N poses.

Inside trajcomp a pose is a homogeneous matrix (N, 4, 4) with millimetres, or
a pose vector (N, 6) ``x, y, z, a, b, c`` in millimetres and radians, where
A, B, C are KUKA-style intrinsic Z-Y'-X'' angles: R = Rz(A) Ry(B) Rx(C).
Frames follow the ``T_a_b`` reading: pose of frame b expressed in frame a.
"""

import numpy as np

_GIMBAL = 1e-12  # cos B below which A and C are coupled (B = +-90 deg)


def _rotation():
    """scipy's Rotation, imported on first use: A, B, C poses never need scipy (0.3 s of a command's start-up)."""
    from scipy.spatial.transform import Rotation

    return Rotation


def _stack(x, width):
    """Return ``x`` as a float array (N, width) and whether it was a single row."""
    arr = np.asarray(x, dtype=float)
    single = arr.ndim == 1
    arr = np.atleast_2d(arr)
    if arr.shape[-1] != width:
        raise ValueError(f"expected rows of {width} values, got shape {arr.shape}")
    return arr, single


def abc_to_matrix(abc):
    """Rotation matrices from A, B, C angles.

    Parameters
    ----------
    abc : array_like, shape (N, 3) or (3,)
        Intrinsic Z-Y'-X'' angles, rad.

    Returns
    -------
    ndarray, shape (N, 3, 3) or (3, 3)
        ``Rz(A) Ry(B) Rx(C)``, written out (no per-call scipy object: the
        program readers and writers convert one pose at a time).
    """
    arr, single = _stack(abc, 3)
    (ca, cb, cc), (sa, sb, sc) = np.cos(arr).T, np.sin(arr).T
    mat = np.empty((len(arr), 3, 3))
    mat[:, 0, 0], mat[:, 0, 1], mat[:, 0, 2] = ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc
    mat[:, 1, 0], mat[:, 1, 1], mat[:, 1, 2] = sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc
    mat[:, 2, 0], mat[:, 2, 1], mat[:, 2, 2] = -sb, cb * sc, cb * cc
    return mat[0] if single else mat


def matrix_to_abc(rot):
    """A, B, C angles (rad), shape (N, 3) or (3,), of rotation matrices (N, 3, 3).

    B is in [-90, 90] deg. At B = +-90 deg (KUKA's tool pointing down) only
    A - C or A + C is defined: C is then 0, as scipy's convention.
    """
    rot = np.asarray(rot, dtype=float)
    r = rot.reshape(-1, 3, 3)
    cos_b = np.hypot(r[:, 0, 0], r[:, 1, 0])
    locked = cos_b < _GIMBAL
    angles = np.empty((len(r), 3))
    angles[:, 1] = np.arctan2(-r[:, 2, 0], cos_b)
    angles[:, 0] = np.where(locked, np.arctan2(-r[:, 0, 1], r[:, 1, 1]), np.arctan2(r[:, 1, 0], r[:, 0, 0]))
    angles[:, 2] = np.where(locked, 0.0, np.arctan2(r[:, 2, 1], r[:, 2, 2]))
    angles += 0.0  # -0.0 (atan2 of a signed zero) is written "-0.000" by every format
    return angles[0] if rot.ndim == 2 else angles


def pose_to_matrix(pose):
    """Homogeneous matrices from pose vectors.

    Parameters
    ----------
    pose : array_like, shape (N, 6) or (6,)
        ``x, y, z`` in mm and ``a, b, c`` in rad.

    Returns
    -------
    ndarray, shape (N, 4, 4) or (4, 4)
    """
    arr, single = _stack(pose, 6)
    mat = np.zeros((len(arr), 4, 4))
    mat[:, :3, :3] = abc_to_matrix(arr[:, 3:])
    mat[:, :3, 3] = arr[:, :3]
    mat[:, 3, 3] = 1.0
    return mat[0] if single else mat


def matrix_to_pose(mat):
    """Pose vectors ``x, y, z, a, b, c`` (mm, rad) of matrices (N, 4, 4) or (4, 4)."""
    mat = np.asarray(mat, dtype=float)
    flat = mat.reshape(-1, 4, 4)
    pose = np.concatenate([flat[:, :3, 3], matrix_to_abc(flat[:, :3, :3])], axis=1)
    return pose[0] if mat.ndim == 2 else pose


def angles_near(angles, reference):
    """Angles (..., K), deg, each turned by whole turns to lie within 180 deg of ``reference`` (same shape):
    A, B, C of a command as the writers write them, next to the target's (C 180.077 by a target's 180, not
    -179.923)."""
    return angles + 360.0 * np.round((np.asarray(reference) - angles) / 360.0)


def quat_to_matrix(quat):
    """Rotation matrices from unit quaternions, scalar first ``[w, x, y, z]`` (N, 4)."""
    arr, single = _stack(quat, 4)
    mat = _rotation().from_quat(arr, scalar_first=True).as_matrix()
    return mat[0] if single else mat


def matrix_to_quat(rot):
    """Unit quaternions ``[w, x, y, z]`` with w >= 0 of rotation matrices (N, 3, 3)."""
    rot = np.asarray(rot, dtype=float)
    quat = _rotation().from_matrix(rot.reshape(-1, 3, 3)).as_quat(canonical=True, scalar_first=True)
    return quat[0] if rot.ndim == 2 else quat


def rotvec_to_matrix(rotvec):
    """Rotation matrices from rotation vectors (axis times angle, rad), (N, 3)."""
    arr, single = _stack(rotvec, 3)
    mat = _rotation().from_rotvec(arr).as_matrix()
    return mat[0] if single else mat


def matrix_to_rotvec(rot):
    """Rotation vectors (rad) of rotation matrices (N, 3, 3)."""
    rot = np.asarray(rot, dtype=float)
    vec = _rotation().from_matrix(rot.reshape(-1, 3, 3)).as_rotvec()
    return vec[0] if rot.ndim == 2 else vec


def invert(mat):
    """Inverse of rigid transforms (N, 4, 4) or (4, 4), without a general inverse."""
    mat = np.asarray(mat, dtype=float)
    rot = mat[..., :3, :3]
    out = np.zeros_like(mat)
    out[..., :3, :3] = np.swapaxes(rot, -1, -2)
    out[..., :3, 3] = -np.einsum("...ji,...j->...i", rot, mat[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def rotation_angle_between(rot_a, rot_b):
    """Angle (rad) of the relative rotation between matrix stacks (N, 3, 3)."""
    rel = np.einsum("...ji,...jk->...ik", rot_a, rot_b)
    cos = (np.trace(rel, axis1=-2, axis2=-1) - 1.0) / 2.0
    skew = np.stack([rel[..., 2, 1] - rel[..., 1, 2], rel[..., 0, 2] - rel[..., 2, 0], rel[..., 1, 0] - rel[..., 0, 1]], -1)
    # atan2 keeps full precision for small angles, where arccos(cos) cannot resolve below ~1e-8 rad.
    return np.arctan2(0.5 * np.linalg.norm(skew, axis=-1), cos)


def mean_rotation(rotations):
    """The rotation (3, 3) nearest, in the chordal sense, to a stack of rotations (N, 3, 3)."""
    u, _, vt = np.linalg.svd(np.sum(rotations, axis=0))
    return u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt
