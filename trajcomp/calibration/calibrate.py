"""Calibration: from measurements to a compensation model, with cross-validation.

One call fits every part the data allows (the paper's linear correction, the
kinematic identification with TCP and tracker registration, the grid of raw
errors, and the composite's residual after the kinematic model), so that
`validate` can compare the modes on the same model. Data that cannot be what
it claims is refused (`trajcomp.calibration.plausibility`). Gross outliers are named by
line; the robust loss bounds their pull on the fit, and they are left out of
the grids and statistics, their nodes filled from the model. Fit and k-fold cross-validation statistics are
recorded in the model's report.

The composite's residual depends on the data: measured at one tool
orientation (the paper's protocol), it is a field over the commanded
position (``idw8`` by default); measured at several orientations or with
orientations (6-DoF), it is the joint-angle error model of
`trajcomp.model.joint_errors`, identified with a refinement of the DH parameters,
which holds at any orientation and for any tool; its spline terms (knot
step, and the penalties whose fits it averages) are chosen on held-out
regions of the measurements, never on interleaved rows, and the choice with
every candidate's held-out error is recorded in the report
(``joint_splines``). The k-fold cross-validation refits with that choice.
"""

import dataclasses
import logging

import numpy as np
from scipy.spatial import cKDTree

from trajcomp.calibration.options import CALIBRATION_METHODS, INTERPOLATIONS, LOSSES, ORIENTATION_WEIGHT
from trajcomp.errors import CalibrationError
from trajcomp.model import landing
from trajcomp.model.grid import TOLERANCE, ResidualGrid, detect_lattice, fit_field
from trajcomp.model.interpolate import GP_MAX_POINTS, WRIST, GaussianField
from trajcomp.model.options import GP_KIND, KNN_KIND, LATTICE_KINDS
from trajcomp.calibration.identify import (best_fit_transform, identify, linearise, outlier_rows, region_folds,
                                           select_splines)
from trajcomp.arm.ik import batch_seed, branch_index, ik
from trajcomp.model.joint_errors import KIND as JOINT_KIND
from trajcomp.model.joint_errors import JointResidual, is_term
from trajcomp.arm.kinematics import fk
from trajcomp.model.linear import fit_linear
from trajcomp.model.compensation_model import CompensationModel
from trajcomp.calibration.orientations import MIN_AXIS_OFFSET, MIN_SPREAD, axis_offset, locates_flange, orientation_spread
from trajcomp.arm.parameters import is_robot_parameter
from trajcomp.calibration.plausibility import check_columns, check_identification, check_units
from trajcomp.model.stats import ErrorStats, kfold_indices
from trajcomp.support.parallel import share_blocks
from trajcomp.arm.transforms import abc_to_matrix, invert, pose_to_matrix

log = logging.getLogger(__name__)

MAX_ROWS = 100_000  # measurements one calibration fits: 12 min and 1.3 GB (2-core machine shared by 6 runs)
LAYER_PLANES = 20  # positions with at most this many distinct coordinates along an axis are node planes along it
OUTER_SHARE = 0.1  # the outer layer of scattered positions: this share of the rows on each side of an axis
OUTER_LAYERS = 2  # outer layers held out on each side of each axis, one and two at a time
RELIABILITY_BINS = 8  # bins of the stated quantile per class of holdout in the calibration report's reliability
FIELD_ON_TOP = "knn"  # the raw-error grid of a joint residual: scattered, so held-out rows leave no hole
GP_SCORED_ROWS = 1000  # training rows (every k-th of more) a gp field is fitted on while scored on held-out regions
GP_TRIED = {"lengths": (150.0, 300.0, 600.0), "nuggets": (0.01, 0.03, 0.1, 0.3)}  # a gp field on top, per region


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


def temperature_range(temperature):
    """``{"min", "mean", "max"}`` of a temperature column (N,), deg C, as a report records it."""
    return {key: round(float(f(temperature)), 3) for key, f in (("min", np.min), ("mean", np.mean), ("max", np.max))}


def register(model, joints, position, measured):
    """Base pose (4, 4) in a new tracker placement, from reference rows measured there.

    The model's predicted positions (its default mode) of the reference rows
    are fitted rigidly to their measured positions (tracker frame), as
    `trajcomp.calibration.identify.best_fit_transform`.

    Raises
    ------
    CalibrationError
        Fewer than 3 reference rows.
    """
    if len(measured) < 3:
        raise CalibrationError(f"{len(measured)} reference rows cannot register a tracker: at least 3 are needed")
    predicted = model.predict(model.method, joints, position, outside="clamp")[0]
    return best_fit_transform(predicted, measured)


def residual_kind(interpolation, joints, spread, oriented):
    """The composite residual's kind for ``interpolation`` ('auto' chooses from the data).

    ``auto`` takes the joint residual for data at several orientations or
    with orientations, else idw8: measured at one orientation, the joint
    residual wins on held-out regions of that orientation but lands worse
    than the DH model alone on targets tilted away from it (virtual UR10,
    paper cube: 0.18 against 0.09 mm mean at 15 deg, bench_accuracy.py).
    """
    if interpolation not in INTERPOLATIONS:
        raise CalibrationError(f"unknown interpolation {interpolation!r} (one of {', '.join(INTERPOLATIONS)})")
    if interpolation == "auto":
        several = joints is not None and (oriented or spread[0] >= MIN_SPREAD)
        return JOINT_KIND if several else "idw8"
    if interpolation == JOINT_KIND and joints is None:
        raise CalibrationError("the joint residual needs the commanded joints j1..j6 or full poses x..c")
    return interpolation


class _Parts:
    """The fitted parts of a model, from one training set in the base frame.

    ``dh`` may be given (the full-data fit, which also registered the
    tracker, or a cross-validation fold's refit of it), and with it the
    joint ``residual`` and the ``splines`` record of its selection (a
    fold's). Gross outliers (`trajcomp.calibration.identify.outlier_rows` of the best
    kinematic model's residuals: the joint residual's when there is one)
    pull little on the robust fits; the linear fit and the scattered fields
    leave them out, the lattice grids fill their nodes from the model. A
    ``gp`` field on top chooses its length and nugget by likelihood unless
    ``splines`` gives them (``field_options``: a fold keeps the full fit's);
    the record it keeps (``selection``) names them.
    """

    def __init__(self, robot, joints, position, measured, rotation, *, method, grid_step, kind, loss,
                 orientation_weight, R_tcp_target=None, dh=None, residual=None, splines=None, workers=1):
        self.dh = dh
        self.grid = None
        self.residual = None
        self.residual_field = None
        self.selection = None
        self.shares = ()
        self.left_out = np.zeros(len(position), dtype=bool)
        if dh is None and joints is not None and method in ("dh", "composite"):
            self.dh = identify(robot, joints, measured, rotation=rotation, loss=loss,
                               orientation_weight=orientation_weight, R_tcp_target=R_tcp_target)
        modelled = None
        if self.dh is not None:
            modelled = fk(self.dh.robot, joints)[:, :3, 3]
            self.left_out[self.dh.outliers] = True
            if method == "composite" and kind == JOINT_KIND:
                self.residual, self.selection, self.shares = (
                    (residual, splines, ()) if residual is not None else _joint_residual(
                        robot, self.dh, joints, position, measured, rotation, loss, orientation_weight, workers))
                modelled = fk(self.residual.robot(self.dh.robot), self.residual.reached(robot, joints))[:, :3, 3]
                self.left_out = np.zeros(len(position), dtype=bool)
                self.left_out[outlier_rows(measured - modelled)] = True
        keep = ~self.left_out
        errors = measured - position
        self.linear = fit_linear(position[keep], errors[keep])
        if method in ("grid", "composite"):
            fill = errors if modelled is None else np.where(self.left_out[:, None], modelled - position, errors)
            self.grid = _field(position, fill, self.left_out, FIELD_ON_TOP if kind == JOINT_KIND else kind, grid_step)
        if self.dh is not None and method == "composite":
            residuals = np.where(self.left_out[:, None], 0.0, measured - modelled)
            if kind != JOINT_KIND:
                self.residual = _field(position, residuals, self.left_out, kind, grid_step)
            elif self.selection["field"]:
                self.residual_field = _field_on_top(position, joints, residuals, self.left_out, self.selection)
                if self.residual_field.kind == GP_KIND:  # a fold's refit keeps the full fit's lengths and nugget
                    field = self.residual_field
                    self.selection = self.selection | {"field_options": {"length": field.length, "nugget": field.nugget}
                                                       | ({"angle_length": field.angle_length}
                                                          if field.needs_joints else {})}

    def model(self, robot, robot_ref, method, T_tracker_base, report, places):
        dh = self.dh
        robot_names = [n for n in dh.names if is_robot_parameter(n)] if dh else []
        pick = [dh.names.index(n) for n in robot_names]
        return CompensationModel(
            nominal=robot,
            robot_ref=robot_ref,
            method=method,
            T_tracker_base=T_tracker_base,
            dh_names=robot_names,
            dh_delta=dh.delta[pick] if dh else np.zeros(0),
            dh_sigma=dh.sigma[pick] if dh else np.zeros(0),
            dh_fixed=dict(dh.identifiability.fixed) if dh else {},
            linear=self.linear,
            grid=self.grid,
            residual=self.residual,
            residual_field=self.residual_field,
            report=report,
            R_tcp_target=dh.R_tcp_target if dh else np.eye(3),
            places_other_tools=places[0],
            other_tools_reason=places[1],
        )


def _field(position, values, left_out, kind, grid_step):
    """A field over commanded positions; lattice kinds take the left-out rows' model values, the others drop them."""
    if kind in LATTICE_KINDS:
        return fit_field(position, values, step=grid_step, interpolation=kind, left_out=left_out)
    return fit_field(position[~left_out], values[~left_out], interpolation=kind)


def _field_on_top(position, joints, residuals, left_out, selection):
    """The joint residual's field on top (kind ``selection["field"]``) of residuals (N, 3) mm, rows ``left_out``
    dropped: a ``gp`` field over the position and the wrist at the lengths and nugget of ``field_options`` where
    the selection holds them (a fold's refit), else at those of the highest likelihood (`GaussianField.fit`)."""
    keep = ~left_out
    if selection["field"] != GP_KIND:
        return fit_field(position[keep], residuals[keep], interpolation=selection["field"])
    options = selection.get("field_options")
    if options is None:
        return GaussianField.fit(position[keep], residuals[keep], joints=joints[keep])
    angles = np.degrees(joints[keep][:, WRIST]) if "angle_length" in options else None
    return GaussianField(position[keep], residuals[keep], angles=angles, **options)


def _joint_residual(nominal, dh, joints, position, measured, rotation, loss, orientation_weight, workers=1):
    """Joint-error terms and a DH refinement on top of the kinematic fit (frames as that fit found them).

    The harmonic and gravity terms are identified with the DH refinement;
    spline terms of joints 1-5 and a residual field over the commanded
    positions and the wrist on top (`_fields_on_top`, or none) are chosen on
    held-out regions (`trajcomp.calibration.identify.select_splines`).
    Joint 6 gets no spline: it turns the TCP about its own axis, which a
    point on the axis hardly sees.

    Returns
    -------
    JointResidual
        On the knots of the chosen step: the fit at the penalty of the most
        weight, or the weighted mean of the fits at the penalties sharing the
        choice (`trajcomp.calibration.identify.Linearisation.shared`, one
        linearised step from the former).
    dict
        The choice: ``field`` (the kind of the field on top, or None), the spline ``step_deg``, ``penalty`` (of
        the most weight) and ``joints``, the held-out ``regions`` and every candidate's held-out
        mean error (``candidates``, the members with their ``share``).
    tuple
        ``(weight, penalty)`` of the penalties sharing the choice (`SplineChoice.shares`; empty without splines).
    """
    spline_joints = (0, 1, 2, 3, 4)
    refined = identify(dh.robot, joints, measured, rotation=rotation, joint_terms=True, loss=loss, nominal=nominal,
                       orientation_weight=orientation_weight, R_tcp_target=dh.R_tcp_target)
    fields = _fields_on_top(position, joints, refined.residuals)
    choice = select_splines(refined, dh.robot, nominal, joints, measured, rotation=rotation, position=position,
                            orientation_weight=orientation_weight, joints=spline_joints, fields=fields, loss=loss,
                            workers=workers)
    basis = choice.basis
    record = {"regions": choice.regions, "candidates": choice.table, "field": choice.field,
              "step_deg": 0.0 if basis is None else float(np.degrees(basis.step.max())),
              "penalty": 0.0 if basis is None else basis.penalty,
              "joints": [] if basis is None else [j + 1 for j in spline_joints]}
    fitted = choice.fit or refined
    pick = [k for k, n in enumerate(fitted.names) if is_robot_parameter(n) or is_term(n)]
    residual = JointResidual([fitted.names[k] for k in pick], fitted.delta[pick], joints.min(axis=0),
                             joints.max(axis=0), basis)
    if len(choice.shares) > 1:
        residual = dataclasses.replace(residual, values=linearise(
            dh.robot, joints, measured, dict(zip(residual.names, residual.values)), rotation=rotation, nominal=nominal,
            R_tcp_target=dh.R_tcp_target, basis=basis, loss=loss, orientation_weight=orientation_weight,
        ).shared(np.zeros(0, dtype=int), choice.shares))
    return residual, record, choice.shares


def shares_positions(position, joints):
    """True when two rows (N, 3) mm, (N, 6) rad command one position (within the lattice tolerance) in two postures.

    A field over the commanded positions cannot tell such rows apart: it
    would give the error of one orientation to another.
    """
    from scipy.spatial import cKDTree  # here: compensating never needs it

    pairs = cKDTree(position).query_pairs(TOLERANCE, output_type="ndarray")
    return bool(np.any(np.abs(joints[pairs[:, 0]] - joints[pairs[:, 1]]) > 1e-6))


def _fields_on_top(position, joints, residuals):
    """The fields a joint residual of commanded positions (N, 3) mm and joints (N, 6) rad may take on top, by kind
    (`select_splines`'s ``fields``: ``field(train, values, held)`` of row indices).

    Up to `GP_MAX_POINTS` rows ``gp``: the field over the position and the
    wrist angles, scored on each held-out region at the lengths and nugget
    of the highest likelihood (among `GP_TRIED` and
    `trajcomp.model.interpolate.ANGLE_LENGTHS`) for the training regions'
    ``residuals`` (N, 3) mm of the joint fit without splines, chosen once
    per region for every candidate, and fitted on every k-th of the
    training rows beyond `GP_SCORED_ROWS` (a factor's cost grows with the
    cube of its rows; the field the model takes holds all of them, its
    lengths and nugget chosen among all of `GaussianField.fit`'s for the
    chosen fit's residuals); ``knn``
    where no commanded position was measured in two orientations
    (`shares_positions`: a field of the position alone would give one
    orientation's error to the other).
    """
    chosen = {}  # per held-out region (its rows' bytes): the gp's length, nugget and wrist length

    def knn(train, values, held):
        return fit_field(position[train], values, interpolation=KNN_KIND).evaluate(position[held], outside="clamp")

    def gp(train, values, held):
        key = held.tobytes()
        if key not in chosen:
            likely = GaussianField.fit(position[train], residuals[train], joints=joints[train], **GP_TRIED)
            chosen[key] = {"length": likely.length, "nugget": likely.nugget, "angle_length": likely.angle_length}
        options = chosen[key]
        every = -(-len(train) // GP_SCORED_ROWS)
        rows = train[::every]
        angles = np.degrees(joints[rows][:, WRIST]) if np.isfinite(options["angle_length"]) else None
        field = GaussianField(position[rows], values[::every], angles=angles, **options)
        return field.evaluate(position[held], joints=joints[held])

    fields = {} if shares_positions(position, joints) else {KNN_KIND: knn}
    return fields | ({GP_KIND: gp} if len(position) <= GP_MAX_POINTS else {})


def selection_words(choice):
    """The joint residual's choice (a ``joint_splines`` record of `calibrate`'s report) in words.

    Names the chosen candidate with its held-out mean |error| (the
    penalties whose fits the model averages with their shares, and the
    heaviest one's held-out mean) and, for comparison, the best candidate
    without splines or, when that was chosen, with them, in mm.
    """
    shares = [f"{c['penalty']:g} {c['share']:.0%}" for c in choice["candidates"] if c.get("share")]
    shared = len(shares) > 1

    def words(candidate, field, shared=False):
        penalty = (f"penalties {', '.join(shares)}: the mean of their fits" if shared
                   else f"penalty {candidate['penalty']:g}")
        splines = f"splines every {candidate['step_deg']:g} deg ({penalty})" if candidate["step_deg"] else "no splines"
        return f"joint errors with {splines}" + (f" + {candidate.get('field_kind', KNN_KIND)} field" if field else "")

    scored = [(c[key], c, key == "with_field_mm") for c in choice["candidates"]
              for key in ("held_out_mm", "with_field_mm") if key in c]
    chosen = next(s for s in scored if s[1]["step_deg"] == choice["step_deg"] and s[1]["penalty"] == choice["penalty"]
                  and s[2] == bool(choice.get("field")))
    other = min((s for s in scored if (s[1]["step_deg"] > 0) != (chosen[1]["step_deg"] > 0)), key=lambda s: s[0],
                default=None)
    return (f"{words(chosen[1], chosen[2], shared)}, held-out mean {chosen[0]:.4f} mm"
            + (f" at {chosen[1]['penalty']:g}" if shared else "")
            + ("" if other is None else f" (best with{'out' if chosen[1]['step_deg'] else ''} splines: "
                                        f"{words(other[1], other[2])}, {other[0]:.4f})"))


def mode_errors(model, joints, position, measured, interpolation=None):
    """Measured minus predicted positions (N, 3) per available mode, as a dict."""
    return {
        mode: measured - model.predict(mode, joints, position, interpolation=interpolation, outside="clamp")[0]
        for mode in model.modes
    }


def other_tools(robot, method, kind, joints, spread, oriented, field_on_top=None):
    """``(places, reason)``: can a model fitted so place a tool other than the measured TCP?"""
    if joints is None or method in ("linear", "grid"):
        return False, f"mode {method} predicts from the commanded TCP position only: it knows nothing of the flange"
    turned = f"the measurements turn the tool by {spread[0]:.1f} and {spread[1]:.1f} deg RMS about its two main axes"
    if not locates_flange(spread):
        return False, (f"{turned}; at least {MIN_SPREAD:g} deg about two axes are needed to locate the flange, so a "
                       "tool other than the measured TCP may miss by tenths of a mm: measure at several orientations "
                       "(trajcomp plan, by default)")
    offset = axis_offset(robot)
    if not oriented and offset < MIN_AXIS_OFFSET:
        return False, (f"{turned}, but the measured point lies {offset:.1f} mm from the last joint's axis, so the "
                       "direction of that axis is not seen and a tool at another distance may miss by tenths of a mm: "
                       f"measure a point at least {MIN_AXIS_OFFSET:g} mm off the axis, or orientations too (6-DoF)")
    if method == "composite" and kind != JOINT_KIND:
        return False, (f"{turned}, but the composite residual is a {kind} field over the measured TCP's positions; "
                       "calibrate with --interpolation joint (or use mode dh) for other tools")
    on_top = ("" if field_on_top is None else f"; the {field_on_top.kind} field on top of the joint residual holds "
              "what that leaves at the measured TCP, and another tool is placed by the joint residual alone")
    return True, (f"{turned}{' with orientations measured' if oriented else f' at {offset:.0f} mm from the last axis'}"
                  ": the flange is located; another tool lands as the measured one does, as far as its offset from "
                  f"the flange is exact and the zero of the last joint is right (one measured frame cannot see it)"
                  f"{on_top}")


def too_many_rows():
    """What to do about more than `MAX_ROWS` measurements, for the message refusing them."""
    return (f"calibrate fits at most {MAX_ROWS} (that took 12 min and 1.3 GB; time and memory grow with the rows): "
            "thin the file (every k-th row) or keep some rows for validate")


def calibrate(robot, meas, *, robot_ref=None, method="composite", frame=None, grid_step=None,
              interpolation="auto", loss="huber", folds=5, seed=0, progress=None,
              orientation_weight=ORIENTATION_WEIGHT, workers=1):
    """Identify a compensation model from measurements.

    Parameters
    ----------
    robot : Robot
        Nominal robot, with the nominal TCP of the measured point.
    meas : Measurements
        Commanded joints and/or poses with measured TCP positions (and
        optionally orientations).
    robot_ref : str, optional
        How the robot is named in the model file (default: its name).
    method : {"linear", "dh", "grid", "composite"}
        The model's default mode; every part it needs is fitted.
    frame : {"base", "tracker"}, optional
        Frame of the measured columns (default: as the file's layout states,
        else base); ``tracker`` identifies the base registration with the arm.
    grid_step : float or array_like of 3 floats, optional
        Expected lattice step, mm (checked against the data).
    interpolation : str
        The composite's residual: ``auto`` (joint for data at several
        orientations or with orientations, else idw8), ``joint``, or a field
        over positions (idw8, trilinear, knn, rbf); the raw-error grid uses
        the field (idw8 when ``joint``).
    loss : str
        Robust loss of the identification (linear, soft_l1, huber, cauchy).
    folds : int
        k of the k-fold cross-validation (0 or 1: none).
    seed : int
        Seeds the fold split (>= 0).
    progress : callable, optional
        Called with a text line as the folds run.
    orientation_weight : float
        mm per rad of orientation residual (6-DoF data).
    workers : int
        Processes scoring the joint residual's candidate knot steps and
        computing the cross-validation's folds
        (`trajcomp.support.parallel.share_blocks`; forked, on POSIX); the
        model does not depend on it. Default 1: this process only.

    Returns
    -------
    CompensationModel
        Its ``report`` holds ``fit`` and ``cross_validation`` statistics per
        mode, ``warnings`` and the outlier lines.

    Raises
    ------
    CalibrationError
        Unknown method or interpolation, no measured columns, more than
        `MAX_ROWS` measurements, joints missing for a DH method, implausible
        data or identification, too few points for the parameters, or a
        degenerate grid.
    """
    if method not in CALIBRATION_METHODS:
        raise CalibrationError(f"unknown method {method!r} (one of {', '.join(CALIBRATION_METHODS)})")
    if loss not in LOSSES:
        raise CalibrationError(f"unknown loss {loss!r} (one of {', '.join(LOSSES)})")
    if not (isinstance(seed, (int, np.integer)) and seed >= 0):
        raise CalibrationError(f"seed must be a non-negative integer, got {seed!r}")
    if meas.measured is None:
        raise CalibrationError(f"{meas.path}: measured columns mx, my, mz are required")
    if len(meas) > MAX_ROWS:
        raise CalibrationError(f"{meas.path}: {len(meas)} measurements; {too_many_rows()}")
    frame = frame or meas.frame or "base"
    joints, position = commanded(robot, meas)
    if joints is None and method in ("dh", "composite"):
        raise CalibrationError(f"{meas.path}: method {method} needs commanded joints j1..j6 or a full pose x..c")
    check_columns(meas)
    rotation = None if meas.measured_orientation is None else abc_to_matrix(meas.measured_orientation)
    spread = orientation_spread(fk(robot, joints)[:, :3, :3] if joints is not None else abc_to_matrix(
        meas.orientation if meas.orientation is not None else np.zeros((1, 3))))
    kind = residual_kind(interpolation, joints, spread, rotation is not None)
    T_tracker_base = best_fit_transform(position, meas.measured) if frame == "tracker" else np.eye(4)
    nominal_error = np.linalg.norm(to_base(T_tracker_base, meas.measured) - position, axis=1)
    check_units(meas, position, meas.measured, nominal_error)
    dh = None
    if joints is not None:
        dh = identify(robot, joints, meas.measured, rotation=rotation, frame=frame, loss=loss,
                      orientation_weight=orientation_weight)
        check_identification(meas.path, dh, robot.T_flange_tool)
        T_tracker_base = dh.T_tracker_base
    measured = to_base(T_tracker_base, meas.measured)
    rotation_base = None if rotation is None else invert(T_tracker_base)[:3, :3] @ rotation
    warnings = []
    command = position if joints is None else np.column_stack([position, np.degrees(joints)])
    _, first, counts = np.unique(np.round(command, 3), axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        lines = meas.lines[np.sort(first[counts > 1])][:10].tolist()
        warnings.append(f"{int((counts - 1).sum())} rows repeat an earlier command (first at lines {lines}); "
                        "their measurements are averaged by the grid")
    options = dict(method=method, grid_step=grid_step, kind=kind, loss=loss, orientation_weight=orientation_weight)
    parts = _Parts(robot, joints, position, measured, rotation_base, dh=dh, workers=workers, **options)
    left_out = parts.left_out
    keep = ~left_out
    if left_out.any():
        lines = meas.lines[left_out].tolist()
        warnings.append(f"{len(lines)} gross outliers (residual far beyond the others; the robust loss bounds their "
                        f"pull on the fit) are left out of the grids and statistics, their nodes filled from the "
                        f"model: lines {lines[:20]}" + (" ..." if len(lines) > 20 else ""))
    fields = [field for field in (parts.grid, parts.residual, parts.residual_field)
              if field is not None and getattr(field, "kind", None) != JOINT_KIND]
    if grid_step is not None and not any(isinstance(field, ResidualGrid) for field in fields):
        warnings.append(f"--grid-step is not used: it checks the nodes of a lattice field, and this model's fields "
                        f"are {', '.join(sorted({field.kind for field in fields})) or 'none'} (scattered, no lattice; "
                        "the joint residual is chosen where several orientations were measured)")
    report = {
        "measurements": {"file": meas.path, "rows": len(meas), "used": int(keep.sum()), "frame": frame,
                         "orientation_spread_deg": [round(float(v), 3) for v in spread]}
        | ({} if meas.temperature is None else {"temperature_c": temperature_range(meas.temperature)}),
        "residual": kind,
        "residual_field": None if parts.residual_field is None else parts.residual_field.kind,
        "warnings": warnings,
        "outlier_lines": meas.lines[left_out].tolist(),
    }
    if dh is not None:
        report["identifiability"] = {"condition": dh.identifiability.condition,
                                     "fixed": dict(dh.identifiability.fixed)}
    if parts.selection is not None:
        report["joint_splines"] = parts.selection
    places = other_tools(robot, method, kind, joints, spread, rotation is not None, parts.residual_field)
    model = parts.model(robot, robot_ref or robot.name, method, T_tracker_base, report, places)
    if joints is not None:
        model = dataclasses.replace(model, postures=tuple(np.unique(branch_index(robot, joints)).tolist()))
    report["fit"] = {m: ErrorStats.from_errors(e).as_dict() for m, e in
                     mode_errors(model, _rows(joints, keep), position[keep], measured[keep]).items()}
    if folds > 1:
        data = (robot, _rows(joints, keep), position[keep], measured[keep], _rows(rotation_base, keep),
                options | {"R_tcp_target": None if dh is None else dh.R_tcp_target, "splines": parts.selection})
        fitted = ((dh, model.residual if kind == JOINT_KIND else None, parts.shares) if method in ("dh", "composite")
                  else None)
        held = fold_errors(*data, folds, seed, progress, fitted, workers)
        report["cross_validation"] = {"folds": folds, "interpolation": held.pop("interpolation")} | {
            m: ErrorStats.from_errors(e).as_dict() for m, e in held.items()}
        report["landing"], reliability = _landing(robot, dh, frame, data, held, fitted, (folds, seed), progress,
                                                  meas.orientation, workers)
        if reliability is not None:
            report["reliability"] = reliability
    for message in warnings:
        log.warning(message)
    return model


def fold_errors(robot, joints, position, measured, rotation, options, folds, seed, progress=None, fitted=None,
                workers=1, splits=None):
    """Held-out errors (N, 3) per mode of k-fold cross-validation, in row order, and the interpolator used.

    The folds fit in the base frame (the tracker registration of the full
    fit). Held-out nodes leave holes in a lattice, so the folds evaluate the
    lattice interpolators (idw8, trilinear) by their scattered counterpart,
    inverse-distance weighting over the 8 nearest training nodes; the
    ``interpolation`` entry names the interpolator the folds used
    (`plane_errors` holds out with the lattice interpolator itself) and the
    field a joint residual takes on top. ``fitted`` ``(dh, residual,
    shares)``, the full fit's `KinematicFit`, joint residual (or None) and
    the penalties sharing it (`_joint_residual`), are refitted
    without each fold's rows by `_Refit`; without it the folds identify
    from the nominal robot. The folds are computed by up to ``workers``
    processes (`trajcomp.support.parallel.share_blocks`); the errors do not
    depend on it. ``splits`` (a list of ``(train, test)`` row indices)
    replace the shuffled k-fold ones (``folds`` and ``seed`` then unused
    but for the message), e.g. held-out regions.
    """
    if len(position) < 2 * folds:
        raise CalibrationError(f"{len(position)} measurements are too few for {folds}-fold cross-validation")
    if options["kind"] in LATTICE_KINDS:
        options = options | {"kind": "knn", "grid_step": None}
    refit = None if fitted is None else _Refit(robot, joints, measured, rotation, options, *fitted)
    splits = kfold_indices(len(position), folds, seed) if splits is None else splits
    folds = len(splits)

    def fold(k):
        train, test = splits[k]
        dh, residual = (None, None) if refit is None else refit(train, test)
        parts = _Parts(robot, _rows(joints, train), position[train], measured[train], _rows(rotation, train), dh=dh,
                       residual=residual, **options)
        model = parts.model(robot, robot.name, options["method"], np.eye(4), {}, (False, ""))
        return mode_errors(model, _rows(joints, test), position[test], measured[test])

    collected = {}
    for k, errors in enumerate(share_blocks(fold, folds, workers)):
        if progress:
            progress(f"cross-validation fold {k + 1}/{folds}")
        for mode, err in errors.items():
            collected.setdefault(mode, np.full((len(position), 3), np.nan))[splits[k][1]] = err
    field = (options.get("splines") or {}).get("field") if options["kind"] == JOINT_KIND else None
    return {"interpolation": options["kind"] + (f" with a {field} field on top" if field else ""), **collected}


class _Refit:
    """The full fit's kinematic model and joint residual refitted without a fold's rows (`fold_errors`).

    Both least-squares problems are linearised once at the full fit, over
    the rows the statistics use with their robust weights there
    (`trajcomp.calibration.identify.linearise`); a fold's refit is one
    Gauss-Newton step from the full fit with the held-out rows' normal
    equations taken off (`Linearisation.without`), instead of an iterated
    identification from the nominal robot per fold: the fits of a fifth
    fewer rows differ from the full fit by micrometres, where the step's
    error is of second order. The joint residual keeps the full fit's
    knots and penalty (its selection; the weighted mean of the refits at
    the penalties sharing it, `Linearisation.shared`), and the range of the
    fold's joints.

    Parameters
    ----------
    robot : Robot
        The nominal robot.
    joints : ndarray, shape (N, 6)
        Commanded joints of the rows, rad.
    measured : ndarray, shape (N, 3)
        Their measured positions, mm, base frame.
    rotation : ndarray, shape (N, 3, 3) or None
        Their measured orientations, base frame.
    options : dict
        `_Parts` options (``loss``, ``orientation_weight``).
    dh : KinematicFit
        The full fit's kinematic model (from ``robot``).
    residual : JointResidual or None
        The full fit's joint residual (on ``dh.robot``).
    shares : tuple
        ``(weight, penalty)`` of the penalties sharing it (`_joint_residual`;
        fewer than two: its own penalty alone).
    """

    def __init__(self, robot, joints, measured, rotation, options, dh, residual, shares=()):
        common = dict(rotation=rotation, R_tcp_target=dh.R_tcp_target, loss=options["loss"],
                      orientation_weight=options["orientation_weight"])
        self.arm = {n: v for n, v in zip(dh.names, dh.delta) if is_robot_parameter(n)}
        self.kinematic = linearise(robot, joints, measured, self.arm, identifiability=dh.identifiability, **common)
        self.joint = None if residual is None else linearise(
            dh.robot, joints, measured, dict(zip(residual.names, residual.values)), nominal=robot, basis=residual.basis,
            **common)
        self.joints, self.basis, self.shares = joints, None if residual is None else residual.basis, shares

    def __call__(self, train, test):
        """The fold's `KinematicFit` and joint residual (or None), without the rows ``test``."""
        dh = self.kinematic.fit_without(test)
        if self.joint is None:
            return dh, None
        names = self.joint.problem.names
        # the DH refinement adds to the DH table (apply_deltas): on the fold's kinematic fit instead of the full
        # fit's, it takes the difference of the two with it
        fold = dict(zip(dh.names, dh.delta))
        refitted = self.joint.shared(test, self.shares) if len(self.shares) > 1 else self.joint.without(test)
        values = refitted + [self.arm[n] - fold[n] if n in fold else 0.0 for n in names]
        train_joints = self.joints[train]
        return dh, JointResidual(names, values, train_joints.min(axis=0), train_joints.max(axis=0), self.basis)


def plane_errors(robot, joints, position, measured, rotation, options, progress=None):
    """Held-out errors (N, 3) per mode of a lattice model, with its own lattice interpolator.

    For each axis and each parity, every other node plane along the axis is
    left out; the model refitted on the others (a lattice twice as coarse
    along that axis) is evaluated at the planes left out inside its box.
    Each row keeps its largest held-out error over the axes, and its
    distances from the rows of the fit that predicted it; rows never held
    out (the corners of the lattice) are NaN.

    Returns
    -------
    held : dict of str to ndarray, shape (N, 3)
    distance : dict of str to ndarray, shape (N,)
        `split_distances` of the rows.
    """
    _, index = detect_lattice(position)
    held, distance = {}, {}
    options = options | {"grid_step": None}
    for axis in range(3):
        for parity in (0, 1):
            train = index[:, axis] % 2 == parity
            planes = np.unique(index[train, axis])
            test = ~train & (index[:, axis] > planes.min()) & (index[:, axis] < planes.max())
            if len(planes) < 2 or not test.any():
                continue
            if progress:
                progress(f"held-out node planes along {'xyz'[axis]} ({'even' if parity else 'odd'})")
            try:
                parts = _Parts(robot, _rows(joints, train), position[train], measured[train], _rows(rotation, train),
                               **options)
            except CalibrationError:  # too few planes left to fit: this axis gives no held-out errors
                continue
            model = parts.model(robot, robot.name, options["method"], np.eye(4), {}, (False, ""))
            away = split_distances(robot, joints, position, [(np.flatnonzero(train), np.flatnonzero(test))])
            for mode, err in mode_errors(model, _rows(joints, test), position[test], measured[test]).items():
                errors = held.setdefault(mode, np.full((len(position), 3), np.nan))
                larger = ~(np.linalg.norm(errors[test], axis=1) >= np.linalg.norm(err, axis=1))  # NaN: not yet held out
                errors[np.flatnonzero(test)[larger]] = err[larger]
                if mode == options["method"]:
                    for key, values in away.items():
                        distance.setdefault(key, np.full(len(position), np.nan))[np.flatnonzero(test)[larger]] = (
                            values[test][larger])
    return held, distance


def split_distances(robot, joints, position, splits):
    """How far each held-out row lies from the training rows of its split, mm (N,), NaN for rows never held out.

    Returns
    -------
    dict of str to ndarray, shape (N,)
        ``positions``: from the nearest training position; ``joints``: from
        what the training rows measured, joint by joint
        (`trajcomp.model.landing.coverage_distance`; absent without joints);
        ``beyond`` and ``beyond_mm``: outside the box of the training positions, in units of its extent and
        in mm (`trajcomp.model.landing.outside_box`).
    """
    keys = ("positions", "beyond", "beyond_mm", *(("joints",) if joints is not None else ()))
    out = {key: np.full(len(position), np.nan) for key in keys}
    for train, test in splits:
        out["positions"][test] = cKDTree(position[train]).query(position[test])[0]
        out["beyond"][test], out["beyond_mm"][test] = landing.outside_box(position[test], position[train])
        if joints is not None:
            out["joints"][test] = landing.coverage_distance(robot, joints[train], joints[test])
    return out


def outer_layers(position):
    """Splits ``(train, test)`` that hold out the outer layers of the measured positions on each side of each axis.

    A layer is a node plane of a lattice, or `OUTER_SHARE` of the rows of
    scattered positions; one and two layers are held out on each side (the
    errors at one and two layers beyond the rest), where at least three
    would be left (an axis with fewer holds out fewer or none).
    """
    splits = []
    every = np.arange(len(position))
    for axis in range(3):
        planes = np.unique(np.round(position[:, axis], 3))
        for side in (-1.0, 1.0):
            along = side * position[:, axis]
            for layers in range(1, OUTER_LAYERS + 1):
                if len(planes) <= LAYER_PLANES:
                    if len(planes) - layers < 3:
                        break
                    test = every[along <= np.sort(side * planes)[layers - 1] + 1e-3]
                else:
                    test = every[along <= np.quantile(along, OUTER_SHARE * layers)]
                splits.append((np.setdiff1d(every, test), test))
    return splits


def _landing(robot, dh, frame, data, held, fitted, split, progress, orientation, workers):
    """The plain-data `trajcomp.model.landing.LandingData` of a calibration (its report's ``landing``) and the
    `reliability` of its stated quantile in the model's mode (its report's ``reliability``), or ``(None, None)``
    when no held-out errors could be computed.

    ``data`` are the rows the statistics use ``(robot, joints, position,
    measured, rotation, options)``, ``held`` their k-fold errors (N, 3) per
    mode, ``fitted`` the full fit's kinematic model and joint residual for
    `fold_errors`, ``split`` the k-fold's ``(folds, seed)``. The held-out
    errors and their distances from the rows that predicted them come from
    the k-fold and slabs of the measured positions (a lattice field: node
    planes held out with its own interpolator, `plane_errors`) and from the
    outer layers of the measured positions held out in turn (`outer_layers`:
    how the errors grow beyond the measured volume).
    """
    _, joints, position, measured, rotation, options = data
    layers = outer_layers(position)
    if options["kind"] in LATTICE_KINDS:
        held, distances = plane_errors(*data, progress)
        method = (f"{options['kind']} on the lattice with every other node plane along each axis held out "
                  "(cells twice as long along that axis)")
        splits, first, slabs = layers, "node planes", []
        words = "one and two outer layers of the measured positions on each side"
    else:
        distances = split_distances(robot, joints, position, kfold_indices(len(position), *split))
        method = f"{split[0]}-fold cross-validation, residual {options['kind']}"
        first = f"{split[0]}-fold"
        slabs, words = region_folds(position, split[0])
        every = np.arange(len(position))
        splits = [(np.setdiff1d(every, test), test) for test in slabs] + layers
        words += ", and one and two outer layers of the measured positions on each side"
    if not held:  # no plane could be held out (outliers left too few): no landing data, as with --folds 0
        return None, None
    sets = [(distances, held)]
    shown = {first: (distances, held)}  # the reliability's classes of holdout
    if splits:
        # slabs and layers in turn, a row held out by several keeping the last one's error and distances, as
        # `fold_errors` and `split_distances` do over all their splits; the reliability shows the slabs whole
        regions = None
        for kind, part in (("slabs", splits[:len(slabs)]), ("outer layers", splits[len(slabs):])):
            if part:
                errors = fold_errors(*data, len(part), 0, progress, fitted, workers, splits=part)
                errors.pop("interpolation")
                shown[kind] = (split_distances(robot, joints, position, part), errors)
                regions = shown[kind] if regions is None else tuple(
                    {key: np.where(np.isnan(above[key]), below[key], above[key]) for key in below}
                    for below, above in zip(regions, shown[kind]))
        sets.append(regions)
        method += f"; {words} held out in turn"
    # a field over positions errs by how far a target lies from the measured positions; every other mode by how far
    # its joints lie from the measured ones
    fields = {"grid"} | ({"composite"} if options["kind"] != JOINT_KIND else set())
    by_joints = set() if joints is None else set(held) - fields
    combined = {mode: _held_rows(sets, mode, "joints" if mode in by_joints else "positions")[:3] for mode in held}
    rotations = fk(robot, joints)[:, :3, :3] if joints is not None else (
        abc_to_matrix(orientation) if orientation is not None else None)
    parameters = ([], np.zeros(0), np.zeros((0, 0)), np.zeros(0), 0.0, 0.0)
    if dh is not None:
        parameters = landing.posterior(
            robot, dh.robot, joints, rotation, frame=frame, residuals=measured - fk(dh.robot, joints)[:, :3, 3],
            fitted=dict(zip(dh.names, dh.delta)),
            hidden=sum(is_robot_parameter(n) for n in dh.identifiability.fixed),
            located=locates_flange(orientation_spread(rotations)))
    extrapolates = {"composite"} if options["kind"] == JOINT_KIND else set()  # its terms go on beyond the ranges
    built = landing.build(combined, method, parameters, rotations, position, joints, by_joints, extrapolates)
    mode = options["method"]
    if mode not in combined:
        return built.to_dict(), None
    rows = {kind: _held_rows([where], mode, "joints" if mode in by_joints else "positions")
            for kind, where in shown.items()}
    d, g, e, g_mm = (np.concatenate(part) for part in zip(*rows.values()))
    near = built.rms_at(mode, d, g, g_mm)
    stated = landing.quantile_of_norm(np.zeros((len(near), 3)), near[:, None, None] ** 2 / 3.0 * np.eye(3))
    classes = np.repeat(list(rows), [len(r[0]) for r in rows.values()])
    return built.to_dict(), reliability(stated, np.linalg.norm(e, axis=1), classes, mode)


def _held_rows(sets, mode, metric):
    """``(distance, beyond, error, beyond_mm)`` (M,), (M,), (M, 3), (M,) of the rows held out in ``sets``
    ``[(distances, errors)]`` (`split_distances`, per-mode (N, 3) errors): distance by ``metric``, NaN rows (never
    held out) left out."""
    d, g, e, g_mm = (np.concatenate(part) for part in zip(*[
        (where[metric], where["beyond"], errors[mode], where["beyond_mm"]) for where, errors in sets]))
    finite = np.isfinite(d) & np.isfinite(e).all(axis=1)
    return d[finite], g[finite], e[finite], g_mm[finite]


def reliability(stated, true, classes, mode, bins=RELIABILITY_BINS):
    """How the stated quantile of held-out errors compares with their true size, per class of holdout.

    Per class, the rows are split by their stated quantile into at most
    ``bins`` groups of equal count; each bin gives its mean stated quantile,
    the `landing.QUANTILE` quantile of its true errors (on the diagonal of a
    reliability plot when the forecast is calibrated, below it when
    conservative) and the share of its rows whose true error is within the
    stated quantile.

    Parameters
    ----------
    stated : ndarray, shape (M,)
        The quantile the landing estimate states at each held-out row (its
        held-out part, at the row's distance from the fit that predicted it), mm.
    true : ndarray, shape (M,)
        The row's held-out |error|, mm.
    classes : ndarray of str, shape (M,)
        How each row was held out (k-fold, node planes, slabs, outer layers).
    mode : str
        The mode of the errors.

    Returns
    -------
    dict
        ``{"mode", "quantile", "classes": {class: {"rows", "covered", "bins": [{"rows", "stated_mm",
        "true_quantile_mm", "covered"}]}}}``.
    """
    out = {}
    for kind in dict.fromkeys(classes.tolist()):
        rows = np.flatnonzero(classes == kind)
        groups = np.array_split(rows[np.argsort(stated[rows], kind="stable")], min(bins, len(rows)))
        out[kind] = {"rows": len(rows), "covered": round(float(np.mean(true[rows] <= stated[rows])), 4), "bins": [
            {"rows": len(group), "stated_mm": round(float(stated[group].mean()), 6),
             "true_quantile_mm": round(float(np.quantile(true[group], landing.QUANTILE)), 6),
             "covered": round(float(np.mean(true[group] <= stated[group])), 4)} for group in groups]}
    return {"mode": mode, "quantile": landing.QUANTILE, "classes": out}
