"""Every golden program, every format: read then write gives the same bytes.

One shared helper (meshio style) runs over every file in
tests/data/programs/ (the .dat of a KRL program travels with its .src), in
its stored line endings and with them swapped (LF, CRLF, CR alone), and checks that
a compensation-like edit (a known rigid shift of every Cartesian target)
changes only the lines holding those targets' numbers.
"""

import re
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.support import atomic
from trajcomp.errors import WriteError

DATA = Path(__file__).parents[1] / "data" / "programs"
PROGRAMS = sorted(
    p for p in DATA.rglob("*") if p.is_file() and p.suffix.lower() not in (".dat", ".txt", ".va")
)


RAPID_MODULES = {".mod", ".modx", ".sys", ".prg"}


def companions(path):
    """The program file and the files read with it (a KRL .dat, the data lists and $config.dat beside it whose
    points it uses, the other modules of a RAPID task's folder, a FANUC backup's POSREG.VA and the other
    programs beside it, which may set its registers)."""
    read_with = {Path(source.path).name for source in formats.read(path).sources[1:]}
    suffix = path.suffix.lower()
    task = RAPID_MODULES if suffix in RAPID_MODULES else {".ls"} if suffix == ".ls" and read_with else set()
    return [path] + [p for p in path.parent.iterdir() if p != path and (
        p.name in read_with or p.suffix.lower() in task)]


def copy_program(path, folder, newline=None):
    """Copy a program (with its companions) to ``folder``, optionally converting line endings."""
    for file in companions(path):
        data = file.read_bytes()
        if newline is not None:
            data = data.replace(b"\r\n", b"\n").replace(b"\n", newline)
        (folder / file.name).write_bytes(data)
    return folder / path.name


def write_then_read(program, out, source=None):
    """Write ``program`` to ``out`` and read it back (the shared round-trip helper).

    The files read with ``source`` (the other modules of a RAPID task) are put beside ``out`` first.
    """
    for file in companions(source)[1:] if source is not None else ():
        if not (file.suffix.lower() == ".dat" and file.stem.lower() == source.stem.lower()):  # written with it
            (out.parent / file.name).write_bytes(file.read_bytes())
    formats.write(out, program)
    return formats.read(out)


def test_there_is_a_golden_program_per_format():
    found = {formats.find_format(p).name for p in PROGRAMS}
    assert found == {"csv", "krl", "rapid", "fanuc_ls", "urscript"}


@pytest.mark.parametrize("newline", [None, b"\n", b"\r\n", b"\r"], ids=["stored", "lf", "crlf", "cr"])
@pytest.mark.parametrize("path", PROGRAMS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_unchanged_program_writes_back_byte_for_byte(path, newline, tmp_path):
    (tmp_path / "in").mkdir()
    (tmp_path / "out").mkdir()
    source = copy_program(path, tmp_path / "in", newline)
    program = formats.read(source)
    again = write_then_read(program, tmp_path / "out" / source.name, source)
    for file in companions(source):
        assert (tmp_path / "out" / file.name).read_bytes() == file.read_bytes(), file.name
    assert len(again.targets) == len(program.targets)
    for a, b in zip(program.targets, again.targets):
        if a.pose is not None:
            np.testing.assert_allclose(a.pose, b.pose, atol=1e-9)
        if a.joints is not None:
            np.testing.assert_allclose(a.joints, b.joints, atol=1e-12)


_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _lines(folder, path):
    return {file.name: file.read_bytes().decode("latin-1").splitlines() for file in companions(folder / path.name)}


def _line_of(text, offset):
    return len(text[:offset].splitlines()) if offset else 1


@pytest.mark.parametrize("newline", [None, b"\r"], ids=["stored", "cr"])
@pytest.mark.parametrize("path", PROGRAMS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_rigid_shift_changes_only_the_compensated_numbers(path, newline, tmp_path):
    """With the line endings as stored and as a carriage return alone (read as lines, kept on write: a CR-only
    KRL or RAPID file was refused as cut off before)."""
    shift = np.array([0.5, -0.25, 0.125])
    (tmp_path / "in").mkdir()
    path = copy_program(path, tmp_path / "in", newline)
    program = formats.read(path)
    stack = program.cartesian_targets()
    moved = stack.T.copy()
    moved[:, :3, 3] += shift
    again = write_then_read(program.with_targets(stack.index, poses=moved), tmp_path / path.name, path)

    allowed = {
        (program.sources[span.source].name, _line_of(program.sources[span.source].text, span.start + 1))
        for i in stack.index
        for span in program.targets[i].spans.values()
    } | {(program.sources[0].name, program.targets[i].line) for i in stack.index if not program.targets[i].spans}
    after = _lines(tmp_path, path)
    if newline == b"\r":
        assert not any(b"\n" in file.read_bytes() for file in companions(tmp_path / path.name))
    for name, old_lines in _lines(path.parent, path).items():
        new_lines = after[name]
        assert len(new_lines) == len(old_lines), name
        for number, (old, new) in enumerate(zip(old_lines, new_lines), start=1):
            if old != new:
                assert (name, number) in allowed, f"{name}:{number} changed: {old!r} -> {new!r}"
                assert _NUMBER.sub("#", old) == _NUMBER.sub("#", new), "only numbers may change"

    again_stack = again.cartesian_targets()
    assert list(again_stack.names) == list(stack.names)
    np.testing.assert_allclose(again_stack.T[:, :3, 3], moved[:, :3, 3], atol=1e-6)
    np.testing.assert_allclose(again_stack.T[:, :3, :3], moved[:, :3, :3], atol=1e-6)


def test_latin1_krl_program_round_trips(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    copy = copy_program(DATA / "krl" / "weld.src", folder)
    text = copy.read_bytes().replace(b";This is", "; Schwei\u00dfnaht f\u00fcr B\u00f6den:".encode("latin-1"))
    copy.write_bytes(text)
    program = formats.read(copy)
    assert program.sources[0].encoding == "latin-1"
    formats.write(tmp_path / "weld.src", program)
    assert (tmp_path / "weld.src").read_bytes() == text


def test_existing_output_is_untouched_when_writing_fails(tmp_path, monkeypatch):
    program = formats.read(DATA / "csv" / "path.csv")
    out = tmp_path / "out.csv"
    out.write_bytes(b"precious\n")

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(atomic.os, "replace", broken)
    with pytest.raises(WriteError):
        formats.write(out, program)
    assert out.read_bytes() == b"precious\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]
