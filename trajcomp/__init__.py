"""trajcomp: offline absolute-accuracy compensation for 6-axis robot arms."""

import sys

from trajcomp.support.signals import hold_from_start, release_in_spawned

# A worker process a run spawned with SIGINT blocked (a local Dask cluster's): from here the stopping signals end it
release_in_spawned()

# ``python -m trajcomp[.cli]`` imports this package first (sys.argv[0] is "-m" while it does): the command line's
# stopping signals are kept from here (`trajcomp.support.signals.hold_from_start`), before the imports below; a
# library user's never
_MODULE = " ".join(getattr(sys, "orig_argv", ())).partition(" -m")[2].split()[:1] if sys.argv[:1] == ["-m"] else []
if _MODULE in (["trajcomp"], ["trajcomp.cli"]):
    hold_from_start()

import logging  # noqa: E402

from trajcomp.errors import (  # noqa: E402
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
