"""The paper's protocol end to end on the virtual robot.

Large cube (corner 300,-100,300, side 500, step 100: 216 points) and small
cube (corner 500,100,500, side 100, step 10: 1331 points) on the paper's
UR10-class arm, the same cubes scaled to the reach of any other arm
(`demo_cubes`); calibrate on the grid, then send 40 random validation targets
inside each cube, compensated in each mode, and measure where the arm really
lands. The table puts the paper's numbers beside ours.
"""

import dataclasses
import itertools

import numpy as np

from trajcomp import formats
from trajcomp.support.atomic import write_atomic
from trajcomp.calibration.calibrate import calibrate
from trajcomp.compensation.target_correction import compensate
from trajcomp.errors import TrajcompError
from trajcomp.jobs.pipeline import CompensationJob
from trajcomp.arm.ik import batch_seed, ik
from trajcomp.arm.kinematics import shoulder_and_reach
from trajcomp.calibration.measurements import Measurements, read_measurements
from trajcomp.calibration.measurement_plan import default_orientation, plan_grid
from trajcomp.arm.robot import load_robot
from trajcomp.calibration.profiles import PAPER_ROBOT
from trajcomp.calibration.virtual_arm import VirtualRobot
from trajcomp.model.stats import ErrorStats
from trajcomp.arm.transforms import abc_to_matrix

# Mean signed error per axis (mm) over 40 random points, from the paper.
PAPER = {
    ("large", "none"): (-0.4349, 1.424, -2.064),
    ("large", "idw8"): (-0.2361, -0.2389, -0.1054),
    ("small", "none"): (-0.3831, 1.462, -2.061),
    ("small", "idw8"): (-0.1466, -0.1353, -0.04813),
    ("small", "composite"): (-0.002851, -0.008719, -0.007675),
}


@dataclasses.dataclass(frozen=True)
class Cube:
    """An axis-aligned calibration cube and its grid.

    Attributes
    ----------
    name : str
    corner : tuple of float, (3,)
        Lowest corner, mm, base frame.
    side, step : float
        Edge length and grid step, mm (side = a whole number of steps).
    """

    name: str
    corner: tuple
    side: float
    step: float

    def __post_init__(self):
        object.__setattr__(self, "corner", tuple(float(v) for v in self.corner))

    def __str__(self):
        points = (round(self.side / self.step) + 1) ** 3
        corner = ",".join(f"{v:g}" for v in self.corner)
        return f"{self.name} cube: corner {corner}, side {self.side:g}, step {self.step:g} mm ({points} points)"


PAPER_CUBES = (Cube("large", (300.0, -100.0, 300.0), 500.0, 100.0), Cube("small", (500.0, 100.0, 500.0), 100.0, 10.0))
# Placements tried around the scaled paper cubes: shifts of up to two large
# steps per axis, nearest first.
_SHIFTS = sorted(itertools.product(range(-2, 3), repeat=3), key=lambda s: (np.dot(s, s), s))

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

    cube: Cube
    points: int
    stats: dict
    model: object


def with_interpolation(model, interpolation):
    """The model with both grids evaluated by another interpolator."""
    swap = lambda field: None if field is None else dataclasses.replace(field, method=interpolation)  # noqa: E731
    return dataclasses.replace(model, grid=swap(model.grid), residual=swap(model.residual))


def demo_cubes(robot):
    """The paper's two cubes, scaled to the arm's reach and placed where it reaches every vertex.

    The paper's cubes are given for its UR10; for another arm they are
    scaled about the shoulder (origin of the joint-2 axis) by the ratio of
    the arms' reaches (`shoulder_and_reach`), the large step rounded to
    10 mm and the small one to 1 mm. When a grid vertex is out of reach in
    that place, both cubes move together by whole large steps (up to two
    per axis, nearest placement first). The UR10 gets the paper's cubes,
    each vertex solved nearest the grid's seed (`plan_grid` with
    ``one_posture=False``): seven corner vertices of the large cube are
    reached only in another arm posture than the rest, which `trajcomp plan`
    refuses, so the demo's large-cube grid mixes two postures.

    Returns
    -------
    tuple of Cube
        The large and the small cube.

    Raises
    ------
    TrajcompError
        No tried placement has every vertex of both grids reachable.
    """
    paper_shoulder, paper_reach = shoulder_and_reach(load_robot(PAPER_ROBOT))
    shoulder, reach = shoulder_and_reach(robot)
    scale = reach / paper_reach
    scaled = []
    for cube, unit in zip(PAPER_CUBES, (10.0, 1.0)):
        step = max(unit, unit * round(cube.step * scale / unit))
        corner = 10.0 * np.round((shoulder + scale * (np.asarray(cube.corner) - paper_shoulder)) / 10.0)
        scaled.append(Cube(cube.name, corner, step * round(cube.side / cube.step), step))
    for shift in _SHIFTS:
        offset = scaled[0].step * np.asarray(shift)
        cubes = tuple(dataclasses.replace(c, corner=np.add(c.corner, offset)) for c in scaled)
        if all(plan_grid(robot, c.corner, c.side, c.step, one_posture=False).reachable.all() for c in cubes):
            return cubes
    raise TrajcompError(
        f"demo: robot {robot.name}: no placement of the paper's cubes scaled to its reach ({reach:.0f} mm, "
        f"{scaled[0]}) has every grid vertex reachable"
    )


def run_cube(virtual, cube, *, validation=40, seed=0, robot_ref=None):
    """Calibrate on one cube's grid and validate compensation at random targets.

    ``robot_ref``: how the model names its robot (a built-in name or a robot YAML file's path, as the user gave
    it; default the robot's name).
    """
    robot = virtual.nominal
    rng = np.random.default_rng([seed, len(cube.name)])
    plan = plan_grid(robot, cube.corner, cube.side, cube.step, one_posture=False)
    q = plan.joints[plan.reachable]
    meas = Measurements(joints=q, position=plan.position[plan.reachable], measured=virtual.measure(q, rng),
                        lines=np.arange(len(q)) + 1, path=f"<virtual {cube.name} cube>")
    model = calibrate(robot, meas, robot_ref=robot_ref or robot.name, method="composite", grid_step=cube.step,
                      folds=5)
    targets = np.tile(np.eye(4), (validation, 1, 1))
    targets[:, :3, :3] = abc_to_matrix(default_orientation(robot))
    targets[:, :3, 3] = np.asarray(cube.corner) + rng.uniform(0.0, cube.side, (validation, 3))
    stats = {}
    for label, (mode, interpolation) in ROWS.items():
        used = model if interpolation is None else with_interpolation(model, interpolation)
        result = compensate(used, targets, mode=mode)
        reached = virtual.reached_poses(result.q, rng)[:, :3, 3]
        measured = reached + rng.normal(0.0, virtual.profile.tracker_sigma, reached.shape)
        stats[label] = ErrorStats.from_errors(measured - targets[:, :3, 3])
    return CubeResult(cube, len(q), stats, model)


def format_comparison(results, noise_sigma):
    """The paper's signed means beside ours, with our |error| norms."""
    lines = [
        f"{'cube':6s} {'mode':10s} {'mean|e|':>8s} {'rms':>8s} {'max':>8s}   "
        f"{'ours dx':>8s} {'dy':>8s} {'dz':>8s}   {'paper dx':>9s} {'dy':>8s} {'dz':>8s}   (mm)"
    ]
    for result in results:
        for label, s in result.stats.items():
            paper = PAPER.get((result.cube.name, label))
            theirs = "".join(f"{v:>9.4f}" for v in paper) if paper else f"{'-':>9s}{'-':>9s}{'-':>9s}"
            lines.append(
                f"{result.cube.name:6s} {label:10s} {s.mean:8.4f} {s.rms:8.4f} {s.max:8.4f}   "
                + "".join(f"{v:8.4f} " for v in s.signed_mean) + "  " + theirs
            )
    floor = noise_sigma * np.sqrt(8.0 / np.pi)
    lines.append(f"noise floor of one measured point (mean |noise|): {floor:.4f} mm")
    return "\n".join(lines)


def write_example_program(path, robot, cube, waypoints=8, seed=0):
    """A program CSV of LIN moves through random targets inside a Cube (user units)."""
    rng = np.random.default_rng(seed)
    abc = np.degrees(default_orientation(robot))
    rows = ["x,y,z,a,b,c,motion,speed,zone"]
    for k, p in enumerate(np.asarray(cube.corner) + rng.uniform(0.1 * cube.side, 0.9 * cube.side, (waypoints, 3))):
        motion, speed, zone = ("PTP", "", "") if k == 0 else ("LIN", "250", "1")
        rows.append(",".join(f"{v:.3f}" for v in (*p, *abc)) + f",{motion},{speed},{zone}")
    write_atomic(path, "\n".join(rows) + "\n")


def run_program(virtual, result, folder):
    """Compensate an example program inside a cube with its model; run both versions on the virtual arm.

    Writes ``program.csv`` and ``program-compensated.csv`` into ``folder``.

    Parameters
    ----------
    virtual : VirtualRobot
    result : CubeResult
        The cube the program's targets are drawn in and the model that corrects them.
    folder : pathlib.Path

    Returns
    -------
    dict
        ``{"as planned": ErrorStats, "compensated": ErrorStats}`` of the
        landing error at the program's targets.
    """
    robot = virtual.nominal
    original, corrected_path = folder / "program.csv", folder / "program-compensated.csv"
    write_example_program(original, robot, result.cube)
    CompensationJob(result.model, retime="none").run(original, corrected_path)  # as ``trajcomp compensate`` does
    program = formats.read(original)
    targets = program.cartesian_targets().T  # CSV targets: base frame, robot tool
    planned = ik(robot, targets, seed=batch_seed(robot, targets)).raise_on_failure(str(original)).q
    landed = {
        "as planned": virtual.reached_poses(planned)[:, :3, 3],
        "compensated": virtual.reached_poses(read_measurements(corrected_path).joints)[:, :3, 3],
    }
    return {label: ErrorStats.from_errors(p - targets[:, :3, 3]) for label, p in landed.items()}


def run_demo(robot, profile="paper", seed=1, progress=None, robot_ref=None):
    """Both cubes of the paper's protocol (`demo_cubes`) on a virtual copy of ``robot``.

    ``robot_ref``: how the models name the robot (`run_cube`): a robot YAML file's path, so that
    ``compensate --robot FILE.yaml --model ..`` finds the same arm.

    Returns
    -------
    virtual : VirtualRobot
    results : list of CubeResult
        The large cube's, then the small cube's.
    """
    virtual = VirtualRobot.create(robot, profile, seed)
    results = []
    for cube in demo_cubes(robot):
        if progress:
            progress(f"{cube}: plan, measure, calibrate, validate")
        results.append(run_cube(virtual, cube, seed=seed, robot_ref=robot_ref))
    return virtual, results
