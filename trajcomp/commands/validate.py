"""``trajcomp validate``: a model's accuracy on measurements, per mode, with a verdict."""

from trajcomp.atomic import write_atomic
from trajcomp.commands._args import command_parser
from trajcomp.commands._report import add_report_options, criteria_of, emit
from trajcomp.commands.calibrate import print_stats
from trajcomp.measurements import parse_mapping, read_measurements
from trajcomp.model import load_model
from trajcomp.report import file_entry, validation_report


def add_parser(sub):
    parser = command_parser(
        sub, "validate", "check a model against measurements",
        "Print the statistics of |measured - predicted| per mode (none, linear, dh, grid, "
        "composite) on a measurement CSV, e.g. a second run of validation points. Exit 1 when the "
        "95th percentile |error| of the model's mode exceeds --tolerance (the verdict of the report).",
        "trajcomp validate model.yaml validation.csv --tolerance 0.05 --json validation.json",
    )
    parser.add_argument("model", help="model file from `trajcomp calibrate`")
    parser.add_argument("measurements", help="measurement CSV with mx, my, mz")
    parser.add_argument("--columns", type=parse_mapping, metavar="FIELD=EXPR,...", help="column mapping for other layouts")
    parser.add_argument("--json", metavar="PATH", help="write the statistics and verdict as JSON (trajcomp-report/1)")
    add_report_options(parser, verdict="accuracy")
    parser.set_defaults(run=run)


def run(args):
    model = load_model(args.model)
    meas = read_measurements(args.measurements, args.columns)
    meas.require_measured()
    files = [file_entry("model", args.model), file_entry("measurements", args.measurements)]
    report = validation_report(model, meas, criteria=criteria_of(args), files=files,
                               options={"columns": args.columns, "tolerance_mm": args.tolerance})
    if not (args.json_only and not args.report):
        print_stats(f"{args.measurements}: {len(meas)} points (|measured - predicted|, mm)", report.doc["modes"])
    if args.json:
        write_atomic(args.json, report.json_text())
    return emit(report, args.report, args.json_only)
