"""Argument types and helpers shared by the sub-commands."""

import argparse
import sys

import numpy as np

from trajcomp.robot import load_robot


def numbers(count):
    """An argparse type: ``count`` comma-separated numbers, as a float array."""

    def parse(text):
        try:
            values = np.array([float(v) for v in text.split(",")])
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {count} comma-separated numbers, got {text!r}") from None
        if len(values) != count or not np.all(np.isfinite(values)):
            raise argparse.ArgumentTypeError(f"expected {count} comma-separated finite numbers, got {text!r}")
        return values

    return parse


def add_robot(parser, required=True):
    parser.add_argument(
        "--robot",
        required=required,
        help="built-in robot name (see `trajcomp robots`) or a robot YAML file",
    )


def robot_of(args):
    return load_robot(args.robot)


def command_parser(sub, name, help, description, *examples):
    """A sub-command parser with its one-line help, description and example command lines.

    The examples are shown under ``example:`` in ``--help``; tests/test_docs.py
    runs them in order from the root of a clone, so each must work as written.
    """
    label = "example" if len(examples) == 1 else "examples"
    return sub.add_parser(
        name,
        help=help,
        description=description,
        epilog=f"{label}:\n" + "\n".join(f"  {example}" for example in examples),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )


def info(message):
    """A progress or report line on stderr."""
    print(message, file=sys.stderr)


def progress(message):
    """A progress line on stderr, only when stderr is a terminal."""
    if sys.stderr.isatty():
        print(message, file=sys.stderr)

