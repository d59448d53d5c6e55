"""Compliance report at scale: time, file sizes and memory of the report of long programs (not a timed test).

Run:  python tests/benchmarks/bench_report.py [N ...]     (default: 1000 100000 300000 1000000)

For each N, a ProgramReport of N targets (a slow sweep of the virtual UR10
with a smooth correction, 50 targets outside the grid and 3 over the
tolerance) is judged by `compliance_report` in a fresh process; the table
gives the time to build the report, to write its JSON and sidecar
(``--json-only``), to render the HTML page, the sizes of the three files and
the memory the report adds on top of the run's own arrays (peak RSS minus
the RSS before the report). Targets (issue 11): report + write well under
1 s at 100,000 targets, bounded memory at 1,000,000, page < 5 MB.
"""

import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

CHILD = """
import json, sys
sys.path[:0] = [{root!r}, {here!r}]
from bench_report import measure
print(json.dumps(measure(int(sys.argv[1]), sys.argv[2])))
"""


def program_report(n):
    """A ProgramReport of n targets on the nominal UR10: a sweep of axis 1 with a small wrist wave."""
    from trajcomp.arm.kinematics import fk
    from trajcomp.compensation.program_rewrite import ProgramReport
    from trajcomp.arm.robot import load_robot

    robot = load_robot("ur10")
    k = np.arange(n)
    q = np.tile(np.radians([0.0, -100.0, 100.0, -90.0, -90.0, 0.0]), (n, 1))
    q[:, 0] = np.radians(np.linspace(-60.0, 60.0, n))
    q[:, 4] += np.radians(15.0 * np.sin(k / 5000.0))
    T_target = fk(robot, q)
    correction = np.zeros((n, 6))
    correction[:, :3] = np.c_[1.0 + 0.3 * np.sin(k / 3000.0), -0.5 * np.ones(n), 0.8 * np.cos(k / 4000.0)]
    correction[:, 3:] = 0.01
    T_command = T_target.copy()
    T_command[:, :3, 3] += correction[:, :3]
    outside = np.zeros(n, bool)
    outside[n // 2:n // 2 + 50] = True
    residual = 1e-6 * (1.0 + np.sin(k / 70.0) ** 2)
    residual[[0, n // 3, n - 1]] = 0.3
    labels = [f"helix.csv:{line}" for line in range(2, n + 2)]
    return robot, ProgramReport(
        labels=labels, lines=k + 2, tools=(None,) * n, frames=(None,) * n, T_target=T_target, T_command=T_command,
        correction=correction, q=q, q_planned=q, declared=("",) * n, written=("",) * n,
        posture_source=("previous",) * n, outside_grid=outside, predicted_residual=residual,
        landing={"estimate_mm": 0.02 + residual, "held_out_mm": np.full(n, 0.02), "unseen_mm": np.zeros(n),
                 "orientation_beyond_deg": np.zeros(n), "unmeasured_posture": np.zeros(n, bool),
                 "other_tool": np.zeros(n, bool)})


def measure(n, folder):
    """Seconds, sizes and added memory of the report of n targets, written to ``folder``."""
    from trajcomp.report import compliance_report

    robot, report = program_report(n)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    start = time.perf_counter()
    result = compliance_report(report, robot)
    built = time.perf_counter() - start
    start = time.perf_counter()
    files = result.write(Path(folder) / f"r{n}", json_only=True)
    written = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    start = time.perf_counter()
    page = result.html_text().encode()
    html = time.perf_counter() - start
    sizes = {f.suffix: f.stat().st_size for f in files}
    return {"n": n, "report_s": built, "write_s": written, "html_s": html, "json_kb": sizes[".json"] / 1e3,
            "html_kb": len(page) / 1e3, "npz_mb": sizes.get(".npz", 0) / 1e6, "added_mb": peak - before,
            "rows": result.doc["target_table"]["rows"]}


def main(sizes):
    here = Path(__file__).resolve().parent
    root, here = str(here.parents[1]), str(here)
    folder = tempfile.mkdtemp(prefix="trajcomp-report-")
    print(f"{'targets':>9} {'report s':>9} {'json+npz s':>10} {'html s':>7} {'rows':>5} {'json kB':>8} "
          f"{'html kB':>8} {'npz MB':>7} {'added MB':>9}")
    for n in sizes:
        best = None
        for _ in range(3 if n <= 300_000 else 1):  # best of 3 (a shared machine)
            run = subprocess.run([sys.executable, "-c", CHILD.format(root=root, here=here), str(n), folder],
                                 capture_output=True, text=True, check=True)
            row = json.loads(run.stdout)
            best = row if best is None or row["report_s"] + row["write_s"] < best["report_s"] + best["write_s"] else best
        r = best
        print(f"{r['n']:>9,} {r['report_s']:>9.3f} {r['write_s']:>10.3f} {r['html_s']:>7.2f} {r['rows']:>5} "
              f"{r['json_kb']:>8.0f} {r['html_kb']:>8.0f} {r['npz_mb']:>7.1f} {r['added_mb']:>9.0f}")
    print("targets: report + JSON write well under 1 s at 100,000 targets; page < 5 MB; memory bounded at 1,000,000")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1_000, 100_000, 300_000, 1_000_000])
