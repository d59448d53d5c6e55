"""Programs as controllers hold them (issue 22, item 2): a program with the other files of its controller.

A RAPID module with the other modules of its task, a KRL program with the
controller's ``$config.dat`` and GLOBAL data lists: a point declared in
another file is read from it, corrected where it is declared (once, for
every file using it) and every changed file is written together. Each test
is a minimal program of that shape.
"""

import gzip
import json
import re
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import calibrated_model
from tests.programs.test_programs_as_run import OFFSET, _krl_point, _stand_in
from trajcomp import formats
from trajcomp.cli import main
from trajcomp.formats.configuration import configuration_data, configuration_for
from trajcomp.errors import ReadError, WriteError
from trajcomp.formats.task import groups
from trajcomp.arm.kinematics import fk
from trajcomp.compensation.program_rewrite import compensate_program
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import matrix_to_quat, matrix_to_rotvec

UNUSED = "[9E9,9E9,9E9,9E9,9E9,9E9]"


def _robtarget(robot, q):
    """A robtarget literal of the ABB arm at joints ``q`` (deg), with its confdata."""
    T = fk(robot, np.radians(q)[None])[0]
    conf = configuration_for(configuration_data("rapid"), robot, np.radians(q)[None])[0]
    position = ",".join(f"{v:.3f}" for v in T[:3, 3])
    quat = ",".join(f"{v:.8f}" for v in matrix_to_quat(T[:3, :3]))
    return f"[[{position}],[{quat}],[{','.join(map(str, conf))}],{UNUSED}]"


def _task(folder, robot):
    """A RAPID task: Main.mod moves to its own p10 and to p30, p40 that Data.sys declares (and a jointtarget)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "Data.sys").write_text(
        "MODULE Data(SYSMODULE)\n"
        f"  TASK PERS robtarget p30:={_robtarget(robot, [5, 10, 15, 0, 50, 0])};\n"
        f"  CONST robtarget p40:=\n    {_robtarget(robot, [-5, 12, 10, 0, 55, 0])};\n"
        "  CONST jointtarget jHome:=[[0,0,0,0,30,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n")
    (folder / "Main.mod").write_text(
        f"MODULE Main\n  CONST robtarget p10:={_robtarget(robot, [0, 10, 15, 0, 50, 0])};\n"
        "  PROC main()\n    MoveAbsJ jHome,v1000,fine,tool0;\n    MoveJ p10,v1000,z10,tool0;\n"
        "    MoveL p30,v100,z10,tool0;\n    MoveL p40,v100,fine,tool0;\n  ENDPROC\nENDMODULE\n")
    return folder / "Main.mod"


def _position(text, name):
    """x, y, z of robtarget ``name`` in a module's text."""
    m = re.search(name + r"\s*:=\s*\[\[([^\]]*)\]", text)
    return np.array([float(v) for v in m.group(1).split(",")])


def test_a_rapid_point_another_module_declares_is_corrected_there_and_written_beside(tmp_path):
    robot = load_robot("abb_irb4600")
    main_mod = _task(tmp_path / "task", robot)
    data_before = (tmp_path / "task" / "Data.sys").read_text()
    (tmp_path / "out").mkdir()
    program = formats.read(main_mod)
    assert program.not_compensated() == ()
    assert [(s.name, s.companion) for s in program.sources] == [("Main.mod", False), ("Data.sys", True)]
    assert [program.where(m.target) for m in program.motions] == [
        "jHome (Data.sys:5)", "p10 (Main.mod:2)", "p30 (Data.sys:2)", "p40 (Data.sys:3)"]
    edited, report = compensate_program(program, _stand_in(robot), robot)
    written = formats.write(tmp_path / "out" / "Main.mod", edited)
    assert sorted(p.name for p in written) == ["Data.sys", "Main.mod"]
    data_after = (tmp_path / "out" / "Data.sys").read_text()
    for name in ("p30", "p40"):  # moved by the stand-in's offset where Data.sys declares them
        np.testing.assert_allclose(_position(data_after, name) - _position(data_before, name), OFFSET, atol=1e-3)
    # nothing but the corrected numbers changed: the jointtarget (kept) and every other byte as written
    assert [line for line in data_after.splitlines() if "robtarget" not in line and "[[" not in line] == \
        [line for line in data_before.splitlines() if "robtarget" not in line and "[[" not in line]
    assert formats.read(tmp_path / "out" / "Main.mod").not_compensated() == ()


def test_a_companion_whose_points_did_not_change_is_not_written(tmp_path):
    robot = load_robot("abb_irb4600")
    folder = tmp_path / "task"
    folder.mkdir()
    (folder / "Data.sys").write_text("MODULE Data(SYSMODULE)\n  CONST jointtarget jHome:=[[0,0,0,0,30,0],"
                                     "[9E9,9E9,9E9,9E9,9E9,9E9]];\nENDMODULE\n")
    (folder / "Main.mod").write_text(f"MODULE Main\n  CONST robtarget p10:={_robtarget(robot, [0, 10, 15, 0, 50, 0])};\n"
                                     "  PROC main()\n    MoveAbsJ jHome,v1000,fine,tool0;\n"
                                     "    MoveJ p10,v1000,z10,tool0;\n  ENDPROC\nENDMODULE\n")
    edited, _ = compensate_program(formats.read(folder / "Main.mod"), _stand_in(robot), robot)  # joints kept
    (tmp_path / "out").mkdir()
    assert [p.name for p in formats.write(tmp_path / "out" / "Main.mod", edited)] == ["Main.mod"]


def test_changed_files_are_written_all_or_none(tmp_path):
    robot = load_robot("abb_irb4600")
    edited, _ = compensate_program(formats.read(_task(tmp_path / "task", robot)), _stand_in(robot), robot)
    (tmp_path / "out" / "Data.sys").mkdir(parents=True)  # the companion cannot be written there
    with pytest.raises(WriteError):
        formats.write(tmp_path / "out" / "Main.mod", edited)
    assert not (tmp_path / "out" / "Main.mod").exists()


def test_a_companion_beside_the_program_is_an_input_and_is_not_overwritten_without_in_place(tmp_path):
    robot = load_robot("abb_irb4600")
    main_mod = _task(tmp_path, robot)
    before = (tmp_path / "Data.sys").read_text()
    program = formats.read(main_mod)
    edited, _ = compensate_program(program, _stand_in(robot), robot)
    with pytest.raises(WriteError, match="Data.sys"):
        formats.write(tmp_path / "Main_corrected.mod", edited, protect=formats.input_paths(main_mod, program))
    assert not (tmp_path / "Main_corrected.mod").exists()
    formats.write(main_mod, edited)  # in place: both files replaced together
    np.testing.assert_allclose(_position((tmp_path / "Data.sys").read_text(), "p30"), _position(before, "p30") + OFFSET,
                               atol=1e-3)


def test_rapid_points_modules_change_at_run_time_are_listed_with_where(tmp_path):
    robot = load_robot("abb_irb4600")
    main_mod = _task(tmp_path, robot)
    (tmp_path / "Main.mod").write_text(main_mod.read_text().replace("CONST robtarget p10", "PERS robtarget p10"))
    (tmp_path / "Teach.mod").write_text("MODULE Teach\n  PROC teach()\n    p10.trans.z := 500;\n"
                                        "    p30 := CRobT();\n  ENDPROC\nENDMODULE\n")
    assert [reason for _, _, reason in formats.read(main_mod).not_compensated()] == [
        "p10 is changed at run time (Teach.mod:3)", "p30 is changed at run time (Teach.mod:4)"]
    # a point another module declares without a value, and a LOCAL one no other module sees
    (tmp_path / "Teach.mod").write_text("MODULE Teach\n  VAR robtarget pHit;\n  LOCAL CONST robtarget pMine:="
                                        f"{_robtarget(robot, [0, 10, 15, 0, 50, 0])};\nENDMODULE\n")
    (tmp_path / "Main.mod").write_text(main_mod.read_text().replace("MoveL p40", "MoveL pHit"))
    assert formats.read(main_mod).not_compensated()[0][2] == "pHit: Teach.mod:2 declares it without a value " \
                                                              "(set at run time)"
    (tmp_path / "Main.mod").write_text(main_mod.read_text().replace("MoveL pHit", "MoveL pMine"))
    with pytest.raises(ReadError, match=r"pMine \(line 7\); no module of its folder declares"):
        formats.read(main_mod)


def test_a_routine_head_over_several_lines_with_an_optional_parameter_is_read(tmp_path):
    """L_support.sys of a real backup: ``PROC CheckE6Ax(\\n jointtarget ExpectJoint\\n \\switch ArmOnly)``."""
    (tmp_path / "L.sys").write_text("MODULE L(SYSMODULE)\n PROC CheckE6Ax(\n    jointtarget ExpectJoint\n"
                                    "    \\switch ArmOnly)\n    MoveAbsJ ExpectJoint,v200,fine,tool0;\n"
                                    "  ENDPROC\nENDMODULE\n")
    assert formats.read(tmp_path / "L.sys").not_compensated() == (
        (5, "MoveAbsJ ExpectJoint,v200,fine,tool0;", "ExpectJoint: routine parameter, known at run time"),)


# ------------------------------------------------------------------ KUKA: $config.dat and GLOBAL data lists


def _krc(tmp_path, robot):
    """A KRC backup: R1/Program/weld.src using XSHARED of R1/System/$config.dat and XTABLE of a GLOBAL list."""
    program_folder, system = tmp_path / "KRC" / "R1" / "Program", tmp_path / "KRC" / "R1" / "System"
    program_folder.mkdir(parents=True)
    system.mkdir()
    point = "{{X {:.3f},Y {:.3f},Z {:.3f},A {:.4f},B {:.4f},C {:.4f},S {},T {}}}".format
    (program_folder / "weld.src").write_text("DEF weld( )\nPTP XP1\nLIN XSHARED\nLIN XTABLE\nEND\n")
    (program_folder / "weld.dat").write_text(
        f"DEFDAT weld\nDECL E6POS XP1={point(*_krl_point(robot, [0, -90, 90, 0, 45, 0]))}\nENDDAT\n")
    (program_folder / "table.dat").write_text(
        f"DEFDAT table PUBLIC\nDECL GLOBAL E6POS XTABLE={point(*_krl_point(robot, [5, -85, 95, 0, 40, 0]))}\n"
        "DECL E6POS XPRIVATE={X 1,Y 0,Z 7,A 0,B 90,C 0,S 2,T 2}\nDECL GLOBAL FRAME XLATER\nENDDAT\n")
    (system / "$config.dat").write_text(
        f"DEFDAT $CONFIG\nE6AXIS XHOME={{A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}}\n"
        f"DECL GLOBAL E6POS XSHARED={point(*_krl_point(robot, [-5, -88, 92, 0, 42, 0]))}\nENDDAT\n")
    return program_folder / "weld.src"


def _xyz(text, name):
    m = re.search(name + r"=\{X ([-\d.]+),Y ([-\d.]+),Z ([-\d.]+)", text)
    return np.array([float(v) for v in m.groups()])


def test_krl_points_of_config_dat_and_global_data_lists_are_corrected_where_declared(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    weld = _krc(tmp_path, robot)
    program = formats.read(weld)
    assert program.not_compensated() == ()
    assert [program.where(m.target) for m in program.motions] == [
        "XP1 (weld.dat:2)", "XSHARED ($config.dat:3)", "XTABLE (table.dat:2)"]
    edited, _ = compensate_program(program, _stand_in(robot), robot)
    config = weld.parents[1] / "System" / "$config.dat"
    before = {p: p.read_text() for p in (weld, config, weld.with_name("table.dat"))}
    # written elsewhere, $config.dat (../System) would leave the output's folder: refused, nothing written
    with pytest.raises(WriteError, match=r"System/\$config\.dat: \$config\.dat, .* outside the output's folder"):
        formats.write(tmp_path / "out" / "weld.src", edited)
    assert not (tmp_path / "out").exists()
    written = formats.write(weld, edited)  # in place: the .src, its .dat, table.dat and $config.dat together
    assert sorted(p.name for p in written) == ["$config.dat", "table.dat", "weld.dat", "weld.src"]
    assert weld.read_text() == before[weld]
    np.testing.assert_allclose(_xyz(config.read_text(), "XSHARED") - _xyz(before[config], "XSHARED"), OFFSET,
                               atol=1e-3)
    assert "XHOME={A1 0,A2 -90" in config.read_text()


def test_krl_points_other_programs_cannot_see_or_that_they_change(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    weld = _krc(tmp_path, robot)
    weld.write_text("DEF weld( )\nPTP XP1\nLIN XLATER\nLIN XPRIVATE\nEND\n")
    # a point another data list declares without GLOBAL: no other program sees it (the controller refuses too)
    with pytest.raises(ReadError, match=r"XPRIVATE \(line 4\)"):
        formats.read(weld)
    weld.write_text("DEF weld( )\nPTP XP1\nLIN XLATER\nLIN XTABLE\nEND\n")
    (weld.parent / "teach.src").write_text("DEF teach( )\nXTABLE.Z = 500\nEND\n")
    assert [reason for _, _, reason in formats.read(weld).not_compensated()] == [
        "XLATER is declared without a value (set at run time, table.dat:4)",
        "XTABLE is changed at run time (teach.src:2)"]


def test_programs_of_a_backup_sharing_a_point_run_as_one_and_keep_its_layout(tmp_path, kuka_model):
    robot = load_robot("kuka_kr6_r900")
    weld = _krc(tmp_path, robot)
    (weld.parent / "seam.src").write_text("DEF seam( )\nPTP XSHARED\nEND\n")
    (weld.parent / "alone.src").write_text(weld.read_text().replace("weld", "alone").replace("LIN XSHARED\n", "")
                                           .replace("LIN XTABLE\n", ""))
    (weld.parent / "alone.dat").write_text(weld.with_suffix(".dat").read_text().replace("weld", "alone"))
    paths = [weld.parent / name for name in ("alone.src", "seam.src", "weld.src")]
    assert groups(paths) == [[0], [1, 2]]  # seam and weld both use XSHARED of $config.dat
    out = tmp_path / "out"
    code = main(["compensate", str(tmp_path / "KRC"), "--model", str(kuka_model), "-o", str(out), "--jobs", "1",
                 "--retime", "none"])
    summary = json.loads((out / "summary.json").read_text())
    inputs = [Path(name).name for f in summary["files"] for name in f["input"].split(" + ")]
    assert inputs == ["alone.src", "seam.src", "weld.src"] and len(summary["files"]) == 2
    assert code == summary["exit_code"] and {f["status"] for f in summary["files"]} <= {"pass", "fail"}
    shared = _xyz((out / "R1" / "System" / "$config.dat").read_text(), "XSHARED")
    original = _xyz((tmp_path / "KRC" / "R1" / "System" / "$config.dat").read_text(), "XSHARED")
    assert 0.01 < np.linalg.norm(shared - original) < 10.0  # corrected once, in the one $config.dat written
    for name in ("weld.src", "weld.dat", "seam.src", "table.dat", "alone.src", "alone.dat"):
        assert (out / "R1" / "Program" / name).is_file()


def test_a_task_read_as_one_program_holds_a_shared_point_once_and_keeps_different_tools_apart(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    weld = _krc(tmp_path, robot)
    (weld.parent / "a.src").write_text("DEF a( )\n$TOOL={X 0,Y 0,Z 100,A 0,B 0,C 0}\nLIN XSHARED\nEND\n")
    (weld.parent / "b.src").write_text("DEF b( )\n$TOOL={X 0,Y 0,Z 200,A 0,B 0,C 0}\nLIN XSHARED\nEND\n")
    program = formats.read_task([weld.parent / "a.src", weld.parent / "b.src"])
    assert [s.name for s in program.sources] == ["a.src", "$config.dat", "b.src"]
    assert sorted(program.tools) == ["0", "TOOL line 2", "TOOL line 2 (b.src)"]
    # one set of numbers cannot serve both tools: b.src's use goes to a copy declared after XSHARED in $config.dat
    assert [program.where(m.target) for m in program.motions] == ["XSHARED ($config.dat:3)", "XSHARED_2 ($config.dat:4)"]
    assert "DECL GLOBAL E6POS XSHARED_2={X " in program.sources[1].text
    assert "LIN XSHARED_2\n" in program.sources[2].text and program.not_compensated() == ()


# ------------------------------------------------------------------ a point used with several tools or frames


def test_each_further_use_of_a_point_gets_a_corrected_copy_named_and_reported(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    weld = _krc(tmp_path, robot)
    weld.write_text("DEF weld( )\nBAS(#TOOL,1)\nPTP XP1\nLIN XTABLE\nBAS(#TOOL,2)\nLIN XTABLE\nPTP XP1\n"
                    "BAS(#TOOL,1)\nLIN XTABLE\nEND\n")
    flange = {"1": np.eye(4), "2": np.eye(4)}
    flange["2"][2, 3] = 50.0
    program = formats.read(weld)
    assert [program.where(m.target) for m in program.motions] == [
        "XP1 (weld.dat:2)", "XTABLE (table.dat:2)", "XTABLE_2 (table.dat:3)", "XP1_2 (weld.dat:3)",
        "XTABLE (table.dat:2)"]
    edited, report = compensate_program(program, _stand_in(robot), robot, tools=flange)
    assert report.warnings[:2] == (
        "point XTABLE is used with tool/frame ('2', None) (line 6) besides its first use: written as a copy "
        "XTABLE_2 after it (table.dat:3), corrected for that use",
        "point XP1 is used with tool/frame ('2', None) (line 7) besides its first use: written as a copy XP1_2 "
        "after it (weld.dat:3), corrected for that use")
    formats.write(weld, edited)
    table = weld.with_name("table.dat").read_text().splitlines()
    assert table[1].startswith("DECL GLOBAL E6POS XTABLE={X ") and table[2].startswith("DECL GLOBAL E6POS XTABLE_2={X ")
    assert table[3].startswith("DECL E6POS XPRIVATE=")  # the rest as it was
    assert weld.read_text().splitlines()[5:7] == ["LIN XTABLE_2", "PTP XP1_2"]
    again = formats.read(weld)  # the written task reads back with no point shared: each copy is its own
    assert again.notes == () and again.not_compensated() == ()
    # each copy is solved for its own tool: the same TCP target, the flange 50 mm back along the tool axis
    T = {label.split(" ")[0]: T for label, T in zip(report.labels, report.T_target)}
    q = {label.split(" ")[0]: q for label, q in zip(report.labels, report.q)}
    np.testing.assert_allclose(T["XTABLE_2"], T["XTABLE"], atol=1e-9)
    flanges = {name: fk(robot, q[name][None], tcp=False)[0] for name in ("XTABLE", "XTABLE_2")}
    np.testing.assert_allclose(flanges["XTABLE"][:3, 3] - flanges["XTABLE_2"][:3, 3], 50.0 * T["XTABLE"][:3, 2],
                               atol=1e-6)


def _ur_pose(robot, q):
    """``x, y, z, rx, ry, rz`` (m, rad) of the UR arm's TCP at joints ``q`` (rad), as a URScript pose literal."""
    T = fk(robot, np.asarray(q)[None])[0]
    return ", ".join(f"{v:.6f}" for v in [*(T[:3, 3] / 1000.0), *matrix_to_rotvec(T[:3, :3])])


def test_a_urscript_pose_variable_used_with_two_tcps_gets_a_copy_per_tcp(tmp_path):
    robot = load_robot("ur10")
    path = tmp_path / "two.script"
    path.write_text(f"def prog():\n  pick = p[{_ur_pose(robot, [0.2, -1.2, 1.4, -1.7, -1.57, 0.3])}]\n"
                    "  set_tcp(p[0,0,0.1,0,0,0])\n  movel(pick, a=1.2, v=0.25)\n  set_tcp(p[0,0,0.2,0,0,0])\n"
                    "  movel(pick, a=1.2, v=0.25) # pick again\nend\n")
    program = formats.read(path)  # the name twice on line 6 (a comment): the line is not renamed, nothing copied
    assert [reason for _, _, reason in program.not_compensated()] == [
        "point pick is used here with tool/frame ('set_tcp line 3', None) and with ('set_tcp line 5', None) at line 6: "
        "one set of numbers cannot be right for both, and no copy is written: its name is not written once in 6: "
        "movel(pick, a=1.2, v=0.25) # pick again; left as written",
        "point pick is used here with tool/frame ('set_tcp line 5', None) and with ('set_tcp line 3', None) at line 4: "
        "one set of numbers cannot be right for both, and no copy is written: its name is not written once in 6: "
        "movel(pick, a=1.2, v=0.25) # pick again; left as written"]
    path.write_text(path.read_text().replace(" # pick again", ""))
    program = formats.read(path)
    assert program.sources[0].text.splitlines()[1:3] == [
        f"  pick = p[{_ur_pose(robot, [0.2, -1.2, 1.4, -1.7, -1.57, 0.3])}]",
        f"  pick_2 = p[{_ur_pose(robot, [0.2, -1.2, 1.4, -1.7, -1.57, 0.3])}]"]
    assert [program.where(m.target) for m in program.motions] == ["pick (two.script:2)", "pick_2 (two.script:3)"]
    assert program.not_compensated() == () and len(program.notes) == 1
    edited, report = compensate_program(program, _stand_in(robot), robot)
    formats.write(path, edited)
    assert "  movel(pick_2, a=1.2, v=0.25)" in path.read_text() and formats.read(path).notes == ()
    # each copy solved for its own TCP: the same target, the flange 100 mm further back along the tool axis
    T = dict(zip((label.split(" ")[0] for label in report.labels), report.T_target))
    q = dict(zip((label.split(" ")[0] for label in report.labels), report.q))
    np.testing.assert_allclose(T["pick_2"], T["pick"], atol=1e-9)
    flanges = {name: fk(robot, q[name][None], tcp=False)[0] for name in ("pick", "pick_2")}
    np.testing.assert_allclose(flanges["pick"][:3, 3] - flanges["pick_2"][:3, 3], 100.0 * T["pick"][:3, 2], atol=1e-6)


def test_a_point_that_cannot_be_copied_lists_each_motion_with_its_tool_and_why(tmp_path):
    path = tmp_path / "pair.script"  # PolyScope's pair: the joints of Waypoint_1_p are Waypoint_1_q's list
    path.write_text("def prog():\n  global Waypoint_1_p=p[0.5, -0.2, 0.4, 0, 3.14159, 0]\n"
                    "  global Waypoint_1_q=[0.1, -1.2, 1.4, -1.7, -1.57, 0.0]\n  set_tcp(p[0,0,0.1,0,0,0])\n"
                    "  movej(get_inverse_kin(Waypoint_1_p, qnear=Waypoint_1_q), a=1.39, v=1.04)\n"
                    "  set_tcp(p[0,0,0.2,0,0,0])\n  movel(Waypoint_1_p, a=1.2, v=0.25)\nend\n")
    program = formats.read(path)
    assert program.notes == () and [(line, reason) for line, _, reason in program.not_compensated()] == [
        (5, "point Waypoint_1_p is used here with tool/frame ('set_tcp line 4', None) and with ('set_tcp line 6', "
            "None) at line 7: one set of numbers cannot be right for both, and no copy is written: its joints are a "
            "list another variable holds (pair.script line 3), which a copy would share; left as written"),
        (7, "point Waypoint_1_p is used here with tool/frame ('set_tcp line 6', None) and with ('set_tcp line 4', "
            "None) at line 5: one set of numbers cannot be right for both, and no copy is written: its joints are a "
            "list another variable holds (pair.script line 3), which a copy would share; left as written")]


REAL = Path(__file__).parents[1] / "data" / "programs" / "real"


def test_real_backups_resolve_points_and_tools_across_their_files():
    """An ABB backup's TASK1 (points in Point_ALL.mod, tools in Tool_Create.mod) and a KUKA palletiser's folder
    (points in the GLOBAL list varglobal.dat, $config.dat beside): tests/data/programs/real/SOURCES.txt."""
    program = formats.read(REAL / "rapid" / "keen1949_TASK1" / "PROGMOD" / "Homeing_Init.mod")
    assert program.not_compensated() == () and len(program.motions) == 9
    assert {s.name for s in program.sources if s.companion} == {"Point_ALL.mod", "Tool_Create.mod"}
    assert {program.where(m.target).split(" (")[1].split(":")[0] for m in program.motions} == {"Point_ALL.mod"}
    np.testing.assert_allclose(program.tools["tool3"][:3, 3], [-41.8404, 134.725, 0.0])  # Tool_Create.mod:22
    # a module of the same backup naming points no module declares: the controller cannot load it either
    with pytest.raises(ReadError, match="Point_Assemble"):
        formats.read(Path(__file__).parents[1] / "data" / "refused" / "rapid" / "keen1949_Teachpoint.mod")
    reasons = [reason for _, _, reason in formats.read(REAL / "krl" / "bpf2pltzpk2" / "pickup.src").not_compensated()]
    assert reasons[0] == "BefPikPos is declared without a value (set at run time, varglobal.dat:166)"
    assert [reason for _, _, reason in formats.read(REAL / "krl" / "bpf2pltzpk2" / "gotoorigin.src").not_compensated()] \
        == ["position computed at run time: {Z 500}"] * 2  # LIN {Z 500}: was refused


# ------------------------------------------------------------------ PolyScope: a .urp beside the .script

URP = """<?xml version="1.0" encoding="UTF-8"?>
<URProgram name="pick">
  <children>
    <MainProgram runOnlyOnce="false">
      <children>
        <Move motionType="MoveJ" speed="1.0471975511965976" acceleration="1.3962634015954636" useActiveTCP="true">
          <children>
            <Waypoint type="Fixed" name="Waypoint_1" kinematicsFlags="1">
              <motionParameters/>
              <position>
                <JointAngles angles="0.0, -1.2, 1.4, -1.7, -1.57, 0.0"/>
                <TCPOffset pose="0.0, 0.0, 0.0, 0.0, 0.0, 0.0"/>
              </position>
              <BaseToFeature pose="0.0, 0.0, 0.0, 0.0, 0.0, 0.0"/>
            </Waypoint>
          </children>
        </Move>
      </children>
    </MainProgram>
  </children>
</URProgram>
"""  # HAND-WRITTEN, in the layout of a PolyScope 3.x/5.x .urp (gzip XML) as public notes quote it


def test_a_polyscope_urp_beside_the_script_is_named_in_the_report_as_not_corrected(tmp_path):
    robot = load_robot("ur10")
    q = np.array([0.0, -1.2, 1.4, -1.7, -1.57, 0.0])
    T = fk(robot, q[None])[0]
    pose = ", ".join(f"{v:.6f}" for v in [*(T[:3, 3] / 1000.0), *matrix_to_rotvec(T[:3, :3])])
    script = tmp_path / "pick.script"
    script.write_text("def pick():\n  global Waypoint_1_p=p[" + pose + "]\n  global Waypoint_1_q=["
                      + ", ".join(map(str, q)) + "]\n  movej(get_inverse_kin(Waypoint_1_p, qnear=Waypoint_1_q), "
                      "a=1.39, v=1.04)\nend\n")
    assert formats.read(script).notes == ()  # no PolyScope program beside it: nothing to say
    (tmp_path / "pick.urp").write_bytes(gzip.compress(URP.encode()))
    urp = (tmp_path / "pick.urp").read_bytes()
    program = formats.read(script)
    assert [s.name for s in program.sources] == ["pick.script"]  # the .urp is not read as a file of the program
    edited, report = compensate_program(program, _stand_in(robot), robot)
    assert report.warnings == (
        "pick.urp beside pick.script is PolyScope's program, from which the controller generates the script: "
        "trajcomp corrects the script only, pick.urp is not corrected (its waypoints are joint angles under the "
        "arm's own calibrated kinematics); run the corrected script, and do not open and save pick.urp over it (nor "
        "a copy of it beside the output): PolyScope would regenerate the script from the uncorrected waypoints",)
    assert [p.name for p in formats.write(script, edited)] == ["pick.script"]
    assert (tmp_path / "pick.urp").read_bytes() == urp  # left exactly as it was


def test_a_task_of_several_files_names_the_file_of_each_motion_it_lists(tmp_path, kuka_model):
    robot = load_robot("kuka_kr6_r900")
    weld = _krc(tmp_path, robot)
    weld.write_text("DEF weld( )\nPTP XP1\nLIN XSHARED\nLIN {Z 500}\nEND\n")
    (weld.parent / "seam.src").write_text("DEF seam( )\nPTP XSHARED\n\nLIN {Z 400}\nEND\n")
    task = formats.read_task([weld, weld.parent / "seam.src"])
    # line 4 of each file: the place names the file, not a line number of the wrong one
    assert task.not_compensated() == (("weld.src:4", "LIN {Z 500}", "position computed at run time: {Z 500}"),
                                      ("seam.src:4", "LIN {Z 400}", "position computed at run time: {Z 400}"))
    assert formats.read(weld).not_compensated()[0][0] == 4  # a program of one file: its line number alone
    _, report = compensate_program(task, _stand_in(robot), robot)
    assert "  seam.src:4: LIN {Z 400} (position computed at run time: {Z 400})" in report.lines_of_text()
    out = tmp_path / "out"
    main(["compensate", str(tmp_path / "KRC"), "--model", str(kuka_model), "-o", str(out), "--jobs", "1",
          "--retime", "none", "--report", str(tmp_path / "reports")])
    (document,) = [json.loads(p.read_text()) for p in (tmp_path / "reports").rglob("*.json")]
    assert [(m.get("file"), m["line"], m["text"]) for m in document["not_compensated"]] == [
        ("seam.src", 4, "LIN {Z 400}"), ("weld.src", 4, "LIN {Z 500}")]


def test_a_task_whose_motions_lie_in_its_second_module_gets_its_speeds_written_there(tmp_path):
    """BData.mod (a tooldata only) sorts before ZMain.mod (the motions): the speed write-back once edited
    the first module's text at the second's positions (IndexError, exit 3)."""
    robot = load_robot("abb_irb4600")
    folder = tmp_path / "task"
    folder.mkdir()
    (folder / "BData.mod").write_text("MODULE BData\n  PERS tooldata tGun:=[TRUE,[[0,0,150],[1,0,0,0]],"
                                      "[2,[0,0,50],[1,0,0,0],0,0,0]];\nENDMODULE\n")
    (folder / "ZMain.mod").write_text(
        f"MODULE ZMain\n  CONST robtarget p10:={_robtarget(robot, [0, 10, 15, 0, 50, 0])};\n"
        f"  CONST robtarget p20:={_robtarget(robot, [20, 10, 15, 0, 50, 0])};\n"
        "  PROC main()\n    MoveJ p10,v1000,z10,tGun;\n    MoveJ p20,v1000,z10,tGun;\n  ENDPROC\nENDMODULE\n")
    model = calibrated_model(tmp_path, "abb_irb4600", "1000,-300,700", 240, 120, folds=0)
    out = tmp_path / "out"
    assert main(["compensate", str(folder), "--model", str(model), "-o", str(out), "--jobs", "1"]) in (0, 1)
    (entry,) = json.loads((out / "summary.json").read_text())["files"]
    assert entry["status"] in ("pass", "fail"), entry["message"]
    written = (out / "ZMain.mod").read_text()
    assert re.search(r"MoveJ p20,v1000\\T:=[0-9.]+,z10,tGun;", written), written
    assert "\\T" not in (folder / "BData.mod").read_text()
