"""The trajcomp exception tree.

Library code raises these; only the command line prints them and chooses an
exit code. Every message names what was wrong and where (file, line, field and
value where they are known).
"""


class TrajcompError(Exception):
    """Root of every error trajcomp raises on purpose."""


class ReadError(TrajcompError):
    """An input file (robot, measurements, program, model) is malformed."""


class WriteError(TrajcompError):
    """An output could not be written; nothing was left half-written."""


class RobotError(TrajcompError):
    """A robot description is inconsistent or unknown."""


class IKError(TrajcompError):
    """A target is unreachable, singular or outside the joint limits."""


class CalibrationError(TrajcompError):
    """Identification cannot produce a trustworthy model from the data."""


class ModelError(TrajcompError):
    """A compensation model file is incompatible or inconsistent."""


class TimingError(TrajcompError):
    """A trajectory cannot be re-timed under the given limits."""


class ToleranceError(TrajcompError):
    """The work ran but its result fails a requested tolerance or limit."""


class CompensationError(TrajcompError):
    """A correction is implausible: larger than the stated bound for a calibrated arm."""
