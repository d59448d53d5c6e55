"""Measurement planning: a cubic grid of TCP targets at one or several tool orientations, solved with nominal IK.

Measured at one orientation (the paper's protocol), a grid calibrates the arm
for that orientation and TCP. At several orientations, turning the tool
about two axes, the identification locates the flange and separates
joint-angle errors, so the model serves other orientations and tools;
`orientations_needed` says from how many orientations of a plan on the
identification has all the parameters it can have.
"""

import dataclasses

import numpy as np

from trajcomp.errors import TrajcompError
from trajcomp.calibration.identify import identifiability
from trajcomp.arm.ik import Configuration, batch_seed, branch_index, ik, ik_family
from trajcomp.arm.kinematics import fk
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc


@dataclasses.dataclass(frozen=True, eq=False)
class MeasurementPlan:
    """Grid targets of a measurement run.

    Attributes
    ----------
    position : ndarray, shape (N, 3)
        TCP target positions, mm, base frame: grid nodes x fastest then y
        then z, each node at every orientation in turn.
    orientation : ndarray, shape (N, 3)
        TCP orientation A, B, C, rad, of each target.
    joints : ndarray, shape (N, 6)
        Nominal IK solution, rad (NaN rows where unreachable).
    reachable : ndarray, shape (N,) bool
    reason : ndarray, shape (N,) str
        Why a target is unreachable ('' where reachable).
    posture : ndarray, shape (N,) int
        The arm posture (`Configuration` index) of each target's grid: one
        per orientation (-1 for a robot without closed-form IK, whose
        targets are each solved nearest the grid's seed).
    """

    position: np.ndarray
    orientation: np.ndarray
    joints: np.ndarray
    reachable: np.ndarray
    reason: np.ndarray
    posture: np.ndarray = None


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
    if not (np.isfinite(step) and step > 0 and np.all(np.isfinite(side)) and np.all(side >= 0)
            and np.all(np.isfinite(corner))):
        raise TrajcompError(f"grid: step must be finite and positive, corner and sides finite, sides non-negative; "
                            f"got corner {corner.tolist()}, side {side.tolist()}, step {step}")
    counts = side / step
    if np.any(np.abs(counts - np.round(counts)) > 1e-6):
        raise TrajcompError(f"grid: side {side.tolist()} mm is not a whole number of {step} mm steps")
    axes = [corner[i] + step * np.arange(int(round(counts[i])) + 1) for i in range(3)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    return np.column_stack([x.ravel(), y.ravel(), z.ravel()])


def default_orientation(robot):
    """TCP orientation A, B, C (rad) of the robot's home configuration."""
    return matrix_to_abc(fk(robot, robot.home)[:3, :3])


def plan_grid(robot, corner, side, step, orientation=None, one_posture=True):
    """Plan a cubic measurement grid and solve every target with nominal IK.

    The targets of each orientation are solved in one arm posture (branch),
    that of its `batch_seed`: a grid measured across postures mixes errors
    of different sign in its interpolation. Targets that posture cannot
    reach are unreachable, with the posture that would reach them as the
    reason, never solved silently in another.

    Parameters
    ----------
    robot : Robot
    corner, side, step
        See `grid_points` (mm).
    orientation : array_like, shape (3,) or (K, 3), optional
        A, B, C in rad, one orientation or several; default: the home
        configuration's TCP orientation.
    one_posture : bool
        False: each target on the branch nearest the seed, postures mixed
        where the seed's does not reach (the demo's paper cube on the UR10).
    """
    nodes = grid_points(corner, side, step)
    orientations = np.atleast_2d(default_orientation(robot) if orientation is None else orientation).astype(float)
    solved, postures = [], []
    closed_form = ik_family(robot) is not None
    for abc in orientations:
        targets = np.tile(np.eye(4), (len(nodes), 1, 1))
        targets[:, :3, :3] = abc_to_matrix(abc)
        targets[:, :3, 3] = nodes
        seed = batch_seed(robot, targets)
        posture = int(branch_index(robot, seed)[0]) if closed_form else -1
        result = ik(robot, targets, seed=seed)
        if one_posture and closed_form:
            result = _in_posture(robot, targets, seed, posture, result)
        solved.append(result)
        postures.append(np.full(len(nodes), posture))

    def order(stack):
        """Per-orientation arrays (K, nodes, ...) -> node-major (nodes * K, ...)."""
        stack = np.asarray(stack)
        return np.swapaxes(stack, 0, 1).reshape(len(nodes) * len(orientations), *stack.shape[2:])

    success = order([r.success for r in solved])
    joints = np.where(success[:, None], order([r.q for r in solved]), np.nan)
    return MeasurementPlan(
        position=np.repeat(nodes, len(orientations), axis=0),
        orientation=np.tile(orientations, (len(nodes), 1)),
        joints=joints,
        reachable=success,
        reason=order([np.asarray(r.reason) for r in solved]),
        posture=order(postures),
    )


def _in_posture(robot, targets, seed, posture, nearest):
    """IKResult of targets (N, 4, 4) in branch ``posture``; where that fails, the reason names the posture
    ``nearest`` (the branch nearest the seed) reaches them in."""
    result = ik(robot, targets, seed=seed, config=posture)
    elsewhere = ~result.success & nearest.success
    if elsewhere.any():
        others = branch_index(robot, nearest.q[elsewhere])
        reason = result.reason.astype(object)
        reason[elsewhere] = [f"not in the grid's arm posture {Configuration.from_index(posture)}, only in "
                             f"{Configuration.from_index(b)}" for b in others]
        result = dataclasses.replace(result, reason=reason.astype(str))
    return result


def orientations_needed(robot, plan, *, frame="tracker", joint_terms=True):
    """How many of a plan's orientations the identification needs, from position measurements.

    Parameters
    ----------
    robot : Robot
    plan : MeasurementPlan
        Its orientations are taken in their order; unreachable targets are left out.
    frame, joint_terms
        As `trajcomp.calibration.identify.identify`.

    Returns
    -------
    counts : list of (int, int)
        ``(k, identifiable parameters)`` using the first k orientations.
    candidates : int
        Number of candidate parameters.
    """
    _, first, group = np.unique(np.round(plan.orientation, 9), axis=0, return_index=True, return_inverse=True)
    rank = np.argsort(np.argsort(first))[group.ravel()]  # orientation number in the plan's order
    counts, candidates = [], 0
    for k in range(1, len(first) + 1):
        rows = (rank < k) & plan.reachable
        ident = identifiability(robot, plan.joints[rows], frame=frame, joint_terms=joint_terms)
        candidates = len(ident.kept) + len(ident.fixed)
        counts.append((k, len(ident.kept)))
    return counts, candidates
