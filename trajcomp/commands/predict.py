"""``trajcomp predict``: where the real arm ends for each commanded row."""

import dataclasses

from trajcomp.commands._args import command_parser, info, layout_of
from trajcomp.commands.validate import add_tracker_options, check_data, tracker_pose
from trajcomp.model.options import MODES


def add_parser(sub):
    parser = command_parser(
        sub, "predict",
        "For each commanded row of a measurement CSV, predict the reached TCP position "
        "(columns px, py, pz added) with a mode of the model: in the base frame, or with "
        "--frame tracker in the tracker frame (the model's registration, or --register rows "
        "measured in a new tracker placement).",
        "trajcomp predict model.yaml plan.csv --mode composite -o predicted.csv",
    )
    parser.add_argument("model", help="model file from `trajcomp calibrate`")
    parser.add_argument("measurements", help="measurement or plan CSV")
    parser.add_argument("--mode", choices=MODES, help="prediction mode (default: the model's method)")
    add_tracker_options(parser)
    parser.add_argument("-o", "--output", required=True, help="CSV to write")
    parser.set_defaults(run=run)


def run(args):
    from trajcomp.calibration.calibrate import commanded
    from trajcomp.calibration.measurements import read_measurements, write_measurements
    from trajcomp.model.model_file import load_model, model_files
    from trajcomp.support.atomic import refuse_inputs

    refuse_inputs([args.output], [*model_files(args.model), args.measurements, args.register, args.columns_file])
    model = load_model(args.model)
    meas = read_measurements(args.measurements, layout_of(args))
    frame = args.frame or meas.frame or "base"
    joints, position = commanded(model.nominal, meas)
    mode = args.mode or model.method
    model.check_mode(mode)
    T_tracker_base = tracker_pose(args, model, frame)
    check_data(model, meas, T_tracker_base, frame)
    predicted, flagged = model.predict(mode, joints, position)
    predicted = predicted @ T_tracker_base[:3, :3].T + T_tracker_base[:3, 3]
    extra = {"px": predicted[:, 0], "py": predicted[:, 1], "pz": predicted[:, 2], "outside_grid": flagged}
    write_measurements(args.output, dataclasses.replace(meas, joints=joints, position=position),
                       comments=[f"predicted by {args.model}, mode {mode}, {frame} frame"], extra=extra)
    if flagged.any():
        info(f"{int(flagged.sum())} rows lie outside the grid: model-only prediction (outside_grid = 1)")
    info(f"wrote {args.output}: {len(meas)} predictions, mode {mode}, {frame} frame")
    return 0
