"""Start-up: wall time of ``trajcomp --help`` and of every sub-command's ``--help``, against other commits (issue 25).

Run:  python tests/benchmarks/bench_startup.py [COMMIT ...] [--runs N]

Each cell starts a fresh interpreter running the console script's entry
point (``trajcomp.cli.main``) with the trajcomp of this tree or of a COMMIT
(its tree extracted with `git archive` into a temporary folder), and times
it from launch to exit. The trees and commands take turns, run after run,
so that a busy shared machine weighs on all of them alike; the table gives
the minimum and the median wall time of the runs (s) per tree, the minimum
CPU time (user + system: what the start-up costs, whatever else the machine
runs) and whether that command line imported numpy. Target: every
``--help`` < 0.15 s wall.
"""

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TARGET = 0.15  # s, issue 25's bound on the start-up of any --help
ENTRY = "import sys\nfrom trajcomp.cli import main\nsys.exit(main())"
PROBE = ("import sys\nfrom trajcomp.cli import main\ntry:\n    main(sys.argv[1:])\nexcept SystemExit:\n    pass\n"
         "print('numpy' in sys.modules, file=sys.stderr)")


def extract(commit, folder):
    """The tree of ``commit`` written into ``folder`` (a Path), by `git archive`."""
    folder.mkdir(parents=True)
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", commit], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder


def command_lines(tree):
    """The command lines timed: ``--version``, ``--help`` and ``NAME --help`` for each command of ``tree``."""
    names = subprocess.run([sys.executable, "-c", "from trajcomp.commands import COMMANDS\nprint(*COMMANDS)"],
                           cwd=tree, env=_environment(tree), capture_output=True, text=True, check=True).stdout.split()
    return [["--version"], ["--help"]] + [[name, "--help"] for name in names]


def _environment(tree):
    """The environment that makes ``tree``'s trajcomp the one imported (run with ``cwd=tree`` too)."""
    return {**os.environ, "PYTHONPATH": str(tree)}


def seconds(tree, argv):
    """``(wall, cpu)`` times (s) of one run of the CLI of ``tree`` with ``argv``, from launch to exit."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", ENTRY, *argv], cwd=tree, env=_environment(tree), check=True,
                   stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def imports_numpy(tree, argv):
    """Whether running ``argv`` with the CLI of ``tree`` imports numpy."""
    done = subprocess.run([sys.executable, "-c", PROBE, *argv], cwd=tree, env=_environment(tree),
                          capture_output=True, text=True, check=True)
    return done.stderr.strip().splitlines()[-1] == "True"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("commits", nargs="*", help="other commits to time in the same run (e.g. main, 4f0b0f4)")
    parser.add_argument("--runs", type=int, default=5, help="runs per cell (default 5)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        trees = {"this tree": ROOT}
        for commit in args.commits:
            trees[commit] = extract(commit, Path(scratch) / commit)
        lines = command_lines(ROOT)
        times = {(label, tuple(argv)): [] for label in trees for argv in lines}
        for _ in range(args.runs):
            for argv in lines:
                for label, tree in trees.items():
                    times[label, tuple(argv)].append(seconds(tree, argv))
        numpy = {(label, tuple(argv)): imports_numpy(tree, argv) for label, tree in trees.items() for argv in lines}
    print(f"`trajcomp ARGS`, {args.runs} runs: wall time min and median, CPU time min (s); numpy imported; "
          f"target < {TARGET} s wall")
    print(f"{'':22s}" + "".join(f" | {label[:30]:30s}" for label in trees))
    header = f"{'ARGS':22s}" + " |   wall min median  cpu numpy" * len(trees)
    print(header)
    print("-" * len(header))
    for argv in lines:
        cells = []
        for label in trees:
            wall, cpu = zip(*times[label, tuple(argv)])
            cells.append(f" | {min(wall):10.3f} {statistics.median(wall):6.3f} {min(cpu):5.3f} "
                         f"{'yes' if numpy[label, tuple(argv)] else 'no':>5s}")
        print(f"{' '.join(argv):22s}" + "".join(cells))
    medians = {" ".join(argv): statistics.median(wall for wall, _ in times["this tree", tuple(argv)]) for argv in lines}
    slow = [argv for argv, median in medians.items() if median >= TARGET]
    print(f"this tree: {len(lines) - len(slow)} of {len(lines)} under {TARGET} s (median wall)"
          + (f"; over: {', '.join(slow)}" if slow else ""))


if __name__ == "__main__":
    main()
