"""``trajcomp simulate``: measure a plan on the virtual robot."""

import dataclasses

from trajcomp.calibration.profiles import PROFILES
from trajcomp.commands._args import add_robot, command_parser, info, non_negative_int, pose, robot_of
from trajcomp.errors import ReadError


def add_parser(sub):
    parser = command_parser(
        sub, "simulate",
        "Run a plan (measurement CSV with j1..j6 or x..c) on the virtual robot and write "
        "the measurement CSV with the measured TCP positions mx, my, mz added (and with "
        "--six-dof the measured orientation mrx, mry, mrz), in the base frame or, with "
        "--tracker, in the frame of a tracker placed there. The virtual robot's errors are "
        "drawn from --seed; each --run draws new noise.",
        "trajcomp simulate plan.csv --robot ur10 --profile paper --seed 1 -o measurements.csv",
        "trajcomp simulate plan.csv --robot ur10 --profile paper --seed 1 --run 1 -o validation.csv",
    )
    parser.add_argument("plan", help="plan CSV (from `trajcomp plan`)")
    add_robot(parser)
    parser.add_argument("--profile", choices=sorted(PROFILES), default="paper", help="error profile (default paper)")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the virtual robot's errors (default 0)")
    parser.add_argument("--run", dest="run_index", type=non_negative_int, default=0,
                        help="measurement run number: seeds the noise (default 0)")
    parser.add_argument("--tracker", type=pose, metavar="x,y,z,a,b,c",
                        help="measure in the frame of a tracker at this pose: the robot base in the tracker frame, mm, deg")
    parser.add_argument("--six-dof", action="store_true", help="also measure the TCP orientation (mrx, mry, mrz)")
    parser.add_argument("-o", "--output", required=True, help="measurement CSV to write")
    parser.set_defaults(run=run)


def run(args):
    import numpy as np

    from trajcomp.arm.kinematics import fk
    from trajcomp.arm.transforms import matrix_to_abc
    from trajcomp.calibration.calibrate import commanded
    from trajcomp.calibration.measurements import read_measurements, write_measurements
    from trajcomp.calibration.virtual_arm import VirtualRobot
    from trajcomp.support.atomic import refuse_inputs

    refuse_inputs([args.output], [args.plan, args.robot])
    robot = robot_of(args)
    meas = read_measurements(args.plan)
    virtual = VirtualRobot.create(robot, args.profile, args.seed)
    q, _ = commanded(robot, meas)
    if q is None:
        raise ReadError(f"{args.plan}: simulate needs commanded joints j1..j6 or full poses x,y,z,a,b,c")
    rng = np.random.default_rng([args.seed, args.run_index])
    seen = virtual.measure_poses(q, rng)
    error = np.linalg.norm(seen[:, :3, 3] - fk(robot, q)[:, :3, 3], axis=1)
    if args.tracker is not None:
        seen = args.tracker @ seen
    out = dataclasses.replace(meas, joints=q, measured=seen[:, :3, 3],
                              measured_orientation=matrix_to_abc(seen[:, :3, :3]) if args.six_dof else None)
    frame = "tracker" if args.tracker is not None else "base"
    write_measurements(
        args.output, out,
        comments=[f"virtual {robot.name}, profile {args.profile}, seed {args.seed}, run {args.run_index}, "
                  f"measured in the {frame} frame"],
    )
    info(f"{args.output}: {len(meas)} measurements, mean |error| {error.mean():.3f} mm, max {error.max():.3f} mm")
    return 0
