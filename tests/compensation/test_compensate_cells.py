"""Compensation as a cell engineer runs it (issue 35, section 3): the smaller items, each with a test."""

from importlib import resources

import pytest
import yaml

from tests.programs.test_programs_as_run import _stand_in
from trajcomp import formats
from trajcomp.arm.robot import load_robot
from trajcomp.cli import main
from trajcomp.compensation.program_rewrite import compensate_program
from trajcomp.errors import IKError


def test_demo_with_a_robot_file_makes_models_compensate_finds_the_arm_of(tmp_path, monkeypatch, capsys):
    """``demo --robot FILE.yaml`` names the file in its models, as ``calibrate`` does: ``compensate --robot
    FILE.yaml --model ..`` then loads the same arm (a bare name, not built in, was "unknown robot")."""
    monkeypatch.chdir(tmp_path)
    text = resources.files("trajcomp.arm.robots").joinpath("kuka_kr6_r900.yaml").read_text(encoding="utf-8")
    (tmp_path / "cell_kr6.yaml").write_text(text.replace("name: kuka_kr6_r900", "name: cell_kr6"))
    assert main(["demo", "--robot", "cell_kr6.yaml", "-o", "demo"]) == 0
    model = yaml.safe_load((tmp_path / "demo" / "model-large.yaml").read_text())
    assert model["robot"]["name"] == "cell_kr6" and model["robot"]["ref"] == "../cell_kr6.yaml"
    capsys.readouterr()
    assert main(["compensate", "demo/program.csv", "--robot", "cell_kr6.yaml", "--model", "demo/model-large.yaml",
                 "-o", "out.csv"]) == 0
    assert (tmp_path / "out.csv").exists() and "unknown robot" not in capsys.readouterr().err



def test_a_model_finds_its_robot_file_from_another_working_folder(tmp_path, monkeypatch, capsys):
    """The model names its robot file relative to the model's own folder: ``compensate`` run from another folder
    (or with the folder moved whole) loads the same arm, and ``--robot`` naming that file by another path is the
    model's robot. The model named it as typed, so from another folder it was "unknown robot ... no such file"."""
    cell = tmp_path / "cell"
    cell.mkdir()
    text = resources.files("trajcomp.arm.robots").joinpath("kuka_kr6_r900.yaml").read_text(encoding="utf-8")
    (cell / "cell_kr6.yaml").write_text(text.replace("name: kuka_kr6_r900", "name: cell_kr6"))
    monkeypatch.chdir(cell)
    assert main(["demo", "--robot", "cell_kr6.yaml", "-o", "demo"]) == 0
    assert yaml.safe_load((cell / "demo" / "model-large.yaml").read_text())["robot"]["ref"] == "../cell_kr6.yaml"
    moved = tmp_path / "moved"
    cell.rename(moved)
    monkeypatch.chdir(tmp_path)
    capsys.readouterr()
    assert main(["compensate", "moved/demo/program.csv", "--model", "moved/demo/model-large.yaml",
                 "-o", "out.csv"]) == 0
    assert main(["compensate", "moved/demo/program.csv", "--robot", str(moved / "cell_kr6.yaml"),
                 "--model", "moved/demo/model-large.yaml", "-o", "out2.csv"]) == 0
    assert "unknown robot" not in capsys.readouterr().err

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


FANUC_POSITION = ("P[{n}]{{\n   GP1:\n\tUF : 0, UT : 0,\t\tCONFIG : 'N U T, 0, 0, 0',\n"
                  "\tX =   {x:.3f}  mm,\tY =     0.000  mm,\tZ =   380.000  mm,\n"
                  "\tW =   180.000 deg,\tP =     0.000 deg,\tR =     0.000 deg\n}};\n")


def test_fanuc_register_motion_before_any_utool_num_is_said_so_not_computed_at_run_time(tmp_path, fanuc_model,
                                                                                        capsys):
    """``L PR[1]`` with no UTOOL_NUM / UFRAME_NUM before it: the register's value is known (POSREG.VA) but not
    the tool and frame it is in. The run's message gives that reason, not "positions computed at run time"."""
    (tmp_path / "POSREG.VA").write_text(
        "[*POSREG*]$POSREG  Storage: SHADOW  Access: RW  : ARRAY[1,100] OF Position Reg\n"
        "    [1,1] =   'APPROACH'   Group: 1   Config: N U T, 0, 0, 0\n"
        "  X:   380.000   Y:    20.000   Z:   400.000\n  W:   180.000   P:     0.000   R:     0.000\n\n")
    (tmp_path / "PICK.LS").write_text(
        "/PROG  PICK\n/ATTR\nOWNER\t\t= MNEDITOR;\n/MN\n   1:J P[1] 100% FINE    ;\n"
        "   2:L PR[1:APPROACH] 200mm/sec FINE    ;\n   3:L P[2] 100mm/sec FINE    ;\n/POS\n"
        + FANUC_POSITION.format(n=1, x=350) + FANUC_POSITION.format(n=2, x=400) + "/END\n")
    out = tmp_path / "out"
    out.mkdir()
    assert main(["compensate", str(tmp_path / "PICK.LS"), "--model", str(fanuc_model), "-o", str(out / "PICK.LS"),
                 "--retime", "none"]) == 1
    err = capsys.readouterr().err
    assert "positions computed at run time" not in err
    assert ("1 of 3 motions were not compensated (the first, line 6: PR[1] is a position in the tool and user frame "
            "active when the line runs: the program sets no UTOOL_NUM and UFRAME_NUM before it") in err
