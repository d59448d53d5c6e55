"""KUKA Status and Turn (KSS system software manual, "Status" and "Turn"), the configuration data of KRL points.

S bit 0 = wrist centre behind axis A1 (overhead area); bit 1 = wrist centre
in front of the line through A2 and A3, in the A1 frame (elbow up in front
of A1, elbow down overhead); bit 2 = A5 < 0 (wrist negative). T bit i is
set when axis i+1 < 0. Status and Turn only bind PTP motions: a LIN or
CIRC moves on in the posture the arm is in (`BINDING_KINDS`).
"""

import numpy as np

from trajcomp.formats.configuration import EDGE, branch_index, distinct_tuples, flags, integer_fields
from trajcomp.programs.items import JOINT

BINDING_KINDS = frozenset({JOINT})


def encode(robot, q):
    """KUKA status and turn ``(S, T)`` of joint vectors q (N, 6), rad: list of int pairs."""
    q = np.atleast_2d(q)
    behind, up, negative = flags(robot, q)
    status = behind * 1 + (up != behind) * 2 + negative * 4
    turn = (q < -1e-9) @ (1 << np.arange(6))  # a joint written as 0 is not negative
    return distinct_tuples(np.c_[status, turn])


def windows(configs):
    """Branch (M,) and joint windows (M, 6) of KUKA ``(S, T)`` rows: T bit i set means axis i+1 < 0."""
    status, turn = integer_fields(configs, 0, 2).T
    back = (status & 1) > 0
    up = ((status & 2) > 0) != back
    bits = ((turn[:, None] >> np.arange(6)) & 1) > 0
    lower = np.where(bits, -np.inf, -EDGE)
    upper = np.where(bits, -2 * EDGE, np.inf)
    return branch_index(back, up, (status & 4) > 0), lower, upper


def merge(old, new, branch_kept, joint_kept):
    """S: bits 0-2 from ``new`` if the branch changed (bits 3-7 kept); T: the bits of joints out of their window."""
    status = old[0] if branch_kept else (old[0] & ~0b111) | (new[0] & 0b111)
    moved = sum(1 << j for j, kept in enumerate(joint_kept.tolist()) if not kept)
    return (status, (old[1] & ~moved) | (new[1] & moved))


def describe(config):
    """``(6, 50)`` -> ``"S 6, T 50"``."""
    return f"S {config[0]}, T {config[1]}"
