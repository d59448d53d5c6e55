"""Poses and targets as a language's numbers: x, y, z and A, B, C nearest the angles the file states."""

import numpy as np

from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc


def same_rotation(rot, old_rot):
    """Whether rotations (..., 3, 3) equal the ones the file states (...): their numbers then stay as written."""
    return np.abs(np.subtract(rot, old_rot)).max(axis=(-2, -1), initial=0.0) <= 1e-12


def turned_abc(rotation, old_abc):
    """The rows whose rotation differs from the file's, and their A, B, C nearest the file's.

    Parameters
    ----------
    rotation : ndarray, shape (N, 3, 3)
    old_abc : ndarray, shape (N, 3)
        A, B, C the file states, deg (R = Rz(A) Ry(B) Rx(C)).

    Returns
    -------
    turned : ndarray of bool, shape (N,)
    abc : ndarray, shape (T, 3)
        A, B, C of the T turned rows, deg, each shifted by whole turns nearest the old one.
    """
    turned = ~same_rotation(rotation, abc_to_matrix(np.radians(old_abc)))
    return turned, near_angle(np.degrees(matrix_to_abc(rotation[turned])), old_abc[turned])


def encode_xyzabc(poses, olds, roles):
    """Numbers of poses (N, 4, 4) as x, y, z (mm) and A, B, C (deg, R = Rz(A) Ry(B) Rx(C)): a dict each.

    ``roles`` names the six numbers in that order (FANUC: x, y, z, r, p, w).
    The angles are chosen nearest the file's ``olds`` (N dicts), and left
    out where the rotation is the one the file states.
    """
    old_abc = np.array([[old[role] for role in roles[3:]] for old in olds], dtype=float).reshape(-1, 3)
    turned, abc = turned_abc(poses[:, :3, :3], old_abc)
    angles = iter(abc.tolist())
    return [dict(zip(roles[:3], position)) | (dict(zip(roles[3:], next(angles))) if turn else {})
            for position, turn in zip(poses[:, :3, 3].tolist(), turned.tolist())]


def encode_targets(targets, olds, joints, cartesian):
    """The numbers of targets in a language (`target_edits`), the Cartesian ones computed together.

    Parameters
    ----------
    targets : list of Target
    olds : list of dict
        Each target's numbers in the file, ``{role: float or str}``.
    joints : callable
        ``joints(target) -> {role: value}`` of a joint target.
    cartesian : callable
        ``cartesian(targets, olds) -> list of {role: value}`` of the
        Cartesian targets (vectorized over them).
    """
    out = [joints(target) if target.is_joint else None for target in targets]
    rows = [k for k, numbers in enumerate(out) if numbers is None]
    for k, numbers in zip(rows, cartesian([targets[k] for k in rows], [olds[k] for k in rows]) if rows else ()):
        out[k] = numbers
    return out


def near_angle(angle, reference, period=360.0):
    """``angle`` (scalar or array) shifted by whole periods to be closest to ``reference``."""
    return angle - period * np.round((np.asarray(angle) - reference) / period)
