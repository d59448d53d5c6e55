"""Posture measures of joint vectors: limit distances, singularity distances, jumps, branch changes.

The singularity distances are those of the branch flags of
`trajcomp.ik.configuration_of`: each flag flips exactly where its measure
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

from trajcomp.ik import BRANCHES, Configuration, branch_index
from trajcomp.kinematics import link_frames

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
    frames = link_frames(robot, np.atleast_2d(q))
    origin = frames[..., :3, 3]
    x1 = frames[:, 1, :3, 0]
    shoulder = np.abs(np.einsum("ni,ni->n", origin[:, 5] - origin[:, 0], x1))
    normal = frames[:, 1, :3, 2]

    def in_plane(v):
        return v - np.einsum("ni,ni->n", v, normal)[:, None] * normal

    to_shoulder = in_plane(origin[:, 1] - origin[:, 2])
    to_wrist = in_plane(origin[:, 4] - origin[:, 2])
    bend = np.degrees(np.arctan2(np.linalg.norm(np.cross(to_shoulder, to_wrist), axis=1),
                                 np.einsum("ni,ni->n", to_shoulder, to_wrist)))
    axes = np.einsum("njk,ji->nik", frames[:, :6, :3, 2], robot.joint_map)
    wrist = np.degrees(np.arcsin(np.clip(np.linalg.norm(np.cross(axes[:, 3], axes[:, 5]), axis=1), 0.0, 1.0)))
    return {"shoulder": shoulder, "elbow": np.minimum(bend, 180.0 - bend), "wrist": wrist}


def joint_jumps(q):
    """Joint change (N, 6), rad, from the previous row of q (N, 6); zero for the first row."""
    q = np.atleast_2d(q)
    return np.diff(q, axis=0, prepend=q[:1])


def branch_changes(robot, q_before, q_after):
    """Where two joint stacks (N, 6), rad, differ in arm branch or turn a joint by half a turn or more.

    Returns
    -------
    changed : ndarray of bool, shape (N,)
    before, after : list of str
        The branches (``front/up/positive``) of each row.
    """
    names = np.array([str(Configuration.from_index(b)) for b in range(BRANCHES)])
    before = names[branch_index(robot, np.atleast_2d(q_before))].tolist()
    after = names[branch_index(robot, np.atleast_2d(q_after))].tolist()
    turned = np.any(np.abs(np.atleast_2d(q_after) - q_before) >= np.pi, axis=1)
    return (np.array(before) != np.array(after)) | turned, before, after
