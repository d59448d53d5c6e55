"""The per-target landing estimate the verdict judges, and the coverage criteria (issue 21 items 1, 2, 6).

A model of the paper's large cube measured in one orientation on the
virtual UR10 (paper profile) compensates targets that the virtual arm then
reaches: the estimate is checked against the true landing error, and the
compliance verdict of programs against what the arm really does.
"""

import json
from types import SimpleNamespace

import numpy as np
import pytest

from trajcomp.model import landing
from trajcomp.calibration.calibrate import calibrate
from trajcomp.cli import main
from trajcomp.compensation.target_correction import compensate
from trajcomp.arm.ik import Configuration, ik
from trajcomp.arm.kinematics import fk
from trajcomp.calibration.measurements import Measurements
from trajcomp.model.model_file import save_model
from trajcomp.calibration.measurement_plan import default_orientation, plan_grid
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot
from trajcomp.arm.parameters import pose_jacobian
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc, pose_to_matrix, rotvec_to_matrix

TOLERANCE = 0.1


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    """Nominal UR10, its virtual copy, the composite model (2 folds) of the large cube and its file."""
    robot = load_robot("ur10")
    virtual = VirtualRobot.create(robot, "paper", seed=1)
    plan = plan_grid(robot, (300.0, -100.0, 300.0), 500.0, 100.0, one_posture=False)  # the demo's paper cube
    meas = Measurements(joints=plan.joints, position=plan.position, lines=np.arange(len(plan.joints)) + 2,
                        measured=virtual.measure(plan.joints, np.random.default_rng(11)), path="cube.csv")
    model = calibrate(robot, meas, grid_step=100.0, folds=2)
    path = tmp_path_factory.mktemp("landing") / "model.yaml"
    save_model(path, model)
    return robot, virtual, model, path


def _tilted(robot, tilt_deg, count, seed):
    """``count`` targets (N, 4, 4) inside the cube, tilted by ``tilt_deg`` about random axes of the tool's x-y plane."""
    rng = np.random.default_rng(seed)
    targets = np.tile(np.eye(4), (count, 1, 1))
    targets[:, :3, 3] = np.array([350.0, -50.0, 350.0]) + rng.uniform(0.0, 400.0, (count, 3))
    angle = rng.uniform(0.0, 2.0 * np.pi, count)
    axis = np.column_stack([np.cos(angle), np.sin(angle), np.zeros(count)])
    targets[:, :3, :3] = abc_to_matrix(default_orientation(robot)) @ rotvec_to_matrix(np.radians(tilt_deg) * axis)
    return targets


def _true_error(virtual, result, targets):
    return np.linalg.norm(virtual.reached_poses(result.q)[:, :3, 3] - targets[:, :3, 3], axis=1)


@pytest.mark.parametrize("tilt", [0.0, 15.0, 30.0])
def test_the_estimate_covers_the_true_landing_error_and_never_passes_a_miss(cell, tilt):
    robot, virtual, model, _ = cell
    targets = _tilted(robot, tilt, 40, seed=int(tilt) + 1)
    result = compensate(model, targets)
    true = _true_error(virtual, result, targets)
    assert np.mean(result.estimate >= true) >= 0.95
    assert not np.any((result.estimate <= TOLERANCE) & (true > TOLERANCE))  # no false pass
    assert result.residual.max() < 1e-4  # the convergence: the model agrees with itself, whatever the tilt
    if tilt == 0.0:
        assert not result.orientation_beyond.any() and np.all(result.unseen < 0.01)
        assert np.mean(result.estimate <= TOLERANCE) >= 0.9  # measured orientation: most targets pass
    else:
        np.testing.assert_allclose(result.orientation_beyond, tilt, atol=1e-6)
        assert np.all(result.unseen > 0.05)  # the TCP's length along the tool axis is unseen in one orientation


def test_the_held_out_errors_use_the_compensation_interpolator(cell):
    robot, _, model, _ = cell
    data = landing.of_model(model)
    assert data.method.startswith("idw8 on the lattice")
    assert model.report["cross_validation"]["interpolation"] == "knn"  # the k-fold leaves holes in the lattice
    # held out, idw8 composite and grid: same order of magnitude as the knn folds, not the fit's zeros
    assert 0.01 < data.held_out["composite"]["p95"] < 0.2 and data.held_out["grid"]["p95"] > 0.1
    assert "outer layers" in data.method  # and how the errors grow beyond the measured volume


def test_the_quantile_of_a_gaussian_error_norm_matches_sampling():
    rng = np.random.default_rng(5)
    mean = rng.normal(0.0, 0.02, (6, 3)) * np.array([[0], [1], [1], [0], [3], [1]])
    factor = rng.normal(0.0, 0.03, (6, 3, 3)) * np.array([1, 1, 0.1, 0.2, 1, 3])[:, None, None]
    covariance = factor @ factor.transpose(0, 2, 1)
    covariance[0] = np.eye(3) * 0.01**2  # isotropic without mean: the chi-square is exact
    samples = mean[:, None, :] + np.einsum("nij,nkj->nki", np.linalg.cholesky(covariance + 1e-12 * np.eye(3)),
                                           rng.normal(size=(6, 200_000, 3)))
    sampled = np.quantile(np.linalg.norm(samples, axis=2), 0.95, axis=1)
    np.testing.assert_allclose(landing.quantile_of_norm(mean, covariance), sampled, rtol=0.04)
    np.testing.assert_allclose(landing.quantile_of_norm(mean[:1] * 0, covariance[:1]), sampled[:1], rtol=0.005)


def test_the_held_out_rms_grows_as_fitted_with_the_distance_and_outside():
    rng = np.random.default_rng(6)
    distance = rng.uniform(0.0, 80.0, 4000)
    beyond = np.where(rng.uniform(size=4000) < 0.3, rng.uniform(10.0, 200.0, 4000), 0.0)
    rms = 0.02 + 0.0005 * distance + beyond * (0.0002 + 1e-6 * beyond)
    errors = np.linalg.norm(rng.normal(size=(4000, 3)), axis=1) / np.sqrt(3.0) * rms  # RMS of |error| = rms
    intercept, start, slope, outside, curve, least = landing.fit_growth(distance, beyond, errors)
    grown = intercept + slope * (np.array([10.0, 70.0]) - start)
    np.testing.assert_allclose(grown, 0.02 + 0.0005 * np.array([10.0, 70.0]), rtol=0.1)
    at = np.array([50.0, 150.0])
    np.testing.assert_allclose(outside * at + curve * at**2, at * (0.0002 + 1e-6 * at), rtol=0.25)
    assert least == 0.0
    # for a model that does not carry the error's structure outside: an error of the interior's size every spacing
    floored = SimpleNamespace(growth={"dh": landing.fit_growth(distance, beyond, errors, spacing=10.0)})
    assert floored.growth["dh"][5] == pytest.approx(intercept / 10.0)
    near = landing.LandingData.rms_at(floored, "dh", np.zeros(2), np.array([0.01, 0.01]), np.array([1.0, 100.0]))
    np.testing.assert_allclose(near, intercept * np.array([1.1, 11.0]), rtol=1e-3)  # the floor: 1 and 100 mm out


def test_the_stated_quantile_covers_held_out_errors_with_heavier_tails_than_a_gaussian_s():
    rng = np.random.default_rng(16)
    distance = rng.uniform(0.0, 80.0, 8000)
    beyond = np.where(rng.uniform(size=8000) < 0.3, rng.uniform(0.05, 1.0, 8000), 0.0)
    scale = 0.02 + 0.0005 * distance + 0.05 * beyond
    errors = np.linalg.norm(rng.standard_t(3, size=(8000, 3)), axis=1) * scale  # Student t, 3 degrees: heavy tails
    fitted = SimpleNamespace(growth={"composite": landing.fit_growth(distance, beyond, errors)})
    near = landing.LandingData.rms_at(fitted, "composite", distance, beyond, beyond * 400.0)
    stated = landing.quantile_of_norm(np.zeros((len(near), 3)), near[:, None, None] ** 2 / 3.0 * np.eye(3))
    for rows in (beyond == 0, beyond > 0, distance > 60):  # inside, outside, far inside
        assert 0.93 < np.mean(errors[rows] <= stated[rows]) < 0.97
    # the RMS of these errors would state too little
    assert np.mean(errors <= landing.quantile_of_norm(np.zeros((len(near), 3)), np.mean(
        (errors / near) ** 2) * near[:, None, None] ** 2 / 3.0 * np.eye(3))) < 0.93


def test_outside_the_box_counts_in_units_of_its_extent():
    box = np.array([[0.0, 0.0, 0.0], [400.0, 200.0, 0.0]])  # a flat box: its z extent is a plane's
    points = np.array([[500.0, 100.0, 0.0], [200.0, 300.0, 0.0], [-100.0, -100.0, 0.0], [200.0, 100.0, 10.0],
                       [200.0, 100.0, 0.0]])
    expected = [0.25, 0.5, np.hypot(0.25, 0.5), 10.0 / landing.THIN, 0.0]
    relative, mm = landing.outside_box(points, box)
    np.testing.assert_allclose(relative, expected)
    np.testing.assert_allclose(mm, [100.0, 100.0, np.hypot(100.0, 100.0), 10.0, 0.0])


def test_a_model_calibrated_before_the_box_counted_in_extents_keeps_its_estimate(cell):
    """Its growth outside was stored per mm (``outside_slope``, ``outside_curve_per_mm``): read, it states what it
    stated, exactly along the box's longest side, at least that elsewhere."""
    stored = cell[2].report["landing"]
    rms, start, slope, per_mm, curve_per_mm = 0.01, 2.0, 3e-4, 2e-4, 1e-6
    old = dict(stored, growth={mode: {"rms_mm": rms, "from_mm": start, "slope": slope, "outside_slope": per_mm,
                                      "outside_curve_per_mm": curve_per_mm} for mode in stored["growth"]})
    data = landing.LandingData.from_dict(old)
    lower, upper = data.positions.min(axis=0), data.positions.max(axis=0)
    longest = int(np.argmax(upper - lower))
    points = np.repeat(((lower + upper) / 2)[None], 3, axis=0)
    points[0, longest] = upper[longest] + 120.0  # along the longest side
    points[1, (longest + 1) % 3] = upper[(longest + 1) % 3] + 120.0  # along a shorter one
    beyond, beyond_mm = landing.outside_box(points, data.positions)
    was = rms + slope * (30.0 - start) + beyond_mm * (per_mm + curve_per_mm * beyond_mm)
    now = data.rms_at("composite", np.full(3, 30.0), beyond, beyond_mm)
    np.testing.assert_allclose(now[[0, 2]], was[[0, 2]], rtol=1e-12)
    assert now[1] >= was[1]


def test_the_coverage_distance_is_each_joint_gap_times_its_lever():
    robot = load_robot("ur10")
    rng = np.random.default_rng(7)
    measured = rng.uniform(-1.0, 1.0, (30, 6))
    q = rng.uniform(-1.2, 1.2, (5, 6))
    gaps = np.abs(q[:, None, :] - measured[None]).min(axis=1)  # brute force: nearest measured value per joint
    step = 1e-6
    lever = np.empty((5, 6))
    for joint in range(6):  # |d TCP / d q_j| by central differences of the forward kinematics
        moved = np.array(q)
        moved[:, joint] += step
        back = np.array(q)
        back[:, joint] -= step
        lever[:, joint] = np.linalg.norm(fk(robot, moved)[:, :3, 3] - fk(robot, back)[:, :3, 3], axis=1) / (2 * step)
    np.testing.assert_allclose(landing.coverage_distance(robot, measured, q), np.linalg.norm(gaps * lever, axis=1),
                               rtol=1e-5)
    assert np.all(landing.coverage_distance(robot, measured, measured) == 0.0)


def test_gauge_directions_are_what_no_configuration_sees():
    robot = load_robot("ur10")
    names = ["d1", "a2", "d2", "d3", "base_z"]
    gauge = landing.gauge_directions(robot, names)
    by_name = dict(zip(names, gauge))  # each parameter's share in each unobservable combination
    assert gauge.shape[1] == 2  # d1 against the registration's height, and d2, d3 along parallel axes 2 and 3
    assert np.abs(by_name["a2"]).max() < 1e-6  # a2 lengthens the upper arm: always seen
    np.testing.assert_allclose(np.abs(gauge.T @ gauge), np.eye(2), atol=1e-9)
    unit = dict(zip(names, np.eye(len(names))))
    for a, b in (("d1", "base_z"), ("d2", "d3")):  # each known combination lies in the span found
        assert max(np.linalg.norm(gauge.T @ (unit[a] + sign * unit[b])) / np.sqrt(2) for sign in (1, -1)) > 1 - 1e-9
    q = np.random.default_rng(8).uniform(-3.0, 3.0, (50, 6))
    moved = pose_jacobian(robot, q, names)[1][:, :3, :] @ gauge
    assert np.abs(moved).max() < 1e-6


def _program(path, robot, targets):
    abc = np.degrees(matrix_to_abc(targets[:, :3, :3]))
    rows = ["x,y,z,a,b,c,motion"] + [",".join(f"{v:.4f}" for v in (*p, *o)) + ",PTP"
                                     for p, o in zip(targets[:, :3, 3], abc)]
    path.write_text("\n".join(rows) + "\n")
    return path


def _criteria(path):
    doc = json.loads(path.read_text())
    return doc, {c["id"]: c for c in doc["verdict"]["criteria"]}


def test_a_tilted_program_fails_the_verdict_where_an_untilted_one_passes(cell, tmp_path):
    robot, virtual, model, model_path = cell
    level = _tilted(robot, 0.0, 8, seed=5)
    tilted = level.copy()
    tilted[:, :3, :3] = _tilted(robot, 15.0, 8, seed=5)[:, :3, :3]
    for name, targets, code in (("level", level, 0), ("tilted", tilted, 1)):
        program = _program(tmp_path / f"{name}.csv", robot, targets)
        report = tmp_path / f"{name}-report"
        assert main(["compensate", str(program), "--model", str(model_path), "-o", str(tmp_path / f"{name}-out.csv"),
                     "--retime", "none", "--report", str(report), "--json-only"]) == code
        doc, criteria = _criteria(report.with_suffix(".json"))
        rows = doc["targets"]
        estimate = np.array([t["landing_estimate_mm"] for t in rows])
        assert all(t["convergence_mm"] < 1e-4 for t in rows) and "landing error" in criteria["residual"]["statement"]
        np.testing.assert_allclose(estimate, [t["held_out_mm"] + t["unseen_mm"] + t["convergence_mm"] for t in rows],
                                   atol=2e-5)
        if name == "level":
            assert criteria["orientation"]["status"] == criteria["residual"]["status"] == "pass"
        else:  # every target tilted by 15 deg beyond the measured orientation, and estimated beyond the tolerance
            assert criteria["orientation"]["failing"] == 8 and criteria["residual"]["failing"] == 8
            assert all(t["orientation_beyond_deg"] == pytest.approx(15.0, abs=1e-3) for t in rows)
            assert "orientation" in rows[0]["flags"] and criteria["outside_grid"]["status"] == "pass"
            q = np.radians([t["joints_deg"] for t in rows])
            true = np.linalg.norm(virtual.reached_poses(q)[:, :3, 3] - targets[:, :3, 3], axis=1)
            assert np.all(estimate >= true)


def test_a_tool_the_model_cannot_place_fails_its_own_criterion(cell):
    robot, virtual, model, _ = cell
    assert not model.places_other_tools
    tool = pose_to_matrix([60.0, 0.0, 200.0, 0.0, 0.0, 0.0])
    targets = _tilted(robot, 0.0, 20, seed=6)
    result = compensate(model, targets, tool=tool)
    true = np.linalg.norm(fk(virtual.true_robot.replace(T_flange_tool=tool), virtual.reached_joints(result.q))[:, :3, 3]
                          - targets[:, :3, 3], axis=1)
    assert result.other_tool.all() and np.mean(result.estimate >= true) >= 0.95
    assert np.all(result.estimate > TOLERANCE) and true.mean() > 0.05  # the flange is not located: tenths of a mm


def test_a_turn_of_the_flange_no_point_sees_moves_another_tool_by_its_lever(cell):
    """A constant turn of the flange about the measured TCP leaves every measurement as it was (the calibration
    cannot see it) and moves a tool 150 mm from that TCP by the turn times 150 mm: the estimate covers a turn of
    1.5 times the stated prior angle, and adds nothing on the measured TCP itself (no lever)."""
    robot, virtual, model, _ = cell
    turn = landing.of_model(model).flange_turn
    assert np.radians(0.001) < turn < np.radians(0.2)
    probe = model.nominal.T_flange_tool
    tool = probe @ pose_to_matrix([0.0, 0.0, 150.0, 0.0, 0.0, 0.0])
    about_probe = pose_to_matrix([*probe[:3, 3], 0.0, 0.0, 0.0])
    turned = about_probe @ pose_to_matrix([0.0, 0.0, 0.0, 1.5 * turn, 0.0, 0.0]) @ np.linalg.inv(about_probe)
    targets = _tilted(robot, 0.0, 20, seed=8)
    result = compensate(model, targets, tool=tool)
    arm = virtual.true_robot.replace(T_flange_tool=turned @ tool)
    true = np.linalg.norm(fk(arm, virtual.reached_joints(result.q))[:, :3, 3] - targets[:, :3, 3], axis=1)
    assert true.mean() > 0.8 * 1.5 * turn * 150.0  # the turn is what moves the tool
    assert np.mean(result.estimate >= true) >= 0.95
    np.testing.assert_allclose(compensate(model, targets, tool=probe).estimate, compensate(model, targets).estimate,
                               atol=1e-4)  # the identified TCP against its nominal: micrometres


def test_a_re_calibration_s_correction_adds_its_own_uncertainty_growing_away_from_its_rows(cell):
    """A correction kriged from a later campaign's few rows (`trajcomp recalibrate`) is as uncertain as those rows
    leave it: about nothing beside a row, its whole signal variance far from every row."""
    import dataclasses

    from trajcomp.model.interpolate import Kriging

    robot, _, model, _ = cell
    rows = np.array([[400.0, 0.0, 400.0], [600.0, 200.0, 400.0], [500.0, 100.0, 650.0]])
    values = np.array([[0.05, -0.02, 0.01], [-0.04, 0.03, 0.02], [0.02, 0.04, -0.05]])
    near, far = _tilted(robot, 0.0, 2, seed=9), _tilted(robot, 0.0, 2, seed=9)
    near[:, :3, 3], far[:, :3, 3] = rows[:2] + 1.0, [[300.0, 300.0, 700.0], [700.0, -100.0, 300.0]]
    added = {}
    for label, scale in (("signal", 1.0), ("none", 1e-6)):
        corrected = dataclasses.replace(model, residual=Kriging(rows, scale * values, length=100.0, nugget=0.01))
        for where, targets in (("near", near), ("far", far)):
            q = compensate(corrected, targets).q
            added[label, where] = landing.estimate(corrected, "composite", q, targets).total
    variance = Kriging(rows, values, length=100.0, nugget=0.01).signal_variance().mean()
    assert np.all(added["signal", "far"] - added["none", "far"] > 0.5 * np.sqrt(3 * variance))
    assert np.all(added["signal", "near"] - added["none", "near"] < 0.2 * np.sqrt(3 * variance))


def test_a_posture_never_measured_is_its_own_criterion_not_outside_the_grid(cell):
    robot, virtual, model, _ = cell
    targets = _tilted(robot, 0.0, 6, seed=7)
    home = ik(robot, targets, seed=robot.home).q
    measured = Configuration.from_index(model.postures[0])
    flipped = ik(robot, targets, config=Configuration(measured.shoulder, measured.elbow,
                                                      "negative" if measured.wrist == "positive" else "positive")).q
    result = compensate(model, targets, seed=flipped)
    assert result.unmeasured_posture.all() and not result.outside.any()  # inside the grid box
    assert not compensate(model, targets, seed=home).unmeasured_posture.any()
    assert np.all(result.unseen > 0.0)


def test_a_light_re_calibration_s_uncertainty_widens_every_estimate(cell):
    """A model updated from a few rows (`trajcomp recalibrate`) carries its update's covariance into the estimate."""
    import dataclasses

    from trajcomp.model import update

    robot, _, model, _ = cell
    record = {"names": ["tool_x", "theta2"], "arm": ["tool_x", "theta2"], "applied": "update",
              "units": ["mm", "deg"], "covariance": [[0.05**2, 0.0], [0.0, 0.0]]}  # tool_x +-0.05 mm
    updated = dataclasses.replace(model, report={**model.report, "update": record})
    targets = _tilted(robot, 0.0, 10, seed=9)
    q = compensate(model, targets).q
    added = update.position_covariance(updated, q)
    np.testing.assert_allclose(np.trace(added, axis1=1, axis2=2), 0.05**2, rtol=1e-6)  # tool_x moves the TCP 1:1
    assert not update.position_covariance(model, q).any()  # never updated: nothing added
    skipped = dataclasses.replace(model, report={**model.report, "update": {**record, "applied": "registration"}})
    assert not update.position_covariance(skipped, q).any()  # the rows kept the model: nothing added
    before = landing.estimate(model, "composite", q, targets).total
    after = landing.estimate(updated, "composite", q, targets).total
    assert np.all(after > before) and np.all(after < before + 2.5 * 0.05)


def test_a_joint_residual_s_miss_grows_beyond_its_measured_range_along_the_joint_s_own_motion():
    """Beyond a joint's measured range its error may miss by `BEYOND_FACTOR` times the largest RMS angle error of a
    joint there (joint 2's gear term: the others are flat), reached `BEYOND_RAMP` out, along the motion of the TCP
    that turning that joint makes (finite differences of the DH angle); inside the range nothing is added."""
    from types import SimpleNamespace

    from trajcomp.arm.kinematics import fk
    from trajcomp.arm.parameters import apply_deltas
    from trajcomp.model.joint_errors import JointResidual

    robot = load_robot("ur10")
    middle = np.radians([10.0, -100.0, 90.0, -80.0, -90.0, 0.0])
    lower, upper = middle - np.radians(20.0), middle + np.radians(20.0)
    residual = JointResidual(("gear2_s1",), [2e-4], lower, upper)
    measured = middle + np.random.default_rng(0).uniform(-1.0, 1.0, (60, 6)) * np.radians(20.0)
    model = SimpleNamespace(residual=residual, nominal=robot)
    data = SimpleNamespace(configurations=measured)
    q = np.tile(middle, (4, 1))
    q[:, 1] = upper[1] + landing.BEYOND_RAMP * np.array([0.0, 0.5, 1.0, 2.0])  # on the edge, half the ramp, ...
    added = landing._beyond_joint_range(model, data, robot, q)
    size = landing.BEYOND_FACTOR * np.std(2e-4 * np.sin(measured[:, 1]))
    step = 1e-6
    column = (fk(apply_deltas(robot, ["theta2"], [step]), q)[:, :3, 3] - fk(robot, q)[:, :3, 3]) / step
    for k, share in enumerate([0.0, 0.5, 1.0, 1.0]):
        expected = (size * share) ** 2 * np.outer(column[k], column[k])
        assert np.allclose(added[k], expected, rtol=1e-4, atol=1e-12)
    wrist = middle.copy()
    wrist[4] = upper[4] + landing.BEYOND_RAMP  # joint 5 alone beyond its range, flat where measured: the same size
    column5 = (fk(apply_deltas(robot, ["theta5"], [step]), wrist[None])[0, :3, 3] - fk(robot, wrist[None])[0, :3, 3]) / step
    assert np.allclose(landing._beyond_joint_range(model, data, robot, wrist[None])[0],
                       size**2 * np.outer(column5, column5), rtol=1e-4, atol=1e-12)


def test_outside_the_measured_volume_a_field_on_a_joint_residual_fades_to_the_joint_residual_s_own_growth(cell):
    """A field on top of a joint residual returns to zero away from its rows, leaving the joint residual, which
    extrapolates: beyond the measured volume the estimate is the joint residual's own (its growth with the joints'
    distance and beyond their ranges), not the kinematic model's held-out errors, which on foreign virtual UR10 arms
    made it 8-25 times the true landing error there (``bench_verdict.py``: 150-300 mm outside, singularities). In an
    arm posture never measured the kinematic model's serve (there the joint model missed by 2.5 times its estimate on
    arms measured off the last axis)."""
    import dataclasses

    from trajcomp.model.interpolate import GaussianField
    from trajcomp.model.joint_errors import JointResidual

    robot, _, model, _ = cell
    targets = _tilted(robot, 0.0, 6, seed=13)
    targets[:, :3, 3] += np.array([0.0, 0.0, 250.0])  # above the cube
    q = ik(robot, targets, seed=robot.home).q
    data = landing.of_model(model)
    residual = JointResidual(("gear2_s1",), [2e-4], data.configurations.min(axis=0), data.configurations.max(axis=0))
    joint_alone = dataclasses.replace(model, residual=residual, residual_field=None)
    wave = GaussianField(data.positions[:4], np.full((4, 3), 0.01), length=200.0, nugget=0.25)
    with_field = dataclasses.replace(joint_alone, residual_field=wave)
    outside = np.ones(len(q), bool)
    alone = landing.estimate(joint_alone, "composite", q, targets, outside=outside).total
    on_top = landing.estimate(with_field, "composite", q, targets, outside=outside).total
    np.testing.assert_allclose(on_top, alone, rtol=1e-12)
    kinematic = data.near_rms("dh", robot, q, targets[:, :3, 3])
    assert np.all(data.near_rms("composite", robot, q, targets[:, :3, 3]) < kinematic)  # what the old estimate took
    # in a posture never measured the joint curves of the wrist were measured at other angles: the kinematic model's
    # held-out errors serve
    other = landing.estimate(with_field, "composite", q, targets, outside=outside, postures=np.ones(len(q), bool))
    np.testing.assert_allclose(other.held_out, landing.quantile_of_norm(
        np.zeros((len(q), 3)), kinematic[:, None, None] ** 2 / 3.0 * np.eye(3)), rtol=1e-12)
