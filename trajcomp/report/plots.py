"""The calibration report's figures, drawn with matplotlib (Agg backend, imported on first use), and the
decimation of long series that every report's figures share.

Each figure function takes arrays in user units (mm, deg) and returns a
matplotlib Figure; `trajcomp.report.html` embeds it as a PNG data URI. The
compliance report, written at every save of an offline-programming tool,
draws its figures as SVG without matplotlib (`trajcomp.report.compliance_figures`).
"""

import numpy as np

from trajcomp.support.signals import held

AXES = ("x", "y", "z")
WIDTH = 10.0  # in, figure width at the page's text width
POINTS = 2000  # points per drawn series: longer ones are decimated (min-max envelope, every k-th target)
CELLS = 400  # raster cells per axis of a view of a long path: one marker per occupied cell
ZERO = 1e-9  # mm: an error statistic at or below it is a zero of rounding, drawn as 0
WIDE_RANGE = 8.0  # a reliability plot whose values span more than this ratio is drawn on log axes
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

    A zero (a grid that interpolates its own nodes, fitted on them: below
    `ZERO`, rounding) has no place on a log axis: its bar is left out and
    ``0`` written at the axis' foot, instead of a bar down to 1e-20 that
    looks like the others.
    The legend sits below the axes, off the bars.

    Parameters
    ----------
    tables : dict of str to dict
        ``{"fit": {mode: stats dict}, "5-fold cross-validation": {...}}``.
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(WIDTH, 3.8), constrained_layout=True)
    modes = list(dict.fromkeys(m for table in tables.values() for m in table))
    width = 0.8 / (2 * len(tables))
    colors = ("#1f5fa8", "#8fb3dd", "#c0392b", "#e6a39c", "#1e7d45", "#9fd3b0")
    bars = []
    for name, table in tables.items():
        for stat in ("mean", "p95"):
            values = np.array([table.get(m, {}).get(stat, np.nan) for m in modes], dtype=float)
            bars.append((f"{name}: {stat}", np.arange(len(modes)) + (len(bars) - len(tables) + 0.5) * width, values))
    positive = np.concatenate([v[v > ZERO] for _, _, v in bars] + [np.ones(1)])
    foot = 10 ** np.floor(np.log10(positive.min()) - 0.3)
    for k, (label, x, values) in enumerate(bars):
        ax.bar(x, np.where(values > ZERO, values, np.nan), width, label=label, color=colors[k % len(colors)])
        for xz in x[values <= ZERO]:
            ax.text(xz, foot * 1.15, "0", ha="center", va="bottom", fontsize=8, color=colors[k % len(colors)],
                    fontweight="bold")
    ax.set_xticks(np.arange(len(modes)), modes)
    ax.set_yscale("log")
    ax.set_ylim(bottom=foot)
    ax.set_ylabel("|error| (mm)")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncols=2 * len(tables), fontsize=8)
    return fig


def reliability(data):
    """The landing estimate's reliability: its stated quantile against the true held-out errors, per class.

    One series per class of holdout (k-fold, node planes, slabs, outer
    layers): each bin of held-out rows (`trajcomp.calibration.calibrate.reliability`)
    at its mean stated quantile (x) and the same quantile of its true errors
    (y). On the diagonal the forecast is calibrated; below it, conservative
    (it states more than the errors reach); above it, it misses. Values
    spanning more than `WIDE_RANGE` are drawn on log axes.

    Parameters
    ----------
    data : dict
        ``{"quantile", "classes": {class: {"rows", "covered", "bins": [{"stated_mm", "true_quantile_mm"}]}}}``.
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(WIDTH * 0.6, 4.6), constrained_layout=True)
    colors, shapes = (_INSIDE, _OUTSIDE, "#1e7d45", "#8e44ad"), ("o", "s", "^", "D")
    values = []
    for k, (name, c) in enumerate(data["classes"].items()):
        x = [b["stated_mm"] for b in c["bins"]]
        y = [b["true_quantile_mm"] for b in c["bins"]]
        values += x + y
        ax.scatter(x, y, s=36, marker=shapes[k % len(shapes)], color=colors[k % len(colors)], alpha=0.75,
                   linewidths=0, label=f"{name}: {c['rows']} rows, {c['covered']:.1%} within the stated quantile")
    positive = [v for v in values if v > ZERO] or [1.0]
    top, low = 1.08 * max(positive), min(positive)
    wide = top / low > WIDE_RANGE  # a few bins far out would squeeze the others into a corner: log axes
    bottom = low / 1.25 if wide else 0.0
    ax.plot([bottom, top], [bottom, top], color=_LIMIT, lw=1.0, ls="--", label="calibrated (stated = true)")
    if wide:
        from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

        ax.set_xscale("log")
        ax.set_yscale("log")
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
            axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_formatter(NullFormatter())
    ax.set_xlim(bottom, top)
    ax.set_ylim(bottom, top)
    ax.set_aspect("equal")
    percent = f"{100 * data['quantile']:g} %"
    ax.set_xlabel(f"stated {percent} quantile of the landing error (mm)")
    ax.set_ylabel(f"true {percent} quantile of the held-out errors (mm)")
    ax.legend(loc="upper left", fontsize=8)
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


def stride(n, points=POINTS):
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
    return (f" {n} targets: the path line is drawn through one target in {stride(n, points)}; the markers, one "
            f"per occupied cell of a {CELLS} x {CELLS} raster of each view, show every target inside and every "
            "one outside the grid.")


def _box(ax, box, i, j):
    """The (i, j) projection of an axis-aligned box (lower (3,), upper (3,)) as a dashed rectangle."""
    from matplotlib.patches import Rectangle

    lower, upper = np.asarray(box[0]), np.asarray(box[1])
    ax.add_patch(Rectangle((lower[i], lower[j]), upper[i] - lower[i], upper[j] - lower[j], fill=False,
                           ls="--", lw=1.2, color=_LIMIT, label="grid box"))
