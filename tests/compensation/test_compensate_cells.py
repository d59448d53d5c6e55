"""Compensation as a cell engineer runs it (issue 35, section 3): the smaller items, each with a test."""

from importlib import resources

import pytest
import yaml

from tests.programs.test_programs_as_run import _stand_in
from trajcomp import formats
from trajcomp.arm.robot import load_robot
from trajcomp.cli import main
from trajcomp.compensation.program import compensate_program
from trajcomp.errors import IKError


def test_demo_with_a_robot_file_makes_models_compensate_finds_the_arm_of(tmp_path, monkeypatch, capsys):
    """``demo --robot FILE.yaml`` names the file in its models, as ``calibrate`` does: ``compensate --robot
    FILE.yaml --model ..`` then loads the same arm (a bare name, not built in, was "unknown robot")."""
    monkeypatch.chdir(tmp_path)
    text = resources.files("trajcomp.arm.robots").joinpath("kuka_kr6_r900.yaml").read_text(encoding="utf-8")
    (tmp_path / "cell_kr6.yaml").write_text(text.replace("name: kuka_kr6_r900", "name: cell_kr6"))
    assert main(["demo", "--robot", "cell_kr6.yaml", "-o", "demo"]) == 0
    model = yaml.safe_load((tmp_path / "demo" / "model-large.yaml").read_text())
    assert model["robot"]["name"] == "cell_kr6" and model["robot"]["ref"] == "cell_kr6.yaml"
    capsys.readouterr()
    assert main(["compensate", "demo/program.csv", "--robot", "cell_kr6.yaml", "--model", "demo/model-large.yaml",
                 "-o", "out.csv"]) == 0
    assert (tmp_path / "out.csv").exists() and "unknown robot" not in capsys.readouterr().err


def test_a_task_s_messages_name_the_module_that_moves_the_arm_not_a_data_module_before_it(tmp_path):
    """BData.mod (tooldata only) sorts before ZMain.mod (the motions): a refusal names ZMain and the point's file."""
    (tmp_path / "BData.mod").write_text(
        "MODULE BData\n  PERS tooldata tGun:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,50],[1,0,0,0],0,0,0]];\nENDMODULE\n")
    (tmp_path / "ZMain.mod").write_text(
        "MODULE ZMain\n  CONST robtarget p10:=[[9000,100,900],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
        "  PROC main()\n    MoveJ p10,v1000,z10,tGun;\n  ENDPROC\nENDMODULE\n")
    program = formats.read_task([tmp_path / "BData.mod", tmp_path / "ZMain.mod"])
    assert program.name == "ZMain"
    robot = load_robot("abb_irb4600")
    with pytest.raises(IKError, match=r"^ZMain: 1 targets cannot be reached .* \(p10 \(ZMain\.mod:2\)"):
        compensate_program(program, _stand_in(robot), robot)
