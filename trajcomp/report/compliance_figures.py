"""The compliance report's figures, as inline SVG (`trajcomp.report.svg`): no plotting library to import.

Each function takes arrays in user units (mm, deg) and returns the
``<svg>`` text. Long series are decimated as `trajcomp.report.plots` says
(min-max envelopes, one marker per raster cell), so that the page stays
small and no extreme is lost.
"""

import numpy as np

from trajcomp.report.plots import AXES, envelope, one_per_cell, stride
from trajcomp.report.svg import PALETTE, Axes, Chart, nice_ticks

WIDTH = 1000  # px, at the page's text width
INSIDE, OUTSIDE, LIMIT, ORANGE = "#1f5fa8", "#c0392b", "#7f8c8d", "#d35400"
SMALLEST = 0.01  # mm and deg: the least span of a correction axis, so that a rounding-sized wiggle looks flat
MARKED = 200  # targets up to which a series marks each target (beyond, the line alone: the page stays small)


def _series(ax, values, color, *, line=True, marker="o", size=5, dash=None, label=None):
    """A per-target series: markers (and a line) up to `trajcomp.report.plots.POINTS` targets, else its band."""
    x, lower, upper = envelope(values)
    marker = marker if len(values) <= MARKED or not line else None
    if len(x) == len(values):
        if line:
            ax.line(x, values, color, dash=dash, label=None if marker else label)
        if marker:
            ax.markers(x, values, color, marker, size, label=label)
    else:
        ax.band(x, lower, upper, color, label=label)


def targets_and_grid(target, outside, grid_box=None, posture=None, orientation=None):
    """The targets in motion order over the top and side views, with the grid box and the uncovered ones marked.

    Crosses: outside the grid; triangles: in an arm posture the calibration
    did not measure; diamonds: oriented beyond the measured orientations
    (``posture``, ``orientation``: boolean masks (N,), optional). Long paths:
    the line through every k-th target, the markers thinned by
    `one_per_cell`, so none is lost.
    """
    step = stride(len(target))
    path = np.r_[np.arange(0, len(target), step), len(target) - 1] if len(target) else np.zeros(0, int)
    none = np.zeros(len(target), dtype=bool)
    posture = none if posture is None else np.asarray(posture, dtype=bool)
    orientation = none if orientation is None else np.asarray(orientation, dtype=bool)
    kinds = (("inside the grid, measured posture and orientation", ~(outside | posture | orientation), "o", INSIDE, 6),
             ("orientation beyond the measured ones", orientation & ~(outside | posture), "D", "#7d3c98", 7),
             ("arm posture not measured", posture & ~outside, "^", ORANGE, 8),
             ("outside the grid", outside, "x", OUTSIDE, 8))
    panels = []
    for i, j in ((0, 1), (0, 2)):
        ax = Axes(equal=True, xlabel=f"{AXES[i]} (mm, base)", ylabel=f"{AXES[j]} (mm, base)")
        ax.line(target[path, i], target[path, j], LIMIT, width=0.8)
        for z, (label, mask, marker, color, size) in enumerate(kinds):
            shown = target[mask][:, [i, j]]
            shown = shown[one_per_cell(shown)]
            if len(shown) or not z:
                ax.markers(shown[:, 0], shown[:, 1], color, marker, size if step == 1 else size / 2,
                           label=label if not panels else None)
        if grid_box is not None:
            ax.rect(np.asarray(grid_box[0])[[i, j]], np.asarray(grid_box[1])[[i, j]], LIMIT,
                    label="grid box" if not panels else None)
        panels.append(ax)
    panels[0].legend_at = "bottom left"
    return Chart(WIDTH, [(420, panels)]).svg("targets")


def corrections(correction_mm, correction_deg, estimate, convergence, tolerance):
    """Per target: position and orientation correction; the landing estimate and the convergence against the tolerance.

    Both correction axes start at zero and span at least `SMALLEST`: a
    correction of 0.0003 deg draws as the flat line it is. ``estimate``
    (N,) mm may be None (no model) or hold NaN (no estimate): then only the
    convergence is drawn.
    """
    top = Axes(title="correction applied (command − target)", ylabel="position (mm)")
    _series(top, correction_mm, INSIDE, label="position")
    top.limits(y=(0.0, max(SMALLEST, float(np.nanmax(correction_mm, initial=0.0)) * 1.05)))
    twin = top.twin(ylabel="orientation (deg)")
    _series(twin, correction_deg, ORANGE, marker="s", dash="5 3", label="orientation")
    twin.limits(y=(0.0, max(SMALLEST, float(np.nanmax(correction_deg, initial=0.0)) * 1.05)))
    bottom = Axes(ylog=True, ylabel="mm", xlabel="target (motion order)")
    if estimate is not None and np.isfinite(estimate).any():
        _series(bottom, np.maximum(estimate, 1e-9), INSIDE, line=False, label="landing estimate")
    _series(bottom, np.maximum(convergence, 1e-9), LIMIT, line=False, size=3, label="convergence (model vs itself)")
    bottom.hline(tolerance, OUTSIDE, label=f"tolerance {tolerance:g} mm")
    bottom.legend_at = "bottom right"
    _whole_targets(len(correction_mm), top, bottom)
    return Chart(WIDTH, [(240, [top]), (260, [bottom])]).svg("corrections")


def joint_ranges(joints_deg, q_min_deg, q_max_deg, margin):
    """Each joint across the targets, as a fraction of its range; the margin band shaded."""
    ax = Axes(ylabel="position in range (0 = min, 1 = max)", xlabel="target (motion order)")
    span = q_max_deg - q_min_deg
    band = float(np.max(margin / span))
    ax.hspan(0, band, OUTSIDE)
    ax.hspan(1 - band, 1, OUTSIDE)
    for j in range(joints_deg.shape[1]):
        _series(ax, (joints_deg[:, j] - q_min_deg[j]) / span[j], PALETTE[j], size=4, label=f"J{j + 1}")
    ax.limits(y=(-0.02, 1.02))
    _whole_targets(len(joints_deg), ax)
    return Chart(WIDTH, [(360, [ax])]).svg("joint ranges")


def singularities(distances, margins):
    """Shoulder (mm), elbow and wrist (deg) singularity distances per target, with their margins."""
    panels = []
    for name, values in distances.items():
        ax = Axes(title=f"{name} ({'mm' if name == 'shoulder' else 'deg'})", xlabel="target")
        _series(ax, values, INSIDE, size=4)
        ax.hline(margins[name], OUTSIDE, width=1.2)
        ax.limits(y=(0.0, None))
        _whole_targets(len(values), ax)
        panels.append(ax)
    return Chart(WIDTH, [(280, panels)]).svg("singularities")


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
    span = q_max - q_min
    position = Axes(ylabel="position in range")
    band = float(np.max(margin / span))
    position.hspan(0, band, OUTSIDE)
    position.hspan(1 - band, 1, OUTSIDE)
    position.limits(y=(-0.02, 1.02))
    velocity = Axes(ylabel="|velocity| % of limit")
    acceleration = Axes(ylabel="|acceleration| % of limit", xlabel="time (s)")
    for j in range(q.shape[1]):
        position.line(t, (q[:, j] - q_min[j]) / span[j], PALETTE[j], width=1, label=f"J{j + 1}")
        velocity.line(t, 100 * np.abs(qd[:, j]) / v_max[j], PALETTE[j], width=1)
        acceleration.line(t, 100 * np.abs(qdd[:, j]) / a_max[j], PALETTE[j], width=1)
    for ax in (velocity, acceleration):
        ax.hline(100, OUTSIDE)
        ax.limits(y=(0, 110))
    for ax in (position, velocity, acceleration):
        ax.limits(x=(float(t[0]), float(t[-1])))
    return Chart(WIDTH, [(230, [position]), (200, [velocity]), (230, [acceleration])]).svg("joint motion")


def timing_peaks(section):
    """Peak joint velocity, acceleration and jerk as a fraction of their limits, per joint."""
    ax = Axes(ylabel="peak / limit (%)")
    width = 0.26
    for k, name in enumerate(("velocity", "acceleration", "jerk")):
        ratios = [row[name]["ratio"] if row[name]["ratio"] is not None else np.nan for row in section["joints"]]
        ax.bars(np.arange(6) + (k - 1) * width, np.array(ratios, dtype=float) * 100, width, PALETTE[k], label=name)
    ax.hline(100, OUTSIDE)
    ax.xticks = (np.arange(6), [f"J{j}" for j in range(1, 7)])
    ax.limits(x=(-0.6, 5.6), y=(0.0, None))
    return Chart(WIDTH, [(300, [ax])]).svg("timing peaks")


def _whole_targets(n, *axes):
    """Whole target numbers 1..n on the x axis of each panel (a half target of room at each end)."""
    ticks = np.unique(np.round(nice_ticks(1, max(n, 2), 10)))
    ticks = ticks[(ticks >= 1) & (ticks <= n)]
    for ax in axes:
        ax.limits(x=(0.5, n + 0.5))
        ax.xticks = (ticks, [f"{t:.0f}" for t in ticks])
