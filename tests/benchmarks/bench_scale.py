"""Scale benchmark: end-to-end CLI throughput and peak memory on long CAM programs (not a timed test).

Run:  python tests/benchmarks/bench_scale.py [N ...]     (default: 100000 300000 1000000)

For each N, a helix of N LIN waypoints blended with 1 mm zones (a CAM path;
program CSV, mm and deg, 3 and 4 decimals) on the virtual UR10 is
compensated in composite mode and re-timed (the default) by the CLI
in a fresh process (`python -m trajcomp.cli compensate`), start-up
included, on one process (`--jobs 1`) and on every usable core (the
default); the table gives wall time and waypoints/s (the median of
`RUNS` runs without sampling: this machine's speed varies by 10-30 % from
run to run), and from another run the peak memory of the process tree
(summed proportional set sizes: the physical memory the run takes) and
the peak resident memory of its largest process.
Also: CLI start-up (`trajcomp --version`) and the compensation core alone
(targets/s on one core).
Targets (issue 11): >= 50,000 waypoints/s at 300,000 points, < 1 GB peak at
1,000,000 points, start-up < 0.3 s.
"""

import contextlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from trajcomp.cli import main
from trajcomp.compensate import compensate
from trajcomp.ik import ik
from trajcomp.model_file import load_model
from trajcomp.parallel import usable_cores
from trajcomp.plan import default_orientation
from trajcomp.transforms import abc_to_matrix

RUNS = 3  # runs of each size and process count without sampling: the median wall time is reported


def helix(robot, n):
    """Poses (n, 4, 4) of a helix of 20 turns inside the UR10 calibration cube, tool orientation of home."""
    t = np.linspace(0.0, 40.0 * np.pi, n)
    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = abc_to_matrix(default_orientation(robot))
    T[:, :3, 3] = np.c_[550 + 80 * np.cos(t), 150 + 80 * np.sin(t), 550 + np.linspace(0.0, 100.0, n)]
    return T


def write_program(path, robot, n):
    abc = np.degrees(default_orientation(robot))
    position = helix(robot, n)[:, :3, 3]
    tail = f",{abc[0]:.4f},{abc[1]:.4f},{abc[2]:.4f},LIN,50,1\n"
    with open(path, "w") as out:
        out.write("x,y,z,a,b,c,motion,speed,zone\n")
        out.writelines(f"{x:.3f},{y:.3f},{z:.3f}{tail}" for x, y, z in position)


def run_cli(args, sample=False):
    """Wall time (s) and memory of ``python -m trajcomp.cli ARGS`` in a fresh process.

    Memory (MB, with ``sample``, which costs the run some CPU): the peak of
    the process tree's physical memory, the sum of its processes'
    proportional set sizes sampled every 10 ms (what a forked worker shares
    with its parent counts once), and the kernel's peak resident memory of
    its largest process (a forked worker's counts the pages it shares).
    """
    start = time.perf_counter()
    with tempfile.TemporaryFile() as err:
        child = subprocess.Popen([sys.executable, "-m", "trajcomp.cli", *args], stdout=subprocess.DEVNULL, stderr=err)
        tree = 0.0
        while sample and not _ended(child.pid):  # an unsampled run is only waited for: polling takes CPU from it
            tree = max(tree, sum(map(_pss_kb, _tree(child.pid))) / 1024.0)
            time.sleep(0.01)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
        if child.returncode != 0:
            err.seek(0)
            raise SystemExit(f"trajcomp {' '.join(args)} exited {child.returncode}:\n{err.read()[-2000:].decode()}")
    return wall, tree, usage.ru_maxrss / 1024.0


def _ended(pid):
    """Whether the process has ended (a zombie not yet reaped, so that wait4 still gives its usage)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


def _tree(pid):
    """The process ``pid`` and its descendants (Linux /proc)."""
    found = [pid]
    for process in found:
        for children in Path(f"/proc/{process}/task").glob("*/children"):
            with contextlib.suppress(OSError):
                found += [int(c) for c in children.read_text().split()]
    return found


def _pss_kb(pid):
    """Proportional set size of a process, kB (0 once it has ended)."""
    with contextlib.suppress(OSError):
        for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
            if line.startswith("Pss:"):
                return int(line.split()[1])
    return 0


def make_model(folder):
    plan, meas, model = folder / "plan.csv", folder / "meas.csv", folder / "model.yaml"
    with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet):
        main(["plan", "--robot", "ur10", "--cube", "300,-100,300", "--side", "500", "--step", "100", "-o", str(plan)])
        main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "-o", str(meas)])
        main(["calibrate", str(meas), "--robot", "ur10", "--grid-step", "100", "--folds", "0", "-o", str(model)])
    return model


def main_bench(sizes):
    folder = Path(tempfile.mkdtemp(prefix="trajcomp-scale-"))
    model_path = make_model(folder)
    startup = min(run_cli(["--version"])[0] for _ in range(3))
    print(f"CLI start-up (trajcomp --version, best of 3): {startup:.3f} s   (target < 0.3 s)")
    model = load_model(model_path)
    T = helix(model.nominal, 100_000)
    seed = ik(model.nominal, T, seed=model.nominal.home).q
    start = time.perf_counter()
    compensate(model, T, seed=seed)
    core = len(T) / (time.perf_counter() - start)
    print(f"compensation core, composite, 100,000 seeded targets, this process: {core:,.0f} targets/s")
    print(f"\n{'waypoints':>10} {'jobs':>5} {'wall s':>8} {'waypoints/s':>12} {'peak MB':>8} {'largest RSS MB':>15}")
    for n in sizes:
        program = folder / f"helix{n}.csv"
        write_program(program, model.nominal, n)
        for jobs in sorted({1, usable_cores()}):
            args = ["compensate", str(program), "--model", str(model_path), "-o", str(folder / "out.csv"),
                    "--jobs", str(jobs)]
            wall = float(np.median([run_cli(args)[0] for _ in range(RUNS)]))
            _, peak, largest = run_cli(args, sample=True)  # another run: sampling costs CPU
            print(f"{n:>10,} {jobs:>5} {wall:>8.2f} {n / wall:>12,.0f} {peak:>8,.0f} {largest:>15,.0f}")
        program.unlink()
    print("targets: >= 50,000 waypoints/s at 300,000; < 1,000 MB at 1,000,000")


if __name__ == "__main__":
    main_bench([int(a) for a in sys.argv[1:]] or [100_000, 300_000, 1_000_000])
