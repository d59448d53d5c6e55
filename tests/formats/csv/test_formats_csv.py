"""Program CSV: columns, joint targets, added joints, errors."""

from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError

PATH = Path(__file__).parents[2] / "data" / "programs" / "csv" / "path.csv"


def test_columns_and_motions():
    program = formats.read(PATH)
    kinds = [(m.kind, m.speed, m.zone) for m in program.motions]
    assert kinds == [("joint", None, None), ("linear", 100.0, 5.0), ("linear", 100.0, None)]
    np.testing.assert_allclose(program.targets[1].pose[:3, 3], [650.25, -100.0, 480.125])


def test_joints_are_added_as_columns_keeping_everything_else(tmp_path):
    program = formats.read(PATH)
    stack = program.cartesian_targets()
    q = np.radians([[1, 2, 3, 4, 5, 6], [7, 8, 9, 10, 11, 12], [0, -90, 90, 0, 45, 0]])
    formats.write(tmp_path / "out.csv", program.with_targets(stack.index, poses=stack.T, joints=q))
    lines = (tmp_path / "out.csv").read_text().splitlines()
    assert lines[0] == "# program CSV golden file: poses in the robot base frame (mm, deg)"
    assert lines[1] == "id,x,y,z,a,b,c,motion,speed,zone,comment,j1,j2,j3,j4,j5,j6"
    assert lines[2] == '1,600.0,-100.0,500.0,0.0,90.0,0.0,PTP,,,"approach, fast",1.0000,2.0000,3.0000,4.0000,5.0000,6.0000'
    np.testing.assert_allclose(formats.read(tmp_path / "out.csv").targets[2].joints, q[2])


@pytest.mark.parametrize(
    "row, message",
    [
        ("1,2,x,4,5,6", "field z: not a number 'x'"),
        ("1,2,3,4,5", "expected 6 fields, got 5"),
        (",,,,,", "a row needs x,y,z,a,b,c or j1..j6"),
    ],
)
def test_malformed_rows_name_file_line_field_and_text(tmp_path, row, message):
    path = tmp_path / "bad.csv"
    path.write_text(f"x,y,z,a,b,c\n0,0,0,0,0,0\n{row}\n")
    with pytest.raises(ReadError, match=rf"bad\.csv:3: {message}: '{row}'"):
        formats.read(path)


@pytest.mark.parametrize("cell, message", [
    ("-62_8.0", "field y: not a number '-62_8.0'"),  # Python's float reads it as -628
    ("-\uff15\uff10", "field y: not a number '-\uff15\uff10'"),  # full-width digits: float reads -50
])
@pytest.mark.parametrize("rows", [1, 100])  # a row alone, and in a column the reader converts at once
def test_numbers_python_reads_but_no_controller_writes_are_refused(tmp_path, cell, message, rows):
    path = tmp_path / "bad.csv"
    path.write_text("x,y,z,a,b,c\n0,0,0,0,0,0\n" + f"410,{cell},650,0,90,0\n" * rows, encoding="utf-8")
    with pytest.raises(ReadError, match=rf"bad\.csv:3: {message}"):
        formats.read(path)


@pytest.mark.parametrize("column", ["zone", "speed"])
@pytest.mark.parametrize("rows", [1, 100])
def test_a_negative_zone_or_speed_is_refused(tmp_path, column, rows):
    path = tmp_path / "bad.csv"
    path.write_text(f"x,y,z,a,b,c,{column}\n" + "410,0,650,0,90,0,-5\n" * rows)
    with pytest.raises(ReadError, match=rf"bad\.csv:2: field {column}: '-5' is negative"):
        formats.read(path)


def test_not_a_program_csv(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("mx,my,mz\n1,2,3\n")
    with pytest.raises(ReadError, match=r"m\.csv:1: not a program CSV"):
        formats.read(path)


@pytest.mark.parametrize(
    "text, message",
    [
        # a typo of x: the rows would otherwise be read as joint targets
        ("xx,y,z,a,b,c,j1,j2,j3,j4,j5,j6\n1,2,3,4,5,6,0,0,0,0,0,0\n", "column x missing"),
        ("x,y,z,a,b,c,speeed\n1,2,3,4,5,6,100\n", "unknown column 'speeed': did you mean 'speed'"),
        ("x,y,z,a,b,c,xx\n1,2,3,4,5,6,7\n", "unknown column 'xx': did you mean 'x'"),
        ("x,y,z,a,b,c,z\n1,2,3,4,5,6,7\n", "column z given twice"),
        ("x,y,z,a,b,c,j1,j2\n1,2,3,4,5,6,0,0\n", "column j3, j4, j5, j6 missing"),
        ("x,y,z,a,b,c\n", "no target rows after the header"),
        ("x,y,z,a,b,c\n# only a comment\n\n", "no target rows after the header"),
    ],
)
def test_header_mistakes_are_refused_not_read_as_another_program(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ReadError, match=rf"bad\.csv:\d+: {message}"):
        formats.read(path)


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1e999", "9" * 5000], ids=["nan", "inf", "-inf", "1e999", "long"])
def test_non_finite_and_over_long_numbers_are_refused(tmp_path, value):
    path = tmp_path / "bad.csv"
    path.write_text(f"x,y,z,a,b,c\n1,2,{value},4,5,6\n")
    with pytest.raises(ReadError, match=r"bad\.csv:2: field z: .*(not a number|out of range)"):
        formats.read(path)


def test_other_columns_are_kept_and_t_is_known(tmp_path):
    path = tmp_path / "ok.csv"
    path.write_text("id,x,y,z,a,b,c,comment,t\n7,1,2,3,4,5,6,keep me,0.5\n")
    program = formats.read(path)
    assert len(program.motions) == 1
    formats.write(tmp_path / "out.csv", program)
    assert (tmp_path / "out.csv").read_text() == path.read_text()


def test_a_program_re_timed_again_gets_its_t_column_rewritten_in_place(tmp_path):
    """A CSV that already has t (a re-timed output, retimed or compensated again): each t cell is
    replaced, keeping its quotes and spaces, and nothing else changes."""
    from trajcomp.formats.csv.writer import with_times

    path = tmp_path / "timed.csv"
    path.write_text('x,y,z,a,b,c,t,id\n1,2,3,4,5,6,0.0,a\n7,8,9,1,2,3, 1.5 ,b\n4,5,6,7,8,9,"2.5",c\n')
    formats.write(tmp_path / "out.csv", with_times(formats.read(path), np.array([0.0, 0.25, 1.125])))
    assert (tmp_path / "out.csv").read_text() == ('x,y,z,a,b,c,t,id\n1,2,3,4,5,6,0.000000000,a\n'
                                                  '7,8,9,1,2,3, 0.250000000 ,b\n4,5,6,7,8,9,"1.125000000",c\n')


def _mixed_rows():
    """Rows of every kind a CAM export mixes: plain, quoted, spaced, bare .5, a joint target, PTP and LIN."""
    return [
        "# mixed", "id,x,y,z,a,b,c,motion,speed,zone,j1,j2,j3,j4,j5,j6",
        "1,600.0,-100.0,500.0,0.0,90.0,0.0,PTP,,,,,,,,",
        '2,"610.5", -100.0 ,500.0,0.0,90.0,0.0,lin,100,5,,,,,,',
        "3,,,,,,,PTP,,,0,-90,90,0,45,0",
        "# a comment between rows",
        "4,620.125,-99.5,.5,0.0,90.0,0.0,LIN,100,,,,,,,",
        "5,630.0,-99.0,501.0,0.0,90.0,0.0,LIN,50,1,10,-80,80,0,90,0",
        "6,640.0,-98.5,502.0,0.0,89.5,0.0,LIN,50,1,,,,,,",
    ]


@pytest.mark.parametrize("block", [1, 2, 3])
@pytest.mark.parametrize("ending", ["\n", "\r\n"])
def test_rows_read_and_written_in_blocks_equal_one_block(tmp_path, monkeypatch, block, ending):
    """Blocks of 1 to 3 rows (the reader and writer work a block at a time) give the tables and bytes of one block."""
    from trajcomp.formats.csv import reader as csv_reader, writer as csv_writer

    path = tmp_path / "mixed.csv"
    path.write_bytes(ending.join(_mixed_rows()).encode())  # no line ending after the last row

    def run():
        program = formats.read(path)
        stack = program.cartesian_targets()
        poses = stack.T.copy()
        poses[:, :3, 3] += [0.25, -0.125, 1.0]
        edited = program.with_targets(stack.index, poses=poses, joints=np.radians(np.tile([5.0, -85, 85, 1, 44, 2],
                                                                                          (len(poses), 1))))
        return program, formats.write(tmp_path / f"out{block}.csv", edited)[0].read_bytes()

    reference, expected = run()
    monkeypatch.setattr(csv_reader, "BLOCK", block)  # the blocks read
    monkeypatch.setattr(csv_writer, "BLOCK", block)  # and written
    program, written = run()
    for name in ("pose", "joints", "line", "is_joint"):
        np.testing.assert_array_equal(getattr(program.target_table(), name), getattr(reference.target_table(), name))
    assert list(program.motion_table().kind) == ["joint", "linear", "joint", "linear", "linear", "linear"]
    np.testing.assert_array_equal(program.motion_table().speed, [np.nan, 100, np.nan, 100, 50, 50])
    assert written == expected and written.count(ending.encode()) == len(_mixed_rows()) - 1
    assert written.decode().splitlines()[6] == "4,620.375,-99.625,1.500,0.0,90.0,0.0,LIN,100,,5.0000,-85.0000,85.0000," \
                                               "1.0000,44.0000,2.0000"


@pytest.mark.parametrize("block", [2, 50_000])
def test_a_mistake_in_a_later_block_is_named_by_its_line(tmp_path, monkeypatch, block):
    from trajcomp.formats.csv import reader as csv_reader

    monkeypatch.setattr(csv_reader, "BLOCK", block)  # only read: the reader's blocks
    rows = _mixed_rows()
    rows.insert(7, "7,650.0,-98.0,503.0,0.0,90.0,0.0,LNI,50,1,,,,,,")
    path = tmp_path / "typo.csv"
    path.write_text("\n".join(rows) + "\n")
    with pytest.raises(ReadError, match=r"typo\.csv:8: field motion: expected PTP or LIN, got 'LNI'"):
        formats.read(path)


def test_a_file_writing_bare_fractions_keeps_them_bare_but_never_loses_an_integer_digit(tmp_path):
    """.5 stays bare (.750), yet 10.5 is 10.500 and -10.25 is -10.250 (not 1.500, -1.250)."""
    path = tmp_path / "bare.csv"
    path.write_text("x,y,z,a,b,c\n.5,-.5,1,0,0,0\n.5,.5,1,0,0,0\n")
    program = formats.read(path)
    stack = program.cartesian_targets()
    poses = stack.T.copy()
    poses[:, :3, 3] = [[10.5, -10.25, 1.0], [0.75, -0.75, 1.0]]
    formats.write(tmp_path / "out.csv", program.with_targets(stack.index, poses=poses))
    assert (tmp_path / "out.csv").read_text().splitlines()[1:] == ["10.500,-10.250,1,0,0,0", ".750,-.750,1,0,0,0"]
