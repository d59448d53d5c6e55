"""trajcomp: offline absolute-accuracy compensation for 6-axis robot arms."""

import logging

from trajcomp.errors import (
    CalibrationError,
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

logging.getLogger(__name__).addHandler(logging.NullHandler())

__all__ = [
    "CalibrationError",
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
