"""``trajcomp plan``: a grid of reachable TCP targets for a measurement run."""

import argparse

from trajcomp.commands._args import add_robot, command_parser, info, numbers, positive_number, robot_of
from trajcomp.errors import ToleranceError


def orientation_list(text):
    """An argparse type: a count of orientations to spread (``5``) or a list ``A,B,C;A,B,C`` (deg)."""
    if ";" not in text and "," not in text:
        try:
            count = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a count or A,B,C;A,B,C;... (deg), got {text!r}") from None
        if not 1 <= count <= 50:
            raise argparse.ArgumentTypeError(f"expected 1 to 50 orientations, got {count}")
        return count
    import numpy as np

    return np.radians(np.array([numbers(3)(item) for item in text.split(";") if item.strip()]))


def add_parser(sub):
    parser = command_parser(
        sub, "plan",
        "Plan a cubic grid of TCP targets, at one tool orientation or several, and solve them "
        "with the nominal kinematics in one arm posture per orientation (that nearest the home pose "
        "at the grid's centre). Writes the measurement CSV layout without measured columns "
        "(each node at every orientation in turn) and says from how many orientations on the "
        "identification has all the parameters it can have. Unreachable targets (out of reach, or "
        "reached only in another posture) are listed on stderr and as comments in the file, and make the "
        "exit code 1.",
        "trajcomp plan --robot ur10 --cube 300,-100,300 --side 400 --step 100 --orientations 5 -o plan.csv",
    )
    add_robot(parser)
    parser.add_argument("--cube", type=numbers(3), required=True, metavar="X,Y,Z", help="lowest corner, mm")
    parser.add_argument("--side", type=positive_number, required=True, help="edge length, mm")
    parser.add_argument("--step", type=positive_number, required=True, help="grid step, mm")
    parser.add_argument("--orientation", type=numbers(3), metavar="A,B,C",
                        help="TCP orientation, deg (default: that of the robot's home configuration)")
    parser.add_argument("--orientations", type=orientation_list, default=1, metavar="N|A,B,C;A,B,C;...",
                        help="several tool orientations: a count spread around --orientation by --tilt (5: the "
                        "orientation, then tilted about +x, +y, -x, -y of the tool), or a list, deg (default 1)")
    parser.add_argument("--tilt", type=positive_number, default=30.0, help="tilt of the spread orientations, deg (default 30)")
    parser.add_argument("-o", "--output", required=True, help="plan CSV to write")
    parser.set_defaults(run=run)


def run(args):
    import numpy as np

    from trajcomp.arm.ik import Configuration
    from trajcomp.calibration.measurement_plan import default_orientation, plan_grid
    from trajcomp.calibration.measurements import Measurements, write_measurements
    from trajcomp.calibration.orientations import spread_orientations
    from trajcomp.support.atomic import refuse_inputs

    refuse_inputs([args.output], [args.robot])
    robot = robot_of(args)
    orientation = default_orientation(robot) if args.orientation is None else np.radians(args.orientation)
    if isinstance(args.orientations, int):
        orientations = spread_orientations(orientation, args.orientations, np.radians(args.tilt))
    else:
        orientations = args.orientations
    plan = plan_grid(robot, args.cube, args.side, args.step, orientations)
    ok = plan.reachable
    lost = [
        f"unreachable target {x:.3f},{y:.3f},{z:.3f} at {a:.2f},{b:.2f},{c:.2f} deg: {reason}"
        for (x, y, z), (a, b, c), reason in zip(plan.position[~ok], np.degrees(plan.orientation[~ok]), plan.reason[~ok])
    ]
    meas = Measurements(joints=plan.joints[ok], position=plan.position[ok], orientation=plan.orientation[ok],
                        lines=np.flatnonzero(ok))
    write_measurements(args.output, meas, comments=[f"trajcomp plan for robot {robot.name}"] + lost)
    postures = ", ".join(str(Configuration.from_index(b)) for b in dict.fromkeys(plan.posture.tolist()) if b >= 0)
    info(f"{args.output}: {ok.sum()} of {len(ok)} targets reachable, {len(orientations)} orientation(s)"
         + (f", arm posture {postures}" if postures else ""))
    for line in describe_needs(robot, plan, orientations):
        info(line)
    for line in lost[:10]:
        info(line)
    if lost:
        raise ToleranceError(f"{len(lost)} of {len(ok)} targets are unreachable (listed in {args.output})")
    return 0


def describe_needs(robot, plan, orientations):
    """Lines saying how many orientations the identification needs (tracker positions, joint errors included)."""
    from trajcomp.arm.transforms import abc_to_matrix
    from trajcomp.calibration.measurement_plan import orientations_needed
    from trajcomp.calibration.orientations import locates_flange, orientation_spread

    if not plan.reachable.any():
        return []
    counts, candidates = orientations_needed(robot, plan)
    best = max(kept for _, kept in counts)
    needed = min(k for k, kept in counts if kept == best)
    spread = orientation_spread(abc_to_matrix(orientations))
    lines = [
        "identifiable from tracker positions (DH, TCP, registration, joint errors; of "
        f"{candidates}): " + ", ".join(f"{k} orientation{'s' * (k > 1)}: {kept}" for k, kept in counts),
        f"the identification needs {needed} of these orientations for its {best} parameters",
    ]
    if not locates_flange(spread):
        lines.append(f"the tool turns {spread[0]:.1f} and {spread[1]:.1f} deg RMS about its two main axes: too little "
                     "to locate the flange; a model from this plan serves the measured TCP and orientation only "
                     "(--orientations 5 tilts it about two axes)")
    return lines
