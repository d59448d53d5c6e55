"""KRL's motions read at once (`trajcomp.formats.krl.at_once.written_motions`) against the one-by-one read: the
state in force at each line (tool, base, speeds, zone), points changed at run time, refusals; and the speed
write-back and text edits of a program held as columns against the same program held as objects."""

import re

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError
from trajcomp.formats import forms
from trajcomp.formats.krl import at_once as krl_at_once
from trajcomp.formats.krl import grammar
from trajcomp.formats.number_fields import line_bounds, text_codes
from trajcomp.formats.text import Lines, mask
from trajcomp.formats.source_shifts import edit_sources
from trajcomp.programs.tables import ItemRows, TargetRows
from tests.formats.test_formats_columnar import _seen, never_written

DAT = ("DEFDAT p\n" + "".join(f"DECL E6POS XP{k}={{X {500 + k},Y {k},Z 600,A 0,B 90,C 0,S 2,T 35}}\n"
                              for k in range(1, 7))
       + "DECL FDAT F2={TOOL_NO 2,BASE_NO 1}\nDECL LDAT L1={VEL 0.3,APO_DIST 4}\nENDDAT\n")
SRC = """DEF p( )
  LIN XP1 C_DIS
  $VEL.CP=0.05 ; m/s
  $APO.CDIS=1.0
  LIN XP2 C_DIS ; a comment
  PTP XP3
  BAS(#VEL_PTP,20)
  $TOOL=TOOL_DATA[1]
  SPTP XP4 C_PTP
  LIN XP5 WITH $VEL.CP=0.1
  FDAT_ACT=F2
  LDAT_ACT=L1
  lin xp6 c_dis
  LIN {X 1,Y 2,Z 3,A 0,B 90,C 0}
  LIN XP6
  $TOOL=$NULLFRAME
  XP2.X=10
  LIN XP2
END
"""


def _program(tmp_path, src=SRC, dat=DAT):
    (tmp_path / "p.src").write_text(src)
    (tmp_path / "p.dat").write_text(dat)
    return tmp_path / "p.src"


def _one_by_one(path, monkeypatch):
    """The program read with no motion read at once."""
    with monkeypatch.context() as patch:
        never_written(patch, grammar.WRITTEN_MOTION, grammar.INLINE_MOTION)
        return formats.read(path)


def test_motions_read_at_once_take_the_state_in_force_at_their_line(tmp_path, monkeypatch):
    path = _program(tmp_path)
    at_once, one_by_one = formats.read(path), _one_by_one(path, monkeypatch)
    assert isinstance(at_once.items, ItemRows) and not isinstance(one_by_one.items, ItemRows)
    assert [repr(item) for item in at_once.items] == [repr(item) for item in one_by_one.items]
    assert at_once.not_compensated() == one_by_one.not_compensated()
    table = at_once.motion_table()
    assert table.speed.tolist()[1:3] == [50.0, pytest.approx(np.nan, nan_ok=True)]  # $VEL.CP 0.05 m/s; PTP: none
    assert table.zone[1] == 1.0 and table.tool[3] == "1" and table.tool[5] == "2"  # C_DIS, TOOL_DATA[1], FDAT F2
    assert table.speed[5] == 300.0 and table.zone[5] == 4.0  # LDAT L1
    assert table.target[-1] == -1 and "XP2 is changed at run time (line 17)" in table.reason[-1]


@pytest.mark.parametrize("src, message", [
    ("DEF p( )\n  LIN XP1\n  LIN XP9 C_DIS\nEND\n", "XP9 (line 3)"),  # a point nobody declares
    ("DEF p( )\n  LIN C_DIS\nEND\n", "p.src:2: LIN needs 1 target(s)"),  # an approximation is no point
])
def test_a_motion_the_one_by_one_read_refuses_is_refused_naming_its_line(tmp_path, monkeypatch, src, message):
    path = _program(tmp_path, src)
    with pytest.raises(ReadError, match=re.escape(message)) as refused:
        formats.read(path)
    with pytest.raises(ReadError) as refused_one_by_one:
        _one_by_one(path, monkeypatch)
    assert str(refused.value) == str(refused_one_by_one.value)


def test_motions_in_a_routine_with_parameters_or_a_tool_known_at_run_time_are_left_as_the_line_read_leaves_them(
        tmp_path, monkeypatch):
    src = "DEF p(P1:IN)\n  LIN P1\n  LIN XP1\n  $TOOL=TOOL_DATA[N]\n  LIN XP2 C_DIS\nEND\n"
    path = _program(tmp_path, src)
    at_once, one_by_one = formats.read(path), _one_by_one(path, monkeypatch)
    assert [repr(item) for item in at_once.items] == [repr(item) for item in one_by_one.items]
    assert len(at_once.not_compensated()) == 2


def test_text_edits_move_a_table_held_program_as_they_move_objects(tmp_path, monkeypatch):
    path = _program(tmp_path)
    at_once, one_by_one = formats.read(path), _one_by_one(path, monkeypatch)
    text = at_once.sources[0].text
    inserted = text.index("  PTP XP3")
    edits = [[(inserted, inserted, "  BAS(#VEL_PTP,10)\n"), (text.index("0.05"), text.index("0.05") + 4, "0.025")],
             []]
    moved, moved_objects = edit_sources(at_once, edits), edit_sources(one_by_one, edits)
    assert isinstance(moved.items, ItemRows)
    assert [repr(item) for item in moved.items] == [repr(item) for item in moved_objects.items]
    assert moved.motions[2].line == 7 and moved.motions[1].spans["speed"].text == "0.025"


def test_a_point_declared_again_after_its_motion_is_the_last_declaration_as_read_one_by_one(tmp_path, monkeypatch):
    src = "DEF p( )\n  LIN XP1\n  LIN XP2\nEND\nDEF q( )\n  DECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 90,C 0}\nEND\n"
    path = _program(tmp_path, src)
    at_once, one_by_one = formats.read(path), _one_by_one(path, monkeypatch)
    assert [repr(item) for item in at_once.items] == [repr(item) for item in one_by_one.items]
    assert at_once.motions[0].target == 6 and at_once.targets[6].pose[0, 3] == 1.0


POINT_VARIANTS = [  # (a line of a data list, whether `WRITTEN_POINT` run at once finds it (`forms.find_lines`))
    ("DECL E6POS XP1={X 1.5,Y -2,Z 3.25,A 0.0,B 90.0,C -0.5,S 2,T 35}", 1),
    ("decl e6pos xp2={x .5,y -.5,z +3,a 1.,b 1e2,c -2.5E-1,s 6,t 0}", 1),
    ("DECL GLOBAL POS XP3={X 1,Y 2,Z 3,A 4,B 5,C 6}", 1),
    ("DECL FRAME XP4={X 1,Y 2,Z 3,A 4,B 5,C 6,E1 7.5}", 1),
    ("DECL E6POS XP5={X 1,Y 2,Z 3,A 4,B 5,C 6,S 6,T 27,E1 0.0,E2 1,E3 2,E4 3,E5 4,E6 5}", 1),
    ("DECL E6POS GLOBAL={X 1,Y 2,Z 3,A 4,B 5,C 6,S 2,T 35}", 1),  # a point named GLOBAL: shared, as the pattern says
    ("DECL E6POS XP6={X 1.23456789012345678,Y 2,Z 3,A 1e400,B 5,C 6}", 1),  # read by float; an infinite A: left out
    ("DECL E6POS XP7={X 1e9,Y 2,Z 3,A 4,B 5,C 6,S 256,T 35}", 1),  # out of range, S beyond its bits: left out
    ("  DECL E6POS XP8={X 1,Y 2,Z 3,A 4,B 5,C 6}", 1),  # indented
    ("DECL\tE6POS XP9 = {X 1,Y 2,Z 3,A 4,B 5,C 6}  ", 1),
    ("DECL E6POS XPé={X 1,Y 2,Z 3,A 4,B 5,C 6}", 0),  # a name beyond ASCII: the pattern
    ("DECL E6POS XP10={X 1..2,Y 2,Z 3,A 4,B 5,C 6}", 1),  # no number (`_field_numbers`): neither reads it
    ("DECL E6POS XP11={X 1,Y 2,Z 3,A 4,B 5,C 6,S +2,T 35}", 1),
    ("DECL E6POS XP12={X 1,Y 2,Z 3,A 4,B 5,C 6,E2 1}", 0),
    ("DECL E6POS XP13={X 1,Y 2,Z 3,A 4,B 5,C 6}{", 0),
    ("DECL E6POS XP14={X 1,Y 2,Z 3,A 4,B 5,C 6} ; a comment after it", 1),  # blanks after the brace
    ("DECL E6POS XP15={X 1,Y 2,Z ,A 4,B 5,C 6}", 0),
    ("DECL E6AXIS XA1={A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}", 0),
    ("DECL FDAT F1={TOOL_NO 1,BASE_NO 0}", 0),
]
MOTION_VARIANTS = [  # (a .src line, whether `WRITTEN_MOTION` run at once finds it (`forms.find_lines`))
    ("  LIN XP1 C_DIS", True), ("PTP XP2", True), ("\tsptp xp3 c_ptp", True), ("  SLIN _P4 C_VEL", True),
    ("  LIN WITHIN", True), ("  LIN C_DISX", True), ("  LIN XP5  C_DIS", True), ("  LIN XP6 C_DIS  ", True),
    ("  LIN WITH", False), ("  LIN C_DIS", False), ("  LIN XPé", False), ("  LIN XP7 WITH $VEL.CP=0.1", False),
    ("  LIN_REL XP8", False), ("  CIRC XP1, XP2", False), ("  LIN 1XP", False), ("  LIN " + "X" * 70, True),
]


def _at_once_and_by_pattern(function, *args):
    """``function(*args)`` as written, and with no line found at once (every line through the forms' patterns)."""
    at_once = function(*args)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(forms, "find_lines", lambda written, codes, starts, ends: [
            (np.zeros(0, dtype=np.int64), np.zeros((0, form.groups + 1, 2), dtype=np.int64)) for form in written])
        return at_once, function(*args)


def _found_at_once(form, masked):
    """The lines (from 0) ``form`` run at once finds in a text."""
    codes = text_codes(masked)
    return forms.find_lines([form], codes, *line_bounds(codes))[0][0]


@pytest.mark.parametrize("ending", ["\n", "\r\n"])
def test_points_read_from_their_characters_are_those_the_pattern_reads(ending):
    text = "; Größe, Maße: a comment beyond ASCII before the points\nDEFDAT p\n" + "".join(
        line + ending for line, _ in POINT_VARIANTS) + "ENDDAT"
    masked, lines = mask(text, ";"), Lines(text)
    assert len(_found_at_once(grammar.WRITTEN_POINT, masked)) == sum(n for _, n in POINT_VARIANTS)
    at_once, by_pattern = _at_once_and_by_pattern(krl_at_once.written_points, 0, masked, lines)
    (line, table, shared), (line_p, table_p, shared_p) = at_once, by_pattern
    assert line.tolist() == line_p.tolist() and shared.tolist() == shared_p.tolist()
    assert table.pose.tobytes() == table_p.pose.tobytes() and list(table.name) == list(table_p.name)
    assert table.config == table_p.config
    assert [None if e is None else e.tolist() for e in table.external] == [
        None if e is None else e.tolist() for e in table_p.external]
    assert table.spans.start.tolist() == table_p.spans.start.tolist()
    assert table.spans.end.tolist() == table_p.spans.end.tolist()
    assert len(line) == 10 and shared.sum() == 2  # XP6, XP7 left out (their line's read names them)


@pytest.mark.parametrize("ending", ["\n", "\r\n"])
def test_motions_read_from_their_characters_are_those_the_pattern_reads(ending):
    text = "DEF p( )\n" + "".join(line + ending for line, _ in MOTION_VARIANTS) + "END"
    masked = mask(text, ";")
    at = _found_at_once(grammar.WRITTEN_MOTION, masked)
    assert (at - 1).tolist() == [k for k, (_, read) in enumerate(MOTION_VARIANTS) if read]
    at_once, by_pattern = _at_once_and_by_pattern(krl_at_once.written_motions, 0, masked, Lines(text))
    assert {k: v.tolist() for k, v in at_once[0].items()} == {k: v.tolist() for k, v in by_pattern[0].items()}
    assert len(at_once[0]["line"]) == 9 and at_once[1] is None


INLINE_VARIANTS = [  # (a .src line, whether `INLINE_MOTION` run at once finds it, whether it is read at once)
    ("  LIN {X 1.5,Y -2,Z 3.25,A 0.0,B 90.0,C -0.5} C_DIS", True, True),
    ("lin {x .5,y -.5,z +3,a 1.,b 1e2,c -2.5E-1}", True, True),  # any case, exponents
    ("\tPTP {X 1,Y 2,Z 3,A 4,B 5,C 6,S 2,T 35} C_PTP", True, True),
    ("  SLIN {X 1,Y 2,Z 3,A 4,B 5,C 6,E1 7.5} c_vel", True, True),
    ("  SPTP {X 1,Y 2,Z 3,A 4,B 5,C 6,S 'B110',T 27,E1 0.0,E2 1,E3 2,E4 3,E5 4,E6 5} C_DIS", True, False),  # bits
    ("  SPTP {X 1,Y 2,Z 3,A 4,B 5,C 6,S 6,T 27,E1 0.0,E2 1,E3 2,E4 3,E5 4,E6 5} C_DIS", True, True),
    ("  LIN {X 1e9,Y 2,Z 3,A 4,B 5,C 6} C_DIS", True, False),  # out of range: its line's read names it
    ("  LIN {X 1,Y 2,Z 3,A 4,B 5,C 6,S 256,T 35}", True, False),  # S beyond its bits
    ("  LIN {X 1..2,Y 2,Z 3,A 4,B 5,C 6}", True, False),  # no number
    ("  LIN  {X 1,Y 2,Z 3,A 4,B 5,C 6}", True, True),  # two blanks
    ("  LIN {X 1,Y 2,Z 3,A 4,B 5,C 6}\tC_DIS ", True, True),
    ("  LIN {X 1,Y 2,Z 3,A 4,B 5,C 6} C_DIS ; Größe, Maße", True, True),  # a comment: blanks after the motion
    ("                    LIN {X 1,Y 2,Z 3,A 4,B 5,C 6}", True, True),  # indented far
    ("  LIN {X 1, Y 2,Z 3,A 4,B 5,C 6}", True, True),  # blanks after some commas
    ("  LIN {X 1, Y 2, Z 3, A 4, B 5, C 6}", True, True),
    ("  LIN {E6POS: X 1.5, Y 2, Z 3, A 4, B 5, C 6, E1 0, E2 0, E3 0, E4 0, E5 0, E6 0} C_DIS", True, True),
    ("  LIN {POS:X 1.5, Y 2, Z 3, A 4, B 5, C 6,S 2, T 35}", True, True),  # the separators mixed
    ("  LIN {FRAME:  X 1.5,Y 2,Z 3,A 4,B 5,C 6}", False, False),
    ("  LIN {X 1,  Y 2,Z 3,A 4,B 5,C 6}", False, False),  # two blanks: one by one
    ("  LIN {X 1 ,Y 2,Z 3,A 4,B 5,C 6}", True, False),  # the field "1 ": no number
    ("  LIN {X 1,Y 2,Z 3,A 4,B 5}", False, False),  # no C: the arm's own, at run time
    ("  LIN {X 1,Y 2,Z 3,A 4,B 5,C 6}C_DIS", False, False),
    ("  LIN {POS: X 1,Y 2,Z 3,A 4,B 5,C 6}", True, True),
    ("  LIN {E6AXIS: X 1,Y 2,Z 3,A 4,B 5,C 6}", False, False),
    ("  PTP {AXIS: A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0} C_PTP", False, False),
    ("  LIN_REL {X 1,Y 2,Z 3,A 4,B 5,C 6}", False, False),
    ("  CIRC {X 1,Y 2,Z 3,A 4,B 5,C 6},{X 1,Y 2,Z 3,A 4,B 5,C 6}", False, False),
    ("  LIN {X 1,Y 2,Z 3,A 4,B 5,C 6} WITH $VEL.CP=0.1", False, False),
    ("  LIN {X 1,Y 2,Z 3,A 4,B 5,C 6,E2 1}", False, False),
]


@pytest.mark.parametrize("ending", ["\n", "\r\n"])
def test_inline_motions_read_from_their_characters_are_those_the_pattern_reads(ending):
    text = "DEF p( ) ; Größe\n" + "".join(line + ending for line, _, _ in INLINE_VARIANTS) + "END"
    masked = mask(text, ";")
    assert (_found_at_once(grammar.INLINE_MOTION, masked) - 1).tolist() == [
        k for k, (_, found, _) in enumerate(INLINE_VARIANTS) if found]
    (columns, table), (columns_p, table_p) = _at_once_and_by_pattern(krl_at_once.written_motions, 0, masked,
                                                                     Lines(text))
    assert {k: v.tolist() for k, v in columns.items()} == {k: v.tolist() for k, v in columns_p.items()}
    assert (columns["line"] - 2).tolist() == [k for k, (_, _, read) in enumerate(INLINE_VARIANTS) if read]
    assert columns["inline"].tolist() == list(range(len(table))) and table.name is None
    assert table.pose.tobytes() == table_p.pose.tobytes() and table.config == table_p.config
    assert table.spans.start.tolist() == table_p.spans.start.tolist()
    assert table.spans.end.tolist() == table_p.spans.end.tolist()
    assert [None if e is None else e.tolist() for e in table.external] == [
        None if e is None else e.tolist() for e in table_p.external]
    assert table.pose[1, :3, 3].tolist() == [0.5, -0.5, 3.0] and table.config[2] == (2, 35)
    assert table.external[3].tolist() == [7.5] and columns["joint"][:4].tolist() == [False, False, True, False]


INLINE_SRC = """&ACCESS RVP
DEF p( ) ; Größe: a comment beyond ASCII
;FOLD INI
BAS (#INITMOV,0 )
;ENDFOLD (INI)
PTP $AXIS_ACT ; skip BCO quickly
$BASE = {FRAME: X 10.000,Y 0.000,Z 0.000,A 0.000,B 0.000,C 0.000}
$TOOL = {FRAME: X 0.000,Y 0.000,Z 100.000,A 0.000,B 0.000,C 0.000}
$VEL.CP = 0.05000
$APO.CDIS = 1.000
PTP {AXIS: A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0} C_PTP
LIN {X 446.000,Y 70.000,Z 635.000,A 0.000,B 90.000,C 0.000} C_DIS
lin {x 446.5,y 70.5,z 6.35e2,a 0,b 90,c 0} c_dis
LIN {E6POS: X 446.7, Y 70.5, Z 635.0, A 0, B 90, C 0, E1 0, E2 0, E3 0, E4 0, E5 0, E6 0} C_DIS

  LIN {X 447.000,Y 71.000,Z 635.000,A 0.000,B 90.000,C 0.000,E1 5.00000} C_DIS ; ß
LIN {X 447.500,Y 71.000,Z 635.000,A 0.000,B 90.000,C 0.000,S 2,T 35}
LIN XP1 C_DIS
$VEL.CP = 0.10000
LIN  {X 448.000,Y 71.000,Z 635.000,A 0.000,B 90.000,C 0.000}
$TOOL = TOOL_DATA[N]
LIN {X 449.000,Y 71.000,Z 635.000,A 0.000,B 90.000,C 0.000} C_DIS
END
"""


@pytest.mark.parametrize("ending", ["\n", "\r\n"])
@pytest.mark.parametrize("dat", [None, "DEFDAT p\nDECL E6POS XP1={X 450,Y 70,Z 635,A 0,B 90,C 0,S 2,T 35}\nENDDAT\n"])
def test_inline_motions_read_at_once_are_the_program_read_one_by_one(tmp_path, monkeypatch, ending, dat):
    src = INLINE_SRC if dat else INLINE_SRC.replace("LIN XP1 C_DIS\n", "")
    (tmp_path / "p.src").write_bytes(src.replace("\n", ending).encode("latin-1"))
    if dat:
        (tmp_path / "p.dat").write_bytes(dat.replace("\n", ending).encode("latin-1"))
    path = tmp_path / "p.src"
    at_once, one_by_one = formats.read(path), _one_by_one(path, monkeypatch)
    assert isinstance(at_once.items, ItemRows) and _seen(at_once) == _seen(one_by_one)
    assert isinstance(at_once.targets, TargetRows) == (dat is None)  # the axis position joins the inline points
    assert at_once.not_compensated() == one_by_one.not_compensated()
    table = at_once.motion_table()
    assert table.speed.tolist()[2:4] == [50.0, 50.0] and table.zone[2] == 1.0 and table.tool[2] == "TOOL line 8"
    assert f"TOOL_DATA[N] set at run time (line {20 + bool(dat)})" in table.reason[-1]
    first = 1 + bool(dat)  # the .dat's point, the axis position, then the inline points
    assert at_once.targets[first + 2].external.tolist() == [0.0] * 6 and at_once.targets[first + 2].pose[0, 3] == 446.7
    assert at_once.targets[first + 3].external.tolist() == [5.0] and at_once.targets[first + 4].config == (2, 35)


def test_inline_motions_of_a_program_held_as_columns_are_written_as_the_objects_are(tmp_path, monkeypatch):
    src = "".join(f"  LIN {{X {400 + k * 0.5:.3f},Y {k * 0.25:.3f},Z 635.000,A 0.000,B 90.000,C 0.000}} C_DIS\n"
                  for k in range(50))
    (tmp_path / "p.src").write_text(f"DEF p( )\n  $VEL.CP = 0.05000\n{src}  LIN {{X 1,Y 2,Z 3,A 0,B 90,C 0}}\n"
                                    "  PTP {A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}\nEND\n")
    path = tmp_path / "p.src"
    at_once, one_by_one = formats.read(path), _one_by_one(path, monkeypatch)
    assert isinstance(at_once.targets, TargetRows) and not isinstance(one_by_one.targets, TargetRows)
    index = np.arange(0, 51, 2)
    poses = np.array([target.pose for target in one_by_one.targets[:51]])[index]
    poses[:, :3, 3] += [0.123456, -0.0004, 1e-7]
    poses[1, :3, :3] = poses[1, :3, :3] @ [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # C turned by 90 degrees
    written = []
    for program in (at_once, one_by_one):
        (tmp_path / "out").mkdir(exist_ok=True)
        formats.write(tmp_path / "out" / "q.src", program.with_targets(index, poses=poses))
        written.append((tmp_path / "out" / "q.src").read_bytes())
    assert written[0] == written[1] and b"DEF q( )" in written[0]
    lines = written[0].splitlines()  # the file's 3 decimals kept; a turned orientation: 4 at least
    assert lines[2] == b"  LIN {X 400.123,Y 0.000,Z 635.000,A 0.000,B 90.000,C 0.000} C_DIS"
    assert lines[4] == b"  LIN {X 401.123,Y 0.500,Z 635.000,A 90.0000,B 0.0000,C 90.0000} C_DIS"


def test_an_inline_point_out_of_range_is_refused_naming_its_line_as_one_by_one(tmp_path, monkeypatch):
    (tmp_path / "p.src").write_text("DEF p( )\n  LIN {X 1,Y 2,Z 3,A 0,B 90,C 0}\n"
                                    "  LIN {X 1,Y 2e9,Z 3,A 0,B 90,C 0}\nEND\n")
    path = tmp_path / "p.src"
    with pytest.raises(ReadError, match=re.escape("p.src:3")) as refused:
        formats.read(path)
    with pytest.raises(ReadError) as refused_one_by_one:
        _one_by_one(path, monkeypatch)
    assert str(refused.value) == str(refused_one_by_one.value) and "Y" in str(refused.value)
