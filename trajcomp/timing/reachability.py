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
exactly the sequential recurrence's. A step costs a few numpy calls on
contiguous (chunks, 12) columns, so the time is about R + chunk_length
steps: consecutive windows of a long run are solved as one problem
(`Bands.of_paths`, `trajcomp.timing.toppra_run.toppra_laws`), so that a
ramp is swept once, not once per window.
"""

import numpy as np

LONGEST_CHUNK = 256  # grid intervals per chunk at most (about the square root of the grid below that)


def squared_speeds(s, dq, ddq, acceleration, x_max, rest, *, ramp=None):
    """Time-optimal squared path speeds x (G,) under joint acceleration limits and speed bounds.

    Parameters
    ----------
    s : ndarray, shape (G,)
        Grid, strictly increasing (rad of path).
    dq, ddq : ndarray, shape (G, n)
        Path derivatives q'(s), q''(s) at the grid points (n = 6, or 7 with a moving track's position).
    acceleration : ndarray, shape (n,) or (G - 1, n)
        Joint acceleration limits, rad/s^2 (per interval: independent runs in one problem).
    x_max : ndarray, shape (G,)
        Upper bound of x at each grid point (joint velocity, TCP speed), finite.
    rest : array_like of int
        Grid points where the path speed is 0 (at least the first and the last).
    ramp : int, optional
        Most grid intervals between two rest points (independent runs in
        one problem): chunks no longer than that settle in one or two
        sweeps. Default: about the square root of the grid (`chunk_length`).

    Returns
    -------
    ndarray, shape (G,)
        x = sd^2, 0 at the rest points.
    """
    x_max = np.array(x_max, dtype=float)
    x_max[rest] = 0.0
    bands = Bands.of_path(np.diff(s), dq, ddq, acceleration)
    length = None if ramp is None else min(ramp, chunk_length(len(s) - 1))
    return forward(bands, backward(bands, x_max, end=0.0, length=length), start=0.0, length=length)


def backward(bands, x_max, end, *, length=None):
    """The controllable bounds h (G,): from x_i <= h_i the path can go on to x_{G-1} <= ``end``.

    Parameters
    ----------
    bands : Bands
        Of the G - 1 grid intervals.
    x_max : ndarray, shape (G,)
        Upper bound of x at each grid point, finite.
    end : float
        The bound at the last grid point (0: rest there; for a window, the next window's bound).
    length : int, optional
        Grid intervals per chunk; default `chunk_length`.
    """
    largest = bands.largest_x(x_max[:-1])
    h = np.append(largest, min(end, x_max[-1]))
    chunks = _Chunks(len(h), length)
    inverse, offset = chunks.laid(bands.sigma, 0.0), chunks.laid(bands.w, np.inf)  # made in place from here
    rising = inverse > 0.0  # x_i <= (h_{i+1} + w) / sigma for the bands with sigma > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        np.divide(offset, inverse, out=offset, where=rising)
        np.divide(1.0, inverse, out=inverse, where=rising)
    falling = ~rising
    offset[falling], inverse[falling] = np.inf, 0.0
    largest = chunks.laid(largest, np.inf)
    reach = np.empty(inverse.shape[1:])

    def step(o, h_next, out):  # out = h_i (n,) of the intervals in column o from h_{i+1} (n,)
        np.multiply(inverse[o], h_next[:, None], out=reach)
        np.add(reach, offset[o], out=reach)
        np.minimum.reduce(reach, axis=1, out=out)
        np.minimum(out, largest[o], out=out)

    return chunks.settle(h, step, reverse=True)


def forward(bands, h, start, *, length=None):
    """The greedy forward pass: x (G,) from x_0 = ``start`` (<= h_0), as fast as h (G,) and the bands
    (`Bands` of the G - 1 intervals) allow; ``length``: grid intervals per chunk (default `chunk_length`)."""
    x = h.copy()
    x[0] = start
    chunks = _Chunks(len(h), length)
    sigma, w, h_next = chunks.laid(bands.sigma, 0.0), chunks.laid(bands.w, np.inf), chunks.laid(h[1:], 0.0)
    reach = np.empty(sigma.shape[1:])

    def step(o, x, out):  # out = x_{i+1} (n,) of the intervals in column o from x_i (n,)
        np.multiply(sigma[o], x[:, None], out=reach)
        np.add(reach, w[o], out=reach)
        np.minimum.reduce(reach, axis=1, out=out)
        np.minimum(out, h_next[o], out=out)

    return np.maximum(chunks.settle(x, step, reverse=False), 0.0)


def chunk_length(stages):
    """Grid intervals per chunk of a grid of ``stages`` intervals: about its square root, 16 to `LONGEST_CHUNK`."""
    return int(np.clip(np.sqrt(stages), 16, LONGEST_CHUNK))


class _Chunks:
    """The intervals of a grid of ``points`` points as n chunks of L consecutive intervals, laid column-major.

    Interval c * L + o is column o, chunk c: per-interval data is laid out
    (L, n, ...), so that one step of a sweep (column o of every chunk)
    reads contiguous memory. The last chunk is padded with intervals that
    bound nothing, and the values of the grid points with 0 beyond the
    last point (finite: a padded interval's 0 * value stays 0).
    """

    def __init__(self, points, length=None):
        self.points = points
        self.length = chunk_length(points - 1) if length is None else max(int(length), 1)
        self.count = -(-(points - 1) // self.length)

    def laid(self, per_interval, fill):
        """Per-interval values (G - 1, ...) as (L, n, ...), padded with ``fill``."""
        L, full = self.length, len(per_interval) // self.length  # chunks without padding
        out = np.empty((L, self.count, *per_interval.shape[1:]))
        chunks = np.swapaxes(out, 0, 1)  # (n, L, ...) view: one copy into the laid-out array
        chunks[:full] = per_interval[: full * L].reshape(full, L, *per_interval.shape[1:])
        if full < self.count:
            chunks[full, : len(per_interval) - full * L] = per_interval[full * L :]
            chunks[full, len(per_interval) - full * L :] = fill
        return out

    def settle(self, values, step, *, reverse):
        """The recurrence over ``values`` (G,), a new array (G,): backward ``values[i] = min(values[i],
        step(values[i + 1]))``, forward ``values[i + 1] = step(values[i])``; ``step(o, v, out)`` writes
        column o's result from v (n,) into out (n,).

        All chunks are swept at once; the sweeps are repeated while a value
        a chunk started from (its border: the next chunk's first point
        backward, its own first point forward) changed during the sweep.
        """
        L, n = self.length, self.count
        padded = np.concatenate([values, np.zeros(n * L + 1 - len(values))])
        table = padded[:-1].reshape(n, L).T.copy()  # (L, n): table[o, c] is point c * L + o
        borders = np.append(table[0, 1:], padded[-1])  # each chunk's point after its last interval
        out = np.empty(n)
        while True:
            if reverse:
                step(L - 1, borders, out)
                np.minimum(table[L - 1], out, out=table[L - 1])
                for o in range(L - 2, -1, -1):
                    step(o, table[o + 1], out)
                    np.minimum(table[o], out, out=table[o])
                if np.array_equal(table[0, 1:], borders[:-1]):
                    break
                borders[:-1] = table[0, 1:]
            else:
                before = table[0].copy()
                for o in range(L - 1):
                    step(o, table[o], table[o + 1])
                step(L - 1, table[L - 1], borders)
                table[0, 1:] = borders[:-1]
                if np.array_equal(table[0], before):
                    break
        padded[:-1], padded[-1] = table.T.ravel(), borders[-1]
        return padded[: self.points]


class Bands:
    """The bands ``sigma x_i - w <= x_{i+1} <= sigma x_i + w`` of grid intervals, and x_i-only bounds.

    Attributes
    ----------
    sigma, w : ndarray, shape (I, 2 n)
        Per interval: joint j's acceleration limit at the interval's start
        (first n) and end (last n); w = inf where the joint does not move.
        n = 6, or 7 with a moving track as the last joint (mm, mm/s^2).
    x_bound : ndarray, shape (I,)
        Bound on x_i alone (a joint that does not move).
    """

    def __init__(self, sigma, w, x_bound):
        self.sigma, self.w, self.x_bound = sigma, w, x_bound

    @classmethod
    def of_path(cls, ds, dq, ddq, acceleration):
        """The bands of a grid's intervals ds (G - 1,), from q', q'' (G, n) at the grid points and the joint
        acceleration limits (n,) or (G - 1, n), rad/s^2 (a track's: mm/s^2)."""
        return cls.of_paths([(ds, dq, ddq, acceleration)], len(ds))

    @classmethod
    def of_paths(cls, paths, intervals):
        """The bands of consecutive grids laid end to end (each grid's last point the next one's first), ``intervals``
        in all: `of_path` of each ``(ds, dq, ddq, acceleration)`` of ``paths``, in order, written into the joined
        arrays. ``paths`` may be any iterable (a generator): it is consumed once, so that the paths made one after
        the other are never all held at once."""
        bands, at = None, 0
        for ds, dq, ddq, acceleration in paths:
            if bands is None:
                bands = cls(*np.empty((2, intervals, 2 * dq.shape[1])), np.empty(intervals))
            bands._fill(slice(at, at + len(ds)), ds, dq, ddq, acceleration)
            at += len(ds)
        return bands

    def _fill(self, rows, ds, dq, ddq, acceleration):
        """Write the bands of a grid's intervals ds (``rows``) from q', q'' and the acceleration limits (`of_path`)."""
        # alpha x_i + beta x_{i+1} in [-a, a]: joint j at the interval's start (first n), at its end (last n)
        two_ds, n = 2.0 * ds[:, None], dq.shape[1]  # n: the arm's 6 joints, and a track's position (7)
        beta, alpha = np.empty((2, len(ds), 2 * n))  # filled in place, then made the bands and bounds in place
        np.divide(dq[:-1], two_ds, out=beta[:, :n])
        np.divide(dq[1:], two_ds, out=alpha[:, n:])
        np.add(alpha[:, n:], ddq[1:], out=beta[:, n:])
        np.subtract(ddq[:-1], beta[:, :n], out=alpha[:, :n])
        np.negative(alpha[:, n:], out=alpha[:, n:])
        acceleration = np.asarray(acceleration, dtype=float)
        a = np.concatenate([acceleration, acceleration], axis=-1)
        sigma, w = self.sigma[rows], self.w[rows]
        still = beta == 0.0  # a joint that does not move: no band, a bound on x_i alone
        with np.errstate(divide="ignore", invalid="ignore"):
            np.negative(np.divide(alpha, beta, out=sigma), out=sigma)
            np.divide(a, np.abs(beta, out=beta), out=w)
            if not still.any():
                self.x_bound[rows] = np.inf
                return
            sigma[still], w[still] = 0.0, np.inf
            np.divide(a, np.abs(alpha, out=alpha), out=alpha)
            alpha[~still] = np.inf
            np.min(alpha, axis=1, out=self.x_bound[rows])

    def largest_x(self, x_max):
        """X_i (G-1,): the largest x_i <= x_max (G-1,) with some x_{i+1} >= 0 inside every band.

        The feasible x_i form an interval [0, X_i] (rest is inside every
        band); the gap ``min(upper) - max(0, lower)`` is concave in x_i, so
        Newton's method from the right converges to X_i in a few steps.
        """
        x = np.minimum(x_max, self.x_bound)
        todo = np.arange(len(x))
        sigma, w = self.sigma, self.w  # every interval at first (no copy), then those still left
        for _ in range(100):
            upper = sigma * x[todo, None]
            lower = upper - w
            upper += w
            iu, il = np.argmin(upper, axis=1), np.argmax(lower, axis=1)
            rows = np.arange(len(todo))
            top, bottom = upper[rows, iu], lower[rows, il]
            gap = top - np.maximum(bottom, 0.0)
            bad = gap < -1e-12 * np.abs(top)
            if not bad.any():
                break
            slope = sigma[rows, iu] - np.where(bottom > 0.0, sigma[rows, il], 0.0)
            todo, gap, slope, sigma, w = todo[bad], gap[bad], slope[bad], sigma[bad], w[bad]
            x[todo] = np.maximum(x[todo] - gap / np.minimum(slope, -1e-300), 0.0)
        return x
