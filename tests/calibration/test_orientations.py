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
