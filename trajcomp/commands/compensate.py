"""``trajcomp compensate``: correct robot programs with a compensation model, one file or a batch.

The options become a `trajcomp.jobs.pipeline.CompensationJob`; one
file runs it here, a batch in workers (`trajcomp.jobs.batch`).
"""

import dataclasses
import math
import sys
from pathlib import Path

from trajcomp.commands._args import command_parser, info, language_names, languages, positive_number
from trajcomp.commands._report import add_report_options, criteria_of
from trajcomp.commands.convert import add_frame_options, add_in_place_option, frame_options
from trajcomp.commands.retime import METHOD_HELP, add_tolerance_option
from trajcomp.compensation.options import JOINT_TARGETS, MAX_CORRECTION, MAX_JOINT_CHANGE, OUTSIDE, RETIME_CHOICES
from trajcomp.errors import RobotError, TrajcompError
from trajcomp.model.options import MODES
from trajcomp.support.parallel import usable_cores


def add_parser(sub):
    parser = command_parser(
        sub, "compensate",
        "Read a program, replace every Cartesian target by the command that makes the real arm land on "
        "it, in the posture the program declares (configuration data, turns, qnear, joints; else the "
        "previous target's), recompute configuration data from the corrected joints and write the program "
        f"in the same format. Languages: {languages()}. A target that cannot keep its "
        "posture, or whose correction is implausibly large, stops the run (exit 2) and nothing is written. "
        "Every run ends with a verdict against stated criteria (residual within --tolerance, targets inside "
        "the grid, posture kept, joint limit and singularity margins, every motion compensated); a failing "
        "verdict exits 1 with the program written and the report saying why.",
        "trajcomp compensate examples/ur10_path.csv --model model.yaml --mode composite -o ur10_path.compensated.csv",
        "trajcomp compensate 'examples/*.csv' --model model.yaml -o corrected/ --jobs 2 --report corrected/reports",
    )
    parser.add_argument("program", nargs="+",
                        help="program file; several files, folders or glob patterns run as a batch")
    parser.add_argument("--model", required=True, help="model file from `trajcomp calibrate`")
    parser.add_argument("--robot", help="the arm the program runs on (built-in name or robot YAML file): refused "
                        "unless it is the model's robot")
    parser.add_argument("--mode", choices=MODES, help="compensation mode (default: the model's method)")
    parser.add_argument("--outside", choices=OUTSIDE, default="model",
                        help="targets outside the grid: model only (flagged; default), nearest grid value, or an error")
    add_frame_options(parser)
    parser.add_argument("--joint-targets", choices=JOINT_TARGETS, default="keep",
                        help="joint-space targets: keep them (default) or compensate the pose they stand for")
    parser.add_argument("--max-joint-change", type=positive_number, default=math.degrees(MAX_JOINT_CHANGE), metavar="DEG",
                        help="largest joint change a correction may cause before the target counts as leaving "
                        "its posture (default %(default)g deg)")
    parser.add_argument("--max-correction", type=positive_number, default=MAX_CORRECTION, metavar="MM",
                        help="largest plausible position correction (default %(default)g mm)")
    parser.add_argument("--retime", choices=RETIME_CHOICES, default="auto",
                        help=f"re-time the corrected program under the robot's limits ({METHOD_HELP}); none: keep "
                        "the program's speeds (default %(default)s)")
    add_tolerance_option(parser)
    add_in_place_option(parser)
    parser.add_argument("--measured", metavar="CSV",
                        help="a validation run of the compensated program: a measurement CSV with the joints as "
                        "written (j1..j6) and the measured TCP (mx,my,mz, base frame unless its layout says tracker); "
                        "the report shows each target's measured landing beside its estimate and fails a measured "
                        "landing above the tolerance (one program)")
    parser.add_argument("-o", "--output", required=True,
                        help="corrected program to write, in the input's language (an extension of another is "
                        "refused without --to); for a batch, the folder to write into")
    parser.add_argument("--to", dest="to_format", metavar="FORMAT",
                        help=f"write the corrected program in this language instead ({language_names()} or a plugin's), as "
                        "`trajcomp convert` would")
    parser.add_argument("--jobs", type=int, default=usable_cores(), metavar="N",
                        help="processes to use: a batch compensates N files at once, one program shares its "
                        "targets among N (default: the %(default)s cores this machine gives)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="batch: run on a Dask distributed cluster (scheduler address, or 'local' "
                        "for a local cluster of --jobs workers)")
    parser.add_argument("--summary", metavar="PATH",
                        help="batch: summary JSON to write (default OUTDIR/summary.json)")
    add_report_options(parser)
    parser.set_defaults(run=run)


def run(args):
    from trajcomp.arm.robot import load_robot
    from trajcomp.calibration.measurements import read_validation_run
    from trajcomp.jobs import batch
    from trajcomp.jobs.options import check_options
    from trajcomp.jobs.pipeline import CompensationJob, loaded_model

    check_options(flags=True, jobs=args.jobs)
    tools, frames = frame_options(args)
    job = CompensationJob(
        model=str(Path(args.model).resolve()), mode=args.mode, outside=args.outside, tools=tools, frames=frames,
        joint_targets=args.joint_targets, max_joint_change=math.radians(args.max_joint_change),
        max_correction=args.max_correction, in_place=args.in_place, criteria=criteria_of(args),
        report=args.report, json_only=args.json_only, retime=args.retime, path_tolerance=args.path_tolerance,
        to_format=args.to_format,
        measured=None if args.measured is None else read_validation_run(args.measured),
    )
    model = loaded_model(job.model)  # a broken model fails the run once, before any file
    if args.robot is not None and load_robot(args.robot).name != model.nominal.name:
        raise RobotError(f"--robot {args.robot}: the model {args.model} is for robot {model.nominal.name}")
    first = args.program[0]
    single = len(args.program) == 1 and not Path(first).is_dir() and not batch.is_pattern(first) \
        and not Path(args.output).is_dir()
    if single:
        run = dataclasses.replace(job, show_stages=True, workers=args.jobs).run(Path(first), Path(args.output))
        result = run.result
        if args.json_only and not args.report:
            sys.stdout.write(run.compliance.json_text())
        for line in result.lines:
            info(line)
        if result.message:
            info(f"trajcomp: {result.message}")
        return batch.EXIT_CODES[result.status]
    if args.json_only and not args.report:
        raise TrajcompError("--json-only: a batch writes one report per program; give --report FOLDER")
    if args.measured:
        raise TrajcompError("--measured: a validation run belongs to one program; give one program file")
    return _run_batch(args, dataclasses.replace(job, report_folder=True, output_root=args.output))


def _run_batch(args, job):
    from trajcomp.jobs import batch
    from trajcomp.model.model_file import model_files

    results, summary = batch.run_programs(
        job, args.program, args.output, to_format=args.to_format, in_place=args.in_place,
        models=model_files(args.model), report=args.report, summary=args.summary, jobs=args.jobs,
        scheduler=args.scheduler, show_progress=True, model=args.model, mode=args.mode or "model default")
    for result in results:
        info(batch.result_line(result))
    counts = {s: sum(r.status == s for r in results) for s in batch.EXIT_CODES}
    info(f"{len(results)} programs: " + ", ".join(f"{n} {s}" for s, n in counts.items() if n) + f"; summary {summary}")
    return batch.exit_code(results)
