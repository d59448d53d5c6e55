"""The model file: YAML and grid sidecar written all or none, names that cannot collide, no non-finite number read."""

import numpy as np
import pytest
import yaml

from trajcomp.calibration.calibrate import calibrate
from trajcomp.errors import ModelError, WriteError
from trajcomp.calibration.measurements import Measurements
from trajcomp.model.model_file import load_model, save_model, sidecar_path
from trajcomp.calibration.measurement_plan import plan_grid
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot


def small_cube_model(seed):
    """A model whose 11^3-node grids go to a sidecar."""
    robot = load_robot("ur10")
    plan = plan_grid(robot, (500, 100, 500), 100, 10)
    virtual = VirtualRobot.create(robot, "paper", seed=seed)
    meas = Measurements(joints=plan.joints, position=plan.position, lines=np.arange(len(plan.joints)) + 2,
                        measured=virtual.measure(plan.joints, np.random.default_rng(seed)))
    return calibrate(robot, meas, grid_step=10, folds=0), plan


@pytest.fixture(scope="module")
def models():
    return small_cube_model(1), small_cube_model(2)


def test_two_models_of_one_stem_keep_their_own_sidecars(models, tmp_path):
    (first, plan), (second, _) = models
    save_model(tmp_path / "cell.yaml", first)
    save_model(tmp_path / "cell.yml", second)
    assert sidecar_path(tmp_path / "cell.yaml") != sidecar_path(tmp_path / "cell.yml")
    points, joints = plan.position[:20] + 3.0, plan.joints[:20]
    for name, model in (("cell.yaml", first), ("cell.yml", second)):
        back = load_model(tmp_path / name)
        np.testing.assert_allclose(back.predict("composite", joints, points)[0],
                                   model.predict("composite", joints, points)[0], atol=1e-12)


def test_a_model_file_name_that_is_not_yaml_is_refused(models, tmp_path):
    (first, _), _ = models
    with pytest.raises(ModelError, match=r"ends in \.yaml or \.yml"):
        save_model(tmp_path / "cell.npz", first)  # its sidecar would be the model itself
    assert not list(tmp_path.iterdir())


def test_yaml_and_sidecar_are_written_all_or_none(models, tmp_path):
    (first, _), (second, _) = models
    path = tmp_path / "cell.yaml"
    save_model(path, first)
    before = path.read_bytes(), sidecar_path(path).read_bytes()
    path.unlink()
    path.mkdir()  # the YAML cannot be put in place: the sidecar must not change either
    (path / "keep").write_text("x")
    with pytest.raises(WriteError):
        save_model(path, second)
    assert sidecar_path(path).read_bytes() == before[1]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cell.yaml", "cell.yaml.npz"]


@pytest.mark.parametrize("edit, message", [
    (lambda doc: doc["parameters"][0].update(delta=float("nan")), "parameters.delta: not finite"),
    (lambda doc: doc["parameters"][1].update(sigma=float("inf")), "parameters.sigma: not finite"),
    (lambda doc: doc.update(tracker_to_base=[0, 0, float("nan"), 0, 0, 0]), "tracker_to_base: not finite"),
    (lambda doc: doc["robot"].update(tool=[0, 0, float("inf"), 0, 0, 0]), "robot.tool: not finite"),
    (lambda doc: doc["linear"]["dx"].update(intercept=float("nan")), r"field linear\.dx\.intercept: nan is beyond"),
    (lambda doc: doc.update(sidecar="../elsewhere.npz"), "sidecar: '../elsewhere.npz' must be the name of a file"),
    (lambda doc: doc.update(sidecar="cell.yaml"), "must be the name of a file beside the model, not the model"),
])
def test_non_finite_numbers_and_unsafe_sidecars_in_a_model_file_are_refused(models, tmp_path, edit, message):
    (first, _), _ = models
    path = tmp_path / "cell.yaml"
    save_model(path, first)
    doc = yaml.safe_load(path.read_text())
    edit(doc)
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    with pytest.raises(ModelError, match=message):
        load_model(path)


def test_non_finite_values_in_a_sidecar_are_refused(models, tmp_path):
    (first, _), _ = models
    path = tmp_path / "cell.yaml"
    save_model(path, first)
    with np.load(sidecar_path(path)) as data:
        arrays = {k: data[k] for k in data.files}
    key = next(iter(arrays))
    arrays[key] = arrays[key].astype(float)
    arrays[key].flat[7] = np.inf
    with open(sidecar_path(path), "wb") as handle:
        np.savez(handle, **arrays)
    _name_sidecar_hash(path)  # a pair made by hand, consistent
    with pytest.raises(ModelError, match=rf"array {key} holds values that are not finite"):
        load_model(path)
    sidecar_path(path).write_bytes(b"not a zip file")
    _name_sidecar_hash(path)
    with pytest.raises(ModelError, match="cannot be read"):
        load_model(path)


def _name_sidecar_hash(path):
    """Have the model at ``path`` name the SHA-256 of the sidecar now beside it."""
    import hashlib

    text = path.read_text()
    digest = hashlib.sha256(sidecar_path(path).read_bytes()).hexdigest()
    path.write_text("\n".join(f"sidecar_sha256: {digest}" if line.startswith("sidecar_sha256:") else line
                              for line in text.splitlines()) + "\n")


def test_a_sidecar_of_another_calibration_or_not_a_file_is_refused(models, tmp_path):
    import os

    (first, _), (second, _) = models
    save_model(tmp_path / "a.yaml", first)
    save_model(tmp_path / "b.yaml", second)
    assert load_model(tmp_path / "a.yaml").grid is not None
    sidecar_path(tmp_path / "a.yaml").write_bytes(sidecar_path(tmp_path / "b.yaml").read_bytes())
    with pytest.raises(ModelError, match=r"a\.yaml\.npz is not the one written with this model \(calibration \w+\)"):
        load_model(tmp_path / "a.yaml")
    sidecar_path(tmp_path / "a.yaml").unlink()
    os.mkfifo(sidecar_path(tmp_path / "a.yaml"))  # reading it would block
    with pytest.raises(ModelError, match="is not a regular file"):
        load_model(tmp_path / "a.yaml")


def test_a_sidecar_unpacking_beyond_its_bound_is_refused_before_unpacking(models, tmp_path, monkeypatch):
    import trajcomp.model.model_file as model_file

    (first, _), _ = models
    save_model(tmp_path / "a.yaml", first)
    unpacked = sum(a.nbytes for a in np.load(sidecar_path(tmp_path / "a.yaml")).values())
    monkeypatch.setattr(model_file, "_SIDECAR_BYTES", unpacked - 1)  # the 1 GiB bound, scaled to this grid
    monkeypatch.setattr(np, "load", None)  # nothing may be unpacked
    with pytest.raises(ModelError, match="unpacks to .* bytes, more than a model's grid"):
        load_model(tmp_path / "a.yaml")


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("format: trajcomp-model/2", "format: trajcomp-model/2\nformat: trajcomp-model/2", 1),
     "found the key 'format' twice"),
    (lambda t: t.replace("tracker_to_base:", "tracker_to_base: [1.0e+300, 0, 0, 0, 0, 0]\nold_tracker_to_base:", 1),
     r"tracker_to_base: a translation beyond 100000 mm"),
    (lambda t: t.replace("delta: ", "delta: 1.0e+308 #", 1), r"parameters.delta: \w+ = 1e\+308 (mm|deg) is beyond"),
    (lambda t: "bomb: &b0 [0, 0, 0, 0, 0, 0, 0, 0, 0, 0]\n" + "".join(
        f"b{i}: &b{i} [{', '.join([f'*b{i - 1}'] * 10)}]\n" for i in range(1, 9)) + t.replace(
        "tracker_to_base:", "tracker_to_base: *b8\nold_tracker_to_base:", 1), "aliases expand to more than"),
])
def test_hostile_model_files_are_refused_quickly_with_a_short_message(models, tmp_path, edit, message):
    import time

    (first, _), _ = models
    path = tmp_path / "m.yaml"
    save_model(path, first)
    path.write_text(edit(path.read_text()))
    start = time.perf_counter()
    with pytest.raises(ModelError, match=message) as refused:
        load_model(path)
    assert time.perf_counter() - start < 2 and len(str(refused.value)) < 600
