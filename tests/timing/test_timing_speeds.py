"""What speed each motion really has, and the field re-timing writes for it under the controller's reading.

Reproducers of issue 20 (items 1 and 2), each a minimal program: speeds that
are not literals are resolved when the file proves them constant, else left
exactly as written and listed ("not re-timed: speed set at run time", in
the report's JSON, on stderr and in the exit code); KUKA inline forms run
the speed of their BAS(#CP_PARAMS, v) / BAS(#PTP_PARAMS, %) and spline
WITH $VEL arguments, and an edit inside a fold shows in its header; a
stated process speed stays as written unless a joint limit forces it lower,
and a lowered cruise speed is checked against an independent computation
(the straight line solved by IK every 0.05 mm, differentiated at that
speed) of what the controller does when it cruises at it.
"""

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.cli import main
from trajcomp.arm.ik import ik
from trajcomp.arm.robot import load_robot

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "programs"
RAPID_POINT = "[[{x},{y},{z}],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"


def retime(tmp_path, source, robot, code=0):
    """Re-time ``source`` (its .dat beside it) through the CLI; the output's text and the report's JSON."""
    output = tmp_path / "out" / source.name
    output.parent.mkdir(exist_ok=True)
    report = output.with_suffix(".html")
    assert main(["retime", str(source), "-o", str(output), "--robot", robot, "--report", str(report)]) == code
    return output.read_text(), json.loads(report.with_suffix(".json").read_text())


def rapid_module(tmp_path, declarations, moves):
    """A RAPID module: MoveJ to P1, then ``moves`` (P2 is 280 mm from P1 along y), with ``declarations``."""
    points = {"P1": (1135, 0, 1415), "P2": (1135, 280, 1415)}
    text = "MODULE Speeds\n" + "".join(
        f"  CONST robtarget {name} := {RAPID_POINT.format(x=x, y=y, z=z)};\n" for name, (x, y, z) in points.items())
    text += "".join(f"  {d}\n" for d in declarations)
    text += "  PROC main()\n    MoveJ P1, v1000, fine, tool0;\n" + "".join(f"    {m}\n" for m in moves)
    path = tmp_path / "Speeds.mod"
    path.write_text(text + "  ENDPROC\nENDMODULE\n")
    return path


def not_retimed(report):
    """``{waypoint label: why}`` of the motions the report lists as not re-timed."""
    return {m["waypoint"]: m["why"] for m in report["timing"]["not_retimed"]["motions"]}


def test_rapid_const_speeddata_is_read_as_its_v_tcp_and_kept(tmp_path):
    """``CONST speeddata vRun := [20,500,5000,1000]``: 280 mm at 20 mm/s, never ``vRun\\T:=0.335`` (836 mm/s)."""
    path = rapid_module(tmp_path, ["CONST speeddata vRun := [20,500,5000,1000];"],
                        ["MoveL P2, vRun, fine, tool0;"])
    assert formats.read(path).motions[1].speed == 20.0
    text, report = retime(tmp_path, path, "abb_irb4600")
    assert "MoveL P2, vRun, fine, tool0;" in text  # the process speed, as written
    assert text.replace("v1000\\T:=", "v1000,").count("\\") == 0  # no \T or \V on the weld
    times = report["timing"]["t_s"]
    assert times[1] - times[0] >= 280.0 / 20.0  # timed at 20 mm/s: 14 s and its ramps
    assert report["timing"]["not_retimed"]["count"] == 0 and report["timing"]["lowered"]["count"] == 0


@pytest.mark.parametrize("declaration,why", [
    ("PERS speeddata vWeld := [20,500,5000,1000];\n  PROC tune()\n    SetWeld vWeld;\n  ENDPROC",
     "vWeld: PERS speeddata the module changes (line 6) and does not assign a literal in the code running straight "
     "to this motion: set at run time"),  # a routine may change its argument (a PERS nothing changes: read in a backup)
    ("VAR speeddata vWeld := [20,500,5000,1000];\n  PROC faster()\n    vWeld := [900,500,5000,1000];\n  ENDPROC",
     "vWeld: VAR speeddata the module changes (line 6) and does not assign a literal in the code running straight "
     "to this motion: set at run time"),  # a VAR nothing changes is its declared value (test_formats_rapid_speeds)
    ("", "vWeld: speeddata not declared in this module, set at run time"),
])
def test_rapid_speeddata_set_at_run_time_is_left_as_written_and_listed(tmp_path, capsys, declaration, why):
    path = rapid_module(tmp_path, [declaration], ["MoveL P2, vWeld, fine, tool0;", "MoveL P1, v100\\V:=vRate, z5, tool0;"])
    text, report = retime(tmp_path, path, "abb_irb4600", code=1)  # listed in the verdict: exit 1
    assert "MoveL P2, vWeld, fine, tool0;" in text and "MoveL P1, v100\\V:=vRate, z5, tool0;" in text
    listed = not_retimed(report)
    assert listed == {"P2 (Speeds.mod:3)": why, "P1 (Speeds.mod:2)": "vRate: num not declared in this module, "
                                                                     "set at run time"}
    speeds = next(c for c in report["verdict"]["criteria"] if c["id"] == "speeds")
    assert speeds["status"] == "fail" and speeds["failing"] == 2
    assert "not re-timed, speed set at run time (left as written): 2 motion(s)" \
        in capsys.readouterr().err


def kuka_program(tmp_path, src_lines, dat_lines=()):
    """The example weld's .dat (P1..P5, with ``dat_lines`` added) and a .src of ``src_lines``."""
    dat = (EXAMPLES / "kuka" / "weld.dat").read_text().replace("ENDDAT", "".join(f"{d}\n" for d in dat_lines)
                                                                 + "ENDDAT")
    (tmp_path / "weld.dat").write_text(dat)
    src = tmp_path / "weld.src"
    src.write_text("DEF weld( )\n" + "".join(f"  {line}\n" for line in src_lines) + "END\n")
    return src


def test_krl_speed_variable_is_resolved_when_the_data_list_proves_it_constant(tmp_path):
    src = kuka_program(tmp_path, ["BAS(#VEL_PTP,50)", "PTP P1", "$VEL.CP=weldVel", "LIN P2", "LIN P3"],
                       ["DECL REAL weldVel=0.02"])
    assert [m.speed for m in formats.read(src).motions] == [50.0, 20.0, 20.0]
    text, report = retime(tmp_path, src, "kuka_kr6_r900")
    assert text == src.read_text()  # 20 mm/s kept: nothing inserted
    assert report["timing"]["not_retimed"]["count"] == 0


@pytest.mark.parametrize("dat,assignment,why", [
    ([], ["weldVel = 0.02"], "weldVel is assigned at run time (line 3)"),
    (["DECL GLOBAL REAL weldVel=0.02"], [], "weldVel: GLOBAL data other programs may change, known at run time"),
])
def test_krl_speed_variable_set_at_run_time_is_left_as_written_and_listed(tmp_path, dat, assignment, why):
    """``$VEL.CP=weldVel``: was given ``$VEL.CP=0.475372`` before each LIN (24 times the weld speed)."""
    src = kuka_program(tmp_path, ["BAS(#VEL_PTP,50)", *assignment, "PTP P1", "$VEL.CP=weldVel", "LIN P2", "LIN P3"],
                       dat)
    text, report = retime(tmp_path, src, "kuka_kr6_r900", code=1)
    assert text.count("$VEL.CP") == 1  # no speed inserted or edited
    listed = not_retimed(report)
    assert set(listed) == {"P2 (weld.dat:3)", "P3 (weld.dat:4)"} and all(w.startswith(why) for w in listed.values())


INLINE_PTP = """;FOLD PTP P1 Vel=40 % PDAT1 Tool[0] Base[0];%{PE}%R 8.3.38,%MKUKATPBASIS,%CMOVE,%VPTP,%P 1:PTP, 2:P1, 3:, 5:40, 7:PDAT1
  $BWDSTART=FALSE
  PDAT_ACT=PPDAT1
  FDAT_ACT=FP1
  BAS(#PTP_PARAMS,40)
  PTP P1
;ENDFOLD"""
INLINE_LIN = """;FOLD LIN P2 Vel={v} m/s CPDAT1 Tool[0] Base[0];%{{PE}}%R 8.3.38,%MKUKATPBASIS,%CMOVE,%VLIN,%P 1:LIN, 2:P2, 3:, 5:{v}, 7:CPDAT1
  $BWDSTART=FALSE
  LDAT_ACT=LCPDAT1
  FDAT_ACT=FP2
  BAS(#CP_PARAMS,{v})
  LIN P2
;ENDFOLD"""
INLINE_DATA = ["DECL FDAT FP1={TOOL_NO 0,BASE_NO 0,IPO_FRAME #BASE}", "DECL FDAT FP2={TOOL_NO 0,BASE_NO 0,IPO_FRAME #BASE}",
               "DECL PDAT PPDAT1={VEL 100.0,ACC 100.0,APO_DIST 100.0}",
               "DECL LDAT LCPDAT1={VEL 2.0,ACC 100.0,APO_DIST 100.0,APO_FAC 50.0,ORI_TYP #VAR,CIRC_TYP #BASE}"]


def test_krl_inline_forms_run_the_speed_of_their_bas_argument(tmp_path):
    """BAS(#CP_PARAMS, 0.02) is 20 mm/s, not the LDAT's VEL 2 m/s (was written 475 mm/s); BAS(#PTP_PARAMS, 40) 40 %."""
    src = kuka_program(tmp_path, [INLINE_PTP, INLINE_LIN.format(v="0.02"), "$VEL.CP=0.02", "LIN P3"], INLINE_DATA)
    assert [(m.speed, m.speed_unit) for m in formats.read(src).motions] == [(40.0, "%"), (20.0, "mm/s"),
                                                                             (20.0, "mm/s")]
    text, _ = retime(tmp_path, src, "kuka_kr6_r900")
    assert text == src.read_text()


def test_krl_spline_with_speeds_are_read(tmp_path):
    src = kuka_program(tmp_path, ["BAS(#VEL_PTP,50)", "PTP P1",
                                  "SLIN P2 WITH $VEL = SVEL_CP(0.2, , LCPDAT1), $TOOL = STOOL2(FP2)",
                                  "SPTP P1 WITH $VEL_AXIS[1] = SVEL_JOINT(40.0), $TOOL = STOOL2(FP2)",
                                  "SLIN P2 WITH $VEL.CP = vSeam",
                                  "SLIN P3 WITH $VEL = {CP 0.3, ORI1 100, ORI2 100}"], INLINE_DATA)
    motions = formats.read(src).motions
    assert [(m.speed, m.speed_unit) for m in motions[:3]] == [(50.0, "%"), (200.0, "mm/s"), (40.0, "%")]
    assert motions[3].speed is None and motions[3].speed_why.startswith("$VEL.CP = vSeam: set at run time")
    assert motions[4].speed is None and "set at run time" in motions[4].speed_why


def test_krl_lowered_speed_inside_an_inline_form_shows_in_its_header(tmp_path):
    """3 m/s is more than the arm can cruise at: the BAS argument is lowered and the fold's header says so."""
    src = kuka_program(tmp_path, [INLINE_PTP, INLINE_LIN.format(v="3"), "LIN P3"], INLINE_DATA)
    text, report = retime(tmp_path, src, "kuka_kr6_r900")
    fold = text[text.index(";FOLD LIN"):text.index(";ENDFOLD", text.index(";FOLD LIN"))]
    written = re.search(r"BAS\(#CP_PARAMS,([\d.]+)\)", fold).group(1)
    assert 0.1 < float(written) < 3.0
    header = fold.splitlines()[0]
    assert f"Vel={written} m/s" in header and f"5:{written}," in header
    assert text.count("$VEL.CP=") == 1  # for P3 (its speed is the one in force after the form): before it
    between = text[text.index(";ENDFOLD", text.index(";FOLD LIN")):text.index("LIN P3")]
    assert re.search(r"\$VEL\.CP=[\d.]+", between)  # outside the fold, whose header stays true
    lowered = report["timing"]["lowered"]
    assert lowered["count"] == 2 and "P2 (weld.dat:3): 3000 mm/s lowered to" in lowered["motions"][0]["detail"]


UR_HEADER = "def weld():\n  movej([0, -1.5702, 1.6052, -1.6057, -1.5708, 0])\n"
UR_LINE = "  movel(p[-0.6880000000, -0.1639410000, 0.5471000000, 2.221441469079, 2.221441469079, 0.0], a=1.2, v={v})\n"


@pytest.mark.parametrize("assignment,why", [
    ("  vslow = read_input_float_register(0)\n", "vslow is set at run time (line 2)"),
    ("  vslow = 0.02\n  if get_standard_digital_in(0):\n    vslow = 0.05\n  end\n",
     "vslow is assigned more than once (lines 2, 4)"),
])
def test_urscript_speed_variable_set_at_run_time_is_left_as_written_and_listed(tmp_path, assignment, why):
    """``v=vslow`` read from a register: was given ``t=0.3994``."""
    path = tmp_path / "weld.script"
    path.write_text("def weld():\n" + assignment + UR_HEADER.split("\n", 1)[1] + UR_LINE.format(v="vslow")
                    + "end\nweld()\n")
    text, report = retime(tmp_path, path, "ur10", code=1)
    assert text == path.read_text()
    assert [w[: len(why)] for w in not_retimed(report).values()] == [why]


@pytest.mark.parametrize("before, inside", [("global vslow = 0.02\n", ""),
                                            ("", "  vslow = 0.05\n  sleep(0.5)\n  vslow = 0.02\n")])
def test_urscript_global_assigned_once_to_a_literal_is_resolved(tmp_path, before, inside):
    """Assigned once, or again in the same program before the motion (a feed change): the literal in force there."""
    path = tmp_path / "weld.script"
    path.write_text(before + UR_HEADER + inside + UR_LINE.format(v="vslow") + "end\nweld()\n")
    assert formats.read(path).motions[-1].speed == 20.0
    text, report = retime(tmp_path, path, "ur10")
    assert text == path.read_text()  # 20 mm/s kept


def test_fanuc_speed_register_is_listed(tmp_path):
    path = tmp_path / "WELD.LS"
    path.write_text((EXAMPLES / "fanuc" / "WELD.LS").read_text().replace("L P[2] 20mm/sec", "L P[2] R[3]mm/sec"))
    text, report = retime(tmp_path, path, "fanuc_lrmate200id", code=1)
    assert "L P[2] R[3]mm/sec FINE" in text
    assert list(not_retimed(report).values()) == ["speed R[3]mm/sec: a register, set at run time"]


def cruise_demand(robot, start, end, speed, step=0.05):
    """Joint velocity and acceleration (each (n, 6)) of cruising at ``speed`` (mm/s) along the straight line.

    Independent of the timing's path fit: the line sampled every ``step`` mm
    (constant orientation), each pose solved by IK in the start's branch, q(x)
    differentiated by central differences and scaled by x' = speed.
    """
    count = int(np.ceil(np.linalg.norm(end[:3, 3] - start[:3, 3]) / step)) + 1
    fraction = np.linspace(0.0, 1.0, count)
    poses = np.repeat(start[None], count, axis=0)
    poses[:, :3, 3] = start[:3, 3] + fraction[:, None] * (end[:3, 3] - start[:3, 3])
    solved = ik(robot, poses, seed=ik(robot, poses[:1]).q[0])  # one branch, each joint's turn nearest the start
    assert solved.success.all()
    q = solved.q
    h = np.linalg.norm(end[:3, 3] - start[:3, 3]) / (count - 1)
    dq = np.gradient(q, h, axis=0)
    ddq = (q[2:] - 2.0 * q[1:-1] + q[:-2]) / h**2
    return np.abs(dq) * speed, np.abs(ddq) * speed**2


def test_a_lowered_cruise_speed_holds_the_joint_limits_at_its_slowest_point(tmp_path):
    """The written $VEL.CP, cruised at, keeps every joint within its limits (and 5 % more would not)."""
    src = kuka_program(tmp_path, ["BAS(#VEL_PTP,50)", "PTP P1", "$VEL.CP=3.0", "LIN P2"])
    text, report = retime(tmp_path, src, "kuka_kr6_r900")
    written = float(re.search(r"\$VEL\.CP=([\d.]+)", text).group(1)) * 1000.0
    assert written < 3000.0  # never faster than programmed
    robot = load_robot("kuka_kr6_r900")
    robot = dataclasses.replace(robot, T_flange_tool=np.eye(4))  # tool 0: the flange
    program = formats.read(src)
    p1, p2 = program.targets[0].pose, program.targets[1].pose
    velocity, acceleration = cruise_demand(robot, p1, p2, written)
    assert np.max(velocity / robot.v_max) <= 1.0 and np.max(acceleration / robot.a_max) <= 1.0
    faster_v, faster_a = cruise_demand(robot, p1, p2, 1.05 * written)
    assert max(np.max(faster_v / robot.v_max), np.max(faster_a / robot.a_max)) > 1.0  # the slowest point binds
    assert report["timing"]["lowered"]["count"] == 1


def test_converting_a_speed_set_at_run_time_says_so(tmp_path, capsys):
    """A PERS speeddata the program changes has no value another language could take: the converted motion is
    written at the language's slowest and listed (exit 1)."""
    path = rapid_module(tmp_path, ["PERS speeddata vWeld := [20,500,5000,1000];", "PROC tune()",
                                   "  vWeld.v_tcp := 40;", "ENDPROC"], ["MoveL P2, vWeld, fine, tool0;"])
    assert main(["convert", str(path), str(tmp_path / "speeds.csv"), "--robot", "abb_irb4600"]) == 1
    assert ("Speeds.mod:10: speed of 'MoveL P2, vWeld, fine, tool0;': vWeld: PERS speeddata the module changes "
            "(line 6) and does not assign a literal in the code running straight to this motion: set at run time: "
            "written at csv's slowest speed, set it before running") in capsys.readouterr().err
    assert formats.read(tmp_path / "speeds.csv").motions[1].speed == 1.0
