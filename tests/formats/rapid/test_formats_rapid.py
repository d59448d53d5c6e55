"""ABB RAPID reader and writer: declarations, moves, frames, confdata, errors."""

from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError
from trajcomp.arm.transforms import quat_to_matrix

WELDING = Path(__file__).parents[2] / "data" / "programs" / "rapid" / "Welding.mod"


@pytest.fixture(scope="module")
def welding():
    return formats.read(WELDING)


def _target(program, name):
    return program.targets[[t.name for t in program.targets].index(name)]


def test_declarations_tools_and_work_objects(welding):
    start = _target(welding, "pStart")
    np.testing.assert_allclose(start.pose[:3, 3], [100, 50, 2.5])
    np.testing.assert_allclose(start.pose[:3, :3], quat_to_matrix([-4.37114e-08, 0.707107, 0.707107, -4.37114e-08]), atol=1e-6)
    assert start.config == (-1, 0, -1, 1)
    assert _target(welding, "pVia").config == (0, -1, 0, 0)  # declaration over two lines
    np.testing.assert_allclose(welding.tools["tGun"][:3, 3], [12.5, -3, 245.75])
    table = welding.frames["wTable"]  # uframe * oframe
    np.testing.assert_allclose(table[:3, 3], [800 - 20, -300 + 10, 250], atol=1e-6)
    np.testing.assert_allclose(np.degrees(_target(welding, "jHome").joints), [0, 0, 0, 0, 30, 0])


def test_moves(welding):
    by_line = {m.line: m for m in welding.motions}
    assert welding.targets[by_line[21].target].name == "jHome"  # \NoEOffs ignored
    circ = by_line[24]
    assert (welding.targets[circ.via].name, welding.targets[circ.target].name) == ("pVia", "pEnd")
    assert (circ.speed, circ.zone, circ.tool, circ.frame) == (12.5, 1.0, "tGun", "wTable")
    assert (by_line[27].zone, by_line[27].tool, by_line[27].frame) == (7.5, "tool0", "wobj0")
    assert by_line[28].frame == "wFixture" and by_line[28].speed == 12.0  # CONST speeddata vWeld: its v_tcp
    assert welding.targets[by_line[29].target].name == "pApproach"  # \Conc
    assert welding.targets[by_line[30].target].is_joint
    assert {m.line for m in welding.runtime_motions()} == {25, 26, 31}  # Offs, RelTool, CRobT
    assert [t.name for t in welding.unused_targets()] == ["pUnused"]


def test_confdata_and_quaternion_sign_are_written(welding, tmp_path):
    start = _target(welding, "pStart")
    index = [t.name for t in welding.targets].index("pStart")
    turned = start.pose.copy()
    turned[:3, :3] = quat_to_matrix([0.0, 0.6, 0.8, 0.0])
    formats.write(tmp_path / "W.mod", welding.with_targets([index], poses=[turned], configs=[(0, 1, -2, 3)]))
    line = (tmp_path / "W.mod").read_text().splitlines()[10]
    assert line == (
        "    CONST robtarget pStart:=[[100.0,50.0,2.5],[0.00000000,0.60000000,0.80000000,0.00000000],"
        "[0,1,-2,3],[9E9,9E9,9E9,9E9,9E9,9E9]];"
    )


@pytest.mark.parametrize(
    "line, message",
    [
        ("CONST robtarget p1:=[[1,2],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];", "malformed robtarget"),
        ("CONST jointtarget j1:=[[1,2,3,4,5],[9E9,9E9,9E9,9E9,9E9,9E9]];", "malformed jointtarget"),
        ("MoveL p1, v100, z10;", "MoveL needs 4 arguments"),
        ("MoveL [[1,2,3],[1,0,0,0]], v100, z10, tool0;", "malformed robtarget"),
    ],
)
def test_malformed_statements_name_file_line_and_text(tmp_path, line, message):
    path = tmp_path / "M.mod"
    path.write_text(f"MODULE M\n  PROC main()\n    {line}\n  ENDPROC\nENDMODULE\n")
    with pytest.raises(ReadError, match=rf"M\.mod:3: {message}: '"):
        formats.read(path)


def test_wrong_language_is_a_clear_error(tmp_path):
    path = tmp_path / "p.mod"
    path.write_text("DEF p( )\nPTP HOME\nEND\n")
    with pytest.raises(ReadError, match="not a RAPID module"):
        formats.read(path)


def _module(tmp_path, body, decls=""):
    path = tmp_path / "M.mod"
    path.write_text(
        "MODULE M\n"
        "  CONST robtarget p10:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        "  CONST robtarget p20:=[[4,5,6],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        "  PERS tooldata MyTool:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n"
        "  PERS wobjdata Frame2:=[FALSE,TRUE,\"\",[[100,200,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n"
        f"{decls}  PROC main()\n{body}  ENDPROC\nENDMODULE\n"
    )
    return path


def test_work_object_after_a_comma_as_robodk_writes_it(tmp_path):
    program = formats.read(_module(tmp_path, "    MoveL p10, v100, z10, tool0,\\WObj:=Frame2;\n"
                                             "    MoveL p20, v100, z10, MyTool ,\\WObj:=Frame2 \\TLoad:=load0;\n"))
    assert [(m.tool, m.frame) for m in program.motions] == [("tool0", "Frame2"), ("MyTool", "Frame2")]


def test_identifiers_are_case_insensitive_and_tool0_wobj0_predefined(tmp_path):
    program = formats.read(_module(tmp_path, "    MoveL P10, v100, fine, Tool0\\WObj:=WOBJ0;\n"
                                             "    MoveJ p20, v100, fine, mytool\\WObj:=frame2;\n"))
    assert [(m.tool, m.frame) for m in program.motions] == [("tool0", "wobj0"), ("MyTool", "Frame2")]
    assert [program.targets[m.target].name for m in program.motions] == ["p10", "p20"]


def test_undeclared_point_is_refused_naming_it(tmp_path):
    path = _module(tmp_path, "    MoveL p10, v100, z10, tool0;\n    MoveL p30, v100, z10, tool0;\n"
                             "    MoveC p40, p20, v100, z10, tool0;\n")
    with pytest.raises(ReadError, match=r"M\.mod: .*p30 \(line 8\), p40 \(line 9\); no module of its folder declares"):
        formats.read(path)
    # another module of the task declares p30 and p40: read from it (a LOCAL point there is not seen)
    (tmp_path / "Data.sys").write_text("MODULE Data(SYSMODULE)\n  TASK PERS robtarget p30:=[[1,2,3],[1,0,0,0],"
                                       "[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n  CONST robtarget p40:=[[1,2,3],"
                                       "[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n")
    program = formats.read(path)
    assert program.not_compensated() == () and [s.name for s in program.sources] == ["M.mod", "Data.sys"]
    via_point = program.motions[2].via
    assert [program.where(i) for i in (program.motions[1].target, via_point)] == ["p30 (Data.sys:2)", "p40 (Data.sys:3)"]
    (tmp_path / "Data.sys").write_text("MODULE Data(SYSMODULE)\n  LOCAL CONST robtarget p30:=[[1,2,3],[1,0,0,0],"
                                       "[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n")
    with pytest.raises(ReadError, match=r"p30 \(line 8\), p40 \(line 9\); no module of its folder declares"):
        formats.read(path)


def test_motions_an_external_device_guides_are_listed(tmp_path):
    """EGM (Externally Guided Motion) moves the arm to poses a sensor streams at run time: listed as motions not read,
    as SearchL is (they were taken for a call that may move the arm, and no report line named them)."""
    body = ("    MoveL p10, v100, fine, tool0;\n    EGMMoveL egmID1, p10, v10, fine, tool0;\n"
            "    EGMRunPose egmID1, EGM_STOP_HOLD \\x \\y \\z \\CondTime:=20;\n")
    program = formats.read(_module(tmp_path, body, ""))
    assert [reason for _, _, reason in program.not_compensated()] == [
        f"{name}: instruction not read by trajcomp, left as written" for name in ("EGMMoveL", "EGMRunPose")]


def test_positions_known_only_at_run_time_are_listed_with_their_reason(tmp_path):
    body = ("    MoveL p10, v100, z10, tool0;\n    MoveL pTemp, v100, z10, tool0;\n    p20.trans.z := 50;\n"
            "    MoveL p20, v100, z10, tool0;\n    MoveL pts{2}, v100, z10, tool0;\n    MyProc p10;\n"
            "    SearchL \\Stop, di1, pHit, p10, v100, tool0;\n  ENDPROC\n"
            "  PROC MyProc(robtarget pGoal)\n    MoveL pGoal, v100, fine, tool0;\n")
    decls = "  VAR robtarget pTemp;\n  VAR robtarget pHit;\n"
    program = formats.read(_module(tmp_path, body, decls))
    reasons = {line: reason for line, _, reason in program.not_compensated()}
    assert reasons == {
        10: "pTemp is declared without a value (set at run time, line 6)",
        12: "p20 is changed at run time (line 11)",
        13: "position computed at run time: pts{2}",
        15: "SearchL: instruction not read by trajcomp, left as written",
        18: "pGoal: routine parameter, known at run time",
    }
    assert sorted((program.targets[i].name, line) for i, line, _ in program.referenced_targets()) == [
        ("p20", 11), ("p20", 12)]
    assert program.unused_targets() == ()


def test_points_passed_to_routines_are_referenced_not_unused(tmp_path):
    program = formats.read(_module(tmp_path, "    MoveL p10, v100, z10, tool0;\n    Glue p20, 3;\n"))
    assert [(program.targets[i].name, line, text) for i, line, text in program.referenced_targets()] == [
        ("p20", 8, "Glue p20, 3;")]
    assert program.unused_targets() == ()


def test_robodk_tool_and_work_object_assignments_set_their_values(tmp_path):
    # As RoboDK's ABB post (ABB_RAPID_IRC5.py, setFrame/setTool) writes them, before inline targets.
    body = ("    rdkWObj.uframe := [[500.000, 0.000, 100.000],[1.00000000, 0.00000000, 0.00000000, 0.00000000]];\n"
            "    rdkTool.tframe := [[0.000, 0.000, 200.000],[0.70710678, 0.00000000, 0.70710678, 0.00000000]];\n"
            "    MoveL [[10,0,0],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],rdkSpeed,z1,rdkTool,"
            "\\WObj:=rdkWObj;\n"
            "    rdkTool.tframe := CalcTool();\n"
            "    MoveL [[20,0,0],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]],rdkSpeed,z1,rdkTool,"
            "\\WObj:=rdkWObj;\n")
    decls = ("  LOCAL PERS tooldata rdkTool := [TRUE,[[0,0,0],[1,0,0,0]],[2,[0,0,15],[1,0,0,0],0,0,0.005]];\n"
             "  LOCAL PERS wobjdata rdkWObj := [FALSE, TRUE, \"\", [[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n")
    program = formats.read(_module(tmp_path, body, decls))
    first, second = program.motions
    assert (first.tool, first.frame) == ("rdkTool line 10", "rdkWObj line 9")
    np.testing.assert_allclose(program.frames[first.frame][:3, 3], [500, 0, 100])
    np.testing.assert_allclose(program.tools[first.tool][:3, 3], [0, 0, 200])
    assert second.target is None and second.reason == "rdkTool is changed at run time (line 12)"


@pytest.mark.parametrize(
    "target, message",
    [
        ("[[1,2,3],[1,0,0,0],[0,1e999,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]", "confdata cf4: '1e999' is out of range"),
        ("[[1,2,3],[1,0,0,0],[0,2.5,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]", "confdata cf4: '2.5' is not a whole number"),
        ("[[1,2,3],[0,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]", "quaternion of length 0, not a rotation"),
        ("[[1,2,1e999],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]", "z: '1e999' is out of range"),
    ],
)
def test_numbers_that_cannot_be_a_target_are_refused(tmp_path, target, message):
    path = _module(tmp_path, f"    MoveL {target}, v100, z10, tool0;\n")
    with pytest.raises(ReadError, match=rf"M\.mod:7: robtarget:? {message}"):
        formats.read(path)


def test_arc_and_trigg_instructions_are_compensated_with_their_tool(tmp_path):
    program = formats.read(_module(tmp_path, "    ArcL p10, v100, seam1, weld1\\Weave:=weave1, z10, MyTool\\WObj:=Frame2;\n"
                                             "    TriggL p20, v200, trigg1, fine, tool0;\n"))
    assert [(program.targets[m.target].name, m.speed, m.zone, m.tool, m.frame) for m in program.motions] == [
        ("p10", 100.0, 10.0, "MyTool", "Frame2"), ("p20", 200.0, None, "tool0", "wobj0")]


REAL = Path(__file__).parents[2] / "data" / "programs" / "real" / "rapid" / "1_T_ROB2.mod"


def test_real_compas_rrc_module_with_a_moving_track(tmp_path):
    program = formats.read(REAL)
    assert program.not_compensated() == () and len(program.usage()) == 11
    assert {m.frame for m in program.motions} == {"DefaultFrame", "wobj0"}
    assert program.targets[1].external[0] == 681.92 and np.isnan(program.targets[1].external[1:]).all()
    assert program.moving_external_axes() == ("E1",)
    from trajcomp.compensation.program_rewrite import convert_program

    formats.write(tmp_path / "track.src", convert_program(program, "krl"))  # no robot: no S/T, the track is kept
    again = formats.read(tmp_path / "track.src")
    np.testing.assert_array_equal([t.external[0] for t in again.targets], [t.external[0] for t in program.targets])
    assert again.moving_external_axes() == ("E1",)


def test_real_module_with_work_object_after_a_comma_and_run_time_targets():
    program = formats.read(REAL.parent / "Cymbergaj.mod")
    assert {m.frame for m in program.motions} == {"test_reakcji"}  # "tool0,\WObj:=test_reakcji": not wobj0
    assert [(line, reason) for line, _, reason in program.not_compensated()] == [
        (103, "target_position is declared without a value (set at run time, line 19)"),
        (113, "position computed at run time: Offs(target_position, 0, 0, 0)"),
        (120, "position computed at run time: Offs(home,0,0,0)"),
    ]
    assert [program.targets[i].name for i in program.usage()] == ["home"]


_FLOW = ["MODULE Flow", "  CONST robtarget p1:=[[100,0,500],[0,0,1,0],[0,0,0,1],[9E9,9E9,9E9,9E9,9E9,9E9]];",
         "  PROC main()", "    {}", "    MoveL p1, v100, z10, tool0;", "    {}", "  ENDPROC", "ENDMODULE", ""]


@pytest.mark.parametrize("opens, closes, message", [
    ("IF di1 = 1 THEN", "", r"Flow\.mod:4: IF has no ENDIF before the ENDPROC of line 7"),
    ("FOR i FROM 1 TO 3 DO", "", r"Flow\.mod:4: FOR has no ENDFOR before the ENDPROC of line 7"),
    ("WHILE di1 = 1 DO", "ENDWHILE\n    ENDWHILE", r"Flow\.mod:7: ENDWHILE closes no block"),
    ("TEST n", "", r"Flow\.mod:4: TEST has no ENDTEST before the ENDPROC of line 7"),
    ("", "ENDIF", r"Flow\.mod:6: ENDIF closes no block"),
    ("IF di1 = 1 AND\n      di2 = 0 THEN", "", r"Flow\.mod:4: IF has no ENDIF before the ENDPROC of line 8"),
])
def test_flow_blocks_not_closed_are_refused_naming_file_and_line(tmp_path, opens, closes, message):
    """A controller refuses to load a module whose IF, FOR, WHILE or TEST is not closed in order (issue 36):
    refused like the module's routines, naming the block's line; exit 2 from the command."""
    path = tmp_path / "Flow.mod"
    path.write_text("\n".join(_FLOW).format(opens, closes))
    with pytest.raises(ReadError, match=message):
        formats.read(path)
    from trajcomp.cli import main
    assert main(["convert", str(path), str(tmp_path / "out.mod"), "--robot", "abb_irb4600"]) == 2


def test_flow_blocks_closed_and_one_line_ifs_are_read(tmp_path):
    """Closed blocks, nested; ``IF cond instruction;`` (no THEN) is one statement, not a block; ELSEIF and CASE
    open none."""
    body = ["    IF di1 = 1 Stop;", "    IF di1 = 1 THEN", "      WHILE di2 = 0 DO", "        TEST n",
            "        CASE 1:", "          MoveL p1, v100, z10, tool0;", "        DEFAULT:", "        ENDTEST",
            "      ENDWHILE", "    ELSEIF di1 = 2 THEN", "      FOR i FROM 1 TO 3 DO", "      ENDFOR", "    ENDIF"]
    path = tmp_path / "Flow.mod"
    path.write_text("\n".join(_FLOW).format("\n".join(body), "if di1 = 0 then\n    endif"))
    assert len(formats.read(path).motions) == 2
