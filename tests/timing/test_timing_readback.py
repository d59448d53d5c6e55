"""The written speed fields, read back as each controller reads them, never run faster than programmed.

The example weld with its lines asked for 3 m/s, more than the arms can
cruise at on those lines, is re-timed in each robot language; the written
program is read again (`trajcomp.formats.read`: the field each motion's
controller runs) and every timed motion is run the controller's way,
independently of the timing:

- a cruise speed (KRL ``$VEL.CP``, RAPID ``\\V``, UR ``v=``, FANUC
  ``mm/sec``) on a line: the TCP cruises at it along the straight line,
  every 1 ms solved by IK and differentiated: no faster than the
  programmed 3 m/s, joint velocity and acceleration within the limits;
- a time (RAPID ``\\T``, UR ``t=``, FANUC ``msec``) or a KRL PTP
  percentage on a joint motion: the joints move synchronously on their
  line, the path accelerating at the first joint's acceleration limit and
  cruising so that the motion takes that time (KRL: cruising at the
  percentage of the leading axis's velocity limit), sampled every 1 ms:
  joint velocity within the limits and the programmed joint speed (KRL,
  FANUC percentage; UR's default 1.05 rad/s), the TCP speed within RAPID's
  v1000.
"""

import shutil
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk, jacobian
from trajcomp.arm.robot import load_robot
from trajcomp.cli import main
from trajcomp.jobs.retime import planned
from trajcomp.compensation.posture import planned_joints
from trajcomp.programs.items import JOINT, LINEAR
from trajcomp.timing import moves_from_program

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "programs"
FAST = 3000.0  # mm/s asked of the lines
PROGRAMS = {  # language: file, robot, the lines' speed made 3 m/s, the joint motions' programmed speed
    "krl": ("kuka/weld.src", "kuka_kr6_r900", ("$VEL.CP=0.020000", "$VEL.CP=3.000000"), {"%": 50.0}),
    "rapid": ("abb/Weld.mod", "abb_irb4600", ("v20,", "v3000,"), {"mm/s": 1000.0}),
    "fanuc_ls": ("fanuc/WELD.LS", "fanuc_lrmate200id", ("20mm/sec", "3000mm/sec"), {"%": 50.0}),
    "urscript": ("ur/weld.script", "ur10", ("v=0.020000", "v=3.000000"), {"rad/s": 1.05}),
}
RATE = 1000.0  # Hz
SLACK = 1.0005  # 1.000 to three digits


def written(tmp_path, language):
    """The fast weld re-timed through the CLI: (program read back from the output, robot, joint speed asked)."""
    source, robot_name, (old, new), joint_speed = PROGRAMS[language]
    folder = tmp_path / "in"
    shutil.copytree((EXAMPLES / source).parent, folder)
    path = folder / Path(source).name
    assert path.read_text().count(old) >= 1
    path.write_text(path.read_text().replace(old, new))
    output = tmp_path / "out" / path.name
    output.parent.mkdir()
    assert main(["retime", str(path), "-o", str(output), "--robot", robot_name]) == 0
    return formats.read(output), load_robot(robot_name), joint_speed


def line_demand(robot, start, end, speed):
    """Joint velocity and acceleration (each (n, 6)) of the TCP cruising at ``speed`` (mm/s) on the line from
    pose ``start`` to ``end`` (4, 4), one orientation: IK every 1 ms, central differences."""
    step = speed / RATE
    count = int(np.ceil(np.linalg.norm(end[:3, 3] - start[:3, 3]) / step)) + 1
    poses = np.repeat(start[None], count, axis=0)
    poses[:, :3, 3] = start[:3, 3] + np.linspace(0.0, 1.0, count)[:, None] * (end[:3, 3] - start[:3, 3])
    solved = ik(robot, poses, seed=ik(robot, poses[:1]).q[0])
    assert solved.success.all()
    dt = np.linalg.norm(end[:3, 3] - start[:3, 3]) / (count - 1) / speed
    return np.gradient(solved.q, dt, axis=0), (solved.q[2:] - 2.0 * solved.q[1:-1] + solved.q[:-2]) / dt**2


def outside_zones(moves, tool, k):
    """The poses (4, 4) where linear motion k leaves the blend at its start and enters the one at its end:
    a corner passed without stopping is blended over min(zone, half of each neighbouring motion's TCP chord),
    and the controller plans a blend's accelerations itself (only the line is run at the cruise speed)."""
    ends = fk(tool, moves.q[max(k - 2, 0) : k + 2])
    i = k - max(k - 2, 0)  # ends[i - 1], ends[i]: motion k's start and end
    chords = np.linalg.norm(np.diff(ends[:, :3, 3], axis=0), axis=1)
    cut = []
    for corner, neighbour in ((k - 1, i - 2), (k, i)):
        blended = 0 < corner < len(moves.q) - 1 and not moves.stop[corner] and moves.zone[corner] > 0
        cut.append(min(moves.zone[corner], 0.5 * chords[i - 1], 0.5 * chords[neighbour]) if blended else 0.0)
    start, end = ends[i - 1].copy(), ends[i].copy()
    direction = (end[:3, 3] - start[:3, 3]) / chords[i - 1]
    start[:3, 3] += cut[0] * direction
    end[:3, 3] -= cut[1] * direction
    return start, end


def joint_line(robot, q_a, q_b, duration=None, percent=100.0):
    """A synchronized joint motion from q_a to q_b (6,) the controller's way: path s in [0, 1] accelerating at
    the first joint's acceleration limit, cruising at the speed that takes ``duration`` s (or, None, at
    ``percent`` of the leading axis's velocity limit), sampled every 1 ms: (q, qd, qdd) (n, 6) each."""
    change = q_b - q_a
    moving = np.abs(change) > 1e-12
    accel = np.min(robot.a_max[moving] / np.abs(change[moving]))
    if duration is None:
        cruise = min(np.min(percent / 100.0 * robot.v_max[moving] / np.abs(change[moving])), np.sqrt(accel))
        duration = 1.0 / cruise + cruise / accel
    assert accel * duration**2 >= 4.0 - 1e-9  # reachable in that time at that acceleration
    cruise = 0.5 * (accel * duration - np.sqrt(max(accel**2 * duration**2 - 4.0 * accel, 0.0)))
    ramp = cruise / accel
    t = np.r_[np.arange(0.0, duration, 1.0 / RATE), duration]
    s_dot = np.minimum(np.minimum(accel * t, cruise), accel * (duration - t))
    s_ddot = np.where(t < ramp, accel, np.where(t > duration - ramp, -accel, 0.0))
    cruising = 0.5 * cruise * ramp + cruise * (t - ramp)
    s = np.where(t < ramp, 0.5 * accel * t**2, np.where(t > duration - ramp, 1.0 - 0.5 * accel * (duration - t) ** 2,
                                                         cruising))
    return q_a + s[:, None] * change, s_dot[:, None] * change, s_ddot[:, None] * change


@pytest.mark.parametrize("language", sorted(PROGRAMS))
def test_the_written_fields_run_the_controllers_way_never_faster_than_programmed(tmp_path, language):
    program, robot, joint_speed = written(tmp_path, language)
    plan = planned_joints(program, robot)
    moves = moves_from_program(program, robot, planned(program, plan.index, plan.q))
    checked = set()
    for k in range(1, len(moves.q)):
        if moves.start[k]:  # from an unknown position: not timed, left as written
            continue
        motion = program.motions[moves.motion[k]]
        tool = robot.replace(T_flange_tool=moves.tools[moves.tool[k]])
        if moves.kind[k] == LINEAR:
            assert motion.speed_unit == "mm/s" and motion.speed <= FAST  # a cruise speed, never above 3 m/s
            start, end = outside_zones(moves, tool, k)
            velocity, acceleration = line_demand(tool, start, end, motion.speed)
            assert np.max(np.abs(velocity) / robot.v_max) <= SLACK
            assert np.max(np.abs(acceleration) / robot.a_max) <= SLACK
            checked.add("cruise")
            continue
        assert moves.kind[k] == JOINT
        if motion.speed_unit == "s":
            q, qd, qdd = joint_line(robot, moves.q[k - 1], moves.q[k], duration=motion.speed)
            checked.add("time")
        else:  # KRL: the percentage of the leading axis's velocity limit
            assert motion.speed_unit == "%" and motion.speed <= joint_speed["%"]
            q, qd, qdd = joint_line(robot, moves.q[k - 1], moves.q[k], percent=motion.speed)
            checked.add("percent")
        limit = np.minimum(robot.v_max, robot.v_max * joint_speed.get("%", 100.0) / 100.0)
        limit = np.minimum(limit, joint_speed.get("rad/s", np.inf))
        assert np.max(np.abs(qd) / limit) <= SLACK and np.max(np.abs(qdd) / robot.a_max) <= SLACK
        if "mm/s" in joint_speed:  # RAPID's MoveJ: the TCP speed of its speeddata
            tcp = np.linalg.norm(np.einsum("nij,nj->ni", jacobian(tool, q)[:, :3], qd), axis=1)
            assert np.max(tcp) <= joint_speed["mm/s"] * SLACK
    assert checked == ({"cruise", "percent"} if language == "krl" else {"cruise", "time"})


def test_a_time_on_a_blended_motion_spans_its_programmed_length_corner_to_corner(tmp_path):
    """A controller given a time for a blended line or arc (RAPID ``\\T``) paces it over the programmed length,
    corner to corner, not over the shorter timed path between blend middles: the timing carries that length, the
    targets' chord and the arc through the via point (computed here from the robtargets alone)."""
    from trajcomp.timing.writeback import retime_program

    def at(r, deg):
        return f"[[{r * np.cos(np.radians(deg)):.3f},{r * np.sin(np.radians(deg)):.3f},1100],[0,0,1,0],[0,0,0,0]," \
               "[9E9,9E9,9E9,9E9,9E9,9E9]]"

    module = (f"MODULE Arc\n  CONST robtarget Q0:={at(900, 10)};\n  CONST robtarget Q1:={at(450, 10)};\n"
              f"  CONST robtarget V1:={at(450, 35)};\n  CONST robtarget Q2:={at(450, 60)};\n"
              f"  CONST robtarget Q3:={at(900, 60)};\n  PROC main()\n    MoveJ Q0, v1000, fine, tool0;\n"
              "    MoveL Q1, v1000\\T:=0.01, z100, tool0;\n    MoveC V1, Q2, v1000\\T:=0.01, z100, tool0;\n"
              "    MoveL Q3, v1000\\T:=0.01, fine, tool0;\n  ENDPROC\nENDMODULE\n")
    path = tmp_path / "Arc.mod"
    path.write_text(module)
    program, robot = formats.read(path), load_robot("abb_irb4600")
    plan = planned_joints(program, robot)
    result = retime_program(program, robot, planned(program, plan.index, plan.q))
    expected = [450.0, 450.0 * np.radians(50.0), 450.0]  # the lines' chords, the arc of 50 deg at 450 mm
    assert np.allclose(result.programmed_length[1:], expected, atol=1e-3)
    assert np.all(result.tcp_length[1:] < np.array(expected) - 1.0)  # the timed path cuts the blended corners
    timed = formats.read(_retimed(path, tmp_path, "abb_irb4600")).motion_table()
    cruise = robot.v_max[0] * 450.0  # mm/s: J1 alone turns the TCP along the arc, at 450 mm from its axis
    assert timed.speed[2] >= expected[1] / cruise  # the controller's pace over the arc: within J1's limit


def test_a_time_paced_over_the_programmed_length_keeps_the_joint_limits_on_the_straight_part(tmp_path):
    """A ``\\T`` asked faster than the arm can go on a blended line (z200 both ends) passing 300 mm from J1's
    axis: the controller paces the written time over the programmed length, corner to corner, so it runs the
    straight part between the zones at L / T. Sampled at 1 kHz with IK there (independent of the timing), no
    joint exceeds its velocity limit (J1 at 300 mm binds). Timed over the shorter path between blend middles
    (1.039 s where 1.092 s are needed), J1 would run 5 % over its limit."""
    corners = [(1300, -500), (300, -500), (300, 500), (1300, 500)]
    quadrant = [int(np.floor(np.degrees(np.arctan2(y, x)) / 90.0)) for x, y in corners]
    module = ("MODULE Near\n" + "".join(
        f"  CONST robtarget Q{n}:=[[{x},{y},1300],[0,0,1,0],[{c},0,{c},0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        for n, ((x, y), c) in enumerate(zip(corners, quadrant)))
        + "  PROC main()\n    MoveJ Q0, v1000, fine, tool0;\n    MoveL Q1, v1000\\T:=0.01, z200, tool0;\n"
        "    MoveL Q2, v1000\\T:=0.01, z200, tool0;\n    MoveL Q3, v1000\\T:=0.01, fine, tool0;\n"
        "  ENDPROC\nENDMODULE\n")
    path = tmp_path / "Near.mod"
    path.write_text(module)
    robot = load_robot("abb_irb4600")
    timed = formats.read(_retimed(path, tmp_path, "abb_irb4600")).motion_table()
    assert timed.speed_unit[2] == "s"
    pace = 1000.0 / timed.speed[2]  # mm/s: the programmed 1000 mm from Q1 to Q2 over the written time
    down = np.diag([-1.0, 1.0, -1.0])  # [0,0,1,0]: the tool turned half about y
    start, end = np.eye(4), np.eye(4)
    start[:3, :3] = end[:3, :3] = down
    start[:3, 3], end[:3, 3] = (300.0, -300.0, 1300.0), (300.0, 300.0, 1300.0)  # 200 mm in from each corner
    velocity, _ = line_demand(robot.replace(T_flange_tool=np.eye(4)), start, end, pace)
    assert np.max(np.abs(velocity) / robot.v_max) <= 1.005


def _retimed(path, tmp_path, robot_name):
    out = tmp_path / "out" / path.name
    out.parent.mkdir(exist_ok=True)
    assert main(["retime", str(path), "-o", str(out), "--robot", robot_name]) in (0, 1)
    return out
