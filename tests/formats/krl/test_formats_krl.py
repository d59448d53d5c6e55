"""KUKA KRL reader and writer: constructs, S/T, errors."""

import re
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.formats.krl.configuration import encode as kuka_status_turn
from trajcomp.errors import ReadError, WriteError
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import abc_to_matrix

WELD = Path(__file__).parents[2] / "data" / "programs" / "krl" / "weld.src"


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


def test_partial_inline_target_is_the_current_position_in_its_other_members(tmp_path):
    """``LIN {Z 500}`` (a real palletiser's lift): the members not given are the arm's current ones: run time."""
    path = _write(tmp_path, "DEF p( )\nLIN {X 1,Y 2,Z 3}\nPTP {A1 10}\nEND\n")
    assert [reason for _, _, reason in formats.read(path).not_compensated()] == [
        "position computed at run time: {X 1,Y 2,Z 3}", "position computed at run time: {A1 10}"]


def test_a_point_of_an_array_is_listed_as_such(tmp_path):
    """``PTP P[1]`` to a point of an array whose values the .dat holds (a palletiser's layers): listed with what it is,
    not as "computed at run time", which it is not (reading arrays' elements is not built)."""
    path = _write(tmp_path, "DEF p( )\nPTP P[1]\nLIN P[I]\nEND\n",
                  "DEFDAT p\nDECL E6POS P[2]\nP[1]={X 500,Y 0,Z 600,A 0,B 90,C 0,S 2,T 2}\nENDDAT\n")
    assert [reason for _, _, reason in formats.read(path).not_compensated()] == [
        f"an element of a point array: {name} (trajcomp reads single points, not arrays' elements)"
        for name in ("P[1]", "P[I]")]


def test_motion_without_target(tmp_path):
    path = _write(tmp_path, "DEF p( )\nCIRC XP1\nEND\n")
    with pytest.raises(ReadError, match=r"p\.src:2: CIRC needs 2 target"):
        formats.read(path)


def test_wrong_language_is_a_clear_error(tmp_path):
    path = _write(tmp_path, "MODULE M\nPROC main()\nENDPROC\nENDMODULE\n")
    with pytest.raises(ReadError, match="not a KRL program"):
        formats.read(path)


SRC = "DEF p( )\nPTP XP1\nLIN XP2\nLIN XP3 C_DIS\nEND\n"
DAT = ("DEFDAT p\nDECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0,S 2,T 2}\nDECL E6POS XP2={X 4,Y 5,Z 6,A 0,B 0,C 0,S 2,T 2}\n"
       "DECL E6POS XP3={X 7,Y 8,Z 9,A 0,B 0,C 0,S 2,T 2}\nENDDAT\n")


def test_src_without_its_dat_names_every_unresolved_point(tmp_path):
    path = _write(tmp_path, SRC)
    with pytest.raises(ReadError, match=r"p\.src: .*XP1 \(line 2\), XP2 \(line 3\), XP3 \(line 4\); no p\.dat"):
        formats.read(path)


@pytest.mark.parametrize(
    "dat, message",
    [
        (DAT.replace("ENDDAT\n", ""), r"p\.dat: no ENDDAT: the data list is cut off"),
        (DAT.replace(",Y 8,Z 9,A 0,B 0,C 0,S 2,T 2}\nENDDAT", "\nENDDAT"), r"p\.dat:4: malformed or cut point"),
        (DAT.replace("DECL E6POS XP3={X 7,Y 8,Z 9,A 0,B 0,C 0,S 2,T 2}\n", ""), r"XP3 \(line 4\); are they declared in p\.dat"),
        ("garbage\x01\x02 not a data list\n", r"p\.dat: not a KRL data list"),
    ],
    ids=["no ENDDAT", "cut line", "point missing", "garbage"],
)
def test_cut_or_garbage_dat_is_refused(tmp_path, dat, message):
    path = _write(tmp_path, SRC, dat)
    with pytest.raises(ReadError, match=message):
        formats.read(path)


def test_positions_known_only_at_run_time_are_listed_with_their_reason(tmp_path):
    src = (
        "DEF p( )\nDECL E6POS XTMP\nPTP XP1\nXTMP = $POS_ACT\nLIN XTMP\nLIN $POS_ACT\nMOVE(XP1)\n"
        "XP3.Z = XP3.Z + 10\nLIN XP3\n$TOOL = TOOL_DATA[1]:{X 1}\nLIN XP2\nEND\n"
        "DEF MOVE(P:IN)\nLIN P\nEND\n"
    )
    program = formats.read(_write(tmp_path, src, DAT))
    reasons = {line: reason for line, _, reason in program.not_compensated()}
    assert reasons == {
        5: "XTMP is declared without a value (set at run time, line 2)",
        6: "$POS_ACT: system variable, known at run time",
        9: "XP3 is changed at run time (line 8)",
        11: "$TOOL = TOOL_DATA[1]:{X 1} set at run time (line 10)",
        14: "P: routine parameter, known at run time",
    }
    assert [program.targets[i].name for i in program.usage()] == ["XP1"]
    # XP2 and XP3 are used, but not compensated: named, not "unused"
    assert [t.name for t in program.unused_targets()] == []
    assert sorted((program.targets[i].name, line) for i, line, _ in program.referenced_targets()) == [
        ("XP2", 11), ("XP3", 8), ("XP3", 9)]


def test_points_passed_to_routines_are_referenced_not_unused(tmp_path):
    src = "DEF p( )\nPTP XP1\nGRIP(XP2, 3)\nEND\n"
    program = formats.read(_write(tmp_path, src, DAT))
    assert [(program.targets[i].name, line, text) for i, line, text in program.referenced_targets()] == [
        ("XP2", 3, "GRIP(XP2, 3)")]
    assert [t.name for t in program.unused_targets()] == ["XP3"]


def test_spline_inline_form_takes_tool_and_base_from_its_fdat(tmp_path):
    dat = DAT.replace("ENDDAT", "DECL FDAT FP2={TOOL_NO 4,BASE_NO 7,IPO_FRAME #BASE}\nENDDAT")
    src = ("DEF p( )\nBAS(#TOOL, 1)\nSLIN XP2 WITH $VEL=SVEL_CP(0.2,,LCPDAT1), $TOOL=STOOL2(FP2), "
           "$BASE=SBASE(FP2.BASE_NO) C_SPL\nEND\n")
    (motion,) = formats.read(_write(tmp_path, src, dat)).motions
    assert (motion.tool, motion.frame, motion.target) == ("4", "7", 1)


@pytest.mark.parametrize("member, value", [("S", "1e999"), ("T", "2.5"), ("X", "1e999"), ("A", "-1e400")])
def test_out_of_range_numbers_are_refused_naming_the_member(tmp_path, member, value):
    dat = re.sub(rf"\b{member} [^,}}]+", f"{member} {value}", DAT, count=1)
    with pytest.raises(ReadError, match=rf"p\.dat:2: {member}: '{value}' is (out of range|not a whole number)"):
        formats.read(_write(tmp_path, SRC, dat))


def test_external_axes_are_read_and_their_motion_detected(tmp_path):
    dat = DAT.replace("T 2}", "T 2,E1 0.0,E2 90.0}").replace("X 4,Y 5,Z 6,A 0,B 0,C 0,S 2,T 2,E1 0.0", "X 4,Y 5,Z 6,A 0,B 0,C 0,S 2,T 2,E1 500.0")
    program = formats.read(_write(tmp_path, SRC, dat))
    np.testing.assert_array_equal(program.targets[1].external, [500.0, 90.0])
    assert program.moving_external_axes() == ("E1",)
    assert formats.read(_write(tmp_path, SRC, DAT)).moving_external_axes() == ()


def test_external_axes_are_carried_by_conversion_and_zero_ones_left_out(tmp_path):
    from trajcomp.compensation.program_rewrite import convert_program

    dat = DAT.replace("S 2,T 2}", "S 2,T 2,E1 0.0,E2 0.0}").replace("Z 6,A 0,B 0,C 0,S 2,T 2,E1 0.0", "Z 6,A 0,B 0,C 0,S 2,T 2,E1 -250.5")
    program = formats.read(_write(tmp_path, SRC, dat))
    formats.write(tmp_path / "copy.src", convert_program(program.replace(sources=()), "krl"))  # generated
    again = formats.read(tmp_path / "copy.src")
    assert [t.external.tolist() for t in again.targets] == [[0.0], [-250.5], [0.0]]  # E2 = 0 everywhere: left out
    with pytest.raises(WriteError, match=r"URScript points hold 0 external axes; target XP2 \(line 3\) gives E1 a value"):
        formats.write(tmp_path / "copy.script", convert_program(program, "urscript"))
    real = formats.read(Path(__file__).parents[2] / "data" / "programs" / "real" / "krl" / "Prog1.src")
    formats.write(tmp_path / "real.src", convert_program(real.replace(sources=()), "krl"))
    assert all(t.external is None for t in formats.read(tmp_path / "real.src").targets)  # E1 0.0 only


def test_a_program_keeps_its_def_under_its_own_name_even_if_krl_could_not_use_it(tmp_path):
    (tmp_path / "in").mkdir()
    source = tmp_path / "in" / "weld-2.src"
    source.write_bytes(b"DEF weld_2( )\r\nPTP {X 1,Y 2,Z 3,A 0,B 0,C 0}\r\nEND\r\n")
    formats.write(tmp_path / "weld-2.src", formats.read(source))
    assert (tmp_path / "weld-2.src").read_bytes() == source.read_bytes()
    with pytest.raises(WriteError, match="cannot name a KRL program"):
        formats.write(tmp_path / "weld-3.src", formats.read(source))


def test_real_robodk_program_reads_with_its_frames_and_external_axis():
    program = formats.read(Path(__file__).parents[2] / "data" / "programs" / "real" / "krl" / "Prog1.src")
    assert program.not_compensated() == ()
    assert {m.tool for m in program.motions} == {"TOOL line 48"} and {m.frame for m in program.motions} == {"BASE line 43"}
    np.testing.assert_allclose(program.tools["TOOL line 48"][:3, 3], [-4.0, 0.0, 371.3])
    index, joints = program.joint_targets()
    assert len(index) == 1 and len(program.cartesian_targets()) == 4


VEL_EXTAX_SRC = """DEF p( )
  BAS(#VEL_PTP,60)
  $VEL.CP=0.5
  PTP XP1
  $VEL_EXTAX[1]=20
  PTP XP2
  LIN XP3
  IF $IN[1] THEN
    $VEL_EXTAX[1]=5
  ENDIF
  PTP XP4
  track_speed()
  PTP XP5
  BAS(#VEL_PTP,40)
  PTP XP6
END

DEF track_speed( )
  $VEL_EXTAX[1]=N_TRACK
END
"""


def test_vel_extax_bounds_a_ptp_along_branches_and_calls_as_the_controller_reads_it(tmp_path):
    """``$VEL_EXTAX[1]`` (a track's % of its own maximum) binds a PTP as its arm's axes' % do (the controller moves
    a PTP's axes together, so the slowest binds), read along branches and calls; ``BAS(#VEL_PTP)`` sets it again
    with the arm's; a LIN keeps its TCP speed; a value set at run time leaves the PTP as written, saying why."""
    (tmp_path / "p.src").write_text(VEL_EXTAX_SRC)
    (tmp_path / "p.dat").write_text("DEFDAT p\n  DECL GLOBAL INT N_TRACK=10\n" + "".join(
        f"  DECL E6POS XP{k}={{X {400 + 10 * k},Y 0,Z 600,A 0,B 90,C 0,S 2,T 35,E1 {100 * k}}}\n"
        for k in range(1, 7)) + "ENDDAT\n")
    table = formats.read(tmp_path / "p.src").motion_table()
    speed = dict(zip((text.split()[1] for text in table.text), table.speed.tolist()))
    assert speed["XP1"] == 60.0 and speed["XP2"] == 20.0  # the track's 20 % below the arm's 60 %
    assert speed["XP3"] == 500.0  # a LIN: $VEL.CP, 0.5 m/s
    assert speed["XP4"] == 5.0  # IF .. ENDIF: 20 % or 5 %, the slowest
    assert np.isnan(speed["XP5"]) and "N_TRACK" in table.speed_why[4]  # set by a routine at run time: as written
    assert speed["XP6"] == 40.0  # BAS(#VEL_PTP) sets the external axes' with the arm's


def _rail(tmp_path, src):
    """The KR6 on a KL track (`SLOW_TRACK`: 500 mm/s, 2500 mm/s^2) and ``tmp_path / "rail.src"`` of ``src`` with its
    .dat: XP1 and XP2 turn the arm some 37 degrees (A1) and lie 600 mm of track apart."""
    from tests.compensation.test_compensate_track import on_track, orientation
    from tests.timing.test_timing_track import SLOW_TRACK
    from trajcomp.arm.ik import ik
    from trajcomp.arm.transforms import matrix_to_abc
    from trajcomp.formats.configuration import configuration_data, configuration_for

    robot = on_track("kuka_kr6_r900", SLOW_TRACK)
    local = np.tile(np.eye(4), (2, 1, 1))
    local[:, :3, :3] = orientation(robot)
    local[:, :3, 3] = [[450.0, -150.0, 700.0], [450.0, 150.0, 700.0]]  # A1 turns some 37 degrees
    q = ik(robot, local, seed=np.tile(robot.home, (2, 1))).raise_on_failure("targets").q
    carriage = np.array([0.0, 600.0])
    world = robot.track.placements(robot.T_world_base, carriage) @ local
    (tmp_path / "rail.dat").write_text("DEFDAT RAIL\n" + "".join(
        f"DECL E6POS XP{k + 1}={{X {T[0, 3]:.4f},Y {T[1, 3]:.4f},Z {T[2, 3]:.4f},"
        + ",".join(f"{n} {v:.5f}" for n, v in zip("ABC", matrix_to_abc(T[:3, :3])))
        + f",S {s},T {t},E1 {e:.1f}}}\n" for k, (T, (s, t), e) in enumerate(
            zip(world, configuration_for(configuration_data("krl"), robot, q), carriage))) + "ENDDAT\n")
    path = tmp_path / "rail.src"
    path.write_text(src)
    return robot, path


def test_a_ptp_moving_the_track_under_vel_extax_is_written_no_faster_than_it(tmp_path, monkeypatch):
    """Re-timed on a KL track (500 mm/s), a PTP that turns the arm and moves the track 600 mm under
    ``$VEL_EXTAX[1]=5`` (25 mm/s) keeps the track at 5 % at most: the ``BAS(#VEL_PTP)`` the timing writes sets
    the track's speed too. Read without ``$VEL_EXTAX``, the timing writes the arm's speed over it."""
    from tests.timing.test_timing_track import retimed
    from trajcomp.formats.krl import reader

    robot, path = _rail(tmp_path, "DEF rail( )\n$BASE=$NULLFRAME\nBAS(#VEL_PTP,100)\nPTP XP1\n$VEL_EXTAX[1]=5\n"
                                  "PTP XP2\nEND\n")

    def track_percent(text):
        """The track's % in force at PTP XP2 as the controller reads the program: its last setting before."""
        before = text.split("PTP XP2")[0]
        return float(re.findall(r"(?:BAS\(#VEL_PTP,\s*|\$VEL_EXTAX\[1\]\s*=\s*)([\d.]+)", before)[-1])

    (tmp_path / "read").mkdir()
    assert track_percent(retimed(tmp_path / "read", robot, path)[1]) <= 5.0
    with monkeypatch.context() as patch:
        patch.setattr(reader, "VEL_EXTAX", re.compile("(?!)"))  # the reader without it
        (tmp_path / "unread").mkdir()
        assert track_percent(retimed(tmp_path / "unread", robot, path)[1]) > 5.0


EXTERNAL_SHARES_SRC = """DEF p( )
  BAS(#VEL_PTP,60)
  SPTP XP1 WITH $VEL_AXIS[1] = SVEL_JOINT(80), $VEL_EXTAX[1] = 20
  SPTP XP2 WITH $VEL_EXTAX[1] = 10, $ACC_EXTAX[1] = 30
  SPTP XP3
  $ACC_EXTAX[1]=40
  PTP XP4
  IF $IN[1] THEN
    $ACC_EXTAX[1]=25
  ENDIF
  SPTP XP5 WITH $VEL_EXTAX[1] = N_TRACK
  track_acc()
  PTP XP6
  SPTP XP2 WITH $VEL_EXTAX[1] = SVEL_EXTAX(5)
END

DEF track_acc( )
  $ACC_EXTAX[1]=N_TRACK
END
"""


def test_external_axis_shares_are_read_as_the_controller_runs_them(tmp_path):
    """A spline PTP's WITH ``$VEL_EXTAX[n]`` and ``$ACC_EXTAX[n]`` bind that motion alone (the slowest of them and
    the speed in force); a ``$ACC_EXTAX[n]`` statement binds every PTP it reaches along branches and calls, as
    ``$ACC_AXIS[n]`` does; a value set at run time (GLOBAL data, a function) leaves the motion as written."""
    (tmp_path / "p.src").write_text(EXTERNAL_SHARES_SRC)
    (tmp_path / "p.dat").write_text("DEFDAT p\n  DECL GLOBAL INT N_TRACK=15\n" + "".join(
        f"  DECL E6POS XP{k}={{X {400 + 10 * k},Y 0,Z 600,A 0,B 90,C 0,S 2,T 35,E1 {100 * k}}}\n"
        for k in range(1, 7)) + "ENDDAT\n")
    table = formats.read(tmp_path / "p.src").motion_table()
    speeds = [None if np.isnan(v) else v for v in table.speed.tolist()]
    shares = [None if np.isnan(v) else round(v, 9) for v in table.acceleration_share.tolist()]
    assert speeds == [20.0, 10.0, 60.0, 60.0, None, 60.0, None]  # WITH: its own, below the 80 % and the 60 %
    assert shares[:4] == [None, 0.3, None, 0.4] and shares[4] == 0.25  # IF .. ENDIF: 40 % or 25 %, the slowest
    assert "N_TRACK" in table.speed_why[4] and "N_TRACK" in table.speed_why[5]  # the routine sets it at run time
    assert table.speed_why[6] == "$VEL_EXTAX[1] = SVEL_EXTAX(5): set at run time (line 14)"
    # a PTP spline block's WITH binds its motions, the slowest of it and theirs, not those after ENDSPLINE
    (tmp_path / "p.src").write_text("DEF p( )\n  BAS(#VEL_PTP,60)\n  PTP_SPLINE WITH $VEL_EXTAX[1] = 30\n"
                                    "    SPTP XP1\n    SPTP XP2 WITH $VEL_EXTAX[1] = 10\n  ENDSPLINE\n"
                                    "  SPTP XP3\nEND\n")
    assert formats.read(tmp_path / "p.src").motion_table().speed.tolist() == [30.0, 10.0, 60.0]


@pytest.mark.parametrize("setting", ["SPTP XP2 WITH $VEL_AXIS[1] = SVEL_JOINT(100), $VEL_EXTAX[1] = 5",
                                     "SPTP XP2 WITH $VEL_AXIS[1] = SVEL_JOINT(100), $ACC_EXTAX[1] = 4",
                                     "$ACC_EXTAX[1]=4\nPTP XP2"])
def test_a_ptp_s_external_axis_shares_bound_its_time_as_the_controller_runs_them(tmp_path, setting):
    """A spline PTP's WITH ``$VEL_EXTAX[1]`` / ``$ACC_EXTAX[1]`` (the track's % of its own maximum speed or
    acceleration, for that motion alone) and a ``$ACC_EXTAX[1]`` statement bind the PTP as the controller moves
    its axes together: 600 mm of track at 5 % of 500 mm/s take at least 24 s, and at 4 % of 2500 mm/s^2 at least
    2 sqrt(600 / 100) = 4.9 s from rest to rest; the setting is kept as written. (The track moves at the PTP's
    % of its limit whatever sets it: a ``$VEL_EXTAX[1]=5`` statement before the PTP was timed 14.3 s, the arm's
    axes alone slowed.)"""
    from tests.timing.test_timing_track import TRACK_ACCELERATION, TRACK_VELOCITY, retimed

    robot, path = _rail(tmp_path, f"DEF rail( )\n$BASE=$NULLFRAME\nBAS(#VEL_PTP,100)\nPTP XP1\n{setting}\nEND\n")
    least = 600.0 / (0.05 * TRACK_VELOCITY) if "VEL_EXTAX" in setting else 2.0 * np.sqrt(
        600.0 / (0.04 * TRACK_ACCELERATION))
    result, text = retimed(tmp_path, robot, path)
    assert result.t[-1] - result.t[-2] >= least
    assert setting.split("\n")[0].split(", ")[-1] in text
