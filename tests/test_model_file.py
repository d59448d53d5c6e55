"""The model file: YAML and grid sidecar written all or none, names that cannot collide, no non-finite number read."""

import numpy as np
import pytest
import yaml

from trajcomp.calibrate import calibrate
from trajcomp.errors import ModelError, WriteError
from trajcomp.measurements import Measurements
from trajcomp.model_file import load_model, save_model, sidecar_path
from trajcomp.plan import plan_grid
from trajcomp.robot import load_robot
from trajcomp.simulate import VirtualRobot


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
    (lambda doc: doc["linear"]["dx"].update(intercept=float("nan")), "linear correction"),
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
    with pytest.raises(ModelError, match=rf"array {key} holds values that are not finite"):
        load_model(path)
    sidecar_path(path).write_bytes(b"not a zip file")
    with pytest.raises(ModelError, match="cannot be read"):
        load_model(path)
