"""Measurement planning: a cubic grid of TCP targets, solved with nominal IK."""

import dataclasses

import numpy as np

from trajcomp.errors import TrajcompError
from trajcomp.ik import ik
from trajcomp.kinematics import fk
from trajcomp.transforms import abc_to_matrix, matrix_to_abc


@dataclasses.dataclass(frozen=True, eq=False)
class Plan:
    """Grid targets of a measurement run.

    Attributes
    ----------
    position : ndarray, shape (N, 3)
        TCP target positions, mm, base frame, x fastest then y then z.
    orientation : ndarray, shape (3,)
        TCP orientation A, B, C, rad, the same for every target.
    joints : ndarray, shape (N, 6)
        Nominal IK solution, rad (NaN rows where unreachable).
    reachable : ndarray, shape (N,) bool
    reason : ndarray, shape (N,) str
        Why a target is unreachable ('' where reachable).
    """

    position: np.ndarray
    orientation: np.ndarray
    joints: np.ndarray
    reachable: np.ndarray
    reason: np.ndarray


def grid_points(corner, side, step):
    """Vertices of an axis-aligned grid, x fastest, then y, then z.

    Parameters
    ----------
    corner : array_like, shape (3,)
        Lowest corner, mm.
    side : float or array_like, shape (3,)
        Edge length per axis, mm.
    step : float
        Grid step, mm; each side must be a whole number of steps.

    Returns
    -------
    ndarray, shape (N, 3)
    """
    corner = np.asarray(corner, dtype=float)
    side = np.broadcast_to(np.asarray(side, dtype=float), (3,))
    if step <= 0 or np.any(side < 0):
        raise TrajcompError(f"grid: step must be positive and sides non-negative, got step {step}, side {side}")
    counts = side / step
    if np.any(np.abs(counts - np.round(counts)) > 1e-6):
        raise TrajcompError(f"grid: side {side.tolist()} mm is not a whole number of {step} mm steps")
    axes = [corner[i] + step * np.arange(int(round(counts[i])) + 1) for i in range(3)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    return np.column_stack([x.ravel(), y.ravel(), z.ravel()])


def default_orientation(robot):
    """TCP orientation A, B, C (rad) of the robot's home configuration."""
    return matrix_to_abc(fk(robot, robot.home)[:3, :3])


def batch_seed(robot, targets):
    """One joint seed (6,) rad for a batch of targets (N, 4, 4).

    The solution nearest the robot's home configuration at the batch's mean
    position (first target's orientation): seeding every target from it keeps
    the batch in one arm posture and on one side of every joint's turn, where
    seeding each from home would flip joint 1 across +-180 deg and mix arm
    postures inside one workspace region.
    """
    centre = targets[:1].copy()
    centre[0, :3, 3] = targets[:, :3, 3].mean(axis=0)
    result = ik(robot, centre, seed=robot.home)
    return result.q[0] if result.success[0] else robot.home


def plan_grid(robot, corner, side, step, orientation=None):
    """Plan a cubic measurement grid and solve every target with nominal IK.

    Targets are solved on the branch nearest `batch_seed`, so that the whole
    grid is measured in one arm configuration.

    Parameters
    ----------
    robot : Robot
    corner, side, step
        See `grid_points` (mm).
    orientation : array_like, shape (3,), optional
        A, B, C in rad; default: the home configuration's TCP orientation.
    """
    position = grid_points(corner, side, step)
    orientation = default_orientation(robot) if orientation is None else np.asarray(orientation, dtype=float)
    targets = np.tile(np.eye(4), (len(position), 1, 1))
    targets[:, :3, :3] = abc_to_matrix(orientation)
    targets[:, :3, 3] = position
    result = ik(robot, targets, seed=batch_seed(robot, targets))
    joints = np.where(result.success[:, None], result.q, np.nan)
    return Plan(position, orientation, joints, result.success.copy(), np.asarray(result.reason))
