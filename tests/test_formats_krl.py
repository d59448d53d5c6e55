"""KUKA KRL reader and writer: constructs, S/T, errors."""

from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.configuration import kuka_status_turn
from trajcomp.errors import ReadError
from trajcomp.robot import load_robot
from trajcomp.transforms import abc_to_matrix

WELD = Path(__file__).parent / "data" / "programs" / "krl" / "weld.src"


@pytest.fixture(scope="module")
def weld():
    return formats.read(WELD)


def test_dat_points_inline_forms_and_state(weld):
    by_line = {m.line: m for m in weld.motions}
    ptp = by_line[27]
    assert (ptp.kind, weld.targets[ptp.target].name, ptp.tool, ptp.frame) == ("joint", "XP1", "1", "2")
    assert (ptp.speed, ptp.speed_unit) == (100.0, "%")
    lin = by_line[34]
    assert (lin.speed, lin.zone) == (200.0, 10.0)  # LDAT VEL 0.2 m/s, APO_DIST 10
    circ = by_line[38]
    assert weld.targets[circ.via].name == "XP3" and weld.targets[circ.target].name == "XP4"
    assert (circ.speed, circ.zone) == (100.0, 5.0)  # $VEL.CP = 0.1, $APO.CDIS = 5
    assert (by_line[43].tool, by_line[43].frame) == ("3", "0")  # BAS(#TOOL, 3), BAS(#BASE, 0)
    assert by_line[49].tool == "TOOL line 47"
    np.testing.assert_allclose(weld.tools["TOOL line 47"][:3, 3], [0, 0, 150])
    np.testing.assert_allclose(weld.frames["2"][:3, 3], [500, -200, 300])


def test_pose_units_and_euler_convention(weld):
    xp1 = weld.targets[[t.name for t in weld.targets].index("XP1")]
    np.testing.assert_allclose(xp1.pose[:3, 3], [612.503, -85.25, 702.0])
    np.testing.assert_allclose(xp1.pose[:3, :3], abc_to_matrix(np.radians([-179.998, 0.512, -180.0])))
    assert xp1.config == (2, 35)
    xp2 = weld.targets[[t.name for t in weld.targets].index("XP2")]
    assert xp2.config == (2, 35)  # 'B010', 'B100011'


def test_joint_targets_and_runtime_motions(weld):
    index, joints = weld.joint_targets()
    assert [weld.targets[i].label for i in index] == ["XJ1", "line 45"]
    np.testing.assert_allclose(np.degrees(joints[0]), [-12.5, -95, 100.25, 0, -35, 12])
    runtime = {m.line for m in weld.runtime_motions()}
    assert runtime == {20, 50, 51, 52}  # XHOME undefined, geometric operator, LIN_REL, XHOME


def test_status_turn_written_from_configuration(weld, tmp_path):
    robot = load_robot("kuka_kr6_r900")
    q = np.radians([[10, -80, 95, -5, 30, 20]])
    st = kuka_status_turn(robot, q)[0]
    assert st == (2, 10)  # A2 < 0: bit 1, A4 < 0: bit 3
    i = [t.name for t in weld.targets].index("XP2")
    edited = weld.with_targets([i], poses=[weld.targets[i].pose], configs=[st])
    formats.write(tmp_path / "weld.src", edited)
    dat = (tmp_path / "weld.dat").read_text(encoding="latin-1")
    assert "S 'B010',T 'B001010'" in dat  # the file's binary notation is kept


def _write(tmp_path, src, dat=None):
    (tmp_path / "p.src").write_text(src)
    if dat is not None:
        (tmp_path / "p.dat").write_text(dat)
    return tmp_path / "p.src"


def test_malformed_point_names_file_line_and_text(tmp_path):
    path = _write(tmp_path, "DEF p( )\nLIN XP1\nEND\n", "DEFDAT p\nDECL E6POS XP1={X 1,Y 2,Z ,A 0,B 0,C 0}\nENDDAT\n")
    with pytest.raises(ReadError, match=r"p\.dat:2: .*Z.*DECL E6POS XP1"):
        formats.read(path)


def test_malformed_inline_target(tmp_path):
    path = _write(tmp_path, "DEF p( )\nLIN {X 1,Y 2,Z 3}\nEND\n")
    with pytest.raises(ReadError, match=r"p\.src:2: point lacks A, B, C: 'LIN \{X 1,Y 2,Z 3\}'"):
        formats.read(path)


def test_motion_without_target(tmp_path):
    path = _write(tmp_path, "DEF p( )\nCIRC XP1\nEND\n")
    with pytest.raises(ReadError, match=r"p\.src:2: CIRC needs 2 target"):
        formats.read(path)


def test_wrong_language_is_a_clear_error(tmp_path):
    path = _write(tmp_path, "MODULE M\nPROC main()\nENDPROC\nENDMODULE\n")
    with pytest.raises(ReadError, match="not a KRL program"):
        formats.read(path)
