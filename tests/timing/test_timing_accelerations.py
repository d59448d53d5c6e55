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
from trajcomp.jobs.retime import planned
from trajcomp.compensation.posture import planned_joints
from tests.conftest import calibrated_model
from tests.timing.test_control_flow import ur_least_time


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
    return motion_joints(program, robot), np.array(json.loads(report.read_text())["timing"]["t_s"]), out.read_text()


def motion_joints(program, robot):
    """Joints (M, 6) rad of a program's M motions' targets: a joint target's own, a pose's in its posture."""
    plan, table = planned_joints(program, robot), program.target_table()
    q = planned(program, plan.index, plan.q)
    q[table.is_joint] = table.joints[table.is_joint]
    return q[program.motion_table().target]


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


KRL_ACC_SRC = "DEF acc( )\n  BAS(#VEL_PTP,100)\n  PTP HOME\n  PTP P1\n  BAS(#ACC_PTP,20)\n  PTP P2\n  PTP P1\nEND\n"
KRL_ACC_DAT = ("DEFDAT acc\n  DECL E6AXIS HOME={A1 0,A2 -90,A3 90,A4 0,A5 45,A6 0}\n"
               "  DECL E6POS P1={X 400,Y -100,Z 700,A 0,B 90,C 0}\n  DECL E6POS P2={X 404,Y -96,Z 703,A 0,B 90,C 0}\n"
               "ENDDAT\n")
UR_ACC = ("def acc():\n  movej([3.1, -1.57, 1.57, -1.57, -1.57, 0.0], a=1.4, v=1.05)\n"
          "  movej([3.15, -1.55, 1.55, -1.57, -1.57, 0.0], a=0.3, v=1.05)\n"
          "  movej([3.1, -1.57, 1.57, -1.57, -1.57, 0.0], a=1.4, v=1.05)\nend\n")
UR_DEFAULT_A = 1.4  # rad/s^2: a movej's acceleration where it states none (URScript manual)
# language: (file, text, other files, robot, model cube (corner, side, step), {motion: (form, value)}): each joint
# motion's programmed acceleration, a share of every joint's limit or the leading axis's (UR movej a=, rad/s^2)
ACC_SOURCES = {
    "krl": ("acc.src", KRL_ACC_SRC, {"acc.dat": KRL_ACC_DAT}, "kuka_kr6_r900", None,
            {2: ("share", 0.2), 3: ("share", 0.2)}),
    "rapid": ("Acc.mod", ACC_MODULE, {}, "abb_irb4600", ("1050,-100,1300", 200, 50),
              {1: ("share", 0.2), 2: ("share", 0.2)}),
    "fanuc": ("ACC.LS", ACC_LS, {}, "fanuc_lrmate200id", None, {1: ("share", 0.2)}),
    "urscript": ("acc.script", UR_ACC, {}, "ur10", ("600,50,550", 200, 50), {1: ("leading", 0.3)}),
}


def least_programmed_time(robot, form, q_a, q_b):
    """The least time (s) from rest to rest the programmed acceleration ``form`` allows: every joint at most its
    share of its limit, or the leading axis at most a (rad/s^2)."""
    kind, value = form
    if kind == "share":
        return least_joint_time(robot, q_a, q_b, value)
    return 2.0 * np.sqrt(np.max(np.abs(q_b - q_a)) / value)


def controller_time(motion, q_a, q_b, robot):
    """The least time (s) the controller takes for a written joint motion from rest to rest, from its field alone
    (`trajcomp.formats.read`): a time; a percentage (KRL PTP, FANUC J): the path parameter cruising at the slowest
    joint's p % of its limit, ramping at the acceleration the motion states (``acceleration_share``) or the arm's;
    a UR movej: the leading axis at its v and a (1.4 rad/s^2 unless stated). None for a TCP speed (RAPID MoveJ
    speed data, CSV), which this does not run."""
    change = np.abs(q_b - q_a)
    if motion.speed_unit == "s":
        return motion.speed
    if motion.speed_unit == "%":
        moving = change > 1e-12
        share = motion.acceleration_share or 1.0
        cruise = np.min(motion.speed / 100.0 * robot.v_max[moving] / change[moving])
        ramps = np.min(share * robot.a_max[moving] / change[moving])
        return 1.0 / cruise + cruise / ramps if cruise < np.sqrt(ramps) else 2.0 / np.sqrt(ramps)
    if motion.speed_unit == "rad/s":
        return ur_least_time(np.max(change), motion.acceleration or UR_DEFAULT_A, motion.speed)
    return None


def source_folder(tmp_path, language):
    name, text, extra, robot, _, _ = ACC_SOURCES[language]
    folder = tmp_path / "source"
    folder.mkdir()
    for file, content in {name: text, **extra}.items():
        (folder / file).write_text(content)
    return folder / name


@pytest.fixture(scope="module")
def acc_models(tmp_path_factory, request):
    """``model(language)``: a compensation model of the language's arm around its acceleration program."""
    made = {}

    def model(language):
        _, _, _, robot, cube, _ = ACC_SOURCES[language]
        if cube is None:
            return request.getfixturevalue({"kuka_kr6_r900": "kuka_model", "fanuc_lrmate200id": "fanuc_model"}[robot])
        if language not in made:
            made[language] = calibrated_model(tmp_path_factory.mktemp(language), robot, *cube)
        return made[language]

    return model


@pytest.mark.parametrize("language", sorted(ACC_SOURCES))
def test_programmed_accelerations_bound_a_compensated_program(tmp_path, language, acc_models):
    """``compensate --retime auto``: each motion under its programmed acceleration takes, in the report and in
    its written field, no less time than that acceleration allows between its compensated joints."""
    name, text, extra, robot_name, _, forms = ACC_SOURCES[language]
    q, t, _ = retimed(tmp_path, name, text, robot_name, extra, acc_models(language))
    robot = load_robot(robot_name)
    written = formats.read(tmp_path / "out" / name).motions
    checked = 0
    for k, form in forms.items():
        least = least_programmed_time(robot, form, q[k - 1], q[k])
        assert t[k] - t[k - 1] >= least - STAMP, (k, t[k] - t[k - 1], least)
        taken = controller_time(written[k], q[k - 1], q[k], robot)
        if taken is not None:
            assert taken >= least * (1 - 1e-6), (k, written[k].text, taken, least)
            checked += 1
    assert checked or language == "rapid"  # a RAPID MoveJ's speed data kept: a TCP speed, not run here


@pytest.mark.parametrize("source, target", [(s, t) for s in sorted(ACC_SOURCES) for t in sorted(ACC_SOURCES)
                                            if s != t])
def test_programmed_accelerations_carried_into_every_conversion(tmp_path, makerless, source, target):
    """Converted into each other language, whose field states a time, a percentage run at the arm's ramps, or a UR
    speed at its default a: each motion under its programmed acceleration takes no less time than that
    acceleration allows (the field lowered to make up for it). CSV states no motion time (the rows are timed by
    ``retime``)."""
    name, text, extra, robot_name, _, forms = ACC_SOURCES[source]
    path = source_folder(tmp_path, source)
    out = tmp_path / ("out" + {"krl": ".src", "rapid": ".mod", "fanuc": ".ls", "urscript": ".script"}[target])
    assert main(["convert", str(path), str(out), "--robot", makerless(robot_name)]) in (0, 1)
    q = motion_joints(formats.read(path), robot := load_robot(robot_name))
    converted = formats.read(out).motions
    assert len(converted) == len(q)
    checked = 0
    for k, form in forms.items():
        taken = controller_time(converted[k], q[k - 1], q[k], robot)
        least = least_programmed_time(robot, form, q[k - 1], q[k])
        if taken is not None:
            assert taken >= least * (1 - 1e-6), (k, converted[k].text, taken, least)
            checked += 1
    assert checked


TCP_SOURCES = {  # language: (file, text, other files, robot, the line's index, its TCP acceleration mm/s^2)
    "krl": ("acc.src", KRL_ACC_SRC.replace("  BAS(#ACC_PTP,20)\n  PTP P2", "  $VEL.CP=2.0\n  $ACC.CP=0.1\n  LIN P2"),
            {"acc.dat": KRL_ACC_DAT.replace("Y -96,Z 703", "Y -56,Z 703")}, "kuka_kr6_r900", 2, 100.0),
    "urscript": ("acc.script", UR_ACC.replace("movej([3.15, -1.55, 1.55, -1.57, -1.57, 0.0], a=0.3, v=1.05)",
                                              "movel([3.15, -1.55, 1.55, -1.57, -1.57, 0.0], a=0.1, v=0.25)"),
                 {}, "ur10", 1, 100.0),
}


@pytest.mark.parametrize("source, target", [(s, t) for s in sorted(TCP_SOURCES) for t in sorted(ACC_SOURCES)
                                            if s != t])
def test_a_tcp_acceleration_carried_into_every_conversion(tmp_path, makerless, source, target):
    """A line under a programmed TCP acceleration a (KRL ``$ACC.CP``, UR movel ``a=``) converted into each other
    language takes no less than 2 sqrt(L / a) from rest to rest: a written time no shorter; a written TCP speed v,
    which no controller exceeds, with L / v no shorter within 0.5 % (the target controller's own ramps add the
    rest)."""
    name, text, extra, robot_name, k, a = TCP_SOURCES[source]
    folder = tmp_path / "source"
    folder.mkdir()
    for file, content in {name: text, **extra}.items():
        (folder / file).write_text(content)
    out = tmp_path / ("out" + {"krl": ".src", "rapid": ".mod", "fanuc": ".ls", "urscript": ".script"}[target])
    assert main(["convert", str(folder / name), str(out), "--robot", makerless(robot_name)]) in (0, 1)
    robot = load_robot(robot_name)
    q = motion_joints(formats.read(folder / name), robot)
    length = np.linalg.norm(fk(robot, q[k])[:3, 3] - fk(robot, q[k - 1])[:3, 3])
    least = 2.0 * np.sqrt(length / a)
    motion = formats.read(out).motions[k]
    assert motion.speed_unit in ("s", "mm/s"), motion.text
    taken = motion.speed if motion.speed_unit == "s" else length / motion.speed
    assert taken >= least * (1 - 5e-3), (motion.text, taken, least)


@pytest.mark.parametrize("language", sorted(TCP_SOURCES))
def test_a_tcp_acceleration_bounds_a_compensated_line(tmp_path, language, acc_models):
    """``compensate --retime auto``: the line under its TCP acceleration a takes, in the report, no less than
    2 sqrt(L / a) over its compensated length L; its written field (a TCP speed) no faster than programmed."""
    name, text, extra, robot_name, k, a = TCP_SOURCES[language]
    q, t, _ = retimed(tmp_path, name, text, robot_name, extra, acc_models(language))
    robot = load_robot(robot_name)
    length = np.linalg.norm(fk(robot, q[k])[:3, 3] - fk(robot, q[k - 1])[:3, 3])
    assert t[k] - t[k - 1] >= 2.0 * np.sqrt(length / a) - STAMP
    source, written = formats.read(tmp_path / "in" / name).motions[k], formats.read(tmp_path / "out" / name).motions[k]
    assert written.speed_unit == source.speed_unit == "mm/s" and written.speed <= source.speed

