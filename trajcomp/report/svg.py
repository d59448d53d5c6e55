"""Charts written directly as inline SVG: the compliance report's figures without a plotting library.

A compliance report is written at every save of an offline-programming tool
(`plugins/trajcomp-robodk`): importing matplotlib and rasterising its
figures took seconds, the whole page must take well under one. These
charts are a few panels of lines, markers, bands, bars and reference lines
on linear or log axes; each panel is one `Axes`, a `Chart` lays panels out
in rows and writes the ``<svg>`` element. Coordinates are written with one
decimal of a pixel; every series of N points is one ``<path>``.
"""

import math

import numpy as np

from trajcomp.report.markup import esc

FONT = 12  # px, tick labels; titles and labels in proportion
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b")  # joint colours, as matplotlib's C0..C5
_MARGIN = {"left": 64, "right": 18, "top": 26, "bottom": 40}  # px around a panel's plotting area


def nice_ticks(low, high, count=6):
    """About ``count`` round tick values covering [low, high] (1, 2, 2.5 or 5 times a power of ten apart)."""
    if not (np.isfinite(low) and np.isfinite(high)) or high <= low:
        return np.array([low])
    raw = (high - low) / max(count - 1, 1)
    power = 10.0 ** math.floor(math.log10(raw))
    step = next(k * power for k in (1, 2, 2.5, 5, 10) if k * power >= raw)
    first = math.ceil(low / step - 1e-9) * step
    ticks = np.arange(first, high + step * 1e-6, step)
    return np.round(ticks / step) * step


def tick_text(values):
    """Tick labels with the decimals the values need, no more (``0``, ``0.25``, ``1``; ``1e-05``)."""
    values = np.asarray(values, dtype=float)
    for decimals in range(7):
        if np.allclose(np.round(values, decimals), values, rtol=0.0, atol=1e-9 * max(1.0, np.abs(values).max(initial=0))):
            return [f"{v:.{decimals}f}" if decimals else f"{v:.0f}" for v in values + 0.0]
    return [f"{v:.3g}" for v in values]


class Axes:
    """One panel: data series on linear or log axes, drawn into a rectangle of the chart (px).

    Series are added in data units; the ranges follow the data unless
    `limits` sets them. ``equal``: one unit is as long along x as along y
    (the views of targets in space).
    """

    def __init__(self, *, ylog=False, equal=False, title="", xlabel="", ylabel=""):
        self.ylog, self.equal = ylog, equal
        self.title, self.xlabel, self.ylabel = title, xlabel, ylabel
        self.items, self.legend_items = [], []
        self.xlim, self.ylim = [None, None], [None, None]
        self.xticks = None  # (positions, labels) for category axes
        self.twin_axes = None
        self.legend_at = "top right"

    def limits(self, x=(None, None), y=(None, None)):
        """Set either end of either axis (None: from the data)."""
        self.xlim = [a if a is not None else b for a, b in zip(x, self.xlim)]
        self.ylim = [a if a is not None else b for a, b in zip(y, self.ylim)]
        return self

    def twin(self, ylabel=""):
        """A second y axis on the right, over the same x (its own series and range)."""
        self.twin_axes = Axes(ylabel=ylabel)
        return self.twin_axes

    def _add(self, kind, x, y, style, label=None, color=None, marker=None):
        self.items.append((kind, np.asarray(x, dtype=float), np.asarray(y, dtype=float), style))
        if label:
            self.legend_items.append((label, color, kind, marker))

    def line(self, x, y, color, width=1.2, dash=None, label=None):
        style = f'fill="none" stroke="{color}" stroke-width="{width}"' + (f' stroke-dasharray="{dash}"' if dash else "")
        self._add("line", x, y, style, label, color)

    def markers(self, x, y, color, shape="o", size=5, label=None):
        """Markers of ``shape`` (o circle, s square, D diamond, ^ triangle, x cross) ``size`` px across."""
        self._add(("marker", shape, size), x, y, color, label, color, shape)

    def band(self, x, lower, upper, color, label=None):
        """The region between two curves (a min-max envelope)."""
        self._add("band", np.r_[x, x[::-1]], np.r_[lower, upper[::-1]], color, label, color)

    def hline(self, y, color, width=1.5, label=None):
        self._add("hline", [np.nan], [y], f'stroke="{color}" stroke-width="{width}"', label, color)

    def hspan(self, low, high, color, opacity=0.15):
        self._add("hspan", [np.nan, np.nan], [low, high], f'fill="{color}" fill-opacity="{opacity}"')

    def rect(self, lower, upper, color, label=None):
        """A dashed rectangle with corners ``lower`` and ``upper`` (x, y)."""
        self._add("rect", [lower[0], upper[0]], [lower[1], upper[1]],
                  f'fill="none" stroke="{color}" stroke-width="1.2" stroke-dasharray="5 3"', label, color)

    def bars(self, x, height, width, color, label=None):
        """Bars of ``width`` (x units) centred at ``x``, from 0 (linear axis) up to ``height`` (NaN: none)."""
        self._add(("bars", width), x, height, color, label, color, "bar")

    # layout and drawing

    def _range(self, axis):
        """(low, high) of an axis: the set limits, else the data's with a 4 % pad."""
        values = []
        for kind, x, y, _ in self.items:
            v = x if axis == 0 else y
            if kind in ("hline", "hspan") and axis == 0:  # they span the x axis, whatever its range
                continue
            if isinstance(kind, tuple) and kind[0] == "bars":
                if axis == 0:
                    values += [x - kind[1] / 2, x + kind[1] / 2]
                    continue
                values.append([0.0])
            values.append(v[np.isfinite(v)])
        data = np.concatenate(values) if values else np.zeros(0)
        if self.ylog and axis == 1:
            data = data[data > 0]
        low, high = (data.min(), data.max()) if len(data) else ((1e-3, 1.0) if self.ylog and axis == 1 else (0.0, 1.0))
        if self.ylog and axis == 1:
            low, high = math.log10(low), math.log10(high)
        pad = 0.04 * (high - low) if high > low else 0.5
        low, high = low - pad, high + pad
        if self.ylog and axis == 1:
            low, high = 10 ** low, 10 ** high
        limits = self.xlim if axis == 0 else self.ylim
        return (limits[0] if limits[0] is not None else low, limits[1] if limits[1] is not None else high)

    def render(self, left, top, width, height, key):
        """The panel's SVG elements in the rectangle (px) of its plotting area; ``key``: its clip path's id,
        unique in the page."""
        (x0, x1), (y0, y1) = self._range(0), self._range(1)
        if self.equal:  # widen one range so that a mm is as long on both axes
            scale = max((x1 - x0) / width, (y1 - y0) / height)
            cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
            x0, x1 = cx - scale * width / 2, cx + scale * width / 2
            y0, y1 = cy - scale * height / 2, cy + scale * height / 2
        fy = _scale(y0, y1, top + height, top, self.ylog)
        fx = _scale(x0, x1, left, left + width, False)
        out = [f'<g font-size="{FONT}">']
        out += self._grid_and_ticks(fx, fy, x0, x1, y0, y1, left, top, width, height)
        out.append(f'<clipPath id="{key}"><rect x="{left}" y="{top}" width="{width}" height="{height}"/></clipPath>')
        out.append(f'<g clip-path="url(#{key})">')
        out += [self._item(item, fx, fy, left, width) for item in self.items]
        if self.twin_axes is not None:
            twin = self.twin_axes
            t0, t1 = twin._range(1)
            ft = _scale(t0, t1, top + height, top, False)
            out += [twin._item(item, fx, ft, left, width) for item in twin.items]
        out.append("</g>")
        if self.twin_axes is not None:
            out += self.twin_axes._right_ticks(ft, t0, t1, left + width, top, height)
        out.append(f'<rect x="{left}" y="{top}" width="{width}" height="{height}" fill="none" stroke="#999"/>')
        if self.title:
            out.append(f'<text x="{left}" y="{top - 8}" font-size="{FONT + 1}">{esc(self.title)}</text>')
        if self.xlabel:
            out.append(f'<text x="{left + width / 2:.1f}" y="{top + height + 34}" text-anchor="middle">'
                       f"{esc(self.xlabel)}</text>")
        if self.ylabel:
            out.append(_vertical(self.ylabel, left - 50, top + height / 2))
        out += self._legend(left, top, width, height)
        out.append("</g>")
        return "".join(out)

    def _grid_and_ticks(self, fx, fy, x0, x1, y0, y1, left, top, width, height):
        out = []
        if self.xticks is not None:
            xt, xl = self.xticks
        else:
            xt = nice_ticks(x0, x1, max(3, int(width // 90)))
            xt = xt[(xt >= x0) & (xt <= x1)]
            xl = tick_text(xt)
        for x, label in zip(xt, xl):
            px = fx(x)
            out.append(f'<line x1="{px:.1f}" x2="{px:.1f}" y1="{top}" y2="{top + height}" stroke="#e3e3e3"/>'
                       f'<text x="{px:.1f}" y="{top + height + 16}" text-anchor="middle">{esc(label)}</text>')
        if self.ylog:
            yt = 10.0 ** np.arange(math.floor(math.log10(y0)), math.ceil(math.log10(y1)) + 1)
            yt = yt[(yt >= y0) & (yt <= y1)]
            yl = [f"{v:g}" for v in yt]
        else:
            yt = nice_ticks(y0, y1, max(3, int(height // 35)))
            yt = yt[(yt >= y0 - 1e-12 * abs(y1 - y0)) & (yt <= y1 + 1e-12 * abs(y1 - y0))]
            yl = tick_text(yt)
        for y, label in zip(yt, yl):
            py = fy(y)
            out.append(f'<line x1="{left}" x2="{left + width}" y1="{py:.1f}" y2="{py:.1f}" stroke="#e3e3e3"/>'
                       f'<text x="{left - 5}" y="{py + 4:.1f}" text-anchor="end">{esc(label)}</text>')
        return out

    def _right_ticks(self, ft, t0, t1, right, top, height):
        ticks = nice_ticks(t0, t1, max(3, int(height // 35)))
        ticks = ticks[(ticks >= t0) & (ticks <= t1)]
        out = [f'<text x="{right + 5}" y="{ft(t) + 4:.1f}">{esc(label)}</text>' for t, label in zip(ticks, tick_text(ticks))]
        if self.ylabel:
            out.append(_vertical(self.ylabel, right + 58, top + height / 2))
        return out

    def _item(self, item, fx, fy, left, width):
        kind, x, y, style = item
        if kind == "hline":
            return f'<line x1="{left}" x2="{left + width}" y1="{fy(y[0]):.1f}" y2="{fy(y[0]):.1f}" {style}/>'
        if kind == "hspan":
            a, b = fy(y[0]), fy(y[1])
            return f'<rect x="{left}" y="{min(a, b):.1f}" width="{width}" height="{abs(a - b):.1f}" {style}/>'
        if kind == "rect":
            a, b = fx(x), fy(y)
            return (f'<rect x="{a.min():.1f}" y="{b.min():.1f}" width="{np.ptp(a):.1f}" height="{np.ptp(b):.1f}" '
                    f"{style}/>")
        if kind == "line":
            return f'<path d="{_polyline(fx(x), fy(y))}" {style}/>'
        if kind == "band":
            return f'<path d="{_polyline(fx(x), fy(y))}Z" fill="{style}" fill-opacity="0.7" stroke="{style}" stroke-width="0.6"/>'
        if kind[0] == "bars":
            keep = np.isfinite(y)
            px0, px1, base = fx(x - kind[1] / 2), fx(x + kind[1] / 2), fy(0.0)
            top = fy(y)
            return "".join(f'<rect x="{a:.1f}" y="{min(t, base):.1f}" width="{b - a:.1f}" height="{abs(base - t):.1f}" '
                           f'fill="{style}"/>' for a, b, t in zip(px0[keep], px1[keep], top[keep]))
        _, shape, size = kind
        keep = np.isfinite(x) & np.isfinite(y)
        if self.ylog:
            keep &= y > 0
        return _markers(fx(x[keep]), fy(y[keep]), shape, size, style)

    def _legend(self, left, top, width, height):
        if not self.legend_items and not (self.twin_axes and self.twin_axes.legend_items):
            return []
        entries = self.legend_items + (self.twin_axes.legend_items if self.twin_axes else [])
        rows = [f'<g font-size="{FONT - 1}">']
        longest = max(len(label) for label, *_ in entries)
        box_width = 30 + 6.2 * longest
        x = left + width - box_width - 6 if "right" in self.legend_at else left + 6
        y = top + 6 if "top" in self.legend_at else top + height - 6 - 16 * len(entries)
        rows.append(f'<rect x="{x:.1f}" y="{y:.1f}" width="{box_width:.1f}" height="{16 * len(entries) + 4}" '
                    'fill="#fff" fill-opacity="0.85" stroke="#ccc"/>')
        for k, (label, color, kind, marker) in enumerate(entries):
            cy = y + 11 + 16 * k
            if marker == "bar":
                rows.append(f'<rect x="{x + 6:.1f}" y="{cy - 5:.1f}" width="14" height="9" fill="{color}"/>')
            elif marker:
                rows.append(_markers(np.array([x + 13]), np.array([cy]), marker, 6, color))
            else:
                rows.append(f'<line x1="{x + 4:.1f}" x2="{x + 22:.1f}" y1="{cy:.1f}" y2="{cy:.1f}" stroke="{color}" '
                            'stroke-width="2"/>')
            rows.append(f'<text x="{x + 26:.1f}" y="{cy + 4:.1f}">{esc(label)}</text>')
        rows.append("</g>")
        return rows


class Chart:
    """Panels in rows: ``Chart(width, [(height, [Axes, ...]), ...])`` (px); `svg` writes it."""

    def __init__(self, width, rows):
        self.width, self.rows = width, rows
        self.right = 72 if any(ax.twin_axes for _, panels in rows for ax in panels) else _MARGIN["right"]

    def svg(self, title):
        """The ``<svg>`` element (scales to the page's width); ``title``, unique in the page, names its parts."""
        height = sum(h for h, _ in self.rows)
        out = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {self.width} {height}" width="{self.width}" '
               f'height="{height}" role="img" font-family="system-ui, sans-serif" fill="#222">'
               f"<title>{esc(title)}</title>"]
        top, slug = 0, "-".join(title.split())
        for row, (row_height, panels) in enumerate(self.rows):
            cell = self.width / len(panels)
            for k, ax in enumerate(panels):
                left = k * cell + _MARGIN["left"]
                right = self.right if k == len(panels) - 1 or ax.twin_axes else _MARGIN["right"]
                out.append(ax.render(left, top + _MARGIN["top"], cell - _MARGIN["left"] - right,
                                     row_height - _MARGIN["top"] - _MARGIN["bottom"], f"clip-{slug}-{row}-{k}"))
            top += row_height
        out.append("</svg>")
        return "".join(out)


def _scale(low, high, start, end, log):
    """Data to px along one axis (a vectorised function)."""
    if log:
        low, high = math.log10(low), math.log10(high)
    span = (high - low) or 1.0

    def to_px(values):
        v = np.asarray(values, dtype=float)
        if log:
            with np.errstate(divide="ignore", invalid="ignore"):
                v = np.log10(v)
        return start + (v - low) / span * (end - start)

    return to_px


def _polyline(px, py):
    """Path data through the points (NaN breaks the line); a curve along x of more points than pixel columns
    goes through each column's lowest and highest point (`_per_column`), so that no peak is lost."""
    px, py = _per_column(np.asarray(px, dtype=float), np.asarray(py, dtype=float))
    keep = np.isfinite(px) & np.isfinite(py)
    parts, pen = [], "M"
    for a, b, k in zip(np.round(px, 1).tolist(), np.round(py, 1).tolist(), keep.tolist()):
        if not k:
            pen = "M"
            continue
        parts.append(f"{pen}{a} {b}")
        pen = "L"
    return "".join(parts)


def _per_column(px, py):
    """The points (px) of a curve along x (x never decreasing, all finite) thinned to each pixel column's lowest
    and highest point, in the order the curve reaches them; other curves as they are."""
    if len(px) <= 1000 or not (np.isfinite(px).all() and np.isfinite(py).all()) or np.any(np.diff(px) < 0):
        return px, py
    column = np.floor(px).astype(np.int64)
    starts = np.flatnonzero(np.r_[True, column[1:] != column[:-1]])
    low, high = np.minimum.reduceat(py, starts), np.maximum.reduceat(py, starts)
    ends = np.r_[starts[1:], len(px)] - 1
    rising = py[starts] <= py[ends]
    ys = np.stack([np.where(rising, low, high), np.where(rising, high, low)], axis=1).ravel()
    xs = np.repeat(column[starts] + 0.5, 2)
    return xs, ys


def _shape(shape, r):
    """Relative path of one marker of half-size ``r`` (px), drawn from its centre."""
    d = 2 * r
    return {
        "o": f"m{-r:g} 0a{r:g} {r:g} 0 1 0 {d:g} 0a{r:g} {r:g} 0 1 0 {-d:g} 0",
        "s": f"m{-0.9 * r:g} {-0.9 * r:g}h{1.8 * r:g}v{1.8 * r:g}h{-1.8 * r:g}z",
        "D": f"m0 {-1.2 * r:g}l{1.2 * r:g} {1.2 * r:g}l{-1.2 * r:g} {1.2 * r:g}l{-1.2 * r:g} {-1.2 * r:g}z",
        "^": f"m0 {-1.2 * r:g}l{1.1 * r:g} {2 * r:g}h{-2.2 * r:g}z",
        "x": f"m{-r:g} {-r:g}l{d:g} {d:g}m0 {-d:g}l{-d:g} {d:g}",
    }[shape]


def _markers(px, py, shape, size, color):
    """Every marker of a series in one path."""
    unit = _shape(shape, size / 2)
    d = "".join(f"M{a} {b}{unit}" for a, b in zip(np.round(px, 1).tolist(), np.round(py, 1).tolist()))
    if shape == "x":
        return f'<path d="{d}" fill="none" stroke="{color}" stroke-width="1.6"/>'
    return f'<path d="{d}" fill="{color}" fill-opacity="0.85"/>'


def _vertical(text, x, y):
    return f'<text transform="translate({x:.1f},{y:.1f}) rotate(-90)" text-anchor="middle">{esc(text)}</text>'
