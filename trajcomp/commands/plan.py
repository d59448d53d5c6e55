"""``trajcomp plan``: a grid of reachable TCP targets for a measurement run."""

import numpy as np

from trajcomp.commands._args import add_robot, command_parser, info, numbers, robot_of
from trajcomp.errors import ToleranceError
from trajcomp.measurements import Measurements, write_measurements
from trajcomp.plan import plan_grid


def add_parser(sub):
    parser = command_parser(
        sub, "plan", "plan a cubic measurement grid",
        "Plan a cubic grid of TCP targets and solve them with the nominal kinematics. "
        "Writes the measurement CSV layout without measured columns; unreachable targets "
        "are listed on stderr and as comments in the file, and make the exit code 1.",
        "trajcomp plan --robot ur10 --cube 300,-100,300 --side 500 --step 100 -o plan.csv",
    )
    add_robot(parser)
    parser.add_argument("--cube", type=numbers(3), required=True, metavar="X,Y,Z", help="lowest corner, mm")
    parser.add_argument("--side", type=float, required=True, help="edge length, mm")
    parser.add_argument("--step", type=float, required=True, help="grid step, mm")
    parser.add_argument("--orientation", type=numbers(3), metavar="A,B,C",
                        help="TCP orientation, deg (default: that of the robot's home configuration)")
    parser.add_argument("-o", "--output", required=True, help="plan CSV to write")
    parser.set_defaults(run=run)


def run(args):
    robot = robot_of(args)
    orientation = None if args.orientation is None else np.radians(args.orientation)
    plan = plan_grid(robot, args.cube, args.side, args.step, orientation)
    ok = plan.reachable
    lost = [
        f"unreachable target {x:.3f},{y:.3f},{z:.3f}: {reason}"
        for (x, y, z), reason in zip(plan.position[~ok], plan.reason[~ok])
    ]
    meas = Measurements(
        joints=plan.joints[ok],
        position=plan.position[ok],
        orientation=np.tile(plan.orientation, (int(ok.sum()), 1)),
        lines=np.flatnonzero(ok),
    )
    write_measurements(args.output, meas, comments=[f"trajcomp plan for robot {robot.name}"] + lost)
    info(f"{args.output}: {ok.sum()} of {len(ok)} targets reachable")
    for line in lost[:10]:
        info(line)
    if lost:
        raise ToleranceError(f"{len(lost)} of {len(ok)} targets are unreachable (listed in {args.output})")
    return 0
