"""The ``formats`` and ``convert`` sub-commands (run through their modules' parsers)."""

import argparse
from pathlib import Path

import pytest

from trajcomp import formats
from trajcomp.cli import main
from trajcomp.commands import convert as convert_command
from trajcomp.commands import formats as formats_command
from trajcomp.errors import TrajcompError

DATA = Path(__file__).parents[1] / "data" / "programs"
EXAMPLES = Path(__file__).parents[2] / "examples" / "programs"


def _run(argv):
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command", required=True)
    formats_command.add_parser(sub)
    convert_command.add_parser(sub)
    args = parser.parse_args(argv)
    return args.run(args)


def test_formats_lists_each_language_with_what_it_declares(capsys):
    assert _run(["formats"]) == 0
    header, *lines = capsys.readouterr().out.splitlines()
    assert header.split() == ["name", "extensions", "maker", "re-timing", "writes", "configuration", "source"]
    rows = {line.split()[0]: " ".join(line.split()) for line in lines}
    assert rows["krl"] == ".src KUKA $VEL.CP, BAS(#VEL_PTP, %) yes built-in".join(["krl ", ""])
    assert rows["csv"] == "csv .csv - the t column - built-in"
    assert rows["urscript"] == "urscript .script .urscript Universal Robots t=, v= - built-in"


def test_convert_rapid_to_fanuc_computes_config(tmp_path, makerless, capsys):
    out = tmp_path / "WELD.LS"
    with pytest.raises(TrajcompError, match=r"a FANUC program \(fanuc_ls\) cannot run on robot abb_irb4600 \(ABB\)"):
        _run(["convert", str(EXAMPLES / "abb" / "Weld.mod"), str(out), "--robot", "abb_irb4600"])
    capsys.readouterr()
    # the first MoveJ's v1000 (a TCP speed along a joint motion) becomes a FANUC J % only with its start known
    assert _run(["convert", str(EXAMPLES / "abb" / "Weld.mod"), str(out), "--robot", makerless("abb_irb4600")]) == 1
    program = formats.read(out)
    assert len(program.motions) == 5
    assert all(t.config == ("F", "U", "T", 0, 0, 0) for t in program.targets)  # IRB 4600 home wrist: J5 = +89 deg
    printed, err = capsys.readouterr()
    assert "wrote" in printed
    assert "Weld.mod:9: speed of 'MoveJ P1, v1000, z5, tool0;': speed 1000 mm/s cannot be converted (its start is " \
           "unknown): written at fanuc_ls's slowest speed" in err
    assert [(m.speed, m.speed_unit) for m in program.motions[:1]] == [(1.0, "%")]


def test_convert_needs_undefined_tools(tmp_path):
    with pytest.raises(TrajcompError, match="tool '1' is used but not defined"):
        _run(["convert", str(DATA / "krl" / "weld.src"), str(tmp_path / "w.script")])


def test_convert_with_tools_and_frames(tmp_path, capsys):
    out = tmp_path / "pick.src"
    # without a robot, the 2 s of L P[6] has no KRL $VEL.CP: written at 1 mm/s and listed (exit 1)
    assert _run(["convert", str(DATA / "fanuc" / "PICK_PLACE.LS"), str(out), "--tool", "1=0,0,100,0,0,0",
                 "--tool", "2=0,0,200,0,0,0", "--frame", "1=500,0,0,90,0,0"]) == 1
    program = formats.read(out)
    out_text, err = capsys.readouterr()
    assert "2 computed at run time" in out_text
    assert "PICK_PLACE.LS:35: speed of '12:L P[6] 2sec CNT10 ;': speed 2 s cannot be converted (no robot given)" in err
    # set inline ($TOOL={X ..}): the controller's TOOL_DATA / BASE_DATA tables are never written
    assert sorted({tuple(program.tools[m.tool][:3, 3]) for m in program.motions if m.target is not None}) == [(0, 0, 200)]
    assert {tuple(program.frames[m.frame][:3, 3]) for m in program.motions if m.target is not None} == {(500, 0, 0)}
    assert "TOOL_DATA" not in out.read_text() and "BASE_DATA" not in out.read_text()


def test_bad_tool_option_is_a_clear_error():
    with pytest.raises(TrajcompError, match=r"--tool '1=0,0': expected NAME=x,y,z,a,b,c"):
        convert_command.parse_frame_values(["1=0,0"], "--tool")


def test_bad_input_exits_with_2(tmp_path, capsys, monkeypatch):
    bad = tmp_path / "bad.src"
    bad.write_text("MODULE M\nENDMODULE\n")
    monkeypatch.setattr("trajcomp.cli.COMMANDS", ("convert",))
    assert main(["convert", str(bad), str(tmp_path / "out.mod")]) == 2
    assert "not a KRL program" in capsys.readouterr().err
