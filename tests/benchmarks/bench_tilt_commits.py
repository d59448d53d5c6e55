"""Tilted targets from a single-orientation grid, runnable against any commit's tree (issue 21, item 3).

Run:  python tests/benchmarks/bench_tilt_commits.py
      git worktree add /tmp/old 4d2ab50 && PYTHONPATH=/tmp/old python tests/benchmarks/bench_tilt_commits.py

Virtual UR10, paper profile, seeds 1-3: the paper's large cube (100 mm
grid) measured in one orientation and calibrated (composite, no folds);
40 random targets in the cube per seed, their tool tilted about a random
horizontal axis, either by an angle drawn uniformly within +-15 deg
("within") or by exactly +-15 deg ("at"); compensated in modes dh and
composite and sent to the virtual arm. Printed: true landing |error| mean
/ max per seed (mm) and the mean of the three means. The script uses only
the API both today's tree and older ones have, so the same protocol runs
on both (as the second command shows).
"""

import inspect

import numpy as np

from trajcomp.calibration.calibrate import calibrate
from trajcomp.compensation.target_correction import compensate
from trajcomp.calibration.measurements import Measurements
from trajcomp.calibration.measurement_plan import default_orientation, plan_grid
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot
from trajcomp.arm.transforms import abc_to_matrix, rotvec_to_matrix

COUNT = 40  # targets per seed


def tilted_targets(robot, rng, spread):
    """Poses (COUNT, 4, 4) in the paper's large cube, tilted ``within`` +-15 deg (uniform) or ``at`` +-15 deg."""
    axis = rng.normal(size=(COUNT, 3))
    axis[:, 2] = 0.0
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    angle = rng.uniform(-15.0, 15.0, (COUNT, 1)) if spread == "within" else 15.0 * rng.choice([-1, 1], (COUNT, 1))
    targets = np.tile(np.eye(4), (COUNT, 1, 1))
    targets[:, :3, :3] = rotvec_to_matrix(axis * np.radians(angle)) @ abc_to_matrix(default_orientation(robot))
    targets[:, :3, 3] = np.array([300.0, -100.0, 300.0]) + rng.uniform(0.0, 500.0, (COUNT, 3))
    return targets


def main():
    robot = load_robot("ur10")
    mixed = {"one_posture": False} if "one_posture" in inspect.signature(plan_grid).parameters else {}  # as the demo
    print(f"{'tilt':7s}{'mode':10s}{'seed 1':>16s}{'seed 2':>16s}{'seed 3':>16s}{'mean of means':>15s}   (mm)")
    for spread in ("within", "at"):
        errors = {"dh": [], "composite": []}
        for seed in (1, 2, 3):
            virtual = VirtualRobot.create(robot, "paper", seed)
            rng = np.random.default_rng(seed)
            plan = plan_grid(robot, (300, -100, 300), 500, 100, **mixed)
            q = plan.joints[plan.reachable]
            meas = Measurements(joints=q, position=plan.position[plan.reachable], measured=virtual.measure(q, rng),
                                lines=np.arange(len(q)) + 2)
            model = calibrate(robot, meas, folds=0)
            targets = tilted_targets(robot, rng, spread)
            for mode, found in errors.items():
                landed = virtual.reached_poses(compensate(model, targets, mode=mode).q)[:, :3, 3]
                found.append(np.linalg.norm(landed - targets[:, :3, 3], axis=1))
        for mode, found in errors.items():
            cells = "".join(f"{e.mean():>8.4f}/{e.max():.4f}" for e in found)
            print(f"{spread:7s}{mode:10s}{cells}{np.mean([e.mean() for e in found]):>15.4f}")


if __name__ == "__main__":
    main()
