"""``trajcomp retime IN -o OUT --robot R``: time a program under the arm's limits and write the timing into it.

Also the re-timing step of ``trajcomp compensate --retime`` (`retime_compensated`).
"""

import dataclasses

import numpy as np

from trajcomp import formats
from trajcomp.support.atomic import refuse_inputs
from trajcomp.commands._args import add_robot, command_parser, info, robot_of
from trajcomp.commands._report import add_report_options, criteria_of, emit
from trajcomp.commands.convert import add_frame_options, add_in_place_option, frame_options, protected_inputs
from trajcomp.errors import TimingError, TrajcompError
from trajcomp.support.memory import release
from trajcomp.support.parallel import in_background
from trajcomp.compensation.program import as_written_report
from trajcomp.compensation.posture import planned_joints, planned_targets
from trajcomp.report import compliance_report, file_entry, report_paths
from trajcomp.timing import METHODS
from trajcomp.timing.path import TOLERANCE

CHOICES = METHODS + ("none",)
# Targets below which the original and the corrected program are timed at once on two processes. A timing's
# working memory is ~230 bytes per waypoint: longer programs are timed one after the other (1M points: 0.95 GB, not 1.1).
TOGETHER = 500_000
METHOD_HELP = ("auto: TOPP-RA for continuous LIN/CIRC runs, ruckig (jerk-limited) for point-to-point "
               "and stop-to-stop motions; toppra or ruckig: that one for every segment")


def add_parser(sub):
    parser = command_parser(
        sub, "retime", "time a program under the arm's joint limits",
        "Read a program (any format; Cartesian targets are solved with the robot's nominal model in the "
        "posture the program declares), compute the time-optimal timing under the robot's joint velocity, "
        "acceleration and jerk limits without running faster than the program asks, check it by sampling "
        "at 1 kHz and write it into the program's speed and time fields (CSV t column, RAPID \\T, URScript "
        "t= / v=, FANUC sec / msec, KRL $VEL.CP / BAS(#VEL_PTP)); every other byte is kept. Exits 1 "
        "(the program written) if a sample exceeds a limit by more than 1 %.",
        "trajcomp retime examples/programs/abb/Weld.mod -o Weld-timed.mod --robot abb_irb4600",
    )
    parser.add_argument("program", metavar="IN", help="program file")
    parser.add_argument("-o", "--output", required=True, help="program to write (same language as IN)")
    add_robot(parser)
    parser.add_argument("--method", choices=METHODS, default="auto", help=METHOD_HELP)
    add_tolerance_option(parser)
    add_frame_options(parser)
    add_in_place_option(parser)
    add_report_options(parser)
    parser.set_defaults(run=run)


def add_tolerance_option(parser):
    """Add ``--path-tolerance MM``: how far the timed path may pass from a waypoint."""
    parser.add_argument("--path-tolerance", type=float, default=TOLERANCE, metavar="MM",
                        help="largest distance of the timed joint path from a waypoint, mm: the path is smoothed "
                        "within it against IK noise (default %(default)g mm)")


def run(args):
    robot = robot_of(args)
    program = formats.read(args.program)
    formats.check_robot_language(args.program, formats.find_format(format=program.format), robot, "the arm --robot names")
    out_format = formats.find_format(args.output).name
    if out_format != program.format:
        raise TrajcompError(f"{args.output}: retime writes the language it reads ({program.format}); "
                            f"convert the program first (trajcomp convert)")
    tools, frames = frame_options(args)
    inputs = [*dict.fromkeys(formats.input_paths(args.program, program)), args.robot]
    refuse_inputs(report_paths(args.report) if args.report else (), inputs, "give --report another name")
    plan = planned_joints(program, robot, tools=tools, frames=frames)
    joints = planned(program, plan.index, plan.q)
    timed, result = timed_program(program, robot, joints, args.method, args.path_tolerance, tools, frames)
    written = formats.write(args.output, timed, protect=protected_inputs(args, args.program, program) + [args.robot])
    for line in timing_lines(result):
        info(line)
    info(f"wrote {', '.join(map(str, written))}")
    report = compliance_report(
        as_written_report(program, plan), robot, criteria=criteria_of(args), command="retime", timing=result,
        files=[file_entry("program", p) for p in dict.fromkeys(formats.input_paths(args.program, program))]
        + [file_entry("output", p) for p in written],
        options={"method": args.method, "path_tolerance_mm": args.path_tolerance},
    )
    code = emit(report, args.report, args.json_only, protect=[*inputs, *written], written_before=written)
    if not result.within_limits:
        info(f"trajcomp: {LIMIT_MESSAGE}")
        return 1
    return code


LIMIT_MESSAGE = "the timing exceeds a limit by more than 1 % in the 1 kHz check (table above): check it before running"


def timed_program(program, robot, joints, method, tolerance, tools, frames):
    """``(program with the timing written into its speed fields, TimingResult)``."""
    from trajcomp.timing.writeback import apply_timing, retime_program

    if not tolerance > 0:
        raise TrajcompError(f"--path-tolerance: expected a positive number of mm, got {tolerance}")
    result = retime_program(program, robot, joints, method=method, tools=tools, frames=frames, tolerance=tolerance)
    return apply_timing(program, result, robot)


def timing_lines(result, before=None):
    """The dense check table, the cycle time(s) and what was written, as text lines."""
    written = sum(s.written for s in result.segments)
    kinds = ", ".join(sorted({s.kind for s in result.segments}))
    return [*result.lines_of_text(before), f"speed settings written for {written} motions ({kinds})"]


def planned(program, index, q):
    """Joints (N, 6) of a program's N targets: q (n, 6) of targets index (n,) (a `trajcomp.compensation.posture.Plan`), NaN
    elsewhere."""
    joints = np.full((len(program.target_table()), 6), np.nan)
    joints[index] = q
    return joints


def retime_compensated(original, corrected, robot, method, tolerance, tools=None, frames=None, *, q_planned=None,
                       workers=1):
    """Time a compensated program, and its original for the cycle time before compensation.

    Parameters
    ----------
    original, corrected : Program
        Before and after compensation (the corrected targets carry their joints).
    robot : Robot
        The nominal robot.
    method : str
        One of `trajcomp.timing.METHODS`.
    tolerance : float
        Path tolerance, mm.
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        Tools and frames the program uses but does not define.
    q_planned : ndarray, shape (n, 6), optional
        The original's Cartesian targets in their declared postures, in
        motion order (`trajcomp.compensation.posture.planned_targets`), rad: the
        compensation's `ProgramReport.q_planned` (rows beyond n, joint
        targets, are not used). Solved again when not given.
    workers : int
        More than 1, for a program of fewer than `TOGETHER` targets: the
        original is timed by another process meanwhile
        (`trajcomp.support.parallel.in_background`); else first, so that only one
        timing's working memory is held at a time.

    Returns
    -------
    (Program, TimingResult, float)
        The corrected program with its timing written (as it was, with a
        warning in the timing, for a language without writable speed
        fields), the timing, and the original program's cycle time (s).

    Raises
    ------
    TimingError
        With a hint to compensate without re-timing.
    """
    from trajcomp.timing.writeback import retime_program, writable

    if q_planned is None:
        plan = planned_joints(original, robot, tools=tools, frames=frames)
        index, q_planned = plan.index, plan.q
    else:
        index = planned_targets(original)
        q_planned = q_planned[: len(index)]
    after = corrected.target_table().joints
    try:
        before = in_background(lambda: retime_program(original, robot, planned(original, index, q_planned),
                                                      method=method, tools=tools, frames=frames,
                                                      tolerance=tolerance).cycle_time,
                               workers if len(after) < TOGETHER else 1)
        release()  # the original's timing's working memory, when it was timed here, before the corrected one's
        if writable(corrected):
            timed, result = timed_program(corrected, robot, after, method, tolerance, tools, frames)
        else:
            timed = corrected
            result = retime_program(corrected, robot, after, method=method, tools=tools, frames=frames,
                                    tolerance=tolerance)
            note = f"the timing is not written: {corrected.format} programs have no speed fields trajcomp writes"
            result = dataclasses.replace(result, warnings=result.warnings + (note,))
        return timed, result, before()  # only the original's cycle time is kept
    except TimingError as exc:
        raise TimingError(f"{exc} (compensate with --retime none to keep the program's speeds)") from None
