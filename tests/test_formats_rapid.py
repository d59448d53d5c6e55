"""ABB RAPID reader and writer: declarations, moves, frames, confdata, errors."""

from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError
from trajcomp.transforms import quat_to_matrix

WELDING = Path(__file__).parent / "data" / "programs" / "rapid" / "Welding.mod"


@pytest.fixture(scope="module")
def welding():
    return formats.read(WELDING)


def _target(program, name):
    return program.targets[[t.name for t in program.targets].index(name)]


def test_declarations_tools_and_work_objects(welding):
    start = _target(welding, "pStart")
    np.testing.assert_allclose(start.pose[:3, 3], [100, 50, 2.5])
    np.testing.assert_allclose(start.pose[:3, :3], quat_to_matrix([-4.37114e-08, 0.707107, 0.707107, -4.37114e-08]), atol=1e-6)
    assert start.config == (-1, 0, -1, 1)
    assert _target(welding, "pVia").config == (0, -1, 0, 0)  # declaration over two lines
    np.testing.assert_allclose(welding.tools["tGun"][:3, 3], [12.5, -3, 245.75])
    table = welding.frames["wTable"]  # uframe * oframe
    np.testing.assert_allclose(table[:3, 3], [800 - 20, -300 + 10, 250], atol=1e-6)
    np.testing.assert_allclose(np.degrees(_target(welding, "jHome").joints), [0, 0, 0, 0, 30, 0])


def test_moves(welding):
    by_line = {m.line: m for m in welding.motions}
    assert welding.targets[by_line[21].target].name == "jHome"  # \NoEOffs ignored
    circ = by_line[24]
    assert (welding.targets[circ.via].name, welding.targets[circ.target].name) == ("pVia", "pEnd")
    assert (circ.speed, circ.zone, circ.tool, circ.frame) == (12.5, 1.0, "tGun", "wTable")
    assert (by_line[27].zone, by_line[27].tool, by_line[27].frame) == (7.5, "tool0", "wobj0")
    assert by_line[28].frame == "wFixture" and by_line[28].speed is None  # custom speeddata
    assert welding.targets[by_line[29].target].name == "pApproach"  # \Conc
    assert welding.targets[by_line[30].target].is_joint
    assert {m.line for m in welding.runtime_motions()} == {25, 26, 31}  # Offs, RelTool, CRobT
    assert [t.name for t in welding.unused_targets()] == ["pUnused"]


def test_confdata_and_quaternion_sign_are_written(welding, tmp_path):
    start = _target(welding, "pStart")
    index = [t.name for t in welding.targets].index("pStart")
    turned = start.pose.copy()
    turned[:3, :3] = quat_to_matrix([0.0, 0.6, 0.8, 0.0])
    formats.write(tmp_path / "W.mod", welding.with_targets([index], poses=[turned], configs=[(0, 1, -2, 3)]))
    line = (tmp_path / "W.mod").read_text().splitlines()[10]
    assert line == (
        "    CONST robtarget pStart:=[[100.0,50.0,2.5],[0.00000000,0.60000000,0.80000000,0.00000000],"
        "[0,1,-2,3],[9E9,9E9,9E9,9E9,9E9,9E9]];"
    )


@pytest.mark.parametrize(
    "line, message",
    [
        ("CONST robtarget p1:=[[1,2],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];", "malformed robtarget"),
        ("CONST jointtarget j1:=[[1,2,3,4,5],[9E9,9E9,9E9,9E9,9E9,9E9]];", "malformed jointtarget"),
        ("MoveL p1, v100, z10;", "MoveL needs 4 arguments"),
        ("MoveL [[1,2,3],[1,0,0,0]], v100, z10, tool0;", "malformed robtarget"),
    ],
)
def test_malformed_statements_name_file_line_and_text(tmp_path, line, message):
    path = tmp_path / "M.mod"
    path.write_text(f"MODULE M\n  PROC main()\n    {line}\n  ENDPROC\nENDMODULE\n")
    with pytest.raises(ReadError, match=rf"M\.mod:3: {message}: '"):
        formats.read(path)


def test_wrong_language_is_a_clear_error(tmp_path):
    path = tmp_path / "p.mod"
    path.write_text("DEF p( )\nPTP HOME\nEND\n")
    with pytest.raises(ReadError, match="not a RAPID module"):
        formats.read(path)
