"""``trajcomp predict``: where the real arm ends for each commanded row."""

import dataclasses

from trajcomp.calibrate import commanded
from trajcomp.commands._args import command_parser, info
from trajcomp.measurements import parse_mapping, read_measurements, write_measurements
from trajcomp.model import MODES, load_model


def add_parser(sub):
    parser = command_parser(
        sub, "predict", "predict reached TCP positions",
        "For each commanded row of a measurement CSV, predict the reached TCP position "
        "(columns px, py, pz added) with a mode of the model.",
        "trajcomp predict model.yaml plan.csv --mode composite -o predicted.csv",
    )
    parser.add_argument("model", help="model file from `trajcomp calibrate`")
    parser.add_argument("measurements", help="measurement or plan CSV")
    parser.add_argument("--mode", choices=MODES, help="prediction mode (default: the model's method)")
    parser.add_argument("--columns", type=parse_mapping, metavar="FIELD=EXPR,...", help="column mapping for other layouts")
    parser.add_argument("-o", "--output", required=True, help="CSV to write")
    parser.set_defaults(run=run)


def run(args):
    model = load_model(args.model)
    meas = read_measurements(args.measurements, args.columns)
    joints, position = commanded(model.nominal, meas)
    mode = args.mode or model.method
    predicted, flagged = model.predict(mode, joints, position)
    extra = {"px": predicted[:, 0], "py": predicted[:, 1], "pz": predicted[:, 2], "outside_grid": flagged}
    write_measurements(args.output, dataclasses.replace(meas, joints=joints, position=position),
                       comments=[f"predicted by {args.model}, mode {mode}"], extra=extra)
    if flagged.any():
        info(f"{int(flagged.sum())} rows lie outside the grid: model-only prediction (outside_grid = 1)")
    info(f"wrote {args.output}: {len(meas)} predictions, mode {mode}")
    return 0
