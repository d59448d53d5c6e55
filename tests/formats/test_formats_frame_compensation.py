"""A URScript target in a frame variable is compensated as the same target stated in the base frame.

RoboDK writes ``ref_frame = p[...]`` then ``movel(pose_trans(ref_frame,
p[...]))``. The framed program and the program of the base-frame poses
(composed here with scipy from the numbers written) are compensated with
the same model; the framed program's new numbers, composed with its frame,
must be the base program's new numbers.
"""

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from trajcomp import formats
from trajcomp.calibration.calibrate import calibrate
from trajcomp.compensation.target_correction import program_corrector
from trajcomp.calibration.measurements import Measurements
from trajcomp.calibration.measurement_plan import plan_grid
from trajcomp.compensation.program_rewrite import compensate_program
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot

FRAME = [-0.6, -0.1, 0.5, 0.0, 0.0, 0.3]  # m, rotation vector rad
LOCAL = [[0.05, -0.02, 0.1, 3.14159, 0.0, 0.0], [0.1, 0.05, 0.12, 3.0, 0.2, 0.1]]


def compose(frame, pose):
    """p of pose_trans(frame, pose) (metres, rotation vector), by scipy."""
    rf, rp = Rotation.from_rotvec(frame[3:]), Rotation.from_rotvec(pose[3:])
    return [*(np.asarray(frame[:3]) + rf.apply(pose[:3])), *(rf * rp).as_rotvec()]


def literals(path):
    return [[float(v) for v in m.split(",")] for m in re.findall(r"p\[([^\]]*)\]", path.read_text())]


@pytest.fixture(scope="module")
def compensator():
    robot = load_robot("ur10")
    plan = plan_grid(robot, (-800.0, -300.0, 400.0), 400.0, 100.0)
    joints = plan.joints[plan.reachable]
    measured = VirtualRobot.create(robot, "paper", seed=1).measure(joints, np.random.default_rng(3))
    meas = Measurements(joints=joints, position=plan.position[plan.reachable], measured=measured,
                        lines=np.arange(len(joints)) + 2, path="m.csv")
    model = calibrate(robot, meas, robot_ref="ur10", method="composite", grid_step=100.0, folds=0)
    return robot, program_corrector(model)


def test_framed_targets_are_compensated_like_the_same_targets_in_the_base_frame(tmp_path, compensator):
    robot, correct = compensator
    text = lambda p: "p[" + ", ".join(f"{v:.12f}" for v in p) + "]"  # noqa: E731
    framed = tmp_path / "framed.script"
    framed.write_text(f"def framed():\n  ref_frame = {text(FRAME)}\n"
                      f"  movej(pose_trans(ref_frame, {text(LOCAL[0])}))\n"
                      f"  movel(pose_trans(ref_frame, {text(LOCAL[1])}))\nend\n")
    base = tmp_path / "base.script"
    base.write_text(f"def base():\n  movej({text(compose(FRAME, LOCAL[0]))})\n"
                    f"  movel({text(compose(FRAME, LOCAL[1]))})\nend\n")
    results = {}
    for path in (framed, base):
        corrected, report = compensate_program(formats.read(path), correct, robot)
        formats.write(tmp_path / f"out_{path.name}", corrected)
        results[path.name] = literals(tmp_path / f"out_{path.name}")
    frame_after, *local_after = results["framed.script"]
    np.testing.assert_allclose(frame_after, FRAME, atol=1e-12)  # the frame is not touched
    for k, local in enumerate(local_after):
        assert np.linalg.norm(np.subtract(local[:3], LOCAL[k][:3])) > 1e-5  # corrected by more than 0.01 mm
        composed = compose(FRAME, local)
        np.testing.assert_allclose(composed[:3], results["base.script"][k][:3], atol=2e-9)  # 0.002 mm
        np.testing.assert_allclose(Rotation.from_rotvec(composed[3:]).as_matrix(),
                                   Rotation.from_rotvec(results["base.script"][k][3:]).as_matrix(), atol=1e-8)
