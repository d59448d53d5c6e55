"""The ``trajcomp`` command line: one sub-command per module in trajcomp.commands.

Library code raises TrajcompError; this is the only place that prints errors
and chooses exit codes: 0 success, 1 the result fails a requested tolerance
or limit, 2 bad usage or bad input, 3 an unexpected exception (a bug:
`trajcomp.support.crash`); 130 (the shells' code of Ctrl-C) when the user interrupts
the run, 143 when it is stopped by SIGTERM (what Docker, systemd and CI
send) and 129 by SIGHUP (its terminal closed), handled alike, also when the
signal reaches only one of its worker processes: what was not finished is
not written (`trajcomp.support.signals`); 141 (SIGPIPE's)
when the reader of its output went away (``| head``).

Each process of a run computes on one BLAS / OpenMP thread unless the user
set the thread variables (`trajcomp.support.threads`).
"""

if __name__ == "__main__":  # ``python -m trajcomp.cli``: a stopping signal from here on ends the run with its code
    from trajcomp.support.signals import hold_from_start

    hold_from_start()

import argparse  # noqa: E402 (after the hold: a signal during the imports is kept for the run)
import importlib
import logging
import os
import signal
import sys
import traceback

from trajcomp import __version__
from trajcomp.support.crash import bug_message, save_traceback
from trajcomp.support.crash import EXIT_CODE as CRASHED
from trajcomp.support.signals import STOPPING, Interrupted, check, raised, stopped
from trajcomp.support.threads import THREAD_VARIABLES
from trajcomp.commands import COMMANDS, EXIT_CODES_HELP
from trajcomp.errors import ToleranceError, TrajcompError

INTERRUPTED = 128 + signal.SIGINT  # 130: exit code of a run stopped by Ctrl-C (SIGINT), as shells report it
STOPPED_CODES = {128 + signum for signum in STOPPING}  # 130, 143, 129
PIPE_CLOSED = 128 + signal.SIGPIPE  # 141: the output's reader went away, as shells report a tool SIGPIPE stops


def build_parser(only=None):
    """The argument parser with the sub-commands named in ``only`` registered, or every one's one-line help.

    Each command's module imports what its work needs (numpy, scipy,
    matplotlib...): registering only the command being run keeps the
    others' imports out of its start-up, and ``trajcomp --help`` (``only``
    None: no command given) lists `COMMANDS` without importing any.
    """
    parser = argparse.ArgumentParser(
        prog="trajcomp",
        description="Offline absolute-accuracy compensation for 6-axis robot arms.",
        epilog=EXIT_CODES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"trajcomp {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="on an internal error (a bug, exit 3) print its traceback instead of saving it to a file")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    if only is None:
        for name, summary in COMMANDS.items():
            sub.add_parser(name, help=summary)
    for name in only or ():
        importlib.import_module(f"trajcomp.commands.{name}").add_parser(sub)
    return parser


def _needed(argv):
    """The commands a command line needs registered: the one it runs, none for --version, else all (None)."""
    argv = [a for a in argv if a != "--debug"]
    if argv and argv[0] in COMMANDS:
        return (argv[0],)
    return () if argv == ["--version"] else None


def parse(parser, argv):
    """``parser.parse_args(argv)``, but an unknown option is reported with its sub-command's usage.

    argparse leaves the arguments a sub-command did not know to the top-level
    parser, which would print ``usage: trajcomp [-h] ... COMMAND ...``: the
    user of ``trajcomp validate --tolerence`` needs validate's options.
    """
    args, unknown = parser.parse_known_args(argv)
    if unknown:
        commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        commands.choices[args.command].error(f"unrecognized arguments: {' '.join(unknown)}")
    return args


def main(argv=None):
    """Run the CLI; returns the exit code (also used as the console script).

    Run as the program (no ``argv``: this process's command line), a run a
    signal stopped then ignores those that follow (a Dask worker's, sent on
    as it is ended), so that the process exits with the first one's code,
    and prints nothing more that is logged (a library's threads and
    processes on their way down). Called in a process that goes on (a test,
    a plugin), neither is changed.
    """
    program = argv is None
    argv = sys.argv[1:] if argv is None else list(argv)
    for name in THREAD_VARIABLES:  # before the commands import numpy (this module does not)
        os.environ.setdefault(name, "1")
    with raised():  # SIGINT, SIGTERM and SIGHUP unwind the run (in the main thread; elsewhere as they are)
        code = _run(argv)
    if program and code in STOPPED_CODES:
        for signum in STOPPING:
            signal.signal(signum, signal.SIG_IGN)
        logging.disable()
    return code


def _run(argv):
    """Parse ``argv`` and run its command; the exit code."""
    args = None
    try:
        check()  # a signal that came while the program started (`trajcomp.support.signals.hold_from_start`)
        args = parse(build_parser(_needed(argv)), argv)
        logging.basicConfig(level=logging.WARNING, handlers=[_warnings()])
        return args.run(args) or 0
    except ToleranceError as exc:
        print(f"trajcomp: {exc}", file=sys.stderr)
        return 1
    except TrajcompError as exc:
        print(f"trajcomp: error: {exc}", file=sys.stderr)
        return 2
    except Interrupted as stop:
        return _stopped(stop)
    except KeyboardInterrupt:
        print("trajcomp: interrupted: what was not finished was not written", file=sys.stderr)
        return INTERRUPTED
    except BrokenPipeError:  # stdout's reader closed it (`trajcomp robots | head -1`): no bug, nothing to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # what is left unflushed goes nowhere at exit
        return PIPE_CLOSED
    except Exception as exc:  # anything else is a bug: say so, keep the traceback, exit 3
        if stopped() is not None:  # a signal's exception that became another on its way (an ImportError)
            return _stopped(stopped())
        debug = args.debug if args is not None else "--debug" in argv
        if debug:
            traceback.print_exc()
        print(f"trajcomp: {bug_message(exc, None if debug else save_traceback(exc), printed=debug)}", file=sys.stderr)
        return CRASHED


def _warnings():
    """The handler printing logged warnings on stderr: trajcomp's as ``trajcomp: warning: ...``, another library's
    (Dask's cluster) with its logger's name on one line (an exception named, no traceback).

    Only warnings and errors: a library's own INFO records (Dask logs each
    worker's start) are not printed. Once a stopping signal came, another
    library's records are dropped: what its processes say on the way down
    follows from the stop the run reports.
    """
    handler = logging.StreamHandler()
    handler.setLevel(logging.WARNING)
    handler.setFormatter(_OneLine())
    handler.addFilter(lambda record: record.name.partition(".")[0] == "trajcomp" or stopped() is None)
    return handler


class _OneLine(logging.Formatter):
    """A logged record as one line: ``trajcomp: warning: [logger: ]message[ (ExceptionType: text)]``."""

    def format(self, record):
        if record.name.partition(".")[0] == "trajcomp":
            return f"trajcomp: warning: {record.getMessage()}"
        message = " ".join(record.getMessage().split())
        if record.exc_info and record.exc_info[1] is not None:
            error = record.exc_info[1]
            message += f" ({type(error).__name__}: {error})"
        return f"trajcomp: warning: {record.name}: {message}"


def _stopped(stop):
    """Say that the run was stopped by a signal (`Interrupted` ``stop``); its exit code.

    """
    if stop.signum != signal.SIGINT:
        print(f"trajcomp: terminated ({stop.name}): what was not finished was not written", file=sys.stderr)
        return stop.exit_code
    print("trajcomp: interrupted: what was not finished was not written", file=sys.stderr)
    return INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
