"""Measured landings of a compensated program: a validation run's measurements matched to its targets.

The compensated program is run on the arm and its TCP measured at each
target (`trajcomp compensate --measured RUN.csv`, the measurement CSV of
`docs/conventions.md`: the commanded joints j1..j6 as written, mx, my, mz).
Each measured row is the run of the targets whose written joints it
commanded (a command measured more than once: the mean of its rows), and
the target's measured landing is the distance from its target position to
the measured one. The compliance report shows it beside
the landing estimate, and how often the estimate covered it.
"""

import numpy as np
from scipy.spatial import cKDTree

from trajcomp.errors import ReadError
from trajcomp.report.verdict import check

MATCH_DEG = 0.01  # a row commanding every joint within this of a target's written joints measured that target


def measured_landing(report, meas, T_tracker_base=None):
    """The measured landing error of each target, mm (N,), NaN where no row measured it.

    Parameters
    ----------
    report : ProgramReport
        The compensation's targets (``T_target`` (N, 4, 4), written joints ``q`` (N, 6) rad).
    meas : Measurements
        The validation run (`trajcomp.calibration.measurements.read_validation_run`): commanded joints and
        measured TCP positions, base frame (or tracker frame, when its layout
        says so and ``T_tracker_base`` is given).
    T_tracker_base : ndarray, shape (4, 4), optional
        The model's tracker registration, for rows measured in the tracker frame.

    Raises
    ------
    ReadError
        Rows measured in the tracker frame without a registration, or
        commanding joints no target was written with (file and line named).
    """
    measured = meas.measured
    if meas.frame == "tracker":
        if T_tracker_base is None:
            raise ReadError(f"{meas.path}: measured in the tracker frame, but the model has no tracker registration")
        measured = measured @ T_tracker_base[:3, :3].T + T_tracker_base[:3, 3]
    q, joints = np.degrees(np.reshape(report.q, (-1, 6))), np.degrees(meas.joints)
    landing = np.full(len(q), np.nan)
    if not len(q):
        return landing
    apart, _ = cKDTree(q).query(joints, p=np.inf)
    if (apart > MATCH_DEG).any():
        line = int(meas.lines[np.argmax(apart > MATCH_DEG)])
        raise ReadError(f"{meas.path}:{line}: j1..j6: no target of the program was written with these joints "
                        f"(within {MATCH_DEG:g} deg): measure the compensated program as written")
    rows = cKDTree(joints)
    apart, row = rows.query(q, p=np.inf)
    seen = np.flatnonzero(apart <= MATCH_DEG)
    landed = measured[row[seen]]
    repeated = rows.query_ball_point(q[seen], MATCH_DEG, p=np.inf, return_length=True) > 1
    for k in np.flatnonzero(repeated):  # a command measured more than once: where it landed on average
        landed[k] = measured[rows.query_ball_point(q[seen[k]], MATCH_DEG, p=np.inf)].mean(axis=0)
    landing[seen] = np.linalg.norm(landed - np.asarray(report.T_target)[seen, :3, 3], axis=1)
    return landing


def measured_summary(landing, estimate, tolerance):
    """What the measured landings say of the forecast: the report's ``measured`` section (None without any).

    Parameters
    ----------
    landing : ndarray, shape (N,)
        `measured_landing`, mm (NaN: not measured).
    estimate : ndarray, shape (N,)
        The landing estimates, mm.
    tolerance : float
        mm.
    """
    seen = np.isfinite(landing)
    if not seen.any():
        return None
    true, forecast = landing[seen], estimate[seen]
    return {"targets": int(seen.sum()), "mean_mm": float(true.mean()), "max_mm": float(true.max()),
            "covered": float(np.mean(forecast >= true)),
            "sharpness": float(np.median(forecast / np.maximum(true, 1e-9))),
            "above_tolerance": int(np.sum(true > tolerance))}


def measured_check(landing, labels, tolerance):
    """The ``measured`` criterion: every measured landing within the tolerance (a Check)."""
    seen = np.isfinite(landing)
    worst = np.nanmax(landing)
    return check("measured", f"every measured landing within {tolerance:g} mm", seen & (landing > tolerance), labels,
                 f"largest measured landing {worst:.4f} mm of {int(seen.sum())} measured targets")
