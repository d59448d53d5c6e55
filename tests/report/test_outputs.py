"""Every command's outputs checked against its inputs: an input is never overwritten, whatever its name."""

import json
import os
import shutil
from pathlib import Path

import pytest

from trajcomp.cli import main

ROOT = Path(__file__).resolve().parents[2]
KUKA = ROOT / "examples" / "programs" / "kuka"
ROBOT = ROOT / "trajcomp" / "arm" / "robots" / "kuka_kr6_r900.yaml"


@pytest.fixture
def cell(tmp_path, kuka_model):
    """A folder with a model (and a hard link to it), a plan, its measurements, a layout file and a KRL program."""
    shutil.copy(kuka_model, tmp_path / "model.yaml")
    os.link(tmp_path / "model.yaml", tmp_path / "linked.yaml")
    shutil.copy(ROBOT, tmp_path / "robot.yaml")
    for name in ("weld.src", "weld.dat"):
        shutil.copy(KUKA / name, tmp_path / name)
    (tmp_path / "layout.yaml").write_text("columns: {}\n")
    assert main(["plan", "--robot", "kuka_kr6_r900", "--cube", "400,-50,650", "--side", "100", "--step", "50",
                 "-o", str(tmp_path / "plan.csv")]) == 0
    assert main(["simulate", str(tmp_path / "plan.csv"), "--robot", "kuka_kr6_r900", "-o",
                 str(tmp_path / "meas.csv")]) == 0
    shutil.copy(tmp_path / "meas.csv", tmp_path / "meas.json")  # a measurement file named as a report would be
    return tmp_path


COMMANDS = {  # a command line (files in the cell's folder) whose output is one of its inputs
    "plan": "plan --robot robot.yaml --cube 400,-50,650 --side 100 --step 50 -o robot.yaml",
    "simulate": "simulate plan.csv --robot kuka_kr6_r900 -o plan.csv",
    "calibrate": "calibrate meas.csv --robot kuka_kr6_r900 --columns-file layout.yaml -o layout.yaml",
    "predict (model)": "predict model.yaml plan.csv -o model.yaml",
    "predict (link)": "predict model.yaml plan.csv -o linked.yaml",
    "validate --json": "validate model.yaml meas.csv --json meas.csv",
    "validate --report": "validate model.yaml meas.json --report meas",  # meas.json and meas.html
    "compensate": "compensate weld.src --model model.yaml -o weld.src",
    "compensate --summary": "compensate weld.src weld.src --model model.yaml -o batch --summary weld.src",
    "convert": "convert weld.src weld.src",
    "retime": "retime weld.src --robot kuka_kr6_r900 -o weld.src",
}


@pytest.mark.parametrize("command", COMMANDS)
def test_an_output_over_an_input_is_refused_and_nothing_changes(cell, command, capsys, monkeypatch):
    monkeypatch.chdir(cell)
    before = {p.name: p.read_bytes() for p in cell.iterdir()}
    assert main(COMMANDS[command].split()) == 2
    assert "would overwrite the input" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in cell.iterdir()} == before


def test_in_place_replaces_the_program_it_reads(cell, capsys, monkeypatch):
    monkeypatch.chdir(cell)
    assert main(["retime", "weld.src", "--robot", "kuka_kr6_r900", "-o", "weld.src", "--in-place"]) in (0, 1)
    assert "wrote weld.src, weld.dat" in capsys.readouterr().err


def _kuka_csv():
    """The cell's weld.src as a CSV program (its targets with the KR6's joints), as text."""
    main(["convert", "weld.src", "kuka-weld.csv", "--robot", "kuka_kr6_r900"])  # exit 1: a speed left to set
    return Path("kuka-weld.csv").read_text()


def test_a_file_name_with_glob_characters_is_that_file(cell, capsys, monkeypatch):
    monkeypatch.chdir(cell)
    program = _kuka_csv()
    Path("p[1].csv").write_text(program)
    Path("p1.csv").write_text(program)
    code = main(["compensate", "p[1].csv", "--model", "model.yaml", "-o", "p[1]-comp.csv"])
    assert code in (0, 1) and Path("p[1]-comp.csv").is_file()  # a file, not a batch folder
    assert not Path("p1-comp.csv").exists()


def test_a_report_that_cannot_be_written_after_the_program_is_exit_1_naming_the_program(cell, capsys, monkeypatch):
    monkeypatch.chdir(cell)
    assert main(["compensate", "weld.src", "--model", "model.yaml", "-o", "out.src", "--report", "none/r",
                 "--json-only", "--retime", "none"]) == 1
    err = capsys.readouterr().err
    assert "the program is written (out.src, out.dat) but not its report" in err and "none" in err
    assert Path("out.src").exists()
    Path("batch/reports").mkdir(parents=True)
    Path("batch/reports/weld.src.json").mkdir()  # a folder where the report goes: it cannot be written
    Path("weld.csv").write_text(_kuka_csv())
    assert main(["compensate", "weld.src", "weld.csv", "--model",
                 "model.yaml", "-o", "batch", "--jobs", "1", "--report", "batch/reports", "--json-only", "--retime", "none"]) == 1
    files = {Path(f["input"]).name: f for f in json.loads(Path("batch/summary.json").read_text())["files"]}
    assert files["weld.src"]["status"] == "fail" and files["weld.src"]["outputs"] == ["batch/weld.src", "batch/weld.dat"]
