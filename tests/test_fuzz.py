"""Seeded byte mutations of every example and test program through read, compensate, convert and write.

Each case mutates one program file (a KRL .src or its .dat) once: a flipped
bit, an inserted or deleted byte, a duplicated or deleted line, two digits
swapped, a number replaced by an extreme one (``1e999``, ``nan``, ``-0``, a
400-digit integer) or blown up (``1e308``, ``1e-320``, ``1e-28``, 400
digits), the file cut off at a random byte, a line repeated 1,000 times, or
punctuation put before a line's first word (``+movel(...)``). These
operators found the crashes of issue 26. The mutated program is read; if it reads, it
is written back in its own language, compensated with a small UR10 model
(tools and frames it does not define are given values) and written, and
converted to another language (the case's seed picks it) and written;
writing renders the files in memory through the same checks and writers as
`trajcomp.formats.write`. Any exception that is not a `TrajcompError`, and
any numpy RuntimeWarning (a NaN or overflow creeping through), fails the
test, listing each crash with a reproducer (program, case, mutation) and
the traceback's last line.
"""

import random
import re
import traceback
import warnings
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.calibration.calibrate import calibrate
from trajcomp.compensation.target_correction import program_corrector
from trajcomp.errors import TrajcompError
from trajcomp.formats.file_writing import check_writable
from trajcomp.calibration.measurements import Measurements
from trajcomp.calibration.measurement_plan import plan_grid
from trajcomp.compensation.program_rewrite import compensate_program, convert_program
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.virtual_arm import VirtualRobot
from trajcomp.arm.transforms import pose_to_matrix

ROOT = Path(__file__).parent.parent
SEEDS = sorted(
    p for folder in (ROOT / "examples" / "programs", Path(__file__).parent / "data" / "programs")
    for p in folder.rglob("*") if p.is_file() and p.suffix.lower() not in (".txt", ".md")
)
CASES_PER_FILE = 30  # the suite's sample; tests/benchmarks/bench_fuzz.py runs 150 per file, re-timing included
LANGUAGES = {"csv": ".csv", "krl": ".src", "rapid": ".mod", "fanuc_ls": ".ls", "urscript": ".script"}
EXTREMES = (b"1e999", b"nan", b"-0", b"9" * 400, b"-1e-320", b"0x10", b"1.5.2")
BLOW_UPS = (b"1e308", b"-1e308", b"1e-320", b"1e-28", b"1" + b"0" * 400, b"0." + b"0" * 400 + b"1")
KINDS = ("flip", "insert", "delete", "duplicate line", "delete line", "swap digits", "extreme", "blow up",
         "truncate", "repeat line", "leading punctuation")
_NUMBER = re.compile(rb"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


@pytest.fixture(scope="module")
def cell():
    """A UR10 and a composite model calibrated on its virtual copy (125 points, under a second)."""
    robot = load_robot("ur10")
    plan = plan_grid(robot, (-800.0, -300.0, 400.0), 400.0, 100.0)
    joints = plan.joints[plan.reachable]
    virtual = VirtualRobot.create(robot, "paper", seed=1)
    measured = virtual.measure(joints, np.random.default_rng(3))
    meas = Measurements(joints=joints, position=plan.position[plan.reachable], measured=measured,
                        lines=np.arange(len(joints)) + 2, path="fuzz.csv")
    model = calibrate(robot, meas, robot_ref="ur10", method="composite", grid_step=100.0, folds=0)
    return robot, program_corrector(model, label="fuzz")


def mutate(data, rng):
    """``(mutated bytes, description)``: one random edit of ``data``."""
    kind = rng.choice(KINDS)
    if not data:
        return b"\n", "empty -> newline"
    at = rng.randrange(len(data))
    if kind == "truncate":
        return data[:at], f"cut off at byte {at}"
    if kind == "flip":
        return data[:at] + bytes([data[at] ^ (1 << rng.randrange(8))]) + data[at + 1:], f"flip bit at {at}"
    if kind == "insert":
        byte = rng.choice(b"0123456789-+.,;:[]{}()='\"\\ \t\n\r*#!eEpPxX\x00\xff")
        return data[:at] + bytes([byte]) + data[at:], f"insert {bytes([byte])!r} at {at}"
    if kind == "delete":
        return data[:at] + data[at + 1:], f"delete byte {at}"
    lines = data.splitlines(keepends=True)
    k = rng.randrange(len(lines))
    if kind == "duplicate line":
        return b"".join(lines[:k + 1] + lines[k:]), f"duplicate line {k + 1}"
    if kind == "delete line":
        return b"".join(lines[:k] + lines[k + 1:]), f"delete line {k + 1}"
    if kind == "repeat line":
        return b"".join(lines[:k] + [lines[k]] * 1000 + lines[k + 1:]), f"line {k + 1} x1000"
    if kind == "leading punctuation":
        indent = len(lines[k]) - len(lines[k].lstrip())
        mark = rng.choice(b"+-*/!.,;:#@$%&=<>?")
        return b"".join(lines[:k] + [lines[k][:indent] + bytes([mark]) + lines[k][indent:]] + lines[k + 1:]), \
            f"{bytes([mark])!r} before line {k + 1}"
    numbers = list(_NUMBER.finditer(data))
    if not numbers:
        return data, "no number"
    m = rng.choice(numbers)
    if kind in ("extreme", "blow up"):
        value = rng.choice(EXTREMES if kind == "extreme" else BLOW_UPS)
        return data[:m.start()] + value + data[m.end():], f"number at {m.start()} -> {value[:12]!r}"
    digits = [i for i in range(len(data) - 1) if chr(data[i]).isdigit() and chr(data[i + 1]).isdigit()]
    if not digits:
        return data, "no digits"
    i = rng.choice(digits)
    return data[:i] + data[i + 1:i + 2] + data[i:i + 1] + data[i + 2:], f"swap digits at {i}"


def given_frames(program):
    """Values for the tools and frames the program uses but does not define (so compensation proceeds)."""
    try:
        usage = program.usage()
    except TrajcompError:
        return {}, {}
    tools = {t for t, _ in usage.values() if t is not None and t not in program.tools}
    frames = {f for _, f in usage.values() if f is not None and f not in program.frames}
    offset = pose_to_matrix([0.0, 0.0, 100.0, 0.0, 0.0, 0.0])
    return dict.fromkeys(tools, offset), dict.fromkeys(frames, np.eye(4))


def render(path, program):
    """The files `trajcomp.formats.write` would write, rendered in memory (same checks, same writers)."""
    check_writable(program)
    files = formats.find_format(path).write(program, path)
    return {p: data if isinstance(data, bytes) else b"".join(data) for p, data in files.items()}  # pieces made now


def exercise(path, out, robot, correct, to_format):
    """Read, write back, compensate and write, convert and write; TrajcompErrors are expected."""
    try:
        program = formats.read(path)
    except TrajcompError:
        return
    own = LANGUAGES[program.format]
    tools, frames = given_frames(program)
    for step in ("write", "compensate", "convert"):
        try:
            if step == "write":
                render(out / f"same{own}", program)
            elif step == "compensate":
                corrected, _ = compensate_program(program, correct, robot, tools=tools, frames=frames)
                render(out / f"corrected{own}", corrected)
            else:
                converted = convert_program(program, to_format, robot=robot, tools=tools, frames=frames)
                render(out / f"converted{LANGUAGES[to_format]}", converted)
        except TrajcompError:
            continue


@pytest.mark.parametrize("seed_file", SEEDS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_mutated_programs_never_crash(seed_file, cell, tmp_path):
    robot, correct = cell
    rng = random.Random(f"{seed_file.name}-7")
    companions = [p for p in seed_file.parent.iterdir() if p.stem == seed_file.stem and p != seed_file]
    crashes = []
    for other in companions:
        (tmp_path / other.name).write_bytes(other.read_bytes())
    original = seed_file.read_bytes()
    for case in range(CASES_PER_FILE):
        data, how = mutate(original, rng)
        (tmp_path / seed_file.name).write_bytes(data)
        program = tmp_path / seed_file.name
        if program.suffix.lower() == ".dat":
            program = next((tmp_path / p.name for p in companions if p.suffix.lower() == ".src"), None)
            if program is None:
                continue
        to_format = rng.choice(sorted(LANGUAGES))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", RuntimeWarning)
                exercise(program, tmp_path / "out", robot, correct, to_format)
        except Exception as exc:  # noqa: BLE001 - the point of the test: anything else is a crash
            last = traceback.format_exception(exc)[-2].strip().splitlines()[0]
            crashes.append(f"case {case}: {how}, then {to_format}: {type(exc).__name__}: {exc} [{last}]")
    assert not crashes, f"{seed_file.name}: {len(crashes)} crashes\n" + "\n".join(crashes[:20])


def test_found_a_wrist_point_a_denormal_off_the_base_axis_solves_without_overflow():
    """Fuzz find: ``p[0, 0, 0.05, -1e-320, 0, 0]`` put the UR10 wrist point 1e-318 mm off axis 1 (ik overflow)."""
    from trajcomp.arm.ik import ik
    from trajcomp.arm.transforms import rotvec_to_matrix

    robot = load_robot("ur10")
    T = np.eye(4)
    T[:3, :3] = rotvec_to_matrix([-1e-320, 0.0, 0.0])
    T[:3, 3] = [0.0, 0.0, 50.0]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        result = ik(robot, T[None], seed=robot.home)
    assert result.reason[0] in ("", "unreachable", "joint limits", "singular", "not converged")
