"""Atomic output: one file complete or untouched, several files all or none, modes kept."""

import os
import stat

import pytest

from trajcomp.support import atomic
from trajcomp.support.atomic import write_atomic, write_files_atomic
from trajcomp.errors import WriteError


def mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


def test_replaced_file_keeps_its_permission_bits(tmp_path):
    out = tmp_path / "prog.src"
    out.write_text("old\n")
    out.chmod(0o640)
    write_atomic(out, "new\n")
    assert out.read_text() == "new\n"
    assert mode(out) == 0o640


def test_new_file_gets_the_umask_mode_not_0600(tmp_path):
    old = os.umask(0o022)
    try:
        write_atomic(tmp_path / "new.csv", b"x\n")
    finally:
        os.umask(old)
    assert mode(tmp_path / "new.csv") == 0o644


@pytest.fixture
def second_rename_fails(monkeypatch):
    """os.replace as atomic uses it, failing on its second call (the disk fills between two files)."""
    real_replace = os.replace
    calls = []

    def second_fails(a, b):
        calls.append(b)
        if len(calls) == 2:
            raise OSError("disk full")
        real_replace(a, b)

    monkeypatch.setattr(atomic.os, "replace", second_fails)
    yield
    monkeypatch.setattr(atomic.os, "replace", real_replace)


def test_files_land_all_or_none_when_a_rename_fails(tmp_path, second_rename_fails):
    src, dat = tmp_path / "weld.src", tmp_path / "weld.dat"
    src.write_bytes(b"old src")
    dat.write_bytes(b"old dat")
    with pytest.raises(WriteError, match="disk full"):
        write_files_atomic({src: b"new src", dat: b"new dat"})
    assert src.read_bytes() == b"old src"
    assert dat.read_bytes() == b"old dat"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["weld.dat", "weld.src"]


def test_a_new_file_is_removed_again_when_its_partner_fails(tmp_path, second_rename_fails):
    with pytest.raises(WriteError):
        write_files_atomic({tmp_path / "m.yaml": b"a", tmp_path / "m.npz": b"b"})
    assert list(tmp_path.iterdir()) == []


def test_missing_folder_writes_nothing(tmp_path):
    with pytest.raises(WriteError, match="does not exist"):
        write_files_atomic({tmp_path / "a.txt": b"a", tmp_path / "no" / "b.txt": b"b"})
    assert list(tmp_path.iterdir()) == []


def test_content_given_in_pieces_is_written_in_order(tmp_path):
    target = tmp_path / "long.csv"
    write_files_atomic({target: [b"x,y\n", b"1,2\n", b"3,4"]})
    assert target.read_bytes() == b"x,y\n1,2\n3,4"


def test_content_given_by_a_generator_is_written_as_it_comes(tmp_path):
    target = tmp_path / "long.csv"
    made = []

    def pieces():
        for piece in (b"x,y\n", b"1,2\n", b"3,4"):
            made.append(piece)
            yield piece

    content = pieces()
    assert not made  # nothing made before the write
    write_files_atomic({target: content})
    assert target.read_bytes() == b"x,y\n1,2\n3,4"


def test_a_failing_generator_leaves_every_file_untouched(tmp_path):
    first, second = tmp_path / "a.src", tmp_path / "a.dat"
    first.write_bytes(b"old src")

    def failing():
        yield b"new dat, part 1"
        raise WriteError("a.dat: cannot be written in latin-1")

    with pytest.raises(WriteError, match="latin-1"):
        write_files_atomic({first: (p for p in [b"new src"]), second: failing()})
    assert first.read_bytes() == b"old src"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.src"]


STEPS = ("open", "fsync", "chmod", "link", "replace", "unlink", "close")  # the file-system calls of a commit


def _count_steps(monkeypatch, on_step):
    """Route the file-system calls a commit makes through ``on_step(name)`` first."""
    for name in STEPS:
        real = getattr(os, name)

        def counted(*args, _real=real, _name=name, **kwargs):
            on_step(_name)
            return _real(*args, **kwargs)

        monkeypatch.setattr(os, name, counted)


def _krl_set(folder, version):
    return {folder / "weld.src": f"DEF weld( )\n  PTP P1 ; {version}\nEND\n".encode(),
            folder / "weld.dat": f"DEFDAT weld\nDECL E6POS P1={{X {version}}}\nENDDAT\n".encode()}


def test_a_kill_before_any_step_of_a_commit_leaves_a_set_that_loads_whole(tmp_path, monkeypatch):
    """Fault injection: the run dies (os._exit, no clean-up) before its k-th file-system call, for every k."""
    import signal

    steps = []
    with monkeypatch.context() as counting:
        _count_steps(counting, steps.append)
        write_files_atomic(_krl_set(tmp_path, 1))
        count = len(steps)
        write_files_atomic(_krl_set(tmp_path, 1))
        count = len(steps) - count  # the calls of one commit over an existing set
    assert count >= 10
    outcomes = {"old": 0, "new": 0}
    for k in range(count + 1):
        for path, data in _krl_set(tmp_path, 1).items():
            path.write_bytes(data)
        pid = os.fork()
        if pid == 0:  # the run that is killed
            calls = []

            def die(name):
                calls.append(name)
                if len(calls) > k:
                    os.kill(os.getpid(), signal.SIGKILL)

            _count_steps(monkeypatch, die)
            write_files_atomic(_krl_set(tmp_path, 2))
            os._exit(0)
        os.waitpid(pid, 0)
        for left in tmp_path.glob(".*"):
            os.utime(left, (0, 0))  # the next run comes later
        atomic.recover(tmp_path, names=["weld.src", "weld.dat"])  # what it does first
        texts = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
        assert sorted(texts) == ["weld.dat", "weld.src"], k  # no journal, temporary or backup left
        versions = {b"1" if b" 1" in text or b"X 1}" in text else b"2" for text in texts.values()}
        assert len(versions) == 1, f"torn set after a kill before step {k}: {texts}"
        outcomes["old" if versions == {b"1"} else "new"] += 1
    assert outcomes["old"] > 0 and outcomes["new"] > 0


def test_an_error_at_any_step_of_a_commit_leaves_the_old_set_and_no_stray(tmp_path, monkeypatch):
    for k in range(40):
        for path, data in _krl_set(tmp_path, 1).items():
            path.write_bytes(data)
        calls = []

        def fail(name):
            calls.append(name)
            if len(calls) == k + 1 and name in ("open", "fsync", "link", "replace"):
                raise OSError(28, "No space left on device")

        with monkeypatch.context() as failing:
            _count_steps(failing, fail)
            try:
                write_files_atomic(_krl_set(tmp_path, 2))
                new = True
            except WriteError:
                new = False
        texts = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
        assert texts == {p.name: d for p, d in _krl_set(tmp_path, 2 if new else 1).items()}, k


def test_concurrent_runs_writing_one_set_leave_one_runs_set_whole(tmp_path):
    pids = []
    for version in range(2, 7):
        pid = os.fork()
        if pid == 0:
            for _ in range(10):
                write_files_atomic(_krl_set(tmp_path, version))
            os._exit(0)
        pids.append(pid)
    for pid in pids:
        assert os.waitpid(pid, 0)[1] == 0
    src, dat = (tmp_path / "weld.src").read_text(), (tmp_path / "weld.dat").read_text()
    assert src.split("; ")[1].split()[0] == dat.split("X ")[1].split("}")[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["weld.dat", "weld.src"]


def test_strays_of_a_killed_run_are_removed_by_the_next_run_but_not_those_being_written(tmp_path):
    (tmp_path / ".weld.src.abc123.tmp").write_bytes(b"")  # left by a killed run
    (tmp_path / ".weld.src.def456.tmp.bak").write_bytes(b"old")
    (tmp_path / ".other.txt.xyz.tmp").write_bytes(b"")  # not a file this run writes: left alone
    (tmp_path / ".weld.src.fresh1.tmp").write_bytes(b"")  # just created by another run, not yet locked
    for stray in (".weld.src.abc123.tmp", ".weld.src.def456.tmp.bak", ".other.txt.xyz.tmp"):
        os.utime(tmp_path / stray, (0, 0))
    write_atomic(tmp_path / "weld.src", b"new\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == [".other.txt.xyz.tmp", ".weld.src.fresh1.tmp", "weld.src"]


def test_a_file_system_without_locks_is_written_unlocked(tmp_path, monkeypatch):
    import errno

    def no_locks(fd, operation):
        raise OSError(errno.ENOLCK, "No locks available")

    monkeypatch.setattr(atomic.fcntl, "flock", no_locks)
    write_files_atomic(_krl_set(tmp_path, 3))
    assert (tmp_path / "weld.dat").read_text().endswith("{X 3}\nENDDAT\n")


def _torn(folder, monkeypatch):
    """A KRL pair at version 1, then a run writing version 2 killed between its two renames (journal left)."""
    import signal

    for path, data in _krl_set(folder, 1).items():
        path.write_bytes(data)
    pid = os.fork()
    if pid == 0:
        real, calls = os.replace, []

        def replace(*args, **kwargs):
            calls.append(args)
            if len(calls) == 3:  # the journal's, the .src's, then this, the .dat's
                os.kill(os.getpid(), signal.SIGKILL)
            return real(*args, **kwargs)

        monkeypatch.setattr(os, "replace", replace)
        write_files_atomic(_krl_set(folder, 2))
        os._exit(0)
    os.waitpid(pid, 0)
    assert b"; 2" in (folder / "weld.src").read_bytes() and b"X 1}" in (folder / "weld.dat").read_bytes()
    assert list(folder.glob(".trajcomp-commit.*.json"))


@pytest.mark.parametrize("how", ["mv", "cp -a"])
def test_a_torn_pair_moved_or_copied_with_its_journal_is_completed_where_it_now_lies(tmp_path, monkeypatch, how):
    import shutil
    import subprocess

    out, moved = tmp_path / "out", tmp_path / "moved"
    out.mkdir()
    _torn(out, monkeypatch)
    subprocess.run([*how.split(), str(out), str(moved)], check=True)
    atomic.recover(moved)  # what reading moved/weld.src does first
    assert sorted(p.name for p in moved.iterdir()) == ["weld.dat", "weld.src"]
    assert {p.name: p.read_bytes() for p in moved.iterdir()} == {p.name: d for p, d in _krl_set(moved, 2).items()}
    if how == "cp -a":  # the original is its own: still torn, its journal there for its own recovery
        assert b"X 1}" in (out / "weld.dat").read_bytes() and list(out.glob(".trajcomp-commit.*.json"))
    shutil.rmtree(out, ignore_errors=True)


def test_a_torn_pair_whose_new_file_is_gone_is_refused_and_a_run_writing_it_anew_goes_on(tmp_path, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    _torn(out, monkeypatch)
    for stray in out.glob(".weld.dat.*.tmp"):  # copied without the hidden temporaries
        stray.unlink()
    with pytest.raises(WriteError, match="torn: .*weld.dat is not the file that run wrote"):
        atomic.recover(out)
    write_files_atomic(_krl_set(out, 3))  # the whole set written again: the journal goes with it
    assert {p.name: p.read_bytes() for p in out.iterdir()} == {p.name: d for p, d in _krl_set(out, 3).items()}


def test_a_stopping_signal_at_any_step_of_a_commit_leaves_a_whole_set_and_nothing_hidden(tmp_path, monkeypatch):
    """SIGTERM, raised as an exception, at each file-system call of a commit: the commit ends first, then the run
    stops; no backup, journal or temporary is left for the next run to clean."""
    import signal

    from trajcomp.support.signals import Interrupted, raised

    for k in range(30):
        for path, data in _krl_set(tmp_path, 1).items():
            path.write_bytes(data)
        calls = []

        def stop(name):
            calls.append(name)
            if len(calls) == k + 1:
                os.kill(os.getpid(), signal.SIGTERM)

        with monkeypatch.context() as stopping, raised():
            _count_steps(stopping, stop)
            try:
                write_files_atomic(_krl_set(tmp_path, 2))
            except Interrupted:
                pass
        texts = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
        assert sorted(texts) == ["weld.dat", "weld.src"], (k, sorted(texts))
        versions = {b"1" if b" 1" in text or b"X 1}" in text else b"2" for text in texts.values()}
        assert len(versions) == 1, k
