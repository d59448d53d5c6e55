"""Light re-calibration: carry a model into a later measuring campaign from a few rows measured there.

Between campaigns a cell changes in a few known ways: the tracker is placed
anew, the probe is remounted, the hall is warmer or colder, a joint's zero
is re-referenced. Those are few parameters, which some thirty measurements
identify; what the full calibration identified from thousands (the DH
table's other deltas, the joint-angle error curves, the residual field on
top) stays as it was. `update` re-identifies, in one robust Gauss-Newton
fit of the model's composite prediction to the new rows:

``registration``  the base pose in the tracker frame, ``base_x`` ...
                  ``base_rz`` (tracker-frame data only);
``tool``          the TCP position in the flange frame, ``tool_x..z``, and
                  for 6-DoF data the measured frame's orientation
                  ``target_rx..rz`` (a remounted probe);
``zeros``         the joint zero offsets ``theta1`` ... ``theta6`` but those
                  another updated frame absorbs exactly: ``theta1`` turns the
                  arm about base z as the registration does, ``theta6`` turns
                  the TCP about the flange axis as a remounted tool does;
``scale``         a thermal scale of the arm's link lengths: every ``a`` and
                  ``d`` of links 1-5 times ``1 + scale`` (link 6 ends in the
                  tool, whose length the ``tool`` group takes), in ppm.

What these parameters leave at the rows is, on a real arm, not noise alone:
the joint-error curves and the arm's compliance change between campaigns in
ways no few parameters hold, and neighbouring rows share that change. On
top of the fit the model takes, a correction over the commanded positions
is tried (`correction`): the kriging mean of the rows' residuals
(`trajcomp.model.interpolate.Kriging`), which follows them near the rows
and returns to zero away from them. It is the updated model's field on top
of its composite (not offered for a model whose composite already has a
field over positions; an earlier update's correction is replaced, it
belonged to the campaign its rows came from).

An update the rows cannot support is refused (`UpdateRefused`): fewer
residuals than twice the parameters, or a parameter the rows' Jacobian does
not identify on its own (`trajcomp.calibration.identify.analyse_identifiability`).

The result (`Update`) says what changed, by how much and with what standard
deviation, and the rows' residual as the model is, registered anew,
updated and corrected, on the rows themselves and with each region of them predicted from
the others (`held_out_errors`); the updated model takes the smallest of
these fits that the rows do not show to be worse (`Update.kept`), and its
``report["update"]`` records the update (`Update.record`): the parameters'
names, values and covariance, and the position uncertainty the update adds
to a target (`added_sigma`). `Update.verdict` says from the same rows
whether the model is still valid, needs this update, or needs a full
calibration.
"""

import dataclasses

import numpy as np

from trajcomp.arm.kinematics import fk
from trajcomp.arm.parameters import BASE_NAMES, TARGET_NAMES, TOOL_NAMES, is_angle, is_robot_parameter
from trajcomp.arm.transforms import invert, matrix_to_rotvec, mean_rotation, rotvec_to_matrix
from trajcomp.calibration.identify import analyse_identifiability, best_fit_transform, region_folds, robust_weights
from trajcomp.calibration.options import ORIENTATION_WEIGHT
from trajcomp.errors import CalibrationError
from trajcomp.model.compensation_model import evaluate_field
from trajcomp.model.interpolate import Kriging
from trajcomp.model.options import KRIGING_KIND
from trajcomp.model.update import PPM, SCALE, SCALED_LINKS, parameter_jacobian, position_covariance, to_display

GROUPS = ("registration", "tool", "zeros", "scale")
ITERATIONS = 30
STEP_TOLERANCE = 1e-9  # scaled units (mm, or rad at 1 m): converged when no parameter moves more
LEVER = 1000.0  # mm: an angle (or the scale) is scaled as its effect at this lever arm, as in `identify`
RTOL = 1e-3  # identifiability threshold of `analyse_identifiability`, as `identify`'s
STILL_VALID = 1.5  # the rows' held-out residual may exceed the model's own mean error by this factor
REGIONS = 5  # slabs of the update's rows, each predicted from the others (`held_out_errors`): 24 rows of 30 fit each
EVIDENCE = 2.0  # standard errors by which a larger fit must lower the rows' held-out residual to be taken
MIN_TEMPERATURE_CHANGE = 0.2  # K: a smaller change of the hall's temperature gives no scale per kelvin
LIGHT_ENOUGH = 1.5  # after the update, the residual may exceed it by this factor for a light update to do


class UpdateRefused(CalibrationError):
    """The rows cannot support the update asked for (too few, or a parameter they do not see)."""


def parameter_names(groups, *, tracker, oriented):
    """The parameters of the update groups ``groups`` (subset of `GROUPS`), in their order.

    ``tracker``: the rows are in the tracker frame (registration possible);
    ``oriented``: they measure orientations (the target's orientation is
    updated with the tool).
    """
    unknown = sorted(set(groups) - set(GROUPS))
    if unknown:
        raise CalibrationError(f"unknown update group(s) {', '.join(unknown)} (of {', '.join(GROUPS)})")
    names = []
    if "registration" in groups and tracker:
        names += BASE_NAMES
    if "tool" in groups:
        names += TOOL_NAMES + (TARGET_NAMES if oriented else ())
    if "zeros" in groups:
        first = 2 if "registration" in groups and tracker else 1
        last = 5 if "tool" in groups else 6
        names += [f"theta{j}" for j in range(first, last + 1)]
    if "scale" in groups:
        names.append(SCALE)
    return names


def _units(names):
    """Display unit of each parameter: deg, ppm or mm."""
    return ["deg" if is_angle(n) else "ppm" if n == SCALE else "mm" for n in names]


def _solver_scale(names):
    """Factor (P,) from solver units (mm of effect at `LEVER`) to internal units."""
    return np.array([1.0 / LEVER if is_angle(n) or n == SCALE else 1.0 for n in names])


def updated_model(model, names, x, T_tracker_base, R_tcp_target):
    """``model`` with the update parameters ``names`` at x (P,) (internal units) applied.

    The tool and zero offsets add to the model's DH deltas; the scale
    multiplies the identified lengths; the registration and the target
    orientation replace the model's (``T_tracker_base``, ``R_tcp_target``:
    the update's starting frames, which x moves).
    """
    values = dict(zip(names, x))
    dh_names, delta, sigma = list(model.dh_names), model.dh_delta.astype(float).copy(), model.dh_sigma.copy()
    robot_names = [n for n in names if n != SCALE and is_robot_parameter(n)]
    for n in robot_names:
        if n not in dh_names:
            dh_names.append(n)
            delta, sigma = np.append(delta, 0.0), np.append(sigma, 0.0)
        delta[dh_names.index(n)] += values[n]
    scale = values.get(SCALE, 0.0)
    if scale:
        nominal = model.nominal.as_standard()
        identified = model.identified.as_standard()
        for kind in ("a", "d"):
            for j in range(SCALED_LINKS):
                length = getattr(identified, kind)[j]
                if f"{kind}{j + 1}" not in dh_names and length != 0.0:
                    dh_names.append(f"{kind}{j + 1}")
                    delta, sigma = np.append(delta, getattr(identified, kind)[j] - getattr(nominal, kind)[j]), \
                        np.append(sigma, 0.0)
                if length != 0.0:
                    delta[dh_names.index(f"{kind}{j + 1}")] += scale * length
    step = np.eye(4)
    if any(n in values for n in BASE_NAMES):
        step[:3, :3] = rotvec_to_matrix([values.get(n, 0.0) for n in BASE_NAMES[3:]])
        step[:3, 3] = [values.get(n, 0.0) for n in BASE_NAMES[:3]]
    R_target = R_tcp_target
    if any(n in values for n in TARGET_NAMES):
        R_target = R_tcp_target @ rotvec_to_matrix([values.get(n, 0.0) for n in TARGET_NAMES])
    return dataclasses.replace(model, dh_names=dh_names, dh_delta=delta, dh_sigma=sigma,
                               T_tracker_base=T_tracker_base @ step, R_tcp_target=R_target)


class _Rows:
    """The update's least-squares problem: a model's composite prediction against the new rows."""

    def __init__(self, model, joints, position, measured, rotation, weight):
        self.joints, self.measured, self.rotation, self.weight = joints, measured, rotation, weight
        self.field = _field(model, position, joints)

    def residual(self, candidate, names, jacobian=True):
        """Residual rows (N, 3 or 6), mm (orientation: rad times the weight), and their Jacobian (N, rows, P)
        in internal units, of the updated model ``candidate``."""
        arm = candidate.arm("composite", outside="clamp")
        q = arm.reached_joints(self.joints)
        T_tcp, jac = parameter_jacobian(arm.robot, q, names, candidate.R_tcp_target)
        T_base_tracker = invert(candidate.T_tracker_base)
        measured = self.measured @ T_base_tracker[:3, :3].T + T_base_tracker[:3, 3]
        rows = [T_tcp[:, :3, 3] + self.field - measured]
        if self.rotation is not None:
            seen = T_base_tracker[:3, :3] @ self.rotation
            rows.append(self.weight * matrix_to_rotvec(T_tcp[:, :3, :3] @ candidate.R_tcp_target
                                                       @ np.swapaxes(seen, 1, 2)))
        residual = np.concatenate(rows, axis=1)
        if not jacobian:
            return residual, None
        jac = jac[:, :residual.shape[1]]
        jac[:, 3:] *= self.weight
        return residual, jac


@dataclasses.dataclass(frozen=True, eq=False)
class Fit:
    """One least-squares fit of update parameters to the rows.

    Attributes
    ----------
    names : list of str
    delta : ndarray, shape (P,)
        Values, internal units (mm, rad, fraction), from the model's (the registration: from a best fit).
    covariance : ndarray, shape (P, P)
        Their covariance, internal units.
    model : CompensationModel
        The model with them applied.
    residual : ndarray, shape (N, 3)
        Measured minus predicted position, mm, base frame.
    held_out : ndarray, shape (N,), or None
        |residual| of each row, mm, predicted by the fit of the rows of the
        other regions (`held_out_errors`); None until computed, or when the
        other regions' rows do not identify the parameters.
    condition : float
        Condition number of the scaled Jacobian.
    """

    names: list
    delta: np.ndarray
    covariance: np.ndarray
    model: object
    residual: np.ndarray
    condition: float
    held_out: np.ndarray = None

    @property
    def sigma(self):
        """Standard deviations (P,), internal units."""
        return np.sqrt(np.diag(self.covariance))


def fit(model, joints, position, measured, rotation=None, names=BASE_NAMES, *, tracker=True, loss="huber",
        orientation_weight=ORIENTATION_WEIGHT):
    """Fit the update parameters ``names`` of ``model`` to rows measured in a new campaign.

    Parameters
    ----------
    model : CompensationModel
        With a composite mode.
    joints : ndarray, shape (N, 6)
        Commanded joints, rad.
    position : ndarray, shape (N, 3)
        Commanded TCP positions, mm, base frame.
    measured : ndarray, shape (N, 3)
        Measured positions, mm, tracker frame (``tracker``) or base frame.
    rotation : ndarray, shape (N, 3, 3), optional
        Measured orientations, same frame.
    names : sequence of str
        `parameter_names` (none: the model as it is, with its own registration).
    tracker : bool
        The rows are in a new tracker placement: the registration starts
        from a rigid best fit of the model's prediction, else from the
        model's (identity for base-frame models).
    loss : str
        Robust loss (`trajcomp.calibration.identify.robust_weights`).
    orientation_weight : float
        mm per rad of orientation residual.

    Raises
    ------
    UpdateRefused
        Too few residuals for the parameters, or parameters the rows do not identify.
    """
    names = list(names)
    model.check_mode("composite")
    if not names:  # the model as it is, its own registration
        residual = _Rows(model, joints, position, measured, rotation, orientation_weight).residual(
            model, names, jacobian=False)[0]
        return Fit([], np.zeros(0), np.zeros((0, 0)), model, -residual[:, :3], 1.0)
    T_start = model.T_tracker_base
    if tracker:
        predicted = model.predict("composite", joints, position, outside="clamp")[0]
        T_start = best_fit_transform(predicted, measured)
    R_start = model.R_tcp_target
    if rotation is not None and any(n in TARGET_NAMES for n in names):
        reached = model.arm("composite", outside="clamp").fk(joints)[:, :3, :3]
        R_start = mean_rotation(np.swapaxes(reached, 1, 2) @ (invert(T_start)[:3, :3] @ rotation))
    rows = _Rows(model, joints, position, measured, rotation, orientation_weight)
    per_row = 3 if rotation is None else 6
    if per_row * len(joints) < 2 * len(names):
        raise UpdateRefused(f"{len(joints)} rows give {per_row * len(joints)} residuals: too few to update "
                            f"{len(names)} parameters ({', '.join(names)}); at least "
                            f"{int(np.ceil(2 * len(names) / per_row))} rows are needed")
    solver = _solver_scale(names)
    x = np.zeros(len(names))
    current = updated_model(model, names, x, T_start, R_start)
    residual, jac = rows.residual(current, names)
    ident = analyse_identifiability(jac.reshape(-1, len(names)) * solver, names, RTOL)
    if ident.fixed:
        raise UpdateRefused(f"these {len(joints)} rows cannot identify the update's {', '.join(names)} (condition "
                            f"{ident.condition:.3g}): they do not tell apart "
                            + "; ".join(_unseen(jac.reshape(-1, len(names)) * solver, names))
                            + ". Measure rows that turn the tool and move the joints more (trajcomp plan --update), "
                            "or leave a group out (--only)")
    for _ in range(ITERATIONS):
        weights = robust_weights(np.linalg.norm(residual, axis=1), loss)
        a = jac.reshape(-1, len(names)) * solver
        w = np.repeat(weights, residual.shape[1])
        step = -np.linalg.solve(a.T @ (w[:, None] * a), a.T @ (w * residual.ravel()))
        x = x + step * solver
        current = updated_model(model, names, x, T_start, R_start)
        residual, jac = rows.residual(current, names)
        if np.max(np.abs(step)) < STEP_TOLERANCE:
            break
    weights = robust_weights(np.linalg.norm(residual, axis=1), loss)
    a = jac.reshape(-1, len(names)) * solver
    w = np.repeat(weights, residual.shape[1])
    inverse = np.linalg.inv(a.T @ (w[:, None] * a))
    variance = float(np.sum(w * residual.ravel() ** 2) / max(residual.size - len(names), 1))
    covariance = variance * inverse * np.outer(solver, solver)
    return Fit(names, x, covariance, current, -residual[:, :3], ident.condition)


def _unseen(jac, names):
    """The combinations of parameters a scaled Jacobian (M, P) does not see (`RTOL`), each in words."""
    _, values, vectors = np.linalg.svd(jac, full_matrices=False)
    combinations = []
    for vector in vectors[values < RTOL * values[0]]:
        big = np.flatnonzero(np.abs(vector) > 0.2 * np.abs(vector).max())
        combinations.append(" with ".join(names[k] for k in big[np.argsort(-np.abs(vector[big]))]))
    return combinations


def added_sigma(update_fit, joints):
    """Position standard deviation (N,) mm per axis the update's arm parameters add at commanded joints (N, 6) rad.

    Only the parameters of the arm (tool, zeros, scale) move a program's
    targets; the registration and the target orientation are frames of the
    measurement. Computed with their covariance (`Fit.covariance`) and the
    derivative of the TCP position at those joints: ``sqrt(trace(J C J^T) / 3)``.
    """
    arm = [k for k, n in enumerate(update_fit.names) if not n.startswith(("base_", "target_"))]
    return _position_sigma(update_fit.model, joints, [update_fit.names[k] for k in arm],
                           update_fit.covariance[np.ix_(arm, arm)])


def update_sigma(model, joints):
    """Position standard deviation (N,) mm per axis a model's last update adds at commanded joints (N, 6) rad.

    From the model file alone: its ``report["update"]`` (`Update.record`,
    `trajcomp.model.update.position_covariance`). Zero for a model the rows
    did not update (``applied`` other than ``update``) or one never updated.
    The landing estimate adds its covariance to every target's.
    """
    return np.sqrt(np.trace(position_covariance(model, joints), axis1=1, axis2=2) / 3.0)


def _position_sigma(model, joints, names, covariance):
    """``sqrt(trace(J C J^T) / 3)`` (N,) mm: parameters ``names`` of covariance C (P, P), internal units, at joints."""
    return np.sqrt(np.trace(position_covariance(model, joints, names, covariance), axis1=1, axis2=2) / 3.0)


def held_out_errors(model, joints, position, measured, rotation, names, regions=REGIONS, corrected=False,
                    **options):
    """|residual| (N,) mm of each row predicted by the fit of ``names`` to the rows of the other regions.

    The rows are cut into ``regions`` slabs of their commanded positions
    (`trajcomp.calibration.identify.region_folds`), as the accuracy of a
    model is judged: an update that follows the model's own errors at the
    rows, not drift, fails to predict another region. ``corrected``: the
    correction (`correction`) of the other regions' residuals is added to
    that fit. None when the rows of the other regions do not identify the
    parameters.
    """
    if not names and not corrected:  # nothing is fitted: each row's residual as the model is
        return np.linalg.norm(fit(model, joints, position, measured, None, (), **options).residual, axis=1)
    errors = np.zeros(len(joints))
    for rows in region_folds(position, regions)[0]:
        if not len(rows):  # fewer rows than regions
            continue
        train = np.setdiff1d(np.arange(len(joints)), rows)
        pick = (joints[train], position[train], measured[train], None if rotation is None else rotation[train])
        try:
            fitted = fit(model, *pick, names, **options)
        except UpdateRefused:
            return None
        seen = fit(fitted.model, joints[rows], position[rows], measured[rows], None, (), **options).residual
        if corrected:
            seen = seen - correction(position[train], fitted.residual).evaluate(position[rows])
        errors[rows] = np.linalg.norm(seen, axis=1)
    return errors


def correction(position, residual):
    """The correction (`Kriging`, chosen by maximum likelihood) of residuals (N, 3) mm at commanded positions
    (N, 3) mm."""
    return Kriging.fit(position, residual)


def corrected_fit(fitted, joints, position, measured, rotation, **options):
    """``fitted`` with the correction of its residuals at the rows as its model's field on top, held out by region.

    None for a model whose composite has a field over positions already (a
    field on top of a field is not offered). The correction's held-out
    residual (`Fit.held_out`) refits ``fitted``'s parameters and the
    correction on the other regions (`held_out_errors`).
    """
    model = fitted.model
    if model.error_field("composite") is not None:
        return None
    field = correction(position, fitted.residual)
    held = held_out_errors(model, joints, position, measured, rotation, fitted.names, corrected=True, **options)
    return dataclasses.replace(fitted, model=dataclasses.replace(model, residual_field=field),
                               residual=fitted.residual - field.evaluate(position), held_out=held)


def better(fit_a, fit_b):
    """True when ``fit_a`` predicts the rows of each region from the others significantly better than ``fit_b``.

    A paired test of the held-out |residual| of each row
    (`Fit.held_out`): the mean improvement exceeds `EVIDENCE` standard
    errors. The held-out residual carries what the fit's own uncertainty
    costs; the test keeps the noise of a few rows from choosing the larger
    fit. False when ``fit_a`` has no held-out residual, or of one row.
    """
    if fit_a.held_out is None or len(fit_a.held_out) < 2:
        return False
    gain = fit_b.held_out - fit_a.held_out
    return bool(gain.mean() > EVIDENCE * gain.std(ddof=1) / np.sqrt(len(gain)))


@dataclasses.dataclass(frozen=True, eq=False)
class Update:
    """A light re-calibration (`update`): the model as it is, registered anew, and updated, on the same rows.

    Attributes
    ----------
    as_is : Fit
        The model as it was, its own registration (no parameter).
    registered : Fit
        The registration alone (base-frame rows: the model as it was).
    updated : Fit
        The update.
    corrected : Fit or None
        The fit the model takes without a correction (`base`), with the
        correction of its residuals at the rows on top (`corrected_fit`).
    expected_mm : float or None
        The model's own mean |error| (`expected_error`), what the rows are judged against.
    joints : ndarray, shape (N, 6)
        The rows' commanded joints, rad.
    temperature : dict or None
        ``{"model", "rows", "change"}``: the mean temperature of the model's
        measurements and of the rows, deg C, where both files have the
        column (`temperature_change`).
    """

    as_is: Fit
    registered: Fit
    updated: Fit
    corrected: Fit
    expected_mm: float
    joints: np.ndarray
    temperature: dict = None

    @property
    def base(self):
        """The parameters' fit the updated model takes: the smallest the rows do not significantly improve on
        (`better`).

        The registration replaces the model's only when it predicts the
        rows better (the tracker moved), the update the registration only
        when it predicts them better again: the rows show the drift. So an
        update never follows noise, keeps a model measured the same day as
        it is, and is never worse than ``validate --register`` on the rows
        it has.
        """
        kept = self.registered if better(self.registered, self.as_is) else self.as_is
        return self.updated if better(self.updated, kept) else kept

    @property
    def kept(self):
        """The fit the updated model takes: `base`, with the correction where that predicts the rows better."""
        corrected = self.corrected is not None and better(self.corrected, self.base)
        return self.corrected if corrected else self.base

    @property
    def applied(self):
        """What the updated model's parameters took: ``update``, ``registration`` or ``none`` (the model as it was)."""
        base = self.base
        return "update" if base is self.updated else "registration" if base is self.registered else "none"

    @property
    def correction(self):
        """The correction the updated model took (`Kriging`), or None."""
        return self.kept.model.residual_field if self.kept is self.corrected else None

    @property
    def model(self):
        """The updated model (the `kept` fit's), its ``report["update"]`` = `record`."""
        report = dict(self.as_is.model.report)
        report["update"] = self.record()
        return dataclasses.replace(self.kept.model, report=report)

    @property
    def outside(self):
        """How many rows lie outside the joint range the model's joint errors were calibrated on."""
        return int(np.sum(self.as_is.model.arm("composite").outside_rows(self.joints)))

    def scale_per_kelvin(self):
        """The updated scale per kelvin of temperature change, ppm/K (None without both temperatures or the scale,
        or for a change under `MIN_TEMPERATURE_CHANGE`): beside the links' expansion coefficient (aluminium about
        23 ppm/K), it says how much of the scale the hall's temperature explains."""
        if self.temperature is None or SCALE not in self.updated.names or \
                abs(self.temperature["change"]) < MIN_TEMPERATURE_CHANGE:
            return None
        return float(self.updated.delta[self.updated.names.index(SCALE)] / PPM / self.temperature["change"])

    def changes(self):
        """``[(name, value, sigma, unit)]`` of the update, display units (mm, deg, ppm)."""
        fit_ = self.updated
        shown = to_display(fit_.names)
        return list(zip(fit_.names, fit_.delta * shown, fit_.sigma * shown, _units(fit_.names)))

    def verdict(self):
        """``(word, why)``: ``valid``, ``recalibrate`` (this light update) or ``recalibrate fully``.

        From the rows predicted by region (`Fit.held_out`): the model (registered anew
        where that predicts them better) within `STILL_VALID` times the
        model's expected error: still valid; else the update, where the rows
        show it, within `LIGHT_ENOUGH` times it: a light re-calibration
        does; else the drift is more than these parameters hold.
        """
        stale = self.registered if better(self.registered, self.as_is) else self.as_is
        before = stale.held_out.mean()
        after = np.inf if self.updated.held_out is None else self.updated.held_out.mean()
        expected = before if self.expected_mm is None else self.expected_mm
        shown = "not identified by a part of the rows" if self.updated.held_out is None else f"{after:.4f} mm"
        figures = (f"residual {before:.4f} mm as the model is{' (registered anew)' if stale is self.registered else ''}"
                   f", {shown} after the update (each region of the rows predicted from the others), model's own "
                   f"error {expected:.4f} mm")
        if self.correction is not None:
            figures += f"; {self.corrected.held_out.mean():.4f} mm with the correction of what the fit leaves"
        if self.outside:
            figures += (f"; {self.outside} of the {len(self.joints)} rows lie outside the joint range the model was "
                        "calibrated on")
        if before <= STILL_VALID * expected:
            return "valid", f"model still valid: {figures}"
        if self.applied == "update" and after <= LIGHT_ENOUGH * expected:
            return "recalibrate", f"re-calibrate (trajcomp recalibrate: the drift is of the updated parameters): {figures}"
        return "recalibrate fully", (f"re-calibrate fully (trajcomp calibrate: the update leaves more than "
                                     f"{LIGHT_ENOUGH:g}x the model's error): {figures}")

    def record(self):
        """The plain-data record stored as ``report["update"]`` of the updated model.

        Keys: ``rows``; ``names``, ``units`` (mm, deg or ppm per name),
        ``values`` and ``sigma`` (display units) of every parameter the
        update fitted (``base_*``: the registration's change from a rigid
        best fit of the model's prediction; ``target_*``: the measured
        frame's turn from the model's); ``covariance`` (P x P, the same
        units: entry i, j in unit i times unit j); ``arm`` (the names among
        them that move a program's targets: tool, zeros, scale);
        ``added_sigma_mm`` (the position standard deviation per axis those
        add at the rows: ``mean`` and ``max``); ``applied`` (``update``,
        ``registration`` or ``none``: what the model took, `kept`; the
        values and covariance are the model's only with ``update``);
        ``as_is_mm``, ``registered_mm``, ``updated_mm`` and
        ``corrected_mm`` (the rows' mean |residual|: ``fit``, and
        ``held_out`` by region, `held_out_errors`; ``corrected_mm`` None
        where no correction was offered); ``correction`` (None, or the
        correction the model took: ``kind``, ``rows``, ``length_mm``,
        ``nugget``);
        ``outside_rows``; ``temperature_c`` (`temperature`) and
        ``scale_ppm_per_k`` (`scale_per_kelvin`), or None; ``verdict`` and
        ``verdict_reason``.
        """
        fit_ = self.updated
        shown = to_display(fit_.names)
        added = added_sigma(fit_, self.joints)
        word, why = self.verdict()

        def residual(fitted):
            return {"fit": float(np.linalg.norm(fitted.residual, axis=1).mean()),
                    "held_out": None if fitted.held_out is None else float(fitted.held_out.mean())}

        return {
            "rows": len(self.joints),
            "names": list(fit_.names),
            "units": _units(fit_.names),
            "values": (fit_.delta * shown).tolist(),
            "sigma": (fit_.sigma * shown).tolist(),
            "covariance": (fit_.covariance * np.outer(shown, shown)).tolist(),
            "arm": [n for n in fit_.names if not n.startswith(("base_", "target_"))],
            "added_sigma_mm": {"mean": float(added.mean()), "max": float(added.max())},
            "condition": fit_.condition,
            "as_is_mm": residual(self.as_is),
            "registered_mm": residual(self.registered),
            "updated_mm": residual(fit_),
            "corrected_mm": None if self.corrected is None else residual(self.corrected),
            "applied": self.applied,
            "correction": None if self.correction is None else {
                "kind": self.correction.kind, "rows": len(self.correction.points),
                "length_mm": self.correction.length, "nugget": self.correction.nugget},
            "outside_rows": self.outside,
            "temperature_c": self.temperature,
            "scale_ppm_per_k": self.scale_per_kelvin(),
            "verdict": word,
            "verdict_reason": why,
        }


def expected_error(model):
    """The model's mean |error| in mode composite: held out (its cross-validation), else of its fit, mm; or None."""
    for section in ("cross_validation", "fit"):
        stats = model.report.get(section, {}).get("composite")
        if isinstance(stats, dict):
            return float(stats["mean"])
    return None


def temperature_change(model, temperature):
    """``{"model", "rows", "change"}`` deg C: the mean temperature the model was measured at (its report's) and
    that of the rows (N,), or None when either is unknown."""
    recorded = model.report.get("measurements", {}).get("temperature_c")
    if temperature is None or not isinstance(recorded, dict) or "mean" not in recorded:
        return None
    rows = float(np.mean(temperature))
    return {"model": float(recorded["mean"]), "rows": rows, "change": rows - float(recorded["mean"])}


def update(model, joints, position, measured, rotation=None, groups=GROUPS, *, tracker=True, loss="huber",
           orientation_weight=ORIENTATION_WEIGHT, temperature=None):
    """Re-identify the parameters of ``groups`` that drift between campaigns from rows of a new one.

    Parameters as `fit`; ``groups`` a subset of `GROUPS`; ``temperature``
    (N,) deg C, the rows' temperature column when the file has one.

    Returns
    -------
    Update
    """
    common = dict(tracker=tracker, loss=loss, orientation_weight=orientation_weight)
    if getattr(model.residual_field, "kind", None) == KRIGING_KIND:  # an earlier update's: this update's replaces it
        model = dataclasses.replace(model, residual_field=None)
    rows = (model, joints, position, measured, rotation)
    levels = [(), BASE_NAMES if tracker else (), parameter_names(groups, tracker=tracker, oriented=rotation is not None)]
    fits = [fit(*rows, names, **common) for names in levels[::-1]][::-1]  # the update first: it needs the most rows
    fits = [dataclasses.replace(fitted, held_out=held_out_errors(*rows, names, **common))
            for fitted, names in zip(fits, levels)]
    result = Update(*fits, None, expected_error(model), joints, temperature_change(model, temperature))
    return dataclasses.replace(result, corrected=corrected_fit(result.base, joints, position, measured, rotation,
                                                               **common))


def choose_rows(model, joints, count=30, groups=GROUPS, *, tracker=True, oriented=True,
                orientation_weight=ORIENTATION_WEIGHT):
    """The ``count`` candidate configurations to measure for an update: representative, and identifying it.

    First the candidates nearest the centres of ``count`` clusters of their
    TCP positions (k-means, seeded): rows spread as the candidates are, so
    that the registration and the update fit the model where programs run.
    When those do not identify the update's parameters, the D-optimal
    choice instead (`_d_optimal`): the rows whose parameter covariance has
    the least volume. D-optimal rows lie at the edges of the workspace,
    where the model's own error is largest, and fit it there: on series B of
    ur10-ipa, registered on them the rest lands at 0.298 mm mean, on
    representative rows at 0.280 (`bench_recalibrate.py`).

    Parameters
    ----------
    model : CompensationModel
    joints : ndarray, shape (C, 6)
        Candidate commanded joints, rad (C >= count).
    count : int
    groups, tracker, oriented, orientation_weight
        As `update` (``oriented``: orientations will be measured).

    Returns
    -------
    ndarray of int, shape (count,)
        Indices of the chosen candidates.
    str
        How they were chosen: ``representative`` or ``D-optimal``.

    Raises
    ------
    UpdateRefused
        Neither choice identifies the update's parameters.
    """
    from scipy.cluster.vq import kmeans2  # here: compensating never needs it

    names = parameter_names(groups, tracker=tracker, oriented=oriented)
    if count > len(joints):
        raise CalibrationError(f"{len(joints)} candidate configurations: fewer than the {count} to choose")
    jac = design(model, joints, names, oriented, orientation_weight)
    position = fk(model.nominal, joints)[:, :3, 3]
    centres, cluster = kmeans2(position, count, seed=1, minit="++")
    chosen = [int(members[np.argmin(np.linalg.norm(position[members] - centres[k], axis=1))])
              for k in range(count) for members in [np.flatnonzero(cluster == k)] if len(members)]
    chosen += [k for k in _d_optimal(jac, count, chosen) if k not in chosen][: count - len(chosen)]  # empty clusters
    if not analyse_identifiability(jac[chosen].reshape(-1, len(names)), names, RTOL).fixed:
        return np.array(chosen), "representative"
    chosen = _d_optimal(jac, count)
    picked = jac[chosen].reshape(-1, len(names))
    if analyse_identifiability(picked, names, RTOL).fixed:
        raise UpdateRefused(f"no {count} of these {len(joints)} candidate configurations identify the update's "
                            f"{', '.join(names)}: they do not tell apart " + "; ".join(_unseen(picked, names))
                            + ". Give candidates that turn the tool and move the joints more, or leave a group out "
                            "(--only)")
    return chosen, "D-optimal"


def _d_optimal(jac, count, start=()):
    """Greedy D-optimal choice (count,) of candidates from their scaled Jacobian (C, rows, P), after ``start``.

    Without ``start``, the first are those a pivoted QR of the Jacobian
    picks (one per parameter at most); each further one is the candidate
    that raises ``log det(J^T J)`` of the chosen ones most.
    """
    from scipy.linalg import qr  # here: compensating never needs it

    blocks, size = jac.shape[1:]
    chosen = list(start)
    if not chosen:
        _, _, order = qr(jac.reshape(-1, size).T, mode="economic", pivoting=True)
        chosen = list(dict.fromkeys(order[:size] // blocks))[:count]
    information = sum((jac[k].T @ jac[k] for k in chosen), 1e-9 * np.eye(size))
    while len(chosen) < count:
        inverse = np.linalg.inv(information)
        # det(M + J_c^T J_c) = det(M) det(I + J_c M^-1 J_c^T): the gain of each candidate c
        gain = np.linalg.slogdet(np.eye(blocks) + np.einsum("crp,pq,csq->crs", jac, inverse, jac))[1]
        gain[chosen] = -np.inf
        best = int(np.argmax(gain))
        chosen.append(best)
        information += jac[best].T @ jac[best]
    return np.array(chosen)


def design(model, joints, names, oriented, orientation_weight=ORIENTATION_WEIGHT):
    """The update's scaled Jacobian (C, rows, P) at commanded joints (C, 6) rad: what rows there would observe.

    Rows 3 (positions) or 6 (``oriented``: orientations too, times the
    weight) per configuration; columns the parameters ``names`` in solver
    units (mm, or the effect at `LEVER` mm of an angle or of the scale).
    """
    rows = _Rows(model, joints, fk(model.nominal, joints)[:, :3, 3], np.zeros((len(joints), 3)),
                 np.tile(np.eye(3), (len(joints), 1, 1)) if oriented else None, orientation_weight)
    return rows.residual(model, names)[1] * _solver_scale(names)  # it does not depend on the measured values


def _field(model, position, joints):
    """The composite's field on top at commanded positions (N, 3), mm, and joints (N, 6) rad, or 0.0 without one."""
    field = model.error_field("composite")
    return 0.0 if field is None else evaluate_field(field, position, outside="clamp", joints=joints)[0]
