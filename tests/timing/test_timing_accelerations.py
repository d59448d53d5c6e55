"""The programmed acceleration bounds the timing as the controller's ramps do: never faster than they allow.

Each language's acceleration form (KRL ``BAS(#ACC_PTP)`` / ``$ACC_AXIS[n]``
and ``$ACC.CP``, RAPID ``AccSet``, FANUC ``ACC``, UR movel ``a=``) is set
before a short motion from rest to rest, where the ramps decide its time.
The reference is independent of the timing: from rest to rest, a joint
that may accelerate at most at a moves its |dq| in no less than
2 sqrt(|dq| / a) (accelerating half way, braking the other half), and a
TCP line of L mm at most a mm/s^2 takes 2 sqrt(L / a). The time re-timing
gives the motion (its report's time stamps) and the time it writes (RAPID
``\\T``, FANUC ``msec``) are no shorter.
"""

import json
import re

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot
from trajcomp.cli import main
from trajcomp.compensation.pipeline import planned
from trajcomp.compensation.posture import planned_joints


def retimed(tmp_path, name, text, robot_name, extra=None, model=None, codes=(0,)):
    """``name`` holding ``text`` (and ``extra`` files) re-timed (``retime``, or with a ``model`` ``compensate
    --retime auto``): (the written motions' joints (M, 6) rad, the report's time stamps (M,) s, the written text)."""
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / name).write_text(text)
    for other, content in (extra or {}).items():
        (folder / other).write_text(content)
    out, report = tmp_path / "out" / name, tmp_path / "report.json"
    out.parent.mkdir()
    run = ["retime", "--robot", robot_name] if model is None else ["compensate", "--model", str(model), "--retime",
                                                                   "auto"]
    assert main([*run, str(folder / name), "-o", str(out), "--report", str(report)]) in (codes if model is None
                                                                                         else (0, 1))
    program, robot = formats.read(out), load_robot(robot_name)
    plan = planned_joints(program, robot)
    q = planned(program, plan.index, plan.q)
    joints = q[program.motion_table().target]
    return joints, np.array(json.loads(report.read_text())["timing"]["t_s"]), out.read_text()


STAMP = 1e-4  # s: the report's time stamps are rounded to 4 decimals


def least_joint_time(robot, q_a, q_b, share):
    """The least time (s) of a joint motion from rest to rest with every joint at ``share`` of its acceleration
    limit."""
    return float(np.max(2.0 * np.sqrt(np.abs(q_b - q_a) / (share * robot.a_max))))


ACC_MODULE = ("MODULE Acc\n"
              "  CONST robtarget P1:=[[1135,0,1415],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
              "  CONST robtarget P2:=[[1141,4,1411],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
              "  PROC main()\n    MoveJ P1, v1000, fine, tool0;\n    AccSet 20, 100;\n"
              "    MoveJ P2, v1000, fine, tool0;\n    MoveJ P1, v1000, fine, tool0;\n  ENDPROC\nENDMODULE\n")


def test_rapid_accset_bounds_the_time_written(tmp_path):
    module = ("MODULE Acc\n"
              "  CONST robtarget P1:=[[1135,0,1415],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
              "  CONST robtarget P2:=[[1141,4,1411],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
              "  PROC main()\n    MoveJ P1, v1000, fine, tool0;\n    AccSet 20, 100;\n"
              "    MoveJ P2, v1000, fine, tool0;\n    MoveJ P1, v1000, fine, tool0;\n  ENDPROC\nENDMODULE\n")
    q, t, text = retimed(tmp_path, "Acc.mod", module, "abb_irb4600")
    robot = load_robot("abb_irb4600")
    written = [float(v) for v in re.findall(r"\\T:=([\d.]+)", text)]
    assert len(written) == 2
    for k, time in zip((1, 2), written):
        least = least_joint_time(robot, q[k - 1], q[k], 0.2)
        assert t[k] - t[k - 1] >= least - STAMP and time >= least * (1 - 1e-6), (k, time, least)


ACC_LS = ("/PROG  ACC\n/ATTR\nOWNER\t\t= MNEDITOR;\nDEFAULT_GROUP\t= 1,*,*,*,*;\n/MN\n"
          "   1:J P[1] 100% FINE    ;\n   2:J P[2] 100% FINE ACC20    ;\n   3:J P[1] 100% FINE ACC150    ;\n"
          "/POS\n" + "".join(f"P[{n}]{{\n   GP1:\n\tUF : 0, UT : 0,\t\tCONFIG : 'N U T, 0, 0, 0',\n"
                             f"\tX = {x:.6f}  mm,\tY = {y:.6f}  mm,\tZ = {z:.6f}  mm,\n"
                             "\tW = 180.000000000 deg,\tP = 0.000000000 deg,\tR = 0.000000000 deg\n};\n"
                             for n, (x, y, z) in {1: (385, 0, 595), 2: (390, 4, 591)}.items()) + "/END\n")


def test_fanuc_acc_bounds_the_time_written_and_above_100_is_read_as_100(tmp_path):
    q, t, text = retimed(tmp_path, "ACC.LS", ACC_LS, "fanuc_lrmate200id")
    robot = load_robot("fanuc_lrmate200id")
    written = [float(v) / 1000.0 for v in re.findall(r"(\d+)msec", text)]
    assert len(written) == 2 and "ACC20" in text and "ACC150" in text  # the options kept
    assert written[0] >= least_joint_time(robot, q[0], q[1], 0.2) * (1 - 1e-6)
    assert t[1] - t[0] >= least_joint_time(robot, q[0], q[1], 0.2) - STAMP
    # ACC150: the timing keeps the arm's limits; its time is no shorter than at them (the controller's own ramps,
    # steeper, then need no more than it)
    assert written[1] >= least_joint_time(robot, q[1], q[2], 1.0) * (1 - 1e-6)


@pytest.mark.parametrize("compensated", [False, True])
def test_krl_acc_ptp_and_acc_cp_bound_the_timing(tmp_path, kuka_model, compensated):
    src = ("DEF acc( )\n  BAS(#VEL_PTP,100)\n  $VEL.CP=2.0\n  PTP HOME\n  PTP P1\n  BAS(#ACC_PTP,20)\n  PTP P2\n"
           "  $ACC={CP 0.1,ORI1 100,ORI2 100}\n  LIN P1\nEND\n")
    dat = ("DEFDAT acc\n  DECL E6AXIS HOME={A1 0,A2 -90,A3 90,A4 0,A5 45,A6 0}\n"
           "  DECL E6POS P1={X 400,Y -100,Z 700,A 0,B 90,C 0}\n  DECL E6POS P2={X 404,Y -96,Z 703,A 0,B 90,C 0}\n"
           "ENDDAT\n")
    q, t, _ = retimed(tmp_path, "acc.src", src, "kuka_kr6_r900", {"acc.dat": dat}, kuka_model if compensated else None,
                      codes=(1,))
    # ORI1 and ORI2, orientation accelerations the timing does not model: the LIN left as written, listed
    assert "$ACC.ORI1 100 deg/s^2" in (tmp_path / "report.json").read_text()
    robot = load_robot("kuka_kr6_r900")
    assert t[2] - t[1] >= least_joint_time(robot, q[1], q[2], 0.2) - STAMP  # the PTP at 20 % of the ramps
    length = np.linalg.norm(fk(robot, q[3])[:3, 3] - fk(robot, q[2])[:3, 3])
    assert t[3] - t[2] >= 2.0 * np.sqrt(length / 100.0) - STAMP  # the LIN at 0.1 m/s^2


def test_urscript_movel_a_bounds_the_timing(tmp_path):
    script = ("def acc():\n  movej([0.0, -1.57, 1.57, -1.57, -1.57, 0.0], a=1.4, v=1.05)\n"
              "  movel([0.05, -1.55, 1.55, -1.57, -1.57, 0.0], a=0.1, v=0.25)\nend\n")
    _, t, text = retimed(tmp_path, "acc.script", script, "ur10")
    robot = load_robot("ur10")
    q = np.array([[0.0, -1.57, 1.57, -1.57, -1.57, 0.0], [0.05, -1.55, 1.55, -1.57, -1.57, 0.0]])  # as written
    length = np.linalg.norm(fk(robot, q[1])[:3, 3] - fk(robot, q[0])[:3, 3])
    assert "a=0.1" in text and length > 10.0
    assert t[1] - t[0] >= 2.0 * np.sqrt(length / 100.0) - STAMP  # 0.1 m/s^2, from rest to rest


@pytest.mark.parametrize("setting", ["$ACC.ORI2=20", "$ACC={CP 2.0,ORI1 30,ORI2 200}"])
def test_krl_orientation_acceleration_leaves_a_line_as_written(tmp_path, setting):
    """``$ACC.ORI1`` / ``ORI2`` bound how fast a LIN may turn the tool, which the timing does not model: a LIN
    after one keeps its speed as written (here a 3 m/s the arm cannot keep would be lowered), listed; a PTP is not
    concerned."""
    src = (f"DEF acc( )\n  BAS(#VEL_PTP,100)\n  $VEL.CP=3.0\n  PTP HOME\n  PTP P1\n  {setting}\n  LIN P2\n"
           "  PTP P1\nEND\n")
    dat = ("DEFDAT acc\n  DECL E6AXIS HOME={A1 0,A2 -90,A3 90,A4 0,A5 45,A6 0}\n"
           "  DECL E6POS P1={X 400,Y -100,Z 700,A 0,B 90,C 0}\n  DECL E6POS P2={X 500,Y 100,Z 600,A 90,B 60,C 0}\n"
           "ENDDAT\n")
    _, _, text = retimed(tmp_path, "acc.src", src, "kuka_kr6_r900", {"acc.dat": dat}, codes=(1,))
    assert text.count("$VEL.CP") == 1 and "$VEL.CP=3.0" in text  # nothing lowered or inserted for the LIN
    listed = json.loads((tmp_path / "report.json").read_text())["timing"]["not_retimed"]
    assert listed["count"] == 1 and "an orientation acceleration" in json.dumps(listed)


def test_rapid_accset_carried_into_a_conversion(tmp_path, makerless):
    """Converted to FANUC, whose J motion states a percentage its controller runs at its full ramps: the motions
    after AccSet 20 take no less time than their 20 % ramps need (the percentage lowered to make up for them)."""
    source = tmp_path / "Acc.mod"
    source.write_text(ACC_MODULE)
    out = tmp_path / "ACC.LS"
    assert main(["convert", str(source), str(out), "--robot", makerless("abb_irb4600")]) in (0, 1)
    program, robot = formats.read(source), load_robot("abb_irb4600")
    plan = planned_joints(program, robot)
    q = planned(program, plan.index, plan.q)[program.motion_table().target]
    fields = re.findall(r"J P\[\d+\] (\d+)(%|msec)", out.read_text())
    assert len(fields) == 3
    for k in (1, 2):
        value, unit = float(fields[k][0]), fields[k][1]
        change = np.abs(q[k] - q[k - 1])
        if unit == "msec":
            taken = value / 1000.0
        else:  # synchronized: the path parameter cruises at the slowest joint's p % and ramps at its limit
            cruise, ramps = np.min(value / 100.0 * robot.v_max / change), np.min(robot.a_max / change)
            taken = 1.0 / cruise + cruise / ramps if cruise < np.sqrt(ramps) else 2.0 / np.sqrt(ramps)
        assert taken >= least_joint_time(robot, q[k - 1], q[k], 0.2) * (1 - 1e-6), (k, fields[k])


def test_fanuc_acc_carried_into_a_conversion(tmp_path, makerless):
    """Converted to RAPID: the motion under ACC20 gets a \\T no shorter than its 20 % ramps need."""
    source = tmp_path / "ACC.LS"
    source.write_text(ACC_LS)
    out = tmp_path / "Acc.mod"
    assert main(["convert", str(source), str(out), "--robot", makerless("fanuc_lrmate200id")]) in (0, 1)
    program, robot = formats.read(source), load_robot("fanuc_lrmate200id")
    plan = planned_joints(program, robot)
    q = planned(program, plan.index, plan.q)[program.motion_table().target]
    times = [float(v) for v in re.findall(r"MoveJ \w+, \w+\\T:=([\d.]+)", out.read_text())]
    assert len(times) == 2 and times[0] >= least_joint_time(robot, q[0], q[1], 0.2) * (1 - 1e-6)


@pytest.mark.parametrize("accset", ["AccSet 50, 30;", "AccSet 50, 100\\FinePointRamp:=30;"])
def test_rapid_softer_ramps_time_a_speed_and_leave_a_time_as_written(tmp_path, accset):
    """A ramp below 100 % (or \\FinePointRamp, for a motion to a fine point) only softens how fast the
    accelerations build up: a line's speed data cruises behind it no faster, so it is timed under AccSet's 50 %
    (its report time no shorter than joints at 50 % of their limits from rest to rest allow); a MoveJ, whose written
    field would be a time the controller keeps by cruising faster behind softer ramps, keeps its field as
    written, listed."""
    module = ACC_MODULE.replace("AccSet 20, 100;", accset).replace(
        "MoveJ P1, v1000, fine, tool0;\n  ENDPROC", "MoveL P1, v1000, fine, tool0;\n  ENDPROC")
    q, t, text = retimed(tmp_path, "Acc.mod", module, "abb_irb4600", codes=(1,))  # a motion left as written
    assert "MoveJ P2, v1000, fine, tool0;" in text  # left as written
    assert "MoveL P1, v1000, fine, tool0;" in text  # a speed the arm keeps: kept
    report = json.loads((tmp_path / "report.json").read_text())["timing"]
    assert "AccSet ramp 30 %" in json.dumps(report)
    # each joint from rest to rest at most at 50 % of its limit, whatever its path
    assert t[2] - t[1] >= least_joint_time(load_robot("abb_irb4600"), q[1], q[2], 0.5) - STAMP
