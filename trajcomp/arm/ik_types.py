"""IK types and constants shared by the solvers: tolerances, failure reasons, `Configuration`, `IKResult`.

The public names are re-exported by `trajcomp.arm.ik`, the module to import them
from; this one imports nothing of the other IK modules, so that all of them
(`trajcomp.arm.ik_closed_form`, `trajcomp.arm.ik_numeric`, `trajcomp.arm.ik`) can use it.
"""

import dataclasses

import numpy as np

from trajcomp.errors import IKError

BRANCHES = 8
POS_TOL = 1e-6  # mm, accepted TCP position error of an IK solution
ROT_TOL = 1e-9  # rad, accepted TCP orientation error of an IK solution

UNREACHABLE = "unreachable"
JOINT_LIMITS = "joint limits"
SINGULAR = "singular"
NOT_CONVERGED = "not converged"


@dataclasses.dataclass(frozen=True)
class Configuration:
    """One of the eight arm configurations (branches) of a closed-form arm.

    Defined geometrically from the DH frames, so the flags mean the same for
    every family (`trajcomp.arm.ik.configuration_of` computes them from joint angles):

    shoulder : {"front", "back"}
        "back" when the wrist point (origin of DH frame 5: the wrist centre
        of a spherical wrist) lies behind axis 1, i.e. its coordinate along
        the x axis of DH frame 1 is negative (KUKA "overhead", ABB "behind
        axis 1", FANUC "B").
    elbow : {"up", "down"}
        "up" when the elbow (axis 3) lies above the line from axis 2 to the
        origin of DH frame 4, seen in the arm plane with the wrist to the
        right and the base z axis up (for a spherical-wrist arm in front of
        axis 1 this is KUKA status bit 1 and FANUC "U").
    wrist : {"positive", "negative"}
        Sign of the triple product ``(a4 x a6) . a5`` of the joint axes
        (sin q5 for the built-in spherical-wrist arms; "negative" is KUKA
        status bit 2 and ABB cfx bit 0).
    """

    shoulder: str = "front"
    elbow: str = "up"
    wrist: str = "positive"

    _VALUES = (("front", "back"), ("up", "down"), ("positive", "negative"))

    def __post_init__(self):
        for name, allowed in zip(("shoulder", "elbow", "wrist"), self._VALUES):
            value = getattr(self, name)
            if value not in allowed:
                raise IKError(f"configuration {name}: expected one of {', '.join(allowed)}, got {value!r}")

    @property
    def index(self):
        """Branch number 0..7: 4 * back + 2 * down + negative."""
        flags = (self.shoulder, self.elbow, self.wrist)
        return sum(4 >> i for i, (value, allowed) in enumerate(zip(flags, self._VALUES)) if value == allowed[1])

    @classmethod
    def from_index(cls, index):
        """The configuration of branch ``index`` (0..7)."""
        if not 0 <= int(index) < BRANCHES:
            raise IKError(f"configuration index must be 0..7, got {index}")
        bits = [(int(index) >> shift) & 1 for shift in (2, 1, 0)]
        return cls(*(allowed[bit] for allowed, bit in zip(cls._VALUES, bits)))

    def __str__(self):
        return f"{self.shoulder}/{self.elbow}/{self.wrist}"


@dataclasses.dataclass(frozen=True, eq=False)
class IKResult:
    """Joint solutions of N targets.

    Attributes
    ----------
    q : ndarray, shape (N, 6)
        Joint angles, rad; NaN where the target failed.
    success : ndarray of bool, shape (N,)
    residual_pos : ndarray, shape (N,)
        TCP position error of the solution, mm (NaN without a solution).
    residual_rot : ndarray, shape (N,)
        TCP orientation error of the solution, rad (NaN without a solution).
    reason : ndarray of str, shape (N,)
        ``""`` on success, else one of ``"unreachable"``, ``"joint limits"``,
        ``"singular"``, ``"not converged"``.
    """

    q: np.ndarray
    success: np.ndarray
    residual_pos: np.ndarray
    residual_rot: np.ndarray
    reason: np.ndarray

    def with_rows(self, rows, other):
        """A copy with rows ``rows`` (M,) taken from ``other``, an IKResult of M targets."""
        fields = {}
        for field in dataclasses.fields(self):
            values, taken = getattr(self, field.name), getattr(other, field.name)
            values = values.astype(np.result_type(values, taken))  # a copy; text as wide as the longer reason
            values[rows] = taken
            fields[field.name] = values
        return IKResult(**fields)

    def raise_on_failure(self, label="targets", names=None, note=""):
        """Raise IKError naming the failed targets and why; else return self.

        Parameters
        ----------
        label : str
            Names the set of targets in the message (e.g. a program file).
        names : sequence of str, length N, optional
            Names of the targets (label and line); default ``target k`` (0-based).
        note : str
            Appended to the message (what the failures have in common).
        """
        failed = np.flatnonzero(~self.success)
        if failed.size:
            name = (lambda i: f"target {i}") if names is None else names.__getitem__
            shown = ", ".join(f"{name(i)}: {self.reason[i]}" for i in failed[:5])
            more = f" and {failed.size - 5} more" if failed.size > 5 else ""
            raise IKError(f"{label}: no IK solution for {failed.size} of {len(self.success)} targets ({shown}{more})"
                          f"{note}")
        return self


def _pose_stack(T):
    T = np.asarray(T, dtype=float)
    if T.shape[-2:] != (4, 4) or T.ndim not in (2, 3):
        raise IKError(f"targets must be poses of shape (N, 4, 4) or (4, 4), got {T.shape}")
    return T.reshape(-1, 4, 4)
