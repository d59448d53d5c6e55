"""The Python API (trajcomp.api): poses, paths and program files through a model, checked on the virtual arm.

References: the virtual UR10 the model was calibrated on (where the TCP
really lands for the returned joints), the closed-form IK branches of the
nominal arm (the posture a hint names), scipy's rotations (the x, y, z, a, b,
c form) and the same targets stated in another frame or form.
"""

import logging
import os
import runpy
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from virtual_cell import landing_error, virtual_cell

import trajcomp
import trajcomp.compensation.target_correction as compensation
from trajcomp import api, formats
from trajcomp.errors import CompensationError, IKError, ModelError, TrajcompError, WriteError
from trajcomp.arm.ik import configuration_of, ik_all
from trajcomp.arm.kinematics import fk

ROOT = Path(__file__).resolve().parents[1]
POSE = np.array([550.0, 100.0, 550.0, 90.0, 0.0, 180.0])  # inside the calibrated cube, the measured orientation
LANDED = 0.03  # mm: a compensated target in the calibrated posture lands within this
MISSED = 0.5  # mm: the uncompensated target misses by more


def matrix(xyzabc):
    """T (4, 4) of x, y, z (mm) and A, B, C (deg, intrinsic Z-Y'-X''), with scipy."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("ZYX", xyzabc[3:], degrees=True).as_matrix()
    T[:3, 3] = xyzabc[:3]
    return T


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    return virtual_cell(tmp_path_factory)


@pytest.fixture(scope="module")
def comp(cell):
    return trajcomp.Compensator(cell.model_path)


@pytest.fixture(scope="module")
def branches(cell):
    """Nominal joints (deg) of POSE on every branch the UR10 reaches it with: {branch index: q}."""
    q, valid = ik_all(cell.robot, matrix(POSE)[None])
    return {b: np.degrees(q[0, b]) for b in range(8) if valid[0, b]}


def test_the_command_lands_on_the_target_where_the_plan_misses(cell, comp, branches):
    hint = branches[3]  # the branch the grid was measured in (nearest home at the cube's centre)
    command, joints, correction = comp.filter_target(POSE, joints_hint=hint)
    assert landing_error(cell, joints, matrix(POSE))[0] < LANDED
    assert landing_error(cell, hint, matrix(POSE))[0] > MISSED
    # the pose sent is the nominal pose of the joints returned, and the correction is command - target
    np.testing.assert_allclose(fk(cell.robot, np.radians(joints)), matrix(command), atol=1e-6)
    np.testing.assert_allclose(correction[:3], command[:3] - POSE[:3], atol=1e-9)
    rotation = Rotation.from_euler("ZYX", command[3:], degrees=True) * Rotation.from_euler("ZYX", POSE[3:], degrees=True).inv()
    np.testing.assert_allclose(correction[3:], rotation.as_rotvec(degrees=True), atol=1e-9)


def test_the_hint_chooses_branch_and_turns(cell, comp, branches):
    for branch, q in branches.items():
        hint = q + 3.0  # a few degrees off, as a planner's joints for a nearby pose
        _, joints, _ = comp.filter_target(POSE, joints_hint=hint)
        assert configuration_of(cell.robot, np.radians(joints)).index == branch
        assert np.abs(joints - q).max() < 1.0, (branch, joints, q)
    turned = branches[3] - [0, 0, 0, 0, 0, 360.0]  # the UR wrist turns +-360 deg: a hint one turn back
    _, joints, _ = comp.filter_target(POSE, joints_hint=turned)
    assert abs(joints[5] - turned[5]) < 1.0
    with pytest.raises(TrajcompError, match=r"J6 = 387.358 deg is outside the limits"):  # no arm is there
        comp.filter_target(POSE, joints_hint=branches[3] + [0, 0, 0, 0, 0, 360.0])


def test_without_a_hint_each_pose_follows_the_one_before(cell, comp):
    path = np.array([POSE + [dx, dx / 2, -dx, 0, 0, 0] for dx in np.linspace(0, 150, 6)])
    result = comp.filter_targets(path)
    assert result.report.posture_source == ("home",) + ("previous",) * 5
    assert np.abs(np.diff(result.joints, axis=0)).max() < 20.0  # no branch or turn switch along the path
    assert landing_error(cell, result.joints, np.array([matrix(p) for p in path])).max() < LANDED


def test_a_path_in_one_call_equals_pose_by_pose(comp, branches):
    path = np.array([matrix(POSE + [dx, -dx, dx / 3, 0, 0, 0]) for dx in (0, 40, 80)])
    hints = np.array([branches[3] + k for k in range(3)])
    together = comp.filter_targets(path, joints_hint=hints)
    assert together.poses.shape == (3, 4, 4) and together.joints.shape == (3, 6)
    for k in range(3):
        command, joints, correction = comp.filter_target(path[k], joints_hint=hints[k])
        np.testing.assert_allclose(together.poses[k], command, atol=1e-9)
        np.testing.assert_allclose(together.joints[k], joints, atol=1e-9)
        np.testing.assert_allclose(together.correction[k], correction, atol=1e-9)


def test_a_long_path_on_two_processes_equals_one(cell, comp, monkeypatch):
    monkeypatch.setattr(compensation, "CHUNK", 8)  # several chunks for the workers to share
    path = np.array([POSE + [dx, -dx / 2, dx / 3, 0, 0, 0] for dx in np.linspace(0.0, 90.0, 40)])
    one = comp.filter_targets(path)
    two = trajcomp.Compensator(cell.model, workers=2).filter_targets(path)
    np.testing.assert_array_equal(two.poses, one.poses)
    np.testing.assert_array_equal(two.joints, one.joints)
    assert landing_error(cell, one.joints, [matrix(p) for p in path]).max() < LANDED
    for bad in (0, 1.5, True):
        with pytest.raises(TrajcompError, match="workers: expected a whole number"):
            trajcomp.Compensator(cell.model, workers=bad)


def test_a_pose_in_a_user_frame_and_its_form(comp, branches):
    frame = np.array([200.0, -50.0, 100.0, 30.0, 0.0, 0.0])
    in_frame = np.linalg.inv(matrix(frame)) @ matrix(POSE)
    command_f, joints_f, correction_f = comp.filter_target(in_frame, frame=frame, joints_hint=branches[3])
    command_b, joints_b, correction_b = comp.filter_target(matrix(POSE), joints_hint=branches[3])
    np.testing.assert_allclose(matrix(frame) @ command_f, command_b, atol=1e-9)
    np.testing.assert_allclose(joints_f, joints_b, atol=1e-9)
    np.testing.assert_allclose(correction_f, correction_b, atol=1e-9)
    command_v, _, _ = comp.filter_target(POSE, joints_hint=branches[3])  # x, y, z, a, b, c in, same out
    assert command_v.shape == (6,)
    np.testing.assert_allclose(matrix(command_v), command_b, atol=1e-9)
    assert np.all(np.abs(command_v[3:] - POSE[3:]) < 1.0)  # C near the given 180 (180.08), not -179.92


def test_the_calibrated_tool_given_explicitly_is_the_default(comp, branches, caplog):
    default = comp.filter_target(POSE, joints_hint=branches[3])
    explicit = comp.filter_target(POSE, tool=np.zeros(6), joints_hint=branches[3])
    for a, b in zip(default, explicit):
        np.testing.assert_allclose(a, b, atol=1e-9)
    with caplog.at_level(logging.WARNING, logger="trajcomp"):
        comp.filter_target(POSE, tool=[0, 0, 100, 0, 0, 0], joints_hint=branches[3])
    assert "tool other than the calibrated TCP" in caplog.text


def test_outside_the_grid_is_flagged_logged_or_refused(cell, comp, branches, caplog):
    outside = POSE + [0, 0, 300, 0, 0, 0]  # above the cube
    with caplog.at_level(logging.WARNING, logger="trajcomp"):
        result = comp.filter_targets([POSE, outside])
    assert result.outside_grid.tolist() == [False, True]
    assert "1 of 2 targets lie outside the compensation grid" in caplog.text
    with pytest.raises(ModelError):
        trajcomp.Compensator(cell.model, outside="error").filter_target(outside)


def test_what_cannot_be_right_is_refused(cell, comp, branches):
    with pytest.raises(IKError, match="leave the programmed posture"):
        trajcomp.Compensator(cell.model, max_joint_change=0.001).filter_target(POSE, joints_hint=branches[3])
    with pytest.raises(CompensationError, match="exceed 0.1 mm"):
        trajcomp.Compensator(cell.model, max_correction=0.1).filter_target(POSE, joints_hint=branches[3])
    with pytest.raises(IKError, match="pose 1"):
        comp.filter_target(POSE + [3000, 0, 0, 0, 0, 0])  # out of reach
    with pytest.raises(IKError, match=r"weld P7 \(line 2\)"):  # the caller's names for its poses
        comp.filter_targets([POSE, POSE + [3000, 0, 0, 0, 0, 0]], names=["weld P6", "weld P7"])
    with pytest.raises(TrajcompError, match="names: 1 names for 2 poses"):
        comp.filter_targets([POSE, POSE], names=["P1"])
    skewed = matrix(POSE)
    skewed[0, 0] += 0.01
    with pytest.raises(TrajcompError, match="not a rigid transform"):
        comp.filter_target(skewed)
    with pytest.raises(TrajcompError, match="pose: expected"):
        comp.filter_target(POSE[:5])
    with pytest.raises(TrajcompError, match="joints_hint"):
        comp.filter_target(POSE, joints_hint=[0, 0, np.nan, 0, 0, 0])
    with pytest.raises(ModelError, match="not available"):
        trajcomp.Compensator(cell.model, mode="grid_typo")


def test_a_program_file_is_compensated_and_written(cell, comp, tmp_path):
    program = tmp_path / "path.csv"
    shutil.copy(ROOT / "examples" / "ur10_path.csv", program)
    run = comp.filter_program(program)
    out, report = run.written[0], run.report
    assert out == tmp_path / "path_compensated.csv"
    original, corrected = formats.read(program), formats.read(out)
    targets = original.cartesian_targets().T
    joints = np.degrees(np.array([t.joints for t in corrected.targets]))
    assert landing_error(cell, joints, targets).max() < LANDED
    assert len(report.labels) == len(targets) and not report.not_compensated
    with pytest.raises(WriteError, match="would overwrite the input"):
        comp.filter_program(program, program)
    before = program.read_bytes()
    assert comp.filter_program(program, program, in_place=True).written == (program,)
    assert program.read_bytes() != before


def test_a_batch_of_program_files_is_compensated_as_each_alone_with_a_summary(cell, comp, tmp_path):
    """The API's batch: the files of a folder mirrored into another, each as `filter_program` writes it alone, a
    broken file refused without stopping the others, and the summary the command line writes."""
    import json

    folder = tmp_path / "in"
    (folder / "cell").mkdir(parents=True)
    shutil.copy(ROOT / "examples" / "ur10_path.csv", folder / "a.csv")
    shutil.copy(ROOT / "examples" / "ur10_path.csv", folder / "cell" / "b.csv")
    (folder / "broken.csv").write_text("x,y,z,a,b,c\n1,2\n")
    results, summary = trajcomp.filter_programs([folder], tmp_path / "out", model=cell.model_path, retime="none")
    status = {Path(r.input).name: r.status for r in results}
    assert status["broken.csv"] == "error" and status["a.csv"] == status["b.csv"] != "error"
    alone = comp.filter_program(folder / "a.csv", tmp_path / "alone.csv", retime="none").written[0]
    for written in (tmp_path / "out" / "a.csv", tmp_path / "out" / "cell" / "b.csv"):
        assert written.read_bytes() == alone.read_bytes()
    assert not (tmp_path / "out" / "broken.csv").exists()
    doc = json.loads(summary.read_text())
    assert summary == tmp_path / "out" / "summary.json" and doc["schema"] == "trajcomp-batch/1"
    assert sorted(Path(f["input"]).name for f in doc["files"]) == ["a.csv", "b.csv", "broken.csv"]

def test_module_functions_load_a_model_file_once_per_version(cell, tmp_path, branches):
    path = tmp_path / "model.yaml"
    shutil.copy(cell.model_path, path)
    first = api.compensator(path)
    assert api.compensator(str(path)).model is first.model
    stat = path.stat()
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000))
    assert api.compensator(path).model is not first.model
    command, joints, _ = trajcomp.filter_target(POSE, joints_hint=branches[3], model=path)
    np.testing.assert_allclose(command, first.filter_target(POSE, joints_hint=branches[3])[0], atol=1e-12)
    with pytest.raises(TypeError, match="belong to the Compensator"):
        api.compensator(first, mode="dh")
    with pytest.raises(TrajcompError, match="missing.yaml: cannot read"):
        api.compensator(tmp_path / "missing.yaml")


def test_importing_trajcomp_does_not_import_the_api():
    code = "import sys, trajcomp; print('trajcomp.api' in sys.modules); trajcomp.Compensator; print('trajcomp.api' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**os.environ, "PYTHONPATH": str(ROOT)}).stdout.split()
    assert out == ["False", "True"]


@pytest.mark.parametrize("example", ["01_filter_target.py", "02_filter_program.py"])
def test_the_examples_run(cell, example, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [example, str(cell.model_path)])
    runpy.run_path(str(ROOT / "examples" / example), run_name="__main__")
    out = capsys.readouterr().out
    assert "correction" in out or "targets compensated" in out
