"""Orientation sets for planning, their spread, and how many of them the identification needs."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from trajcomp.arm.kinematics import fk
from trajcomp.calibration.orientations import axis_offset, orientation_spread, spread_orientations
from trajcomp.calibration.measurement_plan import default_orientation, orientations_needed, plan_grid
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import pose_to_matrix


def test_spread_orientations_tilt_the_tool_about_its_own_x_and_y_axes():
    start = np.radians([90.0, 0.0, 180.0])
    tilted = spread_orientations(start, 5, np.radians(30.0))
    base = Rotation.from_euler("ZYX", start)
    turns = [(base.inv() * Rotation.from_euler("ZYX", abc)).as_rotvec(degrees=True) for abc in tilted]
    np.testing.assert_allclose(turns, [[0, 0, 0], [30, 0, 0], [0, 30, 0], [-30, 0, 0], [0, -30, 0]], atol=1e-9)
    three = spread_orientations(start, 7, np.radians(20.0))[1:4]
    axes = [(base.inv() * Rotation.from_euler("ZYX", abc)).as_rotvec(degrees=True) for abc in three]
    np.testing.assert_allclose(np.degrees(np.arctan2([a[1] for a in axes], [a[0] for a in axes])), [0, 60, 120], atol=1e-9)


def test_orientation_spread_is_the_rms_turn_about_the_principal_axes():
    start = Rotation.from_euler("ZYX", [0.3, -0.2, 0.1])
    about_x = start * Rotation.from_rotvec(np.radians([[10, 0, 0], [-10, 0, 0]]))
    np.testing.assert_allclose(orientation_spread(about_x.as_matrix()), [10, 0, 0], atol=1e-9)
    np.testing.assert_allclose(orientation_spread(start.as_matrix()[None]), [0, 0, 0], atol=1e-9)
    four = start * Rotation.from_rotvec(np.radians([[12, 0, 0], [-12, 0, 0], [0, 6, 0], [0, -6, 0]]))
    np.testing.assert_allclose(orientation_spread(four.as_matrix()), [12 / np.sqrt(2), 6 / np.sqrt(2), 0], atol=1e-9)


def test_axis_offset_is_the_distance_of_the_tcp_from_the_last_axis():
    ur10 = load_robot("ur10")  # UR flange z is the joint-6 axis
    assert axis_offset(ur10.replace(T_flange_tool=pose_to_matrix([30, -40, 150, 0.2, 0, 0]))) == pytest.approx(50.0)
    assert axis_offset(ur10.replace(T_flange_tool=pose_to_matrix([0, 0, 150, 0.2, 0, 0]))) == pytest.approx(0.0, abs=1e-9)


def test_a_plan_at_several_orientations_measures_each_node_at_each_orientation_and_says_what_it_needs():
    robot = load_robot("ur10")
    orientations = spread_orientations(default_orientation(robot), 5, np.radians(30.0))
    plan = plan_grid(robot, (400, 0, 400), 200, 200, orientations)
    assert plan.reachable.all() and len(plan.position) == 8 * 5
    np.testing.assert_allclose(plan.position[:5], np.tile([400, 0, 400], (5, 1)))
    np.testing.assert_allclose(plan.orientation[:5], orientations)
    reached = Rotation.from_matrix(fk(robot, plan.joints)[:, :3, :3])
    assert (reached.inv() * Rotation.from_euler("ZYX", plan.orientation)).magnitude().max() < 1e-9
    counts, candidates = orientations_needed(robot, plan)
    kept = [k for _, k in counts]
    assert kept[0] < kept[-1] <= candidates and kept == sorted(kept)  # one orientation identifies less


def test_the_default_plan_spreads_five_orientations_and_leaves_out_only_tilted_targets_out_of_reach(tmp_path, capsys):
    """`plan`'s default is five orientations; a tilted target the arm cannot reach is listed and left out (exit 0),
    where the same five asked for explicitly, or an untilted target out of reach, exit 1."""
    from trajcomp.calibration.measurements import read_measurements
    from trajcomp.cli import main

    grid = ["--robot", "kuka_kr6_r900", "--cube", "400,-50,650", "--side", "200", "--step", "50"]
    assert main(["plan", *grid, "-o", str(tmp_path / "auto.csv")]) == 0
    err = capsys.readouterr().err
    plan = read_measurements(tmp_path / "auto.csv")
    robot = load_robot("kuka_kr6_r900")
    spread = np.degrees(spread_orientations(default_orientation(robot), 5, np.radians(30.0)))
    distinct = np.unique(np.round(plan.orientation, 6), axis=0)
    assert len(distinct) == 5 and np.allclose(np.sort(distinct, axis=0), np.sort(np.radians(spread), axis=0), atol=1e-6)
    text = (tmp_path / "auto.csv").read_text()
    left = text.count("(a tilted target of the default plan: left out)")
    assert left > 0 and len(plan) == 125 * 5 - left  # every node at its home orientation, the reachable tilts
    assert f"{left} tilted targets the arm cannot reach are left out" in err
    assert main(["plan", *grid, "--orientations", "5", "-o", str(tmp_path / "five.csv")]) == 1
    assert f"{left} of 625 targets are unreachable" in capsys.readouterr().err
    assert main(["plan", *grid, "--orientations", "1", "-o", str(tmp_path / "one.csv")]) == 0
    assert len(read_measurements(tmp_path / "one.csv")) == 125


def test_the_default_flow_lands_tilted_targets_within_45_micrometres(tmp_path):
    """The README's plan -> simulate -> calibrate on the harsh profile's virtual arm, then targets inside the cube
    tilted up to 15 deg compensated: the arm lands them within 0.045 mm on average (0.0045; from a plan at one
    orientation 0.089), and untilted ones within 0.010 mm (0.0045; from one orientation 0.019)."""
    from trajcomp.calibration.virtual_arm import VirtualRobot
    from trajcomp.cli import main
    from trajcomp.compensation.target_correction import compensate
    from trajcomp.model.model_file import load_model
    from trajcomp.arm.transforms import abc_to_matrix, rotvec_to_matrix

    plan, meas, model = tmp_path / "plan.csv", tmp_path / "meas.csv", tmp_path / "model.yaml"
    assert main(["plan", "--robot", "ur10", "--cube", "300,-100,300", "--side", "400", "--step", "100",
                 "-o", str(plan)]) == 0
    assert main(["simulate", str(plan), "--robot", "ur10", "--profile", "harsh", "--seed", "1", "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", "ur10", "--grid-step", "100", "--folds", "2",
                 "-o", str(model)]) == 0
    robot, rng = load_robot("ur10"), np.random.default_rng(5)
    count = 60
    turn = rng.uniform(0.0, 2.0 * np.pi, count)
    tilt = np.radians(rng.uniform(0.0, 15.0, count))[:, None] * np.column_stack([np.cos(turn), np.sin(turn),
                                                                                   np.zeros(count)])
    targets = np.tile(np.eye(4), (2, count, 1, 1))
    targets[..., :3, 3] = np.array([300.0, -100.0, 300.0]) + rng.uniform(0.0, 400.0, (count, 3))
    targets[0, :, :3, :3] = rotvec_to_matrix(tilt) @ abc_to_matrix(default_orientation(robot))
    targets[1, :, :3, :3] = abc_to_matrix(default_orientation(robot))
    arm = VirtualRobot.create(robot, "harsh", 1)  # the arm `simulate --seed 1` measured
    compensated = load_model(model)
    landed = [np.linalg.norm(arm.reached_poses(compensate(compensated, t).q)[:, :3, 3] - t[:, :3, 3], axis=1)
              for t in targets]
    assert landed[0].mean() <= 0.045
    assert landed[1].mean() <= 0.010
