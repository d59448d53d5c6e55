"""The residual error field: lattice detection, the lattice interpolators, one entry point.

The calibration run measures the error at the vertices of a regular,
axis-aligned lattice (docs/method.md). :func:`detect_lattice` recovers that lattice
from scattered commanded positions with a tolerance; :class:`ResidualGrid`
holds one error vector per node and interpolates it inside the grid box with

- ``idw8``: the paper's eqs. 2-4, inverse-distance weights over the 8
  vertices of the cell that contains the target, distances taken to the
  measured vertex coordinates when they are known (a target within
  :data:`VERTEX_HIT` of a vertex takes that vertex's value);
- ``trilinear``: standard trilinear interpolation on the nominal lattice.

:func:`fit_field` builds any residual field by name (the two above, or the
scattered ``knn`` and ``rbf`` of :mod:`trajcomp.model.interpolate`) and
:func:`field_from_dict` reads any of them back. All lengths are millimetres.
"""

import dataclasses

import numpy as np

from trajcomp.errors import CalibrationError, ModelError
from trajcomp.model.interpolate import KNN, RBF, GaussianField, Kriging, VERTEX_HIT, bounded_evaluate, fmt_point, in_box
from trajcomp.model.options import FIELD_KINDS as KINDS, LATTICE_KINDS
from trajcomp.model.stats import AXES, as_vectors

TOLERANCE = 0.5
"""Default lattice tolerance, mm: largest distance per axis of a point from its node."""
_CORNERS = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])


@dataclasses.dataclass(frozen=True, eq=False)
class Lattice:
    """A regular axis-aligned lattice of nodes ``origin + (i, j, k) * step``.

    Attributes
    ----------
    origin : ndarray, shape (3,)
        Node (0, 0, 0), mm.
    step : ndarray, shape (3,)
        Node spacing per axis, mm, positive.
    shape : tuple of 3 int
        Node counts ``(nx, ny, nz)``, each at least 2.
    """

    origin: np.ndarray
    step: np.ndarray
    shape: tuple

    def __post_init__(self):
        origin = np.asarray(self.origin, dtype=float).reshape(3)
        step = np.asarray(self.step, dtype=float).reshape(3)
        shape = tuple(int(n) for n in np.asarray(self.shape).reshape(3))
        if not (np.isfinite(origin).all() and np.isfinite(step).all() and (step > 0).all()):
            raise ModelError(f"lattice: origin {origin.tolist()} and step {step.tolist()} must be finite, step > 0")
        if min(shape) < 2:
            raise ModelError(f"lattice: shape {shape} needs at least 2 nodes on each axis")
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "step", step)
        object.__setattr__(self, "shape", shape)

    @property
    def upper(self):
        """Last node (far corner of the grid box), mm, shape (3,)."""
        return self.origin + (np.array(self.shape) - 1) * self.step

    def nodes(self):
        """Nominal node positions, mm, shape (nx, ny, nz, 3)."""
        axes = [self.origin[a] + self.step[a] * np.arange(self.shape[a]) for a in range(3)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    def locate(self, points):
        """Cell and local coordinates of points inside the grid box.

        Parameters
        ----------
        points : ndarray, shape (N, 3)
            Points inside the box (faces, edges and the upper boundary
            included), mm.

        Returns
        -------
        cell : ndarray of int, shape (N, 3)
            Index of the cell's lower vertex, in ``0 .. shape - 2``.
        local : ndarray, shape (N, 3)
            Position inside the cell, each in [0, 1].
        """
        u = (points - self.origin) / self.step
        cell = np.clip(np.floor(u).astype(int), 0, np.array(self.shape) - 2)
        return cell, np.clip(u - cell, 0.0, 1.0)


def detect_lattice(points, tol=TOLERANCE, step=None):
    """Detect the regular axis-aligned lattice that scattered points lie on.

    Per axis, coordinates closer than ``tol`` chain into one node plane; the
    planes must be at least ``8 * tol`` apart and spaced by integer multiples
    of one step (a missing plane is allowed, it shows as missing nodes); the
    lattice is then fitted by least squares and every point must lie within
    ``tol`` of its node.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Commanded positions, mm.
    tol : float, optional
        Largest distance per axis of a point from its node, mm.
    step : float or array_like of 3 floats, optional
        Expected step, mm; the detected one must match it within ``tol``.

    Returns
    -------
    lattice : Lattice
    index : ndarray of int, shape (N, 3)
        Node index of each point (several points may share a node, and
        nodes may have no point: see :func:`node_counts`).

    Raises
    ------
    CalibrationError
        Naming the axis and the number of points when fewer than 2 node
        planes are found, the coordinates spread continuously or the planes
        lie closer than ``8 * tol`` (not a lattice), the planes are not
        evenly spaced, a point is off its node, or the step is not the
        expected one.
    """
    p = as_vectors(points, "grid points")
    if not tol > 0:
        raise ValueError(f"lattice tolerance must be positive, got {tol}")
    expected = None if step is None else np.broadcast_to(np.asarray(step, dtype=float), (3,))
    n = len(p)
    origin, spacing, shape, index = np.empty(3), np.empty(3), [0, 0, 0], np.empty((n, 3), dtype=int)
    for a, axis in enumerate(AXES):
        c = p[:, a]
        s = np.sort(c)
        starts = np.concatenate([[0], np.flatnonzero(np.diff(s) > tol) + 1])
        lo, hi = np.minimum.reduceat(s, starts), np.maximum.reduceat(s, starts)
        if len(starts) < 2:
            raise CalibrationError(
                f"cannot detect a grid: all {n} points have {axis} within {s[0]:.3f}..{s[-1]:.3f} mm; "
                f"a grid needs at least 2 node planes along {axis}"
            )
        wide = np.argmax(hi - lo)
        if hi[wide] - lo[wide] > 2 * tol:
            raise CalibrationError(
                f"{n} points do not lie on a regular grid: their {axis} coordinates spread continuously "
                f"over {lo[wide]:.3f}..{hi[wide]:.3f} mm (tolerance {tol} mm); use a scattered interpolator"
            )
        centers = np.add.reduceat(s, starts) / np.diff(np.append(starts, n))
        gaps = np.diff(centers)
        if gaps.min() < 8 * tol:
            raise CalibrationError(
                f"{n} points do not lie on a regular grid: node planes along {axis} are only "
                f"{gaps.min():.3f} mm apart, less than 8x the tolerance {tol} mm; use a scattered interpolator"
            )
        multiple = np.round(gaps / gaps.min())
        if np.any(np.abs(gaps - multiple * gaps.min()) > 2 * tol):
            raise CalibrationError(
                f"{n} points: node planes along {axis} are not evenly spaced: gaps "
                + ", ".join(f"{g:.3f}" for g in gaps)
                + f" mm (tolerance {tol} mm)"
            )
        k = np.concatenate([[0], np.cumsum(multiple)])
        spacing[a], origin[a] = np.polyfit(k, centers, 1)
        index[:, a] = np.round((c - origin[a]) / spacing[a]).astype(int)
        shape[a] = int(k[-1]) + 1
        off = np.abs(c - (origin[a] + index[:, a] * spacing[a]))
        if off.max() > tol:
            worst = int(np.argmax(off))
            raise CalibrationError(
                f"point {worst} at {fmt_point(p[worst])} mm is {off[worst]:.3f} mm off the nearest grid node "
                f"along {axis} (tolerance {tol} mm; {n} points)"
            )
    if expected is not None and np.any(np.abs(spacing - expected) > tol):
        axis = AXES[int(np.argmax(np.abs(spacing - expected)))]
        raise CalibrationError(
            f"{n} points: detected grid step {fmt_point(spacing)} mm differs from the expected "
            f"{fmt_point(expected)} mm along {axis} (tolerance {tol} mm)"
        )
    return Lattice(origin, spacing, tuple(shape)), index


def node_counts(lattice, index):
    """Number of points on each node, int array of shape (nx, ny, nz)."""
    flat = np.ravel_multi_index(index.T, lattice.shape)
    return np.bincount(flat, minlength=np.prod(lattice.shape)).reshape(lattice.shape)


def _node_means(lattice, index, data, weights):
    """Per-node weighted average of per-point data (N, 3) -> (nx, ny, nz, 3); every node must have weight."""
    flat = np.ravel_multi_index(index.T, lattice.shape)
    size = int(np.prod(lattice.shape))
    sums = np.stack([np.bincount(flat, weights=weights * data[:, c], minlength=size) for c in range(3)], axis=-1)
    return (sums / np.bincount(flat, weights=weights, minlength=size)[:, None]).reshape(*lattice.shape, 3)


@dataclasses.dataclass(frozen=True, eq=False)
class ResidualGrid:
    """Residual error vectors on the nodes of a lattice, with interpolation.

    Attributes
    ----------
    lattice : Lattice
    values : ndarray, shape (nx, ny, nz, 3)
        Residual error (measured - predicted) at each node, mm.
    nodes : ndarray, shape (nx, ny, nz, 3), or None
        Measured vertex coordinates, mm, for the paper's ``idw8`` distances;
        None uses the nominal lattice nodes.
    method : {'idw8', 'trilinear'}
        Default interpolation method.
    """

    lattice: Lattice
    values: np.ndarray
    nodes: np.ndarray = None
    method: str = "idw8"

    def __post_init__(self):
        want = (*self.lattice.shape, 3)
        for name in ("values", "nodes"):
            arr = getattr(self, name)
            if arr is None:
                continue
            arr = np.asarray(arr, dtype=float)
            if arr.shape != want or not np.isfinite(arr).all():
                raise ModelError(f"residual grid: {name} must be finite with shape {want}, got shape {arr.shape}")
            object.__setattr__(self, name, arr)
        if self.method not in LATTICE_KINDS:
            raise ModelError(f"residual grid: unknown method {self.method!r} (one of {', '.join(LATTICE_KINDS)})")

    @classmethod
    def from_points(cls, points, values, tol=TOLERANCE, method="idw8", measured=None, step=None, left_out=None):
        """Build a grid from errors measured at (approximately) lattice points.

        Parameters
        ----------
        points : array_like, shape (N, 3)
            Commanded positions, mm.
        values : array_like, shape (N, 3)
            Residual error at each point, mm. Repeated measurements of a node
            are averaged.
        tol : float, optional
            Lattice tolerance of :func:`detect_lattice`, mm.
        method : {'idw8', 'trilinear'}, optional
        measured : array_like, shape (N, 3), optional
            Measured positions; their per-node averages become the vertex
            coordinates used by ``idw8``.
        step : float or array_like of 3 floats, optional
            Expected lattice step, mm, see :func:`detect_lattice`.
        left_out : array_like of bool, shape (N,), optional
            Rows (outliers) whose values and measured positions come from a
            model, not a measurement: a node takes them only when it has no
            other row.

        Returns
        -------
        ResidualGrid

        Raises
        ------
        CalibrationError
            On bad input, no lattice or not the expected step (see
            :func:`detect_lattice`) or nodes without a measurement (naming how many and the first one).
        """
        p = as_vectors(points, "grid points")
        v = as_vectors(values, "grid residuals")
        m = None if measured is None else as_vectors(measured, "measured grid points")
        if len(v) != len(p) or (m is not None and len(m) != len(p)):
            extra = "" if m is None else f" and {len(m)} measured points"
            raise CalibrationError(f"grid: {len(p)} points but {len(v)} residuals{extra}")
        lattice, index = detect_lattice(p, tol, step)
        counts = node_counts(lattice, index)
        if (counts == 0).any():
            missing = np.argwhere(counts == 0)
            first = missing[0]
            size = "x".join(str(s) for s in lattice.shape)
            raise CalibrationError(
                f"grid {size} (step {fmt_point(lattice.step)} mm): {len(missing)} of {counts.size} nodes "
                f"have no measurement, first node {tuple(first.tolist())} at "
                f"{fmt_point(lattice.origin + first * lattice.step)} mm; measure them or use a scattered interpolator"
            )
        weights = np.ones(len(p)) if left_out is None else (~np.asarray(left_out, dtype=bool)).astype(float)
        flat = np.ravel_multi_index(index.T, lattice.shape)
        empty = np.bincount(flat, weights=weights, minlength=counts.size) == 0
        weights[empty[flat]] = 1.0  # a node with only left-out rows takes their model values
        nodes = None if m is None else _node_means(lattice, index, m, weights)
        return cls(lattice, _node_means(lattice, index, v, weights), nodes, method)

    @property
    def node_positions(self):
        """Vertex coordinates used by ``idw8``: measured if known, else nominal, (nx, ny, nz, 3) mm."""
        return self.lattice.nodes() if self.nodes is None else self.nodes

    def contains(self, points):
        """Boolean mask (N,) of points inside the grid box (boundary included)."""
        p = as_vectors(points, "query points", error=ModelError)
        return in_box(p, self.lattice.origin, self.lattice.upper)

    def evaluate(self, points, method=None, outside="error"):
        """Interpolated residual error at query points.

        Parameters
        ----------
        points : array_like, shape (N, 3)
            Query positions, mm.
        method : {'idw8', 'trilinear'}, optional
            Defaults to the grid's own method.
        outside : {'error', 'clamp', 'nan'}, optional
            Policy for points outside the grid box, see :func:`bounded_evaluate`.

        Returns
        -------
        ndarray, shape (N, 3)
            Residual error, mm.

        Raises
        ------
        ModelError
            On a point outside the box with ``outside='error'``, or an
            unknown method.
        """
        method = self.method if method is None else method
        if method not in LATTICE_KINDS:
            raise ModelError(f"unknown grid interpolation method {method!r} (one of {', '.join(LATTICE_KINDS)})")
        p = as_vectors(points, "query points", error=ModelError)
        kernel = self._idw8 if method == "idw8" else self._trilinear
        return bounded_evaluate(kernel, p, self.lattice.origin, self.lattice.upper, outside)

    def _corners(self, points):
        """Flat node indices (N, 8) of the corners of each point's cell and its local coordinates (N, 3)."""
        cell, local = self.lattice.locate(points)
        _, ny, nz = self.lattice.shape
        strides = np.array([ny * nz, nz, 1])
        return (cell @ strides)[:, None] + _CORNERS @ strides, local

    def _idw8(self, points):
        corners, _ = self._corners(points)
        offsets = np.take(self.node_positions.reshape(-1, 3), corners, axis=0) - points[:, None, :]
        d = np.sqrt(np.einsum("nkc,nkc->nk", offsets, offsets))  # (N, 8), eq. 2
        hit = d < VERTEX_HIT
        w = 1.0 / np.where(hit, 1.0, d)
        on_vertex = np.flatnonzero(hit.any(axis=1))
        w[on_vertex] = hit[on_vertex] & (np.cumsum(hit[on_vertex], axis=1) == 1)  # the first vertex hit
        q = w / w.sum(axis=1, keepdims=True)  # eq. 3
        return np.einsum("nk,nkc->nc", q, self._corner_values(corners))  # eq. 4

    def _trilinear(self, points):
        corners, t = self._corners(points)
        w = np.prod(np.where(_CORNERS == 1, t[:, None, :], 1.0 - t[:, None, :]), axis=2)  # (N, 8)
        return np.einsum("nk,nkc->nc", w, self._corner_values(corners))

    def _corner_values(self, corners):
        """Node values (N, 8, 3) at flat node indices (N, 8)."""
        return np.take(self.values.reshape(-1, 3), corners, axis=0)

    def to_dict(self):
        """Plain-list dict for the model file: kind, method, origin, step, shape, values[, nodes]."""
        out = {
            "kind": "grid",
            "method": self.method,
            "origin": self.lattice.origin.tolist(),
            "step": self.lattice.step.tolist(),
            "shape": list(self.lattice.shape),
            "values": self.values.tolist(),
        }
        if self.nodes is not None:
            out["nodes"] = self.nodes.tolist()
        return out

    @classmethod
    def from_dict(cls, data):
        """Inverse of :meth:`to_dict`; arrays may be lists or ndarrays.

        Raises
        ------
        ModelError
            On a missing key or inconsistent shapes.
        """
        try:
            lattice = Lattice(data["origin"], data["step"], data["shape"])
            return cls(lattice, data["values"], data.get("nodes"), data.get("method", "idw8"))
        except KeyError as exc:
            raise ModelError(f"residual grid: missing key {exc.args[0]!r}") from None
        except (TypeError, ValueError) as exc:
            raise ModelError(f"residual grid: malformed entry: {exc}") from None


def fit_field(points, values, step=None, interpolation="idw8", **options):
    """Build a residual field of any kind from positions and residual errors.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Commanded positions, mm (on a lattice for ``idw8`` and ``trilinear``).
    values : array_like, shape (N, 3)
        Residual error at each position, mm.
    step : float or array_like of 3 floats, optional
        Expected lattice step, mm, see :func:`detect_lattice`; the
        scattered kinds have no lattice and need no step.
    interpolation : {'idw8', 'trilinear', 'knn', 'rbf', 'gp'}, optional
    **options
        ``idw8``/``trilinear``: ``tol``, ``measured`` of
        :meth:`ResidualGrid.from_points`; ``knn``: ``k``, ``power`` of
        :class:`~trajcomp.model.interpolate.KNN`; ``rbf``: the options of
        :meth:`~trajcomp.model.interpolate.RBF.fit`; ``gp``: ``length`` and
        ``nugget`` of :class:`~trajcomp.model.interpolate.GaussianField`
        (without a length: those of its ``fit``).

    Returns
    -------
    ResidualGrid, KNN, RBF or GaussianField
        Each with ``contains``, ``evaluate(points, method=None,
        outside='error')`` and ``to_dict``.

    Raises
    ------
    CalibrationError
        On bad data, no complete lattice for the lattice kinds, or a lattice
        step other than ``step``.
    ValueError
        On an unknown kind.
    """
    if interpolation == KNN.kind:
        return KNN(points, values, **options)
    if interpolation == RBF.kind:
        return RBF.fit(points, values, **options)
    if interpolation == GaussianField.kind:
        return GaussianField(points, values, **options) if "length" in options else GaussianField.fit(points, values,
                                                                                                      **options)
    if interpolation not in LATTICE_KINDS:
        raise ValueError(f"unknown interpolation {interpolation!r} (one of {', '.join(KINDS)})")
    return ResidualGrid.from_points(points, values, method=interpolation, step=step, **options)


def field_from_dict(data):
    """Rebuild any residual field from its ``to_dict()``; arrays may be lists or ndarrays.

    Raises
    ------
    ModelError
        On an unknown kind, a missing key or malformed arrays.
    """
    kind = data.get("kind")
    if kind == "grid":
        return ResidualGrid.from_dict(data)
    classes = {KNN.kind: KNN, RBF.kind: RBF, Kriging.kind: Kriging, GaussianField.kind: GaussianField}
    if kind not in classes:
        raise ModelError(f"residual field: unknown kind {kind!r} (one of grid, {', '.join(classes)})")
    try:
        return classes[kind](**{k: v for k, v in data.items() if k != "kind"})
    except (TypeError, CalibrationError) as exc:
        raise ModelError(f"residual field {kind}: {exc}") from None
