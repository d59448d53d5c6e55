"""A RAPID module written as CAM tools write it, read at once (`grammar.WRITTEN_FORMS`, `forms.find_lines`): the same
program as the statement-by-statement read, the state in force at each line (tool, work object, speed data,
routine parameters, points assigned at run time), without an object per line."""

import re

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError
from trajcomp.formats.forms import find_lines
from trajcomp.formats.number_fields import line_bounds, text_codes
from trajcomp.formats.rapid import grammar
from trajcomp.formats.rapid import reader as rapid_reader
from trajcomp.formats.text import mask
from trajcomp.programs.tables import ItemRows, TargetRows
from tests.formats.test_formats_columnar import never_written

POINT = "  CONST robtarget p{0}:=[[{0}00,{0}0,500],[0,0,1,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];"


def _module(*body, points=4):
    return "\n".join(["MODULE Cam", *(POINT.format(k) for k in range(1, points + 1)), *body, "ENDMODULE", ""])


def _seen(program):
    """Everything a read gives, comparable: targets bit for bit with their spans, items, tools and frames."""
    targets = [(t.name, t.line, None if t.pose is None else t.pose.tobytes(), t.config, t.tool, t.frame,
                dict(t.spans)) for t in program.targets]
    return targets, [repr(item) for item in program.items], sorted(program.tools), sorted(program.frames)


def _both(path, monkeypatch):
    """The program read at once, and read statement by statement (no line found from its characters, no pattern
    matching)."""
    at_once = formats.read(path)
    with monkeypatch.context() as patch:
        _nothing_at_once(patch)
        return at_once, formats.read(path)


def _nothing_at_once(patch):
    """Patch the reader so that it reads no line at once."""
    never_written(patch, *grammar.WRITTEN_FORMS)


STATES = {
    "tool and work object set between runs": _module(
        "  PERS tooldata tGun:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];",
        "  PERS wobjdata wPart:=[FALSE,TRUE,\"\",[[10,20,30],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];",
        "  PROC main()",
        "    MoveL p1, v50, z1, tGun\\WObj:=wPart;",
        "    tGun.tframe := [[0,0,150],[1,0,0,0]];",
        "    MoveL p2, v50, z1, tGun\\WObj:=wPart;",
        "    MoveJ p3, vmax, fine, tool0;",
        "  ENDPROC"),
    "VAR speed data assigned in the code": _module(
        "  VAR speeddata vCut:=[80,500,5000,1000];",
        "  PROC main()",
        "    MoveL p1, vCut, z1, tool0;",
        "    vCut := [40,200,5000,1000];",
        "    MoveL p2, vCut, z1, tool0;",
        "    WaitTime 1;",
        "    MoveL p3, vCut, z1, tool0;",
        "    IF TRUE THEN",
        "      MoveL p4, vCut\\V:=30, z5, tool0;",
        "    ENDIF",
        "  ENDPROC"),
    "routine parameter, point assigned, expression": _module(
        "  PROC go(robtarget p2)",
        "    MoveL p2, v100, z1, tool0;",
        "    MoveL p1, v100\\T:=2.5, z1, tool0;",
        "  ENDPROC",
        "  PROC main()",
        "    p3.trans.x := 5;",
        "    MoveL p3, v100, z1, tool0;",
        "    MoveL Offs(p4,0,0,10), v100, z1, tool0;",
        "    MoveL p4, v100, z1, tool9;",
        "    go p2;",
        "  ENDPROC"),
    "inline targets as RoboDK writes them, tool changed between": _module(
        "  PERS tooldata tGun:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];",
        "  PROC main()",
        "    MoveL p1,v50,z1,tool0\\WObj:=wobj0;",
        "    MoveL [[500.5,-20.25,300],[0,0,1,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v50,z1,tGun\\WObj:=wobj0;",
        "    MoveJ [[510,-20,300],[0,0,1,0],[-1,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v100,fine,tGun;",
        "    tGun.tframe := [[0,0,150],[1,0,0,0]];",
        "    MoveL [[520,-20,300],[0,0,1,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v50\\V:=20,z1,tGun;",
        "    MoveL [[530,-20,300],[0,0,2,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],v50,z1,tGun;",
        "  ENDPROC"),
    "a statement spread over lines that look read at once": _module(
        "  PROC main()",
        "    MoveL p1, v100,",
        "    MoveL p2, v100, z1, tool0;",
        "    MoveL p3, v100, z1, tool0;",
        "  ENDPROC"),
}


@pytest.mark.parametrize("text", STATES.values(), ids=STATES)
def test_a_module_read_at_once_is_the_one_read_statement_by_statement(tmp_path, monkeypatch, text):
    path = tmp_path / "Cam.mod"
    path.write_text(text.replace("[0,0,2,0]", "[0,0,1,0]"))
    at_once, one_by_one = _both(path, monkeypatch)
    assert isinstance(at_once.items, ItemRows) and not isinstance(one_by_one.items, ItemRows)
    assert _seen(at_once) == _seen(one_by_one)
    assert at_once.not_compensated() == one_by_one.not_compensated()


def test_the_state_in_force_at_each_line(tmp_path):
    path = tmp_path / "Cam.mod"
    path.write_text(STATES["VAR speed data assigned in the code"])
    program = formats.read(path)
    assert isinstance(program.targets, TargetRows)  # every point read at once
    speeds = [(m.speed, m.speed_why[:26]) for m in program.motions]
    # changed in the code: run time until assigned a literal, which holds while the code runs straight (WaitTime)
    assert speeds == [(None, "vCut: VAR speeddata the mo"), (40.0, ""), (40.0, ""), (30.0, "")]
    path.write_text(STATES["tool and work object set between runs"])
    tools = [(m.tool, m.frame) for m in formats.read(path).motions]
    assert tools == [("tGun", "wPart"), ("tGun line 10", "wPart"), ("tool0", "wobj0")]


def test_targets_read_at_once_beside_targets_read_one_by_one(tmp_path, monkeypatch):
    """A CAM post's home jointtarget and inline robtargets join the points read at once, in program order."""
    path = tmp_path / "Cam.mod"
    path.write_text(_module(
        "  CONST jointtarget jHome:=[[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
        "  PROC main()",
        "    MoveAbsJ jHome, v500, fine, tool0;",
        "    MoveL p1, v50, z1, tool0;",
        "    MoveL [[5,6,7],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]], v50, z1, tool0\\WObj:=wobj0;",
        "    MoveL p2, v50, z1, tool0;",
        "  ENDPROC"))
    at_once, one_by_one = _both(path, monkeypatch)
    assert isinstance(at_once.targets, TargetRows)
    assert _seen(at_once) == _seen(one_by_one)
    assert [t.name for t in at_once.targets] == ["p1", "p2", "p3", "p4", "jHome", ""]
    np.testing.assert_allclose(np.degrees(at_once.targets[4].joints), [0, 0, 0, 0, 30, 0])
    np.testing.assert_allclose(at_once.targets[5].pose[:3, 3], [5, 6, 7])


def test_a_point_read_at_once_is_written_back_where_it_stands(tmp_path):
    path = tmp_path / "Cam.mod"
    path.write_text(STATES["tool and work object set between runs"])
    program = formats.read(path)
    moved = program.targets[1].pose.copy()
    moved[:3, 3] += [0.5, -0.25, 1.0]
    formats.write(tmp_path / "out.mod", program.with_targets([1], poses=[moved], configs=[(1, 0, -1, 1)]))
    line = (tmp_path / "out.mod").read_text().splitlines()[2]
    assert line == ("  CONST robtarget p2:=[[200.500,19.750,501.000],[0,0,1,0],[1,0,-1,1],"
                    "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];")


def test_inline_targets_read_at_once_in_program_order_and_a_refused_one_named(tmp_path):
    path = tmp_path / "Cam.mod"
    text = STATES["inline targets as RoboDK writes them, tool changed between"]
    path.write_text(text.replace("[0,0,2,0]", "[0,0,1,0]"))
    program = formats.read(path)
    assert isinstance(program.targets, TargetRows)
    assert [t.name for t in program.targets] == ["p1", "p2", "p3", "p4", "", "", "", ""]
    assert [t.config for t in program.targets[4:6]] == [(0, 0, 0, 1), (-1, 0, 0, 1)]
    np.testing.assert_allclose(program.targets[4].pose[:3, 3], [500.5, -20.25, 300])
    assert [(m.target, m.tool, m.speed) for m in program.motions] == [
        (0, "tool0", 50.0), (4, "tGun", 50.0), (5, "tGun", 100.0), (6, "tGun line 11", 20.0), (7, "tGun line 11", 50.0)]
    assert program.motions[1].spans["speed"].text == "v50" and "target_name" not in program.motions[1].spans
    path.write_text(text)  # a quaternion of length 2: the line-by-line read names it
    with pytest.raises(ReadError, match=r"Cam\.mod:13: robtarget: quaternion of length 2"):
        formats.read(path)


def test_an_undeclared_point_is_refused_naming_its_line(tmp_path):
    path = tmp_path / "Cam.mod"
    path.write_text(_module("  PROC main()", "    MoveL p1, v50, z1, tool0;", "    MoveL p9, v50, z1, tool0;",
                            "  ENDPROC"))
    with pytest.raises(ReadError, match=r"Cam\.mod: .* p9 \(line 8\)"):
        formats.read(path)


_RUN = ("  PROC main()", "    MoveL p1, v50, z1, tool0;", "    MoveJ p2,v100,fine,tool0;",
        "    MoveL p3, v50, z1, tool0;", "    MoveL p4, v50\\V:=12.5, z1, tool0\\WObj:=wobj0;  ! after the ';'",
        "  ENDPROC")
_REST = "[0,0,1,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];"  # a point's value after its position
VARIANTS = {  # each written as CAM tools may write it: the numbers read from the characters as float reads them
    "CRLF line endings": _module(*_RUN).replace("\n", "\r\n"),
    "exponents, signs, bare points": _module(*_RUN).replace("[[300,30,500]", "[[3E2,+.3e2,-5.e-1]").replace(
        "[[400,40,500]", "[[400.,-0.0,1.5000000000000002]"),
    "blanks inside a value and around :=": _module(*_RUN).replace("p2:=[[200,", "p2 := [[ 200,").replace(
        "[[300,30,500],[0,0,1,0]", "[[300,30,500],[0, 0, 1, 0]"),
    "non-ASCII comment before the points": _module(*_RUN).replace("MODULE Cam\n",
                                                                  "MODULE Cam\n  ! Bahn für Düse Ø6\n"),
    "mixed lines: a value over two lines, LOCAL, PERS": _module(*_RUN).replace(
        "  CONST robtarget p2:=[[200,20,500],", "  LOCAL PERS robtarget p2:=[[200,20,500],\n").replace(
        "  CONST robtarget p3", "  PERS robtarget p3"),
    "more digits than a double holds, a configuration written 1.0": _module(*_RUN).replace(
        "[[100,10,500]", "[[100.1234567890123456789,10,500]").replace(
        "[[400,40,500],[0,0,1,0],[0,0,0,1]", "[[400,40,500],[0,0,1,0],[0,0,0,1.0]"),
}


@pytest.mark.parametrize("text", VARIANTS.values(), ids=VARIANTS)
def test_a_variant_read_at_once_is_the_one_read_statement_by_statement(tmp_path, monkeypatch, text):
    path = tmp_path / "Cam.mod"
    path.write_bytes(text.encode("utf-8"))
    at_once, one_by_one = _both(path, monkeypatch)
    assert isinstance(at_once.items, ItemRows)
    assert _seen(at_once) == _seen(one_by_one)
    assert at_once.not_compensated() == one_by_one.not_compensated()


@pytest.mark.parametrize("value, message", [
    ("[[1E400,10,500]," + _REST, r"Cam\.mod:3: p2 x: '1E400' is out of range"),
    ("[[100,10,500],[0,0,1,0],[0,0,0.5,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];", r"Cam\.mod:3: p2 confdata cf6: "),
    ("[[100,10,500],[0,0,1,0],[0,0,0,1],[9E+09,9E+09,1e11,9E+09,9E+09,9E+09]];", r"Cam\.mod:3: p2 extax ec: '1e11' "),
    ("[[100,10,5x0]," + _REST, r"Cam\.mod:3: malformed robtarget: 'CONST robtarget p2:=\[\[100,10,5x0\]"),
])
def test_a_point_the_read_at_once_cannot_take_is_refused_naming_its_field(tmp_path, value, message):
    path = tmp_path / "Cam.mod"
    path.write_text(_module(*_RUN).replace("[[200,20,500]," + _REST, value))
    with pytest.raises(ReadError, match=message):
        formats.read(path)


@pytest.mark.parametrize("at", [0, 3, 5, 9, 12])
def test_data_words_across_the_pieces_looked_in_are_found(at):
    for word in ("SpeedData", "NUM"):
        text = "x" * (16 - at) + word + "y" * 20
        assert rapid_reader._declares_data(text, piece=16)
    assert not rapid_reader._declares_data("x" * 100 + "speed data nu m", piece=16)


def _robodk(*motions, speed="    rdkSpeed := [50.00,500,5000,1000];"):
    """A module as RoboDK's ABB_RAPID_IRC5 post writes it (tests/benchmarks/cam_forms.py, ``rapid:robodk``)."""
    return "\n".join([
        "%%%", "  VERSION:1", "  LANGUAGE:ENGLISH", "%%%", "", "MODULE MOD_Cam", "",
        "    LOCAL PERS tooldata rdkTool := [TRUE,[[0,0,0],[1,0,0,0]],[2,[0,0,15],[1,0,0,0],0,0,0.005]];",
        '    LOCAL PERS wobjdata rdkWObj := [FALSE, TRUE, "", [[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];',
        "    VAR speeddata rdkSpeed := [250,500,5000,1000]; ! set default speed", "",
        "    PROC Cam()", "        ConfJ \\On;", "        ConfL \\Off;",
        "        rdkTool.tframe := [[0.000, 0.000, 50.000],[1.00000000, 0.00000000, 0.00000000, 0.00000000]];",
        speed, *motions, "    ENDPROC", "", "ENDMODULE", ""])


_ROBODK_MOVE = ("        MoveL [[{0}.125, -20.250, 300.000],[0.00000000, 0.00000000, 1.00000000, 0.00000000],[0,0,0,1],"
                "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],rdkSpeed,z1,rdkTool,\\WObj:=rdkWObj;")
_ROBODK = [_ROBODK_MOVE.format(500 + k) for k in range(4)]
ROBODK_VARIANTS = {  # RoboDK's inline robtargets: a blank after each comma of the pose, the tool then ",\WObj"
    "as written": _robodk(*_ROBODK),
    "CRLF, lower case, a tab, blanks before ';'": _robodk(
        *_ROBODK[:2], _ROBODK[2].replace("MoveL", "movel\t").replace(";", "  ;"), *_ROBODK[3:]).replace("\n", "\r\n"),
    "the speed data set between motions, a WaitTime": _robodk(
        *_ROBODK[:2], "        rdkSpeed := [45.00,500,5000,1000];", _ROBODK[2], "        WaitTime 0.5;", _ROBODK[3]),
    "a speed data changed at run time": _robodk(*_ROBODK[:2], "        rdkSpeed.v_tcp := nFeed;", *_ROBODK[2:]),
    "non-ASCII comment, exponents, two blanks": _robodk(
        "        ! Fräsbahn Ø6 – Schlichten", _ROBODK[0].replace("500.125", "5.00125E2"),
        _ROBODK[1].replace(", -20.250", ",  -20.250"), *_ROBODK[2:]),
    "mixed: a named point, a MoveJ, a value over two lines": _robodk(
        *_ROBODK[:2], "        MoveJ [[505,-20,300],[0,0,1,0],[0,0,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],",
        "            rdkSpeed,fine,rdkTool,\\WObj:=rdkWObj;", *_ROBODK[2:]),
}


@pytest.mark.parametrize("text", ROBODK_VARIANTS.values(), ids=ROBODK_VARIANTS)
def test_robodk_variants_read_at_once_are_the_ones_read_statement_by_statement(tmp_path, monkeypatch, text):
    path = tmp_path / "Cam.mod"
    path.write_bytes(text.encode("utf-8"))
    at_once, one_by_one = _both(path, monkeypatch)
    assert isinstance(at_once.items, ItemRows) and isinstance(at_once.targets, TargetRows)
    assert _seen(at_once) == _seen(one_by_one)
    assert at_once.not_compensated() == one_by_one.not_compensated()


def test_robodk_speeds_tools_and_numbers_read_at_once(tmp_path):
    path = tmp_path / "Cam.mod"
    path.write_text(ROBODK_VARIANTS["the speed data set between motions, a WaitTime"])
    program = formats.read(path)
    assert [(m.speed, m.tool, m.frame) for m in program.motions] == [
        (50.0, "rdkTool line 15", "rdkWObj"), (50.0, "rdkTool line 15", "rdkWObj"),
        (45.0, "rdkTool line 15", "rdkWObj"), (45.0, "rdkTool line 15", "rdkWObj")]
    np.testing.assert_array_equal([t.pose[:3, 3] for t in program.targets],
                                  [[500.125, -20.25, 300.0], [501.125, -20.25, 300.0], [502.125, -20.25, 300.0],
                                   [503.125, -20.25, 300.0]])
    assert program.targets[0].spans["y"].text == "-20.250"  # the blank after the comma is not the number's
    path.write_text(ROBODK_VARIANTS["a speed data changed at run time"])
    assert [m.speed for m in formats.read(path).motions] == [50.0, 50.0, None, None]


def test_robodk_out_of_range_number_is_refused_naming_its_field(tmp_path):
    path = tmp_path / "Cam.mod"
    path.write_text(_robodk(*_ROBODK[:2], _ROBODK[2].replace("-20.250", "1E400"), *_ROBODK[3:]))
    with pytest.raises(ReadError, match=r"Cam\.mod:19: robtarget y: '1E400' is out of range"):
        formats.read(path)


@pytest.mark.parametrize("text", [*ROBODK_VARIANTS.values(), *VARIANTS.values(), *STATES.values()])
def test_lines_found_from_their_characters_are_those_the_patterns_match(text):
    """`find_lines` finds a subset of each pattern's lines, with the same groups; here all of them but those
    the patterns match with a \\V or \\T, a LOCAL or blanks before the ``;`` of a declaration."""
    masked = mask(text, "!")
    codes = text_codes(masked)
    starts, ends = line_bounds(codes)
    found = find_lines(grammar.WRITTEN_FORMS, codes, starts, ends)
    for form, (lines, groups) in zip(grammar.WRITTEN_FORMS, found):
        matched = {k: m.regs for k in range(len(starts)) if (m := form.regex.match(masked, starts[k], ends[k]))}
        assert {k: tuple(map(tuple, g)) for k, g in zip(lines.tolist(), groups.tolist())}.items() <= matched.items()
        left = [masked[starts[k]:ends[k]] for k in set(matched) - set(lines.tolist())]
        assert all(re.search(r"\\[VT]|LOCAL|\] ;", line) for line in left), left


def test_a_robodk_module_is_written_as_through_the_objects(tmp_path, monkeypatch):
    path = tmp_path / "Cam.mod"
    path.write_text(ROBODK_VARIANTS["mixed: a named point, a MoveJ, a value over two lines"])
    at_once, one_by_one = _both(path, monkeypatch)
    written = []
    for program, name in ((at_once, "at_once.mod"), (one_by_one, "one_by_one.mod")):
        poses = np.array([t.pose for t in program.targets])
        poses[:, :3, 3] += [0.25, -0.125, 1.0]
        formats.write(tmp_path / name, program.with_targets(list(range(len(poses))), poses=list(poses),
                                                            configs=[(0, -1, 0, 1)] * len(poses)))
        written.append((tmp_path / name).read_text())
    assert written[0] == written[1]
    assert ("MoveL [[500.375, -20.375, 301.000],[0.00000000, 0.00000000, 1.00000000, 0.00000000],[0,-1,0,1],"
            in written[0])


def test_lines_changed_at_random_are_found_at_once_only_as_their_pattern_matches_them():
    """The forms run at once (`forms.Form.find`) on lines changed at random (blanks, optional parts, other words,
    cuts, non-ASCII letters, carriage returns): every line found is one its pattern matches, with its groups, or
    one whose robtarget is not laid out as one (`_value_fields`: then read statement by statement)."""
    rng = np.random.default_rng(7)
    pieces = [" ", "\t", ",", ";", "\\V:=12", "\\WObj:=w1", "LOCAL ", "[", "]", "é", "\r", "x", "MoveL ", ":="]
    seeds = [line for text in (*VARIANTS.values(), *ROBODK_VARIANTS.values()) for line in text.splitlines()]
    lines = []
    for _ in range(3000):
        line = list(seeds[rng.integers(len(seeds))])
        for _ in range(rng.integers(1, 4)):
            at = int(rng.integers(len(line) + 1))
            if rng.random() < 0.5 and line:
                del line[min(at, len(line) - 1)]
            else:
                line[at:at] = pieces[rng.integers(len(pieces))]
        lines.append("".join(line))
    masked = mask("\n".join(lines), "!")
    codes = text_codes(masked)
    starts, ends = line_bounds(codes)
    found = find_lines(grammar.WRITTEN_FORMS, codes, starts, ends)
    for form, (rows, groups) in zip(grammar.WRITTEN_FORMS, found):
        for row, regs in zip(rows.tolist(), groups.tolist()):
            m = form.regex.match(masked, starts[row], ends[row])
            if m is None:
                value = regs[4] if form is grammar.WRITTEN_POINT else regs[2]
                laid_out = rapid_reader._value_fields(codes, np.array(value[:1]), np.array(value[1:]),
                                                      grammar.ROBTARGET.layout)[3]
                assert not laid_out[0], masked[starts[row]:ends[row]]
            else:
                assert m.regs == tuple(map(tuple, regs)), masked[starts[row]:ends[row]]
    assert sum(len(rows) for rows, _ in found) > 300  # many changed lines are still lines CAM tools write
