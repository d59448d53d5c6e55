"""The RoboDK post processor wrapper in plugins/trajcomp-robodk, driven as RoboDK drives a post.

The target path (a language trajcomp does not read): a stand-in vendor post
records every call. References: the virtual UR10 the model was calibrated
on (where the recorded joints really put the TCP), closed-form nominal IK
(the joints RoboDK would plan), and the API's own answer for the same
targets, tool and frame.

The program path: real RoboDK vendor posts (tests/data/robodk_posts, as
published) write the program; the reference is the plain vendor post's
program compensated by ``trajcomp compensate`` (the CLI), which the adapter
must match byte for byte, with the same verdict.
"""

import dataclasses
import importlib.util
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from virtual_cell import landing_error, virtual_cell

import trajcomp
from trajcomp.cli import main
from trajcomp.errors import TrajcompError
from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk
from trajcomp.model.model_file import load_model
from trajcomp.formats.fanuc.configuration import encode as fanuc_config
from trajcomp.formats.rapid.configuration import encode as abb_confdata

PLUGIN = Path(__file__).resolve().parents[2] / "plugins" / "trajcomp-robodk"
POSTS = Path(__file__).resolve().parents[1] / "data" / "robodk_posts"
LANDED = 0.03  # mm
MISSED = 0.5  # mm
FRAME = (100.0, 50.0, 0.0, 15.0, 0.0, 0.0)  # the station's reference frame in the robot base: mm, deg
# Targets in that frame (x, y, z mm, A, B, C deg): inside the calibrated cube, the measured orientation
TARGETS = [(450.0, -80.0, 550.0, 75.0, 0.0, 180.0), (500.0, 20.0, 500.0, 75.0, 0.0, 180.0),
           (560.0, 60.0, 480.0, 75.0, 0.0, 180.0), (600.0, 140.0, 520.0, 75.0, 0.0, 180.0)]
CONF = [0, 1, 1]  # RoboDK's flags for these joints, whatever the brand's polarity


class StandInMat:
    """A pose like ``robodk.robomath.Mat``: a 4x4 list of rows, built from rows."""

    def __init__(self, rows):
        self.rows = [list(map(float, row)) for row in rows]


MATS = [StandInMat]
try:  # RoboDK's own Mat, where the robodk package is installed
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PendingDeprecationWarning)  # robodk/__init__ warns about star imports
        from robodk.robomath import Mat
    MATS.append(Mat)
except ImportError:
    pass


class CountingCompensator(trajcomp.Compensator):
    """A Compensator that counts its vectorized calls."""

    calls = 0

    def filter_targets(self, *args, **kwargs):
        self.calls += 1
        return super().filter_targets(*args, **kwargs)


class VendorPost:
    """A stand-in vendor RobotPost: every method records its name and arguments."""

    def __init__(self, robotpost=None, robotname=None, robot_axes=6, **kwargs):
        self.calls = []
        self.PROG = ""

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return lambda *args: self.calls.append((name, args))


@pytest.fixture(scope="module")
def robodk_plugin():
    sys.path.insert(0, str(PLUGIN))
    import trajcomp_robodk

    yield trajcomp_robodk
    sys.path.remove(str(PLUGIN))


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    return virtual_cell(tmp_path_factory)


def matrix(xyzabc):
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("ZYX", xyzabc[3:], degrees=True).as_matrix()
    T[:3, 3] = xyzabc[:3]
    return T


def planned_joints(cell):
    """The joints RoboDK plans for TARGETS (deg): nominal IK in the calibrated posture, as lists."""
    T = matrix(FRAME) @ np.array([matrix(t) for t in TARGETS])
    return [list(q) for q in np.degrees(ik(cell.robot, T, seed=np.radians([27, -185, 91, 4, -90, 27])).q)]


@pytest.fixture(scope="module", params=MATS, ids=lambda m: m.__module__ + "." + m.__name__)
def generated(request, robodk_plugin, cell):
    """A program generated through the wrapper as RoboDK would, and the vendor's record of it."""
    Mat = request.param
    counting = CountingCompensator(cell.model_path)
    RobotPost = robodk_plugin.compensated_post(VendorPost, model=counting)
    post = RobotPost("KUKA_KRC4_trajcomp", "UR10", 6, lines_x_prog=5000)
    pose = [Mat(matrix(t).tolist()) for t in TARGETS]
    joints = planned_joints(cell)
    home = [0.0, -90.0, 90.0, -90.0, -90.0, 0.0]
    post.ProgStart("weld")
    post.setFrame(Mat(matrix(FRAME).tolist()), 1, "Frame 1")
    post.setTool(Mat(np.eye(4).tolist()), 1, "Flange")
    post.setSpeed(100.0)
    post.MoveJ(None, home)
    post.MoveJ(pose[0], joints[0], CONF)
    post.MoveL(pose[1], joints[1], CONF)
    post.MoveC(pose[2], joints[2], pose[3], joints[3], CONF, tuple(CONF))
    post.ProgFinish("weld")
    post.ProgSave("/tmp/robodk", "weld")
    return {"post": post, "calls": post.vendor.calls, "Mat": Mat, "joints": joints, "home": home,
            "batches": counting.calls}


def moves(calls):
    """``[(pose (4, 4), joints (6,), conf)]`` of the vendor's recorded Move calls with a pose, in order."""
    out = []
    for name, args in calls:
        if name in ("MoveJ", "MoveL") and args[0] is not None:
            out.append((args[0], args[1], args[2]))
        elif name == "MoveC":
            out += [(args[0], args[1], args[4]), (args[2], args[3], args[5])]
    return out


def test_the_vendor_post_writes_commands_that_land(generated, cell):
    recorded = moves(generated["calls"])
    T_target = matrix(FRAME) @ np.array([matrix(t) for t in TARGETS])
    joints = np.array([j for _, j, _ in recorded])
    assert landing_error(cell, joints, T_target).max() < LANDED
    assert landing_error(cell, generated["joints"], T_target).min() > MISSED
    # each pose written is the nominal pose of the joints written, in the station's frame
    T_written = matrix(FRAME) @ np.array([pose.rows for pose, _, _ in recorded])
    np.testing.assert_allclose(fk(cell.robot, np.radians(joints)), T_written, atol=1e-6)


def test_the_same_as_the_api_with_the_stations_tool_and_frame(generated, cell):
    recorded = moves(generated["calls"])
    expected = trajcomp.Compensator(cell.model_path).filter_targets(
        [matrix(t) for t in TARGETS], tool=np.eye(4), frame=FRAME, joints_hint=generated["joints"])
    for k, (pose, joints, conf) in enumerate(recorded):
        np.testing.assert_allclose(np.array(pose.rows), expected.poses[k], atol=1e-12)
        np.testing.assert_allclose(joints, expected.joints[k], atol=1e-12)


def test_types_and_everything_else_pass_through(generated):
    calls, Mat = generated["calls"], generated["Mat"]
    names = [name for name, _ in calls]
    assert names == ["ProgStart", "RunMessage", "setFrame", "setTool", "setSpeed", "MoveJ", "MoveJ", "MoveL",
                     "MoveC", "RunMessage", "ProgFinish", "ProgSave"]
    assert calls[0] == ("ProgStart", ("weld",)) and calls[4] == ("setSpeed", (100.0,))
    assert calls[2][1][1:] == (1, "Frame 1") and calls[-1] == ("ProgSave", ("/tmp/robodk", "weld"))
    assert calls[5] == ("MoveJ", (None, generated["home"], None))  # a joint move: as RoboDK gave it
    assert calls[1][1] == ("compensated pose by pose by trajcomp 0.1.0: robot ur10, mode composite; trajcomp does "
                           "not read this post's programs, so this one is not re-timed and has no verdict", True)
    assert calls[-3][1][0].startswith("trajcomp: 4 poses compensated, largest correction ")
    for pose, joints, conf in moves(calls):
        assert type(pose) is Mat and isinstance(joints, list) and len(joints) == 6
    assert [conf for _, _, conf in moves(calls)] == [CONF, CONF, CONF, tuple(CONF)]  # same posture, same flags
    assert generated["batches"] == 1  # the path's three moves (four poses) in one vectorized call
    post = generated["post"]
    post.PROG = "written"
    assert post.vendor.PROG == "written" and post.PROG == "written"


def test_a_station_that_is_not_the_calibrated_cell_is_refused(robodk_plugin, cell):
    RobotPost = robodk_plugin.compensated_post(VendorPost, model=cell.model_path)
    post = RobotPost("post", "UR10", 6)
    joints = planned_joints(cell)
    post.setFrame(StandInMat(matrix(FRAME).tolist()))
    post.setTool(StandInMat(matrix((0, 0, 5.0, 0, 0, 0)).tolist()))  # RoboDK's tool is 5 mm longer
    with pytest.raises(TrajcompError, match=r"MoveL #1: .* 5.000 mm .* not the calibrated one"):
        post.MoveL(StandInMat(matrix(TARGETS[0]).tolist()), joints[0], CONF)
    with pytest.raises(TrajcompError, match="MoveL #1: RoboDK gave a pose without joints"):
        post.MoveL(StandInMat(matrix(TARGETS[0]).tolist()), None, CONF)
    with pytest.raises(TrajcompError, match="7 axes"):
        RobotPost("post", "UR10 on a track", 7)
    assert [name for name, _ in post.vendor.calls] == ["setFrame", "setTool"]  # no move was written


def test_an_error_in_a_batch_names_the_move(robodk_plugin, cell):
    strict = trajcomp.Compensator(cell.model_path, max_correction=0.1)
    post = robodk_plugin.compensated_post(VendorPost, model=strict)("post", "UR10", 6)
    post.setFrame(StandInMat(matrix(FRAME).tolist()))
    joints = planned_joints(cell)
    post.MoveJ(StandInMat(matrix(TARGETS[0]).tolist()), joints[0], CONF)
    post.MoveC(StandInMat(matrix(TARGETS[2]).tolist()), joints[2], StandInMat(matrix(TARGETS[3]).tolist()),
               joints[3], CONF, CONF)
    with pytest.raises(TrajcompError, match=r"exceed 0.1 mm.*MoveJ #1 .*MoveC #2 via .*MoveC #2 end"):
        post.ProgFinish("weld")


def test_flags_follow_a_joint_across_its_boundary(robodk_plugin, cell):
    before = np.array([27.0, -185.0, 91.0, 4.0, 0.2, 27.0])  # J5 just positive: the wrist flag's boundary
    after = before * [1, 1, 1, 1, -1, 1]
    assert robodk_plugin.conf_after(cell.robot, [1, 0, 1], before, after) == [1, 0, 0]
    assert robodk_plugin.conf_after(cell.robot, (1, 0, 0), after, before) == (1, 0, 1)
    assert robodk_plugin.conf_after(cell.robot, [1, 0, 1], before, before + 0.1) == [1, 0, 1]
    assert robodk_plugin.conf_after(cell.robot, None, before, after) is None


# ------------------------------------------------------- the program path: real vendor posts

CIRCLE = [(470.0, 20.0, 720.0), (510.0, 40.0, 740.0), (540.0, 70.0, 730.0), (560.0, 30.0, 760.0),
          (500.0, 90.0, 700.0)]  # KR6 targets in its base, mm: inside the kuka_model cube (400, -50, 650) + 200
FANUC_PATH = [(420.0, 20.0, 420.0), (400.0, -20.0, 440.0), (450.0, 40.0, 400.0), (380.0, 60.0, 430.0),
              (430.0, -40.0, 410.0)]  # LR Mate targets in its base, mm: inside the FANUC model's cube
FANUC_FRAME = (20.0, -10.0, 0.0, 10.0, 0.0, 0.0)  # its user frame 1 in the base: mm, deg
ABB_PATH = [(1120.0, -180.0, 820.0), (1080.0, -200.0, 860.0), (1150.0, -120.0, 840.0), (1180.0, -200.0, 800.0),
            (1100.0, -100.0, 880.0)]  # IRB 4600 targets in its base, mm: inside the abb_model cube


@dataclasses.dataclass(frozen=True)
class Station:
    """A RoboDK station: the vendor post of its robot, the model, the reference frame and the planned moves."""

    post: str  # the vendor post's module in tests/data/robodk_posts
    model: Path
    robot: object  # the model's nominal robot, with its calibrated TCP
    frame: np.ndarray  # T_base_frame (4, 4), mm
    targets: np.ndarray  # T_frame_tool (5, 4, 4), mm
    joints: np.ndarray  # (5, 6) deg, the joints RoboDK plans: nominal IK in one posture
    flags: list  # [REAR, LOWERARM, FLIP] of each target's joints
    speed: float  # mm/s of setSpeed, or None: the post's default
    circle: bool  # the third and fourth targets as a MoveC (else two MoveL)


def flags_of(robot, q, post):
    """RoboDK's ``[REAR, LOWERARM, FLIP]`` of joints q (N, 6) rad, in the polarity the vendor ``post`` reads.

    The FANUC post writes FLIP as 'F' (J5 >= 0), LOWERARM as 'D', REAR as 'B' (`trajcomp.formats.configuration.
    fanuc_config`); the ABB post writes cfx = 4 REAR + 2 LOWERARM + FLIP (`abb_confdata`); the others ignore them.
    """
    if post == "Fanuc_R30iA":
        return [[int(front == "B"), int(elbow == "D"), int(flip == "F")] for flip, elbow, front, *_ in
                fanuc_config(robot, q)]
    return [[(cfx >> shift) & 1 for shift in (2, 1, 0)] for *_, cfx in abb_confdata(robot, q)]


def station(post, model_path, frame, T_base, seed_deg, speed=None, circle=True):
    """A `Station` planning targets ``T_base`` (N, 4, 4) mm in the posture nearest ``seed_deg``, with RoboDK's flags."""
    robot = load_model(model_path).nominal
    q = ik(robot, T_base, seed=np.radians(seed_deg)).q
    return Station(post, model_path, robot, frame, np.linalg.inv(frame) @ T_base, np.degrees(q),
                   flags_of(robot, q, post), speed, circle)


def small_model(folder, robot, corner):
    """A model of the virtual ``robot`` on a cube at ``corner`` (side 240, step 120: 27 points, folds 0: about 1 s)."""
    plan, meas, model = folder / "plan.csv", folder / "meas.csv", folder / f"{robot}.yaml"
    assert main(["plan", "--robot", robot, "--cube", corner, "--side", "240", "--step", "120", "-o", str(plan)]) == 0
    assert main(["simulate", str(plan), "--robot", robot, "--seed", "1", "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", robot, "--grid-step", "120", "--folds", "0", "-o", str(model)]) == 0
    return model


@pytest.fixture(scope="module")
def stations(cell, kuka_model, tmp_path_factory):
    pytest.importorskip("robodk")
    abb_model = small_model(tmp_path_factory.mktemp("abb"), "abb_irb4600", "1000,-300,700")
    fanuc_model = small_model(tmp_path_factory.mktemp("fanuc"), "fanuc_lrmate200id", "320,-100,300")
    lrmate = np.array([matrix((*p, 0.0, 180.0, 0.0)) for p in FANUC_PATH])
    irb = np.array([matrix((*p, -180.0, 0.0, 180.0)) for p in ABB_PATH])
    ur10 = matrix(FRAME) @ np.array([matrix(t) for t in TARGETS + [(520.0, -40.0, 530.0, 75.0, 0.0, 180.0)]])
    kr6 = np.array([matrix((*p, 0.0, 90.0, 0.0)) for p in CIRCLE])
    return {"krl": station("KUKA_KRC4", kuka_model, matrix((30.0, -20.0, 0.0, 10.0, 0.0, 0.0)),
                           matrix((-30.0, 20.0, 0.0, 0.0, 0.0, 0.0)) @ kr6, [0, -90, 90, 0, 90, 0], 100.0),
            # without setSpeed: this post then assigns its speed variable once, a speed trajcomp can re-time
            "urscript": station("Universal_Robots_SCRIPT", cell.model_path, matrix(FRAME), ur10,
                                [27, -185, 91, 4, -90, 27]),
            "rapid": station("ABB_RAPID_IRC5", abb_model, matrix((50.0, 20.0, 0.0, 5.0, 0.0, 0.0)), irb,
                             [-16, 4, 40, 0, 45, -16], 150.0),
            # the post writes UFRAME_NUM=1 and UTOOL_NUM=1 (RoboDK's numbers), values kept by the controller;
            # it writes a circle on two lines without the pendant's ':' (refused): no MoveC
            "fanuc_ls": station("Fanuc_R30iA", fanuc_model, matrix(FANUC_FRAME), lrmate, [0, 0, 0, 0, -90, 0],
                                100.0, circle=False)}


def vendor_post(name):
    """The vendor post ``name``'s RobotPost, imported afresh: RoboDK runs each post in a new interpreter, and
    these keep a program's lines in class attributes."""
    spec = importlib.util.spec_from_file_location(name, POSTS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PendingDeprecationWarning)  # from robodk import *
        warnings.simplefilter("ignore", DeprecationWarning)  # '\M' in a string of the ABB post, as published
        spec.loader.exec_module(module)
    return module.RobotPost


def write_program(RobotPost, station, folder, tool=None, show_result=False):
    """Generate 'weld' through ``RobotPost`` as RoboDK does; the post and the program file it saved."""
    from robodk.robomath import Mat

    post = RobotPost(station.post, station.robot.name, 6)
    pose = [Mat(T.tolist()) for T in station.targets]
    joints = [list(q) for q in station.joints]
    post.ProgStart("weld")
    post.RunMessage("Program generated by RoboDK", True)
    post.setFrame(Mat(station.frame.tolist()), 1, "Frame 1")
    post.setTool(Mat((station.robot.T_flange_tool if tool is None else tool).tolist()), 1, "Tool 1")
    if station.speed is not None:
        post.setSpeed(station.speed)
    flags = station.flags
    post.MoveJ(pose[0], joints[0], flags[0])
    post.MoveL(pose[1], joints[1], flags[1])
    if station.circle:
        post.MoveC(pose[2], joints[2], pose[3], joints[3], flags[2], flags[3])
    else:
        post.MoveL(pose[2], joints[2], flags[2])
        post.MoveL(pose[3], joints[3], flags[3])
    post.MoveL(pose[4], joints[4], flags[4])
    post.ProgFinish("weld")
    post.ProgSave(str(folder), "weld", False, show_result)
    return post, folder / f"weld.{post.PROG_EXT}"


def verdict(folder, program):
    """The verdict of the report beside ``program``, its folder's name replaced."""
    return json.loads(Path(f"{program}.json").read_text().replace(str(folder), "<folder>"))["verdict"]


@pytest.mark.parametrize("language", ["krl", "rapid", "fanuc_ls", "urscript"])
def test_the_adapter_writes_the_program_and_verdict_of_the_cli(language, stations, robodk_plugin, tmp_path, capsys):
    s = stations[language]
    adapter, plain = tmp_path / "adapter", tmp_path / "plain"
    adapter.mkdir(), plain.mkdir()
    named = {}
    if language == "fanuc_ls":  # the values of the tool and frame numbers the program uses but does not define
        tool = s.robot.T_flange_tool
        named = {"tools": {"1": [*tool[:3, 3], *Rotation.from_matrix(tool[:3, :3]).as_euler("ZYX", degrees=True)]},
                 "frames": {"1": list(FANUC_FRAME)}}
    options = [f"--{kind[:-1]}=1={','.join(map(repr, map(float, value['1'])))}" for kind, value in named.items()]
    RobotPost = robodk_plugin.compensated_post(vendor_post(s.post), model=s.model, json_only=True, **named)
    assert issubclass(RobotPost, robodk_plugin.ProgramPost)
    post, written = write_program(RobotPost, s, adapter)
    _, reference = write_program(vendor_post(s.post), s, plain)
    planned = reference.read_bytes()
    code = main(["compensate", str(reference), "--model", str(s.model), "--joint-targets", "compensate",
                 "--in-place", "-o", str(reference), "--report", str(reference), "--json-only", *options])
    assert written.read_bytes() == reference.read_bytes() != planned
    [run] = post.runs
    assert code in (0, 1) and run.passed == (code == 0)
    assert verdict(adapter, written) == verdict(plain, reference) == json.loads(json.dumps(
        run.compliance.doc["verdict"]).replace(str(adapter), "<folder>"))
    assert sorted(p.name for p in adapter.iterdir()) == sorted(p.name for p in plain.iterdir())
    shown = capsys.readouterr().out  # RoboDK shows what a post prints, and its LOG
    assert f"SAVED: {written}\n" in shown
    for line in (f"\nverdict: {'PASS' if code == 0 else 'FAIL'}, tolerance 0.1 mm", f"\nwrote {written}, "):
        assert line in shown and line in "\n" + post.LOG


def test_a_refused_program_is_moved_aside_not_left_under_its_name(stations, robodk_plugin, tmp_path):
    s = stations["krl"]
    RobotPost = robodk_plugin.compensated_post(vendor_post(s.post), model=s.model, max_correction=0.1)
    with pytest.raises(TrajcompError, match=r"0\.1 mm.*kept as .*weld\.src\.uncompensated, not compensated"):
        write_program(RobotPost, s, tmp_path)
    assert [p.name for p in tmp_path.iterdir()] == ["weld.src.uncompensated"]


def test_the_program_path_keeps_the_station_check(stations, robodk_plugin, tmp_path):
    s = stations["urscript"]
    RobotPost = robodk_plugin.compensated_post(vendor_post(s.post), model=s.model)
    with pytest.raises(TrajcompError, match=r"MoveJ #1: .* 5.000 mm .* not the calibrated one"):
        write_program(RobotPost, s, tmp_path, tool=s.robot.T_flange_tool @ matrix((0, 0, 5.0, 0, 0, 0)))
    assert list(tmp_path.iterdir()) == []


def test_a_language_trajcomp_does_not_read_takes_the_target_path(robodk_plugin, cell):
    motoman = type("RobotPost", (VendorPost,), {"PROG_EXT": "JBI"})
    post = robodk_plugin.compensated_post(motoman, model=cell.model_path)("Motoman", "UR10", 6)
    assert isinstance(post, robodk_plugin.TargetPost)
    post.ProgStart("weld")
    assert "trajcomp does not read .JBI's programs, so this one is not re-timed" in post.vendor.calls[1][1][0]


def test_the_program_shown_is_the_compensated_one(stations, robodk_plugin, tmp_path):
    s = stations["urscript"]
    RobotPost = robodk_plugin.compensated_post(vendor_post(s.post), model=s.model, json_only=True)
    shown = tmp_path / "shown"  # RoboDK's show_result: an editor given the program's path (not waited for)
    editor = [sys.executable, "-c", f"import os, shutil, sys; shutil.copy(sys.argv[1], {str(shown)!r} + '.part'); "
                                    f"os.replace({str(shown)!r} + '.part', {str(shown)!r})"]
    folder = tmp_path / "programs"
    folder.mkdir()
    post, written = write_program(RobotPost, s, folder, show_result=editor)
    for _ in range(300):
        if shown.exists():
            break
        time.sleep(0.1)
    assert shown.read_bytes() == written.read_bytes() and post.runs[0].passed
