"""FANUC .LS and URScript readers and writers: constructs, configuration, errors."""

from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError
from trajcomp.transforms import abc_to_matrix, rotvec_to_matrix

DATA = Path(__file__).parent / "data" / "programs"


@pytest.fixture(scope="module")
def ls():
    return formats.read(DATA / "fanuc" / "PICK_PLACE.LS")


@pytest.fixture(scope="module")
def ur():
    return formats.read(DATA / "urscript" / "pick.script")


def _named(program, name):
    return [t.name for t in program.targets].index(name)


def test_fanuc_positions_frames_and_wpr(ls):
    p3 = ls.targets[_named(ls, "P[3]")]
    np.testing.assert_allclose(p3.pose[:3, 3], [400, -120.5, 120.25])
    # W, P, R = fixed X-Y-Z: R = Rz(R) Ry(P) Rx(W)
    np.testing.assert_allclose(p3.pose[:3, :3], abc_to_matrix(np.radians([90.0, 1.25, 179.5])))
    assert (p3.tool, p3.frame, p3.config) == ("2", "1", ("N", "U", "T", 0, 0, 0))
    assert ls.targets[_named(ls, "P[8]")].config == ("N", "D", "B", -1, 0, 0)
    assert ls.targets[_named(ls, "P[1]")].is_joint


def test_fanuc_motions(ls):
    by_line = {m.line: m for m in ls.motions}
    assert (by_line[25].speed, by_line[25].speed_unit) == (50.0, "%")
    assert by_line[27].zone == 50.0 and by_line[27].speed == 500.0
    circ = by_line[28]  # C P[4] with its continuation line
    assert (ls.targets[circ.via].name, ls.targets[circ.target].name) == ("P[4]", "P[5]")
    assert (by_line[35].speed, by_line[35].speed_unit) == (2.0, "s")
    assert {m.line for m in ls.runtime_motions()} == {30, 31}  # Offset,PR[1] and PR[2]


def test_fanuc_config_rewritten_only_when_changed(ls, tmp_path):
    i = _named(ls, "P[2]")
    edited = ls.with_targets([i], poses=[ls.targets[i].pose], configs=[("F", "U", "T", 0, 0, -1)])
    formats.write(tmp_path / "OUT.LS", edited)
    text = (tmp_path / "OUT.LS").read_text()
    assert "CONFIG : 'F U T, 0, 0, -1'" in text
    assert text.count("CONFIG : 'N U T, 0, 0, 0'") == 4
    assert "LINE_COUNT\t= 14;" in text


@pytest.mark.parametrize(
    "block, message",
    [
        ("\tX = 1.0 mm, Y = 2.0 mm,\n\tW = 0 deg, P = 0 deg, R = 0 deg", "P\\[1\\] lacks Z"),
        ("\tCONFIG : 'N U', X = 1 mm, Y = 2 mm, Z = 3 mm, W = 0 deg, P = 0 deg, R = 0 deg", "P\\[1\\]: malformed CONFIG"),
    ],
)
def test_fanuc_malformed_position(tmp_path, block, message):
    path = tmp_path / "BAD.LS"
    path.write_text(f"/PROG BAD\n/MN\n   1:L P[1] 100mm/sec FINE ;\n/POS\nP[1]{{\n   GP1:\n{block}\n}};\n/END\n")
    with pytest.raises(ReadError, match=rf"BAD\.LS:5: {message}: .P\[1\]"):
        formats.read(path)


def test_fanuc_motion_errors(tmp_path):
    path = tmp_path / "BAD.LS"
    path.write_text("/PROG BAD\n/MN\n   1:L P[7] 100mm/sec FINE ;\n/POS\n/END\n")
    with pytest.raises(ReadError, match=r"BAD\.LS:3: P\[7\] has no entry in /POS"):
        formats.read(path)
    path.write_text("/PROG BAD\n/MN\n   1:L P[1] FINE ;\n/POS\n/END\n")
    with pytest.raises(ReadError, match=r"BAD\.LS:3: motion needs a speed"):
        formats.read(path)


def test_ur_waypoints_units_and_qnear(ur):
    w1 = ur.targets[_named(ur, "Waypoint_1_p")]
    np.testing.assert_allclose(w1.pose[:3, 3], [456.1234, -120.3456, 350.1234])
    np.testing.assert_allclose(w1.pose[:3, :3], rotvec_to_matrix([-0.0012, 3.1403, 0.0399]))
    np.testing.assert_allclose(w1.joints, [-0.1946, -1.4835, 1.7977, -1.8919, -1.5703, -0.1947])
    np.testing.assert_allclose(ur.tools["set_tcp line 3"][:3, 3], [0, 0, 150.5])
    by_line = {m.line: m for m in ur.motions}
    assert ur.targets[by_line[11].target].is_joint  # movej(Home_q)
    assert by_line[10].zone == 5.0 and by_line[10].speed == 250.0
    inline = ur.targets[by_line[15].target]
    np.testing.assert_allclose(inline.joints, [0.5, -1.2, 1.4, -1.8, -1.57, 0.3])
    assert {m.line for m in ur.runtime_motions()} == {17, 18}


def test_ur_pose_and_joints_pairs_both_updated(ur, tmp_path):
    i = _named(ur, "Waypoint_1_p")
    q = np.array([[-0.2, -1.5, 1.8, -1.9, -1.5, -0.2]])
    pose = ur.targets[i].pose.copy()
    pose[:3, 3] += [1.0, 0.0, 0.0]
    formats.write(tmp_path / "pick.script", ur.with_targets([i], poses=[pose], joints=q))
    lines = (tmp_path / "pick.script").read_text().splitlines()
    assert lines[3] == "  global Waypoint_1_p=p[.4571234, -.1203456, .3501234, -0.0012, 3.1403, 0.0399]"
    assert lines[4] == "  global Waypoint_1_q=[-0.200000, -1.500000, 1.800000, -1.900000, -1.500000, -0.200000]"


def test_ur_malformed_pose(tmp_path):
    path = tmp_path / "bad.script"
    path.write_text("def bad():\n  movel(p[0.1, 0.2, 0.3], a=1)\nend\n")
    with pytest.raises(ReadError, match=r"bad\.script:2: malformed pose.*'movel\(p\[0\.1"):
        formats.read(path)


@pytest.mark.parametrize("suffix, other", [(".LS", "MODULE M\nENDMODULE\n"), (".script", "DEF p( )\nEND\n")])
def test_wrong_language_is_a_clear_error(tmp_path, suffix, other):
    path = tmp_path / f"p{suffix}"
    path.write_text(other)
    with pytest.raises(ReadError, match="not a (FANUC|URScript)"):
        formats.read(path)
