"""DH identification recovers the virtual robot's planted errors."""

import numpy as np
import pytest

from trajcomp.errors import CalibrationError
from trajcomp.identify import (
    analyse_identifiability,
    apply_deltas,
    best_fit_transform,
    candidate_parameters,
    identify_dh,
    outlier_rows,
    position_jacobian,
)
from trajcomp.kinematics import fk
from trajcomp.robot import load_robot
from trajcomp.simulate import ErrorProfile, VirtualRobot
from trajcomp.transforms import pose_to_matrix

GEOMETRIC = ErrorProfile("geometric", length_sigma=0.5, angle_sigma=np.radians(0.05), tool_sigma=0.2)


def random_joints(n, seed):
    return np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, 6))


@pytest.mark.parametrize("name", ["ur10", "kuka_kr6_r900", "abb_irb4600", "fanuc_lrmate200id"])
def test_recovers_geometric_errors_everywhere(name):
    nominal = load_robot(name)
    virtual = VirtualRobot.create(nominal, GEOMETRIC, seed=4)
    q = random_joints(300, 1)
    fit = identify_dh(nominal, q, fk(virtual.true_robot, q)[:, :3, 3])
    fresh = random_joints(500, 2)
    error = np.linalg.norm(fk(fit.robot, fresh)[:, :3, 3] - fk(virtual.true_robot, fresh)[:, :3, 3], axis=1)
    # noise-free data: only the weakly observed parameters left at nominal remain (~µm)
    assert error.max() < 0.01


def test_identifiable_deltas_match_the_truth_within_their_sigma():
    nominal = load_robot("ur10")
    virtual = VirtualRobot.create(nominal, GEOMETRIC, seed=7)
    q = random_joints(400, 3)
    rng = np.random.default_rng(0)
    measured = fk(virtual.true_robot, q)[:, :3, 3] + rng.normal(0, 0.005, (400, 3))
    fit = identify_dh(nominal, q, measured)
    truth = virtual.true_robot
    for name, delta, sigma in zip(fit.names, fit.delta, fit.sigma):
        if name.startswith(("a", "alpha")) and name[-1] in "123":
            attr = "alpha" if name.startswith("alpha") else "a"
            true_delta = getattr(truth, attr)[int(name[-1]) - 1] - getattr(nominal, attr)[int(name[-1]) - 1]
            assert abs(delta - true_delta) < 6 * sigma + 1e-9, name


def test_redundant_parameters_are_fixed_and_named():
    nominal = load_robot("ur10")
    names = candidate_parameters(nominal)
    ident = analyse_identifiability(position_jacobian(nominal, random_joints(200, 5), names, np.zeros(len(names))), names)
    # The last joint's angle offset only turns the tool about its own axis: with a
    # tool on that axis it cannot change any position.
    assert "theta6" in ident.fixed and "redundant" in ident.fixed["theta6"]
    assert set(ident.kept) | set(ident.fixed) == set(names)
    assert "beta2" in names and "beta3" in names  # UR axes 2-3-4 are parallel: Hayati


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
        identify_dh(nominal, q, fk(nominal, q)[:, :3, 3])
    q = random_joints(50, 8)
    measured = fk(nominal, q)[:, :3, 3]
    measured[3, 1] = np.nan
    with pytest.raises(CalibrationError, match="NaN"):
        identify_dh(nominal, q, measured)


def test_gross_outliers_are_found_but_smooth_errors_are_not():
    residuals = np.random.default_rng(1).normal(0, 0.02, (200, 3))
    residuals[17] += [3.0, 0, 0]
    assert outlier_rows(residuals).tolist() == [17]
    smooth = np.column_stack([np.linspace(0, 0.4, 200), np.zeros(200), np.zeros(200)])
    assert outlier_rows(smooth).size == 0
