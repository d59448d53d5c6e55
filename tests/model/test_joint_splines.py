"""Joint-angle splines (issue 23) and identification that leaves unseen combinations at nominal (issue 21, item 3)."""

import dataclasses

import numpy as np

from trajcomp.model import joint_errors
from trajcomp.calibration.calibrate import calibrate, selection_words
from trajcomp.compensation.target_correction import compensate
from trajcomp.calibration.identify import identify, linearise, region_folds
from trajcomp.model.joint_errors import JointResidual, SplineBasis
from trajcomp.arm.kinematics import fk
from trajcomp.calibration.measurements import Measurements
from trajcomp.model.model_file import load_model, save_model
from trajcomp.arm.parameters import scales
from trajcomp.calibration.measurement_plan import default_orientation, plan_grid
from trajcomp.report.calibration import calibration_report
from trajcomp.report.html import render
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import ErrorProfile, VirtualRobot
from trajcomp.arm.transforms import abc_to_matrix, pose_to_matrix, rotvec_to_matrix

RANGE = np.radians([[-60, 60], [-120, -40], [40, 130], [-150, -30], [60, 120], [-90, 90]])


def joints_in_range(n, seed):
    """n (N, 6) random joints inside `RANGE`, rad."""
    return np.random.default_rng(seed).uniform(RANGE[:, 0], RANGE[:, 1], (n, 6))


def planted_error(q):
    """Angle error (N,) rad of joint 2: a bump and a ripple of 40 deg period, beyond the harmonics of the model."""
    return np.radians(0.01) * (np.exp(-((q[:, 1] + np.radians(80)) / np.radians(15)) ** 2)
                               + 0.5 * np.sin(q[:, 1] * 360 / 40))


def test_cubic_basis_is_a_partition_of_unity_and_holds_its_boundary_value():
    basis = SplineBasis(RANGE[:, 0], RANGE[:, 1], np.radians([10, 10, 0, 0, 0, 0]))
    q = joints_in_range(50, 1)
    values = basis.matrix(q, 0).toarray()
    np.testing.assert_allclose(values.sum(axis=1), 1.0, atol=1e-12)  # sum of uniform cubic B-splines is 1
    assert values.shape == (50, 12 + 3) and basis.intervals(2) == 0  # 120 deg / 10 deg intervals; joint 3 none
    beyond = q[:2].copy()
    beyond[:, 0] = [RANGE[0, 1] + 0.2, RANGE[0, 0] - 0.3]
    edge = beyond.copy()
    edge[:, 0] = RANGE[0, [1, 0]]
    np.testing.assert_array_equal(basis.matrix(beyond, 0).toarray(), basis.matrix(edge, 0).toarray())


def test_splines_recover_a_planted_joint_angle_error_that_harmonics_cannot():
    """The arm's joint 2 has an error the gear harmonics do not span: the spline identifies it with the DH table."""
    nominal = load_robot("ur10")
    true = VirtualRobot.create(nominal, ErrorProfile("geometric", length_sigma=0.3, angle_sigma=np.radians(0.03)),
                               seed=4).true_robot
    q = joints_in_range(400, 2)

    def landed(joints):
        reached = joints.copy()
        reached[:, 1] += planted_error(joints)
        return fk(true, reached)[:, :3, 3]

    basis = SplineBasis(q.min(axis=0), q.max(axis=0), np.radians([0, 4, 0, 0, 0, 0]), penalty=1e-6)
    fit = identify(nominal, q, landed(q), joint_terms=True, splines=basis)
    harmonics = identify(nominal, q, landed(q), joint_terms=True)
    fresh = joints_in_range(300, 3)
    truth = landed(fresh)

    def error(f):
        return np.linalg.norm(fk(f.robot, f.joint_errors.reached(nominal, fresh))[:, :3, 3] - truth, axis=1)

    assert error(harmonics).mean() > 0.03  # a real error, beyond what the harmonics hold
    assert error(fit).max() < 0.01
    assert any(joint_errors.is_spline(n) for n in fit.names)


def test_spline_residual_round_trips_through_the_model_file(tmp_path):
    """Names, coefficients, knots, penalty and the measured joint range survive save and load."""
    robot = load_robot("ur10")
    plan = plan_grid(robot, (400, -100, 400), 300, 150)
    q = plan.joints[plan.reachable]
    meas = Measurements(joints=q, position=plan.position[plan.reachable],
                        measured=VirtualRobot.create(robot, "paper", 1).measure(q, np.random.default_rng(0)),
                        lines=np.arange(len(q)) + 2)
    model = calibrate(robot, meas, method="dh", folds=0)
    basis = SplineBasis(q.min(axis=0), q.max(axis=0), np.radians([5, 5, 0, 0, 0, 0]), penalty=0.01)
    names = basis.names()
    values = np.random.default_rng(5).normal(0.0, 1e-5, len(names))
    residual = JointResidual(names, values, q.min(axis=0), q.max(axis=0), basis)
    model = dataclasses.replace(model, residual=residual, method="composite")
    save_model(tmp_path / "m.yaml", model)
    loaded = load_model(tmp_path / "m.yaml").residual
    assert loaded.names == residual.names and loaded.basis.penalty == 0.01
    np.testing.assert_array_equal(loaded.lower, q.min(axis=0))
    np.testing.assert_allclose(loaded.offsets(robot, q), residual.offsets(robot, q), rtol=1e-12, atol=1e-18)
    assert np.abs(residual.offsets(robot, q)[:, :2]).max() > 1e-6


def test_single_orientation_fit_leaves_unseen_parameter_combinations_at_nominal():
    """One tool orientation hides wrist and tool combinations: the fit must not move along them.

    The deltas (scaled) have no component along the directions the data do
    not see at all, and tilted targets land as well as the data allow: 15 deg
    tilts landed at 0.12 mm mean in dh mode when one pivoted parameter took
    each confounded effect (a4 moved 2.9 mm for a true 1.0).
    """
    robot = load_robot("ur10")
    virtual = VirtualRobot.create(robot, "paper", 1)
    rng = np.random.default_rng(1)
    plan = plan_grid(robot, (300, -100, 300), 500, 100, one_posture=False)  # the paper cube, as the demo plans it
    q = plan.joints[plan.reachable]
    fit = identify(robot, q, virtual.measure(q, rng))
    model = calibrate(robot, Measurements(joints=q, position=plan.position[plan.reachable],
                                          measured=virtual.measure(q, rng), lines=np.arange(len(q)) + 2), folds=0)
    _, singular, directions = np.linalg.svd(
        _scaled_jacobian(robot, q, fit.names), full_matrices=False)
    unseen = directions[singular < 1e-9 * singular[0]]
    assert len(unseen) >= 8  # the wrist's and the tool's hidden combinations, and the redundant offsets
    scaled = fit.delta / scales(fit.names)
    assert np.abs(unseen @ scaled).max() < 1e-3 * np.abs(scaled).max()  # a pivoted subset moves them by O(1)
    n = 40
    axis = rng.normal(size=(n, 3))
    axis[:, 2] = 0.0
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    targets = np.tile(np.eye(4), (n, 1, 1))
    targets[:, :3, :3] = (rotvec_to_matrix(axis * np.radians(15.0) * rng.choice([-1, 1], (n, 1)))
                          @ abc_to_matrix(default_orientation(robot)))
    targets[:, :3, 3] = np.array([300.0, -100.0, 300.0]) + rng.uniform(0.0, 500.0, (n, 3))
    landed = virtual.reached_poses(compensate(model, targets, mode="dh").q)[:, :3, 3]
    assert np.linalg.norm(landed - targets[:, :3, 3], axis=1).mean() < 0.1


def _scaled_jacobian(robot, q, names):
    """Position Jacobian (3N, P) of the nominal robot per scaled parameter."""
    from trajcomp.arm.parameters import pose_jacobian

    _, jac = pose_jacobian(robot, q, names)
    return jac[:, :3].reshape(-1, len(names)) * scales(names)


def test_spline_terms_hold_their_edge_value_beyond_the_measured_range_and_gear_terms_go_on():
    """Beyond the range a spline holds its boundary value (flagged outside past the margin); a gear harmonic,
    physics of the whole turn, is evaluated where the joint is."""
    robot = load_robot("ur10")
    basis = SplineBasis(RANGE[:, 0], RANGE[:, 1], np.radians([10, 0, 0, 0, 0, 0]))
    names = basis.names()
    residual = JointResidual(names, np.linspace(-1e-4, 1e-4, len(names)), RANGE[:, 0], RANGE[:, 1], basis)
    q = np.tile(RANGE.mean(axis=1), (3, 1))
    q[:, 0] = RANGE[0, 1] + np.radians([0.0, 3.0, 10.0])  # on the edge, inside the margin, beyond it
    offsets = residual.offsets(robot, q)[:, 0]
    assert offsets[2] == offsets[1] == offsets[0] != 0.0
    assert residual.contains(q).tolist() == [True, True, False]
    gear = JointResidual(("gear1_s1",), [1e-4], RANGE[:, 0], RANGE[:, 1])
    assert np.allclose(gear.offsets(robot, q)[:, 0], 1e-4 * np.sin(q[:, 0]), rtol=0, atol=1e-15)


def test_offsets_are_the_identifications_features_times_their_coefficients():
    """Every term (harmonics, gravity at each frame and the TCP, splines) summed per joint as `offsets` does it
    equals the feature matrix identification fits (`features`, the spline basis matrix) times the coefficients."""
    robot = load_robot("ur10")
    basis = SplineBasis(RANGE[:, 0], RANGE[:, 1], np.radians([10, 7, 0, 0, 12, 0]))
    smooth = joint_errors.term_names()
    names = [*smooth, *basis.names()]
    values = np.random.default_rng(6).normal(0.0, 1e-4, len(names))
    residual = JointResidual(names, values, RANGE[:, 0], RANGE[:, 1], basis)
    q = np.vstack([joints_in_range(3000, 7), RANGE[:, 1] + 0.1])  # past the top too: the splines' edge
    expected = np.zeros((len(q), 6))
    for k, value in enumerate((joint_errors.features(robot, q, smooth) * values[: len(smooth)]).T):
        expected[:, joint_errors.term_joint(smooth[k])] += value
    for j in (0, 1, 4):
        own = values[[names.index(f"spline{j + 1}_{k}") for k in range(basis.intervals(j) + 3)]]
        expected[:, j] += basis.matrix(q, j) @ own
    np.testing.assert_allclose(residual.offsets(robot, q), expected, rtol=0, atol=1e-15)
    assert np.abs(expected).max() > 1e-4


def test_region_folds_hold_out_whole_slabs_never_interleaved_rows():
    position = np.random.default_rng(0).uniform(-100.0, 100.0, (200, 3)) * [1.0, 4.0, 2.0]
    regions, words = region_folds(position, 4)
    assert sorted(np.concatenate(regions).tolist()) == list(range(200)) and "along y" in words
    spans = [(position[r, 1].min(), position[r, 1].max()) for r in regions]
    assert all(high < low for (_, high), (low, _) in zip(spans, spans[1:]))  # disjoint slabs, in order


def test_calibrate_chooses_splines_on_held_out_regions_and_records_the_choice():
    """A joint-2 error no harmonic holds: the selection takes splines, says why, and the choice lands better."""
    robot = load_robot("ur10")
    q = joints_in_range(300, 6)
    true = VirtualRobot.create(robot, ErrorProfile("geometric", length_sigma=0.3, angle_sigma=np.radians(0.03)),
                               seed=4).true_robot

    def landed(joints):
        reached = joints.copy()
        reached[:, 1] += planted_error(joints)
        return fk(true, reached)[:, :3, 3]

    meas = Measurements(joints=q, position=fk(robot, q)[:, :3, 3], measured=landed(q), lines=np.arange(len(q)) + 2)
    model = calibrate(robot, meas, interpolation="joint", folds=0)
    record = model.report["joint_splines"]
    assert record["step_deg"] > 0 and record["joints"] == [1, 2, 3, 4, 5] and "slabs" in record["regions"]
    without = [c["held_out_mm"] for c in record["candidates"] if c["step_deg"] == 0]
    assert len(without) == 1 and min(c["held_out_mm"] for c in record["candidates"]) < 0.5 * without[0]
    shared = [c for c in record["candidates"] if c.get("share")]  # the penalties of the chosen step sharing the model
    assert {c["step_deg"] for c in shared} == {record["step_deg"]} and abs(sum(c["share"] for c in shared) - 1) < 1e-9
    assert max(shared, key=lambda c: c["share"])["penalty"] == record["penalty"] == model.residual.basis.penalty
    fresh = joints_in_range(200, 7)
    error = np.linalg.norm(model.arm("composite").fk(fresh)[:, :3, 3] - landed(fresh), axis=1)
    assert error.mean() < 0.01
    stated = calibration_report(model, meas).doc["joint_errors"]
    assert stated["splines"] == record and stated["terms"]["spline"] > 0
    np.testing.assert_allclose(stated["measured_range_deg"]["upper"], np.degrees(q.max(axis=0)), atol=1e-3)
    assert "Joint-angle error model" in render(calibration_report(model, meas))


def test_a_field_over_positions_goes_on_top_of_the_joint_residual_where_it_wins_on_held_out_regions(tmp_path):
    """An error of the place, not of the joints (a smooth wave along x), is left to a field on top.

    Each commanded position is measured once (no position at two
    orientations), so the fields are offered (knn, and the gp field at the
    likelihood's length); the one of the least held-out error is taken; the
    choice, the field and the other-tools verdict survive the model file,
    and the model predicts the wave at positions it never measured.
    """
    robot = load_robot("ur10")
    q = joints_in_range(300, 9)
    position = fk(robot, q)[:, :3, 3]
    true = VirtualRobot.create(robot, ErrorProfile("geometric", length_sigma=0.3, angle_sigma=np.radians(0.03)),
                               seed=5).true_robot

    def landed(joints):
        reached = fk(true, joints)[:, :3, 3]
        return reached + np.column_stack([np.zeros((len(joints), 2)), 0.1 * np.sin(reached[:, 0] / 80.0)])

    meas = Measurements(joints=q, position=position, measured=landed(q), lines=np.arange(len(q)) + 2)
    model = calibrate(robot, meas, interpolation="joint", folds=2)
    record = model.report["joint_splines"]
    kind = record["field"]
    assert model.report["cross_validation"]["interpolation"] == f"joint with a {kind} field on top"
    assert kind in ("knn", "gp") and model.residual_field.kind == kind and not model.places_other_tools
    chosen = [c for c in record["candidates"] if c["step_deg"] == record["step_deg"] and c["penalty"] == record["penalty"]]
    assert chosen[0]["with_field_mm"] < chosen[0]["held_out_mm"]  # the wave is what the joint model cannot hold
    assert chosen[0]["field_kind"] == kind and chosen[0]["with_field_mm"] == min(
        c.get("with_field_mm", np.inf) for c in record["candidates"])
    save_model(tmp_path / "m.yaml", model)
    loaded = load_model(tmp_path / "m.yaml")
    fresh = joints_in_range(100, 10)
    fresh_position = fk(robot, fresh)[:, :3, 3]
    predicted = loaded.predict("composite", fresh, fresh_position, outside="clamp")[0]
    np.testing.assert_allclose(predicted, model.predict("composite", fresh, fresh_position, outside="clamp")[0])
    without = model.arm("composite").fk(fresh)[:, :3, 3]
    truth = landed(fresh)
    assert np.linalg.norm(predicted - truth, axis=1).mean() < 0.7 * np.linalg.norm(without - truth, axis=1).mean()
    assert calibration_report(model, meas).doc["joint_errors"]["field_on_top"] == kind


def test_a_long_noisy_wave_takes_the_gp_field_whose_length_the_folds_keep(tmp_path):
    """A wave of 1.3 m period under 0.02 mm noise per axis: the gp field (the likelihood's length and nugget) beats
    knn on the held-out regions; the model file keeps its kind and the cross-validation's folds its length and
    nugget; at positions never measured it takes most of the wave off."""
    robot = load_robot("ur10")
    q = joints_in_range(300, 9)
    true = VirtualRobot.create(robot, ErrorProfile("geometric", length_sigma=0.3, angle_sigma=np.radians(0.03)),
                               seed=5).true_robot

    def landed(joints):
        reached = fk(true, joints)[:, :3, 3]
        return reached + np.column_stack([np.zeros((len(joints), 2)), 0.1 * np.sin(reached[:, 0] / 200.0)])

    noise = np.random.default_rng(2).normal(0.0, 0.02, (len(q), 3))
    meas = Measurements(joints=q, position=fk(robot, q)[:, :3, 3], measured=landed(q) + noise,
                        lines=np.arange(len(q)) + 2)
    model = calibrate(robot, meas, interpolation="joint", folds=2)
    record = model.report["joint_splines"]
    field = model.residual_field
    assert record["field"] == field.kind == "gp" and model.report["residual_field"] == "gp"
    assert record["field_options"] == {"length": field.length, "nugget": field.nugget}
    assert model.report["cross_validation"]["interpolation"] == "joint with a gp field on top"
    assert "+ gp field" in selection_words(record)
    save_model(tmp_path / "m.yaml", model)
    assert load_model(tmp_path / "m.yaml").residual_field.kind == "gp"
    fresh = joints_in_range(100, 10)
    position = fk(robot, fresh)[:, :3, 3]
    truth = landed(fresh)
    with_field = model.predict("composite", fresh, position, outside="clamp")[0]
    without = model.arm("composite").fk(fresh)[:, :3, 3]
    assert np.linalg.norm(with_field - truth, axis=1).mean() < 0.6 * np.linalg.norm(without - truth, axis=1).mean()


def test_a_refit_without_some_rows_lands_where_identify_lands_on_the_others():
    """Cross-validation's refit (one linearised step from the fit of all rows, `Linearisation.fit_without`) is
    the identification of the rows kept, spline terms, their penalty and the robust weights included."""
    nominal = load_robot("ur10")
    true = VirtualRobot.create(nominal, ErrorProfile("geometric", length_sigma=0.3, angle_sigma=np.radians(0.03)),
                               seed=4).true_robot
    q = joints_in_range(400, 2)
    reached = q.copy()
    reached[:, 1] += planted_error(q)
    measured = fk(true, reached)[:, :3, 3] + np.random.default_rng(3).normal(0.0, 0.02, (400, 3))
    basis = SplineBasis(q.min(axis=0), q.max(axis=0), np.radians([0, 4, 0, 0, 0, 0]), penalty=1e-4)
    fit = identify(nominal, q, measured, joint_terms=True, splines=basis)
    held = np.arange(0, 400, 4)
    kept = np.setdiff1d(np.arange(400), held)
    refit = linearise(nominal, q, measured, dict(zip(fit.names, fit.delta)), basis=basis,
                      identifiability=fit.identifiability).fit_without(held)
    again = identify(nominal, q[kept], measured[kept], joint_terms=True, splines=basis)
    fresh = joints_in_range(300, 3)

    def landed(f):
        return fk(f.robot, f.joint_errors.reached(nominal, fresh))[:, :3, 3]

    moved = np.linalg.norm(landed(again) - landed(fit), axis=1).mean()  # what holding the rows out changes
    assert moved > 1e-3
    assert np.linalg.norm(landed(refit) - landed(again), axis=1).max() < 0.02 * moved
    assert refit.residuals.shape == (300, 3) and refit.names == again.names


def test_a_model_shared_by_penalties_is_the_weighted_mean_of_their_refits():
    """`Linearisation.shared`: one penalty alone is `without`'s refit to the bit; two are the weighted mean of
    `without`'s refits at each, for all rows and without some: the second is solved in the directions the first's
    normal equations see (61 of 99 here, the second's 62), which moves the measured points by under 0.2 % of what
    the two penalties' fits differ by (micrometres: 1.6e-5 mm against 0.011-0.013)."""
    nominal = load_robot("ur10")
    q = joints_in_range(300, 2)
    reached = q.copy()
    reached[:, 1] += planted_error(q)
    true = VirtualRobot.create(nominal, ErrorProfile("geometric", length_sigma=0.3, angle_sigma=np.radians(0.03)),
                               seed=4).true_robot
    measured = fk(true, reached)[:, :3, 3] + np.random.default_rng(3).normal(0.0, 0.02, (300, 3))
    basis = SplineBasis(q.min(axis=0), q.max(axis=0), np.radians([0, 4, 0, 0, 0, 0]), penalty=1e-4)
    fit = identify(nominal, q, measured, joint_terms=True, splines=basis)
    parameters = dict(zip(fit.names, fit.delta))
    linear = linearise(nominal, q, measured, parameters, basis=basis)
    other = linearise(nominal, q, measured, parameters, basis=dataclasses.replace(basis, penalty=1e-2))
    held = np.arange(0, 300, 5)
    np.testing.assert_array_equal(linear.shared(held, [(1.0, 1e-4)]), linear.without(held))
    for rows in (held, np.zeros(0, dtype=int)):
        alone = [linear.without(rows), other.without(rows)]
        apart = np.linalg.norm(linear.jac.apply(alone[0] - alone[1])[:, :3], axis=1).max()  # mm at the measured rows
        mean = linear.shared(rows, [(0.7, 1e-4), (0.3, 1e-2)])
        off = np.linalg.norm(linear.jac.apply(mean - 0.7 * alone[0] - 0.3 * alone[1])[:, :3], axis=1).max()
        assert apart > 0.01 and off < 0.002 * apart


def test_an_error_that_turns_with_the_wrist_takes_the_gp_field_over_the_wrist(tmp_path):
    """Each position measured in several wrist orientations, an error of the place times the wrist's joint 5 (no
    joint-angle error holds it): the gp field over the position and the wrist goes on top, the model file keeps it,
    and predicted poses, and programs compensated with it, land closer at orientations never measured. The measured
    point lies off the last axis, so the model places other tools: a program with another tool takes no field (it
    holds what the joint model leaves at the measured TCP) and is compensated as by the joint model alone."""
    robot = load_robot("ur10").replace(T_flange_tool=pose_to_matrix([40.0, -30.0, 150.0, 0.0, 0.0, 0.0]))
    rng = np.random.default_rng(12)
    centre = joints_in_range(60, 11)
    q = np.repeat(centre, 4, axis=0)
    q[:, 3:] += np.radians(rng.uniform(-40.0, 40.0, (len(q), 3)))
    true = VirtualRobot.create(robot, ErrorProfile("geometric", length_sigma=0.3, angle_sigma=np.radians(0.03)),
                               seed=5).true_robot

    def landed(joints):
        reached = fk(true, joints)[:, :3, 3]
        wave = 0.1 * np.sin(reached[:, 0] / 150.0) * np.cos(2.0 * joints[:, 4])
        return reached + np.column_stack([np.zeros((len(joints), 2)), wave])

    meas = Measurements(joints=q, position=fk(robot, q)[:, :3, 3], measured=landed(q), lines=np.arange(len(q)) + 2)
    model = calibrate(robot, meas, interpolation="joint", folds=0)
    field = model.residual_field
    assert model.report["joint_splines"]["field"] == "gp" and field.needs_joints
    save_model(tmp_path / "m.yaml", model)
    loaded = load_model(tmp_path / "m.yaml")
    fresh = np.repeat(centre[:20], 2, axis=0)
    fresh[:, 3:] += np.radians(rng.uniform(-40.0, 40.0, (len(fresh), 3)))
    position = fk(robot, fresh)[:, :3, 3]
    predicted = loaded.predict("composite", fresh, position)[0]
    truth = landed(fresh)
    without = model.arm("composite").fk(fresh)[:, :3, 3]
    assert np.linalg.norm(predicted - truth, axis=1).mean() < 0.5 * np.linalg.norm(without - truth, axis=1).mean()
    targets = fk(robot, fresh)
    result = compensate(loaded, targets, seed=fresh)
    miss = np.linalg.norm(landed(result.q) - targets[:, :3, 3], axis=1)
    plain = np.linalg.norm(landed(compensate(loaded, targets, seed=fresh, mode="dh").q) - targets[:, :3, 3], axis=1)
    assert miss.mean() < 0.5 * plain.mean()
    assert loaded.error_field("composite", robot.T_flange_tool) is loaded.error_field("composite") is not None
    other = pose_to_matrix([0.0, 0.0, 250.0, 0.0, 0.0, 0.0])
    assert loaded.places_other_tools and loaded.error_field("composite", other) is None
    joint_alone = dataclasses.replace(loaded, residual_field=None)
    np.testing.assert_allclose(compensate(loaded, targets, tool=other, seed=fresh).q,
                               compensate(joint_alone, targets, tool=other, seed=fresh).q, atol=1e-12)
