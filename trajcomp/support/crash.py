"""Unexpected exceptions: one line saying it is a bug, the traceback kept for the report.

An exception that is not a `trajcomp.errors.TrajcompError` is a bug, never
bad input: the command line exits with `EXIT_CODE` (3; a batch's file gets
the status ``crash``), prints one line naming the exception and where its
traceback was saved, and prints the traceback itself with ``--debug``.
"""

import datetime
import os
import tempfile
import traceback
from pathlib import Path

EXIT_CODE = 3  # a crash: neither success (0), a failing verdict (1) nor bad input (2)
_SHOWN = 200  # characters of an exception's text shown on the line (it may quote unbounded input)


def save_traceback(exc):
    """Write ``exc``'s traceback to a new file in the temporary folder; its path, or None if it cannot be written."""
    stamp = datetime.datetime.now().strftime("%Y%m%dT%H%M%S")
    try:
        fd, path = tempfile.mkstemp(prefix=f"trajcomp-crash-{stamp}-", suffix=".txt")
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write("".join(traceback.format_exception(exc)))
    except OSError:
        return None
    return Path(path)


def bug_message(exc, saved=None, printed=False):
    """The one line reporting ``exc`` as a bug, text shortened.

    It says where the traceback is: ``printed`` above, else in the file
    ``saved``, else (it could not be saved) how to see it.
    """
    text = str(exc)
    if len(text) > _SHOWN:
        text = text[:_SHOWN] + f"... ({len(text)} characters)"
    where = ("traceback above" if printed else f"traceback saved in {saved}" if saved
             else "run again with --debug for the traceback")
    return (f"internal error (this is a bug in trajcomp, please report it with the traceback): "
            f"{type(exc).__name__}: {text}; {where}")
