"""Light re-calibration: a virtual arm whose joint zeros, link lengths, TCP and tracker pose drift by known amounts."""

import dataclasses
import json

import numpy as np
import pytest

from trajcomp.arm.kinematics import fk
from trajcomp.arm.parameters import apply_deltas
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc, pose_to_matrix
from trajcomp.calibration.calibrate import calibrate, to_base
from trajcomp.calibration.measurement_plan import default_orientation, plan_grid
from trajcomp.calibration.measurements import Measurements, read_measurements, write_measurements
from trajcomp.calibration.orientations import spread_orientations
from trajcomp.calibration import recalibrate
from trajcomp.calibration.virtual_arm import VirtualRobot
from trajcomp.cli import main
from trajcomp.model.model_file import load_model, save_model

TRACKER = pose_to_matrix([2400.0, -1300.0, 120.0, 0.3, -0.02, 0.01])  # first campaign's base in the tracker frame
MOVED = pose_to_matrix([-300.0, -3200.0, 200.0, -1.2, 0.01, -0.015])  # the tracker placed anew
DRIFT = {"theta2": np.radians(0.015), "theta3": np.radians(-0.01), "theta4": np.radians(0.02),
         "theta5": np.radians(-0.012), "tool_x": 0.3, "tool_y": -0.2, "tool_z": 0.5}
SCALE = 60e-6  # 2.6 K warmer, aluminium links


def scaled(robot, scale):
    """``robot`` (standard DH) with the a and d of links 1-5 times 1 + scale (the update's thermal scale)."""
    std = robot.as_standard()
    factor = np.where(np.arange(6) < 5, 1.0 + scale, 1.0)
    return std.replace(a=std.a * factor, d=std.d * factor)


def _measure(virtual, q, rng, T_tracker_base):
    """6-DoF tracker rows of commanded joints q, tracker frame."""
    poses = T_tracker_base @ virtual.measure_poses(q, rng)
    return Measurements(joints=q, position=fk(virtual.nominal, q)[:, :3, 3], measured=poses[:, :3, 3],
                        measured_orientation=matrix_to_abc(poses[:, :3, :3]), lines=np.arange(len(q)) + 2,
                        frame="tracker")


@pytest.fixture(scope="module")
def cell():
    """A model of the virtual UR10 (tool 150 mm, 5 orientations, 6-DoF, tracker frame), its drifted copy, candidates.

    The model is taken without the gp field calibrate puts on top of its joint residual here (an update offers its
    correction only to a model without a field on top, as of more rows than `GP_MAX_POINTS`)."""
    robot = load_robot("ur10").replace(T_flange_tool=pose_to_matrix([0.0, 0.0, 150.0, 0.0, 0.0, 0.0]))
    virtual = VirtualRobot.create(robot, "paper", seed=3)
    orientations = spread_orientations(default_orientation(robot), 5, np.radians(30.0))
    plan = plan_grid(robot, (300, -100, 300), 500, 125, orientations, one_posture=False)
    q = plan.joints[plan.reachable]
    model = calibrate(robot, _measure(virtual, q, np.random.default_rng(1), TRACKER), folds=0)
    model = dataclasses.replace(model, residual_field=None)
    true = apply_deltas(virtual.true_robot, list(DRIFT), list(DRIFT.values()))
    drifted = dataclasses.replace(virtual, true_robot=scaled(true, SCALE))
    return model, drifted, q


def _one_orientation(robot):
    """Joints (N, 6) of the model's grid at the one default tool orientation."""
    plan = plan_grid(robot, (300, -100, 300), 500, 125, one_posture=False)
    return plan.joints[plan.reachable]


def _rows(cell, count=30, seed=5):
    model, drifted, q = cell
    pick = recalibrate.choose_rows(model, q, count)[0]
    return _measure(drifted, q[pick], np.random.default_rng(seed), MOVED)


def test_the_update_recovers_the_drift_of_joint_zeros_scale_tool_and_tracker(cell):
    model, drifted, q = cell
    rows = _rows(cell)
    result = recalibrate.update(model, rows.joints, rows.position, rows.measured, abc_to_matrix(rows.measured_orientation))
    change = {n: v for n, v, _, _ in result.changes()}
    sigma = {n: s for n, _, s, _ in result.changes()}
    for name in ("theta2", "theta3", "theta4", "theta5"):
        assert change[name] == pytest.approx(np.degrees(DRIFT[name]), abs=0.003), name
        assert sigma[name] < 0.003
    for name in ("tool_x", "tool_y", "tool_z"):
        assert change[name] == pytest.approx(DRIFT[name], abs=0.05), name
    assert change["scale"] == pytest.approx(SCALE * 1e6, abs=25.0)  # ppm: about 1 K of aluminium
    assert sigma["scale"] < 10.0
    updated = result.model
    assert updated.report["update"]["applied"] == "update"
    record = updated.report["update"]  # the added uncertainty, from the model file alone, for the landing estimate
    added = recalibrate.update_sigma(updated, rows.joints)
    assert added.mean() == pytest.approx(record["added_sigma_mm"]["mean"], rel=1e-9)
    assert 0.0 < added.max() < 0.05
    assert not recalibrate.update_sigma(model, rows.joints).any()
    warm = dataclasses.replace(model, report={**model.report, "measurements": {
        **model.report["measurements"], "temperature_c": {"min": 22.9, "mean": 23.0, "max": 23.1}}})
    warmer = recalibrate.update(warm, rows.joints, rows.position, rows.measured,
                                abc_to_matrix(rows.measured_orientation), temperature=np.full(30, 25.6)).record()
    assert warmer["temperature_c"]["change"] == pytest.approx(2.6)
    assert warmer["scale_ppm_per_k"] == pytest.approx(change["scale"] / 2.6)
    moved = MOVED @ np.linalg.inv(TRACKER) @ model.T_tracker_base  # the model's registration, tracker moved
    np.testing.assert_allclose(updated.T_tracker_base[:3, 3], moved[:3, 3], atol=0.05)
    np.testing.assert_allclose(updated.T_tracker_base[:3, :3], moved[:3, :3], atol=5e-5)
    # the drifted arm, measured elsewhere: the update predicts it, the registration alone does not as well
    rest = _measure(drifted, q[::3], np.random.default_rng(9), MOVED)
    errors = {}
    for label, candidate in (("registered", result.registered.model), ("updated", updated)):
        seen = to_base(candidate.T_tracker_base, rest.measured)
        errors[label] = np.linalg.norm(seen - candidate.predict("composite", rest.joints, rest.position)[0], axis=1).mean()
    assert errors["updated"] < 0.03 < errors["registered"]
    assert result.verdict()[0] == "recalibrate"


def test_the_same_day_update_changes_nothing(cell):
    model, drifted, q = cell
    same_day = dataclasses.replace(drifted, true_robot=VirtualRobot.create(model.nominal, "paper", seed=3).true_robot)
    pick = recalibrate.choose_rows(model, q, 30)[0]
    rows = _measure(same_day, q[pick], np.random.default_rng(5), TRACKER)
    result = recalibrate.update(model, rows.joints, rows.position, rows.measured, abc_to_matrix(rows.measured_orientation))
    change = {n: v for n, v, _, _ in result.changes()}
    assert max(abs(change[f"theta{j}"]) for j in range(2, 6)) < 0.005  # deg
    assert max(abs(change[f"tool_{a}"]) for a in "xyz") < 0.03  # mm
    moved = np.linalg.norm(result.model.arm("composite").fk(q)[:, :3, 3] - model.arm("composite").fk(q)[:, :3, 3], axis=1)
    assert moved.mean() < 0.01
    assert result.verdict()[0] == "valid" and result.applied == "none" and result.correction is None
    np.testing.assert_array_equal(result.model.T_tracker_base, model.T_tracker_base)
    added = result.model.report["update"]["added_sigma_mm"]
    assert 0.0 < added["mean"] <= added["max"] < 0.02


def test_a_drift_no_parameter_holds_is_corrected_near_the_rows_and_the_correction_kept_in_the_file(cell, tmp_path):
    """The gear errors grew twofold between campaigns (a worn reducer): the joint zeros, scale, tool and tracker
    do not hold that; the kriging correction of the rows' residuals predicts the arm elsewhere better."""
    model, drifted, q = cell
    worn = dataclasses.replace(drifted, profile=dataclasses.replace(
        drifted.profile, gear_amplitude=2.0 * drifted.profile.gear_amplitude))
    rows = _measure(worn, q[recalibrate.choose_rows(model, q, 30)[0]], np.random.default_rng(5), MOVED)
    result = recalibrate.update(model, rows.joints, rows.position, rows.measured, abc_to_matrix(rows.measured_orientation))
    assert result.applied == "update" and result.correction is not None
    assert result.corrected.held_out.mean() < result.base.held_out.mean()  # why it was taken: the rows' regions
    record = result.model.report["update"]
    assert record["correction"] == {"kind": "kriging", "rows": 30, "length_mm": result.correction.length,
                                    "nugget": result.correction.nugget}
    assert record["corrected_mm"]["held_out"] < record["updated_mm"]["held_out"]
    assert f"{record['corrected_mm']['held_out']:.4f} mm with the correction" in record["verdict_reason"]
    rest = _measure(worn, q[1::3], np.random.default_rng(9), MOVED)  # configurations none of the rows is
    errors = {}
    for label, candidate in (("updated", result.base.model), ("corrected", result.model)):
        seen = to_base(candidate.T_tracker_base, rest.measured)
        errors[label] = np.linalg.norm(seen - candidate.predict("composite", rest.joints, rest.position)[0],
                                       axis=1).mean()
    assert errors["corrected"] < 0.9 * errors["updated"]
    save_model(tmp_path / "worn.yaml", result.model)
    again = load_model(tmp_path / "worn.yaml")
    np.testing.assert_allclose(again.predict("composite", rest.joints, rest.position)[0],
                               result.model.predict("composite", rest.joints, rest.position)[0], atol=1e-9)
    # a later update starts from the model without this campaign's correction, and fits its own
    later = recalibrate.update(again, rows.joints, rows.position, rows.measured, abc_to_matrix(rows.measured_orientation))
    assert later.as_is.model.residual_field is None


def test_the_cli_writes_the_updated_model_with_its_covariance_and_check_says_recalibrate(cell, tmp_path, capsys):
    model, _, _ = cell
    model_path, rows_path, out = tmp_path / "model.yaml", tmp_path / "rows.csv", tmp_path / "new.yaml"
    save_model(model_path, model)
    write_measurements(rows_path, _rows(cell))
    assert main(["recalibrate", str(model_path), str(rows_path), "--frame", "tracker", "-o", str(out)]) == 0
    shown = capsys.readouterr().out
    assert "theta3" in shown and "ppm" in shown and "re-calibrate" in shown
    updated = load_model(out)
    record = updated.report["update"]
    rows = read_measurements(rows_path)
    assert recalibrate.update_sigma(updated, rows.joints).mean() == pytest.approx(record["added_sigma_mm"]["mean"])
    names = record["names"]
    assert len(record["covariance"]) == len(names) and record["units"][names.index("scale")] == "ppm"
    assert record["units"][names.index("theta2")] == "deg"
    k = names.index("theta2")
    assert record["sigma"][k] == pytest.approx(np.sqrt(record["covariance"][k][k]))
    verdict = tmp_path / "check.json"
    assert main(["check", str(model_path), str(rows_path), "--frame", "tracker", "--json", str(verdict)]) == 1
    assert "re-calibrate" in capsys.readouterr().out
    written = json.loads(verdict.read_text())
    assert written["verdict"] == "recalibrate" and written["update"]["applied"] == "update"
    assert main(["check", str(out), str(rows_path), "--frame", "tracker"]) == 0
    assert "model still valid" in capsys.readouterr().out


def test_an_update_the_rows_cannot_support_is_refused_with_exit_2(cell, tmp_path, capsys):
    model, drifted, q = cell
    model_path = tmp_path / "model.yaml"
    save_model(model_path, model)
    one_orientation = _one_orientation(model.nominal)[:30]  # the tool's length along its one direction is not seen
    rows = _measure(drifted, one_orientation, np.random.default_rng(2), MOVED)
    rows = dataclasses.replace(rows, measured_orientation=None)
    write_measurements(tmp_path / "rows.csv", rows)
    assert main(["recalibrate", str(model_path), str(tmp_path / "rows.csv"), "--frame", "tracker",
                 "-o", str(tmp_path / "new.yaml")]) == 2
    error = capsys.readouterr().err
    assert "cannot identify" in error and "rows.csv" in error
    assert "base_z with tool_z" in error
    assert not (tmp_path / "new.yaml").exists()
    assert main(["check", str(model_path), str(tmp_path / "rows.csv"), "--frame", "tracker"]) == 1  # drifted
    shown = capsys.readouterr().out
    assert "no light update from these rows" in shown and "re-calibrate fully" in shown
    few = dataclasses.replace(rows.subset(np.arange(4)))
    write_measurements(tmp_path / "few.csv", few)
    assert main(["recalibrate", str(model_path), str(tmp_path / "few.csv"), "--frame", "tracker",
                 "-o", str(tmp_path / "new.yaml")]) == 2
    assert "too few" in capsys.readouterr().err


def test_plan_update_chooses_representative_rows_that_identify_the_update(cell, tmp_path, capsys):
    model, _, q = cell
    model_path, candidates = tmp_path / "model.yaml", tmp_path / "candidates.csv"
    save_model(model_path, model)
    write_measurements(candidates, Measurements(joints=q, lines=np.arange(len(q)) + 2))
    out = tmp_path / "update-plan.csv"
    assert main(["plan", "--update", str(model_path), "--candidates", str(candidates), "--poses", "-o", str(out)]) == 0
    assert "(representative)" in capsys.readouterr().err
    chosen = read_measurements(out).joints
    assert len(chosen) == 30 and all(np.isclose(q, row).all(axis=1).any() for row in chosen)
    position = fk(model.nominal, q)[:, :3, 3]

    def coverage(joints):  # mean distance of a candidate to the nearest chosen row, mm
        seen = fk(model.nominal, joints)[:, :3, 3]
        return np.linalg.norm(position[:, None] - seen[None], axis=2).min(axis=1).mean()

    rng = np.random.default_rng(0)
    assert coverage(chosen) < min(coverage(q[rng.choice(len(q), 30, replace=False)]) for _ in range(5))
    names = recalibrate.parameter_names(recalibrate.GROUPS, tracker=True, oriented=True)
    jac = recalibrate.design(model, q, names, oriented=True)

    def volume(rows):  # log det of the update's information: the D-optimality criterion
        picked = jac[rows].reshape(-1, len(names))
        return np.linalg.slogdet(picked.T @ picked)[1]

    optimal = volume(recalibrate._d_optimal(jac, 30))
    assert optimal > max(volume(rng.choice(len(q), 30, replace=False)) for _ in range(5))
    one_orientation = tmp_path / "one.csv"
    q = _one_orientation(model.nominal)
    write_measurements(one_orientation, Measurements(joints=q, lines=np.arange(len(q)) + 2))
    assert main(["plan", "--update", str(model_path), "--candidates", str(one_orientation), "-o", str(out)]) == 2
    assert "do not tell apart" in capsys.readouterr().err
