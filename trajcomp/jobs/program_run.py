"""What a job did with one program file (`ProgramRun`), and its report landed beside the program it judges.

Shared by the jobs that write a program and judge it: compensation
(`trajcomp.jobs.pipeline`) and re-timing (`trajcomp.jobs.retime`).
"""

import dataclasses
from pathlib import Path

from trajcomp.errors import TrajcompError
from trajcomp.jobs import batch
from trajcomp.report import file_entry

LIMIT_MESSAGE = "the timing exceeds a limit by more than 1 % in the 1 kHz check (table above): check it before running"


@dataclasses.dataclass(frozen=True, eq=False)
class ProgramRun:
    """What a job did with one program file.

    Attributes
    ----------
    result : batch.FileResult
        Status (pass or fail), the files written and the lines to show.
    compliance : Report
        The compliance report (``.passed``, ``.doc``), written or not.
    report : ProgramReport
        Per target: planned and corrected joints, landing estimate, warnings.
    timing : TimingResult or None
        The timing of the written program; None when it was not re-timed.
    """

    result: batch.FileResult
    compliance: object
    report: object
    timing: object = None

    @property
    def passed(self):
        """Whether the run passed: its verdict, the timing's 1 kHz check and its report written (bool)."""
        return self.result.status == batch.PASS

    @property
    def written(self):
        """The files written, program files first, then report files (tuple of Path)."""
        return tuple(map(Path, self.result.outputs))


def output_entries(written, outputs):
    """The report's entries of the program files ``written`` (staged in the `FileSet` ``outputs``)."""
    return [file_entry("output", p, staged=outputs.digest(p)) for p in written]


def write_report(compliance, target, json_only, protect, written, outputs):
    """Stage the report to ``target`` (when given) into the `FileSet` ``outputs`` beside the program
    (``written``): ``(report files, "")``, or ``([], why)`` when it cannot be written (the program is, alone)."""
    if not target:
        return [], ""
    try:
        return compliance.write(target, json_only=json_only, protect=protect, into=outputs), ""
    except TrajcompError as exc:
        return [], f"the program is written ({', '.join(map(str, written))}) but not its report: {exc}"
