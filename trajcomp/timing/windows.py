"""Long runs in windows: memory bounded by the window, one time law across the joins.

A continuous run of more than `WINDOW` motions (a CAM path of a million
points) is cut at every `WINDOW`-th waypoint. Each window's path is fitted
on its own motions and `OVERLAP` motions beyond each cut
(`trajcomp.timing.path.run_path` with ``part``), so that near a cut it is
the path a fit of the whole run gives; consecutive windows share the cut
waypoint, a grid point of both. The TOPP-RA passes then go across the
windows (`trajcomp.timing.toppra_run.toppra_laws`): one problem over the
whole run, solved window by window.

What holds at a join: the path speed is one value from both sides (the
laws are continuous in time and speed); both windows' paths pass within
the path tolerance of the shared waypoint, computed from the same samples;
each side is dense-checked against the limits like any other run. The
path's direction and curvature may differ between the two fits by their
(small) fitting difference, so the joint acceleration may step there, as
it does at every grid point of a TOPP-RA law.
"""

import dataclasses

import numpy as np

from trajcomp.timing.path import run_path

WINDOW = 20_000  # motions per window
OVERLAP = 256  # motions fitted beyond each cut


def run_windows(moves, robot, first, last, tolerance, window=WINDOW):
    """The fitted paths (list of RunPath) of consecutive windows of waypoints ``first..last``.

    Parameters
    ----------
    moves : Moves
    robot : Robot
    first, last : int
        Waypoints of one run.
    tolerance : float
        Path tolerance, mm.
    window : int or None
        Largest number of motions of a window; None: one window.
    """
    if window is None or last - first <= window:
        return [run_path(moves, robot, first, last, tolerance)]
    cuts = np.r_[np.arange(first, last, window), last]
    return [window_path(moves.rows(lo, hi + 1), robot, lo, tolerance, (a, b))
            for a, b in zip(cuts[:-1].tolist(), cuts[1:].tolist())
            for lo, hi in [(max(first, a - OVERLAP), min(last, b + OVERLAP))]]


def window_path(rows, robot, offset, tolerance, part):
    """The fitted path (RunPath) of one window: a function of the window's own data alone.

    Parameters
    ----------
    rows : Moves
        The waypoints fitted, ``moves.rows(offset, offset + len(rows))``:
        the window and its overlaps.
    robot : Robot
    offset : int
        Index of ``rows``' first waypoint in the whole sequence.
    tolerance : float
        Path tolerance, mm.
    part : (int, int)
        Waypoints ``a..b`` of the whole sequence the window returns.

    Returns
    -------
    RunPath
        Indexed in the whole sequence.
    """
    a, b = part
    run = run_path(rows, robot, 0, len(rows) - 1, tolerance, part=(a - offset, b - offset))
    return dataclasses.replace(run, first=run.first + offset, last=run.last + offset)
