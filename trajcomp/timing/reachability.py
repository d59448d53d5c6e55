"""TOPP-RA's two reachability passes, vectorized over the grid: the time-optimal path speed.

TOPP-RA (Pham & Pham 2018) bounds the squared path speed x = sd^2 on a grid
s_0 < ... < s_{G-1} with a constant path acceleration u on each interval,
so x_{i+1} = x_i + 2 (s_{i+1} - s_i) u. With the joint acceleration
constraint in its "interpolation" discretization (checked at both ends of
the interval with the same u),

    |q'_j(s_i) u + q''_j(s_i) x_i| <= a_j   and   |q'_j(s_{i+1}) u + q''_j(s_{i+1}) x_{i+1}| <= a_j,

every constraint of interval i is a band ``sigma x_i - w <= x_{i+1} <= sigma x_i + w``
(w >= 0: rest, x = 0, is always allowed), or a bound on x_i alone where a
joint does not move. The controllable set of grid point i is then [0, h_i]
(rest is always reachable), with

    h_i = min(X_i, min over bands with sigma > 0 of (h_{i+1} + w) / sigma),

X_i the largest x_i the interval allows at all (the velocity bound and
the bands crossing), and the greedy forward pass is
``x_{i+1} = min(h_{i+1}, min over bands of sigma x_i + w)``.

Both recurrences are solved in chunks of `chunk_length` consecutive grid
intervals: every chunk is swept point by point from its end (backward)
or its start (forward), all chunks at once, one vectorized step per grid
point of a chunk; a chunk is swept again while the value at its border,
which the neighbouring chunk sets, changes. A ramp (acceleration or
braking) of R grid points thus settles in about R / chunk_length rounds
of chunk_length steps: O(G) work and O(R + chunk_length) vectorized steps,
where a wave of one grid point per step re-evaluated a whole ramp at each
step (O(R^2): 17-20 s on a 100,000-point Lissajous path). The result is
exactly the sequential recurrence's.
"""

import numpy as np

LONGEST_CHUNK = 256  # grid intervals per chunk at most (about the square root of the grid below that)


def squared_speeds(s, dq, ddq, acceleration, x_max, rest):
    """Time-optimal squared path speeds x (G,) under joint acceleration limits and speed bounds.

    Parameters
    ----------
    s : ndarray, shape (G,)
        Grid, strictly increasing (rad of path).
    dq, ddq : ndarray, shape (G, 6)
        Path derivatives q'(s), q''(s) at the grid points.
    acceleration : ndarray, shape (6,) or (G - 1, 6)
        Joint acceleration limits, rad/s^2 (per interval: independent runs in one problem).
    x_max : ndarray, shape (G,)
        Upper bound of x at each grid point (joint velocity, TCP speed), finite.
    rest : array_like of int
        Grid points where the path speed is 0 (at least the first and the last).

    Returns
    -------
    ndarray, shape (G,)
        x = sd^2, 0 at the rest points.
    """
    x_max = np.array(x_max, dtype=float)
    x_max[rest] = 0.0
    return forward(s, dq, ddq, acceleration, backward(s, dq, ddq, acceleration, x_max, end=0.0), start=0.0)


def backward(s, dq, ddq, acceleration, x_max, end):
    """The controllable bounds h (G,): from x_i <= h_i the path can go on to x_{G-1} <= ``end``.

    Parameters as `squared_speeds`; ``end`` is the bound at the last grid
    point (0: rest there; for a window, the next window's bound).
    """
    bands = _Bands(np.diff(s), dq, ddq, np.asarray(acceleration, dtype=float))
    h = np.append(bands.largest_x(x_max[:-1]), min(end, x_max[-1]))
    chunks = _Chunks(len(h))
    with np.errstate(divide="ignore", invalid="ignore"):
        rising = bands.sigma > 0.0  # x_i <= (h_{i+1} + w) / sigma for the bands with sigma > 0
        inverse = chunks.laid(np.where(rising, 1.0 / bands.sigma, 0.0), 0.0)
        offset = chunks.laid(np.where(rising, bands.w / bands.sigma, np.inf), np.inf)
    largest = chunks.laid(bands.largest[:-1], np.inf)

    def step(o, h_next):  # h_i (n,) of the intervals in column o from h_{i+1} (n,)
        return np.minimum(largest[:, o], np.min(h_next[:, None] * inverse[:, o] + offset[:, o], axis=1))

    return chunks.settle(h, step, reverse=True)


def forward(s, dq, ddq, acceleration, h, start):
    """The greedy forward pass: x (G,) from x_0 = ``start`` (<= h_0), as fast as h and the bands allow."""
    bands = _Bands(np.diff(s), dq, ddq, np.asarray(acceleration, dtype=float))
    x = h.copy()
    x[0] = start
    chunks = _Chunks(len(h))
    sigma, w, h_next = chunks.laid(bands.sigma, 0.0), chunks.laid(bands.w, np.inf), chunks.laid(h[1:], 0.0)

    def step(o, x):  # x_{i+1} (n,) of the intervals in column o from x_i (n,)
        return np.minimum(h_next[:, o], np.min(sigma[:, o] * x[:, None] + w[:, o], axis=1))

    return np.maximum(chunks.settle(x, step, reverse=False), 0.0)


def chunk_length(stages):
    """Grid intervals per chunk of a grid of ``stages`` intervals: about its square root, 16 to `LONGEST_CHUNK`."""
    return int(np.clip(np.sqrt(stages), 16, LONGEST_CHUNK))


class _Chunks:
    """The intervals of a grid of ``points`` points as (n, L) chunks of L consecutive intervals.

    Interval c * L + o is row c, column o; the last chunk is padded with
    intervals that bound nothing, and the values of the grid points with
    0 beyond the last point (finite: a padded interval's 0 * value stays 0).
    """

    def __init__(self, points):
        self.points = points
        self.length = chunk_length(points - 1)
        self.count = -(-(points - 1) // self.length)

    def laid(self, per_interval, fill):
        """Per-interval values (G - 1, ...) as (n, L, ...), padded with ``fill``."""
        pad = np.full((self.count * self.length - len(per_interval), *per_interval.shape[1:]), fill)
        return np.concatenate([per_interval, pad]).reshape(self.count, self.length, *per_interval.shape[1:])

    def settle(self, values, step, *, reverse):
        """The recurrence over ``values`` (G,), a new array (G,): backward ``values[i] = min(values[i],
        step(values[i + 1]))``, forward ``values[i + 1] = step(values[i])``, ``step(o, v)`` for column o.

        All chunks are swept at once; the sweeps are repeated while a value
        a chunk started from (its border) changed during the sweep.
        """
        L = self.length
        padded = np.concatenate([values, np.zeros(self.count * L + 1 - len(values))])
        table = padded[:-1].reshape(self.count, L)
        borders = padded[L::L]  # each chunk's point after its last interval: the next chunk's first point
        while True:
            if reverse:
                before = borders.copy()
                table[:, L - 1] = np.minimum(table[:, L - 1], step(L - 1, borders))
                for o in range(L - 2, -1, -1):
                    table[:, o] = np.minimum(table[:, o], step(o, table[:, o + 1]))
                if np.array_equal(borders, before):
                    return padded[: self.points]
            else:
                before = table[:, 0].copy()
                for o in range(L - 1):
                    table[:, o + 1] = step(o, table[:, o])
                borders[:] = step(L - 1, table[:, L - 1])
                if np.array_equal(table[:, 0], before):
                    return padded[: self.points]


class _Bands:
    """The bands ``sigma x_i - w <= x_{i+1} <= sigma x_i + w`` (G-1, 12) of every interval, and x_i-only bounds."""

    def __init__(self, ds, dq, ddq, acceleration):
        # alpha x_i + beta x_{i+1} in [-a, a]: joint j at the interval's start (first 6), at its end (last 6)
        two_ds = 2.0 * ds[:, None]
        beta = np.hstack([dq[:-1] / two_ds, dq[1:] / two_ds + ddq[1:]])
        alpha = np.hstack([ddq[:-1] - dq[:-1] / two_ds, -dq[1:] / two_ds])
        a = np.concatenate([acceleration, acceleration], axis=-1)
        moving = beta != 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            self.sigma = np.where(moving, -alpha / beta, 0.0)
            self.w = np.where(moving, a / np.abs(beta), np.inf)
            self.x_bound = np.min(np.where(moving, np.inf, a / np.abs(alpha)), axis=1)

    def backward(self, i, h_next):
        """Largest x_i (n,) of intervals i (n,) from which x_{i+1} <= h_next (n,) can be kept (and X_i)."""
        sigma = self.sigma[i]
        with np.errstate(divide="ignore", invalid="ignore"):
            reach = np.where(sigma > 0.0, (h_next[:, None] + self.w[i]) / sigma, np.inf)
        return np.minimum(self.largest[i], np.min(reach, axis=1))

    def forward(self, i, x):
        """Largest x_{i+1} (n,) the bands of intervals i (n,) allow from x_i = x (n,)."""
        return np.min(self.sigma[i] * x[:, None] + self.w[i], axis=1)

    def largest_x(self, x_max):
        """X_i (G-1,): the largest x_i <= x_max (G-1,) with some x_{i+1} >= 0 inside every band.

        The feasible x_i form an interval [0, X_i] (rest is inside every
        band); the gap ``min(upper) - max(0, lower)`` is concave in x_i, so
        Newton's method from the right converges to X_i in a few steps.
        """
        x = np.minimum(x_max, self.x_bound)
        todo = np.arange(len(x))
        for _ in range(100):
            sigma, w = self.sigma[todo], self.w[todo]
            upper, lower = sigma * x[todo, None] + w, sigma * x[todo, None] - w
            iu, il = np.argmin(upper, axis=1), np.argmax(lower, axis=1)
            rows = np.arange(len(todo))
            top, bottom = upper[rows, iu], lower[rows, il]
            gap = top - np.maximum(bottom, 0.0)
            bad = gap < -1e-12 * np.abs(top)
            if not bad.any():
                break
            slope = sigma[rows, iu] - np.where(bottom > 0.0, sigma[rows, il], 0.0)
            todo, gap, slope = todo[bad], gap[bad], slope[bad]
            x[todo] = np.maximum(x[todo] - gap / np.minimum(slope, -1e-300), 0.0)
        self.largest = np.append(x, 0.0)
        return x
