"""Compensation as a cell engineer runs it (issue 35, section 3): the smaller items, each with a test."""

from importlib import resources

import yaml

from trajcomp.cli import main


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
