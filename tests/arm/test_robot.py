"""Robot YAML loading: the built-in arms and located errors for broken files."""

import math

import numpy as np
import pytest
import yaml

from trajcomp.errors import RobotError
from trajcomp.arm.robot import builtin_robot_names, load_robot, robot_from_yaml

UR5_DH = dict(
    a=[0, -425, -392.25, 0, 0, 0],
    d=[89.159, 0, 0, 109.15, 94.65, 82.3],
    alpha=[90, 0, 0, 90, -90, 0],
)


def test_builtin_names():
    assert {"ur5", "ur10", "kuka_kr6_r900", "abb_irb4600", "fanuc_lrmate200id"} <= set(builtin_robot_names())


@pytest.mark.parametrize("name", builtin_robot_names())
def test_every_builtin_robot_loads_consistently(name):
    robot = load_robot(name)
    assert robot.name == name
    assert robot.source
    assert robot.convention in ("standard", "modified")
    for field in ("a", "alpha", "d", "theta_offset", "q_min", "q_max", "v_max", "a_max", "j_max", "home"):
        values = getattr(robot, field)
        assert values.shape == (6,) and not np.any(np.isnan(values)), field
    assert np.all(robot.q_min < robot.q_max)
    assert np.all(robot.v_max > 0) and np.all(robot.a_max > 0) and np.all(robot.j_max > 0)
    assert robot.within_limits(robot.home).all()
    for frame in (robot.T_base_link0, robot.T_link6_flange, robot.T_flange_tool, robot.T_world_base):
        np.testing.assert_allclose(frame[:3, :3] @ frame[:3, :3].T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(robot.joint_angles(robot.dh_angles(robot.home)), robot.home, atol=1e-12)


def test_ur5_values_are_the_published_table_in_internal_units():
    robot = load_robot("ur5")
    np.testing.assert_allclose(robot.a, UR5_DH["a"])
    np.testing.assert_allclose(robot.d, UR5_DH["d"])
    np.testing.assert_allclose(robot.alpha, np.radians(UR5_DH["alpha"]))
    np.testing.assert_allclose(robot.q_max, np.full(6, 2 * math.pi))
    np.testing.assert_allclose(robot.v_max, np.full(6, math.pi))


def test_fanuc_joint_map_couples_j2_into_j3():
    robot = load_robot("fanuc_lrmate200id")
    theta = robot.dh_angles(np.radians([[0, 10, 20, 0, 0, 0]]))[0]
    # J3 is measured from the horizontal: the DH (relative) angle about +y is -(J2 + J3)
    np.testing.assert_allclose(np.degrees(theta[2]), -30.0)


def test_load_by_path(tmp_path):
    path = tmp_path / "arm.yaml"
    path.write_text(yaml.safe_dump(_document()))
    robot = load_robot(path)
    assert robot.name == "test_arm"
    np.testing.assert_allclose(robot.a, UR5_DH["a"])


def _document():
    """A valid robot document (UR5 numbers), to be broken by the tests."""
    return {
        "name": "test_arm",
        "source": "test",
        "dh": {"convention": "standard", **UR5_DH, "theta_offset": [0] * 6},
        "limits": {
            "position_min": [-360] * 6,
            "position_max": [360] * 6,
            "velocity": [180] * 6,
            "acceleration": [800] * 6,
        },
    }


def _broken(tmp_path, edit):
    doc = _document()
    edit(doc)
    path = tmp_path / "broken.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def _set(path, value):
    def edit(doc):
        *parents, last = path
        target = doc
        for key in parents:
            target = target[key]
        target[last] = value

    return edit


def _delete(path):
    def edit(doc):
        *parents, last = path
        target = doc
        for key in parents:
            target = target[key]
        del target[last]

    return edit


@pytest.mark.parametrize(
    "edit, field",
    [
        (_set(("dh", "a"), [0, -425, -392.25, 0, 0]), "dh.a"),
        (_set(("dh", "d"), [89.159, 0, float("nan"), 109.15, 94.65, 82.3]), "dh.d[2]"),
        (_set(("dh", "alpha"), [90, 0, "zero", 90, -90, 0]), "dh.alpha[2]"),
        (_set(("dh", "convention"), "distal"), "dh.convention"),
        (_set(("limits", "position_min"), [-360, 400, -360, -360, -360, -360]), "limits"),
        (_set(("limits", "position_max"), [360, 360, 360, 360, -400, 360]), "limits"),
        (_set(("limits", "velocity"), [180, 180, -1, 180, 180, 180]), "limits.velocity"),
        (_delete(("limits", "acceleration")), "limits.acceleration"),
        (_delete(("dh",)), "dh"),
        (_delete(("name",)), "name"),
        (_set(("joints",), {"direction": [1, 1, 2, 1, 1, 1]}), "joints.direction"),
        (_set(("base",), [0, 0, 0, 0, 0]), "base"),
    ],
)
def test_broken_file_names_file_and_field(tmp_path, edit, field):
    path = _broken(tmp_path, edit)
    with pytest.raises(RobotError) as info:
        load_robot(path)
    message = str(info.value)
    assert str(path) in message
    assert f"field {field}" in message


def test_min_above_max_names_the_joint(tmp_path):
    path = _broken(tmp_path, _set(("limits", "position_max"), [360, -365, 360, 360, 360, 360]))
    with pytest.raises(RobotError, match="joint 2 position_min -360 deg is not below position_max -365 deg"):
        load_robot(path)


def test_malformed_yaml_names_the_file(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("name: x\ndh: [unclosed\n")
    with pytest.raises(RobotError, match=f"{path}: not valid YAML"):
        load_robot(path)


def test_top_level_must_be_a_mapping(tmp_path):
    path = tmp_path / "list.yaml"
    path.write_text("- 1\n- 2\n")
    with pytest.raises(RobotError, match=str(path)):
        load_robot(path)


def test_unknown_name_lists_the_builtin_robots():
    with pytest.raises(RobotError, match="unknown robot 'kuka_kr1000'.*ur5"):
        load_robot("kuka_kr1000")


def test_numbers_no_arm_has_are_refused_with_a_short_message():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "trajcomp" / "arm" / "robots" / "ur10.yaml").read_text()
    huge = text.replace("a: [", "a: [1.0e+308, ", 1).replace("a: [1.0e+308, 0,", "a: [1.0e+308,", 1)
    with pytest.raises(RobotError, match=r"x\.yaml: field dh\.a\[0\]: 1e\+308 is beyond the 100000 of any arm"):
        robot_from_yaml(huge, "x.yaml")
    listed = text.replace("name:", "name: [" + ", ".join(["1"] * 5000) + "]\nold_name:", 1)
    with pytest.raises(RobotError, match=r"field name: expected a non-empty text, got a list of 5000 items$"):
        robot_from_yaml(listed, "x.yaml")
