"""Stopping signals at random moments: every run ends within 2 s with the signal's code, whole, no process left.

Runs ``MOMENTS`` (100 by default) ``trajcomp`` processes, each in a process
group of its own (tests/signal_runs.py): ``compensate`` of a 20,000-target
CSV program (``--jobs 2``), a batch of four 3,000-target programs
(``--jobs 2``), the same batch on a local Dask cluster (``--scheduler local``,
when Dask is installed) and ``calibrate`` of a 125-point plan, with SIGTERM, SIGINT
or SIGHUP sent to the group, to the main process or to a worker at a
random moment of the run. Prints per command, signal and target: runs,
runs stopped with the signal's code, runs that had finished first, runs
breaking a promise (late, hung, a process left running, a traceback, a
wrong code, a file left under a real name or a temporary) and the longest
time from the signal to the end; then each broken run. Target: 0 broken,
every run ended within 2 s.

    PYTHONPATH=$PWD python tests/benchmarks/bench_signals.py [MOMENTS [SEED [COMMAND]]]

COMMAND runs one of them alone (e.g. ``"dask batch"``).
"""

import collections
import importlib.util
import random
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tests.signal_runs import long_program, run_stopped  # noqa: E402

ROBOT = "kuka_kr6_r900"


def _setup(folder):
    """The model, measurements and programs the runs read."""
    def trajcomp(*args):
        subprocess.run([sys.executable, "-m", "trajcomp.cli", *args], cwd=folder, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    trajcomp("plan", "--robot", ROBOT, "--cube", "400,-50,650", "--side", "200", "--step", "50", "-o", "plan.csv")
    trajcomp("simulate", "plan.csv", "--robot", ROBOT, "--seed", "1", "-o", "meas.csv")
    trajcomp("calibrate", "meas.csv", "--robot", ROBOT, "--grid-step", "50", "--folds", "3", "-o", "kuka.yaml")
    long_program(folder / "long.csv", 20000)
    (folder / "cam").mkdir()
    for k in range(4):
        long_program(folder / "cam" / f"p{k}.csv", 3000)


COMMANDS = {  # name: (arguments, how long it runs about (s), what a finished run writes, what a stopped one may)
    "compensate": (["compensate", "../long.csv", "--model", "../kuka.yaml", "-o", "out.csv", "--jobs", "2"], 6.0,
                   lambda files: files == ["out.csv"], lambda files: not files),
    "batch": (["compensate", "../cam", "--model", "../kuka.yaml", "-o", "out", "--jobs", "2"], 5.0,
              lambda files: set(files) == {f"out/p{k}.csv" for k in range(4)} | {"out/summary.json"},
              lambda files: set(files) <= {f"out/p{k}.csv" for k in range(4)}),
    "dask batch": (["compensate", "../cam", "--model", "../kuka.yaml", "-o", "out", "--jobs", "2",
                    "--scheduler", "local"],
                   8.0, lambda files: set(files) == {f"out/p{k}.csv" for k in range(4)} | {"out/summary.json"},
                   lambda files: set(files) <= {f"out/p{k}.csv" for k in range(4)}),
    "calibrate": (["calibrate", "../meas.csv", "--robot", ROBOT, "--grid-step", "50", "--folds", "3",
                   "-o", "model.yaml"], 1.8,
                  lambda files: files == ["model.yaml"], lambda files: not files),
}


def main(moments=100, seed=0, only=None):
    signal.signal(signal.SIGINT, signal.default_int_handler)  # not ignored by the runs (a shell's background job)
    rng = random.Random(seed)
    commands = [name for name in COMMANDS if name != "dask batch" or importlib.util.find_spec("distributed")]
    commands = [name for name in commands if only in (None, name)]
    table = collections.defaultdict(lambda: [0, 0, 0, 0, 0.0])
    broken = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        _setup(folder)
        for k in range(moments):
            name = rng.choice(commands)
            signum = rng.choice([signal.SIGTERM, signal.SIGINT, signal.SIGHUP])
            target = rng.choice(["group", "group", "main", "worker"])
            arguments, duration, finished, stopped = COMMANDS[name]
            delay = rng.uniform(0.0, duration)
            run = folder / f"run{k}"
            run.mkdir()
            outcome = run_stopped(arguments, run, signum, delay, target)
            problems = outcome.problems(signum, finished, stopped)
            row = table[name, signal.Signals(signum).name, target]
            row[0] += 1
            row[1] += outcome.code == 128 + signum
            row[2] += outcome.code in (0, 1)
            row[3] += bool(problems)
            row[4] = max(row[4], outcome.seconds)
            if problems:
                broken.append((name, signal.Signals(signum).name, outcome.sent_to, f"{delay:.2f} s", problems))
    print(f"{'command':<12}{'signal':<8}{'to':<8}{'runs':>5}{'stopped':>9}{'finished':>9}{'broken':>7}"
          f"{'max end s':>11}")
    for (name, signame, target), (runs, stopped, done, bad, longest) in sorted(table.items()):
        print(f"{name:<12}{signame:<8}{target:<8}{runs:>5}{stopped:>9}{done:>9}{bad:>7}{longest:>11.2f}")
    total = sum(row[0] for row in table.values())
    print(f"{total} runs, {len(broken)} broken, longest end {max(row[4] for row in table.values()):.2f} s")
    for case in broken:
        print("BROKEN", *case)
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main(*map(int, sys.argv[1:3]), *sys.argv[3:4]))
