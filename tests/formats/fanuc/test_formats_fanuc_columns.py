"""FANUC LS at CAM scale: the motion lines and positions read at once against the line-by-line read, the
positions written as columns against the object path, speed fields written from columns."""

import re

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError, WriteError
from trajcomp.formats.fanuc import columns, grammar, speeds, writer
from trajcomp.formats.text import Lines
from trajcomp.formats.source_shifts import edit_sources
from trajcomp.formats.text_edits import target_edits
from trajcomp.programs.tables import ItemRows, TargetRows
from trajcomp.arm.transforms import abc_to_matrix

HEAD = "/PROG  CAM\n/ATTR\nLINE_COUNT\t= 0;\n/MN\n"


def _position(n, x, config="N U T, 0, 0, 0", frame="UF : 0, UT : 1"):
    return (f"P[{n}]{{\n   GP1:\n\t{frame},\t\tCONFIG : '{config}',\n\tX = {x:.3f}  mm,\tY = 20.500  mm,\t"
            f"Z = 300.000  mm,\n\tW = 180.000 deg,\tP = 0.000 deg,\tR = -.5 deg\n}};\n")


def _program(tmp_path, mn, positions, ending="\n"):
    """An .LS file of /MN lines and /POS entries (each a str), line endings ``ending``."""
    text = HEAD + "".join(f"{k:4d}:{line}\n" if not line.startswith(" ") else line + "\n"
                          for k, line in enumerate(mn, start=1)) + "/POS\n" + "".join(positions) + "/END\n"
    path = tmp_path / "cam.ls"
    path.write_bytes(text.replace("\n", ending).encode())
    return path


def _cam(tmp_path, ending="\n"):
    """A CAM job with the lines a CAM post writes and, between them, every other kind the reader follows."""
    mn = ["UTOOL_NUM=1 ;", "UFRAME_NUM=0 ;", "J P[1] 30% FINE    ;"]
    mn += [f"L P[{n}] 50mm/sec CNT1    ;" for n in range(2, 8)]
    mn += ["L P[8] R[4]mm/sec CNT50    ;", "C P[9]    ", "    :  P[10] 50mm/sec CNT1    ;",
           "L P[11] 2000msec CNT0    ;", "L P[12] 50mm/sec FINE    ;", "UTOOL[1]=PR[3] ;",
           "L P[13] 50mm/sec CNT1    ;", "L P[14] 50mm/sec CNT1 Offset,PR[2]    ;", "UTOOL_NUM=2 ;",
           "L P[15] 12.5cm/min CNT1    ;", "l p[16] 50mm/sec cnt1    ;", "L P[17] 50mm/sec CNT1    ;",
           "  ! PR[1]=P[5] ;", "L P[18] 5.5deg/sec CNT1    ;", "L P[19] 50mm/sec CNT1    ;"]
    positions = [_position(n, 100.0 + n) for n in range(1, 20)]
    positions[3] = ("P[4]{\n   GP1:\n\tUF : 0, UT : 1,\n\tJ1= 10.0 deg,\tJ2= 20.0 deg,\tJ3= 0 deg,\n"
                    "\tJ4= 0 deg,\tJ5= -90 deg,\tJ6= 0 deg\n};\n")
    positions[5] = _position(6, 106.0).replace("X = 106.000", "X = ********")
    positions[6] = _position(7, 107.0, frame="UF : 1, UT : 2")
    positions[16] = positions[16].replace("R = -.5 deg", "R = -.5 deg,\tE1= 5.0 mm")
    positions[17] = positions[17].replace("P[18]", 'P[18:"a comment"]')
    return _program(tmp_path, mn, positions, ending)


def _seen(program):
    """Everything a read gives, comparable: targets' numbers bit for bit, spans, items."""
    def bits(array):
        return None if array is None else np.asarray(array).tobytes()

    targets = [(t.name, t.line, bits(t.pose), bits(t.joints), t.config, t.tool, t.frame, bits(t.external),
                dict(t.spans), t.edited) for t in program.targets]
    return targets, [repr(item) for item in program.items]


def _line_by_line(path, monkeypatch):
    """The program read with no line read at once."""
    written = columns.written_positions
    with monkeypatch.context() as patch:
        patch.setattr(columns, "written_positions", lambda masked, start, end: written(masked, 0, 0))
        patch.setattr(grammar, "WRITTEN_MOTION", re.compile(r"(?!)"))
        return formats.read(path)


@pytest.mark.parametrize("ending", ["\n", "\r\n", "\r"])
def test_a_cam_job_reads_at_once_what_it_reads_line_by_line(tmp_path, monkeypatch, ending):
    path = _cam(tmp_path, ending)
    at_once = formats.read(path)
    assert isinstance(at_once.items, ItemRows) and isinstance(at_once.targets, TargetRows)
    assert _seen(at_once) == _seen(_line_by_line(path, monkeypatch))
    motions = at_once.motions
    assert [m.line for m in motions][:3] == [7, 8, 9] and motions[2].text == "5:L P[3] 50mm/sec CNT1 ;"
    assert motions[2].tool == "1" and motions[2].zone == 1.0 and motions[2].speed == 50.0
    assert motions[2].spans["speed"].text == "50mm/sec"
    assert "PR[3]" in motions[11].reason and motions[11].target is None  # after UTOOL[1]=PR[3]: set at run time
    assert motions[13].tool == "2" and motions[13].speed == pytest.approx(12.5 / 6)  # cm/min in mm/s


def test_a_cam_job_refuses_line_by_line_what_it_refuses(tmp_path, monkeypatch):
    path = _program(tmp_path, ["L P[1] 50mm/sec CNT1    ;", "L P[2] 50mm/sec CNT1    ;"], [_position(1, 1.0)])
    with pytest.raises(ReadError, match=r"cam.ls:6: P\[2\] has no entry in /POS"):
        formats.read(path)
    path = _program(tmp_path, ["L P[1] 50mm/sec CNT1    ;"], [_position(1, 1e9)])
    with pytest.raises(ReadError, match=r"cam.ls:7: P\[1\] X: '1000000000.000' is out of range") as refused:
        formats.read(path)
    with pytest.raises(ReadError) as line_by_line:
        _line_by_line(path, monkeypatch)
    assert str(line_by_line.value) == str(refused.value)


def _moved(program):
    """Every target moved 0.5 mm, every other one turned 0.01 deg, every third one's configuration flipped; joint
    targets turned 0.1 deg."""
    table = program.target_table()
    cartesian, joint = np.flatnonzero(~table.is_joint), np.flatnonzero(table.is_joint)
    T = table.pose[cartesian].copy()
    T[:, :3, 3] += 0.5
    T[::2, :3, :3] = T[::2, :3, :3] @ abc_to_matrix(np.radians([0.01, 0.0, 0.0]))
    configs = [("F",) + tuple(config[1:]) if config and k % 3 == 0 else config
               for k, config in enumerate(table.config[i] for i in cartesian.tolist())]
    moved = program.with_targets(cartesian, poses=T, configs=configs)
    return moved.with_targets(joint, joints=table.joints[joint] + np.radians(0.1)) if len(joint) else moved


def test_positions_of_a_table_write_as_columns_what_they_write_as_objects(tmp_path):
    program = _moved(formats.read(_cam(tmp_path)))
    assert isinstance(program.targets, TargetRows)
    as_columns = target_edits(program, writer._encode, writer.MIN_PLACES, writer._encode_columns)
    as_objects = target_edits(program, writer._encode, writer.MIN_PLACES)
    text = program.sources[0].text
    written = as_columns[0].applied(text)
    assert written == as_objects[0].applied(text)
    assert "X = 102.500  mm" in written and "CONFIG : 'F U T, 0, 0, 0'" in written and "J1= 10.1000 deg" in written
    assert "X = ********" in written  # an untaught position is left as it is


def test_a_position_not_finite_is_refused_by_name(tmp_path):
    program = formats.read(_cam(tmp_path))
    T = program.target_table().pose[[2]].copy()
    T[0, 1, 3] = np.nan
    with pytest.raises(WriteError, match=r"P\[3\] \(line 42\): y is not a finite number"):
        target_edits(program.with_targets([2], poses=T), writer._encode, writer.MIN_PLACES, writer._encode_columns)


class _Timing:
    """What `speeds.write_speeds` reads of a timing: the motion of each waypoint."""

    def __init__(self, motion):
        self.motion = np.asarray(motion)


class _Plan:
    def __init__(self, times, cruise):
        self.times, self.cruise = times, cruise


def test_speed_fields_of_a_table_are_written_as_those_of_objects(tmp_path, monkeypatch):
    path = _cam(tmp_path)
    at_once, line_by_line = formats.read(path), _line_by_line(path, monkeypatch)
    motions = len(at_once.motions)
    timing = _Timing(np.arange(motions))
    plan = _Plan({k: 0.0125 * k for k in range(0, motions, 2)}, {k: 20.7 for k in range(1, motions, 2)})
    (timed, settings), (expected, expected_settings) = (speeds.write_speeds(p, timing, None, plan)
                                                        for p in (at_once, line_by_line))
    assert settings == expected_settings and settings[2] == "25msec" and settings[3] == "20mm/sec"
    assert timed.sources[0].text == expected.sources[0].text
    assert _seen(timed) == _seen(expected)
    assert isinstance(timed.items, ItemRows) and timed.motions[3].spans["speed"].text == "20mm/sec"
    assert edit_sources(at_once, [[]]) is at_once


def test_position_numbers_beyond_the_lines_read_at_once_read_line_by_line(tmp_path, monkeypatch):
    path = _program(tmp_path, ["L P[100000000000] 50mm/sec CNT1    ;", "L P[1] 50mm/sec CNT1    ;"],
                    [_position(100000000000, 1.0), _position(1, 2.0)])
    program = formats.read(path)
    assert [m.target for m in program.motions] == [0, 1]
    assert _seen(program) == _seen(_line_by_line(path, monkeypatch))


@pytest.mark.parametrize("text", ["a\nbb\n\nc", "a\nb\n", "", "\n", "a\r\nb\rc\n", "é\nx\n", "x\r\r\n\ny\r",
                                  "\r", "\n\r\n", "é\r\nx\r"])
@pytest.mark.parametrize("piece", [1, 2, 3, Lines.PIECE])  # a "\r\n" across pieces looked at together
def test_line_starts_found_at_once_are_those_of_the_regular_expression(text, piece, monkeypatch):
    monkeypatch.setattr(Lines, "PIECE", piece)
    assert list(Lines(text).starts) == [0] + [m.end() for m in re.finditer(r"\r\n|\r|\n", text)]


def _counted(monkeypatch, name):
    """Count what ``columns.<name>`` returns (the rows read at once) in a list, each call's count appended."""
    counts, function = [], getattr(columns, name)

    def counting(*args):
        found = function(*args)
        counts.append(len(found["p"] if "p" in found else found["line"]))
        return found

    monkeypatch.setattr(columns, name, counting)
    return counts


POSITION_VARIANTS = [  # (entry, read at once)
    (_position(1, 1.0), True),
    ("P[ 2 ]{GP1:UF:0,UT:1,CONFIG:'N U T, 0, 0, 0',X=1.5mm,Y=2mm,Z=3mm,W=4deg,P=5deg,R=6deg};\n", True),
    ("P[3]{\r\n GP1 :\n uf : 0 , ut : 1 ,\f config : 'n u t , 0 , 0 , 0' ,\n x = 1.5e2 MM , y = -2E-1 mm ,"
     " z = +.5 mm ,\n w = 180. DEG , p = -0 deg , r = 1e+1 deg\n};\n", True),
    (_position(4, 4.0).replace("P[4]", 'P[4: "a, b]: c = {}"]'), True),
    (_position(5, 5.0).replace("X = 5.000", "X =\u00a05.000"), False),  # a white space that is not ASCII
    (_position(6, 6.0, frame="UF:0,UT:1").replace("CONFIG : ", "CONFIG:"), True),
    (_position(7, 7.0).replace("UF : 0", "UF : 10"), True),
    (_position(8, 8.0), True),
    (_position(9, 9.0).replace("R = -.5 deg", "R = -.5 deg,\tE1= 5.0 mm"), False),
    (_position(10, 10.0).replace("};", "};  junk  "), True),
    (_position(11, 11.0), True),
    (_position(12, 12.0).replace("X = 12.000  mm", "X = 12.000  deg"), False),
    (_position(13, 13.0).replace("UT : 1", "UT : 1" + " " * 70), False),  # a longer run of blanks than skipped
    (_position(14, 14.0).replace("CONFIG", "KONFIG"), False),
    ("P[15]{\n   GP1:\n\tUF : 0, UT : 1,\n\tJ1= 10.0 deg,\tJ2= 20.0 deg,\tJ3= 0 deg,\n"
     "\tJ4= 0 deg,\tJ5= -90 deg,\tJ6= 0 deg\n};\n", False),
    (_position(16, 16.0).replace("X = 16.000", "X = ********"), False),
    (_position(17, 17.0).replace("\n};", "\n}\t;"), False),  # `_POS` ends an entry at "};": this one swallows
    (_position(18, 18.0), False),  # the next one
]
MOTION_VARIANTS = [  # (line, read at once)
    ("L P[1] 50mm/sec CNT1    ;", True), ("J P[2] 100% FINE ;", True),
    ("L   P[ 3 ]\t\t50 mm/sec   CNT100\t;  ", True), ("L P[4] 50.5mm/sec CNT1 ;", True),
    ("L P[5] 7.deg/sec FINE\t;", True), ("L P[6] 2sec CNT1 ;", True), ("L P[7] 25msec CNT0 ;", True),
    ("L P[7] 12inch/min CNT1 ;", True), ("L P[7] 30cm/min CNT1 ;", True),
    ("L P[8] 50mm/sec CNT 1 ;", False), ("L P[9] 50mm/sec FINE ACC100 ;", False), ("L P[10] 50mm/sec CNT1", False),
    ("   : ACC100 ;", None), ("  ! Grüße: L P[11] 50mm/sec CNT1 ;", None),
    ("L P[11]" + " " * 70 + "50mm/sec CNT1 ;", False), ("L P[12] 50mm/sec CNT1 ;", True),
    ("L P[13] 50mm/sec CNT1 ;", True), ("L P[14] 50mm/sec CNT1 ;", True), ("L P[15] 50mm/sec CNT1 ;", True),
    ("l P[7] 50mm/sec CNT1 ;", False), ("L P[16] 50mm/sec CNT1 ;", False),
    ("   :L P[12] 50mm/sec CNT1 ;", True), ("  :J P[13] 10% FINE ;", True),  # no line number (MakeTP reads it)
    ("WAIT R[1]>0", None), ("   :L P[14] 50mm/sec CNT1 ;", False),  # continues the instruction before it
    ("C P[15]", None), ("       P[16] 50mm/sec CNT1 ;", None),  # so does a line with no ":" (RoboDK's posts)
]


@pytest.mark.parametrize("ending", ["\n", "\r\n"])
@pytest.mark.parametrize("block", [2, 4096])
def test_written_variants_read_at_once_as_line_by_line(tmp_path, monkeypatch, ending, block):
    """Blanks, case, exponents, comments, non-ASCII text, malformed and other entries and lines: those written as
    a CAM post writes them are read at once, the others line by line, and the program is the line-by-line one,
    whatever the block of lines or entries read together."""
    path = _program(tmp_path, ["  ! Grüße, Ωmega ;"] + [line for line, _ in MOTION_VARIANTS],
                    [entry for entry, _ in POSITION_VARIANTS], ending)
    for name, size in (("POSITIONS_AT_ONCE", block), ("MOTIONS_AT_ONCE", block), ("HEADS_AT_ONCE", 3 * block)):
        monkeypatch.setattr(columns, name, size)
    expected = _line_by_line(path, monkeypatch)
    positions_read, motions_read = _counted(monkeypatch, "written_positions"), _counted(monkeypatch,
                                                                                         "written_motions")
    at_once = formats.read(path)
    assert _seen(at_once) == _seen(expected)
    assert positions_read == [sum(fast for _, fast in POSITION_VARIANTS)]
    assert motions_read == [sum(fast is True for _, fast in MOTION_VARIANTS)]


@pytest.mark.parametrize("entry, message", [
    (_position(2, 2.0, config="N U T, 0, 0"), r"cam.ls:13: P\[2\]: malformed CONFIG"),
    (_position(2, 2.0).replace("Y = 20.500  mm", "Y = 2 0.5  mm"), r"cam.ls:13: P\[2\] lacks Y"),
    (_position(2, 2.0).replace("W = 180.000", "W = 1e5"), r"cam.ls:13: P\[2\] W: '1e5' is out of range"),
    (_position(2, 2.0).replace("Z = 300.000", "Z = -inf"), r"cam.ls:13: P\[2\] lacks Z"),
    # Arabic-Indic digits, which Python's float reads: not a number a controller reads
    (_position(2, 2.0).replace("X = 2.000", "X = ٢.000"), r"cam.ls:13: P\[2\] lacks X")])
def test_a_position_among_written_ones_is_refused_by_name(tmp_path, monkeypatch, entry, message):
    path = _program(tmp_path, ["L P[1] 50mm/sec CNT1    ;"], [_position(1, 1.0), entry, _position(3, 3.0)])
    with pytest.raises(ReadError, match=message) as refused:
        formats.read(path)
    with pytest.raises(ReadError) as line_by_line:
        _line_by_line(path, monkeypatch)
    assert str(line_by_line.value) == str(refused.value)


def test_instructions_without_line_numbers_are_read_as_instructions(tmp_path, monkeypatch):
    """As the Grasshopper plug-in Robots writes a program (``:L P[1] ..  ;``, no numbers; MakeTP numbers them): each
    line ended by its ``;`` is an instruction of its own (a comment too), only a line after one not ended continues
    it, with or without its ``:`` (RoboDK's posts write a circular motion's second point without). Read once, these
    motions were none, the program was written unchanged and passed; RoboDK's circular motion was refused."""
    text = ("/PROG  ROB\n/ATTR\nCOMMENT = \"Fanuc LS code\" ;\n/MN\n: UTOOL_NUM=1 ;\n: ! Tool 1 TCP Configuration ;\n"
            ":L P[1] 50mm/sec CNT1  ;\n:C P[2]  \n  :  P[3] 50mm/sec FINE  ;\n:J P[1] 10% FINE  ;\n"
            "   5:C P[2] \n       P[3] 50mm/sec CNT1 ;\n/POS\n"
            + "".join(_position(n, 100.0 + n) for n in (1, 2, 3)) + "/END\n")
    path = tmp_path / "rob.ls"
    path.write_text(text)
    program = formats.read(path)
    assert [(m.line, m.kind, m.via, m.target, m.tool) for m in program.motions] == [
        (7, "linear", None, 0, "1"), (8, "circular", 1, 2, "1"), (10, "joint", None, 0, "1"),
        (11, "circular", 1, 2, "1")]
    assert _seen(program) == _seen(_line_by_line(path, monkeypatch))
