"""What a controller backup declares, read as the controller reads it (issue 35, section 2).

- KUKA: ``TOOL_DATA[n]``, ``BASE_DATA[n]`` (and ``LOAD_DATA[n]``) of
  ``R1/System/$config.dat``, for a program in ``R1/Program`` or a folder of it;
- KRL ``DECL CONST E6POS/POS/FRAME`` in a data list;
- FANUC ``$MNUFRAME`` / ``$MNUTOOL`` of SYSFRAME.VA.

Each program is written by hand in the form the controllers hold. The poses
handed to the correction are checked against the frames composed here with
scipy from the numbers written in the files.
"""

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.programs.test_programs_as_run import OFFSET, _stand_in
from trajcomp import formats
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot
from trajcomp.compensation.program_rewrite import compensate_program
from trajcomp.errors import TrajcompError
from trajcomp.formats.configuration import configuration_data, configuration_for

TOOL = [12.5, -3.0, 185.2, 0.0, 90.0, 0.0]  # KUKA X, Y, Z, A, B, C (mm, deg)
BASE = [150.0, -220.0, 110.5, 90.0, 0.0, 0.0]
JOINTS = ([0.0, -90.0, 90.0, 0.0, 45.0, 0.0], [10.0, -85.0, 95.0, 5.0, 40.0, 10.0])


def _kuka_pose(x, y, z, a, b, c):
    """T (4, 4) of a KUKA frame: R = Rz(A) Ry(B) Rx(C), by scipy."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("ZYX", [a, b, c], degrees=True).as_matrix()
    T[:3, 3] = x, y, z
    return T


def _fanuc_pose(x, y, z, w, p, r):
    """T (4, 4) of a FANUC frame: R = Rz(R) Ry(P) Rx(W) (fixed X-Y-Z), by scipy."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", [w, p, r], degrees=True).as_matrix()
    T[:3, 3] = x, y, z
    return T


def _recording(robot):
    """The stand-in correction (`OFFSET`), recording the base-frame poses and tools it is given."""
    stand_in, seen = _stand_in(robot), {}

    def correct(T, tools, seeds, names):
        seen["T"], seen["tools"] = T.copy(), tools.copy()
        return stand_in(T, tools, seeds, names)

    return correct, seen


def _krl_points(robot, tool, base):
    """``X .., S .., T ..`` members of points at `JOINTS` with tool ``tool`` in base ``base`` (KUKA pose lists)."""
    T_world_tcp = fk(robot, np.radians(JOINTS)) @ _kuka_pose(*tool)
    local = np.linalg.inv(_kuka_pose(*base)) @ T_world_tcp
    status = configuration_for(configuration_data("krl"), robot, np.radians(JOINTS))
    out = []
    for T, (s, t) in zip(local, status):
        a, b, c = Rotation.from_matrix(T[:3, :3]).as_euler("ZYX", degrees=True)
        out.append(f"X {T[0, 3]:.4f},Y {T[1, 3]:.4f},Z {T[2, 3]:.4f},A {a:.5f},B {b:.5f},C {c:.5f},S {s},T {t}")
    return out, T_world_tcp


def _frame_text(values):
    return "{" + ",".join(f"{k} {v}" for k, v in zip("XYZABC", values)) + "}"


def _backup(tmp_path, robot, selects="$TOOL=TOOL_DATA[2]\n$BASE=BASE_DATA[8]\n"):
    """KRC/R1/Program/Cell/weld.src selecting tool 2 and base 8 that R1/System/$config.dat declares."""
    program, system = tmp_path / "KRC" / "R1" / "Program" / "Cell", tmp_path / "KRC" / "R1" / "System"
    program.mkdir(parents=True)
    system.mkdir()
    (system / "$config.dat").write_text(
        "&ACCESS RVO\nDEFDAT  $CONFIG\n;FOLD TOOL/BASE DATA\n"
        f"TOOL_DATA[1]={_frame_text([0, 0, 100, 0, 0, 0])}\nTOOL_DATA[2]={_frame_text(TOOL)}\n"
        'TOOL_NAME[2,]="TORCH"\nTOOL_TYPE[2]=#NONE\n'
        f"BASE_DATA[8]={_frame_text(BASE)}\n"
        "LOAD_DATA[1]={M -1.0,CM {X 0.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0},J {X 0.0,Y 0.0,Z 0.0}}\n"
        "LOAD_DATA[2]={M 5.5,CM {X 1.0,Y 2.0,Z 63.0,A 0.0,B 0.0,C 0.0},J {X 0.1,Y 0.2,Z 0.3}}\n"
        ";ENDFOLD\nENDDAT\n", newline="\r\n")
    points, T_world_tcp = _krl_points(robot, TOOL, BASE)
    (program / "weld.dat").write_text(
        f"DEFDAT  WELD\nDECL E6POS XP1={{{points[0]}}}\nDECL E6POS XP2={{{points[1]}}}\nENDDAT\n", newline="\r\n")
    (program / "weld.src").write_text(f"DEF weld( )\n{selects}$VEL.CP=0.2\nPTP XP1\nLIN XP2\nEND\n",
                                      newline="\r\n")
    return program / "weld.src", T_world_tcp


def test_krl_tool_and_base_of_config_dat_are_read_for_a_program_deep_in_the_backup(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    src, T_world_tcp = _backup(tmp_path, robot)
    program = formats.read(src)
    correct, seen = _recording(robot)
    edited, report = compensate_program(program, correct, robot)
    # the correction gets the world poses the controller moves to, with TOOL_DATA[2] as the tool
    np.testing.assert_allclose(seen["T"], T_world_tcp, atol=1e-3)
    np.testing.assert_allclose(seen["tools"], np.broadcast_to(_kuka_pose(*TOOL), (2, 4, 4)), atol=1e-12)
    # the report names where the values come from, and the load that goes with tool 2
    note = " ".join(program.notes)
    assert "../../System/$config.dat" in note and "TOOL_DATA[2] (line 5)" in note and "BASE_DATA[8] (line 8)" in note
    assert "LOAD_DATA[2] 5.5 kg" in note and "TOOL_DATA[1]" not in note
    # the points move by the world offset expressed in base 8 (turned 90 deg about z)
    formats.write(src, edited)
    moved = [np.array(m.groups(), float) for m in re.finditer(r"X ([-\d.]+),Y ([-\d.]+),Z ([-\d.]+)",
                                                               src.with_suffix(".dat").read_text())]
    assert len(moved) == 2
    expected = _kuka_pose(*BASE)[:3, :3].T @ OFFSET
    original = [np.array(m.groups(), float) for m in re.finditer(
        r"X ([-\d.]+),Y ([-\d.]+),Z ([-\d.]+)", "".join(_krl_points(robot, TOOL, BASE)[0]))]
    for after, was in zip(moved, original):
        np.testing.assert_allclose(after - was, expected, atol=2e-4)


def test_krl_config_dat_load_of_the_default_and_selection_by_bas(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    src, T_world_tcp = _backup(tmp_path, robot, selects="BAS(#TOOL,2)\nBAS(#BASE,8)\n")
    program = formats.read(src)
    correct, seen = _recording(robot)
    compensate_program(program, correct, robot)
    np.testing.assert_allclose(seen["T"], T_world_tcp, atol=1e-3)
    src.write_text(src.read_text().replace("BAS(#TOOL,2)", "BAS(#TOOL,1)"))
    note = " ".join(formats.read(src).notes)
    assert "LOAD_DATA[1] M -1.0: the default load of the machine data" in note


def test_krl_program_own_tool_data_wins_over_config_dat_and_a_missing_one_is_named(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    src, _ = _backup(tmp_path, robot)
    src.write_text(src.read_text().replace("$TOOL=TOOL_DATA[2]", "TOOL_DATA[2]={X 0,Y 0,Z 50,A 0,B 0,C 0}\r\n"
                                                                "$TOOL=TOOL_DATA[2]"))
    program = formats.read(src)
    np.testing.assert_allclose(program.tools["2"][:3, 3], [0, 0, 50])
    assert "TOOL_DATA[2]" not in " ".join(program.notes) and "BASE_DATA[8]" in " ".join(program.notes)
    (src.parents[2] / "System" / "$config.dat").unlink()  # no backup around it: the controller's value is unknown
    with pytest.raises(TrajcompError, match="frame '8' is used but not defined"):
        compensate_program(formats.read(src), _stand_in(robot), robot)


def test_krl_config_dat_entry_cut_short_is_refused_with_file_line_and_field(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    src, _ = _backup(tmp_path, robot)
    config = src.parents[2] / "System" / "$config.dat"
    config.write_text(config.read_text().replace("TOOL_DATA[2]={X 12.5,Y -3.0,Z 185.2,A 0.0,B 90.0,C 0.0}",
                                                 "TOOL_DATA[2]={X 12.5,Y -3.0,Z 185.2,A 0.0,B 90.0}"))
    with pytest.raises(TrajcompError, match=r"\$config\.dat:5: point lacks C"):
        formats.read(src)


# ------------------------------------------------------------------ KRL constants in data lists


def test_krl_const_points_of_a_data_list_are_points(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    points, T_world_tcp = _krl_points(robot, [0] * 6, [0] * 6)
    (tmp_path / "cell.dat").write_text(
        f"DEFDAT CELL\nDECL CONST E6POS XP1={{{points[0]}}}\nDECL GLOBAL CONST POS XP2={{{points[1]}}}\n"
        "DECL CONST FRAME XF={X 0.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0}\nENDDAT\n")
    (tmp_path / "cell.src").write_text("DEF cell( )\n$VEL.CP=0.2\nPTP XP1\nLIN XP2\nEND\n")
    program = formats.read(tmp_path / "cell.src")
    assert [program.where(m.target) for m in program.motions] == ["XP1 (cell.dat:2)", "XP2 (cell.dat:3)"]
    correct, seen = _recording(robot)
    edited, _ = compensate_program(program, correct, robot)
    np.testing.assert_allclose(seen["T"], T_world_tcp, atol=1e-3)
    formats.write(tmp_path / "cell.src", edited)
    text = (tmp_path / "cell.dat").read_text()
    assert "DECL CONST E6POS XP1={X" in text and "DECL GLOBAL CONST POS XP2={X" in text  # kept constants
    assert text.splitlines()[1] != f"DECL CONST E6POS XP1={{{points[0]}}}"  # and corrected


def test_krl_const_point_of_another_data_list_is_read_where_declared(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    points, _ = _krl_points(robot, [0] * 6, [0] * 6)
    (tmp_path / "table.dat").write_text(f"DEFDAT TABLE PUBLIC\nDECL GLOBAL CONST E6POS XT={{{points[0]}}}\nENDDAT\n")
    (tmp_path / "cell.src").write_text("DEF cell( )\nPTP XT\nEND\n")
    (tmp_path / "cell.dat").write_text("DEFDAT CELL\nENDDAT\n")
    program = formats.read(tmp_path / "cell.src")
    assert [program.where(m.target) for m in program.motions] == ["XT (table.dat:2)"]


# ------------------------------------------------------------------ FANUC SYSFRAME.VA

UFRAME = [850.0, -420.5, 35.0, 0.0, 0.0, 90.0]  # X, Y, Z, W, P, R
UTOOL = [5.0, 0.0, 112.0, 0.0, -30.0, 0.0]


def _sysframe(uframes, utools):
    """A SYSFRAME.VA listing as a controller saves it (group 1 only)."""
    def entries(values):
        out = ""
        for n, v in values.items():
            if v is None:
                out += f"    [1,{n}] = 'SPARE' Uninitialized\n"
                continue
            out += (f"    [1,{n}] = 'F{n}'  Group: 1\n  Config: N D B, 0, 0, 0\n"
                    f"  X: {v[0]:9.3f}   Y: {v[1]:9.3f}   Z: {v[2]:9.3f}\n"
                    f"  W: {v[3]:9.3f}   P: {v[4]:9.3f}   R: {v[5]:9.3f}\n")
        return out

    return ("[*SYSTEM*]$MNUFRAME  Storage: SHADOW  Access: RW  : ARRAY[2,9] OF POSITION\n" + entries(uframes)
            + "    [2,1] = \n  Group: 2\n  X: 9999.000 Y: 0.000 Z: 0.000\n  W: 0.000 P: 0.000 R: 0.000\n"
            "[*SYSTEM*]$MNUFRAMENUM  Storage: CMOS  Access: RW  : ARRAY[2] OF BYTE\n  [1] = 1\n  [2] = 0\n"
            "[*SYSTEM*]$MNUTOOL  Storage: SHADOW  Access: RW  : ARRAY[2,10] OF POSITION\n" + entries(utools))


def _fanuc_program(robot, folder, frame="1", tool="3"):
    """PROG.LS with two positions in UF ``frame`` / UT ``tool`` reached at `JOINTS`."""
    T_world_tcp = fk(robot, np.radians(JOINTS)) @ _fanuc_pose(*UTOOL)
    local = np.linalg.inv(_fanuc_pose(*UFRAME)) @ T_world_tcp
    configs = configuration_for(configuration_data("fanuc_ls"), robot, np.radians(JOINTS))
    positions = ""
    for n, (T, config) in enumerate(zip(local, configs), start=1):
        w, p, r = Rotation.from_matrix(T[:3, :3]).as_euler("xyz", degrees=True)
        flip, up, top, *turns = config
        positions += (f"P[{n}]{{\n   GP1:\n\tUF : {frame}, UT : {tool},\t\tCONFIG : '{flip} {up} {top}, "
                      f"{', '.join(map(str, turns))}',\n\tX = {T[0, 3]:10.3f}  mm,\tY = {T[1, 3]:10.3f}  mm,\t"
                      f"Z = {T[2, 3]:10.3f}  mm,\n\tW = {w:10.3f} deg,\tP = {p:10.3f} deg,\tR = {r:10.3f} deg\n}};\n")
    (folder / "PROG.LS").write_text(
        f"/PROG  PROG\n/ATTR\nOWNER\t\t= MNEDITOR;\n/MN\n   1:  UFRAME_NUM={frame} ;\n   2:  UTOOL_NUM={tool} ;\n"
        f"   3:J P[1] 100% FINE    ;\n   4:L P[2] 100mm/sec FINE    ;\n/POS\n{positions}/END\n")
    return folder / "PROG.LS", T_world_tcp


def test_fanuc_user_frame_and_tool_of_sysframe_va_are_read(tmp_path):
    robot = load_robot("fanuc_lrmate200id")
    backup = tmp_path / "MD"
    (backup / "programs").mkdir(parents=True)
    (backup / "SYSFRAME.VA").write_text(_sysframe({1: UFRAME, 2: None}, {1: [0, 0, 50, 0, 0, 0], 3: UTOOL}))
    path, T_world_tcp = _fanuc_program(robot, backup / "programs")  # the backup's listing in the folder above
    program = formats.read(path)
    correct, seen = _recording(robot)
    compensate_program(program, correct, robot)
    np.testing.assert_allclose(seen["T"], T_world_tcp, atol=2e-3)  # positions written to 0.001 mm
    np.testing.assert_allclose(seen["tools"], np.broadcast_to(_fanuc_pose(*UTOOL), (2, 4, 4)), atol=1e-9)
    note = " ".join(program.notes)
    assert "../SYSFRAME.VA" in note and "UFRAME 1 (line 2)" in note and "UTOOL 3" in note and "UTOOL 1" not in note


def test_fanuc_uninitialized_user_frame_is_not_a_value(tmp_path):
    robot = load_robot("fanuc_lrmate200id")
    (tmp_path / "SYSFRAME.VA").write_text(_sysframe({1: UFRAME, 2: None}, {3: UTOOL}))
    path, _ = _fanuc_program(robot, tmp_path, frame="2")
    program = formats.read(path)
    assert "SYSFRAME.VA holds no value for UFRAME 2 (uninitialized, line 6)" in " ".join(program.notes)
    with pytest.raises(TrajcompError, match="frame '2' is used but not defined"):
        compensate_program(program, _stand_in(robot), robot)
