"""Hostile and damaged inputs found by fuzzing: refused with file and line, never a crash or a runaway."""

import re
import shutil
from pathlib import Path

import pytest

from trajcomp import formats
from trajcomp.cli import main
from trajcomp.errors import ReadError

KUKA = Path(__file__).resolve().parents[1] / "examples" / "programs" / "kuka"


@pytest.fixture
def weld(tmp_path):
    for name in ("weld.src", "weld.dat"):
        shutil.copy(KUKA / name, tmp_path / name)
    return tmp_path / "weld.src"


@pytest.mark.parametrize("edit, refusal", [
    (("S 2,", "S 1e19,"), r"weld\.dat:2: S 1e19: outside 0\.\.255"),
    (("T 2}", "T 1e308}"), r"weld\.dat:2: T 1e308: outside 0\.\.63"),  # was an OverflowError
    (("T 2}", "T 64}"), r"weld\.dat:2: T 64: outside 0\.\.63"),
    (("S 2,", "S -1,"), r"weld\.dat:2: S -1: outside 0\.\.255"),
])
def test_kuka_status_and_turn_beyond_their_bits_are_refused(weld, edit, refusal):
    dat = weld.with_suffix(".dat")
    dat.write_text(dat.read_text().replace(*edit, 1))
    with pytest.raises(ReadError, match=refusal):
        formats.read(weld)


def test_a_speed_no_process_uses_is_refused_naming_the_motion(weld, kuka_model, capsys):
    weld.write_text(weld.read_text().replace("$VEL.CP=0.020000", "$VEL.CP=1e-28"))  # was an array of 1e27 samples
    assert main(["compensate", str(weld), "--model", str(kuka_model), "-o", str(weld.with_name("out.src"))]) == 2
    err = capsys.readouterr().err
    assert re.search(r"the motions from P2 \(weld\.dat:3\) .* last 8e\+26 s|last 7\.99\de\+26 s", err)
    assert not weld.with_name("out.src").exists()


def test_a_motion_after_a_sign_is_retimed_not_a_crash(tmp_path, kuka_model):
    script = tmp_path / "plus.script"
    script.write_text("def p():\n  movej([0, -1.57, 1.57, 0, 1.57, 0], a=1, v=0.5)\n"
                      "  +movej([0.1, -1.57, 1.57, 0, 1.57, 0], a=1, v=0.5)\nend\n")
    assert main(["retime", str(script), "--robot", "ur10", "-o", str(tmp_path / "out.script")]) in (0, 1)


def test_an_output_pipe_closed_by_its_reader_is_exit_141_not_a_crash():
    import subprocess
    import sys

    # `trajcomp robots | head -0`: the reader is gone before anything is written (was exit 3, "internal error")
    child = subprocess.Popen([sys.executable, "-m", "trajcomp.cli", "robots"], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    child.stdout.close()  # before the child, still importing, writes its first line
    stderr = child.stderr.read()
    assert child.wait() == 141
    assert "internal error" not in stderr and "Exception ignored" not in stderr
