"""Calibration: from measurements to a compensation model, with cross-validation.

One call fits every part the data allows (the paper's linear correction, the
DH identification, the grid of raw errors, the grid of residuals after the DH
model), so that `validate` can compare the modes on the same model. Fit and
k-fold cross-validation statistics are recorded in the model's report.
"""

import logging

import numpy as np

from trajcomp.errors import CalibrationError
from trajcomp.grid import fit_field
from trajcomp.identify import best_fit_transform, identify_dh
from trajcomp.ik import ik
from trajcomp.kinematics import fk
from trajcomp.linear import fit_linear
from trajcomp.model import CompensationModel
from trajcomp.plan import batch_seed
from trajcomp.stats import ErrorStats, kfold_indices
from trajcomp.transforms import invert, pose_to_matrix

log = logging.getLogger(__name__)

METHODS = ("linear", "dh", "grid", "composite")
LATTICE_INTERPOLATORS = ("idw8", "trilinear")


def commanded(robot, meas):
    """Commanded joints (N, 6) rad and TCP positions (N, 3) mm of measurement rows.

    Joints come from the file, or from nominal IK of the commanded pose (None
    when the file gives positions only); positions from the file, or from
    nominal FK of the joints.
    """
    joints = meas.joints
    if joints is None and meas.orientation is not None:
        targets = pose_to_matrix(np.column_stack([meas.position, meas.orientation]))
        joints = ik(robot, targets, seed=batch_seed(robot, targets)).raise_on_failure(meas.path).q
    position = meas.position if meas.position is not None else fk(robot, joints)[:, :3, 3]
    return joints, position


def _rows(array, index):
    """``array[index]``, passing None through (optional measurement columns)."""
    return None if array is None else array[index]


def to_base(T_tracker_base, measured):
    """Tracker-frame positions (N, 3) expressed in the base frame."""
    T_base_tracker = invert(T_tracker_base)
    return measured @ T_base_tracker[:3, :3].T + T_base_tracker[:3, 3]


class _Parts:
    """The fitted parts of a model, from one training set."""

    def __init__(self, robot, joints, position, measured, *, method, grid_step, interpolation, loss):
        errors = measured - position
        self.linear = fit_linear(position, errors)
        self.dh = None
        self.grid = None
        self.residual = None
        if joints is not None and method in ("dh", "composite"):
            self.dh = identify_dh(robot, joints, measured, loss=loss)
        if method in ("grid", "composite"):
            self.grid = fit_field(position, errors, step=grid_step, interpolation=interpolation)
            if self.dh is not None:
                self.residual = fit_field(position, self.dh.residuals, step=grid_step, interpolation=interpolation)

    def model(self, robot, robot_ref, method, T_tracker_base, report):
        dh = self.dh
        return CompensationModel(
            nominal=robot,
            robot_ref=robot_ref,
            method=method,
            T_tracker_base=T_tracker_base,
            dh_names=list(dh.names) if dh else [],
            dh_delta=dh.delta if dh else np.zeros(0),
            dh_sigma=dh.sigma if dh else np.zeros(0),
            dh_fixed=dict(dh.identifiability.fixed) if dh else {},
            linear=self.linear,
            grid=self.grid,
            residual=self.residual,
            report=report,
        )


def mode_errors(model, joints, position, measured, interpolation=None):
    """Measured minus predicted positions (N, 3) per available mode, as a dict."""
    return {
        mode: measured - model.predict(mode, joints, position, interpolation=interpolation, outside="clamp")[0]
        for mode in model.modes
    }


def calibrate(robot, meas, *, robot_ref=None, method="composite", frame="base", grid_step=None,
              interpolation="idw8", loss="linear", folds=5, seed=0, progress=None):
    """Identify a compensation model from measurements.

    Parameters
    ----------
    robot : Robot
        Nominal robot.
    meas : Measurements
        Commanded joints and/or poses with measured TCP positions.
    robot_ref : str, optional
        How the robot is named in the model file (default: its name).
    method : {"linear", "dh", "grid", "composite"}
        The model's default mode; every part it needs is fitted.
    frame : {"base", "tracker"}
        Frame of the measured positions; ``tracker`` estimates the base
        registration (best-fit rigid transform, refined by the DH fit).
    grid_step : float, optional
        Expected lattice step, mm (checked against the data).
    interpolation : str
        Interpolator of the grids (idw8, trilinear, knn, rbf).
    loss : str
        Robust loss of the DH fit (linear, soft_l1, huber, cauchy).
    folds : int
        k of the k-fold cross-validation (0 or 1: none).
    seed : int
        Seeds the fold split.
    progress : callable, optional
        Called with a text line as the folds run.

    Returns
    -------
    CompensationModel
        Its ``report`` holds ``fit`` and ``cross_validation`` statistics per
        mode, ``warnings`` and the outlier rows.

    Raises
    ------
    CalibrationError
        Unknown method, no measured columns, joints missing for a DH method,
        too few points for the parameters, or a degenerate grid.
    """
    if method not in METHODS:
        raise CalibrationError(f"unknown method {method!r} (one of {', '.join(METHODS)})")
    if meas.measured is None:
        raise CalibrationError(f"{meas.path}: measured columns mx, my, mz are required")
    joints, position = commanded(robot, meas)
    if joints is None and method in ("dh", "composite"):
        raise CalibrationError(f"{meas.path}: method {method} needs commanded joints j1..j6 or a full pose x..c")
    warnings = []
    measured = meas.measured
    T_tracker_base = np.eye(4)
    if frame == "tracker":
        T_tracker_base = best_fit_transform(position, measured)
        measured = to_base(T_tracker_base, measured)
    _, first, counts = np.unique(np.round(position, 3), axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        lines = meas.lines[np.sort(first[counts > 1])][:10].tolist()
        warnings.append(f"{int((counts - 1).sum())} rows repeat an earlier command (first at lines {lines}); their measurements are averaged by the grid")
    options = dict(method=method, grid_step=grid_step, interpolation=interpolation, loss=loss)
    parts = _Parts(robot, joints, position, measured, **options)
    keep = np.ones(len(meas), dtype=bool)
    if parts.dh is not None and len(parts.dh.outliers):
        keep[parts.dh.outliers] = False
        lines = meas.lines[parts.dh.outliers].tolist()
        warnings.append(f"{len(lines)} gross outliers (residual far beyond the others) left out, lines {lines[:20]}")
        parts = _Parts(robot, joints[keep], position[keep], measured[keep], **options)
    joints, position, measured = _rows(joints, keep), position[keep], measured[keep]
    report = {
        "measurements": {"file": meas.path, "rows": len(meas), "used": int(keep.sum()), "frame": frame},
        "warnings": warnings,
        "outlier_lines": meas.lines[~keep].tolist(),
    }
    if parts.dh is not None:
        report["identifiability"] = {"condition": parts.dh.identifiability.condition}
    model = parts.model(robot, robot_ref or robot.name, method, T_tracker_base, report)
    report["fit"] = {m: ErrorStats.from_errors(e).as_dict() for m, e in mode_errors(model, joints, position, measured).items()}
    if folds > 1:
        report["cross_validation"] = cross_validate(
            robot, joints, position, measured, options, folds, seed, progress
        )
    for message in warnings:
        log.warning(message)
    return model


def cross_validate(robot, joints, position, measured, options, folds, seed, progress=None):
    """k-fold cross-validation statistics per mode, as a dict of ErrorStats dicts.

    Held-out nodes leave holes in a lattice, so the folds evaluate the
    lattice interpolators (idw8, trilinear) by their scattered counterpart,
    inverse-distance weighting over the 8 nearest training nodes; the report
    names the interpolator the folds used.
    """
    if len(position) < 2 * folds:
        raise CalibrationError(f"{len(position)} measurements are too few for {folds}-fold cross-validation")
    if options["interpolation"] in LATTICE_INTERPOLATORS:
        options = options | {"interpolation": "knn", "grid_step": None}
    collected = {}
    for k, (train, test) in enumerate(kfold_indices(len(position), folds, seed)):
        if progress:
            progress(f"cross-validation fold {k + 1}/{folds}")
        parts = _Parts(robot, _rows(joints, train), position[train], measured[train], **options)
        model = parts.model(robot, robot.name, options["method"], np.eye(4), {})
        for mode, err in mode_errors(model, _rows(joints, test), position[test], measured[test]).items():
            collected.setdefault(mode, []).append(err)
    return {"folds": folds, "interpolation": options["interpolation"]} | {m: ErrorStats.from_errors(np.concatenate(e)).as_dict() for m, e in collected.items()}
