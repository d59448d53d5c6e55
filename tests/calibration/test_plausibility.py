"""calibrate refuses data that cannot be what it claims; a single outlier does not stop it."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from trajcomp.calibration.calibrate import calibrate
from trajcomp.cli import main
from trajcomp.errors import CalibrationError
from trajcomp.arm.kinematics import fk
from trajcomp.calibration.measurements import Measurements, write_measurements
from trajcomp.model.model_file import save_model
from trajcomp.calibration.measurement_plan import plan_grid
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot


@pytest.fixture(scope="module")
def grid():
    """The paper's large cube measured on the virtual UR10 (216 points, one orientation)."""
    robot = load_robot("ur10")
    plan = plan_grid(robot, (300, -100, 300), 500, 100, one_posture=False)  # as the demo plans it
    virtual = VirtualRobot.create(robot, "paper", seed=1)
    meas = Measurements(joints=plan.joints, position=plan.position, lines=np.arange(len(plan.joints)) + 2,
                        measured=virtual.measure(plan.joints, np.random.default_rng(3)), path="grid.csv")
    return robot, meas


def test_measurements_in_metres_are_refused(grid):
    robot, meas = grid
    with pytest.raises(CalibrationError, match=r"grid.csv: the measured positions spread .* metres\?"):
        calibrate(robot, dataclasses.replace(meas, measured=meas.measured / 1000.0), grid_step=100, folds=0)


def test_joints_in_radians_read_as_degrees_are_refused(grid, tmp_path, capsys):
    robot, meas = grid
    path = tmp_path / "radians.csv"
    as_read = dataclasses.replace(meas, joints=np.radians(meas.joints), position=None)  # the file's numbers are rad
    write_measurements(path, as_read)
    assert main(["calibrate", str(path), "--robot", "ur10", "-o", str(tmp_path / "m.yaml")]) == 2
    assert "joints in radians read as degrees" in capsys.readouterr().err
    assert not (tmp_path / "m.yaml").exists()


def test_data_of_another_robot_is_refused(grid):
    _, meas = grid
    with pytest.raises(CalibrationError, match="another robot"):
        calibrate(load_robot("ur5"), dataclasses.replace(meas, position=None), folds=0)


def test_deltas_no_arm_has_are_refused(grid):
    """A link 30 mm longer than the data sheet: the fit would absorb it, but no UR10 is off by that much."""
    robot, meas = grid
    longer = robot.replace(a=robot.a + [0, -30.0, 0, 0, 0, 0])
    measured = fk(longer, meas.joints)[:, :3, 3]
    with pytest.raises(CalibrationError, match=r"identified a2 moves by -?(29\.9|30\.0)\d* mm, beyond the 20 mm"):
        calibrate(robot, dataclasses.replace(meas, measured=measured, position=None), folds=0)


@pytest.mark.parametrize("column, message", [
    (lambda m: np.column_stack([m[:, 0], m[:, 0], m[:, 2]]), "columns my and mx|columns mx and my"),
    (lambda m: np.column_stack([m[:, 0], m[:, 1], np.full(len(m), 812.5)]), "measured column mz is constant"),
])
def test_duplicated_or_constant_columns_are_refused(grid, column, message):
    robot, meas = grid
    with pytest.raises(CalibrationError, match=message):
        calibrate(robot, dataclasses.replace(meas, measured=column(meas.measured)), folds=0)


def test_measured_columns_equal_to_the_commanded_ones_are_refused(grid):
    robot, meas = grid
    with pytest.raises(CalibrationError, match="equal the commanded"):
        calibrate(robot, dataclasses.replace(meas, measured=meas.position.copy()), folds=0)


def test_a_single_5_mm_outlier_is_named_left_out_and_its_node_filled_from_the_model(grid):
    robot, meas = grid
    measured = meas.measured.copy()
    measured[40] += [5.0, 0.0, 0.0]
    model = calibrate(robot, dataclasses.replace(meas, measured=measured), grid_step=100, folds=0)
    assert model.report["outlier_lines"] == [42]
    assert any("lines [42]" in w for w in model.report["warnings"])
    node = meas.position[40:41]
    joints = meas.joints[40:41]
    dh = model.predict("dh", joints, node)[0]
    np.testing.assert_allclose(model.predict("composite", joints, node)[0], dh, atol=1e-9)  # residual node = model
    np.testing.assert_allclose(model.predict("grid", joints, node)[0], dh, atol=1e-9)  # raw-error node = model
    clean = calibrate(robot, meas, grid_step=100, folds=0)
    shift = np.abs(model.identified.a - clean.identified.a).max()
    assert shift < 0.01  # mm: the robust fit does not feel it


EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "programs"


@pytest.mark.parametrize("argv, named", [
    (["compensate", "ur/weld.script", "--model", "{model}", "-o", "{out}.script"],
     "a Universal Robots program (urscript) cannot run on robot kuka_kr6_r900 (KUKA), the arm of the model"),
    (["compensate", "csv/weld.csv", "--model", "{model}", "--robot", "ur10", "-o", "{out}.csv"],
     "--robot ur10: the model {model} is for robot kuka_kr6_r900"),
    (["compensate", "csv/weld.csv", "--model", "{model}", "-o", "{out}.csv"],  # its joints are a UR10's
     "put robot kuka_kr6_r900's TCP"),
    (["compensate", "csv/weld.csv", "--model", "{model}", "-o", "{out}.csv"], "they fit robot ur10"),
    (["retime", "kuka/weld.src", "--robot", "ur10", "-o", "{out}.src"],
     "a KUKA program (krl) cannot run on robot ur10 (Universal Robots), the arm --robot names"),
    (["convert", "csv/weld.csv", "{out}.ls", "--robot", "abb_irb4600"],
     "a FANUC program (fanuc_ls) cannot run on robot abb_irb4600 (ABB), the arm --robot names"),
])
def test_a_program_model_or_robot_of_another_arm_is_refused_naming_both(kuka_model, tmp_path, capsys, argv, named):
    """Today a KRL program compensated with a UR10 model passed (exit 0) with a 360 deg joint turn."""
    out = tmp_path / "out"
    argv = [a.format(model=kuka_model, out=out) for a in argv]
    argv[1] = str(EXAMPLES / argv[1])
    assert main(argv) == 2
    assert named.format(model=kuka_model) in capsys.readouterr().err
    assert not list(tmp_path.iterdir())  # nothing written


def test_a_csv_program_has_no_vendor_and_runs_on_the_models_arm(kuka_model, tmp_path):
    program = tmp_path / "p.csv"
    program.write_text("x,y,z,a,b,c,motion\n500,50,750,0,90,0,PTP\n520,50,750,0,90,0,LIN\n")
    assert main(["compensate", str(program), "--model", str(kuka_model), "--robot", "kuka_kr6_r900",
                 "--retime", "none", "-o", str(tmp_path / "out.csv")]) == 0


@pytest.mark.parametrize("command", ["validate", "predict"])
def test_validate_and_predict_refuse_data_of_another_robot(grid, kuka_model, tmp_path, capsys, command):
    """Today validate with another robot's model exited 1 with 1,436 mm errors and predict exited 0."""
    _, meas = grid
    data = tmp_path / "ur10.csv"
    write_measurements(data, meas)
    argv = [command, str(kuka_model), str(data)] + (["-o", str(tmp_path / "p.csv")] if command == "predict" else [])
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "ur10.csv: the commanded joints j1..j6 put robot kuka_kr6_r900's TCP a median" in err
    assert "data of another robot" in err
    assert not (tmp_path / "p.csv").exists()


def test_validate_refuses_measurements_in_metres(grid, tmp_path, capsys):
    robot, meas = grid
    model = calibrate(robot, meas, grid_step=100, folds=0)
    save_model(tmp_path / "m.yaml", model)
    data = tmp_path / "metres.csv"
    write_measurements(data, dataclasses.replace(meas, measured=meas.measured / 1000.0))
    assert main(["validate", str(tmp_path / "m.yaml"), str(data)]) == 2
    assert "metres?" in capsys.readouterr().err
