"""``trajcomp plan``: a grid of reachable TCP targets for a measurement run."""

import argparse

from trajcomp.commands._args import add_robot, command_parser, info, numbers, positive_int, positive_number, robot_of
from trajcomp.errors import ToleranceError

DEFAULT_ORIENTATIONS = 5  # the default plan's orientations: the given one, then tilted about +-x, +-y of the tool
DEFAULT_TILT = 30.0  # deg, the tilt of the spread orientations


def orientation_list(text):
    """An argparse type: ``auto``, a count of orientations to spread (``5``) or a list ``A,B,C;A,B,C`` (deg)."""
    if text == "auto":
        return text
    if ";" not in text and "," not in text:
        try:
            count = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected auto, a count or A,B,C;A,B,C;... (deg), got {text!r}") from None
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
        "exit code 1. With --update MODEL --candidates CSV: the rows to measure in a later campaign for "
        "`trajcomp recalibrate` instead.",
        "trajcomp plan --robot ur10 --cube 300,-100,300 --side 400 --step 100 --orientations 5 -o plan.csv",
    )
    add_robot(parser, required=False)
    parser.add_argument("--cube", type=numbers(3), metavar="X,Y,Z", help="lowest corner, mm (a grid: required)")
    parser.add_argument("--side", type=positive_number, help="edge length, mm (a grid: required)")
    parser.add_argument("--step", type=positive_number, help="grid step, mm (a grid: required)")
    parser.add_argument("--update", metavar="MODEL",
                        help="instead of a grid, choose from --candidates the --count configurations to measure for "
                        "`trajcomp recalibrate` in a later campaign of this model: representative of the candidates "
                        "(nearest the centres of clusters of their positions) where they identify the update, else "
                        "D-optimal (the least volume of the update's parameter covariance)")
    parser.add_argument("--candidates", metavar="CSV",
                        help="with --update: configurations the arm may take in the cell (a plan or measurement CSV "
                        "with commanded joints or poses, e.g. the first campaign's plan)")
    parser.add_argument("--count", type=positive_int, default=30, help="with --update: configurations to choose "
                        "(default 30)")
    parser.add_argument("--only", metavar="GROUP[,GROUP]", help="with --update: the groups to update, as "
                        "`trajcomp recalibrate --only` (default all)")
    parser.add_argument("--frame", choices=("base", "tracker"), default="tracker",
                        help="with --update: the frame the campaign will measure in (default tracker: placed anew)")
    parser.add_argument("--poses", action="store_true",
                        help="with --update: the tracker will measure orientations too (6-DoF)")
    parser.add_argument("--orientation", type=numbers(3), metavar="A,B,C",
                        help="TCP orientation, deg (default: that of the robot's home configuration)")
    parser.add_argument("--orientations", type=orientation_list, default="auto", metavar="auto|N|A,B,C;A,B,C;...",
                        help="tool orientations: a count spread around --orientation by --tilt (5: the orientation, "
                        "then tilted about +x, +y, -x, -y of the tool), or a list, deg. Default auto: "
                        f"{DEFAULT_ORIENTATIONS} spread, where a tilted target is unreachable it is left out (listed, "
                        "exit 0); a model from them serves tilted targets and other tools. 1: the paper's one "
                        "orientation (a model for that orientation and TCP only)")
    parser.add_argument("--tilt", type=positive_number, default=DEFAULT_TILT,
                        help=f"tilt of the spread orientations, deg (default {DEFAULT_TILT:g})")
    parser.add_argument("-o", "--output", required=True, help="plan CSV to write")
    parser.set_defaults(run=run)


def run(args):
    from trajcomp.errors import TrajcompError

    if args.update:
        if not args.candidates:
            raise TrajcompError("--update needs --candidates: the configurations the arm may take in the cell")
        return run_update(args)
    missing = [f"--{name}" for name in ("robot", "cube", "side", "step") if getattr(args, name) is None]
    if missing:
        raise TrajcompError(f"a grid plan needs {', '.join(missing)}")
    return run_grid(args)


def run_update(args):
    """``plan --update``: the candidates that best observe the update (`trajcomp.calibration.recalibrate.choose_rows`)."""
    from trajcomp.calibration.calibrate import commanded
    from trajcomp.calibration.measurements import Measurements, read_measurements, write_measurements
    from trajcomp.calibration.recalibrate import GROUPS, choose_rows, parameter_names
    from trajcomp.commands.recalibrate import groups_of
    from trajcomp.errors import CalibrationError
    from trajcomp.model.model_file import load_model, model_files
    from trajcomp.support.atomic import refuse_inputs

    refuse_inputs([args.output], [*model_files(args.update), args.candidates])
    model = load_model(args.update)
    if "composite" not in model.modes:
        raise CalibrationError(f"{args.update}: an update needs a model with mode composite")
    candidates = read_measurements(args.candidates)
    joints, _ = commanded(model.nominal, candidates)
    if joints is None:
        raise CalibrationError(f"{args.candidates}: candidates need commanded joints j1..j6 or full poses x..c")
    groups = groups_of(args.only) or GROUPS
    chosen, how = choose_rows(model, joints, args.count, groups, tracker=args.frame == "tracker", oriented=args.poses)
    names = parameter_names(groups, tracker=args.frame == "tracker", oriented=args.poses)
    outside = int(model.arm("composite").outside_rows(joints[chosen]).sum())
    comments = [f"trajcomp plan --update {args.update}: {len(chosen)} of {len(joints)} candidates of "
                f"{args.candidates} ({how}), observing {', '.join(names)}"]
    picked = candidates.subset(chosen)
    write_measurements(args.output, Measurements(joints=joints[chosen], position=picked.position,
                                                 orientation=picked.orientation, lines=picked.lines),
                       comments=comments)
    info(f"{args.output}: {len(chosen)} of {len(joints)} candidate configurations ({how}), observing "
         f"{', '.join(names)}" + (f"; {outside} lie outside the joint range the model was calibrated on"
                                  if outside else ""))
    return 0


def run_grid(args):
    import numpy as np

    from trajcomp.arm.ik import Configuration
    from trajcomp.calibration.measurement_plan import default_orientation, plan_grid
    from trajcomp.calibration.measurements import Measurements, write_measurements
    from trajcomp.calibration.orientations import spread_orientations
    from trajcomp.support.atomic import refuse_inputs

    refuse_inputs([args.output], [args.robot])
    robot = robot_of(args)
    orientation = default_orientation(robot) if args.orientation is None else np.radians(args.orientation)
    auto = args.orientations == "auto"
    if not isinstance(args.orientations, np.ndarray):
        count = DEFAULT_ORIENTATIONS if auto else args.orientations
        orientations = spread_orientations(orientation, count, np.radians(args.tilt))
    else:
        orientations = args.orientations
    plan = plan_grid(robot, args.cube, args.side, args.step, orientations)
    ok = plan.reachable
    # the default's tilted targets are extra measurements: one the arm cannot reach is left out, not a failure
    left_out = ~ok & (np.arange(len(ok)) % len(orientations) > 0) if auto else np.zeros(len(ok), dtype=bool)
    lost = [
        f"unreachable target {x:.3f},{y:.3f},{z:.3f} at {a:.2f},{b:.2f},{c:.2f} deg: {reason}"
        + (" (a tilted target of the default plan: left out)" if tilted else "")
        for (x, y, z), (a, b, c), reason, tilted in zip(plan.position[~ok], np.degrees(plan.orientation[~ok]),
                                                        plan.reason[~ok], left_out[~ok])
    ]
    meas = Measurements(joints=plan.joints[ok], position=plan.position[ok], orientation=plan.orientation[ok],
                        lines=np.flatnonzero(ok))
    write_measurements(args.output, meas, comments=[f"trajcomp plan for robot {robot.name}"] + lost)
    postures = ", ".join(str(Configuration.from_index(b)) for b in dict.fromkeys(plan.posture.tolist()) if b >= 0)
    info(f"{args.output}: {ok.sum()} of {len(ok)} targets reachable, {len(orientations)} orientation(s)"
         + (f" (the default: tilted {args.tilt:g} deg about two axes of the tool; --orientations 1 plans one)"
            if auto else "") + (f", arm posture {postures}" if postures else ""))
    for line in describe_needs(robot, plan, orientations):
        info(line)
    for line in sorted(lost, key=lambda line: line.endswith("left out)"))[:10]:  # the failing ones first
        info(line)
    failed = int((~ok & ~left_out).sum())
    if left_out.any():
        info(f"{int(left_out.sum())} tilted targets the arm cannot reach are left out (listed in {args.output})")
    if failed:
        raise ToleranceError(f"{failed} of {len(ok)} targets are unreachable (listed in {args.output})")
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
                     "(the default, five orientations, tilts it about two axes)")
    return lines
