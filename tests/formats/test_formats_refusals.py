"""Every writer refuses numbers that are not finite: robot code never receives nan or inf."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError, WriteError
from trajcomp.compensation.program_rewrite import convert_program

PATH = Path(__file__).parents[1] / "data" / "programs" / "csv" / "path.csv"


@pytest.mark.parametrize("suffix", [".csv", ".src", ".mod", ".ls", ".script"])
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_pose_is_refused_naming_the_target(tmp_path, suffix, bad):
    program = formats.read(PATH)
    converted = convert_program(program, formats.find_format(tmp_path / f"p{suffix}").name)
    pose = converted.targets[1].pose.copy()
    pose[0, 3] = bad
    broken = converted.with_targets([1], poses=[pose])
    # named by its line, with the file it came from where the program keeps it (CSV to CSV: path.csv)
    with pytest.raises(WriteError, match=r"target (path\.csv:4|line 4): pose not finite"):
        formats.write(tmp_path / f"p{suffix}", broken)
    assert not list(tmp_path.iterdir())


def test_patched_file_refuses_a_non_finite_edit(tmp_path):
    program = formats.read(PATH)
    pose = program.targets[0].pose.copy()
    pose[2, 3] = np.nan
    with pytest.raises(WriteError, match=r"target path\.csv:3: pose not finite"):
        formats.write(tmp_path / "out.csv", program.with_targets([0], poses=[pose]))
    assert not (tmp_path / "out.csv").exists()


def test_non_finite_speed_is_refused(tmp_path):
    program = formats.read(PATH)
    items = [dataclasses.replace(m, speed=np.inf) if getattr(m, "speed", None) else m for m in program.items]
    with pytest.raises(WriteError, match="line 4 .*speed not finite"):
        formats.write(tmp_path / "out.csv", program.replace(items=tuple(items)))


@pytest.mark.parametrize(
    "name, text, message",
    [
        ("p.csv", "x,y,z,a,b,c,j1,j2,j3,j4,j5,j6\n1,2,3,4,5,6,0,0,0,-100.05e301,0,0\n",
         r"p\.csv:2: field j4: '-100\.05e301' is out of range \(beyond \+-3600\)"),
        ("p.src", "DEF p( )\nLIN {X 2e6,Y 0,Z 0,A 0,B 0,C 0}\nEND\n", r"p\.src:2: X: '2e6' is out of range \(beyond \+-1e\+06\)"),
        ("s.script", "def s():\n  movej([0, 0, 70, 0, 0, 0])\nend\n", r"s\.script:2: list j3: '70' is out of range"),
        ("M.mod", "MODULE M\n  PROC main()\n    MoveAbsJ [[0,0,1e5,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]], v100, fine, tool0;\n"
         "  ENDPROC\nENDMODULE\n", r"M\.mod:3: jointtarget joint 3: '1e5' is out of range"),
        ("P.LS", "/PROG P\n/MN\n   1:L P[1] 100mm/sec FINE ;\n/POS\nP[1]{\n   GP1:\n\tUF : 0, UT : 1,\n"
         "\tX = 1.0 mm, Y = 2.0 mm, Z = 3.0 mm,\n\tW = 0 deg, P = 2e5 deg, R = 0 deg\n};\n/END\n",
         r"P\.LS:5: P\[1\] P: '2e5' is out of range \(beyond \+-10000\)"),
    ],
    ids=["csv joint", "krl position", "urscript joint", "rapid joint", "fanuc angle"],
)
def test_magnitudes_no_program_states_are_refused(tmp_path, name, text, message):
    """A joint beyond ten turns, a position beyond a kilometre: a typo or damage, refused by the reader."""
    (tmp_path / name).write_text(text)
    with pytest.raises(ReadError, match=message):
        formats.read(tmp_path / name)


def test_a_program_that_is_a_fifo_or_a_folder_is_named_as_such_not_as_missing(tmp_path):
    import os

    os.mkfifo(tmp_path / "pipe.src")
    (tmp_path / "dir.src").mkdir()
    with pytest.raises(ReadError, match=r"pipe\.src: is not a regular file \(a FIFO"):
        formats.read(tmp_path / "pipe.src")
    with pytest.raises(ReadError, match=r"dir\.src: is a folder"):
        formats.read(tmp_path / "dir.src")
    with pytest.raises(ReadError, match=r"gone\.src: no such file"):
        formats.read(tmp_path / "gone.src")


@pytest.mark.parametrize("again", ["P3", "p3", "  DECL E6POS P3"])
def test_a_krl_point_a_data_list_declares_twice_is_refused_as_the_controller_does(tmp_path, again):
    """Accepted before: the last declaration was corrected, the first left as written."""
    examples = Path(__file__).resolve().parents[2] / "examples" / "programs" / "kuka"
    (tmp_path / "weld.src").write_text((examples / "weld.src").read_text())
    declaration = again if again.strip().startswith("DECL") else f"DECL E6POS {again}"
    (tmp_path / "weld.dat").write_text((examples / "weld.dat").read_text().replace(
        "ENDDAT", f"{declaration}={{X 500.0,Y 0.0,Z 700.0,A 0.0,B 90.0,C 0.0,S 2,T 2}} ; again\nENDDAT"))
    with pytest.raises(ReadError, match=r"weld\.dat:7: P3 is declared again \(first at line 4\)".replace("P3", again.split()[-1])):
        formats.read(tmp_path / "weld.src")
