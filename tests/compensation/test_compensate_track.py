"""Robots on a linear track (issue 35, section 1): the arm part compensated in the carriage frame.

A virtual arm of each maker stands on a track (a KUKA KL unit driven by
E1, a FANUC rail by E1, an ABB IRBT track by eax_a). It is calibrated at
one carriage position (a grid in its base frame); a hand-written program in
the maker's language states world targets at carriage positions metres
apart. Compensated, each target's written command, run by the virtual arm
from the carriage where the target's track value puts it, lands within
0.02 mm of the world target; the track values are written as they stand.
A program on a track whose robot description has none is refused saying so.
"""

import dataclasses
import json
import re
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from trajcomp import formats
from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot, robot_from_yaml
from trajcomp.arm.transforms import matrix_to_abc
from trajcomp.calibration.calibrate import calibrate
from trajcomp.calibration.measurement_plan import plan_grid
from trajcomp.calibration.measurements import Measurements
from trajcomp.calibration.virtual_arm import VirtualRobot
from trajcomp.compensation.program_rewrite import compensate_program
from trajcomp.compensation.target_correction import program_corrector
from trajcomp.errors import IKError, RobotError, TrajcompError
from trajcomp.formats.configuration import configuration_data, configuration_for

DIRECTION = np.array([1.0, 0.02, 0.0]) / np.linalg.norm([1.0, 0.02, 0.0])  # a track not quite along world x
CARRIAGE = [0.0, 1850.0, 4200.0]  # mm of track position: metres apart
TRACK = """
track:
  direction: [1.0, 0.02, 0.0]
  limits: {position_min: -100, position_max: 5800, velocity: 2000, acceleration: 2500}
  fields: {krl: E1, fanuc_ls: E1, rapid: eax_a}
"""
# each arm's calibrated cube (corner, side, step: mm) and the arm posture its targets are solved in
CELLS = {"kuka_kr6_r900": ((400.0, -50.0, 650.0), 200.0, 50.0),
         "fanuc_lrmate200id": ((300.0, -100.0, 300.0), 200.0, 50.0),
         "abb_irb4600": ((1000.0, -200.0, 700.0), 400.0, 100.0)}


def on_track(name, track=TRACK):
    """Built-in robot ``name`` on the track `TRACK` (its YAML with a ``track`` mapping)."""
    text = resources.files("trajcomp.arm.robots").joinpath(f"{name}.yaml").read_text(encoding="utf-8")
    return robot_from_yaml(text + track, f"{name} on a track")


_CELL, _CELL_MODEL = {}, {}  # per arm: (robot, virtual arm, corrector), and its calibrated model


def cell(name):
    """(robot on the track, virtual arm, program corrector) of arm ``name``, calibrated once per test run."""
    if name not in _CELL:
        robot = on_track(name)
        virtual = VirtualRobot.create(robot, "paper", seed=4)
        model = calibrated(robot, virtual, name, folds=0)
        _CELL[name], _CELL_MODEL[name] = (robot, virtual, program_corrector(model)), model
    return _CELL[name]


def calibrated(robot, virtual, name, folds):
    """The composite model of arm ``name``'s cell, calibrated from its cube measured by ``virtual``."""
    corner, side, step = CELLS[name]
    plan = plan_grid(robot, corner, side, step, orientation=matrix_to_abc(orientation(robot)))
    q = plan.joints[plan.reachable]
    meas = Measurements(joints=q, position=plan.position[plan.reachable],
                        measured=virtual.measure(q, np.random.default_rng(5)), lines=np.arange(len(q)) + 2,
                        path="grid.csv")
    return calibrate(robot, meas, method="composite", grid_step=step, folds=folds)


def arm_poses(robot, rng, count=8):
    """Joints (count, 6) of random poses in the KUKA cell's cube, in the targets' orientation."""
    corner, side, _ = CELLS["kuka_kr6_r900"]
    local = np.tile(np.eye(4), (count, 1, 1))
    local[:, :3, :3] = orientation(robot)
    local[:, :3, 3] = np.asarray(corner) + rng.uniform(0.1 * side, 0.9 * side, (count, 3))
    return ik(robot, local, seed=np.tile(robot.home, (count, 1))).raise_on_failure("poses").q


def orientation(robot):
    """The targets' and the grid's tool orientation (3, 3): the home one tilted (no KUKA B = 90 deg gimbal lock)."""
    tilt = Rotation.from_euler("xyz", [6.0, -9.0, 0.0], degrees=True).as_matrix()
    return fk(robot, robot.home[None])[0, :3, :3] @ tilt


def world_targets(robot, name):
    """World poses (3, 4, 4) inside the arm's calibrated cube, one at each carriage position, and their joints."""
    corner, side, _ = CELLS[name]
    rng = np.random.default_rng(7)
    local = np.tile(np.eye(4), (len(CARRIAGE), 1, 1))
    local[:, :3, :3] = orientation(robot)
    local[:, :3, 3] = np.asarray(corner) + rng.uniform(0.2 * side, 0.8 * side, (len(CARRIAGE), 3))
    q = ik(robot, local, seed=np.tile(robot.home, (len(CARRIAGE), 1))).raise_on_failure("targets").q
    world = robot.track.placements(robot.T_world_base, np.array(CARRIAGE)) @ local
    return world, q


def landing(robot, virtual, world_command, carriage):
    """World positions (N, 3) the virtual arm reaches for world commands (N, 4, 4) at track positions (N,)."""
    placements = robot.track.placements(robot.T_world_base, np.asarray(carriage))
    local = np.linalg.inv(placements) @ world_command
    q = ik(robot, local, seed=np.tile(robot.home, (len(local), 1))).raise_on_failure("commands").q
    return (placements @ virtual.reached_poses(q))[:, :3, 3]


# ------------------------------------------------------------------ the three languages


def _krl(folder, world, q, robot):
    status = configuration_for(configuration_data("krl"), robot, q)
    points = []
    for k, (T, (s, t)) in enumerate(zip(world, status)):
        a, b, c = Rotation.from_matrix(T[:3, :3]).as_euler("ZYX", degrees=True)
        points.append(f"DECL E6POS XP{k + 1}={{X {T[0, 3]:.4f},Y {T[1, 3]:.4f},Z {T[2, 3]:.4f},A {a:.5f},B {b:.5f},"
                      f"C {c:.5f},S {s},T {t},E1 {CARRIAGE[k]:.1f},E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}")
    (folder / "rail.dat").write_text("DEFDAT  RAIL\n" + "\n".join(points) + "\nENDDAT\n")
    (folder / "rail.src").write_text("DEF rail( )\n$BASE=$NULLFRAME\n$VEL.CP=0.2\nBAS(#VEL_PTP,20)\nPTP XP1\n"
                                     "LIN XP2 C_DIS\nLIN XP3\nEND\n")
    return folder / "rail.src"


def _read_poses(text, pattern, rotation):
    """World poses (N, 4, 4) and track positions (N,) of the points of a program's ``text``: ``pattern`` matches
    x, y, z, the three (or four) numbers ``rotation(numbers) -> Rotation`` reads, then the track position."""
    poses, carriage = [], []
    for m in re.finditer(pattern, text):
        v = [float(x) for x in m.groups()]
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = rotation(v[3:-1]).as_matrix(), v[:3]
        poses.append(T)
        carriage.append(v[-1])
    return np.array(poses), np.array(carriage)


def _read_krl(path):
    """World poses (N, 4, 4) and E1 (N,) of the points a KRL .dat declares."""
    return _read_poses(path.with_suffix(".dat").read_text(),
                       r"X ([-\d.]+),Y ([-\d.]+),Z ([-\d.]+),A ([-\d.]+),B ([-\d.]+),C ([-\d.]+),"
                       r"S \d+,T \d+,E1 ([-\d.]+)",
                       lambda abc: Rotation.from_euler("ZYX", abc, degrees=True))


def _fanuc(folder, world, q, robot):
    configs = configuration_for(configuration_data("fanuc_ls"), robot, q)
    positions = ""
    for k, (T, config) in enumerate(zip(world, configs)):
        w, p, r = Rotation.from_matrix(T[:3, :3]).as_euler("xyz", degrees=True)
        flip, up, top, *turns = config
        positions += (f"P[{k + 1}]{{\n   GP1:\n\tUF : 0, UT : 0,\t\tCONFIG : '{flip} {up} {top}, "
                      f"{', '.join(map(str, turns))}',\n\tX = {T[0, 3]:10.3f}  mm,\tY = {T[1, 3]:10.3f}  mm,\t"
                      f"Z = {T[2, 3]:10.3f}  mm,\n\tW = {w:10.3f} deg,\tP = {p:10.3f} deg,\tR = {r:10.3f} deg,\n"
                      f"\tE1 = {CARRIAGE[k]:10.3f}  mm\n}};\n")
    (folder / "RAIL.LS").write_text(
        "/PROG  RAIL\n/ATTR\nOWNER\t\t= MNEDITOR;\nDEFAULT_GROUP\t= 1,*,*,*,*;\n/MN\n   1:  UFRAME_NUM=0 ;\n"
        "   2:  UTOOL_NUM=0 ;\n   3:J P[1] 20% FINE    ;\n   4:L P[2] 200mm/sec CNT50    ;\n"
        f"   5:L P[3] 200mm/sec FINE    ;\n/POS\n{positions}/END\n")
    return folder / "RAIL.LS"


def _read_fanuc(path):
    """World poses (N, 4, 4) and E1 (N,) of the positions of a FANUC .LS."""
    return _read_poses(path.read_text(), r"X =\s*([-\d.]+)\s*mm,\s*Y =\s*([-\d.]+)\s*mm,\s*Z =\s*([-\d.]+)\s*mm,"
                       r"\s*W =\s*([-\d.]+)\s*deg,\s*P =\s*([-\d.]+)\s*deg,\s*R =\s*([-\d.]+)\s*deg,"
                       r"\s*E1 =\s*([-\d.]+)",
                       lambda wpr: Rotation.from_euler("xyz", wpr, degrees=True))


def _rapid(folder, world, q, robot):
    configs = configuration_for(configuration_data("rapid"), robot, q)
    lines = []
    for k, (T, config) in enumerate(zip(world, configs)):
        x, y, z, w = Rotation.from_matrix(T[:3, :3]).as_quat()
        lines.append(f"  CONST robtarget pRail{k + 1}:=[[{T[0, 3]:.3f},{T[1, 3]:.3f},{T[2, 3]:.3f}],"
                     f"[{w:.9f},{x:.9f},{y:.9f},{z:.9f}],[{','.join(map(str, config))}],"
                     f"[{CARRIAGE[k]:.2f},9E9,9E9,9E9,9E9,9E9]];")
    (folder / "Rail.mod").write_text(
        "MODULE Rail\n" + "\n".join(lines) + "\n  PROC main()\n    MoveJ pRail1,v1000,fine,tool0\\WObj:=wobj0;\n"
        "    MoveL pRail2,v200,z10,tool0\\WObj:=wobj0;\n    MoveL pRail3,v200,fine,tool0\\WObj:=wobj0;\n"
        "  ENDPROC\nENDMODULE\n")
    return folder / "Rail.mod"


def _read_rapid(path):
    """World poses (N, 4, 4) and eax_a (N,) of the robtargets of a RAPID module."""
    return _read_poses(path.read_text(), r"\[\[([-\d.]+),([-\d.]+),([-\d.]+)\],\[([-\d.]+),([-\d.]+),([-\d.]+),"
                       r"([-\d.]+)\],\[[-\d,]+\],\[([-\d.]+),", lambda q: Rotation.from_quat([*q[1:], q[0]]))


LANGUAGES = {"kuka_kr6_r900": (_krl, _read_krl), "fanuc_lrmate200id": (_fanuc, _read_fanuc),
             "abb_irb4600": (_rapid, _read_rapid)}


@pytest.mark.parametrize("name", sorted(LANGUAGES))
def test_a_program_on_a_track_lands_within_0_02_mm_of_its_world_targets(tmp_path, name):
    robot, virtual, correct = cell(name)
    write, read = LANGUAGES[name]
    world, q = world_targets(robot, name)
    path = write(tmp_path, world, q, robot)
    program = formats.read(path)
    before = landing(robot, virtual, *read(path))
    edited, report = compensate_program(program, correct, robot)
    assert not [w for w in report.warnings if "external axes" in w]  # the track is the arm's, not a warning
    out = tmp_path / "out"
    out.mkdir()
    formats.write(out / path.name, edited)
    commands, carriage = read(out / path.name)
    np.testing.assert_array_equal(carriage, CARRIAGE)  # the track positions as written
    after = landing(robot, virtual, commands, carriage)
    error_before = np.linalg.norm(before - world[:, :3, 3], axis=1)
    error_after = np.linalg.norm(after - world[:, :3, 3], axis=1)
    assert error_before.min() > 0.3  # the virtual arm misses by tenths of a mm uncompensated
    assert error_after.max() < 0.02, error_after


def test_the_arm_part_is_compensated_in_the_carriage_frame(tmp_path):
    """The poses handed to the correction are the world targets seen from each target's carriage."""
    robot, _, correct = cell("kuka_kr6_r900")
    world, q = world_targets(robot, "kuka_kr6_r900")
    program = formats.read(_krl(tmp_path, world, q, robot))
    seen = {}

    def recording(T, tools, seeds, names):
        seen["T"] = T.copy()
        return correct(T, tools, seeds, names)

    compensate_program(program, recording, robot)
    expected = fk(robot, q)  # the arm's own pose, whatever the carriage
    np.testing.assert_allclose(seen["T"][:, :3, 3], expected[:, :3, 3], atol=2e-3)


def test_a_program_on_a_track_whose_robot_has_none_is_refused_for_that_reason(tmp_path):
    robot = on_track("kuka_kr6_r900")
    world, q = world_targets(robot, "kuka_kr6_r900")
    program = formats.read(_krl(tmp_path, world, q, robot))
    fixed = load_robot("kuka_kr6_r900")
    with pytest.raises(IKError, match=r"^rail: the program moves external axis E1 over 4200 mm and its targets move "
                                      r"with it, out of the reach of robot kuka_kr6_r900 from a fixed base: a robot "
                                      r"on a track, and the robot's description describes no track\. Describe the "
                                      r"track .* cannot reach"):
        compensate_program(program, cell("kuka_kr6_r900")[2], fixed)
    no_field = on_track("kuka_kr6_r900", TRACK.replace("krl: E1, ", ""))
    with pytest.raises(IKError, match="has a track but names no field of krl programs for it"):
        compensate_program(program, cell("kuka_kr6_r900")[2], no_field)
    # an axis that moves a few mm with targets out of reach (a servo gun on an arm taught elsewhere): the posture
    dat = tmp_path / "rail.dat"
    dat.write_text(dat.read_text().replace("E1 1850.0", "E1 20.0").replace("E1 4200.0", "E1 40.0"))
    with pytest.raises(IKError, match=r"^rail: .*cannot reach") as refused:
        compensate_program(formats.read(tmp_path / "rail.src"), cell("kuka_kr6_r900")[2], fixed)
    assert "track" not in str(refused.value)


def test_a_program_far_along_a_track_is_not_taken_for_one_in_another_unit(tmp_path, monkeypatch):
    """Every target 30 m along a track the robot's description lacks: tens of the arm's reaches from its fixed base,
    as the positions of a program in millimetres read as metres are; its targets are refused as out of reach, not
    its unit (a KRL program is in millimetres)."""
    monkeypatch.setitem(globals(), "CARRIAGE", [position + 30_000.0 for position in CARRIAGE])
    robot = on_track("kuka_kr6_r900")
    world, q = world_targets(robot, "kuka_kr6_r900")
    program = formats.read(_krl(tmp_path, world, q, robot))
    with pytest.raises(IKError, match=r"^rail: .*cannot be reached by robot kuka_kr6_r900") as refused:
        compensate_program(program, cell("kuka_kr6_r900")[2], load_robot("kuka_kr6_r900"))
    assert "millimetres" not in str(refused.value)


def test_a_krl_point_without_e1_on_the_first_motion_is_left_as_written_and_the_rest_compensated(tmp_path):
    """KRL: the first motion's point states no E1: the controller runs it from wherever the track stands, which
    the program does not say. That motion is left as written and listed with the reason; the others land within
    0.02 mm of their world targets; run as ``compensate`` runs it, the verdict fails on it (exit 1); ``retime``
    runs it as written."""
    from trajcomp.jobs.pipeline import CompensationJob
    from trajcomp.jobs.retime import RetimeJob

    robot, virtual, correct = cell("kuka_kr6_r900")
    world, q = world_targets(robot, "kuka_kr6_r900")
    path = _krl(tmp_path, world, q, robot)
    dat = path.with_suffix(".dat")
    dat.write_text(re.sub(r",E1 [-\d.]+,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0", "", dat.read_text(), count=1))
    before = dat.read_text().splitlines()[1]
    edited, report = compensate_program(formats.read(path), correct, robot)
    assert len(report.labels) == 2 and report.motions_left == 1
    [(line, text, why)] = report.not_compensated
    assert (line, text) == (5, "PTP XP1")
    assert why.startswith("states no E1, so its track position, hence the arm's base, is unknown: the controller "
                          "keeps the track where the motion before leaves it, which starts from a position"), why
    out = tmp_path / "out"
    out.mkdir()
    formats.write(out / path.name, edited)
    assert (out / dat.name).read_text().splitlines()[1] == before  # XP1 as written
    commands, carriage = _read_krl(out / path.name)
    errors = np.linalg.norm(landing(robot, virtual, commands, carriage) - world[1:, :3, 3], axis=1)
    assert errors.max() < 0.02, errors
    job = tmp_path / "job"
    job.mkdir()
    run = CompensationJob(_CELL_MODEL["kuka_kr6_r900"]).run(path, job / path.name)
    assert run.result.status == "fail" and "uncompensated" in run.result.message
    assert "1 of 3 motions were not compensated (the first, line 5: states no E1" in run.result.message
    [entry] = run.compliance.doc["not_compensated"]
    assert entry["line"] == 5 and "states no E1" in entry["reason"]
    timed = tmp_path / "timed"
    timed.mkdir()
    run = RetimeJob(robot).run(path, timed / path.name)  # retime runs it as written, not refusing the program
    assert run.result.status == "pass" and run.timing.track is not None
    assert (timed / dat.name).read_text().splitlines()[1] == before and "PTP XP1" in (timed / path.name).read_text()


def _krl_with_pos(tmp_path, robot, world, q, motions):
    """The KRL program with XP4: XP3's world pose as a POS (no E1), its motions ``motions`` after XP3's."""
    path = _krl(tmp_path, world, q, robot)
    dat = path.with_suffix(".dat")
    last = dat.read_text().splitlines()[-2]
    dat.write_text(dat.read_text().replace("ENDDAT", re.sub(r",E1 .*\}", "}", last).replace("E6POS XP3", "POS XP4")
                                           + "\nENDDAT"))
    path.write_text(path.read_text().replace("LIN XP3\n", "LIN XP3\n" + motions))
    return path


def test_a_krl_point_without_e1_keeps_the_track_where_the_motion_before_left_it(tmp_path):
    """KRL: a POS point (or an aggregate without E1) leaves the external axes where they are: XP4 after XP3 is
    reached from the carriage at 4200 mm and lands on its world target there; used after two track positions it
    has no one carriage, and is refused naming them."""
    robot, virtual, correct = cell("kuka_kr6_r900")
    world, q = world_targets(robot, "kuka_kr6_r900")
    path = _krl_with_pos(tmp_path, robot, world, q, "LIN XP4\n")
    edited, report = compensate_program(formats.read(path), correct, robot)
    assert len(report.labels) == 4 and not report.not_compensated
    out = tmp_path / "out"
    out.mkdir()
    formats.write(out / path.name, edited)
    m = re.search(r"POS XP4=\{X ([-\d.]+),Y ([-\d.]+),Z ([-\d.]+),A ([-\d.]+),B ([-\d.]+),C ([-\d.]+),",
                  (out / path.name).with_suffix(".dat").read_text())
    command = np.eye(4)
    v = [float(x) for x in m.groups()]
    command[:3, :3], command[:3, 3] = Rotation.from_euler("ZYX", v[3:], degrees=True).as_matrix(), v[:3]
    landed = landing(robot, virtual, command[None], [CARRIAGE[2]])
    assert np.linalg.norm(landed[0] - world[2, :3, 3]) < 0.02
    path = _krl_with_pos(tmp_path, robot, world, q, "LIN XP4\nLIN XP2\nLIN XP4\n")
    _, report = compensate_program(formats.read(path), correct, robot)
    assert len(report.labels) == 3 and [(line, why) for line, _, why in report.not_compensated] == [
        (line, "states no E1, so its track position, hence the arm's base, is unknown: the controller keeps the "
               "track where the motion before leaves it: 1850 and 4200 mm on its uses") for line in (8, 10)]


@pytest.mark.parametrize("name", ["fanuc_lrmate200id", "abb_irb4600"])
def test_a_fanuc_or_rapid_target_without_its_track_value_is_refused_as_its_controller_does(tmp_path, name):
    """RAPID: 9E9 in eax_a of an active axis is the controller's error 40512 (missing external axis value); FANUC:
    a position of a group with an extended axis holds its value (an LS without it does not load). Both refused,
    naming the target, even after a target that states it."""
    robot, _, correct = cell(name)
    world, q = world_targets(robot, name)
    write = LANGUAGES[name][0]
    path = write(tmp_path, world, q, robot)
    text = path.read_text()
    if name == "abb_irb4600":
        text = text.replace("[4200.00,9E9", "[9E9,9E9")
        where, field = r"pRail3 \(Rail\.mod:4\)", "eax_a"
    else:
        text = re.sub(r",?\s*E1 =\s*4200\.000\s*mm", "", text)
        where, field = r"P\[3\] \(RAIL\.LS:\d+\)", "E1"
    path.write_text(text)
    with pytest.raises(TrajcompError, match=where + f" states no {field}: .*; state {field} in every Cartesian target"):
        compensate_program(formats.read(path), correct, robot)


def test_a_fanuc_rail_as_motion_group_2_is_read_compensated_retimed_and_written_back(tmp_path):
    """A rail as FANUC motion group 2 (GP2: J1 in mm in each /POS entry, DEFAULT_GROUP = 1,1,...), described as
    ``fanuc_ls: GP2:J1``: the arm part lands within 0.02 mm of the world targets from the rail's carriage, the
    program is re-timed with the rail as a joint, and every byte but group 1's pose numbers is written back."""
    from trajcomp.jobs.retime import planned
    from trajcomp.compensation.posture import planned_joints
    from trajcomp.timing.writeback import retime_program

    _, virtual, correct = cell("fanuc_lrmate200id")
    robot = on_track("fanuc_lrmate200id", TRACK.replace("fanuc_ls: E1", "fanuc_ls: 'GP2:J1'"))
    world, q = world_targets(robot, "fanuc_lrmate200id")
    path = _fanuc(tmp_path, world, q, robot)
    text = re.sub(r",\n\tE1 =\s*([-\d.]+)\s*mm\n\}",
                  lambda m: f"\n   GP2:\n\tUF : 0, UT : 1,\n\tJ1 = {float(m.group(1)):10.3f}  mm\n}}", path.read_text())
    text = text.replace("DEFAULT_GROUP\t= 1,*,*,*,*;", "DEFAULT_GROUP\t= 1,1,*,*,*;")
    assert text.count("GP2:") == 3 and "E1" not in text
    path.write_text(text)
    program = formats.read(path)
    edited, report = compensate_program(program, correct, robot)
    assert not report.not_compensated and not [w for w in report.warnings if "external axes" in w]
    out = tmp_path / "out"
    out.mkdir()
    formats.write(out / path.name, edited)
    written = (out / path.name).read_text()
    pose_lines = re.compile(r"^\t[XW] = .*$", re.M)
    assert pose_lines.sub("", written) == pose_lines.sub("", text)  # header, group mask, GP2 entries as they were
    commands, _ = _read_poses(written, r"X =\s*([-\d.]+)\s*mm,\s*Y =\s*([-\d.]+)\s*mm,\s*Z =\s*([-\d.]+)\s*mm,"
                              r"\s*W =\s*([-\d.]+)\s*deg,\s*P =\s*([-\d.]+)\s*deg,\s*R =\s*([-\d.]+)\s*deg"
                              r"\s*GP2:\s*UF : 0, UT : 1,\s*J1 =\s*([-\d.]+)",
                              lambda wpr: Rotation.from_euler("xyz", wpr, degrees=True))
    landed = landing(robot, virtual, commands, CARRIAGE)
    assert np.linalg.norm(landed - world[:, :3, 3], axis=1).max() < 0.02
    plan = planned_joints(program, robot)
    timing = retime_program(program, robot, planned(program, plan.index, plan.q))
    assert timing.track.field == "GP2:J1" and timing.within_limits and timing.track.peak_velocity > 100.0


@pytest.mark.parametrize("track, message", [
    (TRACK.replace("[1.0, 0.02, 0.0]", "[0, 0, 0]"), "track.direction: the zero vector"),
    (TRACK.replace("position_min: -100", "position_min: 6000"), "position_min 6000 mm is not below"),
    (TRACK.replace("rapid: eax_a", "rapid: A1"), "track.fields.rapid: expected E1..E6, eax_a..eax_f or GP2:J1..J6"),
    (TRACK.replace("velocity: 2000", "velocity: -1"), "track.limits.velocity: expected a positive number"),
    ("\ntrack: [1, 0, 0]\n", "field track: expected a mapping"),
])
def test_a_track_description_is_checked_field_by_field(track, message):
    with pytest.raises(RobotError, match=re.escape(message)):
        on_track("kuka_kr6_r900", track)


def test_compensate_and_retime_on_a_track_through_the_cli_time_the_track_as_a_joint(tmp_path, monkeypatch, capsys):
    """A program that moves the track is re-timed with the track as a joint: ``compensate`` and ``retime`` print
    its line of the limits table and write the world TCP speed the track allows (`tests/timing/test_timing_track.py`
    checks the figures)."""
    from trajcomp.cli import main

    monkeypatch.chdir(tmp_path)
    text = resources.files("trajcomp.arm.robots").joinpath("kuka_kr6_r900.yaml").read_text(encoding="utf-8")
    slow = TRACK.replace("velocity: 2000", "velocity: 500")
    (tmp_path / "kr6_rail.yaml").write_text(text.replace("name: kuka_kr6_r900", "name: kr6_rail") + slow)
    robot = load_robot("kr6_rail.yaml")
    angles = np.degrees(matrix_to_abc(orientation(robot)))
    assert main(["plan", "--robot", "kr6_rail.yaml", "--cube", "400,-50,650", "--side", "200", "--step", "50",
                 "--orientation=" + ",".join(f"{v:.6f}" for v in angles), "-o", "plan.csv"]) == 0
    assert main(["simulate", "plan.csv", "--robot", "kr6_rail.yaml", "--seed", "1", "-o", "meas.csv"]) == 0
    assert main(["calibrate", "meas.csv", "--robot", "kr6_rail.yaml", "--grid-step", "50", "--folds", "3",
                 "-o", "model.yaml"]) == 0
    world, q = world_targets(robot, "kuka_kr6_r900")
    src = _krl(tmp_path, world, q, robot)
    src.write_text(src.read_text().replace("$VEL.CP=0.2", "$VEL.CP=2"))
    before = src.read_text()
    capsys.readouterr()
    code = main(["compensate", "rail.src", "--model", "model.yaml", "-o", "out.src"])
    out = "".join(capsys.readouterr())
    assert code in (0, 1) and re.search(r"^E1 +[\d.]+ +500 ", out, re.M), out
    assert "the track's (E1) velocity limit" in out and src.read_text() == before
    written = [float(v) for v in re.findall(r"\$VEL\.CP=([\d.]+)", (tmp_path / "out.src").read_text())]
    assert written and all(0.45 < v < 0.5 for v in written)  # m/s: the track's 500 mm/s over 1850 mm in 1802
    assert main(["retime", "rail.src", "--robot", "kr6_rail.yaml", "-o", "timed.src", "--report", "timed.html"]) == 0
    assert "$VEL.CP=0.486" in (tmp_path / "timed.src").read_text()
    track = json.loads((tmp_path / "timed.json").read_text())["timing"]["track"]
    assert track["field"] == "E1" and 490 < track["velocity"]["peak"] <= 505 and track["velocity"]["limit"] == 500


# ------------------------------------------------------------------ calibration with a track


def on_the_real_track(tmp_path, robot, virtual, correct, true, tracks):
    """Landing errors (3,), mm, of the KRL program at `CARRIAGE` whose world targets are where the real track
    ``true`` puts the arm, compensated with each track of ``tracks`` (``{label: Track}``): ``{label: errors}``.
    The controller places the arm with its own (nominal) track; the arm stands on the real one."""
    world, q_targets = world_targets(robot, "kuka_kr6_r900")
    world = true.placements(robot.T_world_base, np.array(CARRIAGE)) @ np.linalg.inv(
        robot.track.placements(robot.T_world_base, np.array(CARRIAGE))) @ world
    path = _krl(tmp_path, world, q_targets, robot)
    errors = {}
    for label, used in tracks.items():
        edited, _ = compensate_program(formats.read(path), correct, robot.replace(track=used))
        out = tmp_path / label
        out.mkdir()
        formats.write(out / path.name, edited)
        commands, carriage = _read_krl(out / path.name)
        arm_q = ik(robot, np.linalg.inv(robot.track.placements(robot.T_world_base, carriage)) @ commands,
                   seed=np.tile(robot.home, (len(commands), 1))).raise_on_failure("commands").q
        landed = (true.placements(robot.T_world_base, carriage) @ virtual.reached_poses(arm_q))[:, :3, 3]
        errors[label] = np.linalg.norm(landed - world[:, :3, 3], axis=1)
    return errors


def test_a_track_calibration_recovers_its_direction_and_scale_and_compensation_then_lands(tmp_path):
    """The real track runs 0.1 deg off its nominal direction and 0.05 % long. Measured at five carriage positions
    (eight arm poses each, 0.01 mm tracker noise), the fit recovers both; compensated with the identified track, a
    program lands within 0.02 mm at 4.2 m of travel, where the nominal track misses by millimetres."""
    from trajcomp.calibration.track_fit import identify_track

    robot, virtual, correct = cell("kuka_kr6_r900")
    turn = Rotation.from_euler("z", 0.1, degrees=True).as_matrix()
    true = robot.track.replace(actual_direction=turn @ robot.track.direction, actual_scale=1.0005)
    corner, side, _ = CELLS["kuka_kr6_r900"]
    rng = np.random.default_rng(11)
    q = arm_poses(robot, rng)
    positions = np.repeat([0.0, 1400.0, 2800.0, 4200.0, 5600.0], len(q))
    joints = np.tile(q, (5, 1))
    measured = (true.placements(robot.T_world_base, positions) @ virtual.reached_poses(joints))[:, :3, 3]
    measured += rng.normal(0.0, 0.01, measured.shape)
    plan = plan_grid(robot, corner, side, 50.0, orientation=matrix_to_abc(orientation(robot)))
    grid_q = plan.joints[plan.reachable]
    meas = Measurements(joints=grid_q, position=plan.position[plan.reachable],
                        measured=virtual.measure(grid_q, np.random.default_rng(5)), lines=np.arange(len(grid_q)) + 2,
                        path="grid.csv")
    model = calibrate(robot, meas, method="composite", grid_step=50.0, folds=0)
    predicted, _ = model.predict("composite", joints, fk(robot, joints)[:, :3, 3])
    fit = identify_track(robot.track, robot.T_world_base, positions, predicted, measured)
    assert abs(fit.direction_change_deg - 0.1) < 0.002
    assert np.degrees(np.arccos(fit.track.actual_direction @ true.actual_direction)) < 0.002
    assert abs(fit.track.actual_scale - 1.0005) < 5e-6 and abs(fit.scale_change - 0.0005) < 5e-6
    assert fit.track.direction is robot.track.direction  # the controller's track, as it has it
    assert fit.residual_rms < 0.03 and np.linalg.norm(fit.offset) < 0.02
    np.testing.assert_array_equal(fit.positions, [0, 1400, 2800, 4200, 5600])
    assert fit.track.beyond_measured([-50.0, 3000.0, 5700.0]).tolist() == [True, False, True]
    assert fit.track.straightness is None and fit.straightness_rms < 3 * fit.noise_rms  # straight: no table
    errors = on_the_real_track(tmp_path, robot, virtual, correct, true,
                               {"nominal": robot.track, "identified": fit.track})
    assert errors["nominal"].max() > 2.0  # 0.1 deg and 0.05 % of 4.2 m
    assert errors["identified"].max() < 0.02, errors


def test_a_track_that_is_not_straight_is_identified_as_a_table_and_compensation_lands_between_its_positions(
        tmp_path):
    """The real track bows 0.08 mm sideways and 0.04 mm up over its travel (a sine along it). Measured at nine
    carriage positions 700 mm apart (eight poses each, 0.01 mm noise), the fit keeps a straightness table that
    matches the bow within 0.01 mm at each; targets between the measured positions then land within 0.02 mm,
    where the line alone misses by the bow; the model file keeps the table."""
    from trajcomp.calibration.track_fit import identify_track
    from trajcomp.model.model_file import load_model, save_model

    robot, virtual, correct = cell("kuka_kr6_r900")
    dense = np.linspace(-100.0, 5800.0, 119)
    bow = np.sin(np.pi * (dense + 100.0) / 5900.0)[:, None] * [0.0, 0.08, 0.04]
    true = robot.track.replace(actual_direction=robot.track.direction, actual_scale=1.0, measured_positions=dense,
                               straightness=bow)
    rng = np.random.default_rng(12)
    q = arm_poses(robot, rng)
    stations = np.arange(0.0, 5601.0, 700.0)
    positions = np.repeat(stations, len(q))
    joints = np.tile(q, (len(stations), 1))
    measured = (true.placements(robot.T_world_base, positions) @ virtual.reached_poses(joints))[:, :3, 3]
    measured += rng.normal(0.0, 0.01, measured.shape)
    model = _CELL_MODEL["kuka_kr6_r900"]
    predicted, _ = model.predict("composite", joints, fk(robot, joints)[:, :3, 3])
    fit = identify_track(robot.track, robot.T_world_base, positions, predicted, measured)
    assert fit.track.straightness is not None and fit.straightness_rms > 3 * fit.noise_rms
    line = fit.track.replace(straightness=None)
    deviation = true.shift(stations) - line.shift(stations)  # the bow beyond the fitted line through 0
    np.testing.assert_allclose(fit.track.straightness, deviation, atol=0.01)
    errors = on_the_real_track(tmp_path, robot, virtual, correct, true, {"line": line, "table": fit.track})
    assert errors["line"].max() > 0.04 and errors["table"].max() < 0.02, errors
    text = resources.files("trajcomp.arm.robots").joinpath("kuka_kr6_r900.yaml").read_text(encoding="utf-8")
    (tmp_path / "kr6_rail.yaml").write_text(text.replace("name: kuka_kr6_r900", "name: kr6_rail") + TRACK)
    on_file = load_robot(str(tmp_path / "kr6_rail.yaml"))
    saved = tmp_path / "model.yaml"
    save_model(saved, dataclasses.replace(model, nominal=on_file.replace(track=fit.track),
                                          robot_ref=str(tmp_path / "kr6_rail.yaml")))
    np.testing.assert_allclose(load_model(saved).nominal.track.straightness, fit.track.straightness, atol=1e-6)


def test_where_the_identified_track_places_the_carriage_is_estimated_within_its_measured_travel():
    """A straight track 0.1 deg off and 0.05 % long, measured at 0, 1400 and 2800 mm (eight poses each, 0.01 mm
    noise; three draws): the carriage's placement error at 400 positions within that travel lies within the
    95 % radius `Track.placement_sigma` gives in 95 % of cases or more; the radius grows away from the measured
    positions and is zero without a calibration."""
    from trajcomp.calibration.track_fit import identify_track

    robot, virtual, _ = cell("kuka_kr6_r900")
    model = _CELL_MODEL["kuka_kr6_r900"]
    turn = Rotation.from_euler("z", 0.1, degrees=True).as_matrix()
    true = robot.track.replace(actual_direction=turn @ robot.track.direction, actual_scale=1.0005)
    covered, radii = [], []
    for seed in range(3):
        rng = np.random.default_rng(seed)
        q = arm_poses(robot, rng)
        positions = np.repeat([0.0, 1400.0, 2800.0], len(q))
        joints = np.tile(q, (3, 1))
        measured = (true.placements(robot.T_world_base, positions) @ virtual.reached_poses(joints))[:, :3, 3]
        measured += rng.normal(0.0, 0.01, measured.shape)
        predicted, _ = model.predict("composite", joints, fk(robot, joints)[:, :3, 3])
        track = identify_track(robot.track, robot.T_world_base, positions, predicted, measured).track
        e = rng.uniform(0.0, 2800.0, 400)
        error = np.linalg.norm(true.shift(e) - track.shift(e), axis=1)
        radius = np.sqrt(7.8147) * track.placement_sigma(e)  # chi-square 95 % of 3 degrees of freedom
        covered.append(error <= radius)
        radii.append(track.placement_sigma(np.array([1400.0, 700.0])))
    assert np.mean(covered) >= 0.95, np.mean(covered, axis=1)
    assert all(mid > at for at, mid in radii)  # midway between two positions more than at one
    assert not robot.track.placement_sigma(np.array([100.0])).any()


def test_a_real_backup_on_a_track_is_recognised_and_compensated_once_its_track_is_described():
    """tests/data/programs/real/rapid/1_T_ROB2.mod (a COMPAS RRC backup: eax_a moves 682-3651 mm with the targets,
    SOURCES.txt). On the IRB 4600 as built in, the refusal names the track; described along x, it is compensated."""
    from tests.programs.test_programs_real import DATA, _unchanged

    program = formats.read(DATA / "programs" / "real" / "rapid" / "1_T_ROB2.mod")
    stated = {str(n): np.eye(4) for n in range(1, 33)}  # the controller's tool and frame tables: not in the files
    with pytest.raises(IKError, match=r"^1_T_ROB2: the program moves external axis E1 over 2969 mm and its targets "
                                      r"move with it, .* describes no track"):
        compensate_program(program, _unchanged, load_robot("abb_irb4600"), tools=stated, frames=stated)
    track = TRACK.replace("[1.0, 0.02, 0.0]", "[1, 0, 0]").replace("position_max: 5800", "position_max: 19000")
    edited, report = compensate_program(program, _unchanged, on_track("abb_irb4600", track), tools=stated,
                                        frames=stated)
    assert len(report.labels) == 10 and not report.warnings


def test_calibrate_with_a_track_column_identifies_the_track_and_compensate_uses_it(tmp_path, monkeypatch, capsys):
    """A measurement file with a ``track`` column: the rows at track position 0 (the grid) calibrate the arm, all
    rows identify the track; the model file keeps the identified track and ``compensate`` places the carriage
    with it, warning of targets beyond the measured travel."""
    from trajcomp.cli import main
    from trajcomp.model.model_file import load_model

    monkeypatch.chdir(tmp_path)
    text = resources.files("trajcomp.arm.robots").joinpath("kuka_kr6_r900.yaml").read_text(encoding="utf-8")
    (tmp_path / "kr6_rail.yaml").write_text(text.replace("name: kuka_kr6_r900", "name: kr6_rail") + TRACK)
    robot = load_robot("kr6_rail.yaml")
    turn = Rotation.from_euler("z", 0.1, degrees=True).as_matrix()
    true = robot.track.replace(actual_direction=turn @ robot.track.direction, actual_scale=1.0005)
    virtual = VirtualRobot.create(robot, "paper", seed=4)
    rng = np.random.default_rng(3)
    corner, side, _ = CELLS["kuka_kr6_r900"]
    plan = plan_grid(robot, corner, side, 50.0, orientation=matrix_to_abc(orientation(robot)))
    grid = plan.joints[plan.reachable]
    poses = grid[rng.choice(len(grid), 8, replace=False)]
    joints = np.concatenate([grid, np.tile(poses, (4, 1))])
    positions = np.concatenate([np.zeros(len(grid)), np.repeat([1500.0, 3000.0, 4500.0, 5000.0], len(poses))])
    measured = (true.placements(robot.T_world_base, positions) @ virtual.reached_poses(joints))[:, :3, 3]
    measured += rng.normal(0.0, 0.01, measured.shape)
    rows = [",".join(f"{v:.6f}" for v in (*np.degrees(q), *m, e)) for q, m, e in zip(joints, measured, positions)]
    (tmp_path / "meas.csv").write_text("j1,j2,j3,j4,j5,j6,mx,my,mz,track\n" + "\n".join(rows) + "\n")
    assert main(["calibrate", "meas.csv", "--robot", "kr6_rail.yaml", "--grid-step", "50", "--folds", "3",
                 "-o", "model.yaml"]) == 0
    assert "track: direction" in capsys.readouterr().err
    identified = load_model("model.yaml").nominal.track
    assert np.degrees(np.arccos(identified.actual_direction @ true.actual_direction)) < 0.002
    assert abs(identified.actual_scale - 1.0005) < 1e-5 and identified.direction @ robot.track.direction > 1 - 1e-12
    np.testing.assert_array_equal(identified.measured_positions, [0, 1500, 3000, 4500, 5000])
    # a program at 0, 1850 and 4200 mm, its world targets where the real track puts the arm
    world, q = world_targets(robot, "kuka_kr6_r900")
    world = true.placements(robot.T_world_base, np.array(CARRIAGE)) @ np.linalg.inv(
        robot.track.placements(robot.T_world_base, np.array(CARRIAGE))) @ world
    _krl(tmp_path, world, q, robot)
    assert main(["compensate", "rail.src", "--model", "model.yaml", "-o", "out.src", "--retime", "none",
                 "--report", "out.html"]) == 0  # between the measured positions: an estimate within 0.1 mm
    residual = next(c for c in json.loads((tmp_path / "out.json").read_text())["verdict"]["criteria"]
                    if c["id"] == "residual")
    assert residual["status"] == "pass", residual
    commands, carriage = _read_krl(tmp_path / "out.src")
    arm_q = ik(robot, np.linalg.inv(robot.track.placements(robot.T_world_base, carriage)) @ commands,
               seed=np.tile(robot.home, (len(commands), 1))).raise_on_failure("commands").q
    landed = (true.placements(robot.T_world_base, carriage) @ virtual.reached_poses(arm_q))[:, :3, 3]
    assert np.linalg.norm(landed - world[:, :3, 3], axis=1).max() < 0.02
    # a target beyond the measured travel is named
    dat = tmp_path / "rail.dat"
    dat.write_text(dat.read_text().replace("E1 4200.0", "E1 5200.0"))
    capsys.readouterr()
    assert main(["compensate", "rail.src", "--model", "model.yaml", "-o", "out2.src", "--retime", "none",
                 "--report", "out2.html"]) == 1  # a finding: its landing is not estimated there
    assert ("1 targets stand at track positions beyond the travel the track's calibration measured (0..5000 mm)"
            in capsys.readouterr().err)
    residual = next(c for c in json.loads((tmp_path / "out2.json").read_text())["verdict"]["criteria"]
                    if c["id"] == "residual")
    assert residual["status"] == "fail" and residual["targets"] == ["XP3 (rail.dat:4)"], residual


CORPUS = Path(__file__).parents[1] / "data" / "programs"  # hand-written track programs: ../data/programs/TRACKS.txt


@pytest.mark.parametrize("name, path", [("kuka_kr6_r900", "krl/KL_RAIL.src"),
                                        ("fanuc_lrmate200id", "fanuc/RAILSEAM.LS"),
                                        ("abb_irb4600", "rapid/IRBT_SEAM.mod")])
def test_the_corpus_track_programs_land_within_0_02_mm(tmp_path, name, path):
    robot, virtual, correct = cell(name)
    read = LANGUAGES[name][1]
    program = formats.read(CORPUS / path)
    world, carriage = read(CORPUS / path)
    assert np.ptp(carriage) > 4000  # the track travels metres with the targets
    edited, report = compensate_program(program, correct, robot, tools={"1": np.eye(4)})
    assert len(report.labels) == 8 and not report.not_compensated
    out = tmp_path / Path(path).name
    formats.write(out, edited)
    commands, written = read(out)
    np.testing.assert_array_equal(written, carriage)
    landed = landing(robot, virtual, commands, written)
    assert np.linalg.norm(landed - world[:, :3, 3], axis=1).max() < 0.02
