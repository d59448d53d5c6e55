"""Error statistics (ISO 9283 style norms) and k-fold cross-validation splits.

Errors are vectors ``e = measured - commanded`` (or measured - predicted), in
millimetres. The headline numbers are norms of ``|e|``: mean, RMS, 95th
percentile and maximum; per-axis signed means and standard deviations are
reported beside them only, because signed means can cancel.
"""

import dataclasses

import numpy as np

from trajcomp.errors import CalibrationError

AXES = ("x", "y", "z")


def as_vectors(array, name, error=CalibrationError):
    """Validate an array of N 3-vectors.

    Parameters
    ----------
    array : array_like, shape (N, 3)
    name : str
        What the array holds, for messages (e.g. ``"commanded positions"``).
    error : type, optional
        Exception class raised on bad input.

    Returns
    -------
    ndarray, shape (N, 3), float

    Raises
    ------
    error
        On a wrong shape, no rows, or a non-finite value (naming the row).
    """
    arr = np.asarray(array, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise error(f"{name}: expected an array of shape (N, 3), got shape {arr.shape}")
    if len(arr) == 0:
        raise error(f"{name}: no rows")
    bad = ~np.isfinite(arr).all(axis=1)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise error(f"{name}: row {row} is not finite: {arr[row].tolist()} ({int(bad.sum())} such rows)")
    return arr


@dataclasses.dataclass(frozen=True)
class ErrorStats:
    """Summary of N error vectors, mm.

    Attributes
    ----------
    n : int
        Number of error vectors.
    mean, rms, p95, max : float
        Mean, root mean square, 95th percentile (linear interpolation between
        order statistics) and maximum of the error norms ``|e|``, mm.
    signed_mean : tuple of 3 float
        Per-axis mean of the signed components ``(dx, dy, dz)``, mm.
    std : tuple of 3 float
        Per-axis population standard deviation of the components, mm.
    """

    n: int
    mean: float
    rms: float
    p95: float
    max: float
    signed_mean: tuple
    std: tuple

    @classmethod
    def from_errors(cls, errors):
        """Statistics of error vectors.

        Parameters
        ----------
        errors : array_like, shape (N, 3)
            Error vectors, mm.

        Returns
        -------
        ErrorStats

        Raises
        ------
        CalibrationError
            On no rows, a wrong shape or a non-finite value.
        """
        e = as_vectors(errors, "error vectors")
        norm = np.linalg.norm(e, axis=1)
        return cls(
            n=len(e),
            mean=float(norm.mean()),
            rms=float(np.sqrt(np.mean(norm**2))),
            p95=float(np.percentile(norm, 95)),
            max=float(norm.max()),
            signed_mean=tuple(float(v) for v in e.mean(axis=0)),
            std=tuple(float(v) for v in e.std(axis=0)),
        )

    def as_dict(self):
        """Plain dict (floats and lists) for YAML reports and model files."""
        out = dataclasses.asdict(self)
        out["signed_mean"] = list(self.signed_mean)
        out["std"] = list(self.std)
        return out

    def summary(self):
        """One line: ``mean 0.123  rms 0.150  p95 0.280  max 0.410 mm``."""
        return f"mean {self.mean:.3f}  rms {self.rms:.3f}  p95 {self.p95:.3f}  max {self.max:.3f} mm"


_COLUMNS = ("n", "mean", "rms", "p95", "max", "dx", "dy", "dz")


def format_table(named_stats):
    """Fixed-width text table, one row per named ErrorStats.

    Parameters
    ----------
    named_stats : mapping of str to ErrorStats
        E.g. ``{"none": ..., "composite": ...}``, in display order.

    Returns
    -------
    str
        Header and one row per entry: n, mean/RMS/p95/max of ``|e|`` and the
        signed per-axis means, all in mm, without a trailing newline.
    """
    width = max([len("mode")] + [len(name) for name in named_stats])
    lines = [f"{'mode':<{width}}" + "".join(f"{c:>10}" for c in _COLUMNS) + "   (mm)"]
    for name, s in named_stats.items():
        numbers = (s.mean, s.rms, s.p95, s.max, *s.signed_mean)
        lines.append(f"{name:<{width}}{s.n:>10d}" + "".join(f"{v:>10.4f}" for v in numbers))
    return "\n".join(lines)


def kfold_indices(n, k, seed=0):
    """Shuffled k-fold cross-validation splits, deterministic by seed.

    Parameters
    ----------
    n : int
        Number of samples.
    k : int
        Number of folds, ``2 <= k <= n``.
    seed : int, optional
        Seed of the shuffle.

    Returns
    -------
    list of (ndarray, ndarray)
        ``k`` pairs ``(train_idx, test_idx)`` of sorted int indices; the test
        sets partition ``range(n)`` and differ in size by at most one.

    Raises
    ------
    CalibrationError
        If ``k`` is below 2 or above ``n``.
    """
    if not 2 <= k <= n:
        raise CalibrationError(f"{k}-fold cross-validation needs 2 <= k <= number of points ({n})")
    order = np.random.default_rng(seed).permutation(n)
    splits = []
    for test in np.array_split(order, k):
        mask = np.zeros(n, dtype=bool)
        mask[test] = True
        splits.append((np.flatnonzero(~mask), np.flatnonzero(mask)))
    return splits
