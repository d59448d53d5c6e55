"""Report options shared by compensate, retime, calibrate and validate, and writing the report."""

import sys

from trajcomp.commands._args import info


def add_report_options(parser, *, verdict="posture"):
    """``--report``, ``--json-only`` and the verdict's criteria options.

    ``verdict``: ``"posture"`` (tolerance, joint limit and singularity
    margins), ``"margins"`` (the margins only: a run without a model, whose
    landing no tolerance judges), ``"accuracy"`` (tolerance only) or None.
    """
    group = parser.add_argument_group("report")
    group.add_argument("--report", metavar="PATH",
                       help="write the report as PATH.html (self-contained page) and PATH.json (schema trajcomp-report/1)")
    group.add_argument("--json-only", action="store_true",
                       help="only the JSON report, no page or plots: to PATH.json with --report, else to stdout")
    if verdict in ("posture", "accuracy"):
        group.add_argument("--tolerance", type=float, default=0.1, metavar="MM",
                           help="largest acceptable landing error: per target (its landing estimate) and for 95 %% of "
                           "the model's held-out points (default %(default)g mm)")
    if verdict in ("posture", "margins"):
        group.add_argument("--limit-margin", type=float, default=1.0, metavar="DEG",
                           help="smallest acceptable distance of a joint to its limits (default %(default)g deg)")
        group.add_argument("--singularity-margin", type=float, default=5.0, metavar="DEG",
                           help="smallest acceptable elbow and wrist singularity distance (default %(default)g deg)")
        group.add_argument("--shoulder-margin", type=float, default=50.0, metavar="MM",
                           help="smallest acceptable distance of the wrist from the shoulder singularity "
                           "(default %(default)g mm)")


def criteria_of(args):
    """The verdict `Criteria` of the parsed options."""
    from trajcomp.report import Criteria

    names = ("tolerance", "limit_margin", "singularity_margin", "shoulder_margin")
    return Criteria(**{name: getattr(args, name) for name in names if hasattr(args, name)})


def emit(report, path, json_only, protect=(), written_before=()):
    """Write a report (or its JSON to stdout), print its summary on stderr; the exit code (0 pass, 1 fail).

    ``protect``: the run's inputs and outputs, which the report's files may
    not be. ``written_before``: the run's outputs already on disk; a report
    that cannot be written then fails the run (exit 1, `ToleranceError`)
    naming them, since an error of input (exit 2) would say nothing was
    written.
    """
    from trajcomp.errors import ToleranceError, TrajcompError

    if path:
        try:
            written = report.write(path, json_only=json_only, protect=protect)
        except TrajcompError as exc:
            if not written_before:
                raise
            raise ToleranceError(f"{', '.join(map(str, written_before))} written, but not the report: {exc}") from exc
    elif json_only:
        sys.stdout.write(report.json_text())
        written = []
    else:
        written = []
    from trajcomp.report import summary_lines

    for line in summary_lines(report.doc):
        info(line)
    if written:
        info(f"report: {', '.join(map(str, written))}")
    return 0 if report.passed else 1
