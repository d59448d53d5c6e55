"""Filter one pose through a compensation model, as an offline programming tool does.

The tool knows the pose the real TCP must reach and the joints it planned
for it (the posture). trajcomp returns the pose to send to the controller
instead, the joints of that command (same posture) and the correction.

    python examples/01_filter_target.py [model.yaml]

Without a model file, a UR10-class virtual arm is calibrated on the paper's
large cube first (trajcomp.paper_protocol, about a second), and both the planned and
the compensated joints are run on it to show where the TCP really lands.
"""

import sys

import numpy as np

import trajcomp
from trajcomp.paper_protocol import PAPER_CUBES, run_cube
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot


def main(model_path=None):
    virtual = None
    if model_path is None:
        virtual = VirtualRobot.create(load_robot("ur10"), "paper", seed=1)
        model_path = run_cube(virtual, PAPER_CUBES[0]).model
    compensator = trajcomp.Compensator(model_path)  # a model file, or a loaded model

    pose = [550.0, 100.0, 550.0, 90.0, 0.0, 180.0]  # x, y, z mm, A, B, C deg: TCP in the robot base frame
    planned = [27.4, -185.3, 91.2, 4.1, -90.0, 27.4]  # deg: the posture the programming tool chose
    command, joints, correction = compensator.filter_target(pose, joints_hint=planned)

    np.set_printoptions(precision=4, suppress=True)
    print(f"{compensator}")
    print(f"target   x y z a b c : {np.array(pose)}")
    print(f"command  x y z a b c : {command}")
    print(f"joints (deg)         : {joints}")
    print(f"correction dx dy dz (mm), rotation vector (deg): {correction}")

    if virtual is not None:
        _, nominal_joints, _ = trajcomp.Compensator(compensator.model, mode="none").filter_target(
            pose, joints_hint=planned)
        for label, q in (("as planned", nominal_joints), ("compensated", joints)):
            reached = virtual.reached_poses(np.radians(q)[None])[0, :3, 3]
            print(f"{label:12s} the virtual arm lands {np.linalg.norm(reached - pose[:3]):.4f} mm from the target")


if __name__ == "__main__":
    main(*sys.argv[1:2])
