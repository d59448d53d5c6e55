"""Argument types and helpers shared by the sub-commands.

Building a parser imports none of the library: the types import what they
convert with (numpy, the layout reader) when an option is parsed, so that
``trajcomp NAME --help`` starts without them.
"""

import argparse
import math
import sys

from trajcomp.commands import COMMANDS, EXIT_CODES_HELP
from trajcomp.errors import TrajcompError


def numbers(count):
    """An argparse type: ``count`` comma-separated numbers, as a float array."""

    def parse(text):
        import numpy as np

        try:
            values = np.array([float(v) for v in text.split(",")])
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {count} comma-separated numbers, got {text!r}") from None
        if len(values) != count or not np.all(np.isfinite(values)):
            raise argparse.ArgumentTypeError(f"expected {count} comma-separated finite numbers, got {text!r}")
        return values

    return parse


def non_negative_int(text):
    """An argparse type: an integer >= 0 (seeds, counts)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def positive_int(text):
    """An argparse type: an integer >= 1 (counts)."""
    value = non_negative_int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a number >= 1, got {text!r}")
    return value


def positive_number(text):
    """An argparse type: a finite number > 0 (steps, lengths, weights)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def steps(text):
    """An argparse type: one positive step, or three (x, y, z), mm."""
    import numpy as np

    values = [positive_number(v) for v in text.split(",")]
    if len(values) not in (1, 3):
        raise argparse.ArgumentTypeError(f"expected one step or three (x,y,z), got {text!r}")
    return values[0] if len(values) == 1 else np.array(values)


def pose(text):
    """An argparse type: ``x,y,z,a,b,c`` (mm, deg) as a matrix (4, 4), mm and rad."""
    import numpy as np

    from trajcomp.arm.transforms import pose_to_matrix

    values = numbers(6)(text)
    return pose_to_matrix(np.concatenate([values[:3], np.radians(values[3:])]))


def mapping(text):
    """An argparse type: a column mapping ``FIELD=EXPR,...`` (`trajcomp.calibration.layout.parse_mapping`)."""
    from trajcomp.calibration.layout import parse_mapping

    try:
        return parse_mapping(text)
    except TrajcompError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_layout(parser):
    """The ``--columns`` / ``--columns-file`` options of the commands that read measurements."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--columns", type=mapping, metavar="FIELD=EXPR,...",
                       help="column mapping for other layouts, e.g. j1=joint_1,mx=x_t+x_dif")
    group.add_argument("--columns-file", metavar="YAML",
                       help="layout file: columns, delimiter, decimal comma, units, rotation conventions, frame "
                       "(examples/columns/*.yaml)")


def layout_of(args):
    """The measurement layout the options name, or None for the standard layout."""
    from trajcomp.calibration.layout import load_layout

    return load_layout(args.columns_file) if args.columns_file else args.columns


def add_robot(parser, required=True):
    parser.add_argument(
        "--robot",
        required=required,
        help="built-in robot name (see `trajcomp robots`) or a robot YAML file",
    )


def robot_of(args):
    """The `trajcomp.arm.robot.Robot` ``--robot`` names."""
    from trajcomp.arm.robot import load_robot

    return load_robot(args.robot)


def command_parser(sub, name, description, *examples):
    """A sub-command parser with its one-line help (`trajcomp.commands.COMMANDS`), description and examples.

    The examples are shown under ``example:`` in ``--help``; tests/test_docs.py
    runs them in order from the root of a clone, so each must work as written.
    """
    label = "example" if len(examples) == 1 else "examples"
    return sub.add_parser(
        name,
        help=COMMANDS[name],
        description=description,
        epilog=f"{label}:\n" + "\n".join(f"  {example}" for example in examples) + f"\n\n{EXIT_CODES_HELP}",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )


def languages():
    """The program languages of the format registry with maker and extensions, for a help text.

    ``"csv (.csv), krl (KUKA .src), ..., and the plugins' (`trajcomp formats`)"``:
    a language added by a folder is listed without a word of the commands
    changed. Plugins are named, not imported: building a parser must not
    import what they import (`trajcomp.formats.formats`).
    """
    from trajcomp import formats
    from trajcomp.formats.capabilities import Vendor

    known = [f"{fmt.name} ({' '.join(filter(None, [getattr(fmt.capability(Vendor), 'name', None), *fmt.extensions]))})"
             for fmt in formats.formats(plugins=False)]
    return ", ".join(known) + ", and the plugins' (`trajcomp formats` lists them)"


def language_names(declaring=None):
    """The names of the registry's languages for a help text: ``"csv, fanuc_ls, ..."`` (plugins as in `languages`).

    ``declaring``: only the languages that declare a capability of that
    type (`trajcomp.formats.capabilities.ConfigurationData` ...).
    """
    from trajcomp import formats

    return ", ".join(fmt.name for fmt in formats.formats(plugins=False)
                     if declaring is None or fmt.capability(declaring))


def speed_field_names():
    """The languages whose re-timing fields the registry declares, with them: ``"krl ($VEL.CP, ...), ..."``."""
    from trajcomp import formats
    from trajcomp.formats.capabilities import SpeedFields

    fields = [(fmt.name, fmt.capability(SpeedFields)) for fmt in formats.formats(plugins=False)]
    return ", ".join(f"{name} ({speeds.names})" if speeds.names else name for name, speeds in fields if speeds)


def info(message):
    """A progress or report line on stderr."""
    print(message, file=sys.stderr)


def progress(message):
    """A progress line on stderr, only when stderr is a terminal."""
    if sys.stderr.isatty():
        print(message, file=sys.stderr)

