"""``trajcomp validate``: a model's accuracy on measurements, per mode, with a verdict."""

import dataclasses

from trajcomp.commands._args import add_layout, command_parser, info, layout_of
from trajcomp.commands._report import add_report_options, criteria_of, emit
from trajcomp.commands.calibrate import print_stats
from trajcomp.errors import ReadError


def add_parser(sub):
    parser = command_parser(
        sub, "validate",
        "Print the statistics of |measured - predicted| per mode (none, linear, dh, grid, "
        "composite) on a measurement CSV, e.g. a second run of validation points, and of the "
        "orientation error for 6-DoF data. Tracker-frame data go through the model's "
        "registration (same tracker placement) or through --register reference rows measured "
        "in a new placement. Exit 1 when the 95th percentile |error| of the model's mode exceeds "
        "--tolerance (the verdict of the report).",
        "trajcomp validate model.yaml validation.csv --tolerance 0.05 --json validation.json",
    )
    parser.add_argument("model", help="model file from `trajcomp calibrate`")
    parser.add_argument("measurements", help="measurement CSV with mx, my, mz")
    add_tracker_options(parser)
    parser.add_argument("--json", metavar="PATH",
                        help="write the statistics and verdict as JSON (trajcomp-report/1); - (or /dev/stdout): "
                        "to stdout, which then holds nothing else (the table goes to stderr)")
    add_report_options(parser, verdict="accuracy")
    parser.set_defaults(run=run)


def add_tracker_options(parser):
    """Layout, ``--frame`` and ``--register`` options shared with predict."""
    add_layout(parser)
    parser.add_argument("--frame", choices=("base", "tracker"),
                        help="frame of the measured columns (default: as the layout file says, else base)")
    parser.add_argument("--register", metavar="CSV",
                        help="reference rows (same layout) measured in a new tracker placement: register the "
                        "tracker from them instead of using the model's registration")


def tracker_pose(args, model, frame):
    """T_tracker_base (4, 4) for the data: identity (base frame), the model's, or registered from --register."""
    import numpy as np

    from trajcomp.calibration.calibrate import commanded, register, to_base
    from trajcomp.calibration.measurements import read_measurements

    if frame != "tracker":
        if args.register:
            raise ReadError("--register needs tracker-frame data (--frame tracker or a layout with frame: tracker)")
        return np.eye(4)
    if not args.register:
        return model.T_tracker_base
    reference = read_measurements(args.register, layout_of(args))
    reference.require_measured()
    joints, position = commanded(model.nominal, reference)
    T_tracker_base = register(model, joints, position, reference.measured)
    residual = np.linalg.norm(to_base(T_tracker_base, reference.measured)
                              - model.predict(model.method, joints, position, outside="clamp")[0], axis=1)
    info(f"registered the tracker on {len(reference)} reference rows of {args.register}: "
         f"mean |residual| {residual.mean():.4f} mm")
    return T_tracker_base


def check_data(model, meas, T_tracker_base, frame):
    """Refuse data the model cannot apply to (another robot, wrong units, a duplicated column): `check_applied`."""
    import numpy as np

    from trajcomp.calibration.calibrate import commanded, to_base
    from trajcomp.calibration.plausibility import check_applied

    _, position = commanded(model.nominal, meas)
    error = None if meas.measured is None else np.linalg.norm(to_base(T_tracker_base, meas.measured) - position, axis=1)
    check_applied(meas, model.nominal, position, error, registered=frame == "tracker")


def orientation_lines(model, meas, T_tracker_base):
    """Orientation |error| lines of 6-DoF data for the kinematic modes (empty without measured orientations)."""
    import numpy as np

    from trajcomp.arm.transforms import abc_to_matrix, invert, rotation_angle_between
    from trajcomp.calibration.calibrate import commanded

    joints, _ = commanded(model.nominal, meas)
    if meas.measured_orientation is None or joints is None:
        return []
    seen = invert(T_tracker_base)[:3, :3] @ abc_to_matrix(meas.measured_orientation)
    lines = []
    for mode in ("dh", "composite"):
        if mode in model.modes:
            predicted = model.arm(mode, outside="clamp").fk(joints)[:, :3, :3] @ model.R_tcp_target
            angle = np.degrees(rotation_angle_between(predicted, seen))
            lines.append(f"{mode} orientation |error|: mean {angle.mean():.4f}  max {angle.max():.4f} deg")
    return lines


STDOUT = ("-", "/dev/stdout")  # --json names of the standard output


def run(args):
    import sys

    from trajcomp.calibration.measurements import read_measurements
    from trajcomp.model.model_file import load_model, model_files
    from trajcomp.report import file_entry, report_paths, validation_report
    from trajcomp.support.atomic import refuse_inputs, write_atomic

    json_out = None if args.json in STDOUT else args.json
    inputs = [*model_files(args.model), args.measurements, args.register, args.columns_file]
    refuse_inputs(filter(None, [json_out, *(report_paths(args.report) if args.report else ())]), inputs)
    model = load_model(args.model)
    meas = read_measurements(args.measurements, layout_of(args))
    meas.require_measured()
    frame = args.frame or meas.frame or "base"
    T_tracker_base = tracker_pose(args, model, frame)
    check_data(model, meas, T_tracker_base, frame)
    placed = dataclasses.replace(model, T_tracker_base=T_tracker_base)  # the data's registration
    files = [file_entry("model", args.model), file_entry("measurements", args.measurements)]
    options = {"columns": None if args.columns is None else dict(args.columns.columns),
               "columns_file": args.columns_file, "frame": frame, "register": args.register,
               "tolerance_mm": args.tolerance}
    report = validation_report(placed, meas, criteria=criteria_of(args), files=files, options=options)
    table = sys.stderr if args.json in STDOUT else sys.stdout  # a JSON on stdout is all stdout holds
    if not (args.json_only and not args.report):
        print_stats(f"{args.measurements}: {len(meas)} points, {frame} frame (|measured - predicted|, mm)",
                    report.doc["modes"], file=table)
        for line in orientation_lines(placed, meas, T_tracker_base):
            print(line, file=table)
    if json_out:
        write_atomic(json_out, report.json_text())
    elif args.json:
        sys.stdout.write(report.json_text())
    json_only = args.json_only and not (args.json in STDOUT and not args.report)  # the JSON is on stdout once
    return emit(report, args.report, json_only, protect=inputs,
                written_before=[json_out] if json_out else ())
