"""Before/after byte comparison of the written programs of two source trees (not a timed test).

Run:  python tests/benchmarks/compare_outputs.py BEFORE_TREE [AFTER_TREE] [--only .src,.ls]
(AFTER_TREE: this checkout; ``--only``: the programs of these suffixes alone)

e.g. ``git archive main | tar -x -C /tmp/before`` then
``python tests/benchmarks/compare_outputs.py /tmp/before``.

Every program of tests/data/programs (the real corpus included) and
examples/programs is compensated by the CLI of each tree (``python -m
trajcomp.cli compensate``, a fresh process with the tree first on the
path) with a composite model of its maker's built-in arm, re-timed
(TOPP-RA / ruckig, which writes speed settings and inserts speed lines)
and not re-timed (``--retime none``); every written file, the exit code and
the standard error must be byte for byte the same in both trees. A
program the arm cannot reach exits 1 or 2 alike in both: its message is
compared too. The models are calibrated once, with the AFTER tree, on the
arms' demo cubes less one step (`bench_scale.make_model`).
Prints one line per program and run, and exits 1 if any output differs.
"""

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path


HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_scale  # noqa: E402 (beside this file)

REPO = HERE.parent.parent
ARMS = {".src": "kuka_kr6_r900", ".mod": "abb_irb4600", ".prg": "abb_irb4600", ".modx": "abb_irb4600",
        ".sys": "abb_irb4600", ".ls": "fanuc_lrmate200id", ".script": "ur10", ".urscript": "ur10", ".csv": "ur10"}
RETIMES = ("auto", "none")


def programs(suffixes=tuple(ARMS)):
    """The program files of the corpora of these suffixes (a KRL .dat goes with its .src), by path."""
    roots = [REPO / "tests" / "data" / "programs", REPO / "examples" / "programs"]
    return sorted(p for root in roots for p in root.rglob("*")
                  if p.is_file() and p.suffix.lower() in suffixes and p.suffix.lower() in ARMS)


def run(tree, program, model, retime, out_folder):
    """Exit code, stderr and ``{file name: bytes}`` of one compensate run of ``tree``'s CLI."""
    out_folder.mkdir(parents=True)
    for other in program.parent.iterdir():  # the other files of its task or controller, beside it
        if other.is_file():
            shutil.copy(other, out_folder / other.name)
    before = {p.name: p.read_bytes() for p in out_folder.iterdir()}
    output = out_folder / f"out_{program.stem}{program.suffix}"
    done = subprocess.run([sys.executable, "-m", "trajcomp.cli", "compensate", str(out_folder / program.name),
                           "--model", str(model), "--retime", retime, "-o", str(output)],
                          capture_output=True, env=os.environ | {"PYTHONPATH": str(tree)}, cwd=out_folder)
    written = {p.name: p.read_bytes() for p in out_folder.iterdir() if before.get(p.name) != p.read_bytes()}
    return done.returncode, done.stderr.replace(str(out_folder).encode(), b"<out>"), written


def main(before_tree, after_tree=REPO, suffixes=tuple(ARMS)):
    folder = Path(tempfile.mkdtemp(prefix="trajcomp-compare-"))
    models = {}
    for robot in sorted(set(ARMS.values())):
        large = bench_scale.demo_cubes(bench_scale.load_robot(robot))[0]
        models[robot] = bench_scale.make_model(folder, robot, large.corner, large.side - large.step, large.step)
    differ = 0
    chosen = programs(suffixes)
    for k, program in enumerate(chosen):
        for retime in RETIMES:
            runs = [run(tree, program, models[ARMS[program.suffix.lower()]], retime, folder / f"{k}-{retime}-{side}")
                    for side, tree in (("before", before_tree), ("after", after_tree))]
            same = runs[0] == runs[1]
            differ += not same
            files = ", ".join(sorted(runs[1][2])) or "nothing written"
            print(f"{'same' if same else 'DIFFERENT':>9}  exit {runs[1][0]}  retime {retime:<4}  "
                  f"{program.relative_to(REPO)} -> {files}", flush=True)
            if not same:
                for name in sorted(set(runs[0][2]) | set(runs[1][2])):
                    if runs[0][2].get(name) != runs[1][2].get(name):
                        print(f"{'':>11}differs: {name}")
                if runs[0][:2] != runs[1][:2]:
                    print(f"{'':>11}exit/stderr: {runs[0][:2]} vs {runs[1][:2]}"[:2000])
    print(f"{differ} of {2 * len(chosen)} runs differ")
    return 1 if differ else 0


if __name__ == "__main__":
    only = sys.argv.index("--only") if "--only" in sys.argv else None
    suffixes = tuple(ARMS) if only is None else tuple(sys.argv[only + 1].lower().split(","))
    trees = [Path(a).resolve() for a in (sys.argv[1:] if only is None else sys.argv[1:only])]
    sys.exit(main(*trees, suffixes=suffixes))
