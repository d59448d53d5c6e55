"""Every writer refuses numbers that are not finite: robot code never receives nan or inf."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import WriteError
from trajcomp.postprocess import convert_program

PATH = Path(__file__).parent / "data" / "programs" / "csv" / "path.csv"


@pytest.mark.parametrize("suffix", [".csv", ".src", ".mod", ".ls", ".script"])
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_pose_is_refused_naming_the_target(tmp_path, suffix, bad):
    program = formats.read(PATH)
    converted = convert_program(program, formats.find_format(tmp_path / f"p{suffix}").name)
    pose = converted.targets[1].pose.copy()
    pose[0, 3] = bad
    broken = converted.with_targets([1], poses=[pose])
    with pytest.raises(WriteError, match=r"target line 4: pose not finite"):
        formats.write(tmp_path / f"p{suffix}", broken)
    assert not list(tmp_path.iterdir())


def test_patched_file_refuses_a_non_finite_edit(tmp_path):
    program = formats.read(PATH)
    pose = program.targets[0].pose.copy()
    pose[2, 3] = np.nan
    with pytest.raises(WriteError, match="target line 3: pose not finite"):
        formats.write(tmp_path / "out.csv", program.with_targets([0], poses=[pose]))
    assert not (tmp_path / "out.csv").exists()


def test_non_finite_speed_is_refused(tmp_path):
    program = formats.read(PATH)
    items = [dataclasses.replace(m, speed=np.inf) if getattr(m, "speed", None) else m for m in program.items]
    with pytest.raises(WriteError, match="line 4 .*speed not finite"):
        formats.write(tmp_path / "out.csv", program.replace(items=tuple(items)))
