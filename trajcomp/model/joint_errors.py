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

- a smooth function of the joint's own angle the harmonics do not reach
  (reducer and encoder cyclic errors of any period, transmission
  stiffness): ``spline{j}_{k}`` adds ``c B_k(q_j)`` to DH angle ``j``,
  ``B_k`` the k-th uniform cubic B-spline over the measured range of the
  joint (`SplineBasis`), its wiggle bounded by a penalty on the second
  differences of the coefficients. Beyond the measured range the spline is
  held at its boundary value: it never extrapolates a shape the data did
  not show (and `JointResidual.contains` says how far beyond it still
  counts as inside).

The features are computed with the *nominal* robot at the commanded joints,
so the coefficients enter linearly and the same model serves every tool and
orientation: a measurement at one orientation corrects the joints, not a
point in space, and does not pollute the prediction at another. The
coefficients are identified with a refinement of the DH parameters
(`trajcomp.calibration.identify`), held together as a `JointResidual`.
"""

import dataclasses
import functools
import re

import numpy as np

from trajcomp.errors import ModelError
from trajcomp.arm.kinematics import frame_columns, in_blocks
from trajcomp.arm.parameters import apply_deltas
from trajcomp.model.options import JOINT_KIND as KIND

HARMONICS = (1, 2)
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
    return name.startswith(("gear", "grav", "spline"))


def is_spline(name):
    """True for the name of a spline term (`SplineBasis`)."""
    return name.startswith("spline")


def term_joint(name):
    """0-based joint index a term acts on."""
    return int(name[6 if is_spline(name) else 4]) - 1


def cubic_pieces(t):
    """The 4 uniform cubic B-splines non-zero in a knot interval, at places t (...) in [0, 1] along it.

    Returns
    -------
    ndarray, shape (..., 4)
        The B-spline centred one knot before the interval's start, at its
        start, at its end and one knot after it (dimensionless, summing to 1).
    """
    inner = lambda u: (4.0 - 6.0 * u**2 + 3.0 * u**3) / 6.0  # noqa: E731 (|u| <= 1 knot steps from the centre)
    outer = lambda u: (2.0 - u) ** 3 / 6.0  # noqa: E731 (1 to 2 knot steps)
    return np.stack([outer(t + 1.0), inner(t), inner(np.abs(t - 1.0)), outer(np.abs(t - 2.0))], axis=-1)


@dataclasses.dataclass(frozen=True, eq=False)
class SplineBasis:
    """Uniform cubic B-splines of each joint's angle over its measured range.

    Attributes
    ----------
    lower, upper : ndarray, shape (6,)
        Measured range of each joint's commanded angle, rad.
    step : ndarray, shape (6,)
        Knot spacing asked for, rad (0: no spline on that joint). The range
        is cut into ``ceil(range / step)`` equal intervals (at least one),
        giving that many plus 3 basis functions.
    penalty : float
        Weight of the squared second differences of the coefficients
        (scaled units, see `trajcomp.arm.parameters.scales`) per measurement.
    """

    lower: np.ndarray
    upper: np.ndarray
    step: np.ndarray
    penalty: float = 0.0

    def __post_init__(self):
        lower, upper, step = (np.asarray(v, dtype=float).reshape(-1) for v in (self.lower, self.upper, self.step))
        if not (lower.shape == upper.shape == step.shape == (6,) and np.all(np.isfinite([*lower, *upper, *step]))
                and np.all(lower <= upper) and np.all(step >= 0.0)
                and np.isfinite(self.penalty) and self.penalty >= 0.0):
            raise ModelError(f"spline basis: need 6 finite lower <= upper, steps >= 0 and a penalty >= 0, got "
                             f"{lower} .. {upper}, steps {step}, penalty {self.penalty}")
        for name, value in (("lower", lower), ("upper", upper), ("step", step)):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "penalty", float(self.penalty))

    def intervals(self, joint):
        """Number of knot intervals of a 0-based joint (0: no spline)."""
        if self.step[joint] == 0.0:
            return 0
        return max(1, int(np.ceil((self.upper[joint] - self.lower[joint]) / self.step[joint] - 1e-9)))

    def names(self):
        """Term names, joint by joint: ``spline{j}_{k}``."""
        return [f"spline{j + 1}_{k}" for j in range(6) for k in range(self.intervals(j) + 3 if self.intervals(j) else 0)]

    def support(self, q, joint):
        """The 4 basis functions of a 0-based joint that are non-zero at each of commanded joints q (N, 6) rad.

        Angles beyond the measured range take the boundary's values.

        Returns
        -------
        columns : ndarray of int, shape (N, 4)
            Their indices k (term ``spline{joint + 1}_{k}``).
        values : ndarray, shape (N, 4)
            Their values (dimensionless, summing to 1).
        """
        first, place = self._intervals_at(q, [joint])
        return first + np.arange(4), cubic_pieces(place[:, 0])

    def _intervals_at(self, q, joints):
        """The knot interval of each of commanded joints q (N, 6) rad, of 0-based ``joints`` (M,) with splines.

        Returns
        -------
        first : ndarray of int, shape (N, M)
            Index of the interval, which is that of the first of the 4
            basis functions non-zero in it (basis k is centred at knot k - 1).
        place : ndarray, shape (N, M)
            Where the angle lies along it, in [0, 1] (angles beyond the
            measured range at its boundary).
        """
        count = np.array([self.intervals(j) for j in joints])
        lower, upper = self.lower[joints], self.upper[joints]
        u = (np.clip(q[:, joints], lower, upper) - lower) / (np.maximum(upper - lower, 1e-12) / count)
        first = np.minimum(np.floor(u).astype(int), count - 1)
        return first, u - first

    def matrix(self, q, joint):
        """Basis values (N, K) of a 0-based joint at commanded joints q (N, 6) rad, sparse (4 per row, `support`)."""
        from scipy import sparse  # here: models without spline terms never need it

        columns, values = self.support(q, joint)
        rows = np.repeat(np.arange(len(q)), 4)
        return sparse.csr_matrix((values.ravel(), (rows, columns.ravel())), shape=(len(q), self.intervals(joint) + 3))

    def coefficients(self, names, values):
        """The spline terms among ``names`` with coefficients ``values`` (rad) as a table (6, K) rad: row j the
        coefficients of joint j's basis functions in order (zero for a term not named, and beyond its count)."""
        table = np.zeros((6, max(self.intervals(j) for j in range(6)) + 3))
        for name, value in zip(names, values):
            if is_spline(name):
                table[term_joint(name), int(name.split("_")[1])] = value
        return table

    def offsets(self, q, table):
        """DH-angle errors (N, 6) rad of the spline terms of coefficients ``table`` (`coefficients`) at joints q (N, 6)
        rad."""
        out = np.zeros((len(q), 6))
        joints = [j for j in range(6) if self.intervals(j)]
        if joints:
            first, place = self._intervals_at(q, joints)
            own = table[joints][np.arange(len(joints))[:, None], first[..., None] + np.arange(4)]  # (N, M, 4)
            terms = own * cubic_pieces(place)
            out[:, joints] = (terms[..., 0] + terms[..., 2]) + (terms[..., 1] + terms[..., 3])  # as einsum sums 4
        return out

    def roughness(self, names):
        """Second-difference penalty matrix (T, T) over term ``names`` (zero outside the spline terms).

        A second difference enters only where its three terms are all in ``names``.
        """
        out = np.zeros((len(names), len(names)))
        index = {n: k for k, n in enumerate(names)}
        second = np.array([1.0, -2.0, 1.0])
        for j in range(6):
            count = self.intervals(j) + 3 if self.intervals(j) else 0
            triples = np.array([[index.get(f"spline{j + 1}_{k + o}", -1) for o in (-1, 0, 1)]
                                for k in range(1, count - 1)], dtype=int).reshape(-1, 3)
            triples = triples[(triples >= 0).all(axis=1)]
            np.add.at(out, (triples[:, :, None], triples[:, None, :]), np.outer(second, second))
        return out

    def to_dict(self):
        """Plain dict for the model file (rad)."""
        return {"lower": self.lower.tolist(), "upper": self.upper.tolist(), "step": self.step.tolist(),
                "penalty": self.penalty}

    @classmethod
    def from_dict(cls, data):
        """Inverse of `to_dict`."""
        return cls(data["lower"], data["upper"], data["step"], data.get("penalty", 0.0))


def features(nominal, q, names):
    """Value of each gear and gravity term's basis function at each configuration.

    Parameters
    ----------
    nominal : Robot
        The nominal robot (with the calibrated TCP).
    q : ndarray, shape (N, 6)
        Commanded joint angles, rad.
    names : sequence of str
        Term names (`term_names`; spline terms are evaluated by their
        `SplineBasis`).

    Returns
    -------
    ndarray, shape (N, T)
        Dimensionless (gear) or m (grav).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    unknown = [name for name in names if not name.startswith(("gear", "grav"))]
    if unknown:
        raise ModelError(f"joint errors: unknown term {unknown[0]!r}")
    return in_blocks(lambda block: (_block_features(nominal, block, names),), q)[0]


def _block_features(nominal, q, names):
    """`features` (n, T) of a block of configurations q (n, 6) (`trajcomp.arm.kinematics.in_blocks`)."""
    out = np.empty((len(q), len(names)))
    columns = [None]  # the DH frames' columns, once a gravity term needs them
    for j, (harmonics, sines, lumps, order) in enumerate(_layout(names)):
        out[:, order] = _joint_features(nominal, q, j, harmonics, sines, lumps, columns).T
    return out


def _layout(names):
    """The gear and gravity terms among ``names`` joint by joint, as `_joint_features` computes them: per joint its
    harmonics (H,), whether each is a sine (H,) bool, the frames its gravity terms' weights are at (G,) int (DH
    frames 0..6, the TCP as 7) and where those H + G terms are in ``names`` (the harmonics first, as `term_names`
    orders them)."""
    layout = []
    for j in range(6):
        gear = [k for k, n in enumerate(names) if n.startswith("gear") and term_joint(n) == j]
        gravity = [k for k, n in enumerate(names) if n.startswith("grav") and term_joint(n) == j]
        lumps = [names[k].split("_")[1] for k in gravity]
        harmonics = np.array([float(names[k][-1]) for k in gear])
        sines = np.array([names[k][-2] == "s" for k in gear], dtype=bool)
        frames = np.array([7 if lump == "t" else int(lump) for lump in lumps], dtype=int)
        layout.append((harmonics, sines, frames, np.array(gear + gravity, dtype=int)))
    return layout


def _joint_features(nominal, q, j, harmonics, sines, lumps, columns):
    """The features (H + G, n) of joint ``j``'s harmonics and gravity terms (`_layout`) at configurations q (n, 6).

    The torque about axis ``j`` of a unit weight along -z of the base frame
    at a point ``p`` is ``axis . ((p - origin) x (0, 0, -1))``, whose cross
    product is ``(-lever_y, lever_x, 0)``: two products per term on the DH
    frames' columns (`trajcomp.arm.kinematics.frame_columns`, the TCP as
    frame 7), which ``columns[0]`` holds once made (None before).
    """
    multiples = harmonics[:, None] * q[:, j]
    multiples[sines], multiples[~sines] = np.sin(multiples[sines]), np.cos(multiples[~sines])
    if not lumps.size:
        return multiples
    if columns[0] is None:
        columns[0] = frame_columns(nominal, q, tcp=True)
    lever = columns[0][lumps, 3, :2] - columns[0][j, 3, :2]  # (G, 2, n), mm
    axis = columns[0][j, 2]
    return np.concatenate([multiples, (axis[1] * lever[:, 0] - axis[0] * lever[:, 1]) / 1000.0])


@dataclasses.dataclass(frozen=True, eq=False)
class JointResidual:
    """Joint-angle errors as a function of the commanded joints, with the DH refinement fitted with them.

    Attributes
    ----------
    names : tuple of str
        Term names (`term_names`) and, fitted together with them, DH and
        tool parameter names (`trajcomp.arm.parameters`) refining the robot the
        residual is added to.
    values : ndarray, shape (P,)
        Term coefficients, rad (gear) or rad/m (grav); parameter deltas, mm or rad.
    lower, upper : ndarray, shape (6,)
        Range of the commanded joints it was fitted on, rad: the errors are
        known there (`contains`), extrapolated elsewhere.
    basis : SplineBasis or None
        The knots of the spline terms (None: no spline terms).
    """

    names: tuple
    values: np.ndarray
    lower: np.ndarray = dataclasses.field(default_factory=lambda: np.full(6, -np.inf))
    upper: np.ndarray = dataclasses.field(default_factory=lambda: np.full(6, np.inf))
    basis: object = None
    kind = KIND

    def __post_init__(self):
        names = tuple(str(n) for n in self.names)
        values = np.asarray(self.values, dtype=float).reshape(-1)
        known = set(term_names()) | set(self.basis.names() if self.basis is not None else ())
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

    @property
    def terms(self):
        """``(names, values)`` of the joint-error terms alone."""
        pick = [k for k, n in enumerate(self.names) if is_term(n)]
        return [self.names[k] for k in pick], self.values[pick]

    def robot(self, identified):
        """``identified`` with this residual's DH refinement applied."""
        pick = [k for k, n in enumerate(self.names) if not is_term(n)]
        return apply_deltas(identified, [self.names[k] for k in pick], self.values[pick])

    def offsets(self, nominal, q):
        """DH-angle errors (N, 6), rad, at commanded joints q (N, 6) rad.

        Beyond the fitted range of a joint the gear and gravity terms, which
        are physics of the whole turn, are evaluated all the same, and the
        spline terms are held at their boundary value: the model's own
        extrapolation. On foreign virtual UR10 arms (``bench_verdict``'s,
        harsh profile) targets 150-300 mm outside the measured cube, near
        the elbow singularity and in the other wrist posture land 2-5x
        closer than with the refined DH model alone (0.05 against 0.22-0.27
        mm mean, 0.24-0.26 against 0.79-1.08, 0.11 against 0.22-0.37).
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        return in_blocks(lambda block: (self._block_offsets(nominal, block),), q)[0]

    def _block_offsets(self, nominal, q):
        """`offsets` (n, 6) of a block of commanded joints q (n, 6) (`trajcomp.arm.kinematics.in_blocks`).

        Each term's feature (`features`) times its coefficient, summed per
        joint in the order of the names (the order in which a product with a
        (T, 6) matrix of the terms' joints summed them: the same bits), then
        the splines'.
        """
        layout, values, splines = self._terms_laid_out
        out = np.zeros(q.shape)
        columns = [None]
        for j, (harmonics, sines, lumps, order) in enumerate(layout):
            if order.size:
                terms = _joint_features(nominal, q, j, harmonics, sines, lumps, columns) * values[order][:, None]
                out[:, j] = np.add.reduce(terms, axis=0)
        if self.basis is not None:
            out += self.basis.offsets(q, splines)
        return out

    @functools.cached_property
    def _terms_laid_out(self):
        """The terms as `offsets` takes them: the `_layout` of their names, their coefficients (rad, rad/m) in the
        names' order and the splines' table (`SplineBasis.coefficients`, None without a basis)."""
        names, values = self.terms
        splines = None if self.basis is None else self.basis.coefficients(names, values)
        return _layout(names), values, splines

    def reached(self, nominal, q):
        """Joint angles (N, 6) rad the arm really takes for commands q: DH-angle errors mapped by the joint map."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        return q + self.offsets(nominal, q) @ np.linalg.inv(nominal.joint_map).T

    def commanded(self, nominal, q_reached):
        """Commands (N, 6) rad under which the arm takes the joint angles ``q_reached``.

        Solves ``reached(q) = q_reached`` by fixed-point iteration; the errors
        are milliradians and vary slowly, so a few passes converge far below
        a microradian.
        """
        q_reached = np.atleast_2d(np.asarray(q_reached, dtype=float))
        q = q_reached.copy()
        for _ in range(COMMAND_ITERATIONS):
            q = q_reached - (self.reached(nominal, q) - q)
        return q

    def to_dict(self):
        """Plain dict for the model file: kind, names, values, joint range (internal units, mm and rad)."""
        out = {"kind": KIND, "names": list(self.names), "values": self.values.tolist(),
               "lower": self.lower.tolist(), "upper": self.upper.tolist()}
        if self.basis is not None:
            out["spline_basis"] = self.basis.to_dict()
        return out

    @classmethod
    def from_dict(cls, data):
        """Inverse of `to_dict`."""
        try:
            basis = SplineBasis.from_dict(data["spline_basis"]) if "spline_basis" in data else None
            return cls(tuple(data["names"]), data["values"], data["lower"], data["upper"], basis)
        except KeyError as exc:
            raise ModelError(f"joint residual: missing key {exc.args[0]!r}") from None
        except (TypeError, ValueError) as exc:
            raise ModelError(f"joint residual: malformed entry: {exc}") from None
