"""Every writer refuses numbers that are not finite: robot code never receives nan or inf."""

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.errors import ReadError, WriteError
from trajcomp.compensation.program_rewrite import convert_program

PATH = Path(__file__).parents[1] / "data" / "programs" / "csv" / "path.csv"


@pytest.mark.parametrize("suffix", [".csv", ".src", ".mod", ".ls", ".script"])
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_pose_is_refused_naming_the_target(tmp_path, suffix, bad):
    program = formats.read(PATH)
    converted = convert_program(program, formats.find_format(tmp_path / f"p{suffix}").name)
    pose = converted.targets[1].pose.copy()
    pose[0, 3] = bad
    broken = converted.with_targets([1], poses=[pose])
    # named by its line, with the file it came from where the program keeps it (CSV to CSV: path.csv)
    with pytest.raises(WriteError, match=r"target (path\.csv:4|line 4): pose not finite"):
        formats.write(tmp_path / f"p{suffix}", broken)
    assert not list(tmp_path.iterdir())


def test_patched_file_refuses_a_non_finite_edit(tmp_path):
    program = formats.read(PATH)
    pose = program.targets[0].pose.copy()
    pose[2, 3] = np.nan
    with pytest.raises(WriteError, match=r"target path\.csv:3: pose not finite"):
        formats.write(tmp_path / "out.csv", program.with_targets([0], poses=[pose]))
    assert not (tmp_path / "out.csv").exists()


def test_non_finite_speed_is_refused(tmp_path):
    program = formats.read(PATH)
    items = [dataclasses.replace(m, speed=np.inf) if getattr(m, "speed", None) else m for m in program.items]
    with pytest.raises(WriteError, match="line 4 .*speed not finite"):
        formats.write(tmp_path / "out.csv", program.replace(items=tuple(items)))


@pytest.mark.parametrize(
    "name, text, message",
    [
        ("p.csv", "x,y,z,a,b,c,j1,j2,j3,j4,j5,j6\n1,2,3,4,5,6,0,0,0,-100.05e301,0,0\n",
         r"p\.csv:2: field j4: '-100\.05e301' is out of range \(beyond \+-3600\)"),
        ("p.src", "DEF p( )\nLIN {X 2e6,Y 0,Z 0,A 0,B 0,C 0}\nEND\n", r"p\.src:2: X: '2e6' is out of range \(beyond \+-1e\+06\)"),
        ("s.script", "def s():\n  movej([0, 0, 70, 0, 0, 0])\nend\n", r"s\.script:2: list j3: '70' is out of range"),
        ("M.mod", "MODULE M\n  PROC main()\n    MoveAbsJ [[0,0,1e5,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]], v100, fine, tool0;\n"
         "  ENDPROC\nENDMODULE\n", r"M\.mod:3: jointtarget joint 3: '1e5' is out of range"),
        ("P.LS", "/PROG P\n/MN\n   1:L P[1] 100mm/sec FINE ;\n/POS\nP[1]{\n   GP1:\n\tUF : 0, UT : 1,\n"
         "\tX = 1.0 mm, Y = 2.0 mm, Z = 3.0 mm,\n\tW = 0 deg, P = 2e5 deg, R = 0 deg\n};\n/END\n",
         r"P\.LS:5: P\[1\] P: '2e5' is out of range \(beyond \+-10000\)"),
    ],
    ids=["csv joint", "krl position", "urscript joint", "rapid joint", "fanuc angle"],
)
def test_magnitudes_no_program_states_are_refused(tmp_path, name, text, message):
    """A joint beyond ten turns, a position beyond a kilometre: a typo or damage, refused by the reader."""
    (tmp_path / name).write_text(text)
    with pytest.raises(ReadError, match=message):
        formats.read(tmp_path / name)


def test_a_program_that_is_a_fifo_or_a_folder_is_named_as_such_not_as_missing(tmp_path):
    import os

    os.mkfifo(tmp_path / "pipe.src")
    (tmp_path / "dir.src").mkdir()
    with pytest.raises(ReadError, match=r"pipe\.src: is not a regular file \(a FIFO"):
        formats.read(tmp_path / "pipe.src")
    with pytest.raises(ReadError, match=r"dir\.src: is a folder"):
        formats.read(tmp_path / "dir.src")
    with pytest.raises(ReadError, match=r"gone\.src: no such file"):
        formats.read(tmp_path / "gone.src")


@pytest.mark.parametrize("again", ["P3", "p3", "  DECL E6POS P3"])
def test_a_krl_point_a_data_list_declares_twice_is_refused_as_the_controller_does(tmp_path, again):
    """Accepted before: the last declaration was corrected, the first left as written."""
    examples = Path(__file__).resolve().parents[2] / "examples" / "programs" / "kuka"
    (tmp_path / "weld.src").write_text((examples / "weld.src").read_text())
    declaration = again if again.strip().startswith("DECL") else f"DECL E6POS {again}"
    (tmp_path / "weld.dat").write_text((examples / "weld.dat").read_text().replace(
        "ENDDAT", f"{declaration}={{X 500.0,Y 0.0,Z 700.0,A 0.0,B 90.0,C 0.0,S 2,T 2}} ; again\nENDDAT"))
    with pytest.raises(ReadError, match=r"weld\.dat:7: P3 is declared again \(first at line 4\)".replace("P3", again.split()[-1])):
        formats.read(tmp_path / "weld.src")


EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "programs"
LONG_LINES = {  # a program of each language with a line LINE_LIMIT + 1 bytes long, and that line's number
    "weld.csv": (lambda text, long: text.replace("\n", "\n#" + long + "\n", 1), 2),
    "weld.src": (lambda text, long: text.replace("DEF weld( )\n", "DEF weld( )\n  ;" + long + "\n"), 2),
    "Weld.mod": (lambda text, long: text.replace("MODULE Weld\n", "MODULE Weld\n  !" + long + "\n"), 2),
    "WELD.LS": (lambda text, long: text.replace("/MN\n", "/MN\n   1:  !" + long + " ;\n"), 22),
    "weld.script": (lambda text, long: text.replace("def weld():\n", "def weld():\n  #" + long + "\n"), 2),
}


@pytest.mark.parametrize("name", LONG_LINES)
def test_a_line_longer_than_any_program_writes_is_refused_naming_it(tmp_path, name):
    """A 50 MB line took 2.2 GB (CSV header) and minutes (a RAPID comment): a MemoryError (exit 3) under a limit.
    A comment just below the bound is read in a fraction of a second of CPU (RAPID took 13 s, KRL 8.5 s per MB of
    blanked comment: a pattern gave its blanks back one at a time; now 0.1-0.4 s)."""
    import time

    from trajcomp.formats.text import LINE_LIMIT

    edit, line = LONG_LINES[name]
    original = next(EXAMPLES.rglob(name))
    for companion in original.parent.glob(original.stem + ".*"):
        (tmp_path / companion.name).write_bytes(companion.read_bytes())
    (tmp_path / name).write_text(edit(original.read_text(), "x" * LINE_LIMIT))
    with pytest.raises(ReadError, match=rf"{re.escape(name)}:{line}: a line longer than 1,048,576 bytes"):
        formats.read(tmp_path / name)
    (tmp_path / name).write_text(edit(original.read_text(), "x" * (LINE_LIMIT - 80)))  # just below: read
    start = time.process_time()
    formats.read(tmp_path / name)
    assert time.process_time() - start < 1.5


def test_a_program_with_a_line_of_tens_of_megabytes_is_refused_with_exit_2_under_a_memory_limit(tmp_path):
    import subprocess
    import sys

    program = tmp_path / "p.csv"
    program.write_text((EXAMPLES / "csv" / "weld.csv").read_text().replace("\n", "," + "x" * 20_000_000 + "\n", 1))
    limit = "import resource; resource.setrlimit(resource.RLIMIT_AS, (1_500_000_000,) * 2); "
    done = subprocess.run([sys.executable, "-c", limit + "from trajcomp.cli import main; raise SystemExit(main())",
                           "convert", str(program), str(tmp_path / "p.src")], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2 and "p.csv:1: a line longer than" in done.stderr, done.stderr
    assert not (tmp_path / "p.src").exists()


@pytest.mark.parametrize("again", ["CONST robtarget P3 :=", "CONST robtarget p3 :=", "VAR robtarget P3:= "])
def test_a_rapid_point_a_module_declares_twice_is_refused_as_the_controller_does(tmp_path, again):
    """Accepted before (exit 0): the last declaration was corrected, the first left as written. RAPID names are not
    case-sensitive; the last form is not one the reader reads at once."""
    text = (EXAMPLES / "abb" / "Weld.mod").read_text()
    p3 = next(line for line in text.splitlines() if "robtarget P3" in line)
    (tmp_path / "Weld.mod").write_text(text.replace("  PROC main()", p3.replace("CONST robtarget P3 :=", again)
                                                    + "\n  PROC main()"))
    name = again.split()[2].rstrip(":=")
    with pytest.raises(ReadError, match=rf"Weld\.mod:8: {name} is declared again \(first at line 4\)"):
        formats.read(tmp_path / "Weld.mod")


def test_a_rapid_routine_may_declare_its_own_point_of_a_module_points_name(tmp_path):
    """Another scope: the controller takes it (the reader crashed with an IndexError on any routine's robtarget
    read with the module's motions)."""
    text = (EXAMPLES / "abb" / "Weld.mod").read_text()
    p3 = next(line for line in text.splitlines() if "robtarget P3" in line)
    (tmp_path / "Weld.mod").write_text(text.replace("  PROC main()\n", "  PROC main()\n  " + p3.replace("CONST", "VAR")
                                                    + "\n"))
    assert len(formats.read(tmp_path / "Weld.mod").targets) == 6


@pytest.mark.parametrize("written", ["as the pendant writes it", "otherwise"])
def test_a_fanuc_position_the_pos_section_gives_twice_is_refused(tmp_path, written):
    text = (EXAMPLES / "fanuc" / "WELD.LS").read_text()
    entry = text[text.index("P[3]{"):text.index("};", text.index("P[3]{")) + 3]
    if written == "otherwise":
        entry = entry.replace("\tX = ", "\tX=")
    (tmp_path / "WELD.LS").write_text(text.replace("/END", entry + "/END"))
    with pytest.raises(ReadError, match=r"WELD\.LS:58: P\[3\] is given again in /POS \(first at line 40\)"):
        formats.read(tmp_path / "WELD.LS")


BLOCKS = {  # program, edit, the refusal (accepted with exit 0 before, but the cut RAPID procedure)
    "krl IF": ("kuka/weld.src", lambda t: t.replace("  LIN P3 C_DIS\n", "  IF $IN[1] THEN\n  LIN P3 C_DIS\n"),
               r"weld\.src:7: IF has no ENDIF before the END of line 12"),
    "krl FOR": ("kuka/weld.src", lambda t: t.replace("  LIN P3 C_DIS\n", "  FOR I=1 TO 3\n  LIN P3 C_DIS\n"),
                r"weld\.src:7: FOR has no ENDFOR before the END of line 12"),
    "krl junk after END": ("kuka/weld.src", lambda t: t + "garbage here\n",
                           r"weld\.src:12: a statement outside every DEF \.\.\. END block: 'garbage here'"),
    "krl motion after END": ("kuka/weld.src", lambda t: t + "LIN P1\n", r"weld\.src:12: a statement outside every"),
    "krl END twice": ("kuka/weld.src", lambda t: t + "END\n", r"weld\.src:12: END closes no block"),
    "rapid junk after ENDMODULE": ("abb/Weld.mod", lambda t: t + "garbage\n",
                                   r"Weld\.mod:16: a statement outside every MODULE \.\.\. ENDMODULE block"),
    "rapid PROC without ENDPROC": ("abb/Weld.mod",
                                   lambda t: t.replace("  PROC main()", "  PROC other()\n  PROC main()"),
                                   r"Weld\.mod:8: PROC has no ENDPROC before the ENDMODULE of line 16"),
    "urscript end twice": ("ur/weld.script", lambda t: t.replace("end\n", "end\nend\n", 1),
                           r"weld\.script:8: END closes no block"),
}


@pytest.mark.parametrize("case", BLOCKS)
def test_a_block_left_open_or_a_statement_outside_the_routines_is_refused_as_the_controller_does(tmp_path, case):
    path, edit, message = BLOCKS[case]
    original = EXAMPLES / path
    for companion in original.parent.glob(original.stem + ".*"):
        (tmp_path / companion.name).write_bytes(companion.read_bytes())
    (tmp_path / original.name).write_text(edit(original.read_text()))
    with pytest.raises(ReadError, match=message):
        formats.read(tmp_path / original.name)


def test_blocks_closed_in_order_and_a_rapid_header_are_read(tmp_path):
    src = (EXAMPLES / "kuka" / "weld.src").read_text().replace("  LIN P3 C_DIS\n", "  IF $IN[1] THEN\n  LIN P3 C_DIS\n"
                                                                 "  ELSE\n    WAIT FOR $IN[2]\n  ENDIF\n")
    (tmp_path / "weld.src").write_text("&ACCESS RVP\n&REL 1\n" + src)
    (tmp_path / "weld.dat").write_text((EXAMPLES / "kuka" / "weld.dat").read_text())
    (tmp_path / "Weld.mod").write_text("%%%\n  VERSION:1\n  LANGUAGE:ENGLISH\n%%%\n\n"
                                       + (EXAMPLES / "abb" / "Weld.mod").read_text() + "! the end\n")
    assert len(formats.read(tmp_path / "weld.src").targets) == len(formats.read(tmp_path / "Weld.mod").targets) == 5
