"""The ``trajcomp`` command line: one sub-command per module in trajcomp.commands.

Library code raises TrajcompError; this is the only place that prints errors
and chooses exit codes: 0 success, 1 the result fails a requested tolerance
or limit, 2 bad usage or bad input; 130 (the shells' code of Ctrl-C) when
the user interrupts the run, which writes nothing it had not finished.

Each process of a run computes on one BLAS / OpenMP thread unless the user
set the thread variables: the linear algebra here is many small products,
and threads of their own fight the run's worker processes and whatever
else shares the machine (calibrating 5,892 measurements beside one
CPU-bound process took 30-49 s with OpenBLAS's threads, 13-18 s without).
"""

import argparse
import importlib
import logging
import os
import sys

from trajcomp import __version__
from trajcomp.errors import ToleranceError, TrajcompError

INTERRUPTED = 130  # exit code of a run stopped by Ctrl-C (SIGINT), as shells report it
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")  # read when numpy loads
COMMANDS = (
    "robots",
    "plan",
    "simulate",
    "calibrate",
    "predict",
    "validate",
    "demo",
    "compensate",
    "formats",
    "convert",
    "retime",
)


def build_parser(only=None):
    """The argument parser with every sub-command registered, or only those named in ``only``.

    Each command's module imports what its work needs (numpy, scipy,
    matplotlib...): registering only the command being run keeps the
    others' imports out of its start-up.
    """
    parser = argparse.ArgumentParser(
        prog="trajcomp",
        description="Offline absolute-accuracy compensation for 6-axis robot arms.",
    )
    parser.add_argument("--version", action="version", version=f"trajcomp {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS if only is None else only:
        module = importlib.import_module(f"trajcomp.commands.{name}")
        module.add_parser(sub)
    return parser


def _needed(argv):
    """The commands a command line needs registered: the one it runs, none for --version, else all (None)."""
    if argv and argv[0] in COMMANDS:
        return (argv[0],)
    return () if argv == ["--version"] else None


def main(argv=None):
    """Run the CLI; returns the exit code (also used as the console script)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    for name in THREAD_VARIABLES:  # before the commands import numpy (this module does not)
        os.environ.setdefault(name, "1")
    parser = build_parser(_needed(argv))
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="trajcomp: warning: %(message)s")
    try:
        return args.run(args) or 0
    except ToleranceError as exc:
        print(f"trajcomp: {exc}", file=sys.stderr)
        return 1
    except TrajcompError as exc:
        print(f"trajcomp: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("trajcomp: interrupted: what was not finished was not written", file=sys.stderr)
        return INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
