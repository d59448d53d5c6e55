"""Non-geometric joint errors: the residual that depends on the joint configuration.

What the DH table cannot hold is, on most arms, an error of the joint
angles themselves, a smooth function of the configuration:

- transmission errors of the gears and encoders, once and twice per turn
  of the joint: ``gear{j}_s{h}``, ``gear{j}_c{h}`` add ``c sin(h q_j)``,
  ``c cos(h q_j)`` to DH angle ``j`` (h = 1, 2);
- joint compliance under gravity: ``grav{j}_{k}`` adds ``c tau`` to DH
  angle ``j``, where ``tau`` (m) is the torque about axis ``j`` of a unit
  weight at the origin of DH frame ``k`` (k >= j) or at the TCP (``k = t``),
  with gravity along -z of the base frame (a floor-mounted arm); ``c`` then
  lumps the mass there and the joint's stiffness (rad per m of lever).

The features are computed with the *nominal* robot at the commanded joints,
so the coefficients enter linearly and the same model serves every tool and
orientation: a measurement at one orientation corrects the joints, not a
point in space, and does not pollute the prediction at another. The
coefficients are identified with a refinement of the DH parameters
(`trajcomp.identify`), held together as a `JointResidual`.
"""

import dataclasses
import re

import numpy as np

from trajcomp.errors import ModelError
from trajcomp.kinematics import fk, link_frames
from trajcomp.parameters import apply_deltas

KIND = "joint"
HARMONICS = (1, 2)
GRAVITY = np.array([0.0, 0.0, -1.0])  # unit weight direction, base frame
_PARAMETER = re.compile(r"^(?:(?:a|alpha|d|theta|beta)[1-6]|tool_[xyz])$")
RANGE_MARGIN = np.radians(5.0)  # rad beyond the fitted joint range still inside: smooth terms extrapolate that far
COMMAND_ITERATIONS = 4  # fixed-point passes of `JointResidual.commanded`: errors are mrad, contraction ~1e-3


def term_names():
    """Every candidate term name, joint by joint."""
    names = []
    for j in range(1, 7):
        names += [f"gear{j}_{f}{h}" for h in HARMONICS for f in ("s", "c")]
        names += [f"grav{j}_{k}" for k in (*range(j, 7), "t")]
    return names


def is_term(name):
    """True for the name of a joint-error term."""
    return name.startswith(("gear", "grav"))


def term_joint(name):
    """0-based joint index a term acts on."""
    return int(name[4]) - 1


def features(nominal, q, names):
    """Value of each term's basis function at each configuration.

    Parameters
    ----------
    nominal : Robot
        The nominal robot (with the calibrated TCP).
    q : ndarray, shape (N, 6)
        Commanded joint angles, rad.
    names : sequence of str
        Term names (`term_names`).

    Returns
    -------
    ndarray, shape (N, T)
        Dimensionless (gear) or m (grav).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    out = np.empty((len(q), len(names)))
    frames = None
    for k, name in enumerate(names):
        j = term_joint(name)
        if name.startswith("gear"):
            harmonic = int(name[-1])
            out[:, k] = (np.sin if name[-2] == "s" else np.cos)(harmonic * q[:, j])
            continue
        if name.startswith("grav"):
            if frames is None:
                frames = link_frames(nominal, q)
                tcp = fk(nominal, q)[:, :3, 3]
            lump = name.split("_")[1]
            point = tcp if lump == "t" else frames[:, int(lump), :3, 3]
            axis, origin = frames[:, j, :3, 2], frames[:, j, :3, 3]
            out[:, k] = np.einsum("ni,ni->n", axis, np.cross(point - origin, GRAVITY)) / 1000.0
            continue
        raise ModelError(f"joint errors: unknown term {name!r}")
    return out


@dataclasses.dataclass(frozen=True, eq=False)
class JointResidual:
    """Joint-angle errors as a function of the commanded joints, with the DH refinement fitted with them.

    Attributes
    ----------
    names : tuple of str
        Term names (`term_names`) and, fitted together with them, DH and
        tool parameter names (`trajcomp.parameters`) refining the robot the
        residual is added to.
    values : ndarray, shape (P,)
        Term coefficients, rad (gear) or rad/m (grav); parameter deltas, mm or rad.
    lower, upper : ndarray, shape (6,)
        Range of the commanded joints it was fitted on, rad: the errors are
        known there (`contains`), extrapolated elsewhere.
    """

    names: tuple
    values: np.ndarray
    lower: np.ndarray = dataclasses.field(default_factory=lambda: np.full(6, -np.inf))
    upper: np.ndarray = dataclasses.field(default_factory=lambda: np.full(6, np.inf))
    kind = KIND

    def __post_init__(self):
        names = tuple(str(n) for n in self.names)
        values = np.asarray(self.values, dtype=float).reshape(-1)
        known = set(term_names())
        unknown = [n for n in names if n not in known and not _PARAMETER.match(n)]
        if unknown or len(values) != len(names) or not np.isfinite(values).all():
            raise ModelError(
                f"joint residual: need finite values for known terms and parameters, got {len(values)} values "
                f"for {len(names)} names (unknown: {', '.join(unknown) or 'none'})"
            )
        lower, upper = (np.asarray(v, dtype=float).reshape(-1) for v in (self.lower, self.upper))
        if lower.shape != (6,) or upper.shape != (6,) or not np.all(lower <= upper):
            raise ModelError(f"joint residual: joint range must be 6 lower <= upper values, got {lower} .. {upper}")
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)

    def contains(self, q):
        """Boolean mask (N,) of commanded joints q (N, 6) inside the fitted range (`RANGE_MARGIN` beyond it allowed)."""
        q = np.atleast_2d(q)
        return np.all((q >= self.lower - RANGE_MARGIN) & (q <= self.upper + RANGE_MARGIN), axis=1)

    def clamped(self, q):
        """Commanded joints q (N, 6) moved into the fitted range."""
        return np.clip(q, self.lower, self.upper)

    @property
    def terms(self):
        """``(names, values)`` of the joint-error terms alone."""
        pick = [k for k, n in enumerate(self.names) if is_term(n)]
        return [self.names[k] for k in pick], self.values[pick]

    def robot(self, identified):
        """``identified`` with this residual's DH refinement applied."""
        pick = [k for k, n in enumerate(self.names) if not is_term(n)]
        return apply_deltas(identified, [self.names[k] for k in pick], self.values[pick])

    def offsets(self, nominal, q, outside="model"):
        """DH-angle errors (N, 6), rad, at commanded joints q (N, 6) rad.

        ``outside`` applies to joints outside the fitted range: ``model``
        leaves their errors out (the refined DH model alone), ``clamp``
        takes them at the nearest joints of the range, ``extrapolate``
        evaluates the terms anyway.
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if outside == "clamp":
            q = self.clamped(q)
        names, values = self.terms
        out = np.zeros(q.shape)
        for k, contribution in enumerate((features(nominal, q, names) * values).T):
            out[:, term_joint(names[k])] += contribution
        if outside == "model":
            out[~self.contains(q)] = 0.0
        return out

    def reached(self, nominal, q, outside="model"):
        """Joint angles (N, 6) rad the arm really takes for commands q: DH-angle errors mapped by the joint map."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        return q + self.offsets(nominal, q, outside) @ np.linalg.inv(nominal.joint_map).T

    def commanded(self, nominal, q_reached, outside="model"):
        """Commands (N, 6) rad under which the arm takes the joint angles ``q_reached``.

        Solves ``reached(q) = q_reached`` by fixed-point iteration; the errors
        are milliradians and vary slowly, so a few passes converge far below
        a microradian.
        """
        q_reached = np.atleast_2d(np.asarray(q_reached, dtype=float))
        q = q_reached.copy()
        for _ in range(COMMAND_ITERATIONS):
            q = q_reached - (self.reached(nominal, q, outside) - q)
        return q

    def to_dict(self):
        """Plain dict for the model file: kind, names, values, joint range (internal units, mm and rad)."""
        return {"kind": KIND, "names": list(self.names), "values": self.values.tolist(),
                "lower": self.lower.tolist(), "upper": self.upper.tolist()}

    @classmethod
    def from_dict(cls, data):
        """Inverse of `to_dict`."""
        try:
            return cls(tuple(data["names"]), data["values"], data["lower"], data["upper"])
        except KeyError as exc:
            raise ModelError(f"joint residual: missing key {exc.args[0]!r}") from None
        except (TypeError, ValueError) as exc:
            raise ModelError(f"joint residual: malformed entry: {exc}") from None
