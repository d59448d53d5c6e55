"""``trajcomp compensate``: correct a robot program with a compensation model."""

from trajcomp import formats
from trajcomp.commands._args import command_parser, info
from trajcomp.commands.convert import add_frame_options, frame_options
from trajcomp.compensate import program_corrector
from trajcomp.model import MODES, load_model
from trajcomp.postprocess import compensate_program


def add_parser(sub):
    parser = command_parser(
        sub, "compensate", "correct a program with a model",
        "Read a program (CSV, KUKA KRL, ABB RAPID, FANUC LS, URScript; see `trajcomp formats`), "
        "replace every Cartesian target by the command that makes the real arm land on it, "
        "recompute configuration data from the corrected joints and write the program in "
        "the same format. Run-time position expressions are listed, not changed.",
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
    parser.add_argument("-o", "--output", required=True, help="corrected program to write")
    parser.set_defaults(run=run)


def run(args):
    model = load_model(args.model)
    program = formats.read(args.program)
    correct = program_corrector(model, mode=args.mode, outside=args.outside, label=args.program)
    tools, frames = frame_options(args)
    corrected, report = compensate_program(
        program, correct, model.nominal, tools=tools, frames=frames, joint_targets=args.joint_targets,
    )
    formats.write(args.output, corrected)
    for line in report.lines():
        info(line)
    outside = getattr(correct, "outside", None)
    if outside is not None and outside.any():
        info(f"{int(outside.sum())} targets lie outside the compensation grid: {args.outside} policy applied")
    info(f"wrote {args.output}")
    return 0
