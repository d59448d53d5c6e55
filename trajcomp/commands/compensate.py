"""``trajcomp compensate``: correct robot programs with a compensation model, one file or a batch."""

import contextlib
import dataclasses
import functools
import importlib
import sys
from pathlib import Path

import numpy as np

from trajcomp import formats
from trajcomp.compensation import batch
from trajcomp.support.atomic import refuse_inputs
from trajcomp.commands._args import command_parser, info, model_inputs, positive_number
from trajcomp.commands._report import add_report_options, criteria_of
from trajcomp.commands.convert import add_frame_options, add_in_place_option, frame_options
from trajcomp.commands.retime import CHOICES as RETIME_CHOICES
from trajcomp.commands.retime import LIMIT_MESSAGE, METHOD_HELP, add_tolerance_option, retime_compensated, timing_lines
from trajcomp.compensation.targets import program_corrector
from trajcomp.errors import RobotError, TrajcompError
from trajcomp.support.memory import end_stage, kept_apart
from trajcomp.model.compensation_model import MODES
from trajcomp.model.model_file import load_model
from trajcomp.support.parallel import meanwhile, usable_cores
from trajcomp.compensation.program import MAX_CORRECTION, compensate_program, convert_program
from trajcomp.compensation.posture import MAX_JOINT_CHANGE
from trajcomp.support.progress import Stages, progress
from trajcomp.report import Criteria, compliance_report, file_entry, model_entry, report_paths, summary_lines
from trajcomp.arm.robot import load_robot
from trajcomp.timing.path import TOLERANCE
from trajcomp.arm.transforms import matrix_to_pose


def add_parser(sub):
    parser = command_parser(
        sub, "compensate", "correct a program with a model",
        "Read a program (CSV, KUKA KRL, ABB RAPID, FANUC LS, URScript; see `trajcomp formats`), "
        "replace every Cartesian target by the command that makes the real arm land on it, in the "
        "posture the program declares (configuration data, turns, qnear, joints; else the previous "
        "target's), recompute configuration data from the corrected joints and write the program in "
        "the same format. A target that cannot keep its posture, or whose correction is implausibly "
        "large, stops the run (exit 2) and nothing is written. Every run ends with a verdict against "
        "stated criteria (residual within --tolerance, targets inside the grid, posture kept, joint "
        "limit and singularity margins, every motion compensated); a failing verdict exits 1 with the "
        "program written and the report saying why.",
        "trajcomp compensate examples/ur10_path.csv --model model.yaml --mode composite -o ur10_path.compensated.csv",
        "trajcomp compensate 'examples/*.csv' --model model.yaml -o corrected/ --jobs 2 --report corrected/reports",
    )
    parser.add_argument("program", nargs="+",
                        help="program file; several files, folders or glob patterns run as a batch")
    parser.add_argument("--model", required=True, help="model file from `trajcomp calibrate`")
    parser.add_argument("--robot", help="the arm the program runs on (built-in name or robot YAML file): refused "
                        "unless it is the model's robot")
    parser.add_argument("--mode", choices=MODES, help="compensation mode (default: the model's method)")
    parser.add_argument("--outside", choices=("model", "clamp", "error"), default="model",
                        help="targets outside the grid: model only (flagged; default), nearest grid value, or an error")
    add_frame_options(parser)
    parser.add_argument("--joint-targets", choices=("keep", "compensate"), default="keep",
                        help="joint-space targets: keep them (default) or compensate the pose they stand for")
    parser.add_argument("--max-joint-change", type=positive_number, default=float(np.degrees(MAX_JOINT_CHANGE)), metavar="DEG",
                        help="largest joint change a correction may cause before the target counts as leaving "
                        "its posture (default %(default)g deg)")
    parser.add_argument("--max-correction", type=positive_number, default=MAX_CORRECTION, metavar="MM",
                        help="largest plausible position correction (default %(default)g mm)")
    parser.add_argument("--retime", choices=RETIME_CHOICES, default="auto",
                        help=f"re-time the corrected program under the robot's limits ({METHOD_HELP}); none: keep "
                        "the program's speeds (default %(default)s)")
    add_tolerance_option(parser)
    add_in_place_option(parser)
    parser.add_argument("-o", "--output", required=True,
                        help="corrected program to write, in the input's language (an extension of another is "
                        "refused without --to); for a batch, the folder to write into")
    parser.add_argument("--to", dest="to_format", metavar="FORMAT",
                        help="write the corrected program in this language instead (see `trajcomp formats`), as "
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


@dataclasses.dataclass(frozen=True)
class CompensateJob:
    """Compensate one program file into one output: the unit of work of a batch (picklable).

    Attributes mirror the command's options; ``tools`` and ``frames`` are
    parsed values (T (4, 4), mm), ``max_joint_change`` is in rad.
    """

    model: str
    mode: str = None
    outside: str = "model"
    tools: dict = dataclasses.field(default_factory=dict)
    frames: dict = dataclasses.field(default_factory=dict)
    joint_targets: str = "keep"
    max_joint_change: float = MAX_JOINT_CHANGE
    max_correction: float = MAX_CORRECTION
    in_place: bool = False
    criteria: Criteria = Criteria()
    report: str = None
    report_folder: bool = False
    json_only: bool = False
    retime: str = "auto"
    path_tolerance: float = TOLERANCE
    to_format: str = None  # another language to write (--to); default the input's
    show_stages: bool = False  # a bar over STAGES on a terminal (one file; a batch shows files instead)
    workers: int = 1  # processes sharing the compensation of one file (a batch spreads files instead)

    STAGES = ("read", "compensate", "re-time", "write", "report")

    def __call__(self, path, output):
        """Compensate ``path`` into ``output``; a `batch.FileResult` (raises TrajcompError on bad input)."""
        return self.run(path, output)[0]

    def run(self, path, output):
        """Compensate ``path`` into ``output``, judge it and write its report: ``(FileResult, Report)``.

        The report goes to ``report`` or, with ``report_folder``, to
        ``report / <output name>`` (``.html`` and ``.json``). No output
        may be an input (the program's files unless ``in_place``, the
        model's); a report that cannot be written once the program is
        makes the file fail (exit 1) with the files written listed, not
        an input error.
        """
        target = None
        if self.report:
            target = Path(self.report) / Path(output).name if self.report_folder else Path(self.report)
        with Stages(self.STAGES, desc=Path(path).name, enabled=self.show_stages) as stages, kept_apart():
            model = _model(self.model)
            program = formats.read(path, workers=self.workers)
            formats.check_robot_language(path, formats.find_format(format=program.format), model.nominal,
                                 f"the arm of the model {self.model}")
            out_format = formats.output_format(output, program, self.to_format)
            formats.check_robot_language(output, out_format, model.nominal, f"the arm of the model {self.model}")
            sources = list(dict.fromkeys(formats.input_paths(path, program)))
            inputs = [*sources, *model_inputs(self.model)]
            refuse_inputs(report_paths(target) if target else (), [*inputs, output], "give --report another name")
            files = [file_entry("program", p) for p in sources]
            correct = program_corrector(model, mode=self.mode, outside=self.outside, label=str(path),
                                        workers=self.workers)
            _next(stages)
            with meanwhile(_import_timing) if self.retime != "none" else contextlib.nullcontext():
                corrected, report = compensate_program(
                    program, correct, model.nominal, tools=self.tools, frames=self.frames,
                    joint_targets=self.joint_targets, max_joint_change=self.max_joint_change,
                    max_correction=self.max_correction, workers=self.workers,
                )
            if out_format.name != program.format:
                corrected = convert_program(corrected, out_format.name, robot=model.nominal, tools=self.tools,
                                            frames=self.frames)
            _next(stages)
            timing, timed, before = [], None, None
            if self.retime != "none":
                corrected, timed, before = retime_compensated(program, corrected, model.nominal, self.retime,
                                                              self.path_tolerance, self.tools, self.frames,
                                                              q_planned=report.q_planned, workers=self.workers)
                timing = timing_lines(timed, before)
            _next(stages)
            protect = inputs[len(sources):] if self.in_place else inputs
            written = formats.write(output, corrected, out_format.name, protect=protect, workers=self.workers)
            _next(stages)
            mode = self.mode or model.method
            compliance = compliance_report(
                report, model.nominal, criteria=self.criteria, model=model,
                model_info=_model_info(self.model, mode), mode=mode,
                files=files + [file_entry("output", p) for p in written], options=self.options(),
                timing=timed, cycle_time_before=before if timed is not None else None, workers=self.workers,
            )
            reports, unwritten = [], ""
            if target:
                try:
                    reports = compliance.write(target, json_only=self.json_only, protect=[*inputs, *written])
                except TrajcompError as exc:
                    unwritten = f"the program is written ({', '.join(map(str, written))}) but not its report: {exc}"
            _next(stages)
        lines = [*summary_lines(compliance.doc), *(f"warning: {w}" for w in report.warnings), *timing,
                 f"wrote {', '.join(map(str, written + reports))}"]
        status, message = batch.PASS, ""
        if not compliance.passed:
            failed = [c["id"] for c in compliance.doc["verdict"]["criteria"] if c["status"] == "fail"]
            status = batch.FAIL
            message = f"the program is written but fails its verdict ({', '.join(failed)}); see the report"
            if report.not_compensated:
                passed = len(report.not_compensated) - report.motions_left
                message += (f"; {report.motions_left} of {len(program.motions)} motions were not compensated "
                            "(positions computed at run time)"
                            + (f", {passed} points passed to routines left as written" if passed else ""))
        if timed is not None and not timed.within_limits:
            status, message = batch.FAIL, "; ".join(filter(None, [message, LIMIT_MESSAGE]))
        if unwritten:
            status, message = batch.FAIL, "; ".join(filter(None, [unwritten, message]))
        return batch.FileResult(str(path), tuple(map(str, written + reports)), status, message, tuple(lines)), compliance

    def options(self):
        """The run's options as user values, for the report's provenance."""
        poses = {}
        for kind in ("tools", "frames"):
            values = {name: matrix_to_pose(T) for name, T in getattr(self, kind).items()}
            poses[kind] = {name: [*p[:3], *np.degrees(p[3:])] for name, p in values.items()}
        return {"mode": self.mode, "outside": self.outside, "joint_targets": self.joint_targets, "to": self.to_format,
                "max_joint_change_deg": float(np.degrees(self.max_joint_change)),
                "max_correction_mm": self.max_correction, "retime": self.retime,
                "path_tolerance_mm": self.path_tolerance, **poses}


def _import_timing():
    """Import what re-timing needs (scipy's splines, 0.3 s) while the workers plan and compensate."""
    importlib.import_module("scipy.interpolate")


def _next(stages):
    """End a stage (`trajcomp.support.memory.end_stage`), the bar one step on."""
    end_stage()
    stages.advance()


@functools.lru_cache(maxsize=4)
def _model(path):
    """The model file, loaded once per process (a batch worker serves many files)."""
    return load_model(path)


@functools.lru_cache(maxsize=4)
def _model_info(path, mode):
    """The report's model entry (file checksum, date, statistics), once per process."""
    return model_entry(path, _model(path), mode)


def run(args):
    if args.jobs < 1:
        raise TrajcompError(f"--jobs: expected a whole number of at least 1, got {args.jobs}")
    tools, frames = frame_options(args)
    job = CompensateJob(
        model=str(Path(args.model).resolve()), mode=args.mode, outside=args.outside, tools=tools, frames=frames,
        joint_targets=args.joint_targets, max_joint_change=np.radians(args.max_joint_change),
        max_correction=args.max_correction, in_place=args.in_place, criteria=criteria_of(args),
        report=args.report, json_only=args.json_only, retime=args.retime, path_tolerance=args.path_tolerance,
        to_format=args.to_format,
    )
    model = _model(job.model)  # a broken model fails the run once, before any file
    if args.robot is not None and load_robot(args.robot).name != model.nominal.name:
        raise RobotError(f"--robot {args.robot}: the model {args.model} is for robot {model.nominal.name}")
    first = args.program[0]
    single = len(args.program) == 1 and not Path(first).is_dir() and not batch.is_pattern(first) \
        and not Path(args.output).is_dir()
    if single:
        result, compliance = dataclasses.replace(job, show_stages=True, workers=args.jobs).run(
            Path(first), Path(args.output))
        if args.json_only and not args.report:
            sys.stdout.write(compliance.json_text())
        for line in result.lines:
            info(line)
        if result.message:
            info(f"trajcomp: {result.message}")
        return batch.EXIT_CODES[result.status]
    if args.json_only and not args.report:
        raise TrajcompError("--json-only: a batch writes one report per program; give --report FOLDER")
    if args.report:
        Path(args.report).mkdir(parents=True, exist_ok=True)
    return _run_batch(args, dataclasses.replace(job, report_folder=True))


def _run_batch(args, job):
    inputs = batch.expand_inputs(args.program)
    outputs = batch.output_paths(inputs, args.output)
    if args.to_format:
        suffix = formats.find_format(format=args.to_format).extensions[0]
        outputs = [path.with_suffix(suffix) for path in outputs]
    summary = Path(args.summary) if args.summary else Path(args.output) / "summary.json"
    refuse_inputs([summary, *outputs], [*inputs, *model_inputs(args.model)], "give --summary another name")
    Path(args.output).mkdir(parents=True, exist_ok=True)
    with progress(len(inputs), desc="compensate", unit="file") as bar:
        results = batch.run_batch(job, inputs, outputs, jobs=args.jobs, scheduler=args.scheduler,
                                  done=lambda result: bar.update(1))
    for result in results:
        info(f"{result.status.upper():5} {result.input}" + (f": {result.message}" if result.message else ""))
    batch.write_summary(summary, results, model=args.model, mode=args.mode or "model default",
                        jobs=args.jobs, scheduler=args.scheduler)
    counts = {s: sum(r.status == s for r in results) for s in batch.EXIT_CODES}
    info(f"{len(results)} programs: " + ", ".join(f"{n} {s}" for s, n in counts.items() if n) + f"; summary {summary}")
    return batch.exit_code(results)
