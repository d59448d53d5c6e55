"""``trajcomp calibrate``: identify a compensation model from measurements."""

from trajcomp.calibration.options import CALIBRATION_METHODS, INTERPOLATIONS, LOSSES, ORIENTATION_WEIGHT
from trajcomp.commands._args import (
    add_layout,
    add_robot,
    command_parser,
    info,
    layout_of,
    non_negative_int,
    pose,
    positive_number,
    progress,
    robot_of,
    steps,
)
from trajcomp.commands._report import add_report_options, criteria_of, emit
from trajcomp.errors import TrajcompError
from trajcomp.support.parallel import usable_cores


def add_parser(sub):
    parser = command_parser(
        sub, "calibrate",
        "Identify a compensation model from measurements: the paper's linear correction, the "
        "arm's kinematics with the TCP and (tracker frame) the base registration in one robust "
        "least-squares fit with identifiability analysis, and the residual: a grid over positions "
        "for data at one tool orientation, joint-angle errors for data at several orientations. "
        "Implausible data (wrong units, another robot) is refused. Prints fit and k-fold "
        "cross-validation statistics (mean, RMS, p95, max of |error|) per mode.",
        "trajcomp calibrate measurements.csv --robot ur10 --method composite --grid-step 100 -o model.yaml",
    )
    parser.add_argument("measurements", help="measurement CSV")
    add_robot(parser)
    parser.add_argument("--tool", type=pose, metavar="x,y,z,a,b,c",
                        help="nominal TCP of the measured point in the flange frame, mm and deg (default: the robot's)")
    parser.add_argument("--method", choices=CALIBRATION_METHODS, default="composite",
                        help="default mode of the model (default composite)")
    parser.add_argument("--grid-step", type=steps, metavar="STEP[,STEP,STEP]",
                        help="expected grid step, mm, or one per axis x,y,z (checked against the data)")
    parser.add_argument("--interpolation", choices=INTERPOLATIONS, default="auto",
                        help="composite residual: auto (joint for data at several orientations, else idw8), joint "
                        "(joint-angle errors), or a field over positions: idw8 (the paper's), trilinear, knn, rbf")
    parser.add_argument("--frame", choices=("base", "tracker"),
                        help="frame of the measured columns (tracker: identify the base registration too; "
                        "default: as the layout file says, else base)")
    parser.add_argument("--loss", choices=LOSSES, default="huber", help="robust loss of the fit (default huber)")
    parser.add_argument("--orientation-weight", type=positive_number, default=ORIENTATION_WEIGHT, metavar="MM_PER_RAD",
                        help=f"weight of measured orientation against position, mm per rad (default {ORIENTATION_WEIGHT:g}: "
                        "1 mrad counts as 0.1 mm)")
    parser.add_argument("--folds", type=non_negative_int, default=5, help="k of the k-fold cross-validation (default 5; 0: none)")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the fold split (default 0)")
    parser.add_argument("--jobs", type=int, default=usable_cores(), metavar="N",
                        help="at most this many processes compute the spline selection and the cross-validation's "
                        "folds, helpers started on idle cores only (default: the %(default)s cores this machine "
                        "gives); the model does not depend on it")
    add_layout(parser)
    parser.add_argument("-o", "--output", required=True, help="model file to write (.yaml)")
    add_report_options(parser, verdict="accuracy")
    parser.set_defaults(run=run)


def print_stats(title, stats, file=None):
    """Print a table of per-mode statistics dicts (as in a model report) to ``file`` (default stdout)."""
    from trajcomp.model.stats import ErrorStats, format_table

    rows = {mode: ErrorStats(**{**s, "signed_mean": tuple(s["signed_mean"]), "std": tuple(s["std"])})
            for mode, s in stats.items() if isinstance(s, dict)}
    print(title, file=file)
    print(format_table(rows), file=file)


def describe(model, combinations=None):
    """Lines on what was identified: parameters (``combinations``: `trajcomp.report.calibration.
    identifiable_combinations`, those the data see only together), TCP, registration, other tools."""
    import numpy as np

    from trajcomp.arm.parameters import is_angle
    from trajcomp.arm.transforms import matrix_to_pose
    from trajcomp.calibration.calibrate import selection_words
    from trajcomp.report.calibration import combination_text

    lines = []
    if model.dh_names:
        hidden = {c["name"] for c in combinations or ()} | set(model.dh_fixed)  # no delta read as the arm's
        own = [(n, np.degrees(d) if is_angle(n) else d, " deg" if is_angle(n) else "")
               for n, d in zip(model.dh_names, model.dh_delta) if n not in hidden or combinations is None]
        lines.append(f"identified {len(model.dh_names)} parameters"
                     + (f", {len(own)} on their own" if combinations else "") + ": "
                     + ", ".join(f"{n} {d:+.4f}{unit}" for n, d, unit in own))
        if combinations:
            lines.append("identified in combination: " + ", ".join(
                f"{combination_text(c)} = {c['value']:+.4f}{' deg' if c['unit'] == 'deg' else ''}"
                for c in combinations))
        lines.append(f"not identified on their own: {', '.join(f'{n} ({r})' for n, r in model.dh_fixed.items()) or 'none'}")
        tcp = model.identified.T_flange_tool[:3, 3]
        lines.append(f"TCP in the flange frame: {tcp[0]:.3f}, {tcp[1]:.3f}, {tcp[2]:.3f} mm")
    if not np.allclose(model.T_tracker_base, np.eye(4)):
        base = matrix_to_pose(model.T_tracker_base)
        lines.append("base in the tracker frame: " + ", ".join(f"{v:.3f}" for v in base[:3])
                     + " mm, " + ", ".join(f"{v:.4f}" for v in np.degrees(base[3:])) + " deg")
    choice = model.report.get("joint_splines")
    if choice and choice.get("candidates"):
        lines.append(f"composite residual chosen on {choice['regions']}: " + selection_words(choice))
    lines.append(f"other tools: {'yes' if model.places_other_tools else 'no'}: {model.other_tools_reason}")
    return lines


def run(args):
    import numpy as np

    from trajcomp.arm.transforms import matrix_to_pose
    from trajcomp.calibration.calibrate import MAX_ROWS, calibrate, too_many_rows
    from trajcomp.calibration.measurements import read_measurements
    from trajcomp.calibration.track_fit import arm_rows, with_identified_track
    from trajcomp.errors import CalibrationError
    from trajcomp.model.model_file import model_files, save_model
    from trajcomp.report import calibration_report, file_entry, report_paths
    from trajcomp.report.calibration import parameter_combinations
    from trajcomp.support.atomic import refuse_inputs
    from trajcomp.support.memory import keep_freed_blocks

    if args.jobs < 1:
        raise TrajcompError(f"--jobs: expected a whole number of at least 1, got {args.jobs}")
    keep_freed_blocks()  # the fits free and make arrays of a few MB thousands of times
    robot = robot_of(args)
    if args.tool is not None:
        robot = robot.replace(T_flange_tool=args.tool)
    inputs = [args.measurements, args.columns_file, args.robot]
    refuse_inputs([*model_files(args.output), *(report_paths(args.report) if args.report else ())], inputs)
    meas = read_measurements(args.measurements, layout_of(args), max_rows=MAX_ROWS, why=too_many_rows())
    try:
        model = calibrate(
            robot, meas.subset(arm_rows(meas, robot)), robot_ref=args.robot, method=args.method, frame=args.frame,
            grid_step=args.grid_step,
            interpolation=args.interpolation, loss=args.loss, folds=args.folds, seed=args.seed, progress=progress,
            orientation_weight=args.orientation_weight, workers=args.jobs,
        )
    except CalibrationError as exc:  # what the data cannot give names the file ("2 measurements are too few...")
        if str(args.measurements) in str(exc):
            raise
        raise CalibrationError(f"{args.measurements}: {exc}") from None
    if meas.track is not None:  # a robot on a track: every row places the track
        model, fit = with_identified_track(model, meas)
        info(f"track: direction {np.round(fit.track.actual_direction, 6).tolist()} "
             f"({fit.direction_change_deg:.4f} deg from the description), scale {fit.track.actual_scale:.6f}, "
             f"{fit.residual_rms:.4f} mm RMS about the line, measured at {len(fit.positions)} positions "
             f"{fit.positions[0]:g}..{fit.positions[-1]:g} mm")
        if fit.straightness_rms is not None:
            kept = "kept as a table" if fit.track.straightness is not None else "within the noise: not kept"
            info(f"track straightness: {fit.straightness_rms:.4f} mm RMS at the {len(fit.positions)} positions "
                 f"(noise {fit.noise_rms:.4f} mm): {kept}")
    save_model(args.output, model)
    report = model.report
    for line in describe(model, parameter_combinations(model, meas)):
        info(line)
    if not (args.json_only and not args.report):
        print_stats(f"fit on {report['measurements']['used']} measurements, residual {report['residual']} "
                    "(|error|, mm):", report["fit"])
        if "cross_validation" in report:
            print_stats(f"{report['cross_validation']['folds']}-fold cross-validation (|error|, mm):",
                        report["cross_validation"])
    info(f"wrote {args.output}")
    if args.report or args.json_only:
        files = [file_entry("measurements", args.measurements), file_entry("model", args.output)]
        options = {k: v for k, v in vars(args).items() if k in ("robot", "method", "interpolation", "frame", "loss",
                                                                 "folds", "seed", "orientation_weight", "columns_file")}
        options["grid_step"] = None if args.grid_step is None else np.atleast_1d(args.grid_step).tolist()
        options["columns"] = None if args.columns is None else dict(args.columns.columns)
        options["tool"] = None if args.tool is None else [float(v) for v in matrix_to_pose(args.tool)]
        report = calibration_report(model, meas, criteria=criteria_of(args), files=files, options=options)
        return emit(report, args.report, args.json_only, protect=[*inputs, *model_files(args.output)],
                    written_before=[args.output])
    return 0
