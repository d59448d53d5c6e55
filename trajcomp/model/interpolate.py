"""Interpolation of scattered residuals, and the domain policy of every residual field.

A residual field maps positions (N, 3) mm to residual errors (N, 3) mm. The
lattice fields (``idw8``, ``trilinear``) live in :mod:`trajcomp.model.grid`; this
module holds the fields of scattered data, which need no lattice:

- :class:`KNN` (``knn``): inverse-distance weighting over the k nearest
  measured points;
- :class:`RBF` (``rbf``): a smoothing radial basis function fit (thin-plate
  spline by default), its smoothing chosen by k-fold cross-validation unless
  given;
- :class:`Kriging` (``kriging``): the mean of a Gaussian process of a few
  scattered residuals (a light re-calibration's correction, see
  `trajcomp.calibration.recalibrate`), its length and noise chosen by
  maximum likelihood; it returns to zero away from its points;
- :class:`GaussianField` (``gp``): the same process, of the position and the
  wrist angles together, as calibrate's field on top of a joint residual
  (`trajcomp.calibration.calibrate`), a kind of its own so that no one takes
  it for a re-calibration's correction.

The domain of the first two is the bounding box of the data;
:func:`bounded_evaluate` applies the same outside policy as the lattice
fields. Kriging's is all space: far from its points it adds nothing.
"""

import dataclasses

import numpy as np

from trajcomp.errors import CalibrationError, ModelError
from trajcomp.model.options import GP_KIND, KNN_KIND, KRIGING_KIND, RBF_KIND
from trajcomp.model.stats import as_vectors, kfold_indices

OUTSIDE = ("error", "clamp", "nan")
VERTEX_HIT = 1e-6
"""Distance (mm) under which a query counts as coinciding with a data point or vertex."""
SMOOTHING_CANDIDATES = (0.0, *(10.0**e for e in range(-6, 1)))
"""Smoothing values tried by cross-validation (coordinates scaled to the unit box)."""
KRIGING_LENGTHS = (100.0, 150.0, 200.0, 300.0, 400.0, 600.0, 800.0)
"""Correlation lengths (mm) `Kriging.fit` tries: a tenth to most of an arm's reach."""
KRIGING_NUGGETS = (0.03, 0.1, 0.2, 0.3, 0.5, 1.0, 2.0)
"""Noise-to-signal variance ratios `Kriging.fit` tries."""
LIKELIHOOD_POINTS = 300
"""Most points whose likelihood `Kriging.fit` compares (every k-th of more)."""
WRIST = slice(3, 6)
"""The joints (4-6, 0-based 3-5) whose angles a `GaussianField` may correlate over: they turn the tool at a position."""
BLOCK_ELEMENTS = 2_000_000
"""Most correlations (floats, 16 MB) `Kriging.evaluate` holds at once."""


def fmt_point(point):
    """``(x.xxx, y.yyy, z.zzz)`` for messages."""
    return "(" + ", ".join(f"{v:.3f}" for v in point) + ")"


def in_box(points, lower, upper):
    """Boolean mask (N,) of points (N, 3) inside the box ``lower..upper`` (boundary included, mm)."""
    slack = 1e-9 * (1.0 + np.abs(upper - lower))
    return np.all((points >= lower - slack) & (points <= upper + slack), axis=1)


def bounded_evaluate(kernel, points, lower, upper, outside):
    """Evaluate ``kernel`` on points with a policy for points outside a box.

    Parameters
    ----------
    kernel : callable
        ``kernel(points (N, 3)) -> (N, 3)``, valid inside the box.
    points : ndarray, shape (N, 3)
        Query points, mm.
    lower, upper : ndarray, shape (3,)
        Corners of the box, mm.
    outside : {'error', 'clamp', 'nan'}
        ``'error'`` raises on the first outside point; ``'clamp'`` evaluates
        at the nearest point of the box; ``'nan'`` returns NaN rows there (so
        the caller can fall back to the model-only value and flag them).

    Returns
    -------
    ndarray, shape (N, 3)

    Raises
    ------
    ModelError
        With ``outside='error'``, naming the first outside point and the box.
    ValueError
        On an unknown policy.
    """
    if outside not in OUTSIDE:
        raise ValueError(f"outside policy {outside!r}: expected one of {', '.join(OUTSIDE)}")
    inside = in_box(points, lower, upper)
    if outside == "error" and not inside.all():
        first = int(np.flatnonzero(~inside)[0])
        raise ModelError(
            f"point {first} at {fmt_point(points[first])} mm lies outside the residual field's box "
            f"{fmt_point(lower)}..{fmt_point(upper)} mm ({int((~inside).sum())} of {len(points)} points outside)"
        )
    values = kernel(np.clip(points, lower, upper))
    if outside == "nan":
        values[~inside] = np.nan
    return values


def _scattered_data(points, values):
    p = as_vectors(points, "scattered points")
    v = as_vectors(values, "scattered residuals")
    if len(p) != len(v):
        raise CalibrationError(f"scattered data: {len(p)} points but {len(v)} residuals")
    return p, v


@dataclasses.dataclass(frozen=True, eq=False)
class _Scattered:
    """Shared behaviour of interpolators of scattered data (points, values in mm)."""

    points: np.ndarray
    values: np.ndarray

    @property
    def lower(self):
        """Lower corner of the data's bounding box, mm, shape (3,)."""
        return self.points.min(axis=0)

    @property
    def upper(self):
        """Upper corner of the data's bounding box, mm, shape (3,)."""
        return self.points.max(axis=0)

    def contains(self, points):
        """Boolean mask (N,) of points inside the data's bounding box."""
        return in_box(as_vectors(points, "query points", error=ModelError), self.lower, self.upper)

    def evaluate(self, points, method=None, outside="error"):
        """Interpolated residual error at query points.

        Parameters
        ----------
        points : array_like, shape (N, 3)
            Query positions, mm.
        method : str, optional
            None or the field's own ``kind`` (for a call shared with the
            lattice fields, whose method can be switched).
        outside : {'error', 'clamp', 'nan'}, optional
            Policy for points outside the data's bounding box, see
            :func:`bounded_evaluate`.

        Returns
        -------
        ndarray, shape (N, 3)
            Residual error, mm.
        """
        self._check_method(method)
        p = as_vectors(points, "query points", error=ModelError)
        return bounded_evaluate(self._kernel, p, self.lower, self.upper, outside)

    def _check_method(self, method):
        if method not in (None, self.kind):
            raise ModelError(f"a {self.kind} residual field cannot be evaluated by {method!r}")

    def _fields(self):
        return {"kind": self.kind, "points": self.points.tolist(), "values": self.values.tolist()}


@dataclasses.dataclass(frozen=True, eq=False)
class KNN(_Scattered):
    """Inverse-distance weighting over the ``k`` nearest data points.

    Weights ``1 / d**power`` normalized to one; a query within
    :data:`~trajcomp.model.grid.VERTEX_HIT` of a data point takes its value.

    Attributes
    ----------
    points, values : ndarray, shape (N, 3)
        Data positions and residual errors, mm.
    k : int
        Number of neighbours, ``1 <= k <= N``.
    power : float
        Distance exponent, e.g. 1 (the paper's weights) or 2 (Shepard).
    """

    k: int = 8
    power: float = 1.0
    kind = KNN_KIND

    def __post_init__(self):
        p, v = _scattered_data(self.points, self.values)
        if not 1 <= self.k <= len(p):
            raise CalibrationError(f"knn: k={self.k} neighbours requested but {len(p)} data points")
        if not self.power > 0:
            raise CalibrationError(f"knn: power must be positive, got {self.power}")
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "values", v)
        from scipy.spatial import cKDTree  # here: compensating with a grid never needs scipy

        object.__setattr__(self, "_tree", cKDTree(p))

    def _kernel(self, points):
        d, idx = self._tree.query(points, k=self.k)
        d, idx = d.reshape(len(points), self.k), idx.reshape(len(points), self.k)
        hit = d < VERTEX_HIT  # neighbours come sorted: a hit is in column 0
        w = np.where(hit[:, :1], hit[:, :1] & (np.arange(self.k) == 0), 1.0 / np.where(hit, 1.0, d) ** self.power)
        return np.einsum("nk,nkc->nc", w / w.sum(axis=1, keepdims=True), self.values[idx])

    def to_dict(self):
        """Plain-list dict: kind, points, values, k, power."""
        return {**self._fields(), "k": self.k, "power": self.power}


def _unit_box(points):
    """Centre (3,) and half largest side of the bounding box of points (N, 3)."""
    lower, upper = points.min(axis=0), points.max(axis=0)
    return 0.5 * (lower + upper), 0.5 * max(float(np.max(upper - lower)), 1e-9)


def _rbf_solve(x, values, smoothing, **options):
    """scipy RBFInterpolator of scaled points x (N, 3), CalibrationError when it cannot be solved."""
    from scipy.interpolate import RBFInterpolator  # here: compensating with a grid never needs scipy

    try:
        return RBFInterpolator(x, values, smoothing=smoothing, **options)
    except (ValueError, np.linalg.LinAlgError) as exc:
        raise CalibrationError(f"rbf fit of {len(x)} points (smoothing {smoothing}): {exc}") from None


@dataclasses.dataclass(frozen=True, eq=False)
class RBF(_Scattered):
    """Smoothing radial basis function fit of scattered residuals.

    Coordinates are scaled to the unit box (centre of the data's bounding
    box, half its largest side) before the fit, so ``smoothing`` and
    ``epsilon`` do not depend on the size of the workspace. Build with
    :meth:`fit` to choose the smoothing by cross-validation.

    Attributes
    ----------
    points, values : ndarray, shape (N, 3)
        Data positions and residual errors, mm.
    smoothing : float
        scipy's ``RBFInterpolator`` smoothing, >= 0 (0 interpolates exactly).
    kernel : str
        scipy kernel name, default ``'thin_plate_spline'``.
    epsilon : float or None
        Shape parameter in scaled units (required by scipy for kernels
        other than the polyharmonic splines).
    neighbors : int or None
        Fit only the nearest ``neighbors`` points per query (large data).
    """

    smoothing: float = 0.0
    kernel: str = "thin_plate_spline"
    epsilon: float = None
    neighbors: int = None
    kind = RBF_KIND

    def __post_init__(self):
        p, v = _scattered_data(self.points, self.values)
        centre, half = _unit_box(p)
        rbf = _rbf_solve((p - centre) / half, v, self.smoothing, **self._options())
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "values", v)
        object.__setattr__(self, "_kernel", lambda q: rbf((q - centre) / half))

    def _options(self):
        return {"kernel": self.kernel, "epsilon": self.epsilon, "neighbors": self.neighbors}

    @classmethod
    def fit(cls, points, values, smoothing=None, folds=5, seed=0, **options):
        """Fit, choosing the smoothing by k-fold cross-validation when not given.

        Parameters
        ----------
        points, values : array_like, shape (N, 3)
            Data positions and residual errors, mm.
        smoothing : float, optional
            Fixed smoothing; by default the candidate of
            :data:`SMOOTHING_CANDIDATES` with the least cross-validated mean
            squared error norm.
        folds, seed : int, optional
            Cross-validation folds and shuffle seed.
        **options
            ``kernel``, ``epsilon``, ``neighbors`` of :class:`RBF`.

        Returns
        -------
        RBF
        """
        p, v = _scattered_data(points, values)
        if smoothing is None:
            centre, half = _unit_box(p)
            x = (p - centre) / half
            splits = kfold_indices(len(p), folds, seed)
            scores = [_cv_score(x, v, splits, s, options) for s in SMOOTHING_CANDIDATES]
            smoothing = SMOOTHING_CANDIDATES[int(np.argmin(scores))]
        return cls(p, v, smoothing=smoothing, **options)

    def to_dict(self):
        """Plain-list dict: kind, points, values, smoothing, kernel, epsilon, neighbors."""
        return {**self._fields(), "smoothing": self.smoothing, **self._options()}


def _cv_score(x, values, splits, smoothing, options):
    """Mean squared held-out error norm of an RBF fit (inf when a fold cannot be solved)."""
    total = 0.0
    for train, test in splits:
        try:
            rbf = _rbf_solve(x[train], values[train], smoothing, **options)
        except CalibrationError:
            return np.inf
        total += np.sum((rbf(x[test]) - values[test]) ** 2)
    return total / len(x)


def _squared_distances(a, b):
    """Squared distances (N, M) between points a (N, D) and b (M, D) (mm^2 for positions in mm)."""
    return np.maximum(np.sum(a**2, axis=1)[:, None] + np.sum(b**2, axis=1)[None, :] - 2.0 * a @ b.T, 0.0)


def _log_likelihood(factor, whitened):
    """Log marginal likelihood of values under a Gaussian process, each axis's variance at its maximum, from the
    Cholesky factor (N, N) of their correlation (nugget included) and the values whitened by it (N, 3)."""
    count = len(factor)
    variance = np.sum(whitened**2, axis=0) / count
    return float(-0.5 * np.sum(count * np.log(variance) + 2.0 * np.sum(np.log(np.diag(factor))) + count))


def _unit_correlation(a, b):
    """Squared-exponential correlation (N, M) of points a (N, D) and b (M, D) given in units of its lengths."""
    return np.exp(-0.5 * _squared_distances(a, b))


@dataclasses.dataclass(frozen=True, eq=False)
class Kriging(_Scattered):
    """Gaussian-process mean (simple kriging, zero prior mean) of residuals at a few scattered points.

    Each axis of the residual is a zero-mean Gaussian process of the
    position with covariance ``variance * (exp(-d^2 / (2 length^2)) +
    nugget * [d = 0])``: near a point the field follows the residuals seen
    there (less the nugget's share, measurement noise), between points it
    blends them, and beyond a few ``length`` from every point it returns to
    zero: it never extrapolates a shape the points did not show, so it is
    defined everywhere (`contains` is all true). Build with `fit` to choose
    ``length`` and ``nugget`` by maximum likelihood.

    Attributes
    ----------
    points, values : ndarray, shape (N, 3)
        Data positions and residual errors, mm.
    length : float
        Correlation length, mm (> 0).
    nugget : float
        Noise variance as a fraction of the signal variance (> 0).
    """

    length: float = 400.0
    nugget: float = 0.3
    kind = KRIGING_KIND

    def __post_init__(self):
        p, v = _scattered_data(self.points, self.values)
        if not (np.isfinite(self.length) and self.length > 0 and np.isfinite(self.nugget) and self.nugget > 0):
            raise CalibrationError(f"kriging: need length > 0 mm and nugget > 0, got {self.length}, {self.nugget}")
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "values", v)
        object.__setattr__(self, "length", float(self.length))
        object.__setattr__(self, "nugget", float(self.nugget))
        from scipy.linalg import solve_triangular  # here: compensating with a grid never needs scipy

        data = self._coordinates(p, self._data_angles())
        factor = np.linalg.cholesky(_unit_correlation(data, data) + self.nugget * np.eye(len(p)))
        whitened = solve_triangular(factor, v, lower=True)
        object.__setattr__(self, "_data", data)
        object.__setattr__(self, "_factor", factor)
        object.__setattr__(self, "_whitened", whitened)
        object.__setattr__(self, "_weights", solve_triangular(factor.T, whitened, lower=False))

    def contains(self, points):
        """All true (N,): the field is defined everywhere (zero far from its points)."""
        return np.ones(len(as_vectors(points, "query points", error=ModelError)), bool)

    def _data_angles(self):
        """Wrist angles (N, 3) deg at the data points, or None (`GaussianField`'s; this process has none)."""
        return None

    def _coordinates(self, points, angles):
        """Points (N, 3) mm in units of the correlation length (N, 3); ``angles`` (a `GaussianField`'s) unused."""
        return points / self.length

    def _query(self, points, joints):
        """Scaled coordinates of query points (N, 3) mm and their commanded joints (N, 6) rad or None."""
        p = as_vectors(points, "query points", error=ModelError)
        return self._coordinates(p, None if joints is None else np.degrees(np.asarray(joints, float)[:, WRIST]))

    def evaluate(self, points, method=None, outside="error", joints=None):
        """The field (N, 3) mm at points (N, 3) mm; every point is inside (``outside`` is accepted, not needed).

        ``joints`` (N, 6) rad: the commanded joints at the points, which a
        `GaussianField` over the wrist angles needs (others ignore them).
        Computed in blocks of queries whose correlations with the data hold
        at most `BLOCK_ELEMENTS` floats (a long program against 2,000 points).
        """
        self._check_method(method)
        query = self._query(points, joints)
        out = np.empty((len(query), 3))
        block = max(1, BLOCK_ELEMENTS // len(self.points))
        for start in range(0, len(query), block):
            out[start:start + block] = _unit_correlation(query[start:start + block], self._data) @ self._weights
        return out

    def signal_variance(self):
        """Maximum-likelihood variance (3,) mm^2 of each axis's signal, given ``length`` and ``nugget``."""
        return np.sum(self._whitened**2, axis=0) / len(self.points)

    def variance(self, points, joints=None):
        """Posterior variance (N,) mm^2 per axis of the field's signal at points (N, 3), mm (mean of the axes).

        Zero at no point; the signal's variance far from every data point.
        ``joints`` as for `evaluate`.
        """
        from scipy.linalg import solve_triangular  # here: compensating with a grid never needs scipy

        solved = solve_triangular(self._factor, _unit_correlation(self._data, self._query(points, joints)), lower=True)
        return (1.0 - np.sum(solved**2, axis=0)) * float(self.signal_variance().mean())

    def log_likelihood(self):
        """Log marginal likelihood of the values under the process, its variances at their maximum."""
        return _log_likelihood(self._factor, self._whitened)

    @classmethod
    def fit(cls, points, values, lengths=KRIGING_LENGTHS, nuggets=KRIGING_NUGGETS):
        """The candidate ``length`` x ``nugget`` of the highest marginal likelihood (`log_likelihood`).

        Parameters
        ----------
        points, values : array_like, shape (N, 3)
            Data positions (N >= 2) and residual errors, mm.
        lengths : sequence of float
            Correlation lengths, mm: those at least twice the median
            distance from a point to its nearest neighbour are tried (at
            least the longest): a shorter correlation the points cannot
            tell from their noise, and the likelihood of a few points then
            takes it for the signal.
        nuggets : sequence of float
            Noise-to-signal variance ratios tried.

        The likelihood is that of at most `LIKELIHOOD_POINTS` of the points
        (every k-th: a factor's cost grows with the cube of the points); the
        field returned holds them all.

        Returns
        -------
        Kriging
        """
        return cls._most_likely(points, values, lengths, nuggets)

    @classmethod
    def _most_likely(cls, points, values, lengths, nuggets, angles=None, angle_lengths=(np.inf,)):
        """`fit` among ``lengths`` x ``nuggets`` x ``angle_lengths`` (deg) of the wrist ``angles`` (N, 3) deg at the
        points (a `GaussianField`'s; None: none), the squared distances of the likelihood's points computed once."""
        from scipy.linalg import solve_triangular  # here: compensating with a grid never needs scipy

        p, v = _scattered_data(points, values)
        gaps = np.sqrt(_squared_distances(p, p) + np.diag(np.full(len(p), np.inf)))
        spacing = float(np.median(gaps.min(axis=1)))
        lengths = [length for length in lengths if length >= 2.0 * spacing] or [max(lengths)]
        every = -(-len(p) // LIKELIHOOD_POINTS)
        sample, sampled = p[::every], v[::every]
        squares = _squared_distances(sample, sample)
        angle_squares = 0.0 if angles is None else _squared_distances(angles[::every], angles[::every])
        scores = {}
        for angle_length in angle_lengths:
            for length in lengths:
                correlation = np.exp(-0.5 * (squares / length**2 + angle_squares / angle_length**2))
                for nugget in nuggets:  # one candidate at a time: each holds an (N, N) factor
                    factor = np.linalg.cholesky(correlation + nugget * np.eye(len(sample)))
                    scores[angle_length, length, nugget] = _log_likelihood(
                        factor, solve_triangular(factor, sampled, lower=True))
        angle_length, length, nugget = max(scores, key=scores.get)
        wrist = {"angles": angles, "angle_length": angle_length} if np.isfinite(angle_length) else {}
        return cls(p, v, length=length, nugget=nugget, **wrist)

    def to_dict(self):
        """Plain-list dict: kind, points, values, length, nugget."""
        return {**self._fields(), "length": self.length, "nugget": self.nugget}


GP_MAX_POINTS = 3000
"""Most points a `GaussianField` is offered for: its factor holds (N, N) floats (72 MB at 3,000 points)."""
GP_NUGGETS = (0.01, *KRIGING_NUGGETS)
"""Noise-to-signal variance ratios `GaussianField.fit` tries: down to 0.01, where the likelihood of the UR5's held-out
slabs sat at the 0.03 bound of `KRIGING_NUGGETS` (it takes 0.01 there, and 0.01 again with 0.003 offered)."""
ANGLE_LENGTHS = (np.inf, 40.0, 80.0, 160.0)
"""Correlation lengths (deg) of the wrist angles `GaussianField.fit` tries with the commanded joints (inf: none)."""


@dataclasses.dataclass(frozen=True, eq=False)
class GaussianField(Kriging):
    """`Kriging` as the residual field a calibration puts on top of its joint residual.

    The same process, length and nugget (chosen by `Kriging.fit`'s maximum
    likelihood on the calibration's residuals, or given): between measured
    points it blends their residuals weighted by the process, not by
    distance alone (`KNN`), it smooths their noise by the nugget, and
    beyond a few lengths from every point it adds nothing instead of
    repeating the nearest residuals. A kind of its own: a model's
    ``kriging`` field is a re-calibration's correction, whose variance the
    landing estimate adds and which a later update replaces; this one is
    part of the calibrated model, its error in the calibration's held-out
    statistics. At most `GP_MAX_POINTS` points (calibrate offers no ``gp``
    beyond them).

    With the wrist angles of its points (``angles``, joints 4-6) and a
    finite ``angle_length``, the process is one of the position and the
    wrist together (a squared-exponential correlation with a length per
    group): rows at one position in other orientations are told apart, and
    the field is evaluated with the commanded joints. On the held-out
    regions of the real arms it predicts what the joint model leaves better
    than a field of the position alone (docs/benchmarks.md: UR5 slabs
    0.088 -> 0.075 mm, UR10 planes 0.107 -> 0.100 mm).

    Attributes
    ----------
    angles : ndarray, shape (N, 3), or None
        Commanded angles of joints 4-6 at the points, deg (None: a field of
        the position alone).
    angle_length : float
        Their correlation length, deg (inf: the angles are not used).
    """

    angles: np.ndarray = None
    angle_length: float = np.inf
    kind = GP_KIND

    def __post_init__(self):
        angle_length = float(self.angle_length)
        angles = None
        if np.isfinite(angle_length):
            angles = np.asarray(self.angles if self.angles is not None else np.zeros((0, 3)), dtype=float)
            if not (angle_length > 0 and angles.shape == (len(np.asarray(self.points)), 3)
                    and np.isfinite(angles).all()):
                raise CalibrationError(f"gp field: a wrist length of {angle_length} deg needs one finite triple of "
                                       f"angles (deg) per point and a length > 0, got angles of shape {angles.shape}")
        elif not np.isinf(angle_length) or angle_length < 0:
            raise CalibrationError(f"gp field: the wrist length must be > 0 deg or inf, got {angle_length}")
        object.__setattr__(self, "angles", angles)
        object.__setattr__(self, "angle_length", angle_length)
        super().__post_init__()

    @property
    def needs_joints(self):
        """True when the field depends on the commanded wrist angles (`evaluate` then needs ``joints``)."""
        return self.angles is not None

    def _data_angles(self):
        return self.angles

    def _coordinates(self, points, angles):
        """Points (N, 3) mm and wrist angles (N, 3) deg in units of their lengths (N, 3 or 6)."""
        if not self.needs_joints:
            return points / self.length
        if angles is None:
            raise ModelError("this gp field depends on the wrist angles: evaluate it with the commanded joints")
        return np.column_stack([points / self.length, angles / self.angle_length])

    @classmethod
    def fit(cls, points, values, lengths=KRIGING_LENGTHS, nuggets=GP_NUGGETS, joints=None,
            angle_lengths=ANGLE_LENGTHS):
        """`Kriging.fit`, and with the commanded joints (N, 6) rad each of ``angle_lengths`` (deg) of the wrist."""
        if joints is None:
            return cls._most_likely(points, values, lengths, nuggets)
        return cls._most_likely(points, values, lengths, nuggets, np.degrees(np.asarray(joints, float)[:, WRIST]),
                                angle_lengths)

    def to_dict(self):
        """Plain-list dict: kind, points, values, length, nugget, and the wrist's angles and length where used."""
        return super().to_dict() | ({"angles": self.angles.tolist(), "angle_length": self.angle_length}
                                    if self.needs_joints else {})
