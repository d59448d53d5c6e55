"""Atomic file output: every file complete or untouched, a set of files all or none.

Content is written to temporary files beside the targets and renamed into
place. Replaced files keep their permission bits; new files get the usual
mode for the user's umask (not the 0600 of a bare temporary file).
"""

import os
import shutil
import stat
import tempfile
from pathlib import Path

from trajcomp.errors import WriteError


def refuse_inputs(outputs, inputs, advice="write to another file"):
    """Refuse outputs that are one of the inputs, or each other.

    A file is the same whatever its name: the same path, a symbolic link to
    it or a hard link to it (same device and inode).

    Parameters
    ----------
    outputs : iterable of str or Path
        Files about to be written.
    inputs : iterable of str or Path or None
        Files the run reads, which must come out untouched (None, and files
        that do not exist, are ignored).
    advice : str
        What the user can do instead, ending the message.

    Raises
    ------
    WriteError
        Naming the output and the input (or the other output) it is.
    """
    kept = {_identity(path): path for path in map(Path, filter(None, inputs)) if path.exists()}
    seen = {}
    for out in map(Path, outputs):
        key = _identity(out)
        if key in kept:
            same = "" if Path(kept[key]) == out else f" ({kept[key]})"
            raise WriteError(f"{out}: would overwrite the input{same}; {advice}")
        if key in seen:
            raise WriteError(f"{out}: written twice in one run (also as {seen[key]}); {advice}")
        seen[key] = out


def _identity(path):
    """What tells files apart: (device, inode) of an existing file, else its absolute path."""
    try:
        found = os.stat(path)
    except OSError:
        return os.path.abspath(path)
    return found.st_dev, found.st_ino


def write_atomic(path, data, *, newline=None, encoding="utf-8", protect=(), advice="write to another file"):
    """Write ``data`` to ``path`` so that the file is either complete or untouched.

    Parameters
    ----------
    path : str or Path
        Destination. An existing file is replaced only once the new content is
        fully on disk.
    data : str or bytes
        Content. ``str`` is encoded with ``encoding``; ``newline`` (``None``:
        ``"\\n"`` becomes the platform line ending, ``""`` keeps the line
        endings ``data`` holds) applies to ``str`` only.
    protect : sequence of str or Path
        Inputs ``path`` must not be (`refuse_inputs`, ``advice`` ending its message).

    Raises
    ------
    WriteError
        If the folder does not exist, the file cannot be written or is an input.
    """
    if isinstance(data, str):
        if newline is None:
            data = data.replace("\n", os.linesep)
        elif newline:
            data = data.replace("\n", newline)
        try:
            data = data.encode(encoding)
        except UnicodeError as exc:
            raise WriteError(f"{path}: cannot write: {exc}") from exc
    write_files_atomic({path: data}, protect=protect, advice=advice)


def write_files_atomic(files, *, protect=(), advice="write to another file"):
    """Write several files all or none.

    Every content is first written to a temporary file beside its target;
    only when all are on disk are they renamed into place. If a rename
    fails, the files already replaced are restored from backups and the
    new ones removed, so a KRL ``.src`` never lands without its ``.dat``
    nor a model YAML without its grid sidecar.

    Parameters
    ----------
    files : Mapping[str or Path, bytes or iterable of bytes]
        Destination paths and their content. An iterable (a list, a
        generator) gives pieces written in order as they come, for a long
        file that is never held in memory whole; an exception it raises
        (a WriteError while the content is made) leaves every file
        untouched, like a failed write.
    protect : sequence of str or Path
        Inputs none of the files may be (`refuse_inputs`, which ends its
        message with ``advice``).

    Raises
    ------
    WriteError
        A folder does not exist, a file cannot be written or is an input;
        nothing on disk has changed.
    """
    files = {Path(path): data for path, data in files.items()}
    refuse_inputs(files, protect, advice)
    staged = {}
    try:
        for path, data in files.items():
            staged[path] = _stage(path, data)
        _commit(staged)
    except BaseException:
        for tmp in staged.values():
            Path(tmp).unlink(missing_ok=True)
        raise


def _stage(path, data):
    """A temporary file beside ``path`` holding ``data``, with ``path``'s mode; its name."""
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise WriteError(f"{path}: folder {folder} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise WriteError(f"{path}: cannot write: {exc.strerror}") from exc
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.writelines([data] if isinstance(data, (bytes, bytearray, memoryview)) else data)
        os.chmod(tmp, _mode_for(path))
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise WriteError(f"{path}: cannot write: {exc}") from exc
    except BaseException:  # the content's generator failed: no temporary left behind
        Path(tmp).unlink(missing_ok=True)
        raise
    return tmp


def _mode_for(path):
    """Permission bits for ``path``: those of the file it replaces, else 0666 less the umask."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _backup(path, backup):
    """A copy of ``path`` at ``backup`` (a hard link where the file system allows); ``backup``."""
    try:
        os.link(path, backup)
    except OSError:
        shutil.copy2(path, backup)
    return backup


def _commit(staged):
    """Rename staged temporaries into place; on failure put every replaced file back."""
    backups, done = {}, []
    try:
        for path in staged:
            if path.exists():
                backups[path] = _backup(path, f"{staged[path]}.bak")
        for path, tmp in staged.items():
            os.replace(tmp, path)
            done.append(path)
    except OSError as exc:
        for path in done:
            if path in backups:
                os.replace(backups.pop(path), path)
            else:
                path.unlink(missing_ok=True)
        raise WriteError(f"{path}: cannot write: {exc}") from exc
    finally:
        for backup in backups.values():
            Path(backup).unlink(missing_ok=True)
