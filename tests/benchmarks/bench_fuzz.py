"""The full fuzz of issue 26: >= 5,000 mutated programs in every format, a table of what became of them.

Runs the operators of tests/test_fuzz.py (bit flips, inserted and deleted
bytes, duplicated and deleted lines, swapped digits, extreme and blown-up
numbers, truncation, a line x1000, leading punctuation) ``CASES`` times on
every example and test program (50 files: 7,500 cases by default), each
case read, written back, compensated and written, converted and written,
and every tenth also re-timed. Prints per language: cases, refused on
reading (a TrajcompError: expected), crashes (any other exception or a
numpy RuntimeWarning), the slowest case (s) and the process's peak memory;
then the crashes with a reproducer. Targets: 0 crashes, no case over 20 s,
peak memory under 1 GB.

    PYTHONPATH=$PWD python tests/benchmarks/bench_fuzz.py [CASES_PER_FILE]
"""

import random
import resource
import sys
import tempfile
import time
import traceback
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import test_fuzz as fuzz  # noqa: E402 (the suite's operators and steps)
from trajcomp import formats  # noqa: E402
from trajcomp.calibration.calibrate import calibrate  # noqa: E402
from trajcomp.compensation.target_correction import program_corrector  # noqa: E402
from trajcomp.errors import TrajcompError  # noqa: E402
from trajcomp.jobs.retime import planned  # noqa: E402
from trajcomp.compensation.posture import planned_joints  # noqa: E402
from trajcomp.timing.writeback import retime_program  # noqa: E402


def cell():
    """The suite's UR10 cell: the robot and a corrector of a composite model."""
    robot = fuzz.load_robot("ur10")
    plan = fuzz.plan_grid(robot, (-800.0, -300.0, 400.0), 400.0, 100.0)
    joints = plan.joints[plan.reachable]
    measured = fuzz.VirtualRobot.create(robot, "paper", seed=1).measure(joints, np.random.default_rng(3))
    meas = fuzz.Measurements(joints=joints, position=plan.position[plan.reachable], measured=measured,
                             lines=np.arange(len(joints)) + 2, path="fuzz.csv")
    model = calibrate(robot, meas, robot_ref="ur10", method="composite", grid_step=100.0, folds=0)
    return robot, program_corrector(model, label="fuzz")


def retime(path, robot):
    """Re-time the program at ``path`` on its nominal joints, as `trajcomp retime` does (TrajcompErrors expected)."""
    program = formats.read(path)
    tools, frames = fuzz.given_frames(program)
    plan = planned_joints(program, robot, tools=tools, frames=frames)
    retime_program(program, robot, planned(program, plan.index, plan.q), tools=tools, frames=frames)


def main(cases_per_file):
    robot, correct = cell()
    rows, crashes = {}, []
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for seed_file in fuzz.SEEDS:
            language = seed_file.parent.name
            row = rows.setdefault(language, {"cases": 0, "refused": 0, "crashes": 0, "slowest": 0.0})
            rng = random.Random(f"{seed_file.name}-26")
            for other in seed_file.parent.iterdir():
                if other.stem == seed_file.stem:
                    (folder / other.name).write_bytes(other.read_bytes())
            original = seed_file.read_bytes()
            for case in range(cases_per_file):
                data, how = fuzz.mutate(original, rng)
                (folder / seed_file.name).write_bytes(data)
                program = folder / seed_file.name
                if program.suffix.lower() == ".dat":
                    program = program.with_suffix(".src")
                to_format = rng.choice(sorted(fuzz.LANGUAGES))
                start = time.perf_counter()
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("error", RuntimeWarning)
                        try:
                            formats.read(program)
                        except TrajcompError:
                            row["refused"] += 1
                        fuzz.exercise(program, folder / "out", robot, correct, to_format)
                        if case % 10 == 0:
                            try:
                                retime(program, robot)
                            except TrajcompError:
                                pass
                except Exception as exc:  # noqa: BLE001 - a crash is what this counts
                    row["crashes"] += 1
                    last = traceback.format_exception(exc)[-2].strip().splitlines()[0]
                    crashes.append(f"{seed_file.name} case {case}: {how}: {type(exc).__name__}: {str(exc)[:150]} [{last}]")
                row["cases"] += 1
                row["slowest"] = max(row["slowest"], time.perf_counter() - start)
            for other in folder.iterdir():
                if other.is_file():
                    other.unlink()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"{'language':10} {'cases':>7} {'refused':>8} {'crashes':>8} {'slowest s':>10}")
    for language, row in sorted(rows.items()):
        print(f"{language:10} {row['cases']:7d} {row['refused']:8d} {row['crashes']:8d} {row['slowest']:10.2f}")
    total = {k: sum(r[k] for r in rows.values()) for k in ("cases", "refused", "crashes")}
    print(f"{'all':10} {total['cases']:7d} {total['refused']:8d} {total['crashes']:8d} "
          f"{max(r['slowest'] for r in rows.values()):10.2f}   peak memory {peak:.0f} MB")
    for line in crashes[:50]:
        print("CRASH", line)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 150)
