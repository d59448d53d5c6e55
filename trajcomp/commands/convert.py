"""``trajcomp convert IN OUT``: rewrite a robot program in another language (`trajcomp.jobs.convert.ConvertJob`).

Also home of the tool and frame options shared by the commands that read
programs (``--tool NAME=x,y,z,a,b,c``, ``--frame``/``--base``/``--wobj``).
"""

import math
import sys

from trajcomp.commands._args import command_parser, language_names, languages
from trajcomp.errors import TrajcompError


def add_frame_options(parser):
    """Add the repeated ``--tool`` and ``--frame`` (alias ``--base``, ``--wobj``, ``--uframe``) options."""
    parser.add_argument(
        "--tool", action="append", default=[], metavar="NAME=x,y,z,a,b,c",
        help="value of a tool the program uses but does not define: TCP in the flange frame, mm and "
        "deg (A, B, C = intrinsic Z-Y'-X''); repeat for several tools, e.g. --tool 1=0,0,150,0,0,0",
    )
    parser.add_argument(
        "--frame", "--base", "--wobj", "--uframe", dest="frame", action="append", default=[],
        metavar="NAME=x,y,z,a,b,c",
        help="value of a user frame / base / work object the program uses but does not define, in the "
        "world frame, mm and deg; repeatable",
    )


def add_in_place_option(parser):
    """Add ``--in-place``: without it, an output that is an input file is refused."""
    parser.add_argument("--in-place", action="store_true",
                        help="allow the output to replace the input program (otherwise refused)")


def parse_frame_values(values, option):
    """``{name: T (4, 4)}`` of ``NAME=x,y,z,a,b,c`` texts (mm, deg).

    Raises
    ------
    TrajcompError
        A malformed value, naming the option and the text.
    """
    import numpy as np

    from trajcomp.arm.transforms import pose_to_matrix

    out = {}
    for text in values:
        name, _, numbers = text.partition("=")
        try:
            pose = [float(v) for v in numbers.split(",")]
        except ValueError:
            pose = []
        if not name.strip() or len(pose) != 6 or not all(math.isfinite(v) for v in pose):
            raise TrajcompError(f"{option} {text!r}: expected NAME=x,y,z,a,b,c (six numbers, mm and deg)")
        out[name.strip()] = pose_to_matrix(np.array(pose[:3] + list(np.radians(pose[3:]))))
    return out


def frame_options(args):
    """``(tools, frames)`` dictionaries from the parsed ``--tool`` / ``--frame`` options."""
    return parse_frame_values(args.tool, "--tool"), parse_frame_values(args.frame, "--frame")


def add_parser(sub):
    from trajcomp.formats.capabilities import ConfigurationData

    parser = command_parser(
        sub, "convert",
        "Read a robot program and write it in the language of OUT's extension. Languages: "
        f"{languages()}. Poses are kept to 1e-6 mm; configuration data (in "
        f"{language_names(ConfigurationData)}) are computed with the robot's kinematics, so give --robot when "
        "the target language needs them. Motions whose position is computed at run time are written as comments (exit 1 if every motion is). "
        "Speeds are written in the target language's units, never faster than the source runs them (give --robot "
        "to convert between joint and TCP speeds); a speed that cannot be carried over is written as the "
        "language's slowest, listed, and the exit code is 1.",
        "trajcomp convert examples/programs/csv/weld.csv weld.src --robot kuka_kr6_r900",
        "trajcomp convert examples/programs/csv/weld.csv weld.script",
    )
    parser.add_argument("input", metavar="IN", help="program to read")
    parser.add_argument("output", metavar="OUT", help="program to write (format from the extension)")
    parser.add_argument("--robot", help="built-in robot name or robot YAML file (for configuration data)")
    parser.add_argument("--from", dest="from_format", metavar="FORMAT",
                        help=f"input format: {language_names()} or a plugin's (default: from the extension)")
    parser.add_argument("--to", dest="to_format", metavar="FORMAT",
                        help=f"output format: {language_names()} or a plugin's (default: from the extension)")
    add_frame_options(parser)
    add_in_place_option(parser)
    parser.set_defaults(run=run)


def run(args):
    from trajcomp.arm.robot import load_robot
    from trajcomp.jobs.batch import EXIT_CODES
    from trajcomp.jobs.convert import ConvertJob

    tools, frames = frame_options(args)
    job = ConvertJob(load_robot(args.robot) if args.robot else None, tools, frames, args.from_format, args.to_format,
                     args.in_place)
    run = job.run(args.input, args.output)
    print(*run.result.lines, sep="\n")
    for warning in run.warnings:
        print(f"trajcomp: warning: {warning}", file=sys.stderr)
    if run.result.message:
        print(f"trajcomp: {run.result.message}", file=sys.stderr)
    return EXIT_CODES[run.result.status]
