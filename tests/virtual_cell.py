"""A calibrated virtual UR10, shared by the API and plugin tests (built once per test run, about 0.2 s).

The paper's large cube (corner 300, -100, 300, side 500, step 100: 216
points) measured on a virtual copy of the UR10 with the paper's error
profile, identified as a composite model and saved to a model file.
"""

import dataclasses

import numpy as np

from trajcomp.calibration.calibrate import calibrate
from trajcomp.calibration.measurements import Measurements
from trajcomp.model.model_file import save_model
from trajcomp.calibration.measurement_plan import plan_grid
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot

CORNER, SIDE, STEP = (300.0, -100.0, 300.0), 500.0, 100.0


@dataclasses.dataclass(frozen=True)
class Cell:
    robot: object  # nominal UR10
    virtual: object  # VirtualRobot: where the real arm lands for commanded joints
    model: object  # CompensationModel
    model_path: object  # Path of the saved model


_CELLS = {}


def virtual_cell(tmp_path_factory):
    """The shared `Cell`; its model file lives in a pytest temporary folder."""
    if "ur10" not in _CELLS:
        robot = load_robot("ur10")
        virtual = VirtualRobot.create(robot, "paper", seed=1)
        plan = plan_grid(robot, CORNER, SIDE, STEP, one_posture=False)  # the demo's paper cube, as it plans it
        measured = virtual.measure(plan.joints, np.random.default_rng(11))
        meas = Measurements(joints=plan.joints, position=plan.position, measured=measured,
                            lines=np.arange(len(plan.joints)) + 2, path="ur10-grid.csv")
        model = calibrate(robot, meas, method="composite", grid_step=STEP, folds=3)  # held-out errors: estimates
        path = tmp_path_factory.mktemp("ur10-cell") / "model.yaml"
        save_model(path, model)
        _CELLS["ur10"] = Cell(robot, virtual, model, path)
    return _CELLS["ur10"]


def landing_error(cell, joints_deg, T_target):
    """|reached - target| (N,) mm of the virtual arm's TCP for commanded joints (N, 6) deg."""
    reached = cell.virtual.reached_poses(np.radians(np.reshape(joints_deg, (-1, 6))))[:, :3, 3]
    return np.linalg.norm(reached - np.reshape(T_target, (-1, 4, 4))[:, :3, 3], axis=1)
