"""Apply corrected poses to robot programs, and convert programs between languages.

`compensate_program` solves every target a program's motions use in the
posture the program declares (`trajcomp.compensation.posture`), asks a ``correct``
callable (the compensation core) once for all of them, seeded there,
refuses corrections that are implausible or leave the posture, brings the
commands back to each target's own frame (`trajcomp.programs.frames`) and writes
them into the program with configuration data recomputed from the
corrected joints. `convert_program` re-expresses a program in another
language.
"""

import dataclasses

import numpy as np

from trajcomp.formats import capability, find_format, track_key
from trajcomp.formats.capabilities import BaseFrameOnly, ConfigurationData, OrientationSpeed, SpeedUnits
from trajcomp.formats.speeds import MotionGeometry, convert_speeds
from trajcomp.formats.configuration import BOUNDARY_TOLERANCE, binding, configuration_for, describe, written_configuration
from trajcomp.errors import CompensationError, TimingError
from trajcomp.arm.ik import pose_error
from trajcomp.arm.kinematics import fk
from trajcomp.programs.frames import FrameTable, in_frames
from trajcomp.compensation.options import MAX_CORRECTION, MAX_JOINT_CHANGE
from trajcomp.compensation.posture import check_posture, planned_joints
from trajcomp.model.landing import QUANTILE, chi2_quantile
from trajcomp.programs.program import Program, place_text
from trajcomp.programs.items import replaced



@dataclasses.dataclass(frozen=True, eq=False)
class ProgramReport:
    """What a compensation did to a program: one row per compensated target, in motion order.

    Attributes
    ----------
    labels : tuple of str, length N
        Target names with file and line (``P1 (weld.dat:12)``).
    lines : ndarray of int, shape (N,)
        Source line of each target's numbers.
    tools, frames : tuple of (str or None), length N
        Tool and user frame names (None: the robot's tool / the base).
    T_target, T_command : ndarray, shape (N, 4, 4)
        Where the TCP must land and the pose sent to the controller, base frame, mm.
    correction : ndarray, shape (N, 6)
        Command minus target: position (mm) and rotation vector (deg).
    q, q_planned : ndarray, shape (N, 6)
        Written (corrected) joints, and the nominal joints of the original
        target in its declared posture, rad.
    declared, written : tuple of str, length N
        Configuration data as the language writes them (``""`` where none).
    posture_source : tuple of str, length N
        ``"joints"``, ``"config"``, ``"previous"`` or ``"home"`` (`trajcomp.compensation.posture`).
    outside_grid : ndarray of bool, shape (N,)
        Targets outside the measured grid or the joint range of a joint residual.
    predicted_residual : ndarray, shape (N,)
        Distance from the target to the model-predicted landing, mm: the
        compensation's convergence (the model agreeing with itself).
    not_compensated : tuple of (int or str, str, str)
        Line, text and reason of motions passed through unchanged (each
        once), then of statements that pass a point where trajcomp cannot
        see the motion (a procedure call); the line is ``"file:line"`` in a
        program joined from several files (`Program.place`).
    motions_left : int
        How many of ``not_compensated`` are motions.
    unused : tuple of str
        Targets no motion uses: left as written.
    joint_targets : tuple of str
        Joint targets, kept as written or compensated (``joint_mode``).
    joint_mode : str
        ``"keep"`` or ``"compensate"``.
    warnings : tuple of str
        What the run could do but the user must know.
    landing : dict of str to ndarray, shape (N,), or None
        The landing estimate (None: no model): ``estimate_mm`` (what the
        verdict judges), its parts ``held_out_mm`` and ``unseen_mm``,
        ``orientation_beyond_deg``, ``unmeasured_posture`` and ``other_tool``
        (`trajcomp.compensation.target_correction.CompensationResult`).
    """

    labels: tuple
    lines: np.ndarray
    tools: tuple
    frames: tuple
    T_target: np.ndarray
    T_command: np.ndarray
    correction: np.ndarray
    q: np.ndarray
    q_planned: np.ndarray
    declared: tuple
    written: tuple
    posture_source: tuple
    outside_grid: np.ndarray
    predicted_residual: np.ndarray
    not_compensated: tuple = ()
    motions_left: int = 0
    unused: tuple = ()
    joint_targets: tuple = ()
    joint_mode: str = "keep"
    warnings: tuple = ()
    landing: dict = None

    def lines_of_text(self):
        """Human-readable summary lines."""
        out = [f"compensated targets: {len(self.labels)}"]
        verb = "compensated" if self.joint_mode == "compensate" else "kept as written"
        if self.joint_targets:
            out.append(f"joint targets {verb}: {', '.join(self.joint_targets)}")
        if self.not_compensated:
            out.append(f"{self.motions_left} motions and {len(self.not_compensated) - self.motions_left} "
                       "points passed to routines NOT compensated:")
            out += [f"  {place_text(place)}: {text} ({reason})" for place, text, reason in self.not_compensated]
        if self.unused:
            out.append(f"unused points left as written: {', '.join(self.unused)}")
        out += [f"warning: {w}" for w in self.warnings]
        return out


def compensate_program(program, correct, robot, *, tools=None, frames=None, joint_targets="keep",
                       max_joint_change=MAX_JOINT_CHANGE, max_correction=MAX_CORRECTION, workers=1):
    """A program whose targets are replaced by their compensated commands, in their declared postures.

    Every target is first solved with the nominal robot in the posture the
    program declares (`trajcomp.compensation.posture.planned_joints`); the compensation
    is seeded there and must stay there.

    Parameters
    ----------
    program : Program
    correct : callable
        ``correct(T_base_tcp (N, 4, 4), T_flange_tool (N, 4, 4), q_seed (N, 6),
        names (N,)) -> CompensationResult``: the nominal-model TCP pose that
        makes the real arm land on each target and its joints (rad), solved
        next to the seed joints. Called once, for all targets (see
        `trajcomp.compensation.target_correction.program_corrector`).
    robot : Robot
        The nominal robot (posture, configuration data, joint-target poses,
        base placement and default tool).
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        Values of tools (T_flange_tool) and user frames (T_world_frame), mm,
        that the program uses but does not define.
    joint_targets : {"keep", "compensate"}
        ``"compensate"`` treats each joint target as the nominal pose FK(q)
        stands for and replaces it with the corrected joints (the jobs check the value: `trajcomp.jobs.options`).
    max_joint_change : float
        Largest change of any joint a correction may cause, rad.
    max_correction : float
        Largest plausible position correction, mm.
    workers : int
        Processes that share the posture planning (`planned_joints`); give
        ``correct`` as many (`trajcomp.compensation.target_correction.program_corrector`).

    Returns
    -------
    (Program, ProgramReport)

    Raises
    ------
    TrajcompError
        A tool or frame used but not defined, or a target used with two
        different tools or frames.
    IKError
        A target its declared posture cannot reach, before or after
        correction, or a correction that leaves the posture.
    CompensationError
        A correction larger than ``max_correction``.
    """
    program = placed_on_track(program, robot, tools, frames)
    table = FrameTable(program, robot, tools, frames)
    plan = planned_joints(program, robot, tools=tools, frames=frames, workers=workers)
    cartesian, T_base_frame, T_tool, T_target = plan.index, plan.T_base_frame, plan.T_flange_tool, plan.T_base_tcp
    rows, q_planned, source = cartesian, plan.q, plan.source
    joint_index, q_joint = program.joint_targets()
    if joint_targets == "compensate" and len(joint_index):
        joint_tools = table.targets_in_base(joint_index)[1]
        T_target = np.concatenate([T_target, fk(robot, q_joint, tcp=False) @ joint_tools])
        T_tool = np.concatenate([T_tool, joint_tools])
        rows = np.concatenate([cartesian, joint_index])
        q_planned = np.concatenate([q_planned, q_joint])
        source = source + ("joints",) * len(joint_index)
    labels = program.labels(rows)
    result = correct(T_target, T_tool, q_planned, labels) if len(rows) else None
    edited, q, T_command = program, np.empty((0, 6)), np.empty((0, 4, 4))
    if result is not None:
        _check_correction(result.correction, labels, max_correction)
        check_posture(q_planned, result.q, labels, max_joint_change)
        q, T_command, n = result.q, result.T_command, len(cartesian)
        written = table.written_commands(cartesian, T_command[:n])  # on a track: for the controller's carriage
        edited = edited.with_targets(cartesian, poses=in_frames(T_base_frame, written), joints=q[:n],
                                     configs=_configs(program, robot, cartesian, q[:n]))
        if n < len(rows):
            edited = edited.with_targets(joint_index, joints=q[n:])
    report = ProgramReport(
        labels=labels,
        **_target_facts(program, rows),
        T_target=T_target,
        T_command=T_command,
        correction=_correction(T_target, T_command),
        q=q,
        q_planned=q_planned,
        declared=_described(program, rows),
        written=_described(edited, rows),
        posture_source=tuple(source),
        outside_grid=np.zeros(len(rows), dtype=bool) if result is None else result.outside,
        predicted_residual=np.zeros(len(rows)) if result is None else result.residual,
        not_compensated=_not_compensated(program, cartesian),
        motions_left=sum(not m.axis_position for m in program.runtime_motions()),
        **_program_facts(program, robot, joint_index, joint_targets),
        landing=None if result is None else _with_track_placement(landing_of(result), robot, table, cartesian),
    )
    if result is not None:
        report = dataclasses.replace(report, warnings=report.warnings + _compensation_warnings(result, labels))
    changed = _configuration_changes(report)
    if changed:
        report = dataclasses.replace(report, warnings=report.warnings + (changed,))
    if beyond := _beyond_the_measured_travel(table, robot, cartesian, labels):
        report = dataclasses.replace(report, warnings=report.warnings + (beyond,))
    return edited, report


def placed_on_track(program, robot, tools=None, frames=None):
    """``program`` with the motions to targets whose track position it leaves unknown left as written and listed
    (`trajcomp.programs.frames.FrameTable.unplaced`: a KRL point without E1 on the first motion, after a call
    or a branch); the program itself when there is none."""
    return program.with_targets_left(FrameTable(program, robot, tools, frames).unplaced())


def _with_track_placement(landing, robot, table, index):
    """The landing arrays with where the identified track places each target's carriage (targets ``index`` (n,),
    the first n rows): within the measured travel its `QUANTILE` radius (an isotropic error of
    `trajcomp.arm.track.Track.placement_sigma` per axis) joined in quadrature and counted as unseen; beyond it
    no estimate (NaN: the verdict fails the target, `_beyond_the_measured_travel` says why)."""
    track = robot.track
    if track is None or track.scatter is None or not len(index):
        return landing
    values = table.track_positions(index)
    radius = np.sqrt(chi2_quantile(QUANTILE, 3)) * track.placement_sigma(values)
    radius[track.beyond_measured(values)] = np.nan
    n = len(index)
    estimate, unseen = landing["estimate_mm"].copy(), landing["unseen_mm"].copy()
    total = np.hypot(estimate[:n], radius)
    unseen[:n] += total - estimate[:n]
    estimate[:n] = total
    return {**landing, "estimate_mm": estimate, "unseen_mm": unseen}


def _beyond_the_measured_travel(table, robot, index, labels):
    """A warning naming the targets ``index`` (N,) at track positions beyond those the track's calibration
    measured ("" if none, or no track was calibrated): there the carriage is placed by the fitted line alone."""
    track = robot.track
    if track is None or track.measured_positions is None or not len(index):
        return ""
    beyond = np.flatnonzero(track.beyond_measured(table.track_positions(index)))
    if not beyond.size:
        return ""
    more = f" and {beyond.size - 10} more" if beyond.size > 10 else ""
    return (f"{beyond.size} targets stand at track positions beyond the travel the track's calibration measured "
            f"({track.measured_positions[0]:g}..{track.measured_positions[-1]:g} mm), where the carriage is placed by "
            f"the fitted line alone and its place is not estimated (their landing is unknown: the verdict fails them; "
            f"measure the track there): {', '.join(labels[k] for k in beyond[:10])}{more}")


def _compensation_warnings(result, labels):
    """What a `CompensationResult` did that the user must know: grid values held at a face, tools it cannot place."""
    out = []
    for mask, what in (
        (result.near_face, "lie inside the grid near a face, where the correction moves their command out of it: "
                           "the grid's nearest value is used there (as --outside clamp), not zero"),
        (result.other_tool, "use a tool other than the calibrated TCP, which the model cannot place (the model "
                            "file's other_tools_reason says why): they may miss by tenths of a mm"),
    ):
        rows = np.flatnonzero(mask)
        if rows.size:
            more = f" and {rows.size - 10} more" if rows.size > 10 else ""
            out.append(f"{rows.size} targets {what}: {', '.join(labels[k] for k in rows[:10])}{more}")
    return tuple(out)


def _configs(program, robot, index, q):
    """Configuration data written for the corrected targets ``index`` (N,) at joints ``q`` (N, 6), rad.

    The declared fields the corrected joints still satisfy are kept as
    written, and so are fields the tool does not own
    (`trajcomp.formats.configuration.written_configuration`); a target whose data
    its language does not bind (a KUKA point only LIN or CIRC motions use)
    keeps them all.
    """
    config = program.target_table().config
    declared = [config[i] for i in index.tolist()]
    binds = np.flatnonzero(binding(program)[index])
    data = capability(program, ConfigurationData)
    written = written_configuration(data, robot, [declared[k] for k in binds.tolist()], q[binds])
    if written is None:
        return None
    for k, config in zip(binds.tolist(), written):
        declared[k] = config
    return declared


def _configuration_changes(report):
    """A warning listing every target whose configuration data the run rewrote ("" if none)."""
    changed = [f"{report.labels[k]}: {d} -> {w}" for k, (d, w) in enumerate(zip(report.declared, report.written))
               if d and d != w]  # a label is built for a changed target only (`Program.labels`)
    if not changed:
        return ""
    more = f" and {len(changed) - 10} more" if len(changed) > 10 else ""
    return (f"configuration data rewritten for {len(changed)} corrected targets (a joint left the window its "
            f"data name, beyond {np.degrees(BOUNDARY_TOLERANCE):g} deg): {'; '.join(changed[:10])}{more}")


def _not_compensated(program, compensated):
    """``((line, text, reason), ...)``: every motion left as written once, then the points passed elsewhere.

    A motion built on a compensated point (``Offs(p10, ...)``, ``pose_add(p, ...)``)
    is said to move with it; a point named only outside motions (a
    procedure argument) is listed at the statement naming it.

    Parameters
    ----------
    compensated : array_like of int
        Indices of the targets the run corrects.
    """
    corrected = set(np.asarray(compensated, dtype=int).tolist())
    listed = []
    motions = [motion for motion in program.runtime_motions() if not motion.axis_position]
    for (place, _, reason), motion in zip(program.not_compensated(), motions):
        moved = [program.targets[i].label for i in dict.fromkeys(motion.refs) if i in corrected]
        if moved:
            reason += (f"; built on {', '.join(moved)}, which {'is' if len(moved) == 1 else 'are'} corrected: "
                       "it moves with them (its offset itself is not compensated)")
        listed.append((place, motion.text, reason))
    lines = {line for line, _, _ in listed}
    listed += [(line, text, f"point {program.targets[i].label} is used here, where trajcomp cannot see the motion "
                            "(a procedure argument, a run-time expression): left as written")
               for i, line, text in program.referenced_targets() if line not in lines]
    return tuple(listed)


def landing_of(result):
    """The `ProgramReport.landing` arrays of a `CompensationResult`."""
    return {"estimate_mm": result.estimate, "held_out_mm": result.held_out, "unseen_mm": result.unseen,
            "orientation_beyond_deg": result.orientation_beyond, "unmeasured_posture": result.unmeasured_posture,
            "other_tool": result.other_tool}


def as_written_report(program, plan, robot=None):
    """The `ProgramReport` of a program run as written (no correction), e.g. for re-timing alone.

    Parameters
    ----------
    program : Program
    plan : trajcomp.compensation.posture.PlannedJoints
        Its Cartesian targets in their declared postures (`planned_joints`).
    robot : Robot, optional
        The arm it runs on (its track, if any, is not an external axis to warn of).
    """
    n = len(plan.index)
    joint_index, _ = program.joint_targets()
    return ProgramReport(
        labels=program.labels(plan.index),
        **_target_facts(program, plan.index),
        T_target=plan.T_base_tcp,
        T_command=plan.T_base_tcp,
        correction=np.zeros((n, 6)),
        q=plan.q,
        q_planned=plan.q,
        declared=_described(program, plan.index),
        written=_described(program, plan.index),
        posture_source=plan.source,
        outside_grid=np.zeros(n, dtype=bool),
        predicted_residual=np.zeros(n),
        **_program_facts(program, robot, joint_index, "keep"),
    )


def _target_facts(program, index):
    """The report fields of targets ``index`` (N,) that the program states: source lines, tools, frames."""
    used = program.usage_table()
    row = np.searchsorted(used.index, index)
    return {"lines": program.target_table().line[index], "tools": tuple(used.tool[row]),
            "frames": tuple(used.frame[row])}


def _described(program, index):
    """Configuration data of targets ``index`` (N,) as the language writes them (`describe`), tuple of str."""
    config = program.target_table().config
    if not any(config):  # no target states any (a CSV program)
        return ("",) * len(index)
    configs = [config[i] for i in index.tolist()]
    data = capability(program, ConfigurationData)
    texts = {c: describe(data, c) for c in set(configs)}  # a path's targets mostly share theirs
    return tuple(texts[c] for c in configs)


def _program_facts(program, robot, joint_index, joint_mode):
    """The report fields that describe the program itself: unused points, joint targets, warnings."""
    return {
        "unused": tuple(t.label for t in program.unused_targets()),
        "joint_targets": tuple(program.targets[i].label for i in joint_index)
        + tuple(f"{program.motions[k].text} ({place_text(program.place(program.motions[k]))})"
                for k in np.flatnonzero(program.motion_table().axis_position)),
        "joint_mode": joint_mode,
        "warnings": _warnings(program, robot),
    }


def _warnings(program, robot):
    """What the user must know about a compensated program: its notes (copies of a point per use), external axes
    that move other than the robot's track (whose carriage places each target's arm base)."""
    moving = program.moving_external_axes()
    axis = None if robot is None or robot.track is None else robot.track.index(program.track_key)
    if axis is not None:
        moving = tuple(name for name in moving if name != f"E{axis + 1}")
    if not moving:
        return program.notes
    return program.notes + (f"the program moves external axes {', '.join(moving)} (a track or positioner): the compensation "
            "assumes the arm's base is fixed, so targets reached after a base move are corrected for the "
            "calibrated base only",)


def _correction(T_target, T_command):
    """Command minus target (N, 6): position (mm) and rotation vector (deg) of R_command R_target^T (`pose_error`)."""
    out = pose_error(T_target, T_command) if len(T_target) else np.zeros((0, 6))
    out[:, 3:] = np.degrees(out[:, 3:])
    return out


def _check_correction(correction, labels, bound):
    """CompensationError naming the targets whose position correction exceeds ``bound`` mm."""
    size = np.linalg.norm(correction, axis=1)
    bad = np.flatnonzero(size > bound)
    if bad.size:
        shown = "; ".join(f"{labels[k]}: {size[k]:.2f} mm" for k in bad[:5])
        more = f" and {bad.size - 5} more" if bad.size > 5 else ""
        raise CompensationError(
            f"{bad.size} corrections exceed {bound:g} mm, implausible for a calibrated arm (wrong model, robot, "
            f"tool or units?): {shown}{more}. Raise --max-correction only if this is intended"
        )


def convert_program(program, to_format, *, robot=None, tools=None, frames=None):
    """The program re-expressed for another language (written fresh, not patched).

    Into the language it was read from, the program itself: its writer
    patches the sources, so nothing is dropped or regenerated.

    Poses keep their frames where the language has user frames; for CSV and
    URScript they are moved to the base frame (the frames' values must then
    be known). Configuration data are computed from each target's joints,
    or from nominal IK when the joints are unknown and a robot is given.
    Speeds are stated in the language's units, each motion no faster than
    its source's controller runs it (`trajcomp.formats.speeds.convert_speeds`,
    with the robot's limits and each motion's geometry); a speed that
    cannot be carried over is written as the language's slowest and the
    motion says why in its ``speed_why``.

    Parameters
    ----------
    program : Program
    to_format : str
        Registry name of the language.
    robot : Robot, optional
        Needed for configuration data (KRL S/T, RAPID confdata, FANUC CONFIG)
        of Cartesian targets without known joints.
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        Values the program uses but does not define.

    Returns
    -------
    Program
        With no sources: writers generate the text.
    """
    if to_format == program.format and program.sources:
        return program  # its own language: written back through the byte-preserving writer, every line kept
    table = FrameTable(program, robot, tools, frames)
    usage = program.usage()
    targets = list(program.targets)
    motions = program.motions
    language = find_format(format=to_format)
    if language.capability(BaseFrameOnly):  # its poses are always in the base frame
        for i, (_, frame) in usage.items():
            if targets[i].pose is not None and frame is not None:
                targets[i] = dataclasses.replace(targets[i], pose=table.frame(frame) @ targets[i].pose, frame=None)
        motions = tuple(dataclasses.replace(m, frame=None) for m in motions)
    cartesian = [i for i in sorted(usage) if not targets[i].is_joint]
    data = language.capability(ConfigurationData)
    unknown = any(targets[i].joints is None for i in cartesian)
    if robot is not None and unknown:
        plan = planned_joints(program, robot, tools=tools, frames=frames)
        for i, joints in zip(plan.index, plan.q):
            if targets[i].joints is None:
                targets[i] = dataclasses.replace(targets[i], joints=joints)
    if (units := language.capability(SpeedUnits)) is not None:
        motions = convert_speeds(motions, units.units, robot, _geometry(program, robot, targets, tools, frames),
                                 language.name, orientation=language.capability(OrientationSpeed) is not None)
    known = [i for i, target in enumerate(targets) if target.joints is not None and not target.is_joint] \
        if robot is not None and data is not None else []
    configs = dict(zip(known, configuration_for(data, robot, np.array([targets[i].joints for i in known]))
                       if known else ()))  # every target's at once
    for i in range(len(targets)):
        targets[i] = replaced(targets[i], config=configs.get(i, ()), spans={}, edited=False)
    return Program(
        format=to_format,
        track_key=track_key(language),
        name=program.name,
        items=motions,
        targets=tuple(targets),
        tools={**(tools or {}), **program.tools},
        frames={**(frames or {}), **program.frames},
    )


def _geometry(program, robot, targets, tools, frames):
    """The `MotionGeometry` of ``program``'s motions with ``targets``' joints; None without a robot or joints."""
    if robot is None:
        return None
    from trajcomp.timing.moves import moves_from_program

    joints = np.array([np.full(6, np.nan) if t.joints is None else t.joints for t in targets]).reshape(-1, 6)
    try:
        moves = moves_from_program(program, robot, joints, tools=tools, frames=frames)
    except TimingError:  # a target without joints, a speed that is not positive: no geometry to convert with
        return None
    return MotionGeometry.of(program, robot, moves)
