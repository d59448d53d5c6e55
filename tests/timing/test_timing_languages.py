"""Every example program re-timed through the CLI in its own language: only speed fields change, holding the timing.

The example weld path is the same in every language: a joint motion to P1
(from an unknown position: not timed), 80 mm down to P2 and an exact stop,
60 mm to P3 blended into 40 mm to P4, all at 20 mm/s, and a joint motion
back. 20 mm/s is a process speed the arms keep easily, so every robot
language keeps the three lines' fields exactly as written and only the
joint motion's changes; the CSV program's rows are its trajectory, so its
``t`` column shows, independently of the timing code, that the first line
takes 80 / 20 = 4 s plus its acceleration ramps, the blended pair 100 / 20
= 5 s plus ramps, and that no line is faster than 20 mm/s on average. The
written fields are parsed here from the text, per language.
"""

import csv
import difflib
import io
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from tests.timing.controller_path import ProgrammedPath
from trajcomp import formats
from trajcomp.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "programs"
PROGRAMS = {  # language: (file, robot)
    "csv": ("csv/weld.csv", "ur10"),
    "krl": ("kuka/weld.src", "kuka_kr6_r900"),
    "rapid": ("abb/Weld.mod", "abb_irb4600"),
    "fanuc_ls": ("fanuc/WELD.LS", "fanuc_lrmate200id"),
    "urscript": ("ur/weld.script", "ur10"),
}
RAMPS = 0.1  # s, at most spent accelerating and braking on a 20 mm/s line (any of these arms)
SPEED_FIELDS = {  # the speed / time fields re-timing may write, per language
    "csv": r",(?:t|[\d.]+)$",  # a t column added
    "krl": r"\$VEL\.CP=[\d.]+|BAS\(#VEL_PTP,[\d.]+\)",
    "rapid": r"\\T:=[\d.]+",
    "fanuc_ls": r"\b[\d.]+(?:%|mm/sec|msec|sec)",
    "urscript": r",\s*t=[\d.]+|v=[\d.]+",
}


def retimed(tmp_path, language):
    source, robot = PROGRAMS[language]
    folder = tmp_path / "in"
    folder.mkdir()
    for file in (EXAMPLES / source).parent.iterdir():
        shutil.copy(file, folder / file.name)
    output = tmp_path / "out" / Path(source).name
    output.parent.mkdir()
    assert main(["retime", str(folder / Path(source).name), "-o", str(output), "--robot", robot,
                 "--report", str(output.with_suffix(".html"))]) == 0
    return (folder / Path(source).name).read_text(), output.read_text(), output


def durations(text):
    """The motion times (s) of the three lines, read from the written CSV program's t column."""
    t = np.array([float(row.rsplit(",", 1)[1]) for row in text.splitlines()[1:]])
    return np.diff(t)[:3]


def blended_lengths(text):
    """The TCP path lengths (mm) of the second and third lines of a written CSV weld: the controller's path
    (`tests.timing.controller_path`) from the second line's start to the middle of the blend at its end, and
    on to the third line's end: the times at the waypoints are those of their places on that path."""
    rows = list(csv.DictReader(io.StringIO(text)))[1:4]
    poses = np.tile(np.eye(4), (3, 1, 1))
    poses[:, :3, 3] = [[float(row[c]) for c in "xyz"] for row in rows]
    zone = float(rows[1]["zone"] or 0.0)
    path = ProgrammedPath(poses, np.array([0.0, zone, 0.0]))
    sigma = np.linspace(0.0, path.total, 200_001)
    travelled = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path.poses(sigma)[:, :3, 3], axis=0), axis=1))]
    middle = np.interp(path.length[0], sigma, travelled)  # the blend's middle: sigma at the corner's line distance
    return middle, travelled[-1] - middle


def line_speeds(language, text):
    """The TCP speeds (mm/s) the controller runs the program's linear motions at, read from its fields."""
    if language == "krl":  # the $VEL.CP in force at each LIN
        speeds, speed = [], None
        for line in text.splitlines():
            if m := re.match(r"\s*\$VEL\.CP=([\d.]+)", line):
                speed = float(m.group(1)) * 1000.0
            elif re.match(r"\s*LIN\b", line):
                speeds.append(speed)
        return speeds
    pattern, scale = {"rapid": (r"MoveL \w+, v\d+\\V:=([\d.]+)|MoveL \w+, v(\d+),", 1.0),
                      "urscript": (r"movel\(.*v=([\d.]+)", 1000.0),
                      "fanuc_ls": (r":L P\[\d\] (\d+)mm/sec", 1.0)}[language]
    return [float(next(g for g in m.groups() if g)) * scale for m in re.finditer(pattern, text)]


@pytest.mark.parametrize("language", sorted(PROGRAMS))
def test_an_example_program_retimes_and_only_its_speed_fields_change(tmp_path, language):
    before, after, output = retimed(tmp_path, language)
    pattern = SPEED_FIELDS[language]
    for tag, i1, i2, j1, j2 in difflib.SequenceMatcher(a=before.splitlines(), b=after.splitlines()).get_opcodes():
        old, new = before.splitlines()[i1:i2], after.splitlines()[j1:j2]
        if tag == "insert":  # KRL sets a speed on a line of its own
            assert language == "krl" and all(re.fullmatch(r"\s*(?:" + pattern + ")", line) for line in new), new
        elif tag == "replace" and language == "csv":
            assert [re.sub(pattern, "", line, count=1) for line in new] == old
        elif tag == "replace":
            assert [re.sub(pattern, "", line) for line in old] == [re.sub(pattern, "", line) for line in new]
        else:
            assert tag == "equal", (tag, old, new)
    assert formats.read(output).format == language  # the written program reads back


def test_the_csv_times_match_the_path_and_its_speed(tmp_path):
    _, after, _ = retimed(tmp_path, "csv")
    first, second, third = durations(after)
    into, out_of = blended_lengths(after)
    assert 80.0 / 20.0 <= first <= 80.0 / 20.0 + RAMPS
    assert 59.0 < into < 60.0 and 39.0 < out_of < 40.0  # the 5 mm blend cuts the corner
    assert second >= into / 20.0 and third >= out_of / 20.0  # never faster than programmed
    assert second + third <= 100.0 / 20.0 + RAMPS


@pytest.mark.parametrize("language", ["krl", "rapid", "fanuc_ls", "urscript"])
def test_the_weld_speed_is_kept_exactly_as_written(tmp_path, language):
    """A stated process speed the arm can cruise at stays as written: compensation changes no process parameter."""
    before, after, output = retimed(tmp_path, language)
    assert line_speeds(language, after) == line_speeds(language, before) == [20.0, 20.0, 20.0]
    report = json.loads(output.with_suffix(".json").read_text())
    assert report["timing"]["lowered"]["count"] == 0 and report["timing"]["not_retimed"]["count"] == 0


def test_the_cycle_time_before_and_after_compensation_is_printed_and_targets_stay_compensated(
        tmp_path, kuka_model, capsys):
    for name in ("weld.src", "weld.dat"):
        shutil.copy(EXAMPLES / "kuka" / name, tmp_path / name)
    timed, plain = tmp_path / "timed" / "weld.src", tmp_path / "plain" / "weld.src"
    timed.parent.mkdir()
    plain.parent.mkdir()
    assert main(["compensate", str(tmp_path / "weld.src"), "--model", str(kuka_model), "-o", str(timed)]) == 0
    err = capsys.readouterr().err
    assert re.search(r"cycle time before compensation [\d.]+ s, after [\d.]+ s", err)
    assert re.search(r"J5\s+[\d.]+\s+388", err)  # the dense check's table: peak and limit per joint
    assert main(["compensate", str(tmp_path / "weld.src"), "--model", str(kuka_model), "-o", str(plain),
                 "--retime", "none"]) == 0
    with_timing, without = formats.read(timed), formats.read(plain)
    for a, b in zip(with_timing.targets, without.targets):  # the inserted lines moved nothing else
        np.testing.assert_allclose(a.pose, b.pose, atol=1e-9)
    assert (timed.parent / "weld.dat").read_text() == (plain.parent / "weld.dat").read_text()
    assert timed.read_text().count("$VEL.CP=") == 1  # the weld's 20 mm/s kept: no line inserted
    assert "$VEL.CP=0.020000" in timed.read_text() and "$VEL.CP=0.020000" in plain.read_text()


EXTENSIONS = {"csv": ".csv", "krl": ".src", "rapid": ".mod", "fanuc_ls": ".ls", "urscript": ".script"}
CROSS = [(a, b) for a in sorted(PROGRAMS) for b in sorted(PROGRAMS) if a != b]


@pytest.mark.parametrize("source,language", CROSS)
def test_every_example_converted_to_another_language_retimes_there(tmp_path, makerless, source, language):
    """The timing of each language on one path; the arm's maker unstated, since a KUKA arm runs no URScript."""
    path, robot = PROGRAMS[source]
    robot = makerless(robot)
    converted, output = tmp_path / f"weld{EXTENSIONS[language]}", tmp_path / f"timed{EXTENSIONS[language]}"
    # the first joint motion starts from an unknown position: a RAPID TCP speed and v_ori cannot become another
    # language's joint speed, nor a joint speed a RAPID or CSV one (TCP); written at the slowest and listed (exit 1)
    listed = source != "csv" and (source == "rapid" or language in ("rapid", "csv"))
    assert main(["convert", str(EXAMPLES / path), str(converted), "--robot", robot]) == (1 if listed else 0)
    # a FANUC program names the ABB work object and tool by number; their values stand in its comments
    frames = ["--tool", "1=0,0,0,0,0,0", "--frame", "1=0,0,0,0,0,0"] * ((source, language) == ("rapid", "fanuc_ls"))
    assert main(["retime", str(converted), "-o", str(output), "--robot", robot, *frames]) == 0
    text = output.read_text()
    if language == "csv":
        first, second, third = durations(text)
        into, out_of = blended_lengths(text)
        assert 80.0 / 20.0 <= first <= 80.0 / 20.0 + RAMPS
        assert second >= into / 20.0 and third >= out_of / 20.0 and second + third <= 100.0 / 20.0 + RAMPS
    else:  # the weld speed kept as converted
        assert line_speeds(language, text) == [20.0, 20.0, 20.0]


def test_krl_restores_the_speed_of_a_motion_that_is_not_retimed(tmp_path):
    """3 m/s is more than the arm can cruise at on these lines: P2 and P3 get lower speeds. After a motion
    computed at run time the next one starts from an unknown position: they keep the programmed 3 m/s."""
    src = (EXAMPLES / "kuka" / "weld.src").read_text().replace("$VEL.CP=0.020000", "$VEL.CP=3.000000")
    src = src.replace("  LIN P4\n", "  LIN_REL {Z 10}\n  LIN P4\n")
    (tmp_path / "weld.src").write_text(src)
    shutil.copy(EXAMPLES / "kuka" / "weld.dat", tmp_path / "weld.dat")
    output = tmp_path / "out" / "weld.src"
    output.parent.mkdir()
    assert main(["retime", str(tmp_path / "weld.src"), "-o", str(output), "--robot", "kuka_kr6_r900"]) == 0
    lines = output.read_text().splitlines()
    before = {name: lines[next(k for k, line in enumerate(lines) if re.match(rf"\s*{name}\b", line)) - 1].strip()
              for name in ("LIN P2", "LIN P3", "LIN_REL", "LIN P4")}
    p2, p3 = (float(re.fullmatch(r"\$VEL\.CP=([\d.]+)", before[name]).group(1)) for name in ("LIN P2", "LIN P3"))
    assert 0.1 < p2 < 3.0 and 0.1 < p3 < 3.0  # edited, inserted
    assert before["LIN_REL"] == "$VEL.CP=3.000000"  # inserted back: the run-time motion and P4 are not re-timed
    assert before["LIN P4"] == "LIN_REL {Z 10}"
    assert [line for line in lines if not line.strip().startswith("$VEL.CP")] == \
        [line for line in src.splitlines() if not line.strip().startswith("$VEL.CP")]


@pytest.mark.parametrize("joint_targets", ["keep", "compensate"])
def test_the_compensations_planned_joints_time_the_original_as_its_posture_plan_does(
        tmp_path, kuka_model, joint_targets, monkeypatch):
    from trajcomp.support import parallel
    from trajcomp.jobs import pipeline
    from trajcomp.jobs.pipeline import retime_compensated
    from trajcomp.compensation.target_correction import program_corrector
    from trajcomp.model.model_file import load_model
    from trajcomp.compensation.program_rewrite import compensate_program

    model = load_model(kuka_model)
    shutil.copy(EXAMPLES / "kuka" / "weld.dat", tmp_path / "weld.dat")
    home = ",".join(f"A{j + 1} {v:.3f}" for j, v in enumerate(np.degrees(model.nominal.home)))
    source = (EXAMPLES / "kuka" / "weld.src").read_text().replace("  LIN P4\n", f"  LIN P4\n  PTP {{{home}}}\n")
    (tmp_path / "weld.src").write_text(source)  # a joint target between the Cartesian ones
    program = formats.read(tmp_path / "weld.src")
    corrected, report = compensate_program(program, program_corrector(model), model.nominal,
                                           joint_targets=joint_targets)
    assert len(report.joint_targets) == 1
    solved = retime_compensated(program, corrected, model.nominal, "auto", 0.005)
    reused = retime_compensated(program, corrected, model.nominal, "auto", 0.005, q_planned=report.q_planned)
    assert reused[2] == solved[2] > 9.0  # the cycle time before compensation, s: 80 + 100 mm at 20 mm/s and more
    np.testing.assert_array_equal(reused[1].t, solved[1].t)
    aside = retime_compensated(program, corrected, model.nominal, "auto", 0.005, q_planned=report.q_planned,
                               workers=2)  # the original timed by another process meanwhile
    assert aside[2] == solved[2]
    np.testing.assert_array_equal(aside[1].t, solved[1].t)
    processes = []  # of the original's timing
    monkeypatch.setattr(pipeline, "in_background",
                        lambda function, workers: processes.append(workers) or parallel.in_background(function, workers))
    monkeypatch.setattr(pipeline, "TOGETHER", len(report.q))  # a long program: one timing after the other
    long = retime_compensated(program, corrected, model.nominal, "auto", 0.005, q_planned=report.q_planned, workers=2)
    assert processes == [1] and long[2] == solved[2]
    np.testing.assert_array_equal(long[1].t, solved[1].t)


def test_the_csv_settings_are_the_t_cells_written_and_made_on_demand(tmp_path, monkeypatch):
    """A CSV's settings (``t=`` and the cell) read against the written file; blocks smaller than a segment."""
    import csv as csv_module

    from trajcomp.arm.robot import load_robot
    from trajcomp.formats import text_sequence
    from trajcomp.formats.text_sequence import Texts
    from trajcomp.timing.writeback import apply_timing, retime_program
    from tests.timing.test_timing import helix, write_joint_program

    monkeypatch.setattr(text_sequence, "TEXT_BLOCK", 7)
    robot = load_robot("ur10")
    _, q = helix(robot, 120, turns=1)
    zones = ["1"] * 120
    zones[60] = ""  # an exact stop: two segments
    source, output = tmp_path / "path.csv", tmp_path / "timed.csv"
    write_joint_program(source, q, zone=zones)
    program = formats.read(source)
    timed, result = apply_timing(program, retime_program(program, robot, program.target_table().joints), robot)
    formats.write(output, timed)
    with output.open() as f:
        cells = ["t=" + row["t"] for row in csv_module.DictReader(f)]
    segments = result.segments
    assert [(s.first, s.last) for s in segments] == [(0, 60), (60, 119)]
    for s in segments:
        assert isinstance(s.settings, Texts) and len(s.settings) == s.last - s.first
        assert list(s.settings) == cells[s.first + 1 : s.last + 1]  # iterated in blocks of 7
        assert s.settings == tuple(cells[s.first + 1 : s.last + 1]) and s.settings[-1] == cells[s.last]
        assert list(s.settings[3:10]) == cells[s.first + 4 : s.first + 11]
        assert s.written == s.last - s.first
        assert s.speed == f"{cells[s.first + 1]} .. {cells[s.last]} ({s.last - s.first} motions)"
    with pytest.raises(IndexError):
        segments[0].settings[60]


def test_spans_and_lines_move_with_the_edits_as_the_rule_says():
    """Offsets after text edits, vectorized, against the rule itself: a position moves by every edit ending at or
    before it; a span's end not by an insertion exactly there (the insertion goes after the span)."""
    from trajcomp.formats.source_shifts import _Shift

    rng = np.random.default_rng(4)
    text = "".join(rng.choice(list("ab \n"), 3000))
    cuts = np.sort(rng.choice(np.arange(1, len(text)), 400, replace=False))
    edits = []
    for a, b in zip(cuts[0::2].tolist(), cuts[1::2].tolist()):
        edits.append((a, a, "X" * int(rng.integers(0, 4))) if rng.random() < 0.4 else
                     (a, min(b, a + int(rng.integers(1, 6))), "\n" * int(rng.integers(0, 3)) + "YZ"))
    edits.sort()
    shift = _Shift(text, edits)
    positions = np.r_[cuts, rng.integers(0, len(text) + 1, 500)]

    def moved(p, end):
        return p + sum(len(t) - (b - a) for a, b, t in edits if b <= p and not (end and a == b == p))

    np.testing.assert_array_equal(shift.starts(positions), [moved(p, False) for p in positions.tolist()])
    np.testing.assert_array_equal(shift.ends(positions), [moved(p, True) for p in positions.tolist()])
    old_starts = [0] + [k + 1 for k, c in enumerate(text) if c == "\n"]
    new_text = shift.new
    numbers = np.arange(0, len(old_starts) + 3)
    expected = [n if not 1 <= n <= len(old_starts) else new_text.count("\n", 0, moved(old_starts[n - 1], False)) + 1
                for n in numbers.tolist()]
    np.testing.assert_array_equal(shift.lines(numbers), expected)
