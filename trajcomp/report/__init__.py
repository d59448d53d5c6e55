"""Reports: compliance of a compensated program, calibration and validation of a model.

Each report is a `Report`: a JSON document of the versioned schema
``trajcomp-report/1`` (``trajcomp/report/schema.json``) with a pass/fail
verdict against stated `Criteria`, figures drawn with matplotlib only when
the self-contained HTML page is rendered, and a one-screen text summary.
"""

from trajcomp.report.calibration import calibration_report, validation_report
from trajcomp.report.compliance import compliance_report
from trajcomp.report.document import SCHEMA, Report, schema
from trajcomp.report.provenance import file_entry, model_entry
from trajcomp.report.summary import summary_lines
from trajcomp.report.verdict import Criteria

__all__ = [
    "SCHEMA",
    "Criteria",
    "Report",
    "calibration_report",
    "compliance_report",
    "file_entry",
    "model_entry",
    "schema",
    "summary_lines",
    "validation_report",
]
