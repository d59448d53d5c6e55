"""Never faster along every path a program can take: speeds, starts and waits read as each controller runs them.

Hand-written programs in the forms their controllers hold (routines and
calls, branches, loops, jumps and labels, waits, every speed form) are
re-timed (``retime``), compensated and re-timed (``compensate --retime
auto``) and converted into the other languages. Each written program is
then run the controller's way by `tests.timing.controller_paths` (every
path: each branch, each loop 0-2 times, into each called routine and back),
independently of trajcomp's reading, and every motion's written field is
compared with the slowest programmed setting that can reach it on the
program as written:

- a speed (KRL ``$VEL.CP``, ``BAS(#VEL_PTP)`` / ``$VEL_AXIS``): the one in
  force at the motion on every path of the output is no faster than the
  slowest on any path of the input;
- a time (RAPID ``\\T``, UR ``t=``, FANUC ``msec``): no shorter than the
  controller's least time for the motion from every start it can have
  (the programmed speed's cruise over the distance, under VelSet, the
  programmed acceleration); a motion whose start is not unique has no time
  written;
- a motion whose speed or start the program does not give (a routine of
  another file) is left as written and listed.
"""

import re

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.cli import main
from trajcomp.programs.items import JOINT
from tests.conftest import calibrated_model
from tests.timing.controller_paths import Op, by_motion, slowest, visits

KRL_SRC = """DEF main( )
  DECL INT I
  BAS(#VEL_PTP,100)
  $VEL.CP=3.0
  $APO.CDIS=5
  PTP HOME
  LIN P1 C_DIS
  LIN P2
  slow()
  LIN P3
  LIN P4
  IF $IN[1] THEN
    $VEL.CP=0.05
  ELSE
    $VEL={CP 2.0,ORI1 200,ORI2 200}
  ENDIF
  LIN P5
  FOR I=1 TO 3
    LIN P6 C_DIS
    LIN P7 C_DIS
  ENDFOR
  $VEL.CP=3.0
  WHILE $IN[2]
    LIN P8
    fast()
  ENDWHILE
  LIN P9 C_DIS
  WAIT SEC 2.0
  LIN P10
  $VEL_AXIS[6]=5
  PTP P11
  other()
  LIN P12
END

DEF slow( )
  $VEL.CP=0.02
END

DEF fast( )
  $VEL.CP=3.0
  LIN P13
END
"""
KRL_POINTS = {"P1": (400, -100, 700), "P2": (480, -100, 700), "P3": (480, 0, 700), "P4": (400, 0, 650),
              "P5": (450, 50, 650), "P6": (500, 50, 700), "P7": (500, -50, 700), "P8": (420, -50, 620),
              "P9": (420, 60, 720), "P10": (480, 60, 720), "P11": (400, -80, 640), "P12": (460, -80, 640),
              "P13": (430, 0, 740)}
KRL_DAT = ("DEFDAT main\n  DECL E6AXIS HOME={A1 0,A2 -90,A3 90,A4 0,A5 45,A6 0}\n"
           + "".join(f"  DECL E6POS {name}={{X {x},Y {y},Z {z},A 0,B 90,C 0}}\n"
                     for name, (x, y, z) in KRL_POINTS.items()) + "ENDDAT\n")
OTHER_SRC = "DEF other( )\n  $VEL.CP=0.01\n  PTP HOME\nEND\n"


def krl_ops(text):
    """The controller's reading of a KRL .src (`controller_paths.Op`), from its lines alone."""
    ops = []
    for line in text.splitlines():
        line = line.split(";")[0].strip()
        upper = line.upper()
        if m := re.match(r"DEF\s+(\w+)", line, re.I):
            ops.append(Op("routine", m.group(1)))
        elif upper in ("END", "ENDIF", "ELSE", "ENDFOR", "ENDWHILE", "ENDLOOP", "LOOP", "EXIT"):
            ops.append(Op({"END": "end", "ENDIF": "endif", "ELSE": "else", "ENDFOR": "endloop",
                           "ENDWHILE": "endloop", "ENDLOOP": "endloop", "LOOP": "loop", "EXIT": "exit"}[upper]))
        elif re.match(r"(IF\b.*THEN)$", upper):
            ops.append(Op("if"))
        elif re.match(r"(FOR|WHILE)\b", upper):
            ops.append(Op("loop"))
        elif re.match(r"WAIT\s+(SEC|FOR)\b", upper):
            ops.append(Op("wait"))
        elif m := re.match(r"GOTO\s+(\w+)$", line, re.I):
            ops.append(Op("jump", m.group(1)))
        elif m := re.match(r"(\w+)\s*:$", line):
            ops.append(Op("label", m.group(1)))
        elif m := re.match(r"\$VEL\.CP\s*=\s*([\d.]+)$", line, re.I):
            ops.append(Op("set", "cp", float(m.group(1))))
        elif m := re.match(r"\$VEL\s*=\s*\{.*\bCP\s+([\d.]+)", line, re.I):
            ops.append(Op("set", "cp", float(m.group(1))))
        elif m := re.match(r"BAS\s*\(\s*#VEL_PTP\s*,\s*([\d.]+)\s*\)$", line, re.I):
            ops += [Op("set", f"a{n}", float(m.group(1))) for n in range(1, 7)]
        elif m := re.match(r"\$VEL_AXIS\[(\d)\]\s*=\s*([\d.]+)$", line, re.I):
            ops.append(Op("set", f"a{m.group(1)}", float(m.group(2))))
        elif m := re.match(r"(PTP|LIN)\s+(\w+)", line, re.I):
            ops.append(Op("motion", f"{m.group(1).upper()} {m.group(2).upper()}"))
        elif m := re.match(r"(\w+)\s*\(\s*\)$", line):
            ops.append(Op("call", m.group(1)))
    return ops


KRL_START = {"cp": None} | {f"a{n}": None for n in range(1, 7)}


def krl_files(folder):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "main.src").write_text(KRL_SRC)
    (folder / "main.dat").write_text(KRL_DAT)
    (folder / "other.src").write_text(OTHER_SRC)
    return folder / "main.src"


def assert_krl_no_faster(source_text, written_text):
    """Every motion of the written KRL runs no faster on any path than the source runs it on that path."""
    before = visits(krl_ops(source_text), "main", KRL_START)
    after = visits(krl_ops(written_text), "main", KRL_START)
    assert before.keys() == after.keys()
    for (key, path), seen in after.items():
        for group in ["cp"] if key.startswith("LIN") else [f"a{n}" for n in range(1, 7)]:
            allowed, written = before[(key, path)].setting(group), seen.setting(group)
            if allowed is None:  # the source sets none: nothing may be set for it
                assert written is None, (key, path, group)
            else:
                assert written is not None and written <= allowed + 1e-9, (key, path, group, allowed, written)


def test_krl_reader_follows_calls_branches_loops_and_waits(tmp_path):
    program = formats.read(krl_files(tmp_path))
    table = program.motion_table()
    by_line = {program.motions[k].text.split()[1]: k for k in range(len(table))}
    speed = dict(zip(by_line, table.speed[list(by_line.values())]))
    assert speed["P3"] == speed["P4"] == 20.0  # slow() set 0.02 m/s before them
    assert speed["P5"] == speed["P6"] == 50.0  # IF .. ELSE: 0.05 or 2.0 m/s, the slowest
    assert speed["P11"] == 5.0  # A6 at 5 %, the others 100 %
    assert "other" in table.speed_why[by_line["P12"]] and "other" in table.start_why[by_line["P12"]]
    assert table.start_why[by_line["P6"]] and table.start_why[by_line["P9"]]  # a loop's back jump, after fast()
    assert not table.start_why[by_line["P3"]]  # slow() moves nothing: P3 starts at P2
    assert np.isnan(table.zone[by_line["P9"]])  # WAIT SEC after its C_DIS: it stops there
    assert table.zone[by_line["P6"]] == 5.0


def test_krl_retimed_and_compensated_run_no_faster_on_any_path(tmp_path, kuka_model, capsys):
    source = krl_files(tmp_path / "in")
    out = tmp_path / "out"
    out.mkdir()
    assert main(["retime", str(source), "-o", str(out / "main.src"), "--robot", "kuka_kr6_r900"]) in (0, 1)
    listed = capsys.readouterr()
    assert "P12" in listed.out + listed.err  # its speed and start are another file's: left as written, listed
    assert_krl_no_faster(KRL_SRC, (out / "main.src").read_text())
    comp = tmp_path / "comp"
    comp.mkdir()
    assert main(["compensate", str(source), "--model", str(kuka_model), "--retime", "auto",
                 "-o", str(comp / "main.src")]) in (0, 1)
    assert_krl_no_faster(KRL_SRC, (comp / "main.src").read_text())


KRL_RESTORED = {  # a speed lowered inside a loop, and inside a branch, before motions that keep theirs
    "loop": "  WHILE $IN[2]\n    LIN P2\n    $VEL.CP=3.0\n    LIN P3\n    LIN P4\n  ENDWHILE\n  LIN P5\n",
    "branch": "  IF $IN[1] THEN\n    $VEL.CP=3.0\n    LIN P2\n    LIN P3\n  ENDIF\n  LIN P4\n  LIN P5\n",
}


def test_krl_goto_over_a_speed_setting_runs_no_faster_on_either_path(tmp_path):
    """GOTO over ``$VEL.CP=0.02``: the LIN after the label runs at 3 m/s or 0.02 m/s, the slowest reaching it."""
    source = ("DEF main( )\n  BAS(#VEL_PTP,100)\n  $VEL.CP=3.0\n  PTP HOME\n  LIN P1\n  IF $IN[1] THEN\n"
              "    GOTO SKIP\n  ENDIF\n  $VEL.CP=0.02\n  LIN P3\n  SKIP:\n  LIN P2\n  LIN P4\nEND\n")
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "main.src").write_text(source)
    (folder / "main.dat").write_text(KRL_DAT)
    table = formats.read(folder / "main.src").motion_table()
    assert table.speed[3] == 20.0 and table.start_why[3]  # after P1 (the jump) or P3
    out = tmp_path / "out" / "main.src"
    out.parent.mkdir()
    assert main(["retime", str(folder / "main.src"), "-o", str(out), "--robot", "kuka_kr6_r900"]) == 0
    assert_krl_no_faster(source, out.read_text())


@pytest.mark.parametrize("body", sorted(KRL_RESTORED))
def test_krl_speed_set_back_so_every_path_runs_the_programmed_speed(tmp_path, body):
    """A $VEL.CP inserted for a motion the timing slows sets the modal speed for whatever runs next on every path:
    the loop's next iteration, the motions after the branch. Run every path the controller's way: each motion
    runs at its programmed speed on every path, or at one lowered speed on every path (the timing's), and never
    faster."""
    source = ("DEF main( )\n  BAS(#VEL_PTP,100)\n  $VEL.CP=0.05\n  PTP HOME\n  LIN P1\n" + KRL_RESTORED[body]
              + "END\n")
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "main.src").write_text(source)
    (folder / "main.dat").write_text(KRL_DAT)
    out = tmp_path / "out" / "main.src"
    out.parent.mkdir()
    assert main(["retime", str(folder / "main.src"), "-o", str(out), "--robot", "kuka_kr6_r900"]) == 0
    before, after = visits(krl_ops(source), "main", KRL_START), visits(krl_ops(out.read_text()), "main", KRL_START)
    assert before.keys() == after.keys()
    runs = {}
    for (key, path), seen in after.items():
        if key.startswith("LIN"):
            runs.setdefault(key, []).append((before[(key, path)].setting("cp"), seen.setting("cp")))
    lowered = 0
    for key, pairs in runs.items():
        assert all(written <= programmed for programmed, written in pairs), (key, pairs)
        if any(written != programmed for programmed, written in pairs):
            assert len({written for _, written in pairs}) == 1, (key, pairs)  # one lowered speed on every path
            lowered += 1
    assert lowered >= 1 and lowered < len(runs)


@pytest.mark.parametrize("target", [".mod", ".ls", ".script", ".csv"])
def test_krl_converted_runs_no_faster_than_any_path(tmp_path, target, makerless):
    source = krl_files(tmp_path / "in")
    program = formats.read(source)
    allowed = by_motion(visits(krl_ops(KRL_SRC), "main", KRL_START))
    out = tmp_path / f"out{target}"
    assert main(["convert", str(source), str(out), "--robot", makerless("kuka_kr6_r900")]) in (0, 1)
    again = formats.read(out)
    lines = [m for m in program.motions if m.kind != JOINT]
    written = [m for m in again.motions if m.kind != JOINT]
    assert len(written) == len(lines)
    for motion, converted in zip(lines, written):
        key = " ".join(motion.text.split()[:2]).upper()
        cp = slowest(allowed[key], "cp")
        if converted.speed_unit == "mm/s" and converted.speed is not None:
            assert cp is not None and converted.speed <= 1000.0 * cp + 1e-6, (key, converted.speed, cp)


RAPID_POINTS = {"P1": (1135, 0, 1415), "P2": (1195, 0, 1335), "P3": (1195, 80, 1335), "P4": (1135, 80, 1300),
                "P5": (1160, 40, 1380), "P6": (1300, 250, 1000), "P7": (1220, 40, 1300), "P8": (1100, 40, 1300)}
RAPID_MODULE = ("MODULE Cell\n" + "".join(
    f"  CONST robtarget {name}:=[[{x},{y},{z}],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
    for name, (x, y, z) in RAPID_POINTS.items()) + """  VAR num n := 0;
  PROC main()
    MoveJ P1, v1000, fine, tool0;
    MoveL P2, v1000, z10, tool0;
    go_far;
    MoveJ P5, v100, fine, tool0;
    VelSet 100, 20;
    MoveJ P4, v1000, fine, tool0;
    MoveL P2, v1000\\V:=800, z10, tool0;
    MoveL P3, v1000\\T:=0.2, fine, tool0;
    VelSet 50, 5000;
    AccSet 50, 100;
    WHILE n < 3 DO
      MoveL P7, v500, z10, tool0;
      MoveL P8, v500, z10, tool0;
      Incr n;
    ENDWHILE
    IF n = 3 THEN
      VelSet 100, 5000;
    ELSE
      VelSet 10, 5000;
    ENDIF
    MoveL P1, v1000, z10, tool0;
    WaitTime 0.5;
    MoveL P3, v1000, z10, tool0;
    WaitDI di1, 1;
    MoveJ P4, v1000, fine, tool0;
    Elsewhere;
    MoveJ P5, v1000, fine, tool0;
  ENDPROC
  PROC go_far()
    MoveJ P6, v1000, fine, tool0;
  ENDPROC
ENDMODULE
""")


SLOWEST_MM_S = 1.0  # a speed that cannot be carried over is written at the target's slowest


def rapid_ops(text):
    """The controller's reading of a RAPID module: each motion keyed by its order in the file, with its TCP
    speed (mm/s), time (\\T) and point; VelSet as settings."""
    ops, count = [], 0
    for line in text.splitlines():
        line = line.split("!")[0].strip()
        word = line.split(" ")[0].rstrip(";").upper() if line else ""
        if m := re.match(r"PROC\s+(\w+)", line, re.I):
            ops.append(Op("routine", m.group(1)))
        elif word in ("ENDPROC", "ENDIF", "ELSE", "ENDWHILE"):
            ops.append(Op({"ENDPROC": "end", "ENDIF": "endif", "ELSE": "else", "ENDWHILE": "endloop"}[word]))
        elif word == "IF":
            ops.append(Op("if"))
        elif m := re.match(r"GOTO\s+(\w+)\s*;$", line, re.I):
            ops.append(Op("jump", m.group(1)))
        elif m := re.match(r"(\w+):$", line):
            ops.append(Op("label", m.group(1)))
        elif word == "WHILE":
            ops.append(Op("loop"))
        elif word.startswith("WAIT"):
            ops.append(Op("wait"))
        elif m := re.match(r"VelSet\s+([\d.]+)\s*,\s*([\d.]+)", line, re.I):
            ops.append(Op("set", "velset", (float(m.group(1)), float(m.group(2)))))
        elif m := re.match(r"Move[LJ]\s+(\w+)\s*,\s*v(\d+)((?:\\\w+:=[\d.]+)*)\s*,\s*(\w+)", line, re.I):
            options = dict(re.findall(r"\\(\w+):=([\d.]+)", m.group(3)))
            ops.append(Op("motion", f"m{count}", (m.group(1), float(m.group(2)), options.get("V"), options.get("T"),
                                                   m.group(4).lower() != "fine")))
            count += 1
        elif re.match(r"\w+;$", line) and word not in ("ENDMODULE",):
            ops.append(Op("call", line.rstrip(";")))
    return ops


def rapid_points(text):
    """``{name: (x, y, z)}`` of a module's robtargets, mm."""
    return {name: tuple(float(v) for v in xyz.split(",")) for name, xyz in
            re.findall(r"robtarget\s+(\w+)\s*:=\s*\[\[([^\]]*)\]", text)}


def rapid_least_times(text, points=None):
    """``{(motion key, path): least time}``: the least time the controller takes for each motion visit (its
    distance from where the path's motion before it ends, between ``points`` (the module's own by default), over
    its speed under the VelSet in force; no time where the path starts there), and ``{motion key: (point, v, V, T,
    zone)}``."""
    points = points or rapid_points(text)
    ops = rapid_ops(text)
    fields = {op.name: op.value for op in ops if op.kind == "motion"}
    out = {}
    for (key, path), visit in visits(ops, "main", {"velset": (100.0, 5000.0)}).items():
        override, top = visit.setting("velset")
        point, v, own_v, t, _ = fields[key]
        speed = min((float(own_v) if own_v else v) * override / 100.0, top)
        if t is not None:  # the controller takes the time, whatever the VelSet's max (its override stretches it)
            least = float(t) * 100.0 / override
        else:
            least = None if not visit.before else np.linalg.norm(
                np.subtract(points[point], points[fields[visit.before][0]])) / speed
        out[(key, path)] = (least, speed, visit)
    return out, fields


def assert_rapid_no_faster(source_text, written_text):
    """Every motion of the written module takes, on every path, no less time than the source's speeds allow on that
    path over the written points (compensated ones move a little)."""
    before, source = rapid_least_times(source_text, rapid_points(written_text))
    after, written = rapid_least_times(written_text)
    assert before.keys() == after.keys()
    checked = 0
    for (key, path), (_, speed, visit) in after.items():
        least, allowed, _ = before[(key, path)]
        point, v, own_v, t, _ = written[key]
        if written[key] == source[key]:  # left as written
            continue
        if t is not None:  # a time: the controller takes it, whatever the VelSet (its max does not hold a \T)
            assert least is not None, (key, path, "a time written for a motion whose start is not unique")
            assert float(t) >= least * (1 - 1e-6), (key, path, float(t), least)
            checked += 1
        else:
            assert speed <= allowed + 1e-9, (key, path, speed, allowed)
    return checked


RAPID_FIELDS = {op.name: op.value for op in rapid_ops(RAPID_MODULE) if op.kind == "motion"}


@pytest.fixture
def rapid_source(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "Cell.mod").write_text(RAPID_MODULE)
    return folder / "Cell.mod"


def test_rapid_reader_follows_calls_loops_branches_velset_and_waits(rapid_source):
    program = formats.read(rapid_source)
    table = program.motion_table()
    lines = {int(line): k for k, line in enumerate(table.line)}
    text = RAPID_MODULE.splitlines()
    at = {f"{n}": lines[i + 1] for n, i in enumerate(i for i, line in enumerate(text) if "Move" in line)}
    assert "line 41" in table.start_why[at["2"]]  # after go_far: it starts at go_far's P6, not at P2
    assert table.speed[at["3"]] == 20.0 and table.speed[at["4"]] == 20.0  # VelSet 100, 20 caps v1000 and \V:=800
    # \T:=0.2 under VelSet 100, 20: a stated time is not held to VelSet's max (RAPID reference, VelSet's
    # limitations): read as its time, timed, not left as written
    assert table.speed[at["5"]] == 0.2 and table.speed_unit[at["5"]] == "s" and not table.speed_why[at["5"]]
    assert table.speed[at["6"]] == 250.0 and table.start_why[at["6"]]  # VelSet 50: v500 at half; after P4 or P8
    assert table.speed[at["8"]] == 100.0  # IF: VelSet 100 or 10: the slowest, 10 % of v1000
    assert np.isnan(table.acceleration_share[at["5"]]) and table.acceleration_share[at["6"]] == 0.5  # AccSet 50
    assert np.isnan(table.zone[at["8"]]) and np.isnan(table.zone[at["9"]])  # WaitTime, WaitDI after them
    assert "Elsewhere" in table.start_why[at["11"]] and "Elsewhere" in table.speed_why[at["11"]]


RAPID_GOTO = RAPID_MODULE.split("  PROC main()")[0] + """  PROC main()
    MoveJ P1, v1000, fine, tool0;
    MoveL P2, v1000, fine, tool0;
    IF di1 = 1 THEN
      GOTO skip;
    ENDIF
    VelSet 100, 20;
    MoveL P3, v1000, fine, tool0;
    skip:
    MoveL P4, v1000, fine, tool0;
    MoveJ P5, v1000, fine, tool0;
    again:
    MoveL P7, v500, z10, tool0;
    MoveJ P8, v500, fine, tool0;
    Incr n;
    IF n < 3 THEN
      GOTO again;
    ENDIF
    MoveJ P1, v1000, fine, tool0;
  ENDPROC
ENDMODULE
"""


def test_rapid_goto_forward_over_a_velset_and_back_as_a_loop_runs_no_faster_on_any_path(tmp_path, abb_model,
                                                                                        makerless):
    """``GOTO skip`` over ``VelSet 100, 20``: the MoveL after the label runs at 1000 or 20 mm/s, from P2 or P3;
    ``GOTO again`` back: the first motion after the label starts at P5 or P8. Run every path the controller's way
    (retime, compensate, each conversion): nothing faster, no time from a start that is not unique."""
    source = tmp_path / "in" / "Goto.mod"
    source.parent.mkdir()
    source.write_text(RAPID_GOTO)
    table = formats.read(source).motion_table()
    assert table.speed[3] == 20.0 and table.start_why[3]  # after P2 (the jump) or P3 (under VelSet 100, 20)
    assert table.start_why[5] and not table.start_why[6]  # P7: after P5 or P8; P8 after P7
    for run in (["retime", "--robot", "abb_irb4600"], ["compensate", "--model", str(abb_model), "--retime", "auto"]):
        out = tmp_path / run[0] / "Goto.mod"
        out.parent.mkdir()
        assert main([run[0], str(source), "-o", str(out), *run[1:]]) in (0, 1)
        assert assert_rapid_no_faster(RAPID_GOTO, out.read_text()) >= 2
    for target in (".src", ".ls", ".script", ".csv"):
        assert_converted_no_faster(source, rapid_ops(RAPID_GOTO), "main", {"velset": (100.0, 5000.0)},
                                   rapid_line_speed, target, makerless("abb_irb4600"), tmp_path)


def test_rapid_retimed_and_compensated_run_no_faster_on_any_path(rapid_source, tmp_path, capsys, abb_model):
    out = tmp_path / "out" / "Cell.mod"
    out.parent.mkdir()
    assert main(["retime", str(rapid_source), "-o", str(out), "--robot", "abb_irb4600"]) in (0, 1)
    assert assert_rapid_no_faster(RAPID_MODULE, out.read_text()) >= 3  # times written, each checked
    captured = capsys.readouterr()
    assert "start not unique" in captured.out + captured.err
    comp = tmp_path / "comp" / "Cell.mod"
    comp.parent.mkdir()
    assert main(["compensate", str(rapid_source), "--model", str(abb_model), "--retime", "auto",
                 "-o", str(comp)]) in (0, 1)
    assert rapid_points(comp.read_text()) != rapid_points(RAPID_MODULE)  # compensated
    assert assert_rapid_no_faster(RAPID_MODULE, comp.read_text()) >= 3


def test_motions_whose_start_is_not_unique_are_listed_as_unknown_not_failed(rapid_source, tmp_path, capsys):
    """A loop's first motion, one after a call or a branch, one after a call of another module's routine: not
    timed, left as written (no faster than programmed): the criterion ``starts`` is not evaluated and lists them,
    ``speeds`` (speeds set at run time) passes, the verdict passes on what was checked and the run exits 0."""
    import json

    out, report = tmp_path / "out" / "Cell.mod", tmp_path / "report.json"
    out.parent.mkdir()
    assert main(["retime", str(rapid_source), "-o", str(out), "--robot", "abb_irb4600", "--report", str(report)]) == 0
    doc = json.loads(report.read_text())
    criteria = {c["id"]: c for c in doc["verdict"]["criteria"]}
    assert doc["verdict"]["result"] == "pass" and criteria["speeds"]["status"] == "pass"
    starts = criteria["starts"]
    assert starts["status"] == "not evaluated" and "not checked" in starts["detail"]
    ops = rapid_ops(RAPID_MODULE)
    keys = [op.name for op in ops if op.kind == "motion"]
    seen = by_motion(visits(ops, "main", {"velset": (100.0, 5000.0)}))
    several = [k for n, k in enumerate(keys) if {v.before for v in seen[k]} != {keys[n - 1] if n else ""}]
    several += [keys[-1]]  # after Elsewhere, a routine of another module: its start is not known
    assert doc["timing"]["unknown_start"]["count"] == len(several) == len(starts["targets"])
    assert "start not unique" in capsys.readouterr().err


TURNED = "0,0.258819,0.965926,0"  # the orientation [0,0,1,0] turned by 30 deg
RAMP_MODULE = ("MODULE Ramp\n" + "".join(
    f"  CONST robtarget {name}:=[[{x},{y},{z}],[{q}],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
    for name, (x, y, z, q) in {"P1": (1135, 0, 1415, "0,0,1,0"), "P2": (1135, 0, 1415, TURNED),
                               "P3": (1195, 80, 1335, "0,0,1,0"), "P4": (1195, 80, 1335, TURNED)}.items())
    + """  PROC main()
    MoveJ P1, v1000, fine, tool0;
    IF di1 = 1 THEN
      AccSet 100, 50;
    ENDIF
    MoveL P2, v1000, fine, tool0;
    MoveJ P3, v1000, fine, tool0;
    MoveL P1, v200, fine, tool0;
    AccSet 100, 100 \\FinePointRamp:=40;
    MoveL P2, v1000, z10, tool0;
    MoveJ P3, v1000, fine, tool0;
    AccSet 100, 100;
    MoveL P4, v1000, fine, tool0;
    MoveJ P1, v1000, fine, tool0;
  ENDPROC
ENDMODULE
""")


def ramp_ops(text):
    """The controller's reading of a RAPID module with AccSet: `tests.timing.test_control_flow.rapid_ops` line by
    line, the motions keyed in file order, and ``AccSet acc, ramp [\\FinePointRamp:=f]`` as the setting ``ramp``:
    (ramp, f) in %, f the ramp towards a fine point (the ramp where not given)."""
    ops = []
    for line in text.splitlines():
        if m := re.match(r"\s*AccSet\s+[\d.]+\s*,\s*([\d.]+)\s*(?:\\FinePointRamp:=([\d.]+))?\s*;", line, re.I):
            ops.append(Op("set", "ramp", (float(m.group(1)), float(m.group(2) or m.group(1)))))
            continue
        for op in rapid_ops(line):
            motion = op.kind == "motion"
            ops.append(Op("motion", f"m{sum(o.kind == 'motion' for o in ops)}", op.value) if motion else op)
    return ops


@pytest.mark.parametrize("compensated", [False, True])
def test_rapid_softer_accset_ramp_gets_no_time_on_any_path_and_is_listed_not_failed(tmp_path, abb_model, compensated):
    """Behind an AccSet ramp below 100 % (on a branch; ``\\FinePointRamp`` towards a fine point) the controller keeps
    a ``\\T`` by cruising faster: on every path (`tests.timing.controller_paths`) a motion reached by a softer ramp
    has no time written, whatever its kind (a MoveJ, a MoveL that only turns the tool); one that runs at full ramps
    on every path gets its ``\\T``, no shorter than the reorientation at v1000's 500 deg/s or the joints' least
    time at their limits. The motions left as written are listed under ``modelled`` (not evaluated), not as speeds
    set at run time: ``speeds`` passes and so does the verdict."""
    import json

    from scipy.spatial.transform import Rotation
    from trajcomp.arm.robot import load_robot
    from tests.timing.test_timing_accelerations import least_joint_time, retimed

    q, _, text = retimed(tmp_path, "Ramp.mod", RAMP_MODULE, "abb_irb4600", model=abb_model if compensated else None)
    doc = json.loads((tmp_path / "report.json").read_text())
    source, written = ramp_ops(RAMP_MODULE), ramp_ops(text)
    fields = {op.name: op.value for op in source if op.kind == "motion"}
    out = {op.name: op.value for op in written if op.kind == "motion"}
    seen = by_motion(visits(source, "main", {"ramp": (100.0, 100.0)}))
    quaternions = {name: [float(v) for v in q_text.split(",")] for name, q_text in
                   re.findall(r"robtarget\s+(\w+)\s*:=\s*\[\[[^\]]*\],\s*\[([^\]]*)\]", text)}
    robot, keys, kept, timed = load_robot("abb_irb4600"), list(fields), 0, 0
    for n, key in enumerate(keys):
        point, _, _, time, blended = out[key]
        softer = any(min(v.setting("ramp")[0], 100.0 if blended else v.setting("ramp")[1]) < 100.0 for v in seen[key])
        if softer:  # no time written; a speed (\V) no faster than programmed
            assert time == fields[key][3] and float(out[key][2] or fields[key][1]) <= fields[key][1], (key, out[key])
            kept += 1
        elif time is not None:
            before = fields[keys[n - 1]][0]
            turn = (Rotation.from_quat(np.roll(quaternions[point], -1))
                    * Rotation.from_quat(np.roll(quaternions[before], -1)).inv()).magnitude()
            assert float(time) >= np.degrees(turn) / 500.0 * (1 - 1e-6), (key, time)
            assert float(time) >= least_joint_time(robot, q[n - 1], q[n], 1.0) * (1 - 1e-6), (key, time)
            timed += 1
    # behind the branch: a reorientation, a MoveJ, a line; the MoveJ to a fine point. Timed: the reorientations at
    # full ramps (compensated, they may travel a little: lines, their speeds written) and the last MoveJ
    assert kept == 4 and timed >= (1 if compensated else 3)
    criteria = {c["id"]: c for c in doc["verdict"]["criteria"]}
    assert criteria["speeds"]["status"] == "pass" and doc["timing"]["not_retimed"]["count"] == 0
    listed = [target.split(" ")[0] for target in criteria["modelled"]["targets"]]
    assert criteria["modelled"]["status"] == "not evaluated" and "AccSet ramp" in criteria["modelled"]["detail"]
    assert doc["timing"]["not_modelled"]["count"] == len(listed)
    # the MoveJs (and, as written, the reorientation: compensated it may travel a little, a line then, its speed
    # written); the line at its stated v200 keeps it
    assert listed == (["P3", "P3"] if out["m1"][2] is not None else ["P2", "P3", "P3"])
    if not compensated:
        assert doc["verdict"]["result"] == "pass"


FANUC_POINTS = {1: (385, 0, 595, "N U T"), 2: (385, 0, 515, "N U T"), 3: (445, 0, 515, "F U T"),
                4: (445, 40, 515, "N U T"), 5: (400, -60, 560, "N U T"), 6: (300, 200, 600, "N U T")}
FANUC_MN = """   1:  UFRAME_NUM=0 ;
   2:  UTOOL_NUM=0 ;
   3:J P[1] 50% FINE    ;
   4:L P[2] 200mm/sec CNT50    ;
   5:  CALL GRIP    ;
   6:L P[3] 200mm/sec FINE    ;
   7:  LBL[1] ;
   8:J P[4] 30% CNT100    ;
   9:J P[5] 30% FINE    ;
  10:  IF R[1]=1,JMP LBL[2] ;
  11:J P[6] 100% FINE    ;
  12:  JMP LBL[1] ;
  13:  LBL[2] ;
  14:L P[2] 100mm/sec CNT100    ;
  15:  WAIT   2.00(sec) ;
  16:J P[4] 40% FINE    ;
  17:J P[5] 40% CNT100    ;
  18:  WAIT DI[1]=ON ;
  19:J P[6] 40% FINE    ;
  20:  FOR R[2]=1 TO 3 ;
  21:J P[1] 50% CNT50    ;
  22:J P[5] 50% CNT50    ;
  23:  ENDFOR ;
  24:J P[4] 50% FINE    ;
"""
FANUC_PROGRAM = ("/PROG  CELL\n/ATTR\nOWNER\t\t= MNEDITOR;\nDEFAULT_GROUP\t= 1,*,*,*,*;\n/MN\n" + FANUC_MN + "/POS\n"
                 + "".join(f"P[{n}]{{\n   GP1:\n\tUF : 0, UT : 0,\t\tCONFIG : '{c}, 0, 0, 0',\n"
                           f"\tX = {x:.6f}  mm,\tY = {y:.6f}  mm,\tZ = {z:.6f}  mm,\n"
                           "\tW = 180.000000000 deg,\tP = 0.000000000 deg,\tR = 0.000000000 deg\n};\n"
                           for n, (x, y, z, c) in FANUC_POINTS.items()) + "/END\n")


def fanuc_ops(text):
    """The controller's reading of a FANUC LS /MN: each motion keyed by its order, with (kind, point, value,
    unit, CNT)."""
    ops, count = [], 0
    body = text.split("/MN")[1].split("/POS")[0]
    for line in body.splitlines():
        line = line.split(":", 1)[1].strip().rstrip(";").strip() if ":" in line else ""
        if m := re.match(r"([JL])\s+P\[(\d+)\]\s+([\d.]+)(%|mm/sec|msec|sec)\s+(FINE|CNT\d+)", line):
            ops.append(Op("motion", f"m{count}", (m.group(1), int(m.group(2)), float(m.group(3)), m.group(4),
                                                   m.group(5) != "FINE")))
            count += 1
        elif m := re.match(r"LBL\[(\d+)\]$", line):
            ops.append(Op("label", m.group(1)))
        elif m := re.match(r"(IF .*,\s*)?JMP LBL\[(\d+)\]$", line):
            ops.append(Op("jump", m.group(2), bool(m.group(1))))
        elif line.startswith("WAIT"):
            ops.append(Op("wait"))
        elif line.startswith("FOR "):
            ops.append(Op("loop"))
        elif line == "ENDFOR":
            ops.append(Op("endloop"))
        elif m := re.match(r"CALL (\w+)$", line):
            ops.append(Op("call", m.group(1)))
    return ops


def fanuc_check(source_text, written_text, joints, robot):
    """Every motion of the written LS takes, on every path, no less time than the controller's least for the
    source on that path: a J at p % moves each joint at most p % of its speed limit, an L at most its mm/sec
    (the distance over it); a time written where the start is not unique is a failure. Returns the times checked."""
    before, after = visits(fanuc_ops(source_text), None, {}), visits(fanuc_ops(written_text), None, {})
    fields = {op.name: op.value for op in fanuc_ops(source_text) if op.kind == "motion"}
    written = {op.name: op.value for op in fanuc_ops(written_text) if op.kind == "motion"}
    assert before.keys() == after.keys()
    checked = 0
    for (key, path), visit in after.items():
        kind, point, value, unit, _ = written[key]
        if written[key] == fields[key]:
            continue  # left as written
        assert unit in ("msec", "sec", "mm/sec"), (key, unit)
        _, _, programmed, programmed_unit, _ = fields[key]
        if unit == "mm/sec":
            assert programmed_unit == "mm/sec" and value <= programmed, (key, value, programmed)
            continue
        assert visit.before, (key, path, "a time written where the motion's start is not unique")
        start = fields[visit.before][1]
        if programmed_unit == "%":
            least = np.max(np.abs(joints[point] - joints[start]) / (programmed / 100.0 * robot.v_max))
        else:
            least = np.linalg.norm(np.subtract(FANUC_POINTS[point][:3], FANUC_POINTS[start][:3])) / programmed
        assert value / (1000.0 if unit == "msec" else 1.0) >= least * (1 - 1e-6), (key, path, value, least)
        checked += 1
    return checked


def fanuc_joints(program, robot):
    """``{position number: joints (6,)}`` of an LS program's positions in their declared configuration."""
    from trajcomp.jobs.retime import planned
    from trajcomp.compensation.posture import planned_joints

    plan = planned_joints(program, robot)
    q = planned(program, plan.index, plan.q)
    return {int(program.targets[i].name.strip("P[]")): q[i] for i in range(len(program.targets))}


def test_fanuc_retimed_and_compensated_run_no_faster_on_any_path_and_a_call_between_configurations_is_run(
        tmp_path, capsys, tmp_path_factory):
    from trajcomp.arm.robot import load_robot

    source = tmp_path / "CELL.LS"
    source.write_text(FANUC_PROGRAM)
    program = formats.read(source)
    table = program.motion_table()
    assert np.isnan(table.zone[6]) and np.isnan(table.zone[8])  # CNT100 then WAIT: it stops there
    assert "GRIP" in table.start_why[2]  # L P[3] (F) after CALL GRIP from P[2] (N): not timed, not refused
    robot = load_robot("fanuc_lrmate200id")
    out = tmp_path / "out" / "CELL.LS"
    out.parent.mkdir()
    assert main(["retime", str(source), "-o", str(out), "--robot", "fanuc_lrmate200id"]) in (0, 1)
    assert fanuc_check(FANUC_PROGRAM, out.read_text(), fanuc_joints(program, robot), robot) >= 4
    captured = capsys.readouterr()
    assert "after a call to GRIP" in captured.out + captured.err
    model = calibrated_model(tmp_path_factory.mktemp("fanuc"), "fanuc_lrmate200id", "300,-100,480", 200, 50)
    comp = tmp_path / "comp" / "CELL.LS"
    comp.parent.mkdir()
    assert main(["compensate", str(source), "--model", str(model), "--retime", "auto", "-o", str(comp)]) in (0, 1)
    compensated = formats.read(comp)
    assert fanuc_check(FANUC_PROGRAM, comp.read_text(), fanuc_joints(compensated, robot), robot) >= 4


UR_SCRIPT = """def cell():
  def go_far():
    movej([0.8, -1.2, 1.4, -1.8, -1.57, 0.0], a=1.4, v=1.0)
  end
  def gripper():
    set_digital_out(0, True)
  end
  movej([0.0, -1.57, 1.57, -1.57, -1.57, 0.0], a=1.4, v=1.05)
  movej([0.1, -1.5, 1.5, -1.6, -1.57, 0.1], a=1.4, v=0.2)
  go_far()
  movej([0.0, -1.57, 1.57, -1.57, -1.57, 0.0], a=1.4, v=0.2)
  gripper()
  movej([0.2, -1.4, 1.4, -1.6, -1.57, 0.0], a=0.5, v=3.14)
  movel([0.25, -1.4, 1.4, -1.6, -1.57, 0.0], a=0.2, v=0.25, r=0.02)
  sleep(1.0)
  movel([0.25, -1.3, 1.3, -1.6, -1.57, 0.0], a=1.2, v=0.25)
  movej([0.4, -1.3, 1.3, -1.6, -1.57, 0.3], a=4.19, v=3.14)
  i = 0
  while i < 3:
    movej([0.3, -1.4, 1.4, -1.6, -1.57, 0.0], a=1.4, v=0.5, r=0.05)
    movej([0.2, -1.5, 1.5, -1.6, -1.57, 0.0], a=1.4, v=0.5, r=0.05)
    i = i + 1
  end
  if get_digital_in(1):
    movej([0.0, -1.57, 1.57, -1.57, -1.57, 0.0], a=1.4, v=1.05)
  else:
    movej([0.1, -1.57, 1.57, -1.57, -1.57, 0.0], a=1.4, v=0.3)
  end
  movej([0.2, -1.4, 1.4, -1.6, -1.57, 0.0], a=1.4, v=1.05)
end
"""


def ur_ops(text):
    """The controller's reading of a script: each motion keyed by its order, with (function, joints, a, v, t)."""
    ops, count, opened = [], 0, []
    for line in text.splitlines():
        line = line.split("#")[0].strip()
        if m := re.match(r"def (\w+)\(", line):
            ops.append(Op("routine", m.group(1)))
            opened.append("end")
        elif re.match(r"(if|while) .*:$", line):
            ops.append(Op("if" if line.startswith("if") else "loop"))
            opened.append("endif" if line.startswith("if") else "endloop")
        elif line == "else:":
            ops.append(Op("else"))
        elif line == "end":
            ops.append(Op(opened.pop()))
        elif line.startswith("sleep("):
            ops.append(Op("wait"))
        elif m := re.match(r"(movej|movel)\(\[([^\]]*)\]((?:, \w=[\d.]+)*)\)$", line):
            options = dict(re.findall(r"(\w)=([\d.]+)", m.group(3)))
            ops.append(Op("motion", f"m{count}", (m.group(1), tuple(float(x) for x in m.group(2).split(",")),
                                                   float(options["a"]), float(options["v"]),
                                                   float(options["t"]) if "t" in options else None)))
            count += 1
        elif m := re.match(r"(\w+)\(\)$", line):
            ops.append(Op("call", m.group(1)))
    return ops


def ur_least_time(distance, a, v):
    """The time a movej takes over ``distance`` (rad, the leading axis) at acceleration ``a`` and speed ``v``."""
    return distance / v + v / a if distance >= v * v / a else 2.0 * np.sqrt(distance / a)


def assert_urscript_no_faster(written_text):
    """Every movej of the written script given a time takes, on every path, no less than its programmed a and v
    allow from the written joints of the motion before it; a time written where the start is not unique, or for a
    movel, is a failure. Returns the times checked."""
    ops = ur_ops(UR_SCRIPT)
    fields = {op.name: op.value for op in ops if op.kind == "motion"}
    written = {op.name: op.value for op in ur_ops(written_text) if op.kind == "motion"}
    visited = visits(ur_ops(written_text), "cell", {})
    assert visited.keys() == visits(ops, "cell", {}).keys()
    checked = 0
    for (key, path), visit in visited.items():
        function, q, a, v, t = written[key]
        if (function, a, v, t) == (fields[key][0], *fields[key][2:]):
            continue  # its fields left as written (a compensated one moves its joints a little)
        assert t is not None and function == "movej", (key, written[key])
        assert visit.before, (key, path, "a time written where the motion's start is not unique")
        assert (a, v) == fields[key][2:4]  # the programmed a and v kept beside the time
        distance = np.max(np.abs(np.subtract(q, written[visit.before][1])))
        least = ur_least_time(distance, a, v)
        assert t >= least * (1 - 1e-4), (key, path, t, least)  # t is written to 4 decimals, rounded up
        checked += 1
    return checked


def test_urscript_retimed_and_compensated_run_no_faster_on_any_path_under_its_a_and_v(tmp_path, tmp_path_factory):
    source = tmp_path / "cell.script"
    source.write_text(UR_SCRIPT)
    table = formats.read(source).motion_table()
    assert "first motion" in table.start_why[1]  # after go_far's motion in the file, but the script's first
    assert "line 3" in table.start_why[3]  # after go_far(): it starts at go_far's motion
    assert np.isnan(table.zone[5]) and table.acceleration[4] == 0.5  # sleep after the blended movel; a=0.5 read
    out = tmp_path / "out" / "cell.script"
    out.parent.mkdir()
    assert main(["retime", str(source), "-o", str(out), "--robot", "ur10"]) in (0, 1)
    assert assert_urscript_no_faster(out.read_text()) >= 3
    model = calibrated_model(tmp_path_factory.mktemp("ur10"), "ur10", "-800,-600,400", 300, 100)
    comp = tmp_path / "comp" / "cell.script"
    comp.parent.mkdir()
    assert main(["compensate", str(source), "--model", str(model), "--retime", "auto", "-o", str(comp)]) in (0, 1)
    assert ur_ops(comp.read_text()) != ur_ops(UR_SCRIPT)  # compensated
    assert assert_urscript_no_faster(comp.read_text()) >= 3


def test_krl_spline_block_runs_at_its_with_speed_and_gets_no_statement_inside(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    (folder / "spl.src").write_text("DEF spl( )\n  $VEL.CP=3.0\n  PTP HOME\n  LIN P1\n"
                                    "  SPLINE WITH $VEL.CP=0.02\n    SLIN P2\n    SLIN P3\n"
                                    "    SLIN P4 WITH $VEL.CP=2.5\n"
                                    "  ENDSPLINE\n  LIN P5\nEND\n")
    (folder / "spl.dat").write_text(KRL_DAT.replace("DEFDAT main", "DEFDAT spl"))
    table = formats.read(folder / "spl.src").motion_table()
    assert table.speed.tolist()[1:] == [3000.0, 20.0, 20.0, 2500.0, 3000.0]  # the block's WITH, SLIN P4's own
    out = tmp_path / "out" / "spl.src"
    out.parent.mkdir()
    assert main(["retime", str(folder / "spl.src"), "-o", str(out), "--robot", "kuka_kr6_r900"]) in (0, 1)
    text = out.read_text()
    block = text[text.index("SPLINE"):text.index("ENDSPLINE")]
    assert "$VEL.CP=" not in block.replace("WITH $VEL.CP=", "")  # nothing inserted inside the block
    speeds = [float(v) for v in re.findall(r"WITH \$VEL\.CP=([\d.]+)", text)]
    assert speeds[0] <= 0.02 and speeds[1] <= 2.5  # the block's and SLIN P4's, never faster
    written = formats.read(out).motion_table()
    assert all(written.speed[k] <= table.speed[k] + 1e-9 for k in range(1, len(written)))


def assert_converted_no_faster(source, ops, entry, initial, line_speed, target, robot, tmp_path, least_time=None):
    """Convert ``source`` into ``target`` and check it: the converted program runs its motions in file order, so
    one whose start the source's flow makes not unique gets no time (a time depends on where the motion starts:
    its speed is carried in a unit that does not, or written at the target's slowest and listed); a line runs no
    faster than the slowest TCP speed any path gives it (``line_speed(fields, visit)``, mm/s, None for other
    motions); a time is no shorter than ``least_time(fields, start fields)`` (s) where given."""
    fields = {op.name: op.value for op in ops if op.kind == "motion"}
    keys = sorted(fields, key=lambda key: int(key[1:]))
    seen = {}
    for (key, _), visit in visits(ops, entry, initial).items():
        seen.setdefault(key, []).append(visit)
    out = tmp_path / f"out{target}"
    assert main(["convert", str(source), str(out), "--robot", robot]) in (0, 1)
    converted = formats.read(out)
    assert len(converted.motions) == len(keys)
    times = 0
    for k, (key, motion) in enumerate(zip(keys, converted.motions)):
        if k and {visit.before for visit in seen.get(key, [])} != {keys[k - 1]}:
            assert motion.speed_unit != "s", (key, motion)
        times += motion.speed_unit == "s"
        if motion.speed_unit == "s" and least_time is not None:
            least = max(least_time(fields[key], fields[visit.before]) for visit in seen[key])
            assert motion.speed >= least * (1 - 1e-6), (key, motion.speed, least)
        if motion.kind != JOINT and motion.speed_unit == "mm/s" and motion.speed is not None:
            allowed = min(line_speed(fields[key], visit) for visit in seen[key])
            assert motion.speed <= allowed + 1e-6, (key, motion.speed, allowed)
    return times


def rapid_line_speed(fields, visit):
    """A RAPID line's TCP speed on a visit: its speed data's (or \\V) under the VelSet in force, mm/s; for a
    ``\\T`` (not held to VelSet's max), the peak any profile that takes that time (stretched by the override)
    over the line from the visit's start may reach: twice its mean speed (a triangle)."""
    override, top = visit.setting("velset")
    point, v, own_v, t, _ = fields
    if t is None:
        return min((float(own_v) if own_v else v) * override / 100.0, top)
    if not visit.before:
        return SLOWEST_MM_S  # no start: the converter cannot carry a time over
    start = RAPID_FIELDS[visit.before][0]
    length = np.linalg.norm(np.subtract(RAPID_POINTS[point], RAPID_POINTS[start]))
    return 2.0 * length / (float(t) * 100.0 / override)


@pytest.mark.parametrize("target", [".src", ".ls", ".script", ".csv"])
def test_rapid_converted_runs_no_faster_than_any_path(rapid_source, tmp_path, target, makerless):
    assert_converted_no_faster(rapid_source, rapid_ops(RAPID_MODULE), "main", {"velset": (100.0, 5000.0)},
                               rapid_line_speed, target, makerless("abb_irb4600"), tmp_path)


@pytest.mark.parametrize("target", [".src", ".mod", ".script", ".csv"])
def test_fanuc_converted_runs_no_faster_than_any_path(tmp_path, target, makerless):
    source = tmp_path / "CELL.LS"
    source.write_text(FANUC_PROGRAM)
    assert_converted_no_faster(source, fanuc_ops(FANUC_PROGRAM), None, {},
                               lambda fields, visit: fields[2] if fields[3] == "mm/sec" else None, target,
                               makerless("fanuc_lrmate200id"), tmp_path)


@pytest.mark.parametrize("target", [".src", ".mod", ".ls", ".csv"])
def test_urscript_converted_runs_no_faster_than_any_path(tmp_path, target, makerless):
    """Also under its a=: a movej converted to a time takes no less than its a and v allow."""
    source = tmp_path / "cell.script"
    source.write_text(UR_SCRIPT)

    def least_time(fields, start):
        function, q, a, v, _ = fields
        return ur_least_time(np.max(np.abs(np.subtract(q, start[1]))), a, v) if function == "movej" else 0.0

    times = assert_converted_no_faster(source, ur_ops(UR_SCRIPT), "cell", {},
                                       lambda fields, visit: 1000.0 * fields[3] if fields[0] == "movel" else None,
                                       target, makerless("ur10"), tmp_path, least_time)
    assert times or target != ".mod"  # RAPID \T checked (FANUC and KRL take %, CSV no field)
