"""KRL's motions read at once (`trajcomp.formats.krl.reader._written_motions`) against the one-by-one read: the
state in force at each line (tool, base, speeds, zone), points changed at run time, refusals; and the speed
write-back and text edits of a program held as columns against the same program held as objects."""

import re

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError
from trajcomp.formats.krl import reader as krl_reader
from trajcomp.formats.text import edit_sources
from trajcomp.programs.tables import ItemRows

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
        patch.setattr(krl_reader, "_WRITTEN_MOTION", re.compile("(?!)"))
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
