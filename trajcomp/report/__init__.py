"""Reports: compliance of a compensated program, calibration and validation of a model.

Each report is a `Report`: a JSON document of the versioned schema
``trajcomp-report/1`` (``trajcomp/report/schema.json``) with a pass/fail
verdict against stated `Criteria`, figures drawn with matplotlib only when
the self-contained HTML page is rendered, and a one-screen text summary.
The names below are imported from their module on first use, so that a
compliance report does not load the calibration machinery and the reverse.
"""

from trajcomp.support.lazy import lazy_names

_MODULES = {
    "SCHEMA": "document",
    "Criteria": "verdict",
    "Report": "document",
    "calibration_report": "calibration",
    "compliance_report": "compliance",
    "file_entry": "provenance",
    "model_entry": "provenance",
    "report_paths": "document",
    "schema": "document",
    "summary_lines": "summary",
    "validation_report": "calibration",
}
__all__ = sorted(_MODULES)

__getattr__ = lazy_names(__name__, _MODULES)
