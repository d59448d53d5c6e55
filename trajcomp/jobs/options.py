"""The options of the jobs, checked in one place.

Every face hands its values to a job (`trajcomp.jobs.pipeline.CompensationJob`,
`trajcomp.jobs.retime.RetimeJob`) or to the API's `trajcomp.api.Compensator`,
and each checks them here when it is made, before any file is read: a wrong
value is refused with the same words whichever face gave it. The command
line's choices come from the same constants (`trajcomp.compensation.options`,
`trajcomp.timing.options`).
"""

import math
import numbers

from trajcomp.compensation.options import JOINT_TARGETS, OUTSIDE, RETIME_CHOICES
from trajcomp.errors import TrajcompError
from trajcomp.timing.options import RETIME_METHODS


def _one_of(choices):
    return (lambda value: isinstance(value, str) and value in choices), f"one of {', '.join(choices)}"


def _positive(value):
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value) and value > 0


def _whole(value):
    return isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= 1


POSITIVE, WHOLE = (_positive, "a positive number"), (_whole, "a whole number of at least 1")
# option name: (whether a value holds, what is expected)
RULES = {
    "outside": _one_of(OUTSIDE),
    "joint_targets": _one_of(JOINT_TARGETS),
    "retime": _one_of(RETIME_CHOICES),
    "method": _one_of(RETIME_METHODS),
    "max_joint_change": POSITIVE,
    "max_correction": POSITIVE,
    "path_tolerance": POSITIVE,
    "workers": WHOLE,
    "jobs": WHOLE,
}


def check_options(flags=False, **values):
    """Refuse the first option value that does not hold its rule (`RULES`).

    Parameters
    ----------
    flags : bool
        Name an option as the command line spells it (``--path-tolerance``),
        not as the API does (``path_tolerance``).
    **values
        Option name to value.

    Raises
    ------
    TrajcompError
        ``"<name>: expected <rule>, got <value>"``.
    """
    for name, value in values.items():
        holds, expected = RULES[name]
        if not holds(value):
            shown = f"--{name.replace('_', '-')}" if flags else name
            raise TrajcompError(f"{shown}: expected {expected}, got {value!r}")
