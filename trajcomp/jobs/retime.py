"""The re-timing job: time one program file under an arm's limits and write the timing into it, no model.

`RetimeJob` is ``trajcomp retime``'s unit of work (picklable, as a batch
needs it); `timed_program` is the re-timing a compensation job runs on its
corrected program too (`trajcomp.jobs.pipeline`).
"""

import dataclasses
from pathlib import Path

import numpy as np

from trajcomp import formats
from trajcomp.compensation.posture import planned_joints
from trajcomp.compensation.program_rewrite import as_written_report, placed_on_track
from trajcomp.errors import TrajcompError
from trajcomp.jobs import batch
from trajcomp.jobs.options import check_options
from trajcomp.jobs.program_run import LIMIT_MESSAGE, ProgramRun, output_entries, write_report
from trajcomp.report import Criteria, compliance_report, file_entry, report_paths, summary_lines
from trajcomp.support.atomic import FileSet, refuse_inputs
from trajcomp.timing.options import TOLERANCE


@dataclasses.dataclass(frozen=True)
class RetimeJob:
    """Time one program file under an arm's limits and write the timing into it: read, plan, re-time, write, judge.

    ``robot`` is the arm (a `trajcomp.arm.robot.Robot`); ``robot_file``
    its file when it came from one (an input no output may replace).
    Other attributes are the options of ``trajcomp retime``, checked when
    the job is made (`trajcomp.jobs.options`).
    """

    robot: object
    robot_file: str = None
    method: str = "auto"
    path_tolerance: float = TOLERANCE
    tools: dict = dataclasses.field(default_factory=dict)
    frames: dict = dataclasses.field(default_factory=dict)
    in_place: bool = False
    criteria: Criteria = Criteria()
    report: str = None
    json_only: bool = False

    def __post_init__(self):
        check_options(method=self.method, path_tolerance=self.path_tolerance)

    def run(self, path, output):
        """Time ``path`` into ``output`` (same language), judge it and write its report: a `ProgramRun`."""
        program = formats.read(path)
        language = formats.find_format(path)
        formats.check_robot_language(path, language, self.robot, "the arm --robot names")
        program = placed_on_track(program, self.robot, self.tools, self.frames)
        if formats.find_format(output) != language:
            raise TrajcompError(f"{output}: retime writes the language it reads ({language.name}); "
                                f"convert the program first (trajcomp convert)")
        sources = list(dict.fromkeys(formats.input_paths(path, program)))
        inputs = [*sources, *([self.robot_file] if self.robot_file else [])]
        refuse_inputs(report_paths(self.report) if self.report else (), inputs, "give --report another name")
        plan = planned_joints(program, self.robot, tools=self.tools, frames=self.frames)
        joints = planned(program, plan.index, plan.q)
        timed, timing = timed_program(program, self.robot, joints, self.method, self.path_tolerance, self.tools,
                                      self.frames)
        protect = inputs[len(sources):] if self.in_place else inputs
        with FileSet() as outputs:  # the program and its report land together, or neither
            written = formats.write(output, timed, protect=protect, into=outputs)
            report = as_written_report(program, plan, self.robot)
            compliance = compliance_report(
                report, self.robot, criteria=self.criteria, command="retime", timing=timing,
                files=[file_entry("program", p) for p in sources] + output_entries(written, outputs),
                options={"method": self.method, "path_tolerance_mm": self.path_tolerance},
            )
            reports, unwritten = write_report(compliance, self.report and Path(self.report), self.json_only,
                                              [*inputs, *written], written, outputs)
        lines = [*timing_lines(timing), f"wrote {', '.join(map(str, written))}", *summary_lines(compliance.doc)]
        if reports:
            lines.append(f"report: {', '.join(map(str, reports))}")
        failures = [unwritten, "" if compliance.passed else "the program is written but fails its verdict; see the "
                    "report", "" if timing.within_limits else LIMIT_MESSAGE]
        message = "; ".join(filter(None, failures))
        result = batch.FileResult(str(path), tuple(map(str, written + reports)), batch.FAIL if message else batch.PASS,
                                  message, tuple(lines))
        return ProgramRun(result, compliance, report, timing)


def planned(program, index, q):
    """Joints (N, 6) of a program's N targets: q (n, 6) of targets index (n,)
    (`trajcomp.compensation.posture.PlannedJoints`), NaN elsewhere."""
    joints = np.full((len(program.target_table()), 6), np.nan)
    joints[index] = q
    return joints


def timed_program(program, robot, joints, method, tolerance, tools, frames):
    """``(program with the timing written into its speed fields, TimingResult)``."""
    from trajcomp.timing.writeback import apply_timing, retime_program

    result = retime_program(program, robot, joints, method=method, tools=tools, frames=frames, tolerance=tolerance)
    return apply_timing(program, result, robot)


def timing_lines(result, before=None):
    """The dense check table, the cycle time(s) and what was written, as text lines."""
    written = sum(s.written for s in result.segments)
    kinds = ", ".join(sorted({s.kind for s in result.segments}))
    return [*result.lines_of_text(before), f"speed settings written for {written} motions ({kinds})"]
