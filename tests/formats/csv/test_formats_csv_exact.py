"""The CSV writer's fast path (canonical columns formatted at once) against independent references.

A column whose cells are all canonical ``%.<d>f`` texts is written without
parsing any text back: these tests hold it to Python's own ``'%.<d>f' % v``
and ``float()`` round trips, and to the exact per-cell path, on tricky values.
"""

import re

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError
from trajcomp.formats.csv import reader as csv_reader, writer as csv_writer
from trajcomp.formats.csv.cells import _canonical
from trajcomp.formats.csv.writer import _UNKNOWN, _column
from trajcomp.formats.fixed_text import joined_rows

CANONICAL = re.compile(r"-?(?:0|[1-9][0-9]*)\.([0-9]+)")

TRICKY = [0.0, -0.0, 0.0005, -0.0005, 0.0004999, -0.0004999, 0.00049999999999999, 1e-7, -1e-7, 0.5, -0.5, 1.0005,
          2.675, -2.675, 1.0015, 0.125, 0.375, 999999.9995, -999999.9995, 123456.78949999, 1e-300, 5e-324,
          89.99999999999999, 90.0, -180.0, 179.99995, 0.1 + 0.2, 1 / 3, -2 / 3, 3600.0, 1e6, -1e6, 12345678901.234]


def reference_canonical(cells):
    """``(d, [float(cell)])`` by regular expression and float(), or None."""
    found = [CANONICAL.fullmatch(c) for c in cells]
    if not all(found) or len({len(m.group(1)) for m in found}) != 1:
        return None
    places = len(found[0].group(1))
    if any(c == "-0." + "0" * places for c in cells):
        return None
    return places, [float(c) for c in cells]


def texts(values, places):
    return ["%.*f" % (places, v) for v in values]


@pytest.mark.parametrize("places", [0, 1, 3, 4, 6, 9, 12, 15])
def test_canonical_columns_and_their_values_match_a_regex_and_float(places):
    rng = np.random.default_rng(places)
    values = np.concatenate([TRICKY, rng.normal(0, 10.0 ** rng.integers(-3, 6, 500)), rng.uniform(-1, 1, 200)])
    cells = [c for c in texts(values, places) if c != "-0." + "0" * places and len(c.lstrip("-")) <= 17]
    if places == 0:  # "%.0f" writes no point: never canonical
        assert _canonical(cells) is None
        return
    expected, got = reference_canonical(cells), _canonical(cells)
    assert got is not None and got[0] == expected[0]
    if got[1] is None:  # more than 15 digits: no values, a cell then goes the exact way
        assert max(len(c.lstrip("-")) - 1 for c in cells) > 15
    else:
        assert [float(v) for v in got[1]] == expected[1]
        assert np.array_equal(np.signbit(got[1]), np.signbit(expected[1]))


@pytest.mark.parametrize("cells", [
    ["1.000", "-0.000"], ["1.000", "01.000"], ["1.000", "+1.000"], ["1.000", ".500"], ["1.000", "-.500"],
    ["1.000", "1.00"], ["1.000", "1.0000"], ["1.000", "1e3"], ["1.000", "1.000e0"], ["1.000", " 1.000"],
    ["1.000", '"1.000"'], ["1.000", ""], ["1.000", "-"], ["1.000", "1-.000"], ["1.000", "1.0.0"], ["1", "2"],
    ["1.000", "1.5\t"], ["1.000", "١.000"], ["1.000", "--1.000"], ["1.000", "1."], ["1.000", "-0.0001"],
])
def test_non_canonical_columns_are_refused(cells):
    assert _canonical(cells) is None
    assert reference_canonical(cells) is None or reference_canonical(cells)[0] != 3


def written(cells, values, min_places, canonical=_UNKNOWN):
    """The cells a column gets (``_column`` rendered as the writer's rows render it)."""
    column = _column(cells, np.arange(len(cells)), np.asarray(values, dtype=float), min_places, canonical)
    return joined_rows([column]).split("\n")


def python_reference(old, value, places):
    """Python's own: ``'%.<p>f' % v`` (never -0), kept as the old text where float() reads both the same."""
    text = "%.*f" % (places, value)
    if float(text) == 0.0:
        text = text.lstrip("-")
    return old if float(text) == float(old) else text


@pytest.mark.parametrize("places, min_places", [(3, 3), (4, 4), (6, 3), (9, 9), (3, 4)])
def test_fast_path_writes_what_python_and_the_exact_path_write(places, min_places):
    rng = np.random.default_rng(places * 10 + min_places)
    old_values = np.concatenate([TRICKY, rng.normal(0, 500, 300)])
    old_values = old_values[np.abs(old_values) < 1e13 / 10.0**places]  # within the fast path's 15 digits
    old = texts(old_values, places)
    old = ["0." + "0" * places if c == "-0." + "0" * places else c for c in old]
    nudges = [0.0, 0.5 * 10.0**-places, -0.5 * 10.0**-places, 0.49999 * 10.0**-places, 1e-12, -1e-12, 10.0**-places]
    for nudge in nudges:
        new = np.array([float(c) for c in old]) + nudge
        fast = written(old, new, min_places)
        column = _column(old, np.arange(len(old)), new, min_places)
        assert (isinstance(column, tuple) and column[1] == places) == (places >= min_places)  # the fast path applies
        exact = written(old, new, min_places, canonical=None)  # the per-cell path, texts parsed back
        assert fast == exact
        p = max(places, min_places)
        for o, v, got in zip(old, new, fast):
            # np.round's zero (rint of v * 10**p) decides "never -0" for ties like -0.0005: both paths share it
            if abs(abs(v) * 10**p - 0.5) > 1e-6:
                assert got == python_reference(o, v, p)


def test_a_value_beyond_fifteen_digits_goes_the_exact_way():
    old = ["123456789012.3456", "1.0000"]
    new = [123456789012.34561, 2.0]
    assert written(old, new, 4) == written(old, new, 4, canonical=None) == ["123456789012.3456", "2.0000"]


def program_csv(tmp_path, rows, header="x,y,z,a,b,c,motion"):
    path = tmp_path / "in.csv"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def moved(path, out, dx):
    program = formats.read(path)
    stack = program.cartesian_targets()
    poses = stack.T.copy()
    poses[:, :3, 3] += dx
    formats.write(out, program.with_targets(stack.index, poses=poses))
    return out.read_text().splitlines()[1:]


@pytest.mark.parametrize("block", [1, 2, 50_000])
def test_columns_of_every_form_keep_their_cells_where_the_number_stays(tmp_path, monkeypatch, block):
    """Canonical, fewer decimals than the least written (kept), more decimals (kept as many), -0.000, quoted, spaced,
    an exponent: only the numbers that change are rewritten, in the column's decimals."""
    monkeypatch.setattr(csv_reader, "BLOCK", block)  # the blocks read
    monkeypatch.setattr(csv_writer, "BLOCK", block)  # and written
    rows = ["1.000,2.0,3.00000,0.0,0.0,0.0,LIN", "-0.000,2.5,-3.12345,0.0,0.0,0.0,LIN",
            '"4.000", 5.0 ,1e1,0.0,0.0,0.0,PTP', "7.250,8.0,9.00001,0.0,0.0,0.0,LIN"]
    path = program_csv(tmp_path, rows)
    assert moved(path, tmp_path / "same.csv", [0.0, 0.0, 0.0]) == rows
    assert moved(path, tmp_path / "out.csv", [0.0004, 1.0, 2e-5]) == [
        "1.000,3.000,3.00002,0.0,0.0,0.0,LIN", "-0.000,3.500,-3.12343,0.0,0.0,0.0,LIN",
        '"4.000", 6.000 ,1e1,0.0,0.0,0.0,PTP', "7.250,9.000,9.00003,0.0,0.0,0.0,LIN"]


@pytest.mark.parametrize("block", [1, 3, 50_000])
def test_a_file_with_a_byte_order_mark_gets_one_whatever_the_blocks(tmp_path, monkeypatch, block):
    monkeypatch.setattr(csv_reader, "BLOCK", block)  # the blocks read
    monkeypatch.setattr(csv_writer, "BLOCK", block)  # and written
    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbfx,y,z,a,b,c\n" + b"".join(b"%d.000,0.000,0.000,0.0,0.0,0.0\n" % k for k in range(7)))
    moved(path, tmp_path / "out.csv", [1.0, 0.0, 0.0])
    data = (tmp_path / "out.csv").read_bytes()
    assert data.startswith(b"\xef\xbb\xbfx,y,z") and data.count(b"\xef\xbb\xbf") == 1
    assert data.splitlines()[-1] == b"7.000,0.000,0.000,0.0,0.0,0.0"


@pytest.mark.parametrize("block", [1, 2, 50_000])
@pytest.mark.parametrize("ending", ["\n", "\r\n", "\r"])
def test_with_times_in_blocks_equals_one_block(tmp_path, monkeypatch, block, ending):
    from trajcomp.formats.csv.writer import with_times

    path = tmp_path / "p.csv"
    path.write_bytes(ending.join(["# c", "x,y,z,a,b,c", "1,2,3,4,5,6", "# between", "", "7,8,9,1,2,3",
                                  "4,5,6,7,8,9"]).encode() + ending.encode())
    formats.write(tmp_path / "one.csv", with_times(formats.read(path), np.array([0.0, 0.25, 1.0000000005])))
    expected = (tmp_path / "one.csv").read_bytes().decode()
    monkeypatch.setattr(csv_reader, "BLOCK", block)  # the blocks read
    monkeypatch.setattr(csv_writer, "BLOCK", block)  # and written
    formats.write(tmp_path / "blocks.csv", with_times(formats.read(path), np.array([0.0, 0.25, 1.0000000005])))
    assert (tmp_path / "blocks.csv").read_bytes().decode() == expected
    assert expected.split(ending)[1:3] == ["x,y,z,a,b,c,t", "1,2,3,4,5,6,0.000000000"]
    assert expected.split(ending)[6] in ("4,5,6,7,8,9,1.000000001", "4,5,6,7,8,9,1.000000000")


def test_times_go_before_the_joints_the_writer_appends_and_into_a_t_column_it_has(tmp_path):
    """As a compensated and re-timed program is written: j1..j6 after the new t column; an existing t in place."""
    from trajcomp.formats.csv.writer import with_times

    path = program_csv(tmp_path, ["1.000,2.000,3.000,0.0,0.0,0.0,LIN", "4.000,5.000,6.000,0.0,0.0,0.0,LIN"])
    program = formats.read(path)
    stack = program.cartesian_targets()
    edited = with_times(program.with_targets(stack.index, poses=stack.T, joints=np.zeros((2, 6))), [0.0, 1.5])
    formats.write(tmp_path / "out.csv", edited)
    assert (tmp_path / "out.csv").read_text().splitlines() == [
        "x,y,z,a,b,c,motion,t,j1,j2,j3,j4,j5,j6",
        "1.000,2.000,3.000,0.0,0.0,0.0,LIN,0.000000000,0.0000,0.0000,0.0000,0.0000,0.0000,0.0000",
        "4.000,5.000,6.000,0.0,0.0,0.0,LIN,1.500000000,0.0000,0.0000,0.0000,0.0000,0.0000,0.0000"]
    formats.write(tmp_path / "again.csv", with_times(formats.read(tmp_path / "out.csv"), [0.25, 2.0]))
    assert [line.split(",")[7] for line in (tmp_path / "again.csv").read_text().splitlines()] == [
        "t", "0.250000000", "2.000000000"]


@pytest.mark.parametrize("ending", ["\n", "\r\n"])
def test_two_processes_read_and_write_what_one_does(tmp_path, monkeypatch, ending):
    """Comments before the header, a byte order mark, quoted and spaced cells, joints appended: the blocks shared
    between processes give the same arrays and bytes, and a faulty row in a later block the same message."""
    monkeypatch.setattr(csv_reader, "BLOCK", 2)  # the blocks read
    monkeypatch.setattr(csv_writer, "BLOCK", 2)  # and written
    rows = ["# exported", "# by a CAM system", "x,y,z,a,b,c,motion,speed,zone"] + [
        f'{500 + k:.3f},{k / 7:.4f}, {300 - k:.2f} ,0.0,"90.0",0.0,{"LIN" if k % 3 else "PTP"},50,1' for k in range(11)]
    path = tmp_path / "in.csv"
    path.write_bytes(b"\xef\xbb\xbf" + ending.join(rows).encode() + ending.encode())
    one, two = formats.read(path, workers=1), formats.read(path, workers=2)
    for name in ("pose", "joints", "line"):
        np.testing.assert_array_equal(getattr(two.target_table(), name), getattr(one.target_table(), name))
    assert two.motion_table().kind.tolist() == one.motion_table().kind.tolist()
    stack = one.cartesian_targets()
    poses = stack.T.copy()
    poses[:, :3, 3] += [0.25, -0.5, 1.0]
    edited = one.with_targets(stack.index, poses=poses, joints=np.full((len(poses), 6), 0.5))
    for workers in (1, 2):
        formats.write(tmp_path / f"out{workers}.csv", edited, workers=workers)
    data = (tmp_path / "out2.csv").read_bytes()
    assert data == (tmp_path / "out1.csv").read_bytes() and data.count(b"\xef\xbb\xbf") == 1
    assert data.splitlines()[2].endswith(b",j1,j2,j3,j4,j5,j6")
    rows[11] = rows[11].replace("LIN", "LINE")
    path.write_text("\n".join(rows) + "\n")
    messages = []
    for workers in (1, 2):
        with pytest.raises(ReadError) as error:
            formats.read(path, workers=workers)
        messages.append(str(error.value))
    assert messages[0] == messages[1] and "in.csv:12" in messages[0]
