"""Atomic output: one file complete or untouched, several files all or none, modes kept."""

import os
import stat

import pytest

from trajcomp import atomic
from trajcomp.atomic import write_atomic, write_files_atomic
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
