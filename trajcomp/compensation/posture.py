"""The arm posture a program declares for each target, as nominal joint angles.

A Cartesian target is reached by up to eight arm branches and, on joints
that turn more than a revolution, by several turns. The program says which
one it means, and that is the one it must run in after compensation:

1. ``"joints"``: joints the program carries for the target (CSV ``j1..j6``,
   URScript ``qnear`` / ``Waypoint_q``): the solution nearest them, branch
   and turns.
2. ``"config"``: configuration data (KUKA S/T, ABB confdata, FANUC CONFIG):
   the branch its flags name, each joint in the window its turn data name
   (`trajcomp.formats.configuration.declared_windows`), a joint within
   `trajcomp.formats.configuration.BOUNDARY_TOLERANCE` of its window's boundary
   inside it; only where the language binds them (KUKA: PTP motions;
   a target only LIN or CIRC motions use is placed as in 3.).
3. ``"previous"``: the program says nothing: the solution nearest the
   joints of the previous position in motion order (target or joint
   target), as the controller moves on from where the arm is.
4. ``"home"``: nothing declared and nothing before it: nearest the robot's
   home configuration.

`planned_joints` solves every target with the nominal robot in its posture:
the joints the uncompensated program runs. Compensation then solves the
corrected target next to these joints and `check_posture` refuses any joint
that moved more than a bound: a branch or turn switch always turns some
joint by tens of degrees, a sub-millimetre correction by far less.
"""

import contextlib
import dataclasses
import functools

import numpy as np

from trajcomp.compensation.options import MAX_JOINT_CHANGE
from trajcomp.formats import capability
from trajcomp.formats.capabilities import ConfigurationData
from trajcomp.formats.configuration import BOUNDARY_TOLERANCE, binding, declared_windows
from trajcomp.errors import IKError
from trajcomp.programs.frames import FrameTable, tool_groups
from trajcomp.arm.ik import ik_all, turn_towards
from trajcomp.arm.kinematics import fk, shoulder_and_reach
from trajcomp.arm.robot import builtin_robot_names, load_robot
from trajcomp.arm.track import carried_by_a_track
from trajcomp.support.parallel import map_blocks

TURN = 2.0 * np.pi
_WINDOW_TOL = 1e-9  # rad, slack of the joint limits
_TURNS = np.arange(-3, 4)  # whole turns tried when placing a joint in its window
METRES_BOX = 10.0  # mm: targets all this close to the base origin are positions in metres
SMALLER_UNIT = 20.0  # of the reach: targets all this far from the shoulder are in a unit smaller than the one read
OTHER_ARM = 0.1  # of the reach: declared joints this far from their targets (median) were solved for another arm
FITS = 5.0  # mm: declared joints this close to their targets (median) fit an arm
BLOCK = 16_384  # undeclared targets whose eight branches are held at once: bounded memory at millions of targets


@dataclasses.dataclass(frozen=True, eq=False)
class PlannedJoints:
    """Nominal joints of a program's targets in their declared postures.

    Attributes
    ----------
    index : ndarray of int, shape (N,)
        Target indices into `Program.targets`, in motion order (first use).
    q : ndarray, shape (N, 6)
        Joint angles, rad.
    source : tuple of str, length N
        How each posture was chosen: ``"joints"``, ``"config"``,
        ``"previous"`` or ``"home"``.
    T_base_frame, T_flange_tool, T_base_tcp : ndarray, shape (N, 4, 4)
        Each target's user frame, tool and pose in the base frame, mm.
    """

    index: np.ndarray
    q: np.ndarray
    source: tuple
    T_base_frame: np.ndarray
    T_flange_tool: np.ndarray
    T_base_tcp: np.ndarray


def motion_order(program):
    """Target indices (used as target or via point) in the order motions first use them."""
    visits = _visits(program)
    _, first = np.unique(visits, return_index=True)
    return visits[np.sort(first)]


def planned_targets(program):
    """Indices of the Cartesian targets motions use, in motion order: the rows of `planned_joints`' `PlannedJoints`."""
    order = motion_order(program)
    return order[~program.target_table().is_joint[order]]


def _visits(program):
    """Target indices (K,) in the order motions reach them: via point, then target, of each motion."""
    motions = program.motion_table()
    visits = np.stack([motions.via, motions.target], axis=1).ravel()
    return visits[visits >= 0]


def planned_joints(program, robot, *, tools=None, frames=None, workers=1):
    """Solve the Cartesian targets with the nominal robot in the posture their program declares.

    Parameters
    ----------
    program : Program
    robot : Robot
        The nominal robot (closed-form IK family).
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        Tools (T_flange_tool) and user frames (T_world_frame), mm, the
        program uses but does not define (`trajcomp.programs.frames.FrameTable`).
    workers : int
        Processes that solve blocks of `BLOCK` targets' closed-form branches
        and chain the undeclared ones (`_chain`, `trajcomp.support.parallel.map_blocks`);
        the plan does not depend on it.

    Returns
    -------
    PlannedJoints
        The Cartesian targets motions use, in motion order.

    Raises
    ------
    IKError
        A target its declared posture cannot reach, named by label and line
        with the configuration it declares and why.
    TrajcompError
        A tool or frame used but not defined.
    """
    table = program.target_table()
    index = planned_targets(program)
    T_base_frame, T_flange_tool, T_base_tcp = FrameTable(program, robot, tools, frames).targets_in_base(index)
    n = len(index)
    _fail_in_metres(program, T_base_tcp)
    _fail_in_a_smaller_unit(program, robot, T_base_tcp)
    branches = functools.partial(_all_branches, robot, T_base_tcp, T_flange_tool)
    hint = table.joints[index]
    has_hint = np.all(np.isfinite(hint), axis=1)
    _fail_outside_limits(program, robot, index[has_hint], hint[has_hint])
    _fail_other_arm(program, robot, index[has_hint], hint[has_hint], T_flange_tool[has_hint], T_base_tcp[has_hint])
    binds = binding(program)[index]
    stated = np.array([bool(table.config[i]) for i in index.tolist()], dtype=bool)
    configured = np.flatnonzero(~has_hint & stated & binds)
    branch, lower, upper = declared_windows(capability(program, ConfigurationData),
                                            [table.config[i] for i in index[configured].tolist()])
    by_config, declared = configured[branch >= 0], branch >= 0
    q = np.full((n, 6), np.nan)
    source = np.empty(n, dtype=object)
    source[:], source[has_hint], source[by_config] = "", "joints", "config"
    rows = np.flatnonzero(has_hint)
    q[rows] = _in_blocks(lambda rows, hint: _nearest(robot, *branches(rows), hint), workers, rows, hint[rows])
    q[by_config] = _in_blocks(lambda rows, *window: _in_windows(robot, *branches(rows), *window), workers,
                              by_config, branch[declared], lower[declared], upper[declared])
    try:
        _fail_unreachable(program, robot, index, q, source)
        _chain(program, robot, index, q, branches, source, workers)
    except IKError as error:  # a robot on a track its description lacks: that is the reason to give first
        if reason := _off_the_track(program, robot, index, T_base_tcp):
            raise IKError(f"{reason}. {error}") from None
        raise
    return PlannedJoints(index, q, tuple(source), T_base_frame, T_flange_tool, T_base_tcp)


def check_posture(q_planned, q, labels, bound=MAX_JOINT_CHANGE):
    """Refuse corrected joints that left the planned posture.

    Parameters
    ----------
    q_planned, q : ndarray, shape (N, 6)
        Planned (uncompensated) and corrected joints, rad.
    labels : sequence of str, length N
        Target names with their source line.
    bound : float
        Largest change of any joint, rad.

    Raises
    ------
    IKError
        Naming each target, the joint, both values (deg) and the bound.
    """
    change = np.abs(q - q_planned)
    bad = np.flatnonzero(np.any(change > bound, axis=1))
    if bad.size:
        joint = np.argmax(change[bad], axis=1)
        shown = "; ".join(
            f"{labels[k]}: J{j + 1} {np.degrees(q_planned[k, j]):.2f} -> {np.degrees(q[k, j]):.2f} deg"
            for k, j in zip(bad[:5], joint[:5])
        )
        more = f" and {bad.size - 5} more" if bad.size > 5 else ""
        raise IKError(
            f"{bad.size} corrected targets leave the programmed posture (a joint turns more than "
            f"{np.degrees(bound):.1f} deg; near a singularity or a joint limit): {shown}{more}. "
            "Move the targets away from the singularity, or raise --max-joint-change if the motion is intended"
        )


def _in_blocks(solve, workers, rows, *arrays):
    """Joints (M, 6) of rows (M,) solved `BLOCK` rows at a time: ``solve(rows, *arrays' rows) -> (B, 6)``."""
    starts = range(0, len(rows), BLOCK)
    blocks = map_blocks(lambda k: solve(*(a[starts[k] : starts[k] + BLOCK] for a in (rows, *arrays))),
                        len(starts), workers)
    return np.concatenate([np.empty((0, 6)), *blocks])


def _all_branches(robot, T_base_tcp, T_flange_tool, rows):
    """Closed-form solutions (R, 8, 6) and validity (R, 8) of targets ``rows`` (R,), grouped by tool."""
    q_all = np.full((len(rows), 8, 6), np.nan)
    valid = np.zeros((len(rows), 8), dtype=bool)
    for tool, group in tool_groups(np.asarray(T_flange_tool[rows], dtype=float)):
        q_all[group], valid[group] = ik_all(robot.replace(T_flange_tool=tool), T_base_tcp[rows[group]])
    return q_all, valid


def _nearest(robot, q_all, valid, reference):
    """Per row the branch and turns (M, 6) nearest ``reference`` (M, 6); NaN where none is valid."""
    candidates = turn_towards(robot, q_all, reference[:, None, :])[0]
    distance = np.where(valid, np.sum((candidates - reference[:, None, :]) ** 2, axis=2), np.inf)
    best = np.argmin(distance, axis=1)
    q = candidates[np.arange(len(q_all)), best]
    q[~np.isfinite(distance[np.arange(len(q_all)), best])] = np.nan
    return q


def _in_windows(robot, q_all, valid, branch, lower, upper):
    """The declared branch (M,) with each joint turned into its window [lower, upper] (M, 6) and the limits.

    A joint within `BOUNDARY_TOLERANCE` outside its window is taken where no
    turn of it lies inside (a joint on a boundary satisfies both codes).
    """
    rows = np.arange(len(branch))
    q = q_all[rows, branch]
    candidates = q[:, :, None] + TURN * _TURNS
    low = np.maximum(lower - BOUNDARY_TOLERANCE, robot.q_min - _WINDOW_TOL)[:, :, None]
    high = np.minimum(upper + BOUNDARY_TOLERANCE, robot.q_max + _WINDOW_TOL)[:, :, None]
    inside = (candidates >= low) & (candidates <= high)
    on_boundary = (candidates < lower[:, :, None]) | (candidates > upper[:, :, None])
    anchor = np.clip(0.0, lower, upper)[:, :, None]  # half-open windows (KUKA T): the turn nearest zero
    cost = np.where(inside, np.abs(candidates - anchor) + on_boundary * 100.0 * TURN, np.inf)
    pick = np.argmin(cost, axis=2)
    chosen = np.take_along_axis(candidates, pick[:, :, None], axis=2)[:, :, 0]
    placed = np.isfinite(np.take_along_axis(cost, pick[:, :, None], axis=2)[:, :, 0]).all(axis=1)
    return np.where((valid[rows, branch] & placed)[:, None], chosen, np.nan)


def _fail_outside_limits(program, robot, index, joints):
    """IKError for targets whose declared joints (M, 6), rad, lie outside the robot's limits: no turn is guessed."""
    outside = np.flatnonzero(~robot.within_limits(joints))
    if outside.size:
        shown = "; ".join(f"{program.where(index[k])}: joints {np.round(np.degrees(joints[k]), 3).tolist()} deg"
                          for k in outside[:5])
        raise IKError(
            f"{program.name}: {outside.size} targets declare joints outside the limits of robot {robot.name} "
            f"({shown}); wrong robot, or joints in the wrong unit? The program was not changed"
        )


def _fail_other_arm(program, robot, index, joints, T_flange_tool, T_base_tcp):
    """IKError for a program whose declared joints (M, 6), rad, do not reach its own targets on ``robot``.

    A program carries the joints its generator solved for its targets on
    the arm it was written for (or a planner's joints near them, a few
    degrees off: a hint): where they put ``robot``'s TCP (with the targets'
    tools, ``T_flange_tool`` (M, 4, 4)) farther than `OTHER_ARM` of the
    arm's reach from the targets ``T_base_tcp`` (M, 4, 4) for most of them,
    and they fit the kinematics of another built-in robot within `FITS` mm,
    the program was written for that arm, which the message names (joints
    that fit no arm are a posture's hint, however far).
    """
    miss = np.median(_declared_miss(robot, joints, T_flange_tool, T_base_tcp)) if len(joints) else 0.0
    if miss <= FITS or miss <= OTHER_ARM * shoulder_and_reach(robot)[1]:  # the reach only for joints that miss
        return
    fitting = [name for name in builtin_robot_names() if name != robot.name
               and np.median(_declared_miss(load_robot(name), joints, T_flange_tool, T_base_tcp)) <= FITS]
    if not fitting:  # hints that choose a posture only, far as they may be: nothing says another arm
        return
    raise IKError(
        f"{program.name}: the joints it declares for its targets put robot {robot.name}'s TCP {miss:.1f} mm from "
        f"them (median of {len(joints)}, {program.where(index[0])} first); they fit robot {' or '.join(fitting)}: "
        "the program was written for another arm; give the robot (or a model of the robot) it runs on. The "
        "program was not changed")


def _declared_miss(robot, joints, T_flange_tool, T_base_tcp):
    """Distance (M,) mm from the targets to where declared joints (M, 6) put ``robot``'s TCP on their tools."""
    reached = fk(robot, joints, tcp=False) @ T_flange_tool
    return np.linalg.norm(reached[:, :3, 3] - T_base_tcp[:, :3, 3], axis=1)


def _fail_in_metres(program, T_base_tcp):
    """IKError for a program whose every target lies within `METRES_BOX` of the base origin: metres, not mm."""
    if len(T_base_tcp) and np.abs(T_base_tcp[:, :3, 3]).max() < METRES_BOX:
        raise IKError(
            f"{program.name}: every target lies within {METRES_BOX:g} mm of the robot base origin, inside the "
            "robot itself: are the positions in metres? trajcomp reads millimetres; the program was not changed"
        )


def _fail_in_a_smaller_unit(program, robot, T_base_tcp):
    """IKError for a program whose every target (N, 4, 4), mm, lies `SMALLER_UNIT` times ``robot``'s reach or
    farther from its shoulder: positions written in a smaller unit than the program's language reads (millimetres in
    a language of metres), where each target would otherwise be refused as out of reach. Not for a program whose
    external axes move: a track may carry the arm that far (`_off_the_track` says why it cannot reach)."""
    if not len(T_base_tcp) or program.moving_external_axes():
        return
    shoulder, reach = shoulder_and_reach(robot)
    nearest = np.linalg.norm(T_base_tcp[:, :3, 3] - shoulder, axis=1).min()
    if nearest >= SMALLER_UNIT * reach:
        raise IKError(
            f"{program.name}: every target lies {nearest / 1000.0:.4g} m or more from robot {robot.name}'s shoulder, "
            f"{nearest / reach:.0f} times its reach ({reach / 1000.0:.3g} m): are the positions in millimetres where "
            "the program's language reads metres (or in another smaller unit)? The program was not changed"
        )


def _fail_unreachable(program, robot, index, q, source):
    """IKError for declared targets without a solution in their declared posture."""
    failed = np.flatnonzero((source != "") & ~np.all(np.isfinite(q), axis=1))
    if not failed.size:
        return
    shown = "; ".join(
        f"{program.where(index[k])}: {_declaration(program.targets[index[k]], source[k])}" for k in failed[:5]
    )
    more = f" and {failed.size - 5} more" if failed.size > 5 else ""
    raise IKError(
        f"{program.name}: {failed.size} targets cannot be reached by robot {robot.name} in the posture "
        f"the program declares ({shown}{more}); the program was not changed"
    )


def _off_the_track(program, robot, index, T_base_tcp):
    """Why targets ``index`` (N,) at ``T_base_tcp`` (N, 4, 4) the arm cannot reach are unreachable when an external
    axis of the program carries the arm (`trajcomp.arm.track.carried_by_a_track`) and the robot's description has
    no track for it; "" otherwise."""
    if robot.track is not None and robot.track.index(program.track_key) is not None:
        return ""
    external = program.target_table().external
    shoulder, reach = shoulder_and_reach(robot)
    for axis in program.moving_external_axes():
        k = int(axis[1:]) - 1
        values = np.array([np.nan if external[i] is None or len(external[i]) <= k else external[i][k]
                           for i in index.tolist()], dtype=float)
        stated = np.isfinite(values)
        if carried_by_a_track(T_base_tcp[stated, :3, 3] - shoulder, values[stated], reach):
            where = ("describes no track" if robot.track is None else
                     f"has a track but names no field of {program.track_key or program.format} programs for it "
                     "(track.fields)")
            return (f"{program.name}: the program moves external axis {axis} over {np.ptp(values[stated]):.0f} mm "
                    f"and its targets move with it, out of the reach of robot {robot.name} from a fixed base: a robot "
                    f"on a track, and the robot's description {where}. Describe the track in the robot's YAML (track: "
                    "direction, limits, fields; docs/tracks.md) and give it with --robot")
    return ""


def _declaration(target, source):
    if source == "joints":
        return f"no solution near joints {np.round(np.degrees(target.joints), 2).tolist()} deg inside the limits"
    return f"configuration {target.config} unreachable or outside the joint limits"


def _runs(program, robot, index, q, source):
    """Runs of undeclared rows in motion order, each with the joints of the position before it.

    Returns a list of ``(rows, anchor)``: consecutive first visits of
    undeclared Cartesian targets (rows of ``index``), and ``anchor() ->
    (joints (6,), from_home)``: the joints the arm has before the first of
    them: a planned declared target, a joint target, home when nothing
    comes before, or a target visited again (solved at its first visit,
    which its posture keeps: the arm is there). Call it when the run is
    reached: an earlier run may solve that target.
    """
    visits = _visits(program)
    row_of = np.full(len(program.targets), -1)
    row_of[index] = np.arange(len(index))
    rows = row_of[visits]
    undeclared = np.zeros(len(rows), dtype=bool)
    undeclared[np.unique(rows, return_index=True)[1]] = True
    undeclared &= rows >= 0
    undeclared[undeclared] = np.asarray(source, dtype=object)[rows[undeclared]] == ""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], undeclared.astype(int), [0]])))
    joints = program.target_table().joints

    def anchor(before):
        if before < 0:
            return robot.home, True
        return (q[rows[before]] if rows[before] >= 0 else joints[visits[before]]), False

    return [(rows[begin:end], functools.partial(anchor, begin - 1)) for begin, end in zip(edges[0::2], edges[1::2])]


def _chain(program, robot, index, q, branches, source, workers=1):
    """Fill the undeclared rows, each nearest the joints of the position before it.

    A run of undeclared targets is chained a block of `BLOCK` rows at a time
    (`_chained`). The blocks' closed-form solutions (``branches(rows)``) are
    computed ahead by ``workers`` processes, each chaining its block on a
    guess: from the run's anchor when it is known before the plan starts
    (home, a declared target or a joint target). A block's chain depends
    on its first row's posture alone, so the guess is taken where its first
    row is the solution nearest the true predecessor; elsewhere (a joint
    that turned on by more than half a turn, another branch) the block is
    chained again here.
    """
    runs = _runs(program, robot, index, q, source)
    blocks = []  # (rows, the guess of the joints before them)
    for rows, anchor_of in runs:
        guess = np.array(anchor_of()[0])  # NaN where an earlier run solves the target before the run
        blocks += [(rows[begin : begin + BLOCK], guess) for begin in range(0, len(rows), BLOCK)]
    guessed = map_blocks(lambda k: _guessed_chain(robot, branches, *blocks[k]), len(blocks), workers)
    with contextlib.closing(guessed) as guesses:
        for rows, anchor_of in runs:
            anchor, from_home = anchor_of()
            for begin in range(0, len(rows), BLOCK):
                block = rows[begin : begin + BLOCK]
                first_branches, first_valid, chained = next(guesses)
                first = _nearest(robot, first_branches, first_valid, anchor[None])[0]
                if chained is None or not np.array_equal(chained[0], first):
                    chained = _chained(robot, *branches(block), anchor)
                reached = np.all(np.isfinite(chained), axis=1)
                if not reached.all():
                    raise IKError(
                        f"{program.name}: {program.where(index[block[np.argmin(reached)]])}: robot {robot.name} "
                        "cannot reach the target inside its joint limits; the program was not changed"
                    )
                q[block] = chained
                source[block] = "previous"
                if from_home:
                    source[block[0]] = "home"
                anchor, from_home = chained[-1], False


def _guessed_chain(robot, branches, rows, guess):
    """A block's first row's solutions (1, 8, 6), their validity (1, 8) and its chain from the joints ``guess`` (6,)
    (`_chained`; None when the guess is not known: NaN, a target an earlier run solves)."""
    q_all, valid = branches(rows)
    chained = _chained(robot, q_all, valid, guess) if np.all(np.isfinite(guess)) else None
    return q_all[:1], valid[:1], chained


def _chained(robot, q_all, valid, anchor):
    """Joints (B, 6) of a block of undeclared rows, each nearest the joints before it, the first nearest ``anchor``.

    The chain is proposed keeping the branch of the first row with the
    joints turning continuously (unwrapped); the proposal is checked row by
    row against the nearest solution (`_nearest`) to its predecessor and
    proposed again from where another branch or turn is nearer. Smooth
    paths take one proposal. ``q_all`` (B, 8, 6) and ``valid`` (B, 8) are
    the rows' closed-form solutions; rows from the first that no solution
    reaches are NaN.
    """
    q = np.full((len(q_all), 6), np.nan)
    start = 0
    while start < len(q_all):
        first = _nearest(robot, q_all[start : start + 1], valid[start : start + 1], anchor[None])[0]
        if not np.all(np.isfinite(first)):
            break
        branch = _branch_of(q_all[start], first)
        proposal = np.unwrap(np.vstack([first, q_all[start + 1 :, branch]]), axis=0)
        agree = _nearest_is_proposed(robot, q_all[start + 1 :], valid[start + 1 :], branch, proposal)
        stop = len(agree) if agree.all() else int(np.argmin(agree))
        q[start : start + 1 + stop] = proposal[: 1 + stop]
        anchor = proposal[stop]
        start += 1 + stop
    return q


def _nearest_is_proposed(robot, q_all, valid, branch, proposal):
    """Mask (M,): is row k + 1 of ``proposal`` (M + 1, 6), in ``branch``, the solution `_nearest` row k of it?

    ``q_all`` (M, 8, 6) and ``valid`` (M, 8) are the solutions of the
    proposal's rows 1 .. M. Where the proposed row is valid, well inside
    the limits and a small step, and every other branch is farther even at
    its nearest turn (a lower bound of its distance, whatever the limits),
    it is the nearest; the other rows are compared with `_nearest` itself.
    """
    reference, proposed = proposal[:-1], proposal[1:]
    step = proposed - reference
    turned = q_all - reference[:, None, :]
    turned -= TURN * np.round(turned / TURN)  # each joint at its nearest turn: |turned| <= half a turn
    floor = np.where(valid, np.einsum("mbj,mbj->mb", turned, turned), np.inf)
    floor[:, branch] = np.inf
    sure = (valid[:, branch] & robot.within_limits(proposed, tol=0.0) & (np.abs(step).max(axis=1) < 0.5 * np.pi)
            & (floor.min(axis=1) > np.einsum("mj,mj->m", step, step) + 1e-9))
    agree = sure.copy()
    doubt = np.flatnonzero(~sure)
    if doubt.size:
        best = _nearest(robot, q_all[doubt], valid[doubt], reference[doubt])
        agree[doubt] = np.all(np.abs(best - proposed[doubt]) < 1e-9, axis=1)
    return agree


def _branch_of(q_branches, q):
    """Index of the branch (of q_branches (8, 6)) that ``q`` (6,) is a turn of."""
    wrapped = np.angle(np.exp(1j * (q_branches - q)))
    return int(np.nanargmin(np.where(np.isnan(wrapped), np.inf, np.abs(wrapped)).sum(axis=1)))
