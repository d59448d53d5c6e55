"""FANUC .LS and URScript readers and writers: constructs, configuration, errors."""

import re
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError, WriteError
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import abc_to_matrix, rotvec_to_matrix

DATA = Path(__file__).parents[1] / "data" / "programs"


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


@pytest.mark.parametrize("after, line", [("junk\n", 11), ("\n  ! a comment\n", 12),
                                         ("/MN\n   2:L P[1] 100mm/sec FINE ;\n", 11), ("\x1a", 11)])
def test_fanuc_text_after_end_is_refused_naming_file_and_line(tmp_path, capsys, after, line):
    """Issue 36: the controller's loader refuses an .LS with anything but blank lines after /END (the real ones
    end there); it was accepted with exit 0."""
    from trajcomp.cli import main

    path = tmp_path / "AFTER.LS"
    text = ("/PROG AFTER\n/MN\n   1:L P[1] 100mm/sec FINE ;\n/POS\nP[1]{\n   GP1:\n\tUF : 0, UT : 1,\n"
            "\tX = 1.0 mm, Y = 2.0 mm, Z = 3.0 mm, W = 0 deg, P = 0 deg, R = 0 deg\n};\n/END\n")
    path.write_text(text + "\n \t\n\n")  # blank lines: read
    assert len(formats.read(path).motions) == 1
    path.write_text(text + after)
    with pytest.raises(ReadError, match=rf"AFTER\.LS:{line}: text after /END: nothing but blank lines"):
        formats.read(path)
    assert main(["convert", str(path), str(tmp_path / "out.csv")]) == 2
    assert f"AFTER.LS:{line}: text after /END" in capsys.readouterr().err


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
    assert by_line[17].frame == "Plane_1" and "Plane_1" not in ur.frames  # an installation feature: give its value
    assert {m.line for m in ur.runtime_motions()} == {18}


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


def test_a_script_of_statements_alone_is_read_and_a_text_of_none_refused(tmp_path):
    """A script of top-level I/O statements without a def, a move or a pose (as UniversalRobots/URScript_Examples'
    modbus/wago-750/read-digital.script, sent to the secondary interface): a controller runs it, so it is read, with
    no motion (it was refused as "not a URScript program"); a text with no URScript in it still is."""
    path = tmp_path / "io.script"
    path.write_text('# read the inputs\nmodbus_add_signal("192.168.1.100", 255, 0, 0, "D_IN", True, 24)\nsleep(1)\n'
                    'global inputs = modbus_get_signal_status("D_IN", False)\nmodbus_delete_signal("D_IN")\n')
    program = formats.read(path)
    assert len(program.targets) == 0 and list(program.not_compensated()) == []
    (tmp_path / "notes.script").write_text("call the cell about the new fixture\n")
    with pytest.raises(ReadError, match=r"notes\.script: not a URScript program"):
        formats.read(tmp_path / "notes.script")


def _ls(tmp_path, mn, pos):
    path = tmp_path / "T.LS"
    lines = "".join(f"{k:4d}:{line} ;\n" for k, line in enumerate(mn, start=1))
    path.write_text(f"/PROG  T\n/ATTR\n/MN\n{lines}/POS\n{pos}/END\n")
    return path


def _p(n, x, ut=1, config="N U T, 0, 0, 0", extra=""):
    return (f"P[{n}]{{\n   GP1:\n\tUF : 0, UT : {ut},\t\tCONFIG : '{config}',\n"
            f"\tX = {x}  mm,\tY = 0.000  mm,\tZ = 500.000  mm,\n\tW = 180.000 deg,\tP = 0.000 deg,\tR = 0.000 deg{extra}\n}};\n")


def test_fanuc_german_export_reads_konfig_tool_and_the_servo_gun_axis():
    program = formats.read(DATA / "real" / "fanuc" / "up106.ls")
    assert [program.targets[m.target].config for m in program.motions] == [("N", "U", "T", 0, 0, 0)] * 3
    assert {m.tool for m in program.motions} == {"1"} and {m.frame for m in program.motions} == {"0"}
    assert [(m.speed, m.speed_unit, m.zone) for m in program.motions] == [(100.0, "%", None)] * 3
    assert [t.external.tolist() for t in program.targets] == [[100.0, 0.0, 0.0], [20.0, 0.0, 0.0], [100.0, 0.0, 0.0]]
    assert program.moving_external_axes() == ("E1",)  # GP2 J1, the servo gun


def test_fanuc_motion_to_an_untaught_position_is_listed_not_refused():
    # the controller loads such a program and faults only if the line runs (real backup, SOURCES.txt)
    program = formats.read(DATA / "real" / "fanuc" / "motn015.ls")
    [(line, _, reason)] = program.not_compensated()
    assert line == 27 and re.fullmatch(r"P\[1\] is not taught \(its position is \*+, line 31\): the controller "
                                       r"faults only if this line runs", reason)


def test_fanuc_untaught_position_nothing_moves_to_is_fine(tmp_path):
    untaught = "P[2]{\n   GP1:\n\tUF : F, UT : F,\t\tKONFIG : 'N D B, 0, 0, 0',\n\tX = ********  mm\n};\n"
    program = formats.read(_ls(tmp_path, ["L P[1] 100mm/sec FINE"], _p(1, "400.000") + untaught))
    assert len(program.targets) == 1 and program.not_compensated() == ()


def test_fanuc_tool_set_at_run_time_stops_compensation_from_that_line(tmp_path):
    mn = ["UTOOL_NUM=1", "L P[1] 100mm/sec FINE", "UTOOL[1]=PR[5]", "L P[2] 100mm/sec FINE",
          "L P[3] 100mm/sec FINE"]
    program = formats.read(_ls(tmp_path, mn, _p(1, "400.000") + _p(2, "410.000") + _p(3, "420.000", ut=2)))
    assert [program.targets[i].name for i in program.usage()] == ["P[1]", "P[3]"]  # P[3] uses tool 2
    assert program.not_compensated() == (
        (7, "4:L P[2] 100mm/sec FINE ;", "tool 1 set at run time by UTOOL[1]=PR[5] (line 6)"),)
    assert [program.targets[i].name for i, _, _ in program.referenced_targets()] == ["P[2]"]


def test_fanuc_register_and_max_speeds_corner_region_and_references(tmp_path):
    mn = ["L P[1] R[4]mm/sec CNT R[2]", "L P[2] max_speed CR50", "PR[1]=P[3]", "L P[3] 100mm/sec FINE Offset,PR[1]"]
    program = formats.read(_ls(tmp_path, mn, _p(1, "400.000") + _p(2, "410.000") + _p(3, "420.000")))
    assert [(m.speed, m.zone, m.target) for m in program.motions] == [(None, None, 0), (None, 50.0, 1), (100.0, None, None)]
    assert program.not_compensated()[0][2] == "Offset applied at run time"
    assert [(program.targets[i].name, line) for i, line, _ in program.referenced_targets()] == [("P[3]", 6), ("P[3]", 7)]


def test_fanuc_circle_with_a_register_point_passes_through_whole(tmp_path):
    path = tmp_path / "C.LS"
    path.write_text("/PROG  C\n/MN\n   1:C P[1]    \n    :  PR[2] 100mm/sec FINE    ;\n   2:L P[2] 100mm/sec FINE ;\n"
                    f"/POS\n{_p(1, '400.000')}{_p(2, '410.000')}/END\n")
    program = formats.read(path)
    circle = program.motions[0]
    assert (circle.target, circle.via, circle.refs) == (None, None, (0,))
    assert circle.reason == ("position register PR[2]: its value is the controller's; no POSREG.VA beside the "
                             "program (its backup's)")


def test_a_circle_without_its_via_point_is_never_written(tmp_path):
    import dataclasses

    program = formats.read(DATA / "fanuc" / "PICK_PLACE.LS")
    items = [dataclasses.replace(m, via=None) if getattr(m, "kind", "") == "circular" else m for m in program.items]
    for suffix in (".LS", ".src", ".mod", ".script"):
        from trajcomp.compensation.program_rewrite import convert_program

        converted = convert_program(program.replace(items=tuple(items)), formats.find_format(tmp_path / f"x{suffix}").name,
                                    tools={"1": np.eye(4), "2": np.eye(4)}, frames={"1": np.eye(4)})
        with pytest.raises(WriteError, match=r"line 28 .*a circle needs its via point"):
            formats.write(tmp_path / f"x{suffix}", converted)


@pytest.mark.parametrize("x", ["1e999", "-1e400"])
def test_fanuc_out_of_range_number_is_refused(tmp_path, x):
    with pytest.raises(ReadError, match=rf"T\.LS:\d+: P\[1\] X: '{x}' is out of range"):
        formats.read(_ls(tmp_path, ["L P[1] 100mm/sec FINE"], _p(1, x)))


ROBODK_UR = DATA / "real" / "ur" / "Prog1.script"


def test_robodk_urscript_poses_in_ref_frame_are_compensable_targets(tmp_path):
    from scipy.spatial.transform import Rotation

    from trajcomp.compensation.program_rewrite import convert_program

    program = formats.read(ROBODK_UR)
    assert program.not_compensated() == ()
    moves = [m for m in program.motions if m.kind == "linear"]
    assert len(moves) == 8 and {m.frame for m in moves} == {"ref_frame"} and {m.speed for m in moves} == {250.0}
    np.testing.assert_allclose(program.frames["ref_frame"][:3, 3], [1323.43, 124.721, 611.576])
    # The base-frame pose the arm goes to, by scipy from the numbers written: ref_frame * p
    frame = np.array([1.323430, 0.124721, 0.611576])
    p = np.array([-0.221556, -0.116633, 0.191249]), Rotation.from_rotvec([-0.295626, 3.094521, 0.301191])
    formats.write(tmp_path / "base.csv", convert_program(program, "csv"))
    row = (tmp_path / "base.csv").read_text().splitlines()[3].split(",")
    np.testing.assert_allclose([float(v) for v in row[:3]], (frame + p[0]) * 1000.0, atol=1e-6)
    np.testing.assert_allclose(Rotation.from_euler("ZYX", [float(v) for v in row[3:6]], degrees=True).as_matrix(),
                               p[1].as_matrix(), atol=1e-9)


def _script(tmp_path, body):
    path = tmp_path / "s.script"
    path.write_text("def s():\n" + "".join(f"  {line}\n" for line in body) + "end\n")
    return path


def test_lists_that_are_not_poses_are_not_points(tmp_path):
    program = formats.read(_script(tmp_path, [
        "gains = [0, 0, 0, 0]", "selection = [0, 0, 1, 0, 0, 0]", "limits = [0.1, 0.1, 0.15, 0.35, 0.35, 0.35]",
        "force_mode(tool_pose(), selection, [0, 0, 20, 0, 0, 0], 2, limits)",
        "movel(p[0.4, 0.1, 0.3, 0, 3.14, 0], a=1.2, v=0.1)"]))
    assert len(program.targets) == 1 and program.unused_targets() == ()


def test_urscript_positions_known_only_at_run_time_are_listed(tmp_path):
    program = formats.read(_script(tmp_path, [
        "p1 = p[0.4, 0.1, 0.3, 0, 3.14, 0]", "p2 = pose_add(p1, p[0, 0, 0.05, 0, 0, 0])", "movel(p2)",
        "def go(target):", "  movel(target)", "end", "movel(later)", "later = p[0.5, 0.1, 0.3, 0, 3.14, 0]",
        "set_tcp(get_tcp_offset())", "movel(p1)", "servoj([0, -1.5, 1.5, -1.5, -1.5, 0], t=0.008)"]))
    reasons = {line: reason for line, _, reason in program.not_compensated()}
    assert reasons == {
        4: "p2 is set at run time (line 3)",
        6: "target: function parameter, known at run time",
        8: "later is assigned further down: its value depends on the order of calls",
        11: "TCP set at run time: set_tcp(get_tcp_offset()) (line 10)",
        12: "servoj: streamed set point, not compensated by trajcomp",
    }
    # p1 feeds the run-time pose on line 3 and is moved to after the run-time TCP: used, not "unused"
    assert [(program.targets[i].name, line) for i, line, _ in program.referenced_targets()] == [("p1", 3), ("p1", 11)]


def test_urscript_velocity_and_torque_control_is_listed(tmp_path):
    """speedl, speedj and direct_torque move the arm (UniversalRobots/URScript_Examples: admittance_control.script
    drives it by speedl in a loop, joint_impedance_cartesian_circle_motion.script by direct_torque): listed, not
    passed over as "no compensable motion" (nothing silent)."""
    program = formats.read(_script(tmp_path, [
        "speedl([0, 0, 0.05, 0, 0, 0], a=0.5, t=0.008)", "speedj([0.1, 0, 0, 0, 0, 0], 1.4, 0.008)",
        "direct_torque([0, 0, 0, 0, 0, 0], friction_comp=True)", "movel(p[0.4, 0.1, 0.3, 0, 3.14, 0], a=1.2, v=0.1)"]))
    reasons = [reason for _, _, reason in program.not_compensated()]
    assert reasons == [f"{f}: the arm moves by the velocity or torque given at run time, not compensated by trajcomp"
                       for f in ("speedl", "speedj", "direct_torque")]
    assert len(program.targets) == 1


def test_a_variable_the_script_never_assigns_is_refused(tmp_path):
    with pytest.raises(ReadError, match=r"s\.script: .*Waypoint_9_p \(line 2\); they are never assigned"):
        formats.read(_script(tmp_path, ["movel(Waypoint_9_p, a=1.2, v=0.25)"]))


def test_set_tcp_from_a_variable(tmp_path):
    program = formats.read(_script(tmp_path, ["tcp = p[0, 0, 0.2, 0, 0, 0]", "set_tcp(tcp)",
                                              "movel(p[0.4, 0.1, 0.3, 0, 3.14, 0])"]))
    (motion,) = program.motions
    np.testing.assert_allclose(program.tools[motion.tool][:3, 3], [0, 0, 200])
    assert program.unused_targets() == () and len(program.targets) == 1


def test_a_speed_variable_set_again_where_the_feed_changes_is_read_where_it_runs(tmp_path):
    """As RoboDK's UR post writes a feed change (``speed_ms = 0.020`` between motions of its main program): each
    motion runs at the literal last assigned above it, a motion in a loop too; where the value depends on the calls
    (a routine called from elsewhere, a thread) or an assignment runs conditionally, it is known at run time."""
    def speeds(lines):
        path = tmp_path / "feed.script"
        path.write_text("\n".join(lines) + "\n")
        return [(m.line, m.speed) for m in formats.read(path).motions]

    pose = "p[0.5, 0.1, 0.5, 0, 3.14, 0]"
    assert speeds(["def Prog():", "  global speed_ms = 0.050", "  def Spray(on):", f"    movel({pose}, v=speed_ms)",
                   "  end", f"  movel({pose}, a=1.2, v=speed_ms)", "  speed_ms = 0.020",
                   f"  movel({pose}, 1.2, speed_ms, 0, 0)", "  while True:", f"    movel({pose}, v=speed_ms)", "  end",
                   "end", "Prog()"]) == [(4, None), (6, 50.0), (8, 20.0), (10, 20.0)]
    assert speeds(["v_cut = 0.1", "def sub():", f"  movel({pose}, v=v_cut)", "end", f"movel({pose}, v=v_cut)",
                   "v_cut = 0.2", "while True:", f"  movel({pose}, v=v_cut)", "end", "thread beside():",
                   f"  movel({pose}, v=v_cut)", "end", "if 1 > 2:", "  v_other = 0.3", "end", "v_other = 0.4",
                   f"movel({pose}, v=v_other)"]) == [(3, None), (5, 100.0), (8, 200.0), (11, None), (17, None)]
    # a routine that sets it again, called between the assignment above a motion and the motion
    assert speeds(["def slow():", "  v_cut = 0.05", "end", "v_cut = 0.1", "slow()", f"movel({pose}, v=v_cut)"]) == [
        (6, None)]
    # the same script wrapped in a routine called twice: the routine's first motion runs at 0.1, then 0.2
    assert speeds(["def twice():", "  movel(p[0.5, 0.1, 0.5, 0, 3.14, 0], v=v_cut)", "  v_cut = 0.2", "end",
                   "v_cut = 0.1", "twice()", "twice()"])[0] == (2, None)


def test_urscript_qnear_out_of_range_is_refused(tmp_path):
    path = _script(tmp_path, ["movej(get_inverse_kin(p[0.4, 0.1, 0.3, 0, 3.14, 0], qnear=[0, -1.5, 1e999, 0, 0, 0]))"])
    with pytest.raises(ReadError, match=r"s\.script:2: qnear 3: '1e999' is out of range"):
        formats.read(path)


def test_urscript_movec_with_a_run_time_via_point_converts_to_ls_as_a_comment(tmp_path):
    from trajcomp.compensation.program_rewrite import convert_program

    path = _script(tmp_path, ["movel(p[0.4, 0.1, 0.3, 0, 3.14, 0])",
                              "movec(pose_add(get_actual_tcp_pose(), p[0, 0.01, 0, 0, 0, 0]), p[0.42, 0.12, 0.3, 0, 3.14, 0])"])
    program = formats.read(path)
    circle = program.motions[1]
    assert (circle.target, circle.via, circle.line) == (None, None, 3)
    formats.write(tmp_path / "C.LS", convert_program(program, "fanuc_ls", robot=load_robot("ur10")))
    assert "! not converted: movec(pose_add(" in (tmp_path / "C.LS").read_text()
