"""Whether measurements locate the flange, and orientation sets for planning.

Position measurements of one point locate the flange only when

- the tool was turned about two independent axes: ``p = flange + R t``
  tells the point's offset ``t`` from the flange position only through the
  change of ``R`` (`orientation_spread`: RMS rotation about the principal
  axes of a set of orientations), and
- the point lies off the last joint's axis, or orientations are measured
  too: a point on that axis does not move when the axis tilts, so its
  direction, and with it every other tool's lever, stays unseen
  (`axis_offset`).
"""

import numpy as np

from trajcomp.arm.kinematics import fk, link_frames
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc, matrix_to_rotvec, mean_rotation, rotvec_to_matrix

MIN_SPREAD = 5.0  # deg RMS about each of two axes: below it the flange is not located
MIN_AXIS_OFFSET = 20.0  # mm from the last axis a measured point needs for position data to see the axis direction


def orientation_spread(rotations):
    """RMS rotation (3,) deg about the principal axes of a set of orientations, largest first.

    Parameters
    ----------
    rotations : ndarray, shape (N, 3, 3)
    """
    rotations = np.asarray(rotations, dtype=float).reshape(-1, 3, 3)
    centre = mean_rotation(rotations)
    spread = matrix_to_rotvec(rotations @ centre.T)
    values = np.linalg.svd(spread, compute_uv=False) / np.sqrt(len(spread))
    return np.degrees(np.pad(values, (0, 3 - len(values))))


def locates_flange(spread):
    """True when a spread (3,) deg turns the tool about two axes by at least `MIN_SPREAD`."""
    return bool(spread[1] >= MIN_SPREAD)


def axis_offset(robot):
    """Distance (mm) of the robot's TCP from the axis of its last joint."""
    frame = link_frames(robot, robot.home)[0, 5]
    axis, origin = frame[:3, 2], frame[:3, 3]
    lever = fk(robot, robot.home)[:3, 3] - origin
    return float(np.linalg.norm(lever - axis * (lever @ axis)))


def spread_orientations(orientation, count, tilt):
    """``count`` orientations around one: itself, then the tool tilted about axes of its x-y plane.

    The first is ``orientation``. The ``n = count - 1`` others tilt the tool
    by ``+tilt`` about ``m = max(ceil(n / 2), 2)`` axes evenly turned over
    half a turn (x, y for m = 2), then by ``-tilt`` about the same axes, in
    that order: two give +x, +y; four +-x, +-y.

    Parameters
    ----------
    orientation : array_like, shape (3,)
        A, B, C, rad.
    count : int
        Number of orientations, at least 1.
    tilt : float
        Tilt angle, rad.

    Returns
    -------
    ndarray, shape (count, 3)
        A, B, C, rad.
    """
    orientation = np.asarray(orientation, dtype=float)
    base = abc_to_matrix(orientation)
    others = count - 1
    axes = max(-(-others // 2), 2)
    tilts = [sign * tilt for sign in (1.0, -1.0) for _ in range(axes)]
    angles = [np.pi * i / axes for _ in range(2) for i in range(axes)]
    out = [orientation]
    for angle, signed in zip(angles[:others], tilts[:others]):
        axis = np.array([np.cos(angle), np.sin(angle), 0.0])
        out.append(matrix_to_abc(base @ rotvec_to_matrix(signed * axis)))
    return np.array(out)
