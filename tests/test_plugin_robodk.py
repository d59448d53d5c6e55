"""The RoboDK post processor wrapper in plugins/trajcomp-robodk, driven as RoboDK drives a post.

A stand-in vendor post records every call. References: the virtual UR10 the
model was calibrated on (where the recorded joints really put the TCP),
closed-form nominal IK (the joints RoboDK would plan), and the API's own
answer for the same targets, tool and frame.
"""

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from virtual_cell import landing_error, virtual_cell

import trajcomp
from trajcomp.errors import TrajcompError
from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk

PLUGIN = Path(__file__).resolve().parents[1] / "plugins" / "trajcomp-robodk"
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
    assert calls[1][1] == ("compensated by trajcomp 0.1.0: robot ur10, mode composite", True)
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
