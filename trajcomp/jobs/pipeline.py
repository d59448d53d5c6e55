"""The compensation job: read, plan postures, compensate, re-time, write, judge.

Every face of trajcomp runs it: ``trajcomp compensate`` (one file, or a
batch on local processes or a Dask cluster), the Python API
(`trajcomp.Compensator.filter_program`), the plugins and the demo. The
same program and options give the same bytes and the same verdict through
each of them (tests/jobs/test_pipeline.py).

`CompensationJob` compensates one program file with a model (re-timed as
`trajcomp.jobs.retime` times a program). It is picklable, so a batch sends
it to its workers, and returns a `ProgramRun`: the files written, the
compliance report and what each stage found.
"""

import contextlib
import dataclasses
import functools
import importlib
from pathlib import Path

import numpy as np

from trajcomp import formats
from trajcomp.arm.transforms import matrix_to_pose
from trajcomp.compensation.options import MAX_CORRECTION, MAX_JOINT_CHANGE
from trajcomp.compensation.posture import planned_joints, planned_targets
from trajcomp.compensation.program_rewrite import compensate_program, convert_program, placed_on_track
from trajcomp.compensation.target_correction import program_corrector
from trajcomp.errors import TimingError
from trajcomp.jobs import batch
from trajcomp.jobs.options import check_options
from trajcomp.jobs.program_run import LIMIT_MESSAGE, ProgramRun, output_entries, write_report
from trajcomp.jobs.retime import planned, timed_program, timing_lines
from trajcomp.model.compensation_model import CompensationModel
from trajcomp.model.model_file import load_model, model_files
from trajcomp.programs.program import place_text
from trajcomp.report import Criteria, compliance_report, file_entry, model_entry, report_paths, summary_lines
from trajcomp.report.measured import measured_landing
from trajcomp.support.atomic import FileSet, refuse_inputs
from trajcomp.support.memory import end_stage, kept_apart, release
from trajcomp.support.parallel import in_background, meanwhile
from trajcomp.support.progress import Stages
from trajcomp.support.signals import held
from trajcomp.timing.options import TOLERANCE

# Targets below which the original and the corrected program are timed at once on two processes. A timing's
# working memory is ~230 bytes per waypoint: longer programs are timed one after the other (1M points: 0.95 GB, not 1.1).
TOGETHER = 500_000
STAGES = ("read", "compensate", "re-time", "write", "report")


@dataclasses.dataclass(frozen=True)
class CompensationJob:
    """Compensate one program file into one output: read, plan, compensate, re-time, write, judge.

    The unit of work of every face (picklable: a batch sends it to its
    workers). Attributes are the options of ``trajcomp compensate``;
    ``tools`` and ``frames`` are parsed values (T (4, 4), mm) and
    ``max_joint_change`` is in rad.

    ``model`` is a model file (loaded once per process) or a loaded
    `CompensationModel`, used as it is: ``model_file`` then names the file
    it came from (the report's provenance, an input no output may replace),
    or None for a model made in memory (its report names no file).
    """

    model: object
    model_file: str = None
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
    output_root: str = None  # the folder every output stays in (a batch's); default the output's own folder
    measured: object = None  # a validation run of the compensated program (`Measurements`, as
    # `trajcomp.calibration.measurements.read_validation_run` reads it): its landings in the report

    def __post_init__(self):
        check_options(outside=self.outside, joint_targets=self.joint_targets, retime=self.retime,
                      max_joint_change=self.max_joint_change, max_correction=self.max_correction,
                      path_tolerance=self.path_tolerance, workers=self.workers)

    def __call__(self, path, output):
        """Compensate ``path`` into ``output``; a `batch.FileResult` (raises TrajcompError on bad input)."""
        return self.run(path, output).result

    def run(self, path, output):
        """Compensate ``path`` into ``output``, judge it and write its report: a `ProgramRun`.

        ``path`` and ``output`` may be tuples: the files of one task that
        share points (`trajcomp.formats.task.groups`), compensated as one
        program written beside the first output as they lie beside the
        first file. The report goes to ``report`` or, with
        ``report_folder``, to ``report / <output's path under
        output_root>`` (``.html`` and ``.json``), its folder made. No output may be an input (the program's files unless
        ``in_place``, the model's); a report that cannot be written once
        the program is makes the file fail (exit 1) with the files written
        listed, not an input error.
        """
        task = path if isinstance(path, tuple) else None
        if task is not None:
            path, output = task[0], output[0]
        target = _report_target(self.report, self.report_folder, output, self.output_root)
        with Stages(STAGES, desc=Path(path).name, enabled=self.show_stages) as stages, kept_apart():
            model = loaded_model(self.model)
            whose = "the arm of the model" + (f" {self.source}" if self.source else "")
            program = formats.read(path, workers=self.workers) if task is None else formats.read_task(task)
            formats.check_robot_language(path, formats.find_format(path), model.nominal, whose)
            program = placed_on_track(program, model.nominal, self.tools, self.frames)  # also the timing's original
            out_format = formats.output_format(output, program, self.to_format)
            formats.check_robot_language(output, out_format, model.nominal, whose)
            sources = list(dict.fromkeys(formats.input_paths(path, program)))
            inputs = [*sources, *(model_files(self.source) if self.source else []),
                      *([self.measured.path] if self.measured else [])]
            refuse_inputs(report_paths(target) if target else (), [*inputs, output], "give --report another name")
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
            with FileSet() as outputs:  # the program and its report land together, or neither
                written = formats.write(output, corrected, out_format.name, protect=protect, workers=self.workers,
                                        root=self.output_root, into=outputs)
                _next(stages)
                mode = self.mode or model.method
                landed = None if self.measured is None else measured_landing(report, self.measured, model.T_tracker_base)
                compliance = compliance_report(
                    report, model.nominal, criteria=self.criteria, model=model,
                    model_info=_model_info(self.model, mode, self.source), mode=mode,
                    files=[file_entry("program", p) for p in sources]
                    + ([file_entry("validation run", self.measured.path)] if self.measured else [])
                    + output_entries(written, outputs),
                    options=self.options(), timing=timed, cycle_time_before=before if timed is not None else None,
                    workers=self.workers, measured=landed,
                )
                reports, unwritten = write_report(compliance, target, self.json_only, [*inputs, *written], written,
                                                   outputs)
            _next(stages)
        lines = [*summary_lines(compliance.doc), *(f"warning: {w}" for w in report.warnings), *timing,
                 f"wrote {', '.join(map(str, written + reports))}"]
        status, message = batch.PASS, ""
        if not compliance.passed:
            failed = [c["id"] for c in compliance.doc["verdict"]["criteria"] if c["status"] == "fail"]
            status = batch.FAIL
            message = f"the program is written but fails its verdict ({', '.join(failed)})"
            if reports or self.json_only:  # without a report the criteria's lines above say it all
                message += "; see the report"
            if report.not_compensated:
                passed = len(report.not_compensated) - report.motions_left
                place, _, why = report.not_compensated[0]  # its own reason: run time, a frame unknown, a copy ..
                message += (f"; {report.motions_left} of {len(program.motions)} motions were not compensated "
                            f"(the first, {place_text(place)}: {why}; the report lists each)"
                            + (f", {passed} points passed to routines left as written" if passed else ""))
        if timed is not None and not timed.within_limits:
            status, message = batch.FAIL, "; ".join(filter(None, [message, LIMIT_MESSAGE]))
        if unwritten:
            status, message = batch.FAIL, "; ".join(filter(None, [unwritten, message]))
        result = batch.FileResult(batch.named(task or path), tuple(map(str, written + reports)), status, message,
                                  tuple(lines))
        return ProgramRun(result, compliance, report, timed)

    @property
    def source(self):
        """The model's file (str), or None for a model made in memory."""
        return self.model_file if isinstance(self.model, CompensationModel) else str(self.model)

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


def retime_compensated(original, corrected, robot, method, tolerance, tools=None, frames=None, *, q_planned=None,
                       workers=1):
    """Time a compensated program, and its original for the cycle time before compensation.

    Parameters
    ----------
    original, corrected : Program
        Before and after compensation (the corrected targets carry their joints).
    robot : Robot
        The nominal robot.
    method : str
        One of `trajcomp.timing.RETIME_METHODS`.
    tolerance : float
        Path tolerance, mm.
    tools, frames : Mapping[str, ndarray (4, 4)], optional
        Tools and frames the program uses but does not define.
    q_planned : ndarray, shape (n, 6), optional
        The original's Cartesian targets in their declared postures, in
        motion order (`trajcomp.compensation.posture.planned_targets`), rad: the
        compensation's `ProgramReport.q_planned` (rows beyond n, joint
        targets, are not used). Solved again when not given.
    workers : int
        More than 1, for a program of fewer than `TOGETHER` targets: the
        original is timed by another process meanwhile
        (`trajcomp.support.parallel.in_background`); else first, so that only one
        timing's working memory is held at a time.

    Returns
    -------
    (Program, TimingResult, float)
        The corrected program with its timing written (as it was, with a
        warning in the timing, for a language without writable speed
        fields), the timing, and the original program's cycle time (s).

    Raises
    ------
    TimingError
        With a hint to compensate without re-timing.
    """
    from trajcomp.timing.writeback import retime_program, run_time_speeds, writable

    if q_planned is None:
        plan = planned_joints(original, robot, tools=tools, frames=frames)
        index, q_planned = plan.index, plan.q
    else:
        index = planned_targets(original)
        q_planned = q_planned[: len(index)]
    after = corrected.target_table().joints
    try:
        before = in_background(lambda: retime_program(original, robot, planned(original, index, q_planned),
                                                      method=method, tools=tools, frames=frames,
                                                      tolerance=tolerance).cycle_time,
                               workers if len(after) < TOGETHER else 1)
        release()  # the original's timing's working memory, when it was timed here, before the corrected one's
        if writable(corrected):
            timed, result = timed_program(corrected, robot, after, method, tolerance, tools, frames)
        else:
            timed = corrected
            result = retime_program(corrected, robot, after, method=method, tools=tools, frames=frames,
                                    tolerance=tolerance)
            note = f"the timing is not written: {corrected.format} programs have no speed fields trajcomp writes"
            result = dataclasses.replace(result, warnings=result.warnings + (note,),
                                         as_written=run_time_speeds(corrected, result))
        return timed, result, before()  # only the original's cycle time is kept
    except TimingError as exc:
        raise TimingError(f"{exc} (compensate with --retime none to keep the program's speeds)") from None


def loaded_model(model):
    """The `CompensationModel` of a job or an API call: ``model`` itself, or its file loaded once per process and
    file version (a batch worker serves many files; a file recalibrated under the same name loads again)."""
    if isinstance(model, CompensationModel):
        return model
    path = Path(model).resolve()
    return _model_file(str(path), _version(path))


def _version(path):
    """The modification time of file ``path``, ns; None for a file that cannot be read (`load_model` then says why)."""
    try:
        return Path(path).stat().st_mtime_ns
    except OSError:
        return None


@functools.lru_cache(maxsize=8)
def _model_file(path, version):
    """The model in ``path``; ``version`` (its modification time) makes an edited file load again."""
    return load_model(path)


def _model_info(model, mode, source):
    """The report's model entry (file checksum, date, statistics): once per process for a file a job loads, of
    ``source`` (its file, or None) for a loaded model."""
    if isinstance(model, CompensationModel):
        return model_entry(source, model, mode)
    return _file_model_info(source, _version(source), mode)


@functools.lru_cache(maxsize=4)
def _file_model_info(path, version, mode):
    return model_entry(path, loaded_model(path), mode)


def _report_target(report, folder, output, root=None):
    """Where a job's report goes: ``report``; for a batch's folder, ``report / <output's path under root>``
    (the input folders mirrored, as the programs are), or ``report / <output name>`` without a root; None for none."""
    if not report:
        return None
    if not folder:
        return Path(report)
    return Path(report) / (Path(output).relative_to(root) if root is not None else Path(output).name)


def _import_timing():
    """Import what re-timing needs (scipy's splines, 0.3 s) while the workers plan and compensate (a stopping
    signal taken after it: raised into a C extension's initialisation, it would break the import)."""
    with held():
        importlib.import_module("scipy.interpolate")


def _next(stages):
    """End a stage (`trajcomp.support.memory.end_stage`), the bar one step on."""
    end_stage()
    stages.advance()
