"""The real programs of tests/data/programs/real (SOURCES.txt): every one read, compensated or refused for a
reason a controller shares.

Each program is read (no false refusal), then compensated with a stand-in
correction on the built-in arm of its maker: every motion is either
compensated or listed once, the written program reads back, and only a
target that arm cannot reach (these are other arms: a controller of that
arm would refuse them too) stops a run. Byte-exact read/write of every file
is tests/formats/test_formats_roundtrip.py.
"""

import functools
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.compensation.target_correction import CompensationResult
from trajcomp.errors import IKError, ReadError
from trajcomp.compensation.program_rewrite import compensate_program
from trajcomp.arm.robot import load_robot

DATA = Path(__file__).parents[1] / "data"
REAL = sorted(p for p in (DATA / "programs" / "real").rglob("*")
              if p.is_file() and p.suffix.lower() not in (".dat", ".txt", ".va"))
REFUSED = sorted(p for p in (DATA / "refused").rglob("*") if p.is_file())
ARM = {"krl": "kuka_kr6_r900", "rapid": "abb_irb4600", "fanuc_ls": "fanuc_lrmate200id", "urscript": "ur10"}


def _unchanged(T, tools, seeds, names):
    """A stand-in correction: the command is the target, at the planned joints."""
    n = len(T)
    return CompensationResult(T, seeds, np.zeros((n, 6)), np.zeros(n, bool), np.zeros(n))


def test_the_corpus_holds_programs_of_every_language():
    languages = [formats.find_format(p).name for p in REAL]
    assert len(REAL) >= 35 and {lang: languages.count(lang) >= 1 for lang in ARM} == dict.fromkeys(ARM, True)


@functools.cache
def _compensated(path):
    """The program at ``path`` read and compensated on its maker's built-in arm.

    Returns
    -------
    tuple
        ``(program, edited, report)``, or ``(program, message, None)`` with the
        IKError's message when that arm cannot reach it. Cached: the corpus test
        below sees every program whichever xdist worker ran its own test.
    """
    program = formats.read(path)
    robot = load_robot(ARM[program.format])
    stated = {str(n): np.eye(4) for n in range(1, 33)}  # the controller's tool and frame tables: not in the files
    try:
        edited, report = compensate_program(program, _unchanged, robot, tools=stated, frames=stated,
                                            joint_targets="compensate")
    except IKError as error:  # another arm than the built-in one of its maker
        return program, str(error), None
    return program, edited, report


@pytest.mark.parametrize("path", REAL, ids=lambda p: str(p.relative_to(DATA / "programs" / "real")))
def test_a_real_program_is_compensated_or_refused_as_its_controller_would(path, tmp_path):
    program, edited, report = _compensated(path)
    if report is None:
        assert "cannot reach" in edited or "cannot be reached" in edited or "outside the limits" in edited
        return
    lines = [line for line, _, _ in report.not_compensated]
    assert len(lines) == len(set(lines))  # a motion listed once
    assert report.motions_left <= len(program.motions)
    assert report.motions_left == sum(not m.axis_position for m in program.runtime_motions())
    for other in path.parent.iterdir():  # the other modules of its task, beside it as on the controller
        if other.is_file() and other.stem != path.stem:
            (tmp_path / other.name).write_bytes(other.read_bytes())
    written = formats.write(tmp_path / path.name, edited)
    assert formats.read(written[0]).format == program.format


def test_every_language_has_a_real_program_compensated():
    runs = {path: _compensated(path) for path in REAL}
    done = {program.format for program, _, report in runs.values() if report is not None and len(report.labels)}
    # the one real URScript program is RoboDK's for a UR10e, beyond the built-in UR10's reach at line 76; the
    # FANUC backups are of spot-welding arms far larger than the LR Mate, or move only to positions left as written
    assert done >= {"krl", "rapid"}, {path.name: edited for path, (_, edited, report) in runs.items() if report is None}


@pytest.mark.parametrize("path", REFUSED, ids=lambda p: p.name)
def test_a_refused_program_is_one_no_controller_runs(path):
    with pytest.raises(ReadError):
        formats.read(path)
