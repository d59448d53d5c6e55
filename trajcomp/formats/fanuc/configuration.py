"""FANUC CONFIG ``'F/N U/D T/B, t1, t4, t6'``, the configuration data of LS positions.

"F" (flip) when the wrist is positive, J5 > 0 (a tool pointing down with
J4 = 0 is J5 = -90 deg, the common 'N U T'), "U" elbow up, "B" wrist centre
behind J1; turn numbers ``floor((q + 180 deg) / 360 deg)`` of joints 1, 4
and 6.
"""

import numpy as np

from trajcomp.formats.configuration import EDGE, branch_index, distinct_tuples, flags, integer_fields, joint_windows


def encode(robot, q):
    """FANUC CONFIG ``(flip, elbow, front, t1, t4, t6)`` of joint vectors q (N, 6), rad.

    ``flip`` is ``"F"`` (J5 > 0) or ``"N"``, ``elbow`` ``"U"`` or ``"D"``, ``front``
    ``"T"`` or ``"B"``; t1, t4, t6 are turn numbers (int).
    """
    q = np.atleast_2d(q)
    behind, up, negative = flags(robot, q)
    turns = np.floor((q[:, [0, 3, 5]] + np.pi) / (2 * np.pi) - 1e-12).astype(int)
    return distinct_tuples(np.c_[negative, up, behind, turns], lambda row: (
        "N" if row[0] else "F", "U" if row[1] else "D", "B" if row[2] else "T", *row[3:]))


def windows(configs):
    """Branch and joint windows of FANUC CONFIG rows: joints 1, 4, 6 in turn t, ((2t - 1) pi, (2t + 1) pi]."""
    letters = np.array([config[:3] for config in configs], dtype=object).reshape(-1, 3)
    turns = integer_fields(configs, 3, 6)
    lower, upper = joint_windows(turns, [0, 3, 5], lambda t: (2 * t - 1) * np.pi + EDGE,
                                 lambda t: (2 * t + 1) * np.pi)
    branch = branch_index(letters[:, 2] == "B", letters[:, 1] == "U", letters[:, 0] == "N")
    return branch, lower, upper


def merge(old, new, branch_kept, joint_kept):
    """Flip, elbow, front from ``new`` if the branch changed; each turn digit of a joint out of its turn."""
    letters = old[:3] if branch_kept else new[:3]
    kept = joint_kept.tolist()
    turns = tuple(o if k else n for o, n, k in zip(old[3:6], new[3:6], (kept[0], kept[3], kept[5])))
    return (*letters, *turns, *old[6:])


def describe(config):
    """``("N", "U", "T", 0, 0, 0)`` -> ``"N U T, 0, 0, 0"``."""
    return f"{' '.join(config[:3])}, {', '.join(str(t) for t in config[3:])}"
