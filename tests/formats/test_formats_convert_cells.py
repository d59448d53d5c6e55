"""``trajcomp convert`` on programs as cells hold them (issue 35, section 3).

- into its own language a program is written back byte for byte, a point
  used with two tools or work objects included (no copy per use: its
  numbers are not changed), and no motion is said to be written as a comment;
- into another language, a program every motion of which is computed at
  run time would be a file of comments only: exit 1, said on stderr.
"""

from trajcomp.cli import main

RAPID_TWO_TOOLS = (
    "MODULE Cell\n"
    "  PERS tooldata tGun:=[TRUE,[[0,0,150],[1,0,0,0]],[2,[0,0,50],[1,0,0,0],0,0,0]];\n"
    "  PERS tooldata tGrip:=[TRUE,[[10,0,220],[1,0,0,0]],[3,[0,0,80],[1,0,0,0],0,0,0]];\n"
    "  CONST robtarget p10:=[[1200,100,900],[0,0,1,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
    "  CONST robtarget p20:=[[1200,-100,900],[0,0,1,0],[-1,0,-1,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n"
    "  PROC main()\n"
    "    MoveJ p10,v1000,z10,tGun;\n"
    "    MoveL p20,v200,fine,tGun;\n"
    "    MoveL p10,v200,fine,tGrip;\n"
    "  ENDPROC\n"
    "ENDMODULE\n")


def test_same_language_convert_of_a_point_used_with_two_tools_is_byte_identical(tmp_path, capsys):
    src = tmp_path / "Cell.mod"
    src.write_bytes(RAPID_TWO_TOOLS.replace("\n", "\r\n").encode())
    out = tmp_path / "out" / "Cell.mod"
    out.parent.mkdir()
    assert main(["convert", str(src), str(out)]) == 0
    assert out.read_bytes() == src.read_bytes()  # no p10_2
    printed = capsys.readouterr()
    assert "computed at run time" not in printed.out and "3 motions, as written" in printed.out
    assert printed.err == ""


def test_same_language_convert_of_krl_with_two_bases_is_byte_identical(tmp_path, capsys):
    (tmp_path / "cell.dat").write_text("DEFDAT CELL\nDECL E6POS XP1={X 400,Y 0,Z 600,A 0,B 90,C 0,S 2,T 2}\n"
                                       "ENDDAT\n")
    (tmp_path / "cell.src").write_text("DEF cell( )\n$BASE={X 0,Y 0,Z 0,A 0,B 0,C 0}\nPTP XP1\n"
                                       "$BASE={X 10,Y 0,Z 0,A 0,B 0,C 0}\nLIN XP1\nEND\n")
    out = tmp_path / "out"
    out.mkdir()
    assert main(["convert", str(tmp_path / "cell.src"), str(out / "cell.src")]) == 0
    for name in ("cell.src", "cell.dat"):
        assert (out / name).read_bytes() == (tmp_path / name).read_bytes()
    assert "computed at run time" not in capsys.readouterr().out


def test_cross_language_convert_with_every_motion_computed_at_run_time_fails(tmp_path, capsys):
    src = tmp_path / "Offsets.mod"
    src.write_text("MODULE Offsets\n  CONST robtarget p10:=[[1200,100,900],[0,0,1,0],[0,0,0,0],"
                   "[9E9,9E9,9E9,9E9,9E9,9E9]];\n  PROC main()\n    MoveL Offs(p10,0,0,50),v200,fine,tool0;\n"
                   "    MoveL RelTool(p10,0,0,-20),v200,fine,tool0;\n  ENDPROC\nENDMODULE\n")
    out = tmp_path / "offsets.src"
    assert main(["convert", str(src), str(out)]) == 1
    printed = capsys.readouterr()
    assert "0 motions, 2 computed at run time written as comments" in printed.out
    assert "every motion of" in printed.err and "holds comments only, no motion" in printed.err
    assert "line 4" in printed.err and "Offs" in printed.err
    assert out.exists()  # written, as exit 1 says: the verdict fails, the file is there to read
