"""Kinematic identification recovers the virtual robot's planted errors, TCP and tracker registration."""

import numpy as np
import pytest

from trajcomp.model import joint_errors
from trajcomp.errors import CalibrationError
from trajcomp.calibration.identify import _Problem, best_fit_transform, identify, outlier_rows
from trajcomp.arm.kinematics import fk
from trajcomp.arm.parameters import apply_deltas, candidate_parameters, scales
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import ErrorProfile, VirtualRobot
from trajcomp.arm.transforms import matrix_to_rotvec, pose_to_matrix, rotvec_to_matrix

GEOMETRIC = ErrorProfile("geometric", length_sigma=0.5, angle_sigma=np.radians(0.05), tool_sigma=0.2)


def random_joints(n, seed):
    return np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, 6))


@pytest.mark.parametrize("name", ["ur10", "kuka_kr6_r900", "abb_irb4600", "fanuc_lrmate200id"])
def test_recovers_geometric_errors_everywhere(name):
    nominal = load_robot(name)
    virtual = VirtualRobot.create(nominal, GEOMETRIC, seed=4)
    q = random_joints(300, 1)
    fit = identify(nominal, q, fk(virtual.true_robot, q)[:, :3, 3])
    fresh = random_joints(500, 2)
    error = np.linalg.norm(fk(fit.robot, fresh)[:, :3, 3] - fk(virtual.true_robot, fresh)[:, :3, 3], axis=1)
    # noise-free data: only the weakly observed parameters left at nominal remain (~µm)
    assert error.max() < 0.01


@pytest.mark.parametrize("name", ["ur10", "kuka_kr6_r900", "fanuc_lrmate200id"])
def test_analytic_jacobian_matches_finite_differences(name):
    """Every kind of parameter: DH (Hayati beta, coupled joint map), tool, target, registration, joint terms, splines.

    Spline columns are never stored densely: the normal equations assembled
    from their sparse basis must equal those of the finite-difference Jacobian.
    """
    robot = VirtualRobot.create(load_robot(name).replace(T_flange_tool=pose_to_matrix([10, -20, 150, 0.3, 0.2, 0.1])),
                                "harsh", 3).true_robot.replace(beta=np.array([0, 1e-3, -2e-3, 0, 0, 0]))
    q = random_joints(7, 0)
    basis = joint_errors.SplineBasis(q.min(axis=0), q.max(axis=0), np.radians([40, 0, 60, 0, 0, 90]))
    names = (candidate_parameters(robot, orientation=True, tracker=True) + joint_errors.term_names()
             + basis.names())
    T_tracker_base = pose_to_matrix([1000, 200, -300, 0.5, -0.2, 2.0])
    R_tcp_target = rotvec_to_matrix([0.2, -1.0, 0.4])
    seen = T_tracker_base @ fk(robot, q)
    problem = _Problem(robot, load_robot(name), q, seen[:, :3, 3], seen[:, :3, :3] @ R_tcp_target,
                       T_tracker_base, R_tcp_target, 100.0, basis)
    problem.setup(names)
    start = np.zeros(len(names))
    residual, jac = problem.evaluate(start)
    difference = np.empty(residual.shape + (len(names),))
    for k in range(len(names)):
        step = np.zeros(len(names))
        step[k] = 1e-6
        difference[:, :, k] = (problem.evaluate(start + step, False)[0] - problem.evaluate(start - step, False)[0]) / 2e-6
    weights = np.linspace(0.5, 1.0, len(q))
    scale = scales(names)
    a = (difference * scale).reshape(-1, len(names))
    w = np.repeat(weights, residual.shape[1])
    normal, gradient = jac.normal_equations(residual, weights, scale)
    expected = a.T @ (w[:, None] * a)
    np.testing.assert_allclose(normal, expected, atol=1e-6 * np.abs(expected).max())
    np.testing.assert_allclose(gradient, a.T @ (w * residual.ravel()), atol=1e-6 * np.abs(gradient).max())
    assert sum(joint_errors.is_spline(n) for n in names) == len(basis.names()) > 10


def test_recovers_a_planted_tcp_and_tracker_registration():
    """Tracker-frame 6-DoF data of an arm with DH, TCP and target-mounting errors."""
    nominal = load_robot("ur10").replace(T_flange_tool=pose_to_matrix([0, 0, 150, 0, 0, 0]))
    true = VirtualRobot.create(nominal, GEOMETRIC, seed=5).true_robot
    T_tracker_base = pose_to_matrix([2400.0, -1300.0, 120.0, 0.4, -0.05, 2.9])
    R_tcp_target = rotvec_to_matrix([0.0, 0.0, np.pi / 2 + 0.01])  # probe mounted a quarter turn about the tool axis
    q = random_joints(200, 6)
    seen = T_tracker_base @ fk(true, q)
    fit = identify(nominal, q, seen[:, :3, 3], rotation=seen[:, :3, :3] @ R_tcp_target, frame="tracker")
    np.testing.assert_allclose(fit.robot.T_flange_tool[:3, 3], true.T_flange_tool[:3, 3], atol=1e-3)
    assert np.linalg.norm(true.T_flange_tool[:3, 3] - nominal.T_flange_tool[:3, 3]) > 0.1  # there was an error to find
    # the zero of joint 6 and the tool's mounting turn the TCP frame: they show as a turn of the probe's mounting
    turn = matrix_to_rotvec(fit.R_tcp_target @ R_tcp_target.T)
    assert 0 < np.linalg.norm(turn) < np.radians(0.1)
    # base z and the turn about base z trade with d1 and theta1: the rest of the registration is the truth
    np.testing.assert_allclose(fit.T_tracker_base[:3, 2], T_tracker_base[:3, 2], atol=1e-7)
    fresh = random_joints(300, 7)
    predicted = fit.T_tracker_base @ fk(fit.robot, fresh)
    expected = T_tracker_base @ fk(true, fresh)
    assert np.abs(predicted[:, :3, 3] - expected[:, :3, 3]).max() < 1e-3
    seen_frames = (predicted[:, :3, :3] @ fit.R_tcp_target) @ np.swapaxes(expected[:, :3, :3] @ R_tcp_target, 1, 2)
    assert np.abs(matrix_to_rotvec(seen_frames)).max() < 1e-8


def test_joint_terms_capture_the_virtual_robots_compliance_and_gear_errors():
    """The virtual robot computes its own gravity torques and gear errors; the terms must span them."""
    nominal = load_robot("ur10")
    virtual = VirtualRobot.create(nominal, "paper", seed=2)
    q = random_joints(400, 8)
    measured = fk(virtual.true_robot, virtual.reached_joints(q))[:, :3, 3]
    geometric = identify(nominal, q, measured)
    fit = identify(nominal, q, measured, joint_terms=True)
    fresh = random_joints(300, 9)
    truth = fk(virtual.true_robot, virtual.reached_joints(fresh))[:, :3, 3]
    error = np.linalg.norm(fk(fit.robot, fit.joint_errors.reached(nominal, fresh))[:, :3, 3] - truth, axis=1)
    error_geometric = np.linalg.norm(fk(geometric.robot, fresh)[:, :3, 3] - truth, axis=1)
    assert error_geometric.mean() > 0.02  # the DH table alone cannot hold them
    assert error.max() < 2e-3


def test_commanded_joints_invert_the_joint_errors():
    nominal = load_robot("kuka_kr6_r900")
    names = joint_errors.term_names()
    residual = joint_errors.JointResidual(names, np.random.default_rng(1).normal(0, 1e-3, len(names)))
    q = random_joints(50, 3)
    np.testing.assert_allclose(residual.reached(nominal, residual.commanded(nominal, q)), q, atol=1e-12)


def test_gravity_feature_is_the_torque_of_a_unit_weight():
    """UR10 with the upper arm horizontal: a weight at the elbow acts about joint 2 with the arm length as lever."""
    nominal = load_robot("ur10")
    q = np.array([[0.3, 0.0, 0.0, -np.pi / 2, 0.0, 0.0]])
    value = joint_errors.features(nominal, q, ["grav2_2", "grav1_t"])
    # DH frame 2 origin lies a2 = -612 mm along x1; weight along -z; z1 = base -y turned by q1
    assert value[0, 0] == pytest.approx(0.612, abs=1e-9)
    assert value[0, 1] == pytest.approx(0.0, abs=1e-12)  # joint 1 is vertical: gravity has no torque about it


def test_redundant_parameters_are_fixed_and_named():
    nominal = load_robot("ur10")
    q = random_joints(200, 5)
    fit = identify(nominal, q, fk(nominal, q)[:, :3, 3])
    # UR axes 2-3-4 are parallel: their offsets d2, d3, d4 act along one direction
    assert sum(name in fit.identifiability.fixed for name in ("d2", "d3", "d4")) == 2
    assert all("redundant" in fit.identifiability.fixed[n] for n in ("d2", "d3", "d4") if n in fit.identifiability.fixed)
    assert "beta2" in fit.names and "beta3" in fit.names
    assert not any(n.endswith("6") for n in candidate_parameters(nominal))  # link 6 is the tool's


def test_apply_deltas_matches_a_hand_perturbed_table():
    nominal = load_robot("ur5")
    moved = apply_deltas(nominal, ["a2", "tool_z"], [1.5, 2.0])
    by_hand = nominal.replace(a=nominal.a + [0, 1.5, 0, 0, 0, 0], T_flange_tool=pose_to_matrix([0, 0, 2.0, 0, 0, 0]))
    q = random_joints(20, 6)
    np.testing.assert_allclose(fk(moved, q), fk(by_hand, q), atol=1e-9)


def test_tracker_registration_recovers_a_rigid_transform():
    points = np.random.default_rng(2).uniform(-500, 500, (50, 3))
    T = pose_to_matrix([100.0, -20.0, 5.0, 0.3, -0.2, 1.0])
    moved = points @ T[:3, :3].T + T[:3, 3]
    np.testing.assert_allclose(best_fit_transform(points, moved), T, atol=1e-9)


def test_too_few_points_and_nan_raise():
    nominal = load_robot("ur10")
    q = random_joints(5, 8)
    with pytest.raises(CalibrationError, match="too few"):
        identify(nominal, q, fk(nominal, q)[:, :3, 3])
    q = random_joints(50, 8)
    measured = fk(nominal, q)[:, :3, 3]
    measured[3, 1] = np.nan
    with pytest.raises(CalibrationError, match="NaN"):
        identify(nominal, q, measured)


def test_a_gross_outlier_is_named_and_does_not_pull_the_robust_fit():
    nominal = load_robot("ur10")
    virtual = VirtualRobot.create(nominal, GEOMETRIC, seed=1)
    q = random_joints(150, 4)
    clean = fk(virtual.true_robot, q)[:, :3, 3] + np.random.default_rng(2).normal(0, 0.01, (150, 3))
    spoiled = clean.copy()
    spoiled[10] += [5.0, 0.0, 0.0]
    robust = identify(nominal, q, spoiled)
    plain = identify(nominal, q, spoiled, loss="linear")
    assert robust.outliers.tolist() == [10] and robust.weights[10] < 0.05
    reference = fk(identify(nominal, q, clean).robot, q)[:, :3, 3]
    shift = {name: np.abs(fk(fit.robot, q)[:, :3, 3] - reference).max() for name, fit in (("robust", robust), ("plain", plain))}
    assert shift["robust"] < 0.2 * shift["plain"]


def test_gross_outliers_are_found_but_smooth_errors_are_not():
    residuals = np.random.default_rng(1).normal(0, 0.02, (200, 3))
    residuals[17] += [3.0, 0, 0]
    assert outlier_rows(residuals).tolist() == [17]
    smooth = np.column_stack([np.linspace(0, 0.4, 200), np.zeros(200), np.zeros(200)])
    assert outlier_rows(smooth).size == 0
