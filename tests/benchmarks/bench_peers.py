"""trajcomp beside its peers: per-pose IK, residual interpolation, DH identification (times as ratios).

Run as ``python tests/benchmarks/bench_peers.py [N]`` (default N = 2,000 IK
poses). The peers are optional benchmark extras (``pip install -e
".[bench]"``): roboticstoolbox-python, ur-analytic-ik and ik-geo; a row whose
package is missing says so and the rest run. Threads are pinned to one, so
every figure is per core; each time is the best of three runs.

1. IK on the UR10 (CB3 DH table, the same in every package): N poses from
   joints around the calibration posture, each solved near a seed 3 deg off
   its true joints (a planner's neighbouring joints). trajcomp solves all N
   in one vectorized call (and, for comparison, one pose per call); the peers
   one pose per call. Errors are measured with trajcomp's FK; "posture" is
   the share of solutions on the true branch (turns modulo 360 deg).
2. Residual interpolation: the composite model's residual grid (6 x 6 x 6
   nodes, 100 mm) of the virtual UR10, evaluated at 100,000 points (speed)
   and at 2,000 validation points against the virtual arm's noise-free
   residual (accuracy), beside scipy's RegularGridInterpolator and
   RBFInterpolator on the same data.
3. Identification: trajcomp's fit (`trajcomp.calibration.identify.identify`: analytic
   Jacobian, identifiability by QR, robust loss) beside a plain scipy least_squares over all 24 DH deltas and the TCP
   with finite differences, on the same 216 measurements; accuracy is the
   DH model's mean landing error at the validation points.
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import importlib  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from scipy.interpolate import RBFInterpolator, RegularGridInterpolator  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402

from trajcomp.calibration.calibrate import calibrate  # noqa: E402
from trajcomp.calibration.identify import identify  # noqa: E402
from trajcomp.arm.ik import configuration_of, ik  # noqa: E402
from trajcomp.model.interpolate import RBF  # noqa: E402
from trajcomp.arm.kinematics import fk, link_frames  # noqa: E402
from trajcomp.calibration.measurements import Measurements  # noqa: E402
from trajcomp.arm.parameters import apply_deltas  # noqa: E402
from trajcomp.calibration.measurement_plan import plan_grid  # noqa: E402
from trajcomp.arm.robot import load_robot  # noqa: E402
from trajcomp.calibration.virtual_arm import VirtualRobot  # noqa: E402
from trajcomp.arm.transforms import rotation_angle_between  # noqa: E402

REPEATS = 3
CUBE = ((300.0, -100.0, 300.0), 500.0, 100.0)  # the paper's large cube: corner, side, step (mm)
POSTURE = np.radians([27.0, -185.0, 91.0, 4.0, -90.0, 27.0])  # the calibration posture in that cube
SPREAD = np.radians(20.0)  # joints drawn within +-20 deg of it
SEED_OFF = np.radians(3.0)  # the seed's distance from the true joints, per joint


def best_time(work):
    """Best-of-REPEATS wall time of ``work()``, s."""
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        work()
        times.append(time.perf_counter() - start)
    return min(times)


def optional(module):
    """The imported module, or None when its package is not installed."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return importlib.import_module(module)
    except ImportError:
        return None


def table(title, columns, rows):
    """Print rows (tuples of already formatted cells) under a title and a header."""
    widths = [max(len(str(c)) for c in column) for column in zip(columns, *rows)]
    print(f"\n{title}")
    for row in (columns, *rows):
        print("  ".join(str(cell).rjust(w) if k else str(cell).ljust(w) for k, (cell, w) in enumerate(zip(row, widths))))


# ------------------------------------------------------------------------------------------ IK


def ik_rows(robot, n):
    """One row per solver: name, us/pose, poses/s, ratio, max pos err, max rot err, solved, posture."""
    rng = np.random.default_rng(0)
    q_true = POSTURE + rng.uniform(-SPREAD, SPREAD, (n, 6))
    T = fk(robot, q_true)
    seed = q_true + rng.uniform(-SEED_OFF, SEED_OFF, (n, 6))
    branch = np.array([c.index for c in configuration_of(robot, q_true)])
    solvers = {
        "trajcomp ik, N poses per call": (lambda: ik(robot, T, seed=seed).q, True),
        "trajcomp ik, 1 pose per call": (lambda: np.array([ik(robot, T[k], seed=seed[k]).q[0] for k in range(n)]), True),
    }
    rtb, ur_ik, ik_geo = optional("roboticstoolbox"), optional("ur_analytic_ik"), optional("ik_geo")
    if rtb is not None:
        ets = rtb.models.DH.UR10().ets()  # metres
        metres = T.copy()
        metres[:, :3, 3] /= 1000.0
        # tol bounds E = e^T e / 2 (m, rad): 1e-18 is about 1.4e-6 mm, as trajcomp's 1e-6 mm
        solvers["roboticstoolbox ik_LM (C++, tol 1e-18)"] = (
            lambda: np.array([_rtb_q(ets.ik_LM(metres[k], q0=seed[k], tol=1e-18, ilimit=100, slimit=1))
                              for k in range(n)]), False)
    if ur_ik is not None:
        metres = T.copy()
        metres[:, :3, 3] /= 1000.0
        solvers["ur-analytic-ik, closest of 8"] = (
            lambda: np.array([_first(ur_ik.ur10.inverse_kinematics_closest(metres[k], *seed[k])) for k in range(n)]),
            False)
    if ik_geo is not None:
        bot, R0 = _ik_geo_ur(ik_geo, robot)
        solvers["ik-geo, nearest of all"] = (
            lambda: np.array([_nearest([s for s, _ in bot.get_ik((T[k, :3, :3] @ R0.T).T, T[k, :3, 3])], seed[k])
                              for k in range(n)]), False)
    rows, reference = [], None
    for name, (solve, ours) in solvers.items():
        q = solve()
        seconds = best_time(solve)
        reference = reference or seconds
        solved = np.all(np.isfinite(q), axis=1)
        reached = fk(robot, np.where(solved[:, None], q, 0.0))
        pos = np.linalg.norm(reached[:, :3, 3] - T[:, :3, 3], axis=1)[solved]
        rot = np.degrees(rotation_angle_between(reached[:, :3, :3], T[:, :3, :3]))[solved]
        same = np.array([c.index for c in configuration_of(robot, np.where(solved[:, None], q, 0.0))]) == branch
        rows.append((name, f"{1e6 * seconds / n:.1f}", f"{n / seconds:,.0f}", f"{seconds / reference:.1f}x",
                     f"{pos.max():.1e}", f"{rot.max():.1e}", f"{solved.mean():.1%}", f"{(same & solved).mean():.1%}"))
    for name, module in (("roboticstoolbox-python", rtb), ("ur-analytic-ik", ur_ik), ("ik-geo", ik_geo)):
        if module is None:
            rows.append((f"{name}: not installed", "-", "-", "-", "-", "-", "-", "-"))
    return rows


def _rtb_q(solution):
    return np.asarray(solution.q) if solution.success else np.full(6, np.nan)


def _first(solutions):
    return np.asarray(solutions[0]) if len(solutions) else np.full(6, np.nan)


def _nearest(solutions, seed):
    """The solution nearest the seed, turns taken modulo 360 deg."""
    if not solutions:
        return np.full(6, np.nan)
    q = np.array(solutions)
    return q[np.argmin(np.sum(np.angle(np.exp(1j * (q - seed))) ** 2, axis=1))]


def _ik_geo_ur(ik_geo, robot):
    """ik-geo's UR model from trajcomp's DH frames at zero (axes h, offsets p) and the flange rotation there."""
    frames = link_frames(robot, np.zeros((1, 6)))[0]
    origins, axes = frames[:, :3, 3], frames[:, :3, 2]
    flange = fk(robot, np.zeros(6))
    p = np.vstack([origins[0], np.diff(origins[:6], axis=0), flange[:3, 3] - origins[5]])
    return ik_geo.Robot.three_parallel_two_intersecting(axes[:6], p), flange[:3, :3]


# ------------------------------------------------------------------------ cell, interpolation


def virtual_cell():
    """The virtual UR10, its 216 measurements on the cube, the composite model and validation data."""
    robot = load_robot("ur10")
    virtual = VirtualRobot.create(robot, "paper", seed=1)
    plan = plan_grid(robot, *CUBE, one_posture=False)  # as the demo plans it
    measured = virtual.measure(plan.joints, np.random.default_rng(11))
    meas = Measurements(joints=plan.joints, position=plan.position, measured=measured,
                        lines=np.arange(len(plan.joints)) + 2, path="grid")
    model = calibrate(robot, meas, method="composite", grid_step=CUBE[2], folds=0)
    rng = np.random.default_rng(5)
    targets = np.tile(fk(robot, plan.joints[:1]), (2000, 1, 1))
    targets[:, :3, 3] = np.asarray(CUBE[0]) + rng.uniform(0.0, CUBE[1], (2000, 3))
    q = ik(robot, targets, seed=POSTURE).q
    truth = virtual.reached_poses(q)[:, :3, 3]  # noise-free: where the arm lands for commanded q
    return robot, meas, model, q, targets[:, :3, 3], truth


def interpolation_rows(model, meas, q, commanded, truth):
    """One row per interpolator: name, build s, us/point, ratio, mean and max |error| at validation points."""
    grid = model.residual
    axes = [grid.lattice.origin[a] + grid.lattice.step[a] * np.arange(grid.lattice.shape[a]) for a in range(3)]
    predicted = fk(model.identified, meas.joints)[:, :3, 3]
    residuals = meas.measured - predicted  # what the grid was built from
    wanted = truth - fk(model.identified, q)[:, :3, 3]  # the residual the field should predict
    queries = np.random.default_rng(7).uniform(grid.lattice.origin, grid.lattice.upper, (100_000, 3))
    builders = {
        "trajcomp idw8 (the paper's)": lambda: lambda p: grid.evaluate(p, method="idw8"),
        "trajcomp trilinear": lambda: lambda p: grid.evaluate(p, method="trilinear"),
        "scipy RegularGridInterpolator linear": lambda: RegularGridInterpolator(axes, grid.values, method="linear"),
        "scipy RegularGridInterpolator cubic": lambda: RegularGridInterpolator(axes, grid.values, method="cubic"),
        "trajcomp rbf (smoothing by 5-fold CV)": lambda: (lambda f: lambda p: f.evaluate(p))(
            RBF.fit(meas.position, residuals)),
        "scipy RBFInterpolator (thin plate, raw mm)": lambda: RBFInterpolator(meas.position, residuals),
    }
    rows, reference = [], None
    for name, build in builders.items():
        build_seconds = best_time(build)
        field = build()
        seconds = best_time(lambda: field(queries))
        reference = reference or seconds
        error = np.linalg.norm(field(commanded) - wanted, axis=1)
        rows.append((name, f"{build_seconds:.3f}", f"{1e6 * seconds / len(queries):.2f}",
                     f"{seconds / reference:.2f}x", f"{error.mean():.4f}", f"{error.max():.4f}"))
    return rows


# ------------------------------------------------------------------------------ identification


def identification_rows(robot, meas, q, commanded, truth):
    """trajcomp's fit and a plain finite-difference least_squares: name, s, ratio, evaluations, accuracy."""
    names = [f"{p}{i + 1}" for i in range(6) for p in ("a", "alpha", "d", "theta")] + ["tool_x", "tool_y", "tool_z"]
    evaluations = {"n": 0}

    def residual(x):
        evaluations["n"] += 1
        return (fk(apply_deltas(robot, names, x), meas.joints)[:, :3, 3] - meas.measured).ravel()

    fits = {
        "trajcomp identify (analytic Jacobian, QR, huber)": lambda: identify(robot, meas.joints, meas.measured).robot,
        "scipy least_squares, 27 parameters, 2-point FD": lambda: apply_deltas(
            robot, names, least_squares(residual, np.zeros(len(names)), method="trf").x),
    }
    rows, reference = [], None
    for name, fit in fits.items():
        evaluations["n"] = 0
        identified = fit()
        calls = evaluations["n"]
        seconds = best_time(fit)
        reference = reference or seconds
        error = np.linalg.norm(fk(identified, q)[:, :3, 3] - truth, axis=1)
        fit_rms = np.sqrt(np.mean(np.sum((fk(identified, meas.joints)[:, :3, 3] - meas.measured) ** 2, axis=1)))
        rows.append((name, f"{seconds:.3f}", f"{seconds / reference:.1f}x", str(calls or "-"),
                     f"{fit_rms:.4f}", f"{error.mean():.4f}"))
    return rows


def main(n):
    robot, meas, model, q, commanded, truth = virtual_cell()
    table(f"IK, UR10, {n} poses near the calibration posture, seeds 3 deg off (ratio: time / trajcomp batch)",
          ("solver", "us/pose", "poses/s", "ratio", "max pos mm", "max rot deg", "solved", "posture"),
          ik_rows(robot, n))
    table("Residual interpolation, 6x6x6 grid of the virtual UR10 (ratio: time / trajcomp idw8; error vs the "
          "noise-free residual at 2000 points, mm)",
          ("interpolator", "build s", "us/point", "ratio", "mean |err|", "max |err|"),
          interpolation_rows(model, meas, q, commanded, truth))
    table("DH identification, 216 measurements of the virtual UR10 (ratio: time / trajcomp; accuracy: mean landing "
          "error of the DH model at 2000 validation points, mm)",
          ("fit", "s", "ratio", "FD evals", "fit rms mm", "mean |err|"),
          identification_rows(robot, meas, q, commanded, truth))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2000)
