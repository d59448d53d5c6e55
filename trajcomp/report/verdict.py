"""The verdict of a report: stated criteria, each passed, failed or not evaluated, with what it concerns.

A report passes when every criterion that could be evaluated passes; a
criterion that could not (no timing, no grid) says why and does not fail
the run. Each failed criterion names the targets (labels) or program lines
it concerns, so that the fix can start at the right place.
"""

import dataclasses

import numpy as np

from trajcomp.errors import TrajcompError

PASS, FAIL, NOT_EVALUATED = "pass", "fail", "not evaluated"
LISTED = 2000  # targets named per failed criterion; `Check.failing` counts them all


@dataclasses.dataclass(frozen=True)
class Criteria:
    """Thresholds of the verdict, in user units.

    Attributes
    ----------
    tolerance : float
        Largest acceptable landing error, mm: per target (its landing
        estimate, `trajcomp.model.landing`) and for 95 % of the model's held-out
        points (model accuracy).
    limit_margin : float
        Smallest acceptable distance of a joint to its position limit, deg.
    singularity_margin : float
        Smallest acceptable elbow and wrist singularity distance, deg.
    shoulder_margin : float
        Smallest acceptable shoulder singularity distance, mm.
    """

    tolerance: float = 0.1
    limit_margin: float = 1.0
    singularity_margin: float = 5.0
    shoulder_margin: float = 50.0

    def __post_init__(self):
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if not (np.isfinite(value) and value >= 0):
                raise TrajcompError(f"{field.name.replace('_', ' ')}: expected a finite number >= 0, got {value}")

    def as_dict(self):
        """``{"tolerance_mm": ..., "limit_margin_deg": ..., ...}``."""
        units = {"tolerance": "mm", "limit_margin": "deg", "singularity_margin": "deg", "shoulder_margin": "mm"}
        return {f"{name}_{unit}": getattr(self, name) for name, unit in units.items()}


@dataclasses.dataclass(frozen=True)
class Check:
    """One criterion and its outcome.

    Attributes
    ----------
    id : str
        Stable key (``residual``, ``outside_grid``, ...).
    statement : str
        The criterion in words, with its threshold.
    status : {"pass", "fail", "not evaluated"}
    detail : str
        What was found (worst value) or why it was not evaluated.
    targets : tuple of str
        Labels of the targets it fails for (the first `LISTED`, motion order).
    lines : tuple of int
        Program lines it fails for (motions without a target).
    failing : int
        How many targets or lines it fails for.
    """

    id: str
    statement: str
    status: str
    detail: str = ""
    targets: tuple = ()
    lines: tuple = ()
    failing: int = 0

    def as_dict(self):
        return {**dataclasses.asdict(self), "targets": list(self.targets), "lines": list(self.lines)}


def check(id, statement, failing, labels, detail):
    """A Check from a boolean mask (N,) of failing targets and their labels (Sequence[str], N)."""
    failing = np.flatnonzero(np.asarray(failing, dtype=bool))
    return Check(id, statement, FAIL if len(failing) else PASS, detail,
                 targets=tuple(str(labels[k]) for k in failing[:LISTED].tolist()), failing=len(failing))


def not_evaluated(id, statement, reason):
    """A Check that could not be evaluated, and why."""
    return Check(id, statement, NOT_EVALUATED, reason)


def verdict(checks):
    """The verdict dict of a report: ``{"result": "pass" | "fail" | "not evaluated", "criteria": [...]}``.

    A verdict passes only on evidence: with no criterion failed and none
    evaluated either, it is not evaluated (and the run fails, as a pass
    would claim what nothing checked).
    """
    statuses = {c.status for c in checks}
    result = FAIL if FAIL in statuses else PASS if PASS in statuses else NOT_EVALUATED
    return {"result": result, "criteria": [c.as_dict() for c in checks]}


def accuracy_check(stats, mode, tolerance, source, missing=None):
    """The model-accuracy criterion: 95th percentile |error| of ``mode`` within the tolerance.

    Parameters
    ----------
    stats : dict or None
        Statistics dict of the mode (`trajcomp.model.stats.ErrorStats.as_dict`).
    mode : str
    tolerance : float
        mm.
    source : str
        Where the statistics come from (``"5-fold cross-validation"``,
        ``"validation measurements"``), for the statement.
    missing : str, optional
        Why there are no statistics (default: the model has none of the mode).
    """
    statement = f"95 % of {source} errors in mode {mode} within {tolerance:g} mm"
    if not stats:
        return not_evaluated("model_accuracy", statement, missing or f"no statistics of mode {mode} in the model")
    p95 = stats["p95"]
    return Check("model_accuracy", statement, PASS if p95 <= tolerance else FAIL,
                 f"p95 |error| {p95:.4f} mm (mean {stats['mean']:.4f}, max {stats['max']:.4f} mm, {stats['n']} points)")
