"""``trajcomp validate``: a model's accuracy on measurements, per mode."""

from trajcomp.calibrate import commanded, mode_errors, to_base
from trajcomp.commands._args import command_parser
from trajcomp.errors import ToleranceError
from trajcomp.measurements import parse_mapping, read_measurements
from trajcomp.model import load_model
from trajcomp.stats import ErrorStats, format_table


def add_parser(sub):
    parser = command_parser(
        sub, "validate", "check a model against measurements",
        "Print the statistics of |measured - predicted| per mode (none, linear, dh, grid, "
        "composite) on a measurement CSV, e.g. a second run of validation points. With "
        "--tolerance, exit 1 when the model's mode exceeds it (mean |error|).",
        "trajcomp validate model.yaml validation.csv --tolerance 0.05",
    )
    parser.add_argument("model", help="model file from `trajcomp calibrate`")
    parser.add_argument("measurements", help="measurement CSV with mx, my, mz")
    parser.add_argument("--columns", type=parse_mapping, metavar="FIELD=EXPR,...", help="column mapping for other layouts")
    parser.add_argument("--tolerance", type=float, help="maximum mean |error| of the model's mode, mm")
    parser.set_defaults(run=run)


def run(args):
    model = load_model(args.model)
    meas = read_measurements(args.measurements, args.columns)
    meas.require_measured()
    joints, position = commanded(model.nominal, meas)
    measured = to_base(model.T_tracker_base, meas.measured)
    stats = {m: ErrorStats.from_errors(e) for m, e in mode_errors(model, joints, position, measured).items()}
    print(f"{args.measurements}: {len(meas)} points (|measured - predicted|, mm)")
    print(format_table(stats))
    achieved = stats[model.method].mean
    if args.tolerance is not None and achieved > args.tolerance:
        raise ToleranceError(f"mode {model.method}: mean |error| {achieved:.4f} mm exceeds the tolerance {args.tolerance} mm")
    return 0
