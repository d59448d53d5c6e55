"""Scale benchmark: end-to-end CLI throughput and peak memory on long CAM programs (not a timed test).

Run:  python tests/benchmarks/bench_scale.py [N ...]     (default: 100000 300000 1000000)
      python tests/benchmarks/bench_scale.py languages [LANGUAGE ...] [N ...]     (default: all, 20000 100000)
      ... --runs K     (runs of each timing, the median reported; default 3)

For each N, a helix of N LIN waypoints blended with 1 mm zones (a CAM path;
program CSV, mm and deg, 3 and 4 decimals) on the virtual UR10 is
compensated in composite mode and re-timed (the default) by the CLI
in a fresh process (`python -m trajcomp.cli compensate`), start-up
included, on one process (`--jobs 1`) and on every usable core (the
default), with the model a user gets (`make_model`: `calibrate`'s
defaults, so each target's landing estimate is computed); the table gives
wall time, CPU time (user + system of the process and its workers) and
waypoints/s (the median of `RUNS` runs without sampling: this machine's
speed varies by 10-30 % from run to run), and from another run the peak
memory of the process tree (summed proportional set sizes: the physical
memory the run takes) and the peak resident memory of its largest process;
then pandas' read_csv + to_csv of the same file and the default run's
ratios to it (wall and CPU time).
Also: CLI start-up (`trajcomp --version`) and the compensation core alone
(targets/s on one core).
Targets (issue 11): >= 50,000 waypoints/s at 300,000 points, < 1 GB peak at
1,000,000 points, start-up < 0.3 s; (issue 38) the default run within 4x
pandas' read and write at 300,000 points.

``languages``: the same helix in every language, each on a built-in arm of
its vendor (CSV and URScript on the UR10, KRL on the KUKA, RAPID on the
ABB, FANUC LS on the FANUC), in the arm's demo calibration cube (less one step) with a
composite model of the virtual arm, and in CSV on each of these arms. Per language, in one run so that the
figures are ratios that survive a busy machine: the I/O floor (the program
read and written again by `trajcomp.formats`, no compensation, a fresh
process; for CSV also pandas' read_csv + to_csv where pandas is
installed), `trajcomp compensate` (re-timed, every core), its ratio to the
CSV path on the same arm and to the floor, and its peak memory above that
of a 100-waypoint program of the same language, per waypoint. Each language
also in the other forms CAM post-processors write it (`cam_forms.FORMS`, a
row ``LANGUAGE:FORM`` each, e.g. ``krl:inline``): ``languages krl`` runs
every KRL form, ``languages krl:inline`` that one.
Targets (issue 25): every language within 2x the CSV path, <= 2 KB per
waypoint above start-up; CSV within 8x the pandas floor.
"""

import contextlib
import io
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from cam_forms import FORMS
from trajcomp.cli import main
from trajcomp.compensation.target_correction import compensate
from trajcomp.paper_protocol import demo_cubes
from trajcomp.arm.ik import ik
from trajcomp.model.model_file import load_model
from trajcomp.support.parallel import usable_cores
from trajcomp.calibration.measurement_plan import default_orientation
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import abc_to_matrix

RUNS = 3  # runs of each size and process count without sampling: the median wall time is reported
LANGUAGES = {  # built-in arm of a vendor -> its languages (language, extension); CSV first, the reference
    "ur10": (("csv", ".csv"), ("urscript", ".script")),
    "kuka_kr6_r900": (("csv", ".csv"), ("krl", ".src")),
    "abb_irb4600": (("csv", ".csv"), ("rapid", ".mod")),
    "fanuc_lrmate200id": (("csv", ".csv"), ("fanuc", ".ls")),
}


def helix(robot, n, centre=(550.0, 150.0, 600.0), radius=80.0, rise=100.0):
    """Poses (n, 4, 4) of a helix of 20 turns, tool orientation of home.

    ``centre``, ``radius`` and ``rise`` in mm; by default inside the UR10's calibration cube.
    """
    t = np.linspace(0.0, 40.0 * np.pi, n)
    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = abc_to_matrix(default_orientation(robot))
    circle = np.c_[radius * np.cos(t), radius * np.sin(t), np.linspace(-rise / 2, rise / 2, n)]
    T[:, :3, 3] = circle + np.asarray(centre)
    return T


def write_program(path, robot, n, **placement):
    abc = np.degrees(default_orientation(robot))
    position = helix(robot, n, **placement)[:, :3, 3]
    tail = f",{abc[0]:.4f},{abc[1]:.4f},{abc[2]:.4f},LIN,50,1\n"
    with open(path, "w") as out:
        out.write("x,y,z,a,b,c,motion,speed,zone\n")
        out.writelines(f"{x:.3f},{y:.3f},{z:.3f}{tail}" for x, y, z in position)


def run_cli(args, sample=False):
    """Wall time (s), memory and CPU time of ``python -m trajcomp.cli ARGS`` in a fresh process (`run_python`)."""
    return run_python(["-m", "trajcomp.cli", *args], sample)


def run_python(args, sample=False):
    """Wall time (s), memory and CPU time (s) of ``python ARGS`` in a fresh process.

    Memory (MB, with ``sample``, which costs the run some CPU): the peak of
    the process tree's physical memory, the sum of its processes'
    proportional set sizes sampled every 10 ms (what a forked worker shares
    with its parent counts once), and the kernel's peak resident memory of
    its largest process (a forked worker's counts the pages it shares).
    CPU time: user + system of the process and the workers it waited for
    (what a busy shared machine changes least).
    """
    start = time.perf_counter()
    with tempfile.TemporaryFile() as err:
        child = subprocess.Popen([sys.executable, *args], stdout=subprocess.DEVNULL, stderr=err)
        tree = 0.0
        while sample and not _ended(child.pid):  # an unsampled run is only waited for: polling takes CPU from it
            tree = max(tree, sum(map(_pss_kb, _tree(child.pid))) / 1024.0)
            time.sleep(0.01)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
        if child.returncode not in (0, 1):  # 1: written, its verdict fails
            err.seek(0)
            raise SystemExit(f"python {' '.join(args)} exited {child.returncode}:\n{err.read()[-2000:].decode()}")
    return wall, tree, usage.ru_maxrss / 1024.0, usage.ru_utime + usage.ru_stime


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


def make_model(folder, robot="ur10", corner=(300, -100, 300), side=400, step=100):
    """A composite model of the virtual ``robot`` calibrated on a grid (mm) of the paper's protocol, with
    `calibrate`'s defaults (5-fold cross-validation: the model a user gets, whose landing estimate the
    compensation computes).

    The default cube is the paper's large cube less one step: the arm reaches all of it in one posture
    (`trajcomp plan` refuses the paper's 500 mm cube on the UR10).
    """
    plan, meas, model = folder / f"plan-{robot}.csv", folder / f"meas-{robot}.csv", folder / f"model-{robot}.yaml"
    quietly(["plan", "--robot", robot, "--cube", ",".join(f"{v:g}" for v in corner), "--side", f"{side:g}",
             "--step", f"{step:g}", "-o", str(plan)])
    quietly(["simulate", str(plan), "--robot", robot, "--seed", "1", "-o", str(meas)])
    quietly(["calibrate", str(meas), "--robot", robot, "--grid-step", f"{step:g}", "-o", str(model)])
    return model


def quietly(args):
    """``trajcomp ARGS`` in this process, its output dropped; raises where it fails."""
    err = io.StringIO()
    with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(err):
        code = main(args)
    if code != 0:
        raise SystemExit(f"trajcomp {' '.join(args)} exited {code}:\n{err.getvalue()[-2000:]}")


def language_bench(sizes, languages=()):
    """The languages' table (module docstring): floor, compensate, ratios, memory per waypoint.

    ``languages``: the robot languages to run (each with CSV on its arm, the reference); all when empty.
    """
    folder = Path(tempfile.mkdtemp(prefix="trajcomp-languages-"))
    print(f"{'waypoints':>10} {'language':>22} {'arm':>18} {'floor s':>8} {'compensate s':>13} {'x CSV':>6} "
          f"{'x floor':>8} {'peak MB':>8} {'KB/waypoint':>12}")
    wanted = {name.split(":")[0] for name in languages}
    chosen = {robot: pairs for robot, pairs in LANGUAGES.items()
              if not languages or any(language in wanted for language, _ in pairs[1:])}
    arms = {}
    for robot in chosen:
        large = demo_cubes(load_robot(robot))[0]
        side = large.side - large.step  # one arm posture reaches all of it (see `make_model`)
        centre = np.add(large.corner, side / 2)
        arms[robot] = make_model(folder, robot, large.corner, side, large.step), dict(
            centre=centre, radius=0.16 * large.side, rise=0.2 * large.side)
    for n in sizes:
        csv_time = {}
        for robot, language, extension in ((r, *pair) for r, pairs in chosen.items() for pair in pairs):
            model, placement = arms[robot]
            paths, place = {}, folder / robot  # KRL: the file name is the program's name (a letter first, no '-')
            place.mkdir(exist_ok=True)
            for size in (100, n):
                source = place / f"helix_{size}.csv"
                write_program(source, load_robot(robot), size, **placement)
                paths[size] = source if language == "csv" else place / f"helix_{size}{extension}"
                if language != "csv":
                    quietly(["convert", str(source), str(paths[size]), "--robot", robot])
            forms = [(language, lambda path, _: path)] + [(f"{language}:{name}", make)
                                                          for name, make in FORMS.get(language, {}).items()]
            for label, make in forms:
                if label == "csv" or not languages or {label, label.split(":")[0]} & set(languages):
                    written = {size: make(paths[size], place) for size in paths}
                    _language_row(n, label, robot, written, model, place / f"out{extension}", csv_time)
            if language == "csv" and robot == "ur10":
                _pandas_floor(paths[n], place / f"out{extension}", csv_time[robot])
    print("targets: every language <= 2x CSV (same arm); <= 2 KB per waypoint above start-up; "
          "CSV <= 8x the pandas floor")


def _language_row(n, label, robot, paths, model, out, csv_time):
    """Time one program of ``n`` waypoints (``paths[n]``; ``paths[100]`` the start-up's) and print its row.

    The CSV row on an arm sets ``csv_time[robot]``, the reference of the arm's other rows.
    """
    program = paths[n]
    floor = float(np.median([run_python(["-c", "from trajcomp import formats; import sys; "
                                         "formats.write(sys.argv[2], formats.read(sys.argv[1]))",
                                         str(program), str(out)])[0] for _ in range(RUNS)]))
    args = ["compensate", str(program), "--model", str(model), "-o", str(out)]
    wall = float(np.median([run_cli(args)[0] for _ in range(RUNS)]))
    if label == "csv":
        csv_time[robot] = wall
    peak = run_cli(args, sample=True)[1]
    start = run_cli(["compensate", str(paths[100]), "--model", str(model), "-o", str(out)], sample=True)[1]
    print(f"{n:>10,} {label:>22} {robot:>18} {floor:>8.2f} {wall:>13.2f} {wall / csv_time[robot]:>6.2f} "
          f"{wall / floor:>8.2f} {peak:>8,.0f} {(peak - start) * 1024 / n:>12.2f}", flush=True)


def _pandas_floor(program, out, wall, cpu=None):
    """Print pandas' read_csv + to_csv of the CSV program (a fresh process, median of `RUNS`) and the CSV path's
    ratios to it: wall time ``wall`` (s), and CPU time ``cpu`` (s) where given."""
    try:
        import pandas  # noqa: F401 (only whether it is installed)
    except ImportError:
        print(f"{'':>10} {'pandas':>22} not installed: no pandas floor")
        return
    runs = [run_python(["-c", "import pandas, sys; pandas.read_csv(sys.argv[1]).to_csv(sys.argv[2], index=False)",
                        str(program), str(out)]) for _ in range(RUNS)]
    floor, floor_cpu = (float(np.median(column)) for column in zip(*((r[0], r[3]) for r in runs)))
    if cpu is None:
        print(f"{'':>10} {'pandas':>22} {'(CSV floor)':>18} {floor:>8.2f} {'':>13} {'':>6} {wall / floor:>8.2f}")
    else:
        print(f"{'':>10} {'pandas read + write':>22} {floor:>8.2f} {floor_cpu:>8.2f}   the default run: "
              f"{wall / floor:.1f}x pandas' wall time, {cpu / floor_cpu:.1f}x its CPU time")


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
    print(f"\n{'waypoints':>10} {'jobs':>5} {'wall s':>8} {'CPU s':>8} {'waypoints/s':>12} {'peak MB':>8} "
          f"{'largest RSS MB':>15}")
    for n in sizes:
        program = folder / f"helix{n}.csv"
        write_program(program, model.nominal, n)
        for jobs in sorted({1, usable_cores()}):
            args = ["compensate", str(program), "--model", str(model_path), "-o", str(folder / "out.csv"),
                    "--jobs", str(jobs)]
            runs = [run_cli(args) for _ in range(RUNS)]
            wall, cpu = (float(np.median(column)) for column in zip(*((r[0], r[3]) for r in runs)))
            _, peak, largest, _ = run_cli(args, sample=True)  # another run: sampling costs CPU
            print(f"{n:>10,} {jobs:>5} {wall:>8.2f} {cpu:>8.2f} {n / wall:>12,.0f} {peak:>8,.0f} {largest:>15,.0f}",
                  flush=True)
        _pandas_floor(program, folder / "pandas.csv", wall, cpu)  # against the default run (every usable core)
        program.unlink()
    print("targets: >= 50,000 waypoints/s at 300,000; < 1,000 MB at 1,000,000; the default run within 4x pandas' "
          "read and write at 300,000")


if __name__ == "__main__":
    if "--runs" in sys.argv:
        at = sys.argv.index("--runs")
        RUNS = int(sys.argv[at + 1])
        del sys.argv[at:at + 2]
    if sys.argv[1:2] == ["languages"]:
        named = [a for a in sys.argv[2:] if not a.isdigit()]
        language_bench([int(a) for a in sys.argv[2:] if a.isdigit()] or [20_000, 100_000], named)
    else:
        main_bench([int(a) for a in sys.argv[1:]] or [100_000, 300_000, 1_000_000])
