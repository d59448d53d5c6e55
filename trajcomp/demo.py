"""The paper's protocol end to end on the virtual robot.

Large cube (corner 300,-100,300, side 500, step 100: 216 points) and small
cube (corner 500,100,500, side 100, step 10: 1331 points) on a UR10-class
virtual arm; calibrate on the grid, then send 40 random validation targets
inside each cube, compensated in each mode, and measure where the arm really
lands. The table puts the paper's numbers beside ours.
"""

import dataclasses

import numpy as np

from trajcomp import formats
from trajcomp.atomic import write_atomic
from trajcomp.calibrate import calibrate
from trajcomp.compensate import compensate, program_corrector
from trajcomp.ik import ik
from trajcomp.measurements import Measurements, read_measurements
from trajcomp.postprocess import compensate_program
from trajcomp.plan import batch_seed, default_orientation, plan_grid
from trajcomp.simulate import VirtualRobot
from trajcomp.stats import ErrorStats
from trajcomp.transforms import abc_to_matrix

# Mean signed error per axis (mm) over 40 random points, from the paper.
PAPER = {
    ("large", "none"): (-0.4349, 1.424, -2.064),
    ("large", "idw8"): (-0.2361, -0.2389, -0.1054),
    ("small", "none"): (-0.3831, 1.462, -2.061),
    ("small", "idw8"): (-0.1466, -0.1353, -0.04813),
    ("small", "composite"): (-0.002851, -0.008719, -0.007675),
}

CUBES = {"large": ((300.0, -100.0, 300.0), 500.0, 100.0), "small": ((500.0, 100.0, 500.0), 100.0, 10.0)}

# Row label -> (model mode, grid interpolation)
ROWS = {
    "none": ("none", None),
    "linear": ("linear", None),
    "dh": ("dh", None),
    "idw8": ("grid", "idw8"),
    "trilinear": ("grid", "trilinear"),
    "composite": ("composite", "idw8"),
}


@dataclasses.dataclass(frozen=True)
class CubeResult:
    """Validation statistics of one cube: ``{row label: ErrorStats}`` and the calibration model."""

    name: str
    points: int
    stats: dict
    model: object


def with_interpolation(model, interpolation):
    """The model with both grids evaluated by another interpolator."""
    swap = lambda field: None if field is None else dataclasses.replace(field, method=interpolation)  # noqa: E731
    return dataclasses.replace(model, grid=swap(model.grid), residual=swap(model.residual))


def run_cube(virtual, name, corner, side, step, *, validation=40, seed=0):
    """Calibrate on one cube's grid and validate compensation at random targets."""
    robot = virtual.nominal
    rng = np.random.default_rng([seed, len(name)])
    plan = plan_grid(robot, corner, side, step)
    q = plan.joints[plan.reachable]
    meas = Measurements(joints=q, position=plan.position[plan.reachable], measured=virtual.measure(q, rng),
                        lines=np.arange(len(q)) + 1, path=f"<virtual {name} cube>")
    model = calibrate(robot, meas, robot_ref=robot.name, method="composite", grid_step=step, folds=0)
    targets = np.tile(np.eye(4), (validation, 1, 1))
    targets[:, :3, :3] = abc_to_matrix(default_orientation(robot))
    targets[:, :3, 3] = np.asarray(corner) + rng.uniform(0.0, side, (validation, 3))
    stats = {}
    for label, (mode, interpolation) in ROWS.items():
        used = model if interpolation is None else with_interpolation(model, interpolation)
        result = compensate(used, targets, mode=mode)
        reached = virtual.reached_poses(result.q, rng)[:, :3, 3]
        measured = reached + rng.normal(0.0, virtual.profile.tracker_sigma, reached.shape)
        stats[label] = ErrorStats.from_errors(measured - targets[:, :3, 3])
    return CubeResult(name, len(q), stats, model)


def format_comparison(results, noise_sigma):
    """The paper's signed means beside ours, with our |error| norms."""
    lines = [
        f"{'cube':6s} {'mode':10s} {'mean|e|':>8s} {'rms':>8s} {'max':>8s}   "
        f"{'ours dx':>8s} {'dy':>8s} {'dz':>8s}   {'paper dx':>9s} {'dy':>8s} {'dz':>8s}   (mm)"
    ]
    for result in results:
        for label, s in result.stats.items():
            paper = PAPER.get((result.name, label))
            theirs = "".join(f"{v:>9.4f}" for v in paper) if paper else f"{'-':>9s}{'-':>9s}{'-':>9s}"
            lines.append(
                f"{result.name:6s} {label:10s} {s.mean:8.4f} {s.rms:8.4f} {s.max:8.4f}   "
                + "".join(f"{v:8.4f} " for v in s.signed_mean) + "  " + theirs
            )
    floor = noise_sigma * np.sqrt(8.0 / np.pi)
    lines.append(f"noise floor of one measured point (mean |noise|): {floor:.4f} mm")
    return "\n".join(lines)


def write_example_program(path, robot, corner, side, waypoints=8, seed=0):
    """A program CSV of LIN moves through random targets inside a cube (user units)."""
    rng = np.random.default_rng(seed)
    abc = np.degrees(default_orientation(robot))
    rows = ["x,y,z,a,b,c,motion,speed,zone"]
    for k, p in enumerate(np.asarray(corner) + rng.uniform(0.1 * side, 0.9 * side, (waypoints, 3))):
        motion, speed, zone = ("PTP", "", "") if k == 0 else ("LIN", "250", "1")
        rows.append(",".join(f"{v:.3f}" for v in (*p, *abc)) + f",{motion},{speed},{zone}")
    write_atomic(path, "\n".join(rows) + "\n")


def run_program(virtual, model, folder, corner, side):
    """Compensate an example program with ``model`` and run both versions on the virtual arm.

    Writes ``program.csv`` and ``program-compensated.csv`` into ``folder``.

    Returns
    -------
    dict
        ``{"as planned": ErrorStats, "compensated": ErrorStats}`` of the
        landing error at the program's targets.
    """
    robot = virtual.nominal
    original, corrected_path = folder / "program.csv", folder / "program-compensated.csv"
    write_example_program(original, robot, corner, side)
    program = formats.read(original)
    corrected, _ = compensate_program(program, program_corrector(model, label=str(original)), robot)
    formats.write(corrected_path, corrected)
    targets = program.cartesian_targets().T  # CSV targets: base frame, robot tool
    planned = ik(robot, targets, seed=batch_seed(robot, targets)).raise_on_failure(str(original)).q
    landed = {
        "as planned": virtual.reached_poses(planned)[:, :3, 3],
        "compensated": virtual.reached_poses(read_measurements(corrected_path).joints)[:, :3, 3],
    }
    return {label: ErrorStats.from_errors(p - targets[:, :3, 3]) for label, p in landed.items()}


def run_demo(robot, profile="paper", seed=1, progress=None):
    """Both cubes of the paper's protocol; returns the list of CubeResult."""
    virtual = VirtualRobot.create(robot, profile, seed)
    results = []
    for name, (corner, side, step) in CUBES.items():
        if progress:
            progress(f"{name} cube: plan, measure, calibrate, validate")
        results.append(run_cube(virtual, name, corner, side, step, seed=seed))
    return virtual, results
