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
