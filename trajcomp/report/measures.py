"""Posture measures of joint vectors: limit distances, singularity distances, jumps, branches.

The singularity distances are those of the branch flags of
`trajcomp.arm.ik.configuration_of`: each flag flips exactly where its measure
reaches zero, so a small measure means a small correction can switch the
arm's branch or swing a joint fast.

``shoulder``  distance of the wrist point (origin of DH frame 5) from the
              plane through axis 1 perpendicular to the x axis of DH frame 1,
              mm (for the built-in arms: from axis 1, less the lateral offset).
``elbow``     how far the arm is from stretched or folded: the angle at the
              elbow between shoulder and wrist (axis 2, axis 3 and the origin
              of DH frame 4, projected on the plane normal to axis 2), from
              0 or 180 deg, whichever is nearer, deg.
``wrist``     angle between the axes of joints 4 and 6 (0 at the wrist
              singularity, q5 = 0 on the built-in arms), deg.
"""

import numpy as np

from trajcomp.arm.ik import BRANCHES, Configuration, branch_index, frames_branch_index
from trajcomp.arm.kinematics import frame_columns, in_blocks

SINGULARITIES = ("shoulder", "elbow", "wrist")


def limit_distances(robot, q):
    """Distance of each joint to its nearer position limit, rad, shape (N, 6); negative outside."""
    q = np.atleast_2d(q)
    return np.minimum(q - robot.q_min, robot.q_max - q)


def singularity_distances(robot, q):
    """Shoulder (mm), elbow (deg) and wrist (deg) distances of joint vectors q (N, 6), rad.

    Returns
    -------
    dict of str to ndarray, shape (N,)
        Keys `SINGULARITIES`, see the module docstring.
    """
    def block(q):
        distances = _singularity_distances(robot, frame_columns(robot, q))
        return tuple(distances[name] for name in SINGULARITIES)

    return dict(zip(SINGULARITIES, in_blocks(block, np.atleast_2d(q))))


def _singularity_distances(robot, columns):
    """`singularity_distances` of the DH frames' columns (7, 4, 3, N) (`trajcomp.arm.kinematics.frame_columns`)."""
    origin = columns[:, 3].transpose(2, 0, 1)  # (N, 7, 3): the frames' origins
    x1 = columns[1, 0].T
    shoulder = np.abs(np.einsum("ni,ni->n", origin[:, 5] - origin[:, 0], x1))
    normal = columns[1, 2].T

    def in_plane(v):
        return v - np.einsum("ni,ni->n", v, normal)[:, None] * normal

    to_shoulder = in_plane(origin[:, 1] - origin[:, 2])
    to_wrist = in_plane(origin[:, 4] - origin[:, 2])
    bend = np.degrees(np.arctan2(np.linalg.norm(np.cross(to_shoulder, to_wrist), axis=1),
                                 np.einsum("ni,ni->n", to_shoulder, to_wrist)))
    z = columns[:6, 2].transpose(2, 0, 1)  # DH axes (N, 6, 3); the axis of joint i is column i of the joint map
    axis4, axis6 = (np.einsum("njk,j->nk", z, robot.joint_map[:, i]) for i in (3, 5))
    wrist = np.degrees(np.arcsin(np.clip(np.linalg.norm(np.cross(axis4, axis6), axis=1), 0.0, 1.0)))
    return {"shoulder": shoulder, "elbow": np.minimum(bend, 180.0 - bend), "wrist": wrist}


def joint_jumps(q, before=None):
    """Joint change (N, 6), rad, from the previous row of q (N, 6).

    The first row's is from ``before`` (6,), the joints preceding q (a
    chunk's predecessor); zero without it.
    """
    q = np.atleast_2d(q)
    return np.diff(q, axis=0, prepend=q[:1] if before is None else np.reshape(before, (1, 6)))


BRANCH_NAMES = tuple(str(Configuration.from_index(b)) for b in range(BRANCHES))  # by branch index


def posture_measures(robot, q, q_planned):
    """Singularity distances and branches of written joints q (N, 6), and whether they left the planned posture.

    Parameters
    ----------
    robot : Robot
    q, q_planned : ndarray, shape (N, 6)
        Written and planned (declared posture) joints, rad.

    Returns
    -------
    singular : dict of str to ndarray, shape (N,)
        `singularity_distances` of q.
    branch, branch_planned : ndarray of uint8, shape (N,)
        Branch index of q and of q_planned (`BRANCH_NAMES` names it: ``front/up/positive``).
    changed : ndarray of bool, shape (N,)
        The branch differs or a joint turned by half a turn or more.
    """
    q, q_planned = np.atleast_2d(q), np.atleast_2d(q_planned)
    columns = frame_columns(robot, q)  # once for both measures
    branch = frames_branch_index(robot, columns).astype(np.uint8)
    branch_planned = branch_index(robot, q_planned).astype(np.uint8)
    turned = np.any(np.abs(q - q_planned) >= np.pi, axis=1)
    return _singularity_distances(robot, columns), branch, branch_planned, (branch != branch_planned) | turned
