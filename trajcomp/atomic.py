"""Atomic file output: write to a temporary file beside the target, then rename."""

import os
import tempfile
from pathlib import Path

from trajcomp.errors import WriteError


def write_atomic(path, data, *, newline=None, encoding="utf-8"):
    """Write ``data`` to ``path`` so that the file is either complete or untouched.

    Parameters
    ----------
    path : str or Path
        Destination. An existing file is replaced only once the new content is
        fully on disk.
    data : str or bytes
        Content. ``str`` is encoded with ``encoding``; ``newline`` is passed to
        the text layer (``""`` keeps the line endings that ``data`` holds).

    Raises
    ------
    WriteError
        If the folder does not exist or the file cannot be written.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise WriteError(f"{path}: folder {folder} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise WriteError(f"{path}: cannot write: {exc.strerror}") from exc
    try:
        if isinstance(data, bytes):
            with os.fdopen(fd, "wb") as handle:
                handle.write(data)
        else:
            with os.fdopen(fd, "w", encoding=encoding, newline=newline) as handle:
                handle.write(data)
        os.replace(tmp, path)
    except (OSError, UnicodeError) as exc:
        Path(tmp).unlink(missing_ok=True)
        raise WriteError(f"{path}: cannot write: {exc}") from exc
