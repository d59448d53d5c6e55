"""``trajcomp simulate``: measure a plan on the virtual robot."""

import dataclasses

import numpy as np

from trajcomp.commands._args import add_robot, command_parser, info, robot_of
from trajcomp.calibrate import commanded
from trajcomp.errors import ReadError
from trajcomp.kinematics import fk
from trajcomp.measurements import read_measurements, write_measurements
from trajcomp.simulate import PROFILES, VirtualRobot


def add_parser(sub):
    parser = command_parser(
        sub, "simulate", "measure a plan on the virtual robot",
        "Run a plan (measurement CSV with j1..j6 or x..c) on the virtual robot and write "
        "the measurement CSV with the measured TCP positions mx, my, mz added. The "
        "virtual robot's errors are drawn from --seed; each --run draws new noise.",
        "trajcomp simulate plan.csv --robot ur10 --profile paper --seed 1 -o measurements.csv",
        "trajcomp simulate plan.csv --robot ur10 --profile paper --seed 1 --run 1 -o validation.csv",
    )
    parser.add_argument("plan", help="plan CSV (from `trajcomp plan`)")
    add_robot(parser)
    parser.add_argument("--profile", choices=sorted(PROFILES), default="paper", help="error profile (default paper)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the virtual robot's errors (default 0)")
    parser.add_argument("--run", dest="run_index", type=int, default=0, help="measurement run number: seeds the noise (default 0)")
    parser.add_argument("-o", "--output", required=True, help="measurement CSV to write")
    parser.set_defaults(run=run)



def run(args):
    robot = robot_of(args)
    meas = read_measurements(args.plan)
    virtual = VirtualRobot.create(robot, args.profile, args.seed)
    q, _ = commanded(robot, meas)
    if q is None:
        raise ReadError(f"{args.plan}: simulate needs commanded joints j1..j6 or full poses x,y,z,a,b,c")
    rng = np.random.default_rng([args.seed, args.run_index])
    measured = virtual.measure(q, rng)
    out = dataclasses.replace(meas, joints=q, measured=measured)
    write_measurements(
        args.output, out,
        comments=[f"virtual {robot.name}, profile {args.profile}, seed {args.seed}, run {args.run_index}"],
    )
    error = np.linalg.norm(measured - fk(robot, q)[:, :3, 3], axis=1)
    info(f"{args.output}: {len(meas)} measurements, mean |error| {error.mean():.3f} mm, max {error.max():.3f} mm")
    return 0
