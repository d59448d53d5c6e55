"""Converted speeds run no faster: every source language x every target language x every speed unit.

Each source program is written here as its language's text (joint motion,
line, joint motion, line between four joint vectors of the KUKA KR 6, the
lines' targets as poses with their configuration data), with the speed
fields of one variant: every unit each language states (KRL %, m/s; RAPID
vN, \\T, a literal speeddata whose v_ori binds, vmax; FANUC %, sec, msec,
mm/sec, cm/min, deg/sec, max_speed; UR rad/s, m/s, t=, its defaults; CSV
mm/s, none). It is converted into every other language, written, and read
back with `trajcomp.formats.read`; each motion's field, as read back, is
run the controller's way, restated here independently of
`trajcomp.formats.speeds`: the path parameter s in [0, 1] cruises at a
rate c (1/s) between ramps at the rate the slowest joint allows, so every
joint runs at c |dq_j| and the TCP at c |dp/ds| (c L along a line):

- ``%`` p: c = min_j p/100 v_max_j / |dq_j|; UR movej v: c = v / max_j |dq_j|;
- a TCP speed v: v / L on a line, v / max|J_v(q(s)) dq| along a joint motion
  (1001 points); RAPID's v_ori and FANUC ``deg/sec`` w: w / the line's
  reorientation (max|J_w(q(s)) dq| along a joint motion);
- a time T: the trapezoid's cruise (a T - sqrt(a^2 T^2 - 4 a)) / 2;
- always within the arm's limits, c <= min_j v_max_j / |dq_j|.

Every motion whose start is known runs at c no larger than the source's
(so every joint and the TCP no faster, taking no less time); the first one,
from wherever the arm is, keeps its speed only where the unit is the same
(or a percentage meets a leading-axis speed, through the velocity limits),
else it is written at the target language's slowest and listed.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.arm.kinematics import fk, jacobian
from trajcomp.arm.robot import load_robot
from trajcomp.cli import main
from trajcomp.arm.transforms import matrix_to_pose, matrix_to_quat, matrix_to_rotvec, rotation_angle_between
from trajcomp.compensation.program_rewrite import convert_program
from trajcomp.formats.fanuc.configuration import encode as fanuc_config
from trajcomp.formats.rapid.configuration import encode as abb_confdata
from trajcomp.formats.speeds import arc_length
from trajcomp.programs.items import JOINT

ROBOT = load_robot("kuka_kr6_r900")
Q = np.radians([[0.0, -90.0, 90.0, 0.0, 45.0, 0.0],  # joint motion (start unknown)
                [5.0, -80.0, 95.0, 10.0, 40.0, 20.0],  # line: mostly a reorientation (v_ori can bind)
                [30.0, -60.0, 100.0, -20.0, 50.0, 60.0],  # joint motion
                [32.0, -62.0, 103.0, -20.0, 48.0, 62.0]])  # line
KINDS = ("joint", "linear", "joint", "linear")
EXTENSION = {"csv": ".csv", "krl": ".src", "rapid": ".mod", "fanuc_ls": ".ls", "urscript": ".script"}
VARIANTS = {  # language: {variant: (joint motions' field, lines' field)}
    "krl": {"percent, m/s": ("BAS(#VEL_PTP,30)", "$VEL.CP=0.25"), "slow": ("BAS(#VEL_PTP,3)", "$VEL.CP=0.004")},
    "rapid": {"vN": ("v200", "v100"), "T": ("v1000\\T:=2.5", "v1000\\T:=1.5"),
              "v_ori": ("[300,20,5000,1000]", "[300,20,5000,1000]"), "vmax": ("vmax", "vmax")},
    "fanuc_ls": {"%, mm/sec": ("30%", "250mm/sec"), "sec": ("2sec", "2sec"), "msec, cm/min": ("1500msec", "1200cm/min"),
                 "max_speed, deg/sec": ("max_speed", "30deg/sec"), "max_speed": ("max_speed", "max_speed")},
    "urscript": {"rad/s, m/s": ("v=0.8", "v=0.25"), "t": ("t=2.5", "t=1.5"), "defaults": ("", "")},
    "csv": {"mm/s": ("300", "150"), "none": ("", "")},
}
CASES = [(source, variant, target) for source in VARIANTS for variant in VARIANTS[source] for target in EXTENSION
         if target != source]


def numbers(values, places=6):
    return ",".join(f"{v:.{places}f}" for v in values)


def source_text(language, joint_field, line_field):
    """The program of ``language`` moving through `Q` with the given speed fields."""
    poses = fk(ROBOT, Q)
    xyzabc = matrix_to_pose(poses)
    fields = [joint_field if kind == "joint" else line_field for kind in KINDS]
    if language == "krl":
        lines = ["DEF src( )"]
        for q, p, kind, field in zip(Q, xyzabc, KINDS, fields):
            lines.append(f"  {field}")
            if kind == "joint":
                lines.append("  PTP {" + ",".join(f"A{j + 1} {v:.6f}" for j, v in enumerate(np.degrees(q))) + "}")
            else:
                values = [*p[:3], *np.degrees(p[3:])]
                lines.append("  LIN {" + ",".join(f"{n} {v:.6f}" for n, v in zip("XYZABC", values)) + "}")
        return "\r\n".join(lines + ["END"]) + "\r\n"
    if language == "rapid":
        decls, body = [], []
        for k, (q, T, kind, field) in enumerate(zip(Q, poses, KINDS, fields)):
            if kind == "joint":
                decls.append(f"  CONST jointtarget j{k} := [[{numbers(np.degrees(q))}],[9E9,9E9,9E9,9E9,9E9,9E9]];")
                body.append(f"    MoveAbsJ j{k}, {field}, fine, tool0;")
            else:
                conf = ",".join(map(str, abb_confdata(ROBOT, q[None])[0]))
                quat = numbers(matrix_to_quat(T[:3, :3]), 9)
                decls.append(f"  CONST robtarget p{k} := [[{numbers(T[:3, 3])}],[{quat}],"
                             f"[{conf}],[9E9,9E9,9E9,9E9,9E9,9E9]];")
                body.append(f"    MoveL p{k}, {field}, fine, tool0;")
        return "\n".join(["MODULE src", *decls, "  PROC main()", *body, "  ENDPROC", "ENDMODULE"]) + "\n"
    if language == "fanuc_ls":
        mn, pos = [], []
        for k, (q, p, kind, field) in enumerate(zip(Q, xyzabc, KINDS, fields), start=1):
            mn.append(f"{k:4d}:{'J' if kind == 'joint' else 'L'} P[{k}] {field} FINE ;")
            if kind == "joint":
                j = np.degrees(q)
                pos.append(f"P[{k}]{{\n   GP1:\n\tUF : 0, UT : 0,\n" + ",".join(f"\tJ{i + 1}= {v:.6f} deg" for i, v in
                                                                             enumerate(j)) + "\n};")
            else:
                c = fanuc_config(ROBOT, q[None])[0]
                w, pp, r = np.degrees(p[[5, 4, 3]])
                pos.append(f"P[{k}]{{\n   GP1:\n\tUF : 0, UT : 0,\t\tCONFIG : '{c[0]} {c[1]} {c[2]}, {c[3]}, {c[4]}, "
                           f"{c[5]}',\n\tX = {p[0]:.6f} mm,\tY = {p[1]:.6f} mm,\tZ = {p[2]:.6f} mm,\n"
                           f"\tW = {w:.6f} deg,\tP = {pp:.6f} deg,\tR = {r:.6f} deg\n}};")
        return "\n".join(["/PROG SRC", "/ATTR", "/MN", *mn, "/POS", *pos, "/END"]) + "\n"
    if language == "urscript":
        lines = ["def src():"]
        for q, T, kind, field in zip(Q, poses, KINDS, fields):
            option = f", {field}" if field else ""
            if kind == "joint":
                lines.append(f"  movej([{numbers(q, 9)}]{option})")
            else:
                lines.append(f"  movel(p[{numbers(T[:3, 3] / 1000.0, 9)}, {numbers(matrix_to_rotvec(T[:3, :3]), 9)}]"
                             f"{option})")
        return "\n".join(lines + ["end", "src()"]) + "\n"
    rows = ["x,y,z,a,b,c,motion,speed,j1,j2,j3,j4,j5,j6"]
    for q, p, kind, field in zip(Q, xyzabc, KINDS, fields):
        rows.append(f"{numbers([*p[:3], *np.degrees(p[3:])])},{'PTP' if kind == 'joint' else 'LIN'},{field},"
                    f"{numbers(np.degrees(q))}")
    return "\n".join(rows) + "\n"


def geometry(k):
    """(dq (6,), TCP extent, orientation extent) of motion k: along a line its length (mm) and reorientation
    (rad); along a joint motion the peaks of |dp/ds| and |dphi/ds| (1001 points)."""
    dq = Q[k] - Q[k - 1]
    if KINDS[k] == "linear":
        T = fk(ROBOT, Q[[k - 1, k]])
        return dq, np.linalg.norm(T[1, :3, 3] - T[0, :3, 3]), rotation_angle_between(T[0, :3, :3], T[1, :3, :3])
    rates = np.einsum("nij,j->ni", jacobian(ROBOT, Q[k - 1] + np.linspace(0, 1, 1001)[:, None] * dq), dq)
    return dq, np.linalg.norm(rates[:, :3], axis=1).max(), np.linalg.norm(rates[:, 3:], axis=1).max()


def rate(motion, k):
    """The cruise rate (1/s) of motion k under its field as read (see the module)."""
    dq, tcp, turn = geometry(k)
    moving = np.abs(dq) > 0
    limit = np.min(ROBOT.v_max[moving] / np.abs(dq[moving]))
    speed, unit = motion.speed, motion.speed_unit
    out = [limit]
    if speed is not None:
        if unit == "%":
            out.append(speed / 100.0 * limit)
        elif unit == "rad/s":
            out.append(speed / np.abs(dq).max() if motion.kind == JOINT else speed / turn)
        elif unit == "mm/s":
            out.append(speed / tcp)
        else:
            a = np.min(ROBOT.a_max[moving] / np.abs(dq[moving]))
            out.append(0.5 * (a * speed - np.sqrt(max((a * speed) ** 2 - 4.0 * a, 0.0))))
    if motion.orientation_speed is not None:
        out.append(motion.orientation_speed / turn)
    return min(out)


@pytest.mark.parametrize("source,variant,target", CASES)
def test_a_converted_motion_runs_no_faster_than_its_source(tmp_path, source, variant, target):
    path = tmp_path / f"src{EXTENSION[source]}"
    path.write_text(source_text(source, *VARIANTS[source][variant]))
    program = formats.read(path)
    assert [m.kind for m in program.motions] == list(KINDS) and not any(m.speed_why for m in program.motions)
    converted = convert_program(program, target, robot=ROBOT)
    formats.write(tmp_path / f"out{EXTENSION[target]}", converted)
    again = formats.read(tmp_path / f"out{EXTENSION[target]}")
    assert [m.kind for m in again.motions] == list(KINDS)
    # every speed stated (KRL: a BAS(#VEL_PTP) before each PTP), but a KRL line at the arm's limits: no $VEL.CP,
    # the one in force is no faster
    assert not any(m.speed_why for m, stated in zip(again.motions, program.motions)
                   if m.kind == JOINT or stated.speed is not None)
    listed = [bool(m.speed_why) for m in converted.motions]
    assert not any(listed[1:])  # every motion whose start is known is converted
    for k in range(1, 4):
        before, after = rate(program.motions[k], k), rate(again.motions[k], k)
        assert after <= before * (1 + 1e-9), (k, program.motions[k], again.motions[k])
        if program.motions[k].speed is not None:  # converted, not merely slowed (a language's defaults may be)
            assert after >= 0.5 * before
    first, written = program.motions[0], again.motions[0]
    if listed[0]:  # written at the slowest: 1 %, 1 mm/s (v_ori 1 deg/s), UR 1 deg/s
        slowest = {"%": 1.0, "mm/s": 1.0, "rad/s": np.radians(1.0)}[written.speed_unit]
        assert 0.999 * slowest <= written.speed <= slowest
    elif first.speed is not None and written.speed_unit == first.speed_unit:  # kept
        assert written.speed == pytest.approx(first.speed, rel=1e-6) and written.speed <= first.speed
    elif first.speed is not None:  # a percentage and a leading-axis speed: every joint no faster, whatever it moves
        percent, axis = (written, first) if written.speed_unit == "%" else (first, written)
        assert {percent.speed_unit, axis.speed_unit} == {"%", "rad/s"}
        if written is percent:
            assert percent.speed / 100.0 * ROBOT.v_max.max() <= axis.speed * (1 + 1e-9)
        else:
            assert axis.speed <= percent.speed / 100.0 * ROBOT.v_max.min() * (1 + 1e-9)
    else:  # the arm's limits: the target's own (none; KRL, FANUC 100 %; RAPID vmax; UR's default 1.05 rad/s)
        assert (written.speed, written.speed_unit) in ((None, "mm/s"), (100.0, "%"), (5000.0, "mm/s"), (1.05, "rad/s"))


def test_a_speed_set_at_run_time_is_written_at_the_slowest_and_listed(tmp_path):
    text = source_text("krl", "BAS(#VEL_PTP,30)", "$VEL.CP=0.25").replace("$VEL.CP=0.25", "$VEL.CP=vWeld", 1)
    (tmp_path / "src.src").write_text(text)
    program = formats.read(tmp_path / "src.src")
    assert program.motions[1].speed_why
    for target in ("rapid", "fanuc_ls", "urscript", "csv"):
        converted = convert_program(program, target, robot=ROBOT)
        assert "set it before running" in converted.motions[1].speed_why
        formats.write(tmp_path / f"out{EXTENSION[target]}", converted)
        line = formats.read(tmp_path / f"out{EXTENSION[target]}").motions[1]
        assert (line.speed, line.speed_unit) == (1.0, "mm/s")


def test_compensate_to_another_language_lists_the_speed_it_could_not_carry_over(tmp_path, kuka_model, capsys):
    """The example weld's first PTP, 50 % of the axis speeds from wherever the arm is, has no CSV speed (a TCP
    speed) it is sure to be no faster than: written at 1 mm/s, the speeds criterion fails (exit 1) naming it."""
    weld = Path(__file__).resolve().parents[2] / "examples" / "programs" / "kuka" / "weld.src"
    out, report = tmp_path / "weld.csv", tmp_path / "weld.json"
    assert main(["compensate", str(weld), "--model", str(kuka_model), "-o", str(out), "--to", "csv",
                 "--report", str(report), "--json-only"]) == 1
    doc = json.loads(report.read_text())
    [speeds] = [c for c in doc["verdict"]["criteria"] if c["id"] == "speeds"]
    assert speeds["status"] == "fail" and "speed 50 % cannot be converted (its start is unknown)" in speeds["detail"]
    assert "speeds" in capsys.readouterr().err
    assert formats.read(out).motions[0].speed == 1.0


@pytest.mark.parametrize("end,via", [(90, 45), (270, 135), (180, 90), (60, 10), (342, 180), (11.5, 5)])
def test_a_circles_length_is_its_arc_through_the_via_point(end, via):
    """r theta of a circle of 100 mm from 0 deg through ``via`` to ``end`` (the minor or the major arc)."""
    def at(angle):
        return np.array([100.0 * np.cos(np.radians(angle)), 100.0 * np.sin(np.radians(angle)), 5.0])

    assert arc_length(np.array([at(0), at(via), at(end)])) == pytest.approx(100.0 * np.radians(end), rel=1e-12)
    assert arc_length(np.array([at(0), at(end)])) == pytest.approx(np.linalg.norm(at(end) - at(0)))
