"""ABB confdata (RAPID reference, confdata), the configuration data of RAPID robtargets.

cf1, cf4, cf6 = quadrant ``floor(q / 90 deg)`` of joints 1, 4, 6; cfx of
spherical-wrist arms = 4 * (wrist centre behind axis 1) + 2 * (wrist centre
behind the lower arm) + (axis 5 negative), "behind the lower arm" being the
complement of KUKA's Status bit 1.
"""

import numpy as np

from trajcomp.formats.configuration import EDGE, branch_index, distinct_tuples, flags, integer_fields, joint_windows


def encode(robot, q):
    """ABB confdata ``(cf1, cf4, cf6, cfx)`` of joint vectors q (N, 6), rad: list of int tuples."""
    q = np.atleast_2d(q)
    behind, up, negative = flags(robot, q)
    quadrant = np.floor(q[:, [0, 3, 5]] / (np.pi / 2) + 1e-9).astype(int)
    cfx = behind * 4 + (up == behind) * 2 + negative * 1
    return distinct_tuples(np.c_[quadrant, cfx])


def windows(configs):
    """Branch and joint windows of ABB confdata rows: joints 1, 4, 6 in quadrants [cf, cf + 1) * 90 deg."""
    values = integer_fields(configs, 0, 4)
    cfx = values[:, 3]
    back = (cfx & 4) > 0
    up = ((cfx & 2) > 0) == back
    lower, upper = joint_windows(values[:, :3], [0, 3, 5], lambda c: c * np.pi / 2 - EDGE,
                                 lambda c: (c + 1) * np.pi / 2 - 2 * EDGE)
    return branch_index(back, up, (cfx & 1) > 0), lower, upper


def merge(old, new, branch_kept, joint_kept):
    """cf1, cf4, cf6 from ``new`` where the joint left its quadrant; cfx if the branch changed."""
    quadrants = tuple(o if kept else n for o, n, kept in zip(old[:3], new[:3], joint_kept[[0, 3, 5]]))
    return (*quadrants, old[3] if branch_kept else new[3], *old[4:])


def describe(config):
    """``(0, -1, 0, 1)`` -> ``"[0,-1,0,1]"``."""
    return "[" + ",".join(str(v) for v in config) + "]"
