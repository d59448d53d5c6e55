"""The paper's indirect linear correction: per-axis linear fits of the error.

Each error component (dx, dy, dz) is fitted, by least squares, as an
intercept plus a linear function of a subset of the commanded coordinates
(x, y, z). The subset is chosen per error axis by an information criterion
that penalizes complexity (BIC by default, AIC on request): the paper's arm
showed dx ~ y, dy ~ x, dz ~ x, and the selection recovers such relations
without fitting noise with irrelevant regressors. Lengths in mm; slopes are
mm of error per mm of commanded coordinate.
"""

import dataclasses
import itertools

import numpy as np

from trajcomp.errors import CalibrationError, ModelError
from trajcomp.model.stats import AXES, as_vectors

ERRORS = ("dx", "dy", "dz")
CRITERIA = ("bic", "aic")
_SUBSETS = [s for size in range(4) for s in itertools.combinations(range(3), size)]  # smallest first
_RSS_FLOOR = 1e-18
"""Residual mean square floor, mm^2 (1e-9 mm RMS): an exact fit must not score -inf."""


@dataclasses.dataclass(frozen=True, eq=False)
class LinearCorrection:
    """Linear error model ``e = c0 + cx*x + cy*y + cz*z`` per error axis.

    Attributes
    ----------
    coefficients : ndarray, shape (3, 4)
        Rows dx, dy, dz; columns intercept (mm), then the slopes for x, y, z
        (mm/mm), zero for regressors not chosen.
    regressors : tuple of 3 tuples of str
        Chosen regressors per error axis, e.g. ``(("y",), ("x",), ("x",))``.
    r2 : tuple of 3 float
        Coefficient of determination of each fit (1 when the error is
        constant and fully explained by the intercept).
    criterion : str
        The selection criterion used, ``'bic'`` or ``'aic'``.
    """

    coefficients: np.ndarray
    regressors: tuple
    r2: tuple
    criterion: str = "bic"

    def __post_init__(self):
        coefficients = np.asarray(self.coefficients, dtype=float)
        if coefficients.shape != (3, 4) or not np.isfinite(coefficients).all():
            raise ModelError(
                f"linear correction: coefficients must be finite with shape (3, 4), got shape {coefficients.shape}"
            )
        regressors = tuple(tuple(r) for r in self.regressors)
        if len(regressors) != 3 or any(name not in AXES for r in regressors for name in r):
            raise ModelError(f"linear correction: regressors must be 3 lists of x, y, z, got {regressors}")
        object.__setattr__(self, "coefficients", coefficients)
        object.__setattr__(self, "regressors", regressors)
        object.__setattr__(self, "r2", tuple(float(v) for v in self.r2))

    def predict_error(self, points):
        """Predicted error at commanded positions.

        Parameters
        ----------
        points : array_like, shape (N, 3)
            Commanded positions, mm.

        Returns
        -------
        ndarray, shape (N, 3)
            Predicted error (measured - commanded), mm.
        """
        p = as_vectors(points, "commanded positions", error=ModelError)
        return self.coefficients[:, 0] + p @ self.coefficients[:, 1:].T

    def describe(self):
        """One line per error axis, e.g. ``dx = 0.0021*y - 0.35 (R^2 0.930)``."""
        lines = []
        for name, coef, chosen, r2 in zip(ERRORS, self.coefficients, self.regressors, self.r2):
            terms = [(coef[1 + AXES.index(axis)], f"*{axis}") for axis in chosen] + [(coef[0], "")]
            text = f"{terms[0][0]:.6g}{terms[0][1]}" + "".join(
                f" {'-' if c < 0 else '+'} {abs(c):.6g}{suffix}" for c, suffix in terms[1:]
            )
            lines.append(f"{name} = {text} (R^2 {r2:.3f})")
        return "\n".join(lines)

    def to_dict(self):
        """Plain dict for the model file: per error axis its intercept, chosen slopes and R^2."""
        out = {"criterion": self.criterion}
        for name, coef, chosen, r2 in zip(ERRORS, self.coefficients, self.regressors, self.r2):
            slopes = {axis: float(coef[1 + AXES.index(axis)]) for axis in chosen}
            out[name] = {"intercept": float(coef[0]), "slopes": slopes, "r2": r2}
        return out

    @classmethod
    def from_dict(cls, data):
        """Inverse of :meth:`to_dict`.

        Raises
        ------
        ModelError
            On a missing key, an unknown regressor or a non-numeric value.
        """
        try:
            coefficients = np.zeros((3, 4))
            regressors, r2 = [], []
            for row, name in enumerate(ERRORS):
                entry = data[name]
                slopes = entry["slopes"]
                unknown = set(slopes) - set(AXES)
                if unknown:
                    raise ModelError(f"linear correction {name}: unknown regressor(s) {sorted(unknown)}")
                coefficients[row, 0] = entry["intercept"]
                for axis, value in slopes.items():
                    coefficients[row, 1 + AXES.index(axis)] = value
                regressors.append(tuple(a for a in AXES if a in slopes))
                r2.append(float(entry["r2"]))
            return cls(coefficients, tuple(regressors), tuple(r2), data.get("criterion", "bic"))
        except KeyError as exc:
            raise ModelError(f"linear correction: missing key {exc.args[0]!r}") from None
        except (TypeError, ValueError, AttributeError) as exc:
            raise ModelError(f"linear correction: malformed entry: {exc}") from None


def fit_linear(points, errors, criterion="bic"):
    """Fit the indirect linear correction, choosing the regressors per error axis.

    For every subset of {x, y, z} (plus an intercept) whose design matrix
    has full rank, each error axis is fitted by least squares and scored by
    ``n log(RSS/n) + k log n`` (BIC) or ``+ 2k`` (AIC), with k parameters;
    the lowest score wins, ties going to the smaller subset.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Commanded positions, mm.
    errors : array_like, shape (N, 3)
        Errors measured - commanded, mm.
    criterion : {'bic', 'aic'}, optional

    Returns
    -------
    LinearCorrection

    Raises
    ------
    CalibrationError
        On fewer than 5 points (4 parameters + 1), mismatched lengths or a
        non-finite value.
    ValueError
        On an unknown criterion.
    """
    if criterion not in CRITERIA:
        raise ValueError(f"unknown selection criterion {criterion!r} (one of {', '.join(CRITERIA)})")
    p = as_vectors(points, "commanded positions")
    e = as_vectors(errors, "errors")
    n = len(p)
    if len(e) != n:
        raise CalibrationError(f"linear correction: {n} positions but {len(e)} errors")
    if n < 5:
        raise CalibrationError(f"linear correction: {n} points, need at least 5 (4 parameters + 1)")
    penalty = np.log(n) if criterion == "bic" else 2.0
    best_score = np.full(3, np.inf)
    coefficients = np.zeros((3, 4))
    regressors = [()] * 3
    rss_best = np.zeros(3)
    for subset in _SUBSETS:
        design = np.column_stack([np.ones(n), p[:, subset]])
        coef, _, rank, _ = np.linalg.lstsq(design, e, rcond=None)
        if rank < design.shape[1]:
            continue  # a coordinate constant over the data: not identifiable
        rss = np.sum((e - design @ coef) ** 2, axis=0)
        score = n * np.log(np.maximum(rss / n, _RSS_FLOOR)) + design.shape[1] * penalty
        better = score < best_score
        for axis in np.flatnonzero(better):
            coefficients[axis] = 0.0
            coefficients[axis, [0, *(1 + a for a in subset)]] = coef[:, axis]
            regressors[axis] = tuple(AXES[a] for a in subset)
        best_score = np.where(better, score, best_score)
        rss_best = np.where(better, rss, rss_best)
    tss = np.sum((e - e.mean(axis=0)) ** 2, axis=0)
    r2 = np.where(tss > 0, 1.0 - rss_best / np.where(tss > 0, tss, 1.0), 1.0)
    return LinearCorrection(coefficients, tuple(regressors), tuple(r2), criterion)
