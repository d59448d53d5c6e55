"""trajcomp: offline absolute-accuracy compensation for 6-axis robot arms."""

import logging

from trajcomp.errors import (
    CalibrationError,
    CompensationError,
    IKError,
    ModelError,
    ReadError,
    RobotError,
    TimingError,
    ToleranceError,
    TrajcompError,
    WriteError,
)

__version__ = "0.1.0"

# The Python API (trajcomp.api), imported on first use so that the CLI starts without it.
_API = ("Compensator", "filter_program", "filter_programs", "filter_target", "filter_targets")

logging.getLogger(__name__).addHandler(logging.NullHandler())

__all__ = [
    *_API,
    "CalibrationError",
    "CompensationError",
    "IKError",
    "ModelError",
    "ReadError",
    "RobotError",
    "TimingError",
    "ToleranceError",
    "TrajcompError",
    "WriteError",
    "__version__",
]


def __getattr__(name):
    if name in _API:
        from trajcomp import api

        return getattr(api, name)
    raise AttributeError(f"module 'trajcomp' has no attribute {name!r}")
