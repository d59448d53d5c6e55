"""Accuracy benchmark: prints the tables of issue 3 (not a timed test).

Run:  python tests/benchmarks/bench_accuracy.py

1. Virtual robot, paper profile, the paper's two cubes: compensation landing
   error at 40 random targets per cube and mode, beside the noise floor.
2. Real UR5 grid (../shared/data/ur5-grid, 1000 poses): 5-fold
   cross-validation of none / linear / dh / grid / composite with the
   scattered interpolators (the poses are not on an exact lattice).
"""

from pathlib import Path

from trajcomp.calibrate import calibrate
from trajcomp.demo import format_comparison, run_demo
from trajcomp.measurements import parse_mapping, read_measurements
from trajcomp.robot import load_robot
from trajcomp.stats import ErrorStats, format_table

UR5_GRID = Path(__file__).resolve().parents[3] / "shared" / "data" / "ur5-grid" / "grid.csv"
UR5_COLUMNS = ",".join([f"j{i}=joint_{i}" for i in range(1, 7)] + ["x=x_t", "y=y_t", "z=z_t",
                        "mx=x_t+x_dif", "my=y_t+y_dif", "mz=z_t+z_dif"])
PUBLISHED_UR5 = 0.155  # mm mean, hybrid MDH + neural network (Jacobi 2025)


def virtual_tables():
    for seed in (1, 2, 3):
        virtual, results = run_demo(load_robot("ur10"), "paper", seed)
        print(f"\n== virtual UR10, paper profile, seed {seed}: landing error after compensation")
        print(format_comparison(results, virtual.profile.noise_sigma))


def ur5_table():
    if not UR5_GRID.exists():
        print(f"\n== real UR5 grid: {UR5_GRID} not present, skipped")
        return
    meas = read_measurements(UR5_GRID, parse_mapping(UR5_COLUMNS))
    for interpolation in ("knn", "rbf"):
        model = calibrate(load_robot("ur5"), meas, interpolation=interpolation, folds=5)
        cv = {m: ErrorStats(**{**s, "signed_mean": tuple(s["signed_mean"]), "std": tuple(s["std"])})
              for m, s in model.report["cross_validation"].items() if isinstance(s, dict)}
        print(f"\n== real UR5 grid, 1000 poses, 5-fold cross-validation, residual interpolator {interpolation}")
        print(format_table(cv))
        print(f"best published on these data: {PUBLISHED_UR5} mm mean; composite: {cv['composite'].mean:.4f} mm")


if __name__ == "__main__":
    virtual_tables()
    ur5_table()
