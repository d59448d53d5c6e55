"""KRL programs written under another file name take that name in DEF and DEFDAT (KUKA requires it)."""

from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.cli import main
from trajcomp.errors import WriteError

KRL = Path(__file__).parents[2] / "data" / "programs" / "krl"


def test_another_file_name_renames_def_and_defdat_and_nothing_else(tmp_path):
    program = formats.read(KRL / "weld.src")
    written = formats.write(tmp_path / "weld_v2.src", program)
    assert sorted(p.name for p in written) == ["weld_v2.dat", "weld_v2.src"]
    src = (KRL / "weld.src").read_bytes()
    dat = (KRL / "weld.dat").read_bytes()
    assert (tmp_path / "weld_v2.src").read_bytes() == src.replace(b"DEF weld( )", b"DEF weld_v2( )", 1)
    assert (tmp_path / "weld_v2.dat").read_bytes() == dat.replace(b"DEFDAT  weld", b"DEFDAT  weld_v2", 1)
    assert src.count(b"DEF weld( )") == 1 and dat.count(b"DEFDAT  weld") == 1


def test_the_renamed_program_reads_back_with_its_points(tmp_path):
    program = formats.read(KRL / "weld.src")
    formats.write(tmp_path / "Seam_7.src", program)
    again = formats.read(tmp_path / "Seam_7.src")
    assert again.name == "Seam_7"
    assert [t.name for t in again.targets] == [t.name for t in program.targets]
    for a, b in zip(again.targets, program.targets):
        np.testing.assert_array_equal(a.joints if a.is_joint else a.pose, b.joints if b.is_joint else b.pose)


def test_the_same_name_in_another_case_is_written_byte_for_byte(tmp_path):
    program = formats.read(KRL / "weld.src")
    formats.write(tmp_path / "WELD.SRC", program)
    assert (tmp_path / "WELD.SRC").read_bytes() == (KRL / "weld.src").read_bytes()
    assert (tmp_path / "WELD.DAT").read_bytes() == (KRL / "weld.dat").read_bytes()


def test_a_program_without_dat_is_renamed_too(tmp_path):
    (tmp_path / "a.src").write_bytes(b"&ACCESS RVP\r\nDEF a( )\r\n  PTP {X 1,Y 2,Z 3,A 0,B 0,C 0}\r\nEND\r\nDEF sub( )\r\nEND\r\n")
    formats.write(tmp_path / "b.src", formats.read(tmp_path / "a.src"))
    assert (tmp_path / "b.src").read_bytes() == (tmp_path / "a.src").read_bytes().replace(b"DEF a(", b"DEF b(")
    assert not (tmp_path / "b.dat").exists()


@pytest.mark.parametrize("cut", [0, 3, 9])
def test_def_and_defdat_after_a_long_header_are_renamed_as_the_whole_text_reads_them(tmp_path, cut):
    # the names are searched in growing beginnings of the text (64 KB first): a name cut at the end of one is
    # read whole, and a DEF in a string before them is none
    lines = ";" + "x" * 65000 + '\n&PARAM MSG = "\nDEF no( )\nDEFDAT no\n'
    header = lines + "y" * (65536 - 7 - cut - len(lines) - 2) + '"\n'  # DEFDAT's name cut after ``cut`` letters
    (tmp_path / "prog_name.src").write_text(header + "DEF prog_name( )\n  PTP XP1\nEND\n")
    (tmp_path / "prog_name.dat").write_text(header + "DEFDAT prog_name\nDECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0}\n"
                                            "ENDDAT\n")
    formats.write(tmp_path / "renamed.src", formats.read(tmp_path / "prog_name.src"))
    assert (tmp_path / "renamed.src").read_text() == header + "DEF renamed( )\n  PTP XP1\nEND\n"
    assert (tmp_path / "renamed.dat").read_text().startswith(header + "DEFDAT renamed\nDECL E6POS XP1=")


@pytest.mark.parametrize("name", ["weld-2.src", "2weld.src", "a_name_longer_than_24_chars.src"])
def test_a_file_name_krl_cannot_use_is_refused(tmp_path, name):
    program = formats.read(KRL / "weld.src")
    with pytest.raises(WriteError, match="cannot name a KRL program"):
        formats.write(tmp_path / name, program)
    assert main(["convert", str(KRL / "weld.src"), str(tmp_path / name)]) == 2
    assert list(tmp_path.iterdir()) == []


def test_convert_names_a_new_krl_program_after_its_file(tmp_path, makerless):
    assert main(["convert", str(KRL.parent / "csv" / "path.csv"), str(tmp_path / "path_kuka.src"),
                 "--robot", makerless("ur10")]) == 0
    assert (tmp_path / "path_kuka.src").read_text().startswith("DEF path_kuka( )")
    assert (tmp_path / "path_kuka.dat").read_text().startswith("DEFDAT path_kuka")
