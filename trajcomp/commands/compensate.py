"""``trajcomp compensate``: correct a robot program with a compensation model."""

import numpy as np

from trajcomp import formats
from trajcomp.commands._args import command_parser, info
from trajcomp.commands.convert import add_frame_options, add_in_place_option, frame_options, protected_inputs
from trajcomp.compensate import program_corrector
from trajcomp.model import MODES, load_model
from trajcomp.postprocess import MAX_CORRECTION, compensate_program
from trajcomp.posture import MAX_JOINT_CHANGE


def add_parser(sub):
    parser = command_parser(
        sub, "compensate", "correct a program with a model",
        "Read a program (CSV, KUKA KRL, ABB RAPID, FANUC LS, URScript; see `trajcomp formats`), "
        "replace every Cartesian target by the command that makes the real arm land on it, in the "
        "posture the program declares (configuration data, turns, qnear, joints; else the previous "
        "target's), recompute configuration data from the corrected joints and write the program in "
        "the same format. A target that cannot keep its posture, or whose correction is implausibly "
        "large, stops the run (exit 2) and nothing is written. Motions whose position is computed at "
        "run time are listed and left as written; the run then exits 1.",
        "trajcomp compensate program.csv --model model.yaml --mode composite -o corrected.csv",
    )
    parser.add_argument("program", help="program file")
    parser.add_argument("--model", required=True, help="model file from `trajcomp calibrate`")
    parser.add_argument("--mode", choices=MODES, help="compensation mode (default: the model's method)")
    parser.add_argument("--outside", choices=("model", "clamp", "error"), default="model",
                        help="targets outside the grid: model only (flagged; default), nearest grid value, or an error")
    add_frame_options(parser)
    parser.add_argument("--joint-targets", choices=("keep", "compensate"), default="keep",
                        help="joint-space targets: keep them (default) or compensate the pose they stand for")
    parser.add_argument("--max-joint-change", type=float, default=float(np.degrees(MAX_JOINT_CHANGE)), metavar="DEG",
                        help="largest joint change a correction may cause before the target counts as leaving "
                        "its posture (default %(default)g deg)")
    parser.add_argument("--max-correction", type=float, default=MAX_CORRECTION, metavar="MM",
                        help="largest plausible position correction (default %(default)g mm)")
    add_in_place_option(parser)
    parser.add_argument("-o", "--output", required=True, help="corrected program to write")
    parser.set_defaults(run=run)


def run(args):
    for option, value in (("--max-joint-change", args.max_joint_change), ("--max-correction", args.max_correction)):
        if not (np.isfinite(value) and value > 0):
            raise formats.TrajcompError(f"{option}: expected a positive number, got {value}")
    model = load_model(args.model)
    program = formats.read(args.program)
    correct = program_corrector(model, mode=args.mode, outside=args.outside, label=args.program)
    tools, frames = frame_options(args)
    corrected, report = compensate_program(
        program, correct, model.nominal, tools=tools, frames=frames, joint_targets=args.joint_targets,
        max_joint_change=np.radians(args.max_joint_change), max_correction=args.max_correction,
    )
    formats.write(args.output, corrected, protect=protected_inputs(args, args.program, program))
    for line in report.lines_of_text():
        info(line)
    outside = report.outside_grid
    if outside.any():
        info(f"{int(outside.sum())} targets lie outside the compensation grid: {args.outside} policy applied")
    info(f"wrote {args.output}")
    if report.not_compensated:
        info(f"trajcomp: {len(report.not_compensated)} of {len(program.motions)} motions were not compensated "
             "(positions computed at run time, listed above): the program is written, but not fully corrected")
        return 1
    return 0
