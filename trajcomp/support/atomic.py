"""Atomic file output: every file complete or untouched, a set of files all or none.

Content is written to temporary files beside the targets (``.NAME.XXXX.tmp``),
flushed to the disk (fsync) and renamed into place; the folder is flushed
after the renames. Replaced files keep their permission bits; new files get
the usual mode for the user's umask (not the 0600 of a bare temporary file).

A set of several files (a KRL ``.src`` and its ``.dat``, a model and its
grid sidecar, a program and its report) is committed through a journal: once
every temporary is complete on disk, a journal naming each rename is written
(``.trajcomp-commit.XXXX.json``, itself written whole and renamed into
place), then the temporaries are renamed, then the journal removed. A run
killed between two renames (a power cut, an OOM kill, SIGKILL) leaves the
journal behind, and the next trajcomp run that writes into or reads from
that folder rolls the set forward: the renames still to do are done, so the
set on disk is the new one whole, never the new ``.src`` with the old
``.dat``. Rolling forward rather than back needs no copy of the old files
and always works, since every new file was complete before the first
rename. (A rename that fails with an error, rather than a kill, puts the
replaced files back from hard-link backups: the set is then the old one.)

Runs writing into the same folder commit one after the other (an exclusive
``flock`` on the folder while its journals are rolled forward, strays
removed and a set renamed), so two runs writing the same KRL output leave
one run's pair, not a ``.src`` of one and the ``.dat`` of the other. A
temporary is locked by the run that writes it until it is renamed; one
that nobody holds is a stray of a killed run, removed by the next run
writing that file.
"""

import contextlib
import errno
import hashlib
import json
import os
import shutil
import stat
import tempfile
import time
from pathlib import Path

from trajcomp.errors import WriteError
from trajcomp.support import signals

try:
    import fcntl
except ImportError:  # not POSIX: no locks (one run at a time per folder is then the user's to ensure)
    fcntl = None

JOURNAL_PREFIX = ".trajcomp-commit."
_NO_LOCKS = (errno.ENOLCK, errno.EOPNOTSUPP, errno.EINVAL)  # a file system without flock: write unlocked
_STRAY_AGE = 10.0  # s: a temporary younger than this may be one another run has created but not yet locked


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

    Every content is first written to a temporary file beside its target
    and flushed to the disk; only when all are there are they renamed into
    place, through a journal (see the module's docstring), under a lock on
    each folder. If a rename fails, the files already replaced are restored
    from backups and the new ones removed, so a KRL ``.src`` never lands
    without its ``.dat`` nor a model YAML without its grid sidecar; if the
    run is killed between renames, the next run completes them.

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
    with FileSet() as outputs:
        outputs.stage(files, protect=protect, advice=advice)


class FileSet:
    """Files staged one group after another and committed as one set at the end of the block, all or none.

    For outputs that must not be told apart by a kill or a concurrent run,
    and whose later files depend on the earlier ones: a program and its
    report, which names the program's SHA-256 (`digest`). Each `stage`
    writes its files to temporaries (`write_files_atomic`); leaving the
    block normally renames every staged file into place in one commit;
    leaving it by an exception removes them, nothing on disk changed.
    """

    def __init__(self):
        self._staged, self._digests, self._holds = {}, {}, []

    def stage(self, files, *, protect=(), advice="write to another file"):
        """Write ``files`` to temporaries, to be committed with the set; all of them or, on an error, none.

        Parameters as `write_files_atomic`'s.

        Raises
        ------
        WriteError
            A folder does not exist, a file cannot be written, is an input,
            or is staged already; the set's other files stay staged.
        """
        files = {Path(path): data for path, data in files.items()}
        refuse_inputs(files, protect, advice)
        for path in files:
            if path in self._staged:
                raise WriteError(f"{path}: written twice in one set of outputs; {advice}")
            if path.is_dir():  # found now, not when the set's renames fail
                raise WriteError(f"{path}: is a folder; {advice}")
        staged = {}
        try:
            for path, data in files.items():
                staged[path], hold, self._digests[path] = _stage(path, data)
                self._holds.append(hold)
        except BaseException:
            for tmp in staged.values():
                Path(tmp).unlink(missing_ok=True)
            raise
        self._staged.update(staged)
        return list(files)

    def digest(self, path):
        """``(SHA-256 hex, bytes)`` of a staged file's content."""
        return self._digests[Path(path)], os.stat(self._staged[Path(path)]).st_size

    def __enter__(self):
        return self

    def __exit__(self, kind, error, trace):
        try:
            if error is None and self._staged:
                signals.check()  # a stop whose exception was lost on the way commits nothing
                with signals.held(), _locked_folders(self._staged):  # a stopping signal: after the commit and
                    for folder in _folders(self._staged):  # the unlock (no backup, journal or locked folder left)
                        recover(folder, names=[p.name for p in self._staged if _folders([p]) == [folder]])
                    _commit(self._staged, self._digests)
        except BaseException:
            self._remove()
            raise
        finally:
            if error is not None:
                self._remove()
            for hold in self._holds:
                os.close(hold)
        return False

    def _remove(self):
        for tmp in self._staged.values():
            Path(tmp).unlink(missing_ok=True)


def recover(folder, names=()):
    """Roll forward the commits a killed run left in ``folder``, and remove the strays of files ``names``.

    A journal's renames still to do are done (their temporaries are
    complete: the journal is written only once they are), then the journal
    and the backups it names are removed (a journal cut off before it was
    complete names no rename yet done: it is removed). A temporary ``.NAME.XXXX.tmp``
    (or its ``.bak``) of one of ``names`` that no run holds locked, older
    than 10 s (a run locks its temporary just after creating it), is a
    stray of a killed run and removed. The caller holds the folder's lock
    (`write_files_atomic`), or takes it here.

    Parameters
    ----------
    folder : str or Path
    names : sequence of str
        File names whose strays to remove.

    Raises
    ------
    WriteError
        A rename of the roll-forward fails (the journal stays for the next run).
    """
    folder = Path(folder)
    try:
        journals = sorted(folder.glob(JOURNAL_PREFIX + "*.json*"))
    except OSError:
        return
    if not journals and not names:
        return
    with _locked_folders([folder / "lock"]):
        for journal in journals:
            if journal.suffix == ".json":
                _roll_forward(journal, names)
            else:  # a journal being written when its run was killed: the commit never started
                journal.unlink(missing_ok=True)
        for name in names:
            for stray in folder.glob(f".{_glob_escape(name)}.*.tmp*"):
                if stray.suffix in (".tmp", ".bak") and _unheld(stray) and _age(stray) > _STRAY_AGE:
                    stray.unlink(missing_ok=True)


def _roll_forward(journal, names=()):
    """Do the renames a journal names that are still to do, then remove it and its backups.

    Its paths are taken relative to its folder. A file whose new version
    (its temporary) is gone and which is not that version (its SHA-256
    differs: the folder was copied without the temporaries, or a file was
    replaced since) leaves the set torn: refused, unless every file of the
    set is among ``names``, which the run is writing anew.

    Raises
    ------
    WriteError
        The journal cannot be read, a rename fails, or the set is torn.
    """
    try:
        entries = json.loads(journal.read_text(encoding="utf-8"))
        here = journal.parent
        renames = [(here / tmp, here / target, *digest) for tmp, target, *digest in entries["renames"]]
        backups = [here / backup for backup in entries["backups"]]
    except FileNotFoundError:  # another run rolled it forward meanwhile
        return
    except (OSError, ValueError, TypeError, KeyError) as exc:
        raise WriteError(f"{journal}: an interrupted commit's journal cannot be read: {exc}") from exc
    torn = [target for tmp, target, *digest in renames if not tmp.exists() and digest and _sha256(target) != digest[0]]
    if torn and not {target.name for _, target, *_ in renames} <= set(names):
        raise WriteError(
            f"{journal}: a set of files a run was stopped while committing is torn: {', '.join(map(str, torn))} "
            "is not the file that run wrote, and its new version is gone (the folder copied or moved without "
            "it?); write the set again, or restore it, then remove the journal")
    try:
        for tmp, target, *_ in renames:
            if tmp.exists():
                os.replace(tmp, target)
        _sync_folders(target for _, target, *_ in renames)
        for backup in backups:
            backup.unlink(missing_ok=True)
        journal.unlink()
    except OSError as exc:
        raise WriteError(f"{journal}: cannot complete an interrupted commit: {exc}") from exc
    _sync_folders([journal])


def sha256_of(path):
    """The SHA-256 (hex) of a file's content, read a MiB at a time (OSError when it cannot be read)."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _sha256(path):
    """`sha256_of`, or None when the file cannot be read."""
    try:
        return sha256_of(path)
    except OSError:
        return None


def _glob_escape(name):
    """``name`` with the glob's special characters taken literally."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in name)


def _unheld(path):
    """Whether no process holds ``path`` locked (a temporary being written is); True on a system without locks."""
    if fcntl is None:
        return False  # cannot tell: keep it
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except OSError:
        return False
    finally:
        os.close(fd)


def _age(path):
    """Seconds since ``path`` was last modified (0 if it is gone)."""
    try:
        return time.time() - os.stat(path).st_mtime
    except OSError:
        return 0.0


def _folder(path):
    return path.parent if str(path.parent) else Path(".")


def _folders(paths):
    """The distinct folders of ``paths`` (absolute), in sorted order (locks are taken in it: no deadlock)."""
    return sorted({Path(os.path.abspath(_folder(Path(p)))) for p in paths})


_HELD = {}  # folder -> its locked descriptor, while this process commits there


@contextlib.contextmanager
def _locked_folders(paths):
    """An exclusive lock on the folder of each of ``paths`` for the block (none where locks do not exist)."""
    taken = []
    try:
        for folder in _folders(paths):
            if folder in _HELD or fcntl is None or not folder.is_dir():
                continue
            try:
                fd = os.open(folder, os.O_RDONLY)
            except OSError as exc:
                raise WriteError(f"{folder}: cannot lock the folder to write into it: {exc}") from exc
            _HELD[folder] = fd
            taken.append(folder)
            _lock(fd, folder)
        yield
    finally:
        for folder in taken:
            os.close(_HELD.pop(folder))  # closing releases the lock


def _lock(fd, path):
    """An exclusive flock on ``fd`` (waiting for it); none on a file system without locks."""
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
    except OSError as exc:
        if exc.errno not in _NO_LOCKS:
            raise WriteError(f"{path}: cannot lock it to write: {exc}") from exc


def _stage(path, data):
    """A temporary file beside ``path`` holding ``data``, flushed to disk, with ``path``'s mode.

    Returns its name, an open descriptor holding it locked (close it once
    the temporary is renamed or removed) and the SHA-256 of ``data`` (hex).
    """
    folder = _folder(path)
    if not folder.is_dir():
        raise WriteError(f"{path}: folder {folder} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise WriteError(f"{path}: cannot write: {exc.strerror}") from exc
    try:
        if fcntl is not None:
            _lock(fd, path)
        hold = os.dup(fd)  # shares the lock, held after the file is closed
    except (OSError, WriteError) as exc:
        os.close(fd)
        Path(tmp).unlink(missing_ok=True)
        raise WriteError(f"{path}: cannot write: {exc}") from exc
    try:
        digest = hashlib.sha256()
        with os.fdopen(fd, "wb") as handle:
            for piece in [data] if isinstance(data, (bytes, bytearray, memoryview)) else data:
                digest.update(piece)
                handle.write(piece)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(tmp, _mode_for(path))
    except OSError as exc:
        os.close(hold)
        Path(tmp).unlink(missing_ok=True)
        raise WriteError(f"{path}: cannot write: {exc}") from exc
    except BaseException:  # the content's generator failed: no temporary left behind
        os.close(hold)
        Path(tmp).unlink(missing_ok=True)
        raise
    return tmp, hold, digest.hexdigest()


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


def _sync_folders(paths):
    """Flush the folders of ``paths`` to disk (their renames and new names); where a folder cannot be, skip."""
    for folder in _folders(paths):
        try:
            fd = os.open(folder, os.O_RDONLY)
        except OSError:
            continue
        try:
            os.fsync(fd)
        except OSError:  # a file system without folder fsync
            pass
        finally:
            os.close(fd)


def _write_journal(staged, backups, digests):
    """Write the journal of a commit beside its first file, whole (temporary, fsync, rename); its path.

    It names each rename (temporary, file, the new content's SHA-256) and
    each backup by its path relative to the journal's folder, so that the
    folder moved or copied with its journal still rolls forward its own
    files, and a file that is not the new one is told apart (`_roll_forward`).
    """
    first = next(iter(staged))
    here = os.path.abspath(_folder(first))
    entries = {"renames": [[os.path.relpath(tmp, here), os.path.relpath(path, here), digests[path]]
                           for path, tmp in staged.items()],
               "backups": [os.path.relpath(b, here) for b in backups.values()]}
    fd, tmp = tempfile.mkstemp(prefix=JOURNAL_PREFIX, suffix=".json.tmp", dir=_folder(first))
    journal = Path(tmp[: -len(".tmp")])
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            json.dump(entries, handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, journal)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    _sync_folders([journal])
    return journal


def _commit(staged, digests):
    """Rename staged temporaries into place (through a journal for several, naming their ``digests``); on failure
    put every replaced file back."""
    backups, done, journal, path = {}, [], None, None
    try:
        for path in staged:
            if path.exists():
                backups[path] = _backup(path, f"{staged[path]}.bak")
        if len(staged) > 1:
            journal = _write_journal(staged, backups, digests)
        for path, tmp in staged.items():
            os.replace(tmp, path)
            done.append(path)
        _sync_folders(staged)
    except OSError as exc:
        try:
            for put_back in done:
                if put_back in backups:
                    os.replace(backups.pop(put_back), put_back)
                else:
                    put_back.unlink(missing_ok=True)
        except OSError as undo:
            raise WriteError(f"{path}: cannot write: {exc}; putting the replaced files back failed too ({undo}): "
                             f"{', '.join(map(str, done))} may be new, the other files old") from exc
        raise WriteError(f"{path}: cannot write: {exc}") from exc
    finally:
        for backup in backups.values():
            Path(backup).unlink(missing_ok=True)
        if journal is not None:
            journal.unlink(missing_ok=True)
