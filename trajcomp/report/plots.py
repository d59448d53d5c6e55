"""The report figures, drawn with matplotlib (Agg backend, imported on first use).

Each function takes arrays in user units (mm, deg) and returns a
matplotlib Figure; `trajcomp.report.html` embeds it as a PNG data URI.
"""

import numpy as np

from trajcomp.support.signals import held

AXES = ("x", "y", "z")
WIDTH = 10.0  # in, figure width at the page's text width
POINTS = 2000  # points per drawn series: longer ones are decimated (min-max envelope, every k-th target)
CELLS = 400  # raster cells per axis of a view of a long path: one marker per occupied cell
_INSIDE, _OUTSIDE, _LIMIT = "#1f5fa8", "#c0392b", "#7f8c8d"


def pyplot():
    """matplotlib.pyplot on the Agg backend (no display needed).

    SIGINT, SIGTERM and SIGHUP wait for the end of its first import (about
    a second): raised into the initialisation of one of its C extensions,
    they would abort the interpreter (exit 134).
    """
    with held():
        import matplotlib

        matplotlib.use("Agg", force=True)
        import matplotlib.pyplot as plt

    plt.rcParams.update({"font.size": 9, "axes.grid": True, "grid.alpha": 0.3, "axes.spines.top": False,
                         "axes.spines.right": False, "figure.dpi": 100})
    return plt


def error_trends(position, errors, trends, excluded=None):
    """The paper's plots: each error axis against each commanded coordinate, with the fitted lines.

    Parameters
    ----------
    position : ndarray, shape (N, 3)
        Commanded positions, mm.
    errors : ndarray, shape (N, 3)
        Measured minus commanded, mm.
    trends : dict
        ``trends["dx"]["y"] = {"slope_mm_per_m", "intercept_mm", "r2"}`` (`trajcomp.report.calibration.trends`).
    excluded : ndarray of bool, shape (N,), optional
        Rows left out of the fit (outliers), drawn as crosses.
    """
    plt = pyplot()
    fig, axes = plt.subplots(3, 3, figsize=(WIDTH, 8.0), sharex="col", sharey="row", constrained_layout=True)
    keep = np.ones(len(position), dtype=bool) if excluded is None else ~excluded
    for row, name in enumerate(("dx", "dy", "dz")):
        for col, axis in enumerate(AXES):
            ax = axes[row, col]
            ax.scatter(position[keep, col], errors[keep, row], s=6, alpha=0.5, color=_INSIDE, linewidths=0)
            if not keep.all():
                ax.scatter(position[~keep, col], errors[~keep, row], s=20, marker="x", color=_OUTSIDE, label="outlier")
            fit = trends[name][axis]
            span = np.array([position[:, col].min(), position[:, col].max()])
            strong = fit["r2"] >= 0.5
            ax.plot(span, fit["intercept_mm"] + fit["slope_mm_per_m"] * span / 1000.0,
                    color=_OUTSIDE if strong else "black", lw=2.2 if strong else 1.0)
            ax.set_title(f"{name} vs {axis}: {fit['slope_mm_per_m']:+.3f} mm/m, R² {fit['r2']:.2f}",
                         fontsize=8.5, fontweight="bold" if strong else "normal")
            if row == 2:
                ax.set_xlabel(f"commanded {axis} (mm)")
            if col == 0:
                ax.set_ylabel(f"{name} (mm)")
    return fig


def error_maps(position, maps, limit_box=None):
    """|error| coloured over the top view (x, y) and the side view (x, z), one row per map.

    Parameters
    ----------
    position : ndarray, shape (N, 3)
        Positions, mm.
    maps : sequence of (str, ndarray (N,))
        Row title and |error| (mm) of each row, e.g. before and after.
    limit_box : (ndarray (3,), ndarray (3,)), optional
        Lower and upper corner of the grid box, drawn as a rectangle.
    """
    plt = pyplot()
    fig, axes = plt.subplots(len(maps), 2, figsize=(WIDTH, 3.6 * len(maps)), squeeze=False, constrained_layout=True)
    for row, (title, values) in enumerate(maps):
        order = np.argsort(values)  # largest errors drawn last, on top
        top = max(float(np.percentile(values, 99)), 1e-9)
        above = int(np.sum(values > top))
        for col, (i, j) in enumerate(((0, 1), (0, 2))):
            ax = axes[row, col]
            art = ax.scatter(position[order, i], position[order, j], c=values[order], s=14, cmap="viridis",
                             vmin=0.0, vmax=top, linewidths=0)
            if limit_box is not None:
                _box(ax, limit_box, i, j)
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_xlabel(f"{AXES[i]} (mm)")
            ax.set_ylabel(f"{AXES[j]} (mm)")
            clipped = "" if not above or col else (
                f"\ncolour scale clipped at its 99th percentile ({top:.3g} mm):\n{above} point{'s' * (above > 1)} above "
                f"it, up to {values.max():.3g} mm, in the top colour")
            ax.set_title(f"{title}: {'top' if col == 0 else 'side'} view{clipped}", fontsize=9, loc="left")
        fig.colorbar(art, ax=axes[row, :], label="|error| (mm)" + (", clipped ▲" if above else ""), shrink=0.9,
                     extend="max" if above else "neither")
    return fig


def mode_statistics(tables):
    """Mean and p95 |error| per mode, one group of bars per statistics table, log scale.

    Parameters
    ----------
    tables : dict of str to dict
        ``{"fit": {mode: stats dict}, "5-fold cross-validation": {...}}``.
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(WIDTH, 3.4), constrained_layout=True)
    modes = list(dict.fromkeys(m for table in tables.values() for m in table))
    width = 0.8 / (2 * len(tables))
    colors = ("#1f5fa8", "#8fb3dd", "#c0392b", "#e6a39c", "#1e7d45", "#9fd3b0")
    k = 0
    for name, table in tables.items():
        for stat in ("mean", "p95"):
            values = [table.get(m, {}).get(stat, np.nan) for m in modes]
            ax.bar(np.arange(len(modes)) + (k - len(tables) + 0.5) * width, values, width,
                   label=f"{name}: {stat}", color=colors[k % len(colors)])
            k += 1
    ax.set_xticks(np.arange(len(modes)), modes)
    ax.set_yscale("log")
    ax.set_ylabel("|error| (mm)")
    ax.legend(ncols=2, fontsize=8)
    return fig


def envelope(values, points=POINTS):
    """A per-target series decimated to at most ``points`` bins, keeping every extreme.

    Parameters
    ----------
    values : ndarray, shape (N,)
    points : int

    Returns
    -------
    x, lower, upper : ndarray, shape (B,)
        1-based target number at each bin's centre, the smallest and the
        largest value in the bin (B = N and lower = upper when N <= points).
    """
    values = np.asarray(values, dtype=float)
    n = len(values)
    if n <= points:
        return np.arange(1, n + 1), values, values
    width = -(-n // points)
    padded = np.full(width * -(-n // width), np.nan)
    padded[:n] = values
    bins = padded.reshape(-1, width)
    x = np.minimum(np.arange(len(bins)) * width + (width + 1) / 2, n)
    return x, np.nanmin(bins, axis=1), np.nanmax(bins, axis=1)


def envelope_note(n, points=POINTS):
    """The caption sentence of a per-target figure of ``n`` targets drawn as envelopes ("" when drawn whole)."""
    if n <= points:
        return ""
    return (f" {n} targets: each curve is drawn as its band from smallest to largest value over bins of "
            f"{-(-n // points)} targets, so that no extreme is lost.")


def _series(ax, values, style, color, **kwargs):
    """A per-target series: points and lines up to `POINTS` targets, else its min-max envelope as a band."""
    x, lower, upper = envelope(values)
    if len(x) == len(values):
        ax.plot(x, values, style, color=color, **kwargs)
    else:
        ax.fill_between(x, lower, upper, color=color, alpha=0.7, lw=0.6, edgecolor=color, step="mid",
                        label=kwargs.get("label"))


def _stride(n, points=POINTS):
    """Every how many targets a path of ``n`` targets is drawn (1 up to ``points``)."""
    return max(1, -(-n // points))


def one_per_cell(points, cells=CELLS):
    """Which of the points (K, 2) to mark so that every one shows: the first in each occupied raster cell.

    Up to `POINTS` points, all of them; beyond, the bounding box is cut into
    ``cells`` x ``cells`` cells (finer than the drawn pixels) and the first
    point of each occupied cell is kept, so every point lies within one cell
    of a kept one and an isolated target is never dropped.

    Returns
    -------
    ndarray of int
        Ascending indices into ``points``.
    """
    points = np.asarray(points, dtype=float)
    if len(points) <= POINTS:
        return np.arange(len(points))
    lower = points.min(axis=0)
    span = np.maximum(points.max(axis=0) - lower, 1e-9)
    cell = np.minimum((points - lower) / span * cells, cells - 1).astype(np.int64)
    _, first = np.unique(cell[:, 0] * cells + cell[:, 1], return_index=True)
    return np.sort(first)


def path_note(n, points=POINTS):
    """The caption sentence of the targets figure of ``n`` targets ("" when every target is drawn)."""
    if n <= points:
        return ""
    return (f" {n} targets: the path line is drawn through one target in {_stride(n, points)}; the markers, one "
            f"per occupied cell of a {CELLS} x {CELLS} raster of each view, show every target inside and every "
            "one outside the grid.")


def targets_and_grid(target, outside, grid_box=None, posture=None, orientation=None):
    """The targets in motion order over the top and side views, with the grid box and the uncovered ones marked.

    Crosses: outside the grid; triangles: in an arm posture the calibration
    did not measure; diamonds: oriented beyond the measured orientations
    (``posture``, ``orientation``: boolean masks (N,), optional). Long paths
    (`path_note`): the line through every k-th target, at most `POINTS`;
    the markers thinned by `one_per_cell`, so none is lost.
    """
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(WIDTH, 4.0), constrained_layout=True)
    step = _stride(len(target))
    path = np.r_[np.arange(0, len(target), step), len(target) - 1] if len(target) else np.zeros(0, int)
    none = np.zeros(len(target), dtype=bool)
    posture = none if posture is None else np.asarray(posture, dtype=bool)
    orientation = none if orientation is None else np.asarray(orientation, dtype=bool)
    kinds = (("inside the grid, measured posture and orientation", ~(outside | posture | orientation), "o", _INSIDE, 18),
             ("orientation beyond the measured ones", orientation & ~(outside | posture), "D", "#7d3c98", 30),
             ("arm posture not measured", posture & ~outside, "^", "#d35400", 36),
             ("outside the grid", outside, "x", _OUTSIDE, 40))
    for ax, (i, j) in zip(axes, ((0, 1), (0, 2))):
        ax.plot(target[path, i], target[path, j], color=_LIMIT, lw=0.8, zorder=1)
        for z, (label, mask, marker, color, size) in enumerate(kinds):
            shown = target[mask][:, [i, j]]
            shown = shown[one_per_cell(shown)]
            if len(shown) or not z:
                ax.scatter(shown[:, 0], shown[:, 1], s=size if step == 1 else size / 4, marker=marker, color=color,
                           label=label, zorder=2 + z)
        if grid_box is not None:
            _box(ax, grid_box, i, j)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"{AXES[i]} (mm, base)")
        ax.set_ylabel(f"{AXES[j]} (mm, base)")
    axes[0].legend(fontsize=8)
    return fig


def corrections(correction_mm, correction_deg, estimate, convergence, tolerance):
    """Per target: position and orientation correction; the landing estimate and the convergence against the tolerance.

    ``estimate`` (N,) mm may be None (no model) or hold NaN (no estimate):
    then only the convergence is drawn.
    """
    plt = pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(WIDTH, 4.8), sharex=True, constrained_layout=True)
    _series(top, correction_mm, "o-", _INSIDE, ms=3)
    top.set_ylabel("position (mm)", color=_INSIDE)
    twin = top.twinx()
    _series(twin, correction_deg, "s--", "#d35400", ms=3)
    twin.set_ylabel("orientation (deg)", color="#d35400")
    twin.grid(False)
    top.set_title("correction applied (command − target)")
    if estimate is not None and np.isfinite(estimate).any():
        _series(bottom, np.maximum(estimate, 1e-9), "o", _INSIDE, ms=3, label="landing estimate")
    _series(bottom, np.maximum(convergence, 1e-9), ".", _LIMIT, ms=2, label="convergence (model vs itself)")
    bottom.set_yscale("log")
    bottom.axhline(tolerance, color=_OUTSIDE, lw=1.5, label=f"tolerance {tolerance:g} mm")
    bottom.set_ylabel("mm")
    bottom.set_xlabel("target (motion order)")
    bottom.legend(fontsize=8, loc="lower right")
    _integer_ticks(bottom)
    return fig


def joint_ranges(joints_deg, q_min_deg, q_max_deg, margin):
    """Each joint across the targets, as a fraction of its range; the margin band shaded."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(WIDTH, 3.4), constrained_layout=True)
    span = q_max_deg - q_min_deg
    for j in range(joints_deg.shape[1]):
        _series(ax, (joints_deg[:, j] - q_min_deg[j]) / span[j], "o-", f"C{j}", ms=2.5, lw=1, label=f"J{j + 1}")
    band = float(np.max(margin / span))
    ax.axhspan(0, band, color=_OUTSIDE, alpha=0.15)
    ax.axhspan(1 - band, 1, color=_OUTSIDE, alpha=0.15)
    ax.set_ylim(-0.02, 1.02)
    ax.set_ylabel("position in range (0 = min, 1 = max)")
    ax.set_xlabel("target (motion order)")
    ax.legend(ncols=6, fontsize=8, loc="upper center")
    _integer_ticks(ax)
    return fig


def singularities(distances, margins):
    """Shoulder (mm), elbow and wrist (deg) singularity distances per target, with their margins."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(WIDTH, 2.8), constrained_layout=True)
    for ax, (name, values) in zip(axes, distances.items()):
        unit = "mm" if name == "shoulder" else "deg"
        _series(ax, values, "o-", _INSIDE, ms=2.5, lw=1)
        ax.axhline(margins[name], color=_OUTSIDE, lw=1.2)
        ax.set_ylim(bottom=0)
        ax.set_title(f"{name} ({unit})")
        ax.set_xlabel("target")
        _integer_ticks(ax)
    return fig


def joint_motion(t, q, qd, qdd, q_min, q_max, v_max, a_max, margin):
    """Joint position, velocity and acceleration over time against the limits, one panel each.

    Position as a fraction of each joint's range (the limit margin shaded),
    |velocity| and |acceleration| as a percentage of each joint's limit.

    Parameters
    ----------
    t : ndarray, shape (S,)
        Sample times, s.
    q, qd, qdd : ndarray, shape (S, 6)
        deg, deg/s, deg/s^2.
    q_min, q_max, v_max, a_max : ndarray, shape (6,)
        The limits, same units.
    margin : float
        Limit margin, deg.
    """
    plt = pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(WIDTH, 6.6), sharex=True, constrained_layout=True)
    span = q_max - q_min
    for j in range(q.shape[1]):
        axes[0].plot(t, (q[:, j] - q_min[j]) / span[j], color=f"C{j}", lw=1, label=f"J{j + 1}")
        axes[1].plot(t, 100 * np.abs(qd[:, j]) / v_max[j], color=f"C{j}", lw=1)
        axes[2].plot(t, 100 * np.abs(qdd[:, j]) / a_max[j], color=f"C{j}", lw=1)
    band = float(np.max(margin / span))
    axes[0].axhspan(0, band, color=_OUTSIDE, alpha=0.15)
    axes[0].axhspan(1 - band, 1, color=_OUTSIDE, alpha=0.15)
    axes[0].set_ylim(-0.02, 1.02)
    axes[0].set_ylabel("position in range\n(0 = min, 1 = max)")
    axes[0].legend(ncols=6, fontsize=8, loc="upper center")
    for ax, name in zip(axes[1:], ("|velocity|", "|acceleration|")):
        ax.axhline(100, color=_OUTSIDE, lw=1.5)
        ax.set_ylim(0, 110)
        ax.set_ylabel(f"{name}\n% of limit")
    axes[2].set_xlabel("time (s)")
    return fig


def timing_peaks(section):
    """Peak joint velocity, acceleration and jerk as a fraction of their limits, per joint."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(WIDTH, 3.0), constrained_layout=True)
    names = ("velocity", "acceleration", "jerk")
    width = 0.26
    for k, name in enumerate(names):
        ratios = [row[name]["ratio"] if row[name]["ratio"] is not None else np.nan for row in section["joints"]]
        ax.bar(np.arange(6) + (k - 1) * width, np.array(ratios, dtype=float) * 100, width, label=name)
    ax.axhline(100, color=_OUTSIDE, lw=1.5)
    ax.set_xticks(np.arange(6), [f"J{j}" for j in range(1, 7)])
    ax.set_ylabel("peak / limit (%)")
    ax.legend(ncols=3, fontsize=8)
    return fig


def _integer_ticks(ax):
    """Whole target numbers on the x axis."""
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(nbins="auto", integer=True))


def _box(ax, box, i, j):
    """The (i, j) projection of an axis-aligned box (lower (3,), upper (3,)) as a dashed rectangle."""
    from matplotlib.patches import Rectangle

    lower, upper = np.asarray(box[0]), np.asarray(box[1])
    ax.add_patch(Rectangle((lower[i], lower[j]), upper[i] - lower[i], upper[j] - lower[j], fill=False,
                           ls="--", lw=1.2, color=_LIMIT, label="grid box"))
