"""``trajcomp retime IN -o OUT --robot R``: time a program under the arm's limits and write the timing into it.

The options become a `trajcomp.jobs.retime.RetimeJob`.
"""

import sys

from trajcomp.commands._args import add_robot, command_parser, info, positive_number, robot_of, speed_field_names
from trajcomp.commands._report import add_report_options, criteria_of
from trajcomp.commands.convert import add_frame_options, add_in_place_option, frame_options
from trajcomp.timing.options import RETIME_METHODS, TOLERANCE

METHOD_HELP = ("auto: TOPP-RA for continuous LIN/CIRC runs, ruckig (jerk-limited) for point-to-point "
               "and stop-to-stop motions; toppra or ruckig: that one for every segment")


def add_parser(sub):
    parser = command_parser(
        sub, "retime",
        "Read a program (a language of `trajcomp formats`; Cartesian targets are solved with the robot's "
        "nominal model in the posture the program declares), compute the time-optimal timing under the "
        "robot's joint velocity, acceleration and jerk limits without running faster than the program asks, "
        "check it by sampling at 1 kHz and write it into the program's speed and time fields, those its "
        f"language declares ({speed_field_names()}, and plugins that declare them); every other byte is kept. Exits 1 "
        "(the program written) if a sample exceeds a limit by more than 1 %.",
        "trajcomp retime examples/programs/abb/Weld.mod -o Weld-timed.mod --robot abb_irb4600",
    )
    parser.add_argument("program", metavar="IN", help="program file")
    parser.add_argument("-o", "--output", required=True, help="program to write (same language as IN)")
    add_robot(parser)
    parser.add_argument("--method", choices=RETIME_METHODS, default="auto", help=METHOD_HELP)
    add_tolerance_option(parser)
    add_frame_options(parser)
    add_in_place_option(parser)
    add_report_options(parser, verdict="margins")  # no model: no landing a tolerance judges
    parser.set_defaults(run=run)


def add_tolerance_option(parser):
    """Add ``--path-tolerance MM``: how far the timed path may pass from a waypoint."""
    parser.add_argument("--path-tolerance", type=positive_number, default=TOLERANCE, metavar="MM",
                        help="largest distance of the timed joint path from a waypoint, mm: the path is smoothed "
                        "within it against IK noise (default %(default)g mm)")


def run(args):
    from trajcomp.jobs.batch import EXIT_CODES
    from trajcomp.jobs.retime import RetimeJob

    tools, frames = frame_options(args)
    job = RetimeJob(robot_of(args), robot_file=args.robot, method=args.method, path_tolerance=args.path_tolerance,
                    tools=tools, frames=frames, in_place=args.in_place, criteria=criteria_of(args),
                    report=args.report, json_only=args.json_only)
    run = job.run(args.program, args.output)
    if args.json_only and not args.report:
        sys.stdout.write(run.compliance.json_text())
    for line in run.result.lines:
        info(line)
    if run.result.message:
        info(f"trajcomp: {run.result.message}")
    return EXIT_CODES[run.result.status]
