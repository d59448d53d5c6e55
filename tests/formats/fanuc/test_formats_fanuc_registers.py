"""FANUC position registers (issue 22): ``PR[n]`` motions resolved from the backup's POSREG.VA.

The real files are a spot-welding cell's backup (tests/data/programs/real/fanuc/ub10200, SOURCES.txt);
the other POSREG.VA listings here are HAND-WRITTEN fixtures in the layout of that real file, for the
cases it does not hold (a register the program sets, ``PR[R[n]]=``, a register not taught).
"""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.programs.test_programs_as_run import OFFSET, _stand_in
from trajcomp import formats
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import matrix_to_pose
from trajcomp.compensation.program_rewrite import compensate_program
from trajcomp.errors import WriteError
from trajcomp.formats.configuration import configuration_data, configuration_for
from trajcomp.formats.task import groups

BACKUP = Path(__file__).parents[2] / "data" / "programs" / "real" / "fanuc" / "ub10200"


def _wpr_pose(x, y, z, w, p, r):
    """T (4, 4) of a FANUC position: R = Rz(r) Ry(p) Rx(w), stated independently of trajcomp's transforms."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("ZYX", [r, p, w], degrees=True).as_matrix()
    T[:3, 3] = x, y, z
    return T


def test_a_real_backup_s_register_is_read_from_its_posreg_va_and_registers_set_at_run_time_are_listed():
    program = formats.read(BACKUP / "_masterpos.ls")
    assert [(s.name, s.companion) for s in program.sources] == [("_masterpos.ls", False), ("posreg.va", True)]
    (motion,) = [m for m in program.motions if "PR[254" in m.text]
    assert program.where(motion.target) == "PR[254] (posreg.va:315)"
    register = program.targets[motion.target]
    # posreg.va:315-318: [1,254] 'MasterPSN', Config: N U T, 0, 0, 0, X 1322.445 Y 924.767 Z 194.152 W 18.349 ...
    np.testing.assert_allclose(register.pose, _wpr_pose(1322.445, 924.767, 194.152, 18.349, 8.021, 91.743),
                               atol=1e-9)
    assert register.config == ("N", "U", "T", 0, 0, 0)
    assert (motion.tool, motion.frame) == ("1", "0")  # UTOOL_NUM=1, UFRAME_NUM=0 before it (a PR states neither)
    # PR[1] is set by another program of the backup (homeub10200rbt01.ls line 23: PR[1:@Home]=JPOS)
    assert program.not_compensated() == (
        (48, "26:J PR[1:@Home] 100% FINE ;", "position register PR[1] is set at run time "
                                             "(homeub10200rbt01.ls:23, PR[1:@Home]=JPOS)"),
        (66, "44:J PR[1:@Home] 100% FINE ;", "position register PR[1] is set at run time "
                                             "(homeub10200rbt01.ls:23, PR[1:@Home]=JPOS)"))
    assert program.notes[0].startswith("position registers PR[254] are read from posreg.va")
    # a register the program itself sets (opensgg2.ls line 32), and one a motion offsets at run time
    assert formats.read(BACKUP / "opensgg2.ls").not_compensated()[0][2] == (
        "position register PR[25] is set at run time (line 32, PR[25:MAX GUN OPENING]=JPOS)")
    reasons = {reason for _, _, reason in formats.read(BACKUP / "td_gun1.ls").not_compensated()}
    assert "Tool_Offset applied at run time" in reasons
    # a program none of whose registers is read does not take posreg.va along: a batch runs each program alone
    assert [s.name for s in formats.read(BACKUP / "opensgg2.ls").sources] == ["opensgg2.ls"]
    assert groups(sorted(BACKUP.glob("*.ls"))) == [[0], [1], [2], [3]]


def test_a_corrected_register_is_written_into_the_posreg_va_beside_the_output_and_nothing_else(tmp_path):
    program = formats.read(BACKUP / "_masterpos.ls")
    (i,) = [m.target for m in program.motions if "PR[254" in m.text]
    moved = program.targets[i].pose.copy()
    moved[:3, 3] += [0.25, -0.5, 1.0]
    written = formats.write(tmp_path / "_masterpos.ls", program.with_targets([i], poses=moved[None]))
    assert sorted(p.name for p in written) == ["_masterpos.ls", "posreg.va"]
    assert (tmp_path / "_masterpos.ls").read_bytes() == (BACKUP / "_masterpos.ls").read_bytes()
    before = (BACKUP / "posreg.va").read_bytes().split(b"\r\n")
    after = (tmp_path / "posreg.va").read_bytes().split(b"\r\n")  # CRLF kept
    assert [k + 1 for k, (a, b) in enumerate(zip(before, after)) if a != b] == [317] and len(after) == len(before)
    assert after[316] == b"  X:  1322.695   Y:   924.267   Z:   195.152"
    # all or none: the register file cannot be written, so the program is not written either
    (tmp_path / "out" / "posreg.va").mkdir(parents=True)
    with pytest.raises(WriteError):
        formats.write(tmp_path / "out" / "_masterpos.ls", program.with_targets([i], poses=moved[None]))
    assert not (tmp_path / "out" / "_masterpos.ls").exists()


# ------------------------------------------------------------------ hand-written fixtures (layout of the real file)

HEADER = "[*POSREG*]$POSREG  Storage: SHADOW  Access: RW  : ARRAY[1,10] OF Position Reg\n"
TAIL = "\n[*POSREG*]$MAXPREGNUM  Storage: CMOS  Access: RW  : INTEGER = 10\n\n"


def _cartesian(n, robot, q):
    """A Cartesian register entry of the arm at joints ``q`` (deg), as a controller lists it."""
    T = fk(robot, np.radians(q)[None])[0]
    x, y, z, a, b, c = matrix_to_pose(T)
    flip, elbow, front, *turns = configuration_for(configuration_data("fanuc_ls"), robot, np.radians(q)[None])[0]
    w, p, r = np.degrees([c, b, a])
    return (f"    [1,{n}] =   'Reg{n}' \n  Group: 1   Config: {flip} {elbow} {front}, {turns[0]}, {turns[1]}, "
            f"{turns[2]}\n  X: {x:9.3f}   Y: {y:9.3f}   Z: {z:9.3f}\n  W: {w:9.3f}   P: {p:9.3f}   R: {r:9.3f}\n")


def _program(name, body):
    lines = [line for line in body.strip("\n").split("\n")]
    mn = "".join(f"{k:4d}:  {line} ;\n" for k, line in enumerate(lines, start=1))
    return f"/PROG  {name.upper()}\n/ATTR\nLINE_COUNT\t= {len(lines)};\n/MN\n{mn}/POS\n/END\n"


def _cell(folder, robot, body, others=()):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "POSREG.VA").write_text(
        HEADER + _cartesian(1, robot, [0, 10, -10, 0, -60, 0]) + _cartesian(2, robot, [10, 5, -5, 0, -70, 10])
        + "    [1,3] =   'Home'   Group: 1\n  J1 =     0.000 deg   J2 =     0.000 deg   J3 =     0.000 deg \n"
          "  J4 =     0.000 deg   J5 =   -90.000 deg   J6 =      .000 deg \n\n"
        + "    [1,4] =   '' Uninitialized\n"
        + "    [1,5] =   'Open' \n  Group: 1   Config: N U T, 0, 0, 0\n  X:  ********   Y:     0.000   Z:     0.000\n"
          "  W:     0.000   P:     0.000   R:     0.000\n"
        + "    [2,1] =   ''   Group: 2\n  J1 =  -130.224 mm  \n\n" + TAIL)  # a servo gun's axis, as ub10200's
    for name, text in others:
        (folder / name).write_text(_program(name.split(".")[0], text))
    path = folder / "MAIN.LS"
    path.write_text(_program("main", body))
    return path


def test_registers_left_as_written_say_why_per_motion(tmp_path):
    robot = load_robot("fanuc_lrmate200id")
    path = _cell(tmp_path, robot, """UFRAME_NUM=0
UTOOL_NUM=1
L PR[1] 100mm/sec FINE
J PR[3] 50% FINE
L PR[4] 100mm/sec FINE
L PR[5] 100mm/sec FINE
L PR[7] 100mm/sec FINE
L PR[2] 100mm/sec CNT50
PR[2,3]=PR[2,3]+10""", others=[("TEACH.LS", "PR[1]=LPOS")])
    program = formats.read(path)
    assert [program.where(m.target) for m in program.motions if m.target is not None] == [
        "PR[3] (POSREG.VA:10)"]
    assert [reason for _, _, reason in program.not_compensated()] == [
        "position register PR[1] is set at run time (TEACH.LS:5, PR[1]=LPOS)",
        "position register PR[4] is uninitialized in POSREG.VA (line 14): the controller faults if this line runs "
        "before something sets it",
        "position register PR[5] is not taught in POSREG.VA (********, line 15)",
        "position register PR[7]: POSREG.VA holds no register 7 of group 1",
        "position register PR[2] is set at run time (line 13, PR[2,3]=PR[2,3]+10)"]
    # an indirect write may set any register: every register motion is left
    (tmp_path / "TEACH.LS").write_text(_program("teach", "PR[R[4]]=LPOS"))
    listed = formats.read(path).not_compensated()
    assert [reason for _, _, reason in listed][:5] == [
        f"position register PR[{n}] is set at run time (TEACH.LS:5, PR[R[4]]=LPOS)" for n in (1, 3, 4, 5, 7)]
    assert len(listed) == 6  # PR[2]: the program's own PR[2,3]= named first
    # the tool and frame a Cartesian register moves in are the ones active: none set in the program, none known
    (tmp_path / "TEACH.LS").unlink()
    path.write_text(_program("main", "L PR[1] 100mm/sec FINE\nJ PR[3] 50% FINE"))
    assert formats.read(path).not_compensated() == (
        (5, "1: L PR[1] 100mm/sec FINE ;", "PR[1] is a position in the tool and user frame active when the line "
                                           "runs: the program sets no UTOOL_NUM and UFRAME_NUM before it"),)


def test_a_register_is_compensated_where_the_backup_holds_it_once_for_the_programs_sharing_it(tmp_path):
    robot = load_robot("fanuc_lrmate200id")
    folder = tmp_path / "backup"
    body = "UFRAME_NUM=0\nUTOOL_NUM=1\nJ PR[3] 50% FINE\nL PR[1] 100mm/sec FINE\nL PR[2] 100mm/sec FINE"
    path = _cell(folder, robot, body, others=[("SEAM.LS", "UFRAME_NUM=0\nUTOOL_NUM=1\nL PR[2] 100mm/sec FINE")])
    before = (folder / "POSREG.VA").read_text()
    program = formats.read(path)
    assert program.not_compensated() == ()
    # group 2's register 1 (the gun) is the external axis of PR[1], carried unchanged; PR[2] has none
    assert [program.targets[m.target].external for m in program.motions[1:3]] == [[-130.224], None]
    edited, report = compensate_program(program, _stand_in(robot), robot, tools={"1": np.eye(4)})
    assert any(w.startswith("position registers PR[1], PR[2], PR[3] are read from POSREG.VA") for w in report.warnings)
    (tmp_path / "out").mkdir()
    written = formats.write(tmp_path / "out" / "MAIN.LS", edited)
    assert sorted(p.name for p in written) == ["MAIN.LS", "POSREG.VA"]
    after = formats.read(tmp_path / "out" / "MAIN.LS")  # the written registers read back, moved by the correction
    old = formats.read(path)
    for k in (1, 2):  # the Cartesian registers: moved by the stand-in's offset, nothing else in the file
        np.testing.assert_allclose(after.targets[after.motions[k].target].pose[:3, 3]
                                   - old.targets[old.motions[k].target].pose[:3, 3], OFFSET, atol=1e-3)
    changed = [k for k, (a, b) in enumerate(zip(before.splitlines(), (tmp_path / "out" / "POSREG.VA").read_text()
                                                .splitlines())) if a != b]
    assert changed == [3, 7]  # the X/Y/Z lines of PR[1] and PR[2]; the joint register PR[3] kept
    # the programs sharing the register file run as one (a batch groups them), so PR[2] is corrected once
    assert groups([path, folder / "SEAM.LS"]) == [[0, 1]]
    task = formats.read_task([path, folder / "SEAM.LS"])
    assert [task.where(m.target) for m in task.motions] == [
        "PR[3] (POSREG.VA:10)", "PR[1] (POSREG.VA:2)", "PR[2] (POSREG.VA:6)", "PR[2] (POSREG.VA:6)"]


def test_a_register_used_with_two_tools_lists_each_motion_with_why_no_copy_is_written(tmp_path):
    robot = load_robot("fanuc_lrmate200id")
    path = _cell(tmp_path, robot, "UFRAME_NUM=0\nUTOOL_NUM=1\nL PR[1] 100mm/sec FINE\nUTOOL_NUM=2\n"
                                  "L PR[1] 100mm/sec FINE\nJ PR[3] 50% FINE")
    program = formats.read(path)
    why = ("one set of numbers cannot be right for both, and no copy is written: a position register holds one "
           "position (a copy would need a register the controller does not use); left as written")
    assert program.not_compensated() == (
        (7, "3: L PR[1] 100mm/sec FINE ;", f"point PR[1] is used here with tool/frame ('1', '0') and with ('2', '0') "
                                           f"at line 9: {why}"),
        (9, "5: L PR[1] 100mm/sec FINE ;", f"point PR[1] is used here with tool/frame ('2', '0') and with ('1', '0') "
                                           f"at line 7: {why}"))
    assert program.where(program.motions[2].target) == "PR[3] (POSREG.VA:10)"  # the joint register: one position


def test_a_position_whose_index_a_register_holds_is_listed_not_refused(tmp_path):
    """``L P[R[3]] ...`` was refused ("motion needs a speed"): the controller runs it, to P[value of R[3]]."""
    path = tmp_path / "T.LS"
    path.write_text(_program("t", "L P[R[3]] 100mm/sec FINE\nL P[R[3:idx]] 100mm/sec CNT10\nJ PR[R[4]] 50% FINE\n"
                                  "L P[AR[1]] R[2]mm/sec FINE"))
    assert formats.read(path).not_compensated() == (
        (5, "1: L P[R[3]] 100mm/sec FINE ;", "P[R[3]]: position index computed at run time"),
        (6, "2: L P[R[3:idx]] 100mm/sec CNT10 ;", "P[R[3:idx]]: position index computed at run time"),
        (7, "3: J PR[R[4]] 50% FINE ;", "position register PR[R[4]]: its number is set at run time"),
        (8, "4: L P[AR[1]] R[2]mm/sec FINE ;", "P[AR[1]]: position index computed at run time"))


def test_a_commented_out_line_sets_no_register_and_calls_nothing(tmp_path):
    """``//PR[R[199]]=PR[26] ;`` is an instruction the pendant commented out: it does not run. In a real backup
    (WILDER-SYSTEMS-LLC/git-ftp, rivetlocation.ls line 7) it made every register of the backup "set at run time"
    (an indirect write sets any register), so no register motion of any of its programs was compensated."""
    robot = load_robot("fanuc_lrmate200id")
    path = _cell(tmp_path, robot, "UFRAME_NUM=0\nUTOOL_NUM=1\nLBL[1]\n//PR[1]=LPOS\nL PR[1] 100mm/sec FINE\n"
                                  "//CALL TEACH\nJ PR[3] 50% FINE\n//JMP LBL[1]",
                 others=[("TEACH.LS", "//PR[R[199]]=PR[26:RIVET LOCATION]\n//UTOOL_NUM=9")])
    program = formats.read(path)
    assert program.not_compensated() == ()
    assert [program.where(m.target) for m in program.motions] == ["PR[1] (POSREG.VA:2)", "PR[3] (POSREG.VA:10)"]
    assert [m.start_why for m in program.motions][1:] == [""]  # after a call, or a jump back, its start is unknown
