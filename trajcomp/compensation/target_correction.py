"""Compensation: the command that makes the real arm land on each target.

For targets T (TCP poses in the base frame) and a mode of the model, find
joints q such that the model's *predicted reached* pose is T, and emit the
nominal-model pose of q (what the nominal controller must receive) with q.
The reached position is ``FK_true(q) + f(c)`` where FK_true is the model's
arm (`CompensationModel.arm`: the identified robot, with joint-angle errors
for a composite fitted at several orientations, or the nominal one), f the
additive error field of the mode (zero, the linear error
model, the raw-error grid or the residual grid) and c the commanded position,
at which the field was measured. Because f depends on c, the solution is a
short fixed-point iteration; the field is smooth, so a first pass aimed
from where the command is expected lands far below the measurement noise,
and a second or third pass is seldom needed (a target stops once the model
predicts it lands within `LANDED`).
"""

import dataclasses
import functools

import numpy as np

from trajcomp.model import landing
from trajcomp.errors import ModelError, TrajcompError
from trajcomp.programs.frames import tool_groups
from trajcomp.arm.ik import IKResult, batch_seed, ik_near, ik_numeric, pose_error
from trajcomp.arm.kinematics import fk
from trajcomp.model.compensation_model import evaluate_field, same_tool
from trajcomp.report.measures import singularity_distances
from trajcomp.support.parallel import map_blocks

ITERATIONS = 3  # fixed-point passes at most
REACH_EDGE = 2.0  # deg: an elbow this close to stretched is at the edge of the arm's reach
LANDED = 1e-5  # mm: a target whose predicted landing error is below this needs no further pass
CHUNK = 8192  # targets compensated together: the working arrays stay small and memory stays flat


@dataclasses.dataclass(frozen=True, eq=False)
class CompensationResult:
    """Commands for N targets.

    Attributes
    ----------
    T_command : ndarray, shape (N, 4, 4)
        TCP pose to send to the nominal controller, base frame, mm.
    q : ndarray, shape (N, 6)
        The joint angles of that command, rad.
    correction : ndarray, shape (N, 3)
        Commanded minus target position, mm.
    outside : ndarray, shape (N,) bool
        Targets outside the grid, handled by the ``outside`` policy.
    residual : ndarray, shape (N,)
        Distance from the target to where the model predicts the arm lands
        with the command, mm: what the fixed-point iteration left (its
        convergence, not an accuracy).
    near_face : ndarray, shape (N,) bool
        Targets inside the grid whose command lies outside it (near a face,
        the correction moves the command out): the grid's nearest value is
        used there, as ``outside="clamp"`` would, not zero. All False when
        not given.
    other_tool : ndarray, shape (N,) bool
        Targets on a tool other than the measured TCP, compensated with a
        model that cannot place other tools (`CompensationModel.places_other_tools`).
        All False when not given.
    held_out, unseen : ndarray, shape (N,)
        The two parts of the landing estimate (`trajcomp.model.landing`), mm: the
        model's held-out errors near the target, and what the measurements
        could not see at its orientation, tool and posture (NaN when not
        given: no estimate).
    orientation_beyond : ndarray, shape (N,)
        Angle of the target's orientation beyond the measured ones, deg
        (0 when not given).
    unmeasured_posture : ndarray, shape (N,) bool
        Targets in an arm posture the calibration did not measure (outside
        the calibrated region, but not ``outside`` the grid). All False when
        not given.
    """

    T_command: np.ndarray
    q: np.ndarray
    correction: np.ndarray
    outside: np.ndarray
    residual: np.ndarray
    near_face: np.ndarray = None
    other_tool: np.ndarray = None
    held_out: np.ndarray = None
    unseen: np.ndarray = None
    orientation_beyond: np.ndarray = None
    unmeasured_posture: np.ndarray = None

    def __post_init__(self):
        n = len(self.residual)
        defaults = {"near_face": np.zeros(n, bool), "other_tool": np.zeros(n, bool), "held_out": np.full(n, np.nan),
                    "unseen": np.full(n, np.nan), "orientation_beyond": np.zeros(n),
                    "unmeasured_posture": np.zeros(n, bool)}
        for name, value in defaults.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, value)

    @property
    def estimate(self):
        """Landing estimate (N,), mm: held-out + unseen + the convergence residual (`trajcomp.model.landing`)."""
        return self.held_out + self.unseen + self.residual

    @classmethod
    def concatenate(cls, parts, order, n):
        """One result of ``n`` rows made of several: rows ``order[k]`` (index array or slice) come from the k-th of
        ``parts``.

        ``parts`` may be any iterable (a generator): it is consumed once, so
        parts computed one after the other are never all held at once.
        """
        fields = None
        for part, rows in zip(parts, order):
            if fields is None:
                fields = {f.name: np.empty((n, *getattr(part, f.name).shape[1:]), getattr(part, f.name).dtype)
                          for f in dataclasses.fields(cls)}
            for name, values in fields.items():
                values[rows] = getattr(part, name)
        return cls(**fields)


def compensate(model, targets, *, mode=None, tool=None, seed=None, outside="model", label="targets", names=None,
               workers=1):
    """Compensated commands for target TCP poses.

    Parameters
    ----------
    model : CompensationModel
    targets : ndarray, shape (N, 4, 4)
        Where the real TCP must go, base frame, mm.
    mode : str, optional
        One of ``model.modes``; default ``model.method``.
    tool : ndarray, shape (4, 4), optional
        TCP in the flange frame of the program's tool, taken as exact. Default:
        the measured TCP (declared tool for the command, identified tool for
        the real arm).
    seed : array_like, shape (N, 6) or (6,), optional
        Joint seed choosing the IK branch; default: `batch_seed` of the targets.
    outside : {"model", "clamp", "error"}
        Policy for targets outside the grid, or outside the joint range of a
        joint residual (see `CompensationModel.predict`), or in an arm posture
        the calibration did not measure (``error`` refuses them).
    label : str
        Names the set of targets in error messages (e.g. the program file).
    names : sequence of str, length N, optional
        Names of the targets in error messages (label and line); default
        ``target k`` (0-based).
    workers : int
        Processes that compensate chunks of `CHUNK` targets at once
        (`trajcomp.support.parallel.map_blocks`); the result does not depend on it.

    Raises
    ------
    IKError
        A target (named) cannot be reached.
    ModelError
        Unknown mode, or a target outside the grid with ``outside="error"``.
    """
    mode = mode or model.method
    model.check_mode(mode)
    targets = np.asarray(targets, dtype=float)
    nominal = model.nominal if tool is None else model.nominal.replace(T_flange_tool=tool)
    seed = batch_seed(nominal, targets) if seed is None else seed
    seed = np.broadcast_to(np.asarray(seed, dtype=float), (len(targets), 6))
    policy = "model" if outside == "error" else outside  # "error": the targets outside are refused below, all named
    arm = model.arm(mode, tool, policy)
    rows = functools.partial(_compensate_rows, model, mode, nominal, arm, model.error_field(mode, tool), policy,
                             label, tool)
    if len(targets) <= CHUNK:
        result = rows(targets, seed, names)
    else:
        starts = range(0, len(targets), CHUNK)
        chunks = map_blocks(lambda k: rows(targets[starts[k] : starts[k] + CHUNK],
                                           seed[starts[k] : starts[k] + CHUNK]), len(starts), workers)
        try:
            result = CompensationResult.concatenate(chunks, [slice(i, i + CHUNK) for i in starts], len(targets))
        except TrajcompError:
            # A chunk names its targets from 0 and counts only its own: redo the whole
            # set in one piece (each target is compensated on its own, so it fails the
            # same way) for the message naming every failing target of the set.
            result = rows(targets, seed, names)
    if outside == "error" and (result.outside | result.unmeasured_posture).any():
        _refuse_outside(model, mode, tool, arm, result, label, names)
    return result


def _refuse_outside(model, mode, tool, arm, result, label, names):
    """ModelError naming every target outside the calibrated region and why (``outside="error"``)."""
    field = model.error_field(mode, tool)
    reasons = [
        (np.zeros(len(result.q), dtype=bool) if field is None else ~field.contains(result.T_command[:, :3, 3])
         & ~result.near_face, "outside the grid"),
        (arm.outside_rows(result.q), "joints outside the joint range the model was calibrated on"),
        (result.unmeasured_posture, "in an arm posture the calibration never measured"),
    ]
    name = (lambda i: f"target {i}") if names is None else names.__getitem__
    out = np.flatnonzero(result.outside | result.unmeasured_posture)
    shown = "; ".join(f"{name(i)}: " + ", ".join(why for mask, why in reasons if mask[i]) for i in out[:10])
    more = f"; and {out.size - 10} more" if out.size > 10 else ""
    raise ModelError(f"{label}: {out.size} of {len(result.q)} targets lie outside the calibrated region "
                     f"(--outside error): {shown}{more}")


def _compensate_rows(model, mode, nominal, arm, field, outside, label, tool, targets, seed, names=None):
    """`compensate` of targets (N, 4, 4) from joint seeds (N, 6) with the mode's arm and error field.

    Each fixed-point pass solves the rows not yet landed for their goal minus
    the error term at their last commanded position; a row stops once the
    model predicts it lands within `LANDED` of its goal (or after
    `ITERATIONS` passes). The first pass takes the error term where the
    command is expected: the goal moved by the error term there and by the
    model's arm's offset from the nominal arm at the seed (a few
    micrometres from where it lands).
    """
    goal = targets[:, :3, 3]
    inside = np.zeros(len(goal), dtype=bool) if field is None else field.contains(goal)
    error_term = functools.partial(_error_term, model, mode, field, outside, inside)
    q, command, residual = np.array(seed), fk(nominal, seed), np.empty(len(targets))
    passes = ITERATIONS if mode == "linear" or field is not None else 1
    offset = np.zeros_like(goal)
    if passes > 1:  # the error term about where the command lands: most rows then land in one pass
        expected = goal - error_term(goal, q)[0] + command[:, :3, 3] - arm.fk(q)[:, :3, 3]
        offset = error_term(expected, q)[0]
    todo = np.arange(len(targets))
    for k in range(passes):
        aimed = targets[todo]
        aimed[:, :3, 3] = goal[todo] - offset[todo]
        solved = _solve(arm.robot, nominal, aimed, q[todo], command[todo])
        if not solved.success.all():
            _of_all(solved, todo, len(targets)).raise_on_failure(label, names,
                                                                 _at_the_reach(nominal, q[todo][~solved.success]))
        q[todo] = arm.commanded_joints(solved.q)
        command[todo] = fk(nominal, q[todo])
        offset, flagged = error_term(command[:, :3, 3], q)
        residual[todo] = np.linalg.norm(arm.fk(q[todo])[:, :3, 3] + offset[todo] - goal[todo], axis=1)
        todo = todo[residual[todo] >= LANDED]
        if not todo.size:
            break
    posture = model.unmeasured_posture(q)
    other_tool = tool is not None and not same_tool(tool, model.nominal.T_flange_tool) and not model.places_other_tools
    outside_rows = flagged | arm.outside_rows(q)
    estimate = landing.estimate(model, mode, q, targets, tool, posture, other_tool, outside_rows)
    return CompensationResult(command, q, command[:, :3, 3] - goal, outside_rows, residual,
                              near_face=inside & ~field.contains(command[:, :3, 3]) if field is not None else None,
                              other_tool=np.full(len(q), other_tool), held_out=estimate.held_out,
                              unseen=estimate.unseen, orientation_beyond=estimate.orientation,
                              unmeasured_posture=posture)


def _error_term(model, mode, field, outside, inside, commanded, joints):
    """The mode's additive error (N, 3), mm, at commanded positions (N, 3) and joints (N, 6) rad, and the rows
    outside its grid (N,).

    Rows whose target is ``inside`` (N,) the grid take the grid's nearest
    value where their command leaves it (near a face): their error is the
    grid's there, not zero, and they are not outside.
    """
    if field is None:
        flagged = np.zeros(len(commanded), dtype=bool)
        return (model.linear.predict_error(commanded) if mode == "linear" else np.zeros_like(commanded)), flagged
    values, flagged = evaluate_field(field, commanded, outside=outside, joints=joints)
    near_face = inside & flagged
    if near_face.any():
        values[near_face] = evaluate_field(field, commanded[near_face], outside="clamp", joints=joints[near_face])[0]
    return values, flagged & ~inside


def _at_the_reach(robot, seeds):
    """Why targets that found no command (their joints before the correction, seeds (M, 6) rad) fail, where it is
    the reach: the elbow within `REACH_EDGE` deg of stretched, so a correction outward asks more reach of the arm
    than it has in the target's orientation (an empty text otherwise)."""
    elbow = singularity_distances(robot, seeds)["elbow"]
    if not (elbow < REACH_EDGE).any():
        return ""
    return (f"; {int((elbow < REACH_EDGE).sum())} of them at the edge of the arm's reach (the elbow "
            f"{elbow.min():.2f} deg from stretched): the correction needs more reach than the arm has in the "
            "target's orientation")


def _of_all(solved, rows, n):
    """An IKResult of rows (M,) of n targets as one of all n (the others solved), for its failure message."""
    if len(rows) == n:
        return solved
    every = IKResult(np.zeros((n, 6)), np.ones(n, dtype=bool), np.zeros(n), np.zeros(n),
                     np.full(n, "", dtype=solved.reason.dtype))
    return every.with_rows(rows, solved)


SEED_NEAR = (10.0, 0.05)  # mm, rad: a seed this close to its target starts Gauss-Newton directly


def _solve(real, nominal, targets, seed, seed_pose):
    """IK of the real arm for targets (N, 4, 4), seeded by joints (N, 6) whose nominal TCP is ``seed_pose`` (N, 4, 4).

    Rows whose seed puts the nominal TCP within `SEED_NEAR` of the target
    (planned joints, the previous pass) are refined by Gauss-Newton from
    it, which stays on the seed's branch and turns; the others get the
    nominal closed form's branch nearest the seed first (`ik_near`).
    """
    error = pose_error(seed_pose, targets)
    near = (np.linalg.norm(error[:, :3], axis=1) < SEED_NEAR[0]) & (np.linalg.norm(error[:, 3:], axis=1) < SEED_NEAR[1])
    solved = ik_numeric(real, targets, np.where(near[:, None], seed, np.nan))
    far = np.flatnonzero(~solved.success)
    if far.size:
        solved = solved.with_rows(far, ik_near(real, nominal, targets[far], seed=seed[far]))
    return solved


def program_corrector(model, *, mode=None, outside="model", label="program", workers=1):
    """The ``correct`` callable of `trajcomp.compensation.program_rewrite.compensate_program` for a model.

    ``correct(targets (N, 4, 4), tools (N, 4, 4), seeds (N, 6), names) ->
    CompensationResult``. Targets are grouped by tool (a program uses few)
    and each group is compensated in one vectorized call. Targets on the
    robot's declared tool are the TCP that was measured: they get the
    identified tool for the real arm (``tool=None`` of `compensate`); the
    others are marked ``other_tool`` when the model cannot place other tools.
    ``workers`` processes share the chunks of each group (`compensate`).
    """

    def correct(targets, tools, seeds, names):
        groups = tool_groups(tools)
        if len(groups) == 1:  # the usual program: one tool, no per-row copies or names
            return on_tool(groups[0][0], targets, seeds, names)
        return CompensationResult.concatenate(
            (on_tool(tool, targets[rows], seeds[rows], [names[k] for k in rows]) for tool, rows in groups),
            [rows for _, rows in groups], len(targets),
        )

    def on_tool(tool, targets, seeds, names):
        measured_tcp = same_tool(tool, model.nominal.T_flange_tool)
        return compensate(model, targets, mode=mode, tool=None if measured_tcp else tool, seed=seeds,
                          outside=outside, label=label, names=names, workers=workers)

    return correct
