"""Programs as controllers run them (issue 22): no false refusal, nothing rewritten that was not asked.

Each test is a minimal program of a shape seen in real controller programs:
what a controller loads and runs is read and written, what the tool cannot
know is listed, and configuration data keep every field the tool does not
own.
"""

import re

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.cli import main
from trajcomp.compensation.target_correction import CompensationResult
from trajcomp.formats.configuration import configuration_data, configuration_for, written_configuration
from trajcomp.errors import ReadError
from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk
from trajcomp.compensation.program_rewrite import compensate_program, convert_program
from trajcomp.compensation.posture import planned_joints
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import matrix_to_abc, matrix_to_quat

OFFSET = np.array([0.3, -0.2, 0.1])  # mm, the stand-in correction


def _stand_in(robot):
    """A ``correct`` that moves every target by `OFFSET` and solves the nominal IK next to the seed."""

    def correct(T, tools, seeds, names):
        command = T.copy()
        command[:, :3, 3] += OFFSET
        q = np.array([ik(robot.replace(T_flange_tool=tool), t[None], seed=s).q[0]
                      for t, tool, s in zip(command, tools, seeds)])
        n = len(T)
        return CompensationResult(command, q, np.tile([*OFFSET, 0, 0, 0], (n, 1)), np.zeros(n, bool), np.zeros(n))

    return correct


def _krl(tmp_path, points, body):
    """A KRL program (.src + .dat) of E6POS points ``{name: (x, y, z, a, b, c, s, t)}`` and motion lines."""
    dat = ["DEFDAT cell"] + [
        f"DECL E6POS {name}={{X {x:.3f},Y {y:.3f},Z {z:.3f},A {a:.4f},B {b:.4f},C {c:.4f},S {s},T {t}}}"
        for name, (x, y, z, a, b, c, s, t) in points.items()
    ] + ["ENDDAT"]
    (tmp_path / "cell.dat").write_text("\n".join(dat) + "\n")
    (tmp_path / "cell.src").write_text("\n".join(["DEF cell( )", *body, "END"]) + "\n")
    return tmp_path / "cell.src"


def _krl_point(robot, q, status=None, turn=None):
    T = fk(robot, np.radians(q)[None])[0]
    s, t = configuration_for(configuration_data("krl"), robot, np.radians(q)[None])[0]
    return (*T[:3, 3], *np.degrees(matrix_to_abc(T[:3, :3])), s if status is None else status,
            t if turn is None else turn)


# ------------------------------------------------------------------ configuration data


def test_kuka_status_bits_above_bit_2_and_turn_bits_above_a6_are_kept():
    robot = load_robot("kuka_kr6_r900")
    q = np.radians([[10.0, -80.0, 100.0, 20.0, 30.0, -40.0]])
    s, t = configuration_for(configuration_data("krl"), robot, q)[0]  # S 2, T 34: A2 and A6 negative
    assert (s, t) == (2, 34)
    # bit 4 of S: taught on an absolutely accurate robot; T bit 6: no axis of this arm
    assert written_configuration(configuration_data("krl"), robot, [(s | 16, t | 64)], q) == [(18, 98)]
    # A1 declared negative but at +10 deg: only T bit 0 follows the joints, the others stay
    assert written_configuration(configuration_data("krl"), robot, [(18, 98 | 1)], q) == [(18, 98)]
    # the branch changed (S bits 0-2 say wrist negative): bits 0-2 recomputed, bit 4 kept
    assert written_configuration(configuration_data("krl"), robot, [(16 | 4 | 2, 98)], q) == [(18, 98)]


def test_a_joint_on_a_code_boundary_keeps_its_declared_code():
    robot = load_robot("abb_irb4600")
    q = np.radians([[0.0, 10.0, 20.0, 0.0, 30.0, 0.0]])
    # RobotStudio writes a home pose's J4 = J6 = 0 as quadrant -1: the controller accepts it
    assert written_configuration(configuration_data("rapid"), robot, [(0, -1, -1, 0)], q) == [(0, -1, -1, 0)]
    q_nudged = q + np.radians([0, 0, 0, -0.2, 0, 0.3])
    assert written_configuration(configuration_data("rapid"), robot, [(0, 0, -1, 0)], q_nudged) == [(0, 0, -1, 0)]
    q_moved = q + np.radians([0, 0, 0, -2.0, 0, 0])  # beyond the tolerance: the quadrant follows the joint
    assert written_configuration(configuration_data("rapid"), robot, [(0, 0, 0, 0)], q_moved) == [(0, -1, 0, 0)]
    # FANUC J4 = 180.2 deg declared turn 0: -179.8 deg is inside turn 0, so the written turn must move
    fanuc = load_robot("fanuc_lrmate200id")
    q4 = np.radians([[0.0, 10.0, -20.0, 180.2, -30.0, 0.0]])
    (flags,) = configuration_for(configuration_data("fanuc_ls"), fanuc, q4)
    assert written_configuration(configuration_data("fanuc_ls"), fanuc, [(*flags[:3], 0, 0, 0)], q4) == [(*flags[:3], 0, 1, 0)]


def test_rapid_home_pose_written_on_a_quadrant_boundary_is_reachable(tmp_path):
    robot = load_robot("abb_irb4600")
    q = np.radians([0.0, 0.0, 0.0, 0.0, 30.0, 0.0])
    T = fk(robot, q[None])[0]
    quat = matrix_to_quat(T[:3, :3])
    text = (f"[[{T[0, 3]:.2f},{T[1, 3]:.2f},{T[2, 3]:.2f}],[{','.join(f'{v:.6f}' for v in quat)}],[0,-1,-1,0],"
            "[9E9,9E9,9E9,9E9,9E9,9E9]]")
    path = tmp_path / "home.mod"
    path.write_text(f"MODULE home\n  CONST robtarget pHome:={text};\n  PROC main()\n    MoveJ pHome,v100,fine,tool0;\n"
                    "  ENDPROC\nENDMODULE\n")
    program = formats.read(path)
    plan = planned_joints(program, robot)
    np.testing.assert_allclose(plan.q[0], q, atol=1e-4)
    edited, _ = compensate_program(program, _stand_in(robot), robot)
    assert edited.targets[0].config == (0, -1, -1, 0)


def test_kuka_status_and_turn_of_lin_targets_do_not_bind_and_stay_as_written(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    points = {"P1": _krl_point(robot, [0.0, -90.0, 90.0, 0.0, 45.0, 0.0]),
              "P2": _krl_point(robot, [5.0, -85.0, 95.0, 0.0, 40.0, 0.0], status=18, turn=63)}  # stale T
    program = formats.read(_krl(tmp_path, points, ["PTP P1", "LIN P2"]))
    edited, report = compensate_program(program, _stand_in(robot), robot)
    (tmp_path / "out").mkdir()
    formats.write(tmp_path / "out" / "cell.src", edited)
    written = (tmp_path / "out" / "cell.dat").read_text()
    assert re.search(r"DECL E6POS P2=\{.*,S 18,T 63\}", written)  # the controller ignores them on a LIN
    assert report.posture_source == ("config", "previous")
    np.testing.assert_allclose(report.q[1], np.radians([5.0, -85.0, 95.0, 0.0, 40.0, 0.0]), atol=0.01)
    assert not any("configuration data rewritten" in w for w in report.warnings)


# ------------------------------------------------------------------ same-language convert


def test_same_language_convert_keeps_every_line(tmp_path, capsys):
    text = ("MODULE weld\n  CONST robtarget p1:=[[900,0,900],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
            "  PROC main()\n    FOR i FROM 1 TO 3 DO\n      MoveL p1,v100,fine,tool0;\n      SetDO doWeld,1;\n"
            "      ArcLStart p1,v100,seam1,weld1,fine,tool0;\n    ENDFOR\n  ENDPROC\nENDMODULE\n")
    (tmp_path / "weld.mod").write_text(text)
    assert main(["convert", str(tmp_path / "weld.mod"), str(tmp_path / "copy.mod")]) == 0
    assert (tmp_path / "copy.mod").read_text() == text


def test_krl_generated_from_another_language_never_writes_the_tool_table(tmp_path):
    (tmp_path / "p.mod").write_text(
        "MODULE p\n  PERS tooldata tGun:=[TRUE,[[0,0,150],[1,0,0,0]],[1,[0,0,10],[1,0,0,0],0,0,0]];\n"
        "  CONST robtarget p1:=[[1135,0,1265],[0,0,1,0],[0,-1,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        "  PROC main()\n    MoveL p1,v100,fine,tGun;\n  ENDPROC\nENDMODULE\n")
    converted = convert_program(formats.read(tmp_path / "p.mod"), "krl", robot=load_robot("abb_irb4600"))
    formats.write(tmp_path / "p.src", converted)
    src = (tmp_path / "p.src").read_text()
    assert "TOOL_DATA" not in src and "BASE_DATA" not in src
    assert re.search(r"\$TOOL=\{X 0\.000000,Y 0\.000000,Z 150\.000000,A 0\.0+,B 0\.0+,C 0\.0+\}", src)


# ------------------------------------------------------------------ false refusals


def test_rapid_routine_parameters_of_any_routine_are_run_time_positions(tmp_path):
    path = tmp_path / "pick.mod"
    path.write_text(
        "MODULE pick\n  CONST robtarget pA:=[[600,100,500],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        "  PROC main()\n    PickAt pA;\n  ENDPROC\n  PROC PickAt(robtarget pPick)\n"
        "    MoveL Offs(pPick,0,0,100),v500,z10,tool0;\n    MoveL pPick,v100,fine,tool0;\n  ENDPROC\n"
        "  PROC Other()\n    MoveL pA,v100,fine,tool0;\n  ENDPROC\nENDMODULE\n")
    program = formats.read(path)
    assert [(m.line, m.reason) for m in program.runtime_motions()] == [
        (7, "position computed at run time: Offs(pPick,0,0,100)"), (8, "pPick: routine parameter, known at run time")]
    assert list(program.usage()) == [0]


def test_fanuc_register_speeds_untaught_points_and_scara_config(tmp_path):
    position = ("P[{n}]{{\n   GP1:\n\tUF : 0, UT : 1,\t\tCONFIG : '{config}',\n\tX =   400.000  mm,\tY = {y}  mm,"
                "\tZ =   500.000  mm,\n\tW =   180.000 deg,\tP =     0.000 deg,\tR =     0.000 deg\n}};\n")
    untaught = "P[3]{\n   GP1:\n\tUF : 0, UT : 1,\t\tCONFIG : 'N U T, 0, 0, 0',\n\tX = ********  mm\n};\n"
    mn = ["J P[1] 100% FINE", "L P[2] R[25:pos uw]mm/sec FINE", "L P[1] AR[1]mm/sec CNT100", "L P[3] 100mm/sec FINE"]
    body = "".join(position.format(n=n, y=f"{y:9.3f}", config="N U T, 0, 0, 0") for n, y in ((1, 0.0), (2, 100.0)))
    path = tmp_path / "REG.LS"
    path.write_text("/PROG  REG\n/ATTR\n/MN\n" + "".join(f"   {k + 1}:{line}    ;\n" for k, line in enumerate(mn))
                    + "/POS\n" + body + untaught + "/END\n")
    program = formats.read(path)
    assert [m.target for m in program.motions] == [0, 1, 0, None]
    assert program.not_compensated() == (
        (7, "4:L P[3] 100mm/sec FINE ;",
         "P[3] is not taught (its position is ********, line 21): the controller faults only if this line runs"),)
    path.write_text(path.read_text().replace("'N U T, 0, 0, 0'", "'L, 0, 0, 0'", 1))
    with pytest.raises(ReadError, match=r"CONFIG 'L, 0, 0, 0' is a 4-axis arm's .*4-axis arms are not supported"):
        formats.read(path)


def _script(tmp_path, lines):
    path = tmp_path / "s.script"
    path.write_text("def s():\n" + "".join(f"  {line}\n" for line in lines) + "end\n")
    return path


def test_urscript_polyscope_shapes_are_read(tmp_path):
    program = formats.read(_script(tmp_path, [
        "set_tcp(p[0.0,0.0,0.1,0.0,0.0,0.0])",
        "Kp = [1000, 1000, 500, 100, 100, 100]",  # gains: six numbers no joint can hold
        "pick_p = p[-0.5, -0.2, 0.3, 3.14, 0.0, 0.0]",
        "movej([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])",
        "set_tcp(p[0.0,0.0,0.1,0.0,0.0,0.0])",  # PolyScope sets it again at every Set node: the same tool
        "movel(pose_trans(pick_p, p[0,0,-0.1,0,0,0]), a=1.2, v=0.25)",  # the approach idiom
        "movel(pick_p, a=1.2, v=0.1)",
        "movel(pose_add(pick_p, p[0,0,0.1,0,0,0]), a=1.2, v=0.25)",
    ]))
    assert len(program.tools) == 1 and len({m.tool for m in program.motions}) == 1
    pick = program.motions[2].target
    assert [m.target for m in program.motions] == [0, None, pick, None]
    assert [m.refs for m in program.runtime_motions()] == [(pick,), (pick,)]
    assert program.frames == {}


def test_a_point_used_with_two_work_objects_is_written_as_a_corrected_copy_per_use(tmp_path):
    robot = load_robot("abb_irb4600")
    targets = []
    for k, q in enumerate(([0.0, 0.0, 0.0, 0.0, 30.0, 0.0], [10.0, 5.0, 5.0, 0.0, 30.0, 0.0])):
        T = fk(robot, np.radians(q)[None])[0]
        quat = matrix_to_quat(T[:3, :3])
        targets.append(f"  CONST robtarget p{k + 1}:=[[{T[0, 3]:.2f},{T[1, 3]:.2f},{T[2, 3] - 200:.2f}],"
                       f"[{','.join(f'{v:.6f}' for v in quat)}],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n")
    frames = "".join(f"  PERS wobjdata {name}:=[FALSE,TRUE,\"\",[[0,0,{z}],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];\n"
                     for name, z in (("wA", 200), ("wB", 201)))
    path = tmp_path / "two.mod"
    path.write_text("MODULE two\n" + frames + "".join(targets) + "  PROC main()\n"
                    "    MoveJ p1,v100,fine,tool0\\WObj:=wA;\n    MoveL p2,v100,fine,tool0\\WObj:=wA;\n"
                    "    MoveL p2,v100,fine,tool0\\WObj:=wB;\n  ENDPROC\nENDMODULE\n")
    program = formats.read(path)
    edited, report = compensate_program(program, _stand_in(robot), robot)
    # the use in wB goes to a copy declared after p2 (tests/programs/test_programs_tasks.py: the copies in detail)
    assert list(report.labels) == ["p1 (two.mod:4)", "p2 (two.mod:5)", "p2_2 (two.mod:6)"]
    assert report.motions_left == 0 and report.not_compensated == ()
    assert report.warnings[0] == ("point p2 is used with tool/frame ('tool0', 'wB') (line 10) besides its first use: "
                                  "written as a copy p2_2 after it (two.mod:6), corrected for that use")
    formats.write(tmp_path / "out.mod", edited)
    lines = (tmp_path / "out.mod").read_text().splitlines()
    assert lines[5].startswith("  CONST robtarget p2_2:=[[") and lines[9] == "    MoveL p2_2,v100,fine,tool0\\WObj:=wB;"


def test_motions_left_are_counted_once_and_offsets_of_a_corrected_point_move_with_it(tmp_path):
    robot = load_robot("abb_irb4600")
    T = fk(robot, np.radians([[0.0, 0.0, 0.0, 0.0, 30.0, 0.0]]))[0]
    quat = matrix_to_quat(T[:3, :3])
    point = f"[[{T[0, 3]:.2f},{T[1, 3]:.2f},{T[2, 3]:.2f}],[{','.join(f'{v:.6f}' for v in quat)}],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]"
    path = tmp_path / "offs.mod"
    path.write_text(f"MODULE offs\n  CONST robtarget p1:={point};\n  CONST robtarget p2:={point};\n  PROC main()\n"
                    "    MoveL Offs(p1,0,0,50),v100,z10,tool0;\n    MoveL p1,v100,fine,tool0;\n"
                    "    MoveL Offs(p2,0,0,50),v100,fine,tool0;\n    Weld p2;\n  ENDPROC\nENDMODULE\n")
    program = formats.read(path)
    _, report = compensate_program(program, _stand_in(robot), robot)
    assert report.motions_left == 2 <= len(program.motions) == 3
    (line5, _, moved), (line7, _, alone), (line8, _, passed) = report.not_compensated
    assert (line5, line7, line8) == (5, 7, 8)
    assert moved.endswith("built on p1, which is corrected: it moves with them (its offset itself is "
                          "not compensated)")
    assert "built on" not in alone and passed.startswith("point p2 is used here")


def test_fanuc_backup_shapes_a_controller_loads(tmp_path):
    """A track's E1 in mm beyond 3,600, a CDn termination, a position stated as RX..RR (seen in spot-welding backups)."""
    track = ("P[1]{\n   GP1:\n\tUF : 0, UT : 1,\t\tCONFIG : 'N U T, 0, 0, 0',\n\tX =   400.000  mm,\tY =     0.000  mm,"
             "\tZ =   500.000  mm,\n\tW =   180.000 deg,\tP =     0.000 deg,\tR =     0.000 deg,\n\tE1=  3827.669  mm\n};\n")
    rail = ("P[2]{\n   GP1:\n\tUF : 1, UT : 2,\t\tCONFIG : 'N U T, 0, 0, 0',\n\tRX =   341.681  mm,\tRY =  -170.477  mm,"
            "\tRZ =  -671.251  mm,\n\tRW =    29.745 deg,\tRP =   -14.702 deg,\tRR =    72.713 deg,\n\tE1=  2500.000  mm\n};\n")
    path = tmp_path / "TRACK.LS"
    path.write_text("/PROG  TRACK\n/ATTR\n/MN\n   1:J P[1] 100% FINE    ;\n"
                    "   2:L P[2] 2000mm/sec CD100 ACC100    ;\n/POS\n" + track + rail + "/END\n")
    program = formats.read(path)
    assert program.targets[0].external.tolist() == [3827.669]
    assert [m.target for m in program.motions] == [0, None] and program.motions[1].zone == 100.0
    assert program.not_compensated()[0][2] == ("P[2] is stated as RX, RY, RZ, RW, RP, RR (line 14), a representation "
                                               "trajcomp does not read: left as written")


def test_krl_points_of_config_dat_or_another_data_list_are_read_not_refused(tmp_path):
    program_folder, system = tmp_path / "KRC" / "R1" / "Program", tmp_path / "KRC" / "R1" / "System"
    program_folder.mkdir(parents=True)
    system.mkdir()
    (program_folder / "weld.src").write_text("DEF weld( )\nPTP XP1\nLIN XSHARED\nLIN XTABLE\nLIN XNOWHERE\nEND\n")
    (program_folder / "weld.dat").write_text("DEFDAT weld\nDECL E6POS XP1={X 445,Y 0,Z 790,A 0,B 90,C 0,S 2,T 2}\n"
                                             "ENDDAT\n")
    (program_folder / "table.dat").write_text("DEFDAT table PUBLIC\nDECL GLOBAL E6POS XTABLE={X 1,Y 0,Z 7,A 0,B 90,"
                                              "C 0,S 2,T 2}\nENDDAT\n")
    (system / "$config.dat").write_text("DEFDAT $CONFIG\nDECL GLOBAL E6POS XSHARED={X 445,Y 0,Z 700,A 0,B 90,C 0,"
                                        "S 2,T 2}\nENDDAT\n")
    with pytest.raises(ReadError, match=r"XNOWHERE \(line 5\); are they declared in weld\.dat\?"):
        formats.read(program_folder / "weld.src")
    (program_folder / "weld.src").write_text("DEF weld( )\nPTP XP1\nLIN XSHARED\nLIN XTABLE\nEND\n")
    program = formats.read(program_folder / "weld.src")  # read where declared (tests/programs/test_programs_tasks.py)
    assert program.not_compensated() == ()
    assert [program.where(m.target) for m in program.motions[1:]] == ["XSHARED ($config.dat:2)", "XTABLE (table.dat:2)"]
