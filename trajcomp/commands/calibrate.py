"""``trajcomp calibrate``: identify a compensation model from measurements."""

from trajcomp.calibrate import METHODS, calibrate
from trajcomp.commands._args import add_robot, command_parser, info, progress, robot_of
from trajcomp.commands._report import add_report_options, emit
from trajcomp.measurements import parse_mapping, read_measurements
from trajcomp.model import save_model
from trajcomp.stats import ErrorStats, format_table


def add_parser(sub):
    parser = command_parser(
        sub, "calibrate", "identify a compensation model",
        "Identify a compensation model from a measurement CSV: the paper's linear "
        "correction, the DH parameters (least squares, with identifiability analysis) "
        "and the residual grid. Prints fit and k-fold cross-validation statistics "
        "(mean, RMS, p95, max of |error|) per mode.",
        "trajcomp calibrate measurements.csv --robot ur10 --method composite --grid-step 100 -o model.yaml",
    )
    parser.add_argument("measurements", help="measurement CSV")
    add_robot(parser)
    parser.add_argument("--method", choices=METHODS, default="composite", help="default mode of the model (default composite)")
    parser.add_argument("--grid-step", type=float, help="expected grid step, mm (checked against the data)")
    parser.add_argument("--interpolation", default="idw8",
                        help="grid interpolator: idw8 (the paper's), trilinear, knn, rbf (default idw8)")
    parser.add_argument("--frame", choices=("base", "tracker"), default="base",
                        help="frame of the measured columns (tracker: estimate the base registration)")
    parser.add_argument("--loss", choices=("linear", "soft_l1", "huber", "cauchy"), default="linear",
                        help="robust loss of the DH fit (default linear)")
    parser.add_argument("--folds", type=int, default=5, help="k of the k-fold cross-validation (default 5; 0: none)")
    parser.add_argument("--columns", type=parse_mapping, metavar="FIELD=EXPR,...",
                        help="column mapping for other layouts, e.g. j1=joint_1,mx=x_t+x_dif")
    parser.add_argument("-o", "--output", required=True, help="model file to write (.yaml)")
    add_report_options(parser, verdict=None)
    parser.set_defaults(run=run)


def print_stats(title, stats):
    """Print a table of per-mode statistics dicts (as in a model report)."""
    rows = {mode: ErrorStats(**{**s, "signed_mean": tuple(s["signed_mean"]), "std": tuple(s["std"])})
            for mode, s in stats.items() if isinstance(s, dict)}
    print(title)
    print(format_table(rows))


def run(args):
    robot = robot_of(args)
    meas = read_measurements(args.measurements, args.columns)
    model = calibrate(
        robot, meas, robot_ref=args.robot, method=args.method, frame=args.frame,
        grid_step=args.grid_step, interpolation=args.interpolation, loss=args.loss,
        folds=args.folds, progress=progress,
    )
    save_model(args.output, model)
    report = model.report
    if model.dh_names:
        info(f"identified {len(model.dh_names)} parameters; left at nominal: {', '.join(model.dh_fixed) or 'none'}")
    if not (args.json_only and not args.report):
        print_stats(f"fit on {report['measurements']['used']} measurements (|error|, mm):", report["fit"])
        if "cross_validation" in report:
            print_stats(f"{report['cross_validation']['folds']}-fold cross-validation (|error|, mm):",
                        report["cross_validation"])
    info(f"wrote {args.output}")
    if args.report or args.json_only:
        from trajcomp.report import calibration_report, file_entry

        files = [file_entry("measurements", args.measurements), file_entry("model", args.output)]
        options = {k: v for k, v in vars(args).items() if k in ("robot", "method", "grid_step", "interpolation",
                                                                 "frame", "loss", "folds", "columns")}
        return emit(calibration_report(model, meas, files=files, options=options), args.report, args.json_only)
    return 0
