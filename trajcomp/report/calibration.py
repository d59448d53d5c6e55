"""Calibration and validation reports: accuracy per mode, ISO 9283, error trends and maps, parameters, validity.

The per-point errors are recomputed here from the measurements and the
model (`trajcomp.calibration.calibrate.mode_errors`); the fit and cross-validation
statistics are those `calibrate` stored in the model.
"""

import numpy as np
from scipy.spatial.transform import Rotation

from trajcomp.calibration.calibrate import commanded, mode_errors, to_base
from trajcomp.model.grid import ResidualGrid
from trajcomp.arm.parameters import is_angle
from trajcomp.arm.kinematics import fk
from trajcomp.report import plots
from trajcomp.report.document import Figure, Report
from trajcomp.report.provenance import grid_box, header
from trajcomp.model import landing
from trajcomp.report.verdict import Criteria, accuracy_check, verdict
from trajcomp.model.stats import AXES, ErrorStats
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc, matrix_to_pose

ISO_CYCLES = 30  # cycles per pose of the ISO 9283 test


def trends(position, errors):
    """Least-squares line of each error axis against each commanded coordinate.

    Parameters
    ----------
    position, errors : ndarray, shape (N, 3)
        Commanded positions and errors, mm.

    Returns
    -------
    dict
        ``out["dx"]["y"] = {"slope_mm_per_m", "intercept_mm", "r2"}``; R² is 0
        where the coordinate or the error does not vary.
    """
    out = {}
    for e, name in enumerate(("dx", "dy", "dz")):
        out[name] = {}
        for c, axis in enumerate(AXES):
            x, y = position[:, c], errors[:, e]
            dx, dy = x - x.mean(), y - y.mean()
            sxx, syy = float(dx @ dx), float(dy @ dy)
            slope = float(dx @ dy) / sxx if sxx > 0 else 0.0
            r2 = slope**2 * sxx / syy if syy > 0 else 0.0
            out[name][axis] = {"slope_mm_per_m": slope * 1000.0, "intercept_mm": float(y.mean() - slope * x.mean()),
                               "r2": float(min(r2, 1.0))}
    return out


def iso9283(position, measured, predicted, mode, command=None):
    """ISO 9283-style pose accuracy (AP) and repeatability (RP) over commands measured more than once.

    Per repeated command (a pose: its values equal to the third decimal):
    the barycentre of the attained positions; AP = its distance to the
    command (and to the model's prediction); RP = mean + 3 standard
    deviations (n - 1) of the distances of the attained positions to the
    barycentre. One position reached in several orientations is several
    poses, each with its own error: not repeated cycles of one.

    Parameters
    ----------
    position, measured, predicted : ndarray, shape (N, 3)
        Commanded, measured and model-predicted positions, mm.
    mode : str
        The mode of ``predicted``.
    command : ndarray, shape (N, K), optional
        What tells each row's commanded pose: its joints (deg), or its
        position and orientation; default the position alone.
    """
    command = position if command is None else command
    _, group, counts = np.unique(np.round(command, 3), axis=0, return_inverse=True, return_counts=True)
    group = group.ravel()
    repeated = np.flatnonzero(counts >= 2)
    if not repeated.size:
        return {"available": False, "mode": mode,
                "note": "no command was measured more than once, so repeatability (RP) and the ISO 9283 pose "
                        "accuracy (AP of a barycentre) cannot be computed; measure a few poses 30 times to get them"}

    def mean_of(values):
        sums = np.stack([np.bincount(group, weights=values[:, c], minlength=len(counts)) for c in range(3)], axis=1)
        return sums / counts[:, None]

    barycentre = mean_of(measured)
    distance = np.linalg.norm(measured - barycentre[group], axis=1)
    l_mean = np.bincount(group, weights=distance) / counts
    spread = np.bincount(group, weights=(distance - l_mean[group]) ** 2) / np.maximum(counts - 1, 1)
    rp = l_mean + 3.0 * np.sqrt(spread)
    ap = np.linalg.norm(barycentre - mean_of(position), axis=1)
    ap_model = None if predicted is None else np.linalg.norm(barycentre - mean_of(predicted), axis=1)
    poses = [{"position": mean_of(position)[g].round(3).tolist(), "cycles": int(counts[g]), "ap_mm": float(ap[g]),
              "ap_model_mm": None if ap_model is None else float(ap_model[g]), "rp_mm": float(rp[g])}
             for g in repeated]
    few = counts[repeated].min() < ISO_CYCLES
    return {
        "available": True,
        "mode": mode,
        "note": f"{repeated.size} commands were measured {_range(counts[repeated])} times"
                + (f"; ISO 9283 asks for {ISO_CYCLES} cycles per pose, so these figures are indicative" if few else ""),
        "cycles_min": int(counts[repeated].min()),
        "cycles_max": int(counts[repeated].max()),
        "ap_max_mm": float(ap[repeated].max()),
        "ap_model_max_mm": None if ap_model is None else float(ap_model[repeated].max()),
        "rp_max_mm": float(rp[repeated].max()),
        "poses": poses,
    }


def _range(values):
    """``"3"`` or ``"3 to 5"``."""
    low, high = int(values.min()), int(values.max())
    return f"{low}" if low == high else f"{low} to {high}"


def orientations(rotations):
    """Distinct commanded orientations (to about 0.1 deg) and their spread, of rotation matrices (N, 3, 3)."""
    if rotations is None:
        return None
    _, first = np.unique(np.round(rotations.reshape(-1, 9), 3), axis=0, return_index=True)
    rot = Rotation.from_matrix(rotations)
    deviation = np.degrees((rot.mean().inv() * rot).magnitude())
    return {"distinct": int(len(first)), "max_deviation_deg": float(deviation.max()),
            "examples": np.degrees(matrix_to_abc(rotations[np.sort(first)[:5]])).round(3).tolist()}


def _data(model, meas):
    """Commanded joints (or None), positions, measured positions in the base frame, and errors per mode."""
    joints, position = commanded(model.nominal, meas)
    measured = to_base(model.T_tracker_base, meas.measured)
    return joints, position, measured, mode_errors(model, joints, position, measured)


SHOWN_TERM = 0.01  # a combination shows the terms whose coefficient (mm/mm, mm/deg, deg/mm, deg/deg) is at least this


def identifiable_combinations(model, joints, residuals, rotation=False):
    """What the data identify of the parameters: each kept parameter with the fixed ones it stands in for.

    A parameter the data do not identify on their own (``model.dh_fixed``,
    pivoted QR of `trajcomp.calibration.identify`) has a column of the
    Jacobian that the kept ones reproduce, J_F = J_K A: the data see each
    kept parameter k only as the combination ``k + sum_f A_kf f``. Its value
    (the fit's deltas put in) and standard deviation are what the
    measurements determine; the separate deltas are not (the fit spreads
    them at least cost from the nominal arm). The frames the fit refines
    with the arm count among the kept (the tracker registration of
    tracker-frame data, the measured frame of orientations): a parameter
    they stand in for (base z for d1) is in no combination of the arm's.

    Parameters
    ----------
    model : CompensationModel
    joints : ndarray, shape (N, 6)
        Commanded joints of the fit's rows, rad.
    residuals : ndarray, shape (N, 3)
        Measured minus predicted by the parameter model (mm): their
        variance scales the standard deviations.
    rotation : bool
        The rows measured orientations too (their Jacobian rows count, at
        the default orientation weight).

    Returns
    -------
    list of dict
        Per kept parameter of the arm that stands for fixed ones: ``name``,
        ``terms`` (``[{"name", "coefficient"}]``, the fixed parameters in its
        combination, coefficient in the combination's unit per the term's),
        ``value``, ``sigma``, ``unit`` (mm or deg).
    """
    from trajcomp.arm.parameters import BASE_NAMES, TARGET_NAMES, pose_jacobian, scales
    from trajcomp.calibration.options import ORIENTATION_WEIGHT

    frames = [*(BASE_NAMES if not np.allclose(model.T_tracker_base, np.eye(4)) else ()),
              *(TARGET_NAMES if rotation else ())]
    names = [*model.dh_names, *frames]
    _, jac = pose_jacobian(model.identified, joints, names, model.R_tcp_target)
    rows = np.concatenate([jac[:, :3], ORIENTATION_WEIGHT * jac[:, 3:]], axis=1) if rotation else jac[:, :3]
    scale = scales(names)
    J = rows.reshape(-1, len(names)) * scale  # solver units, as the identification's analysis
    kept = [k for k, n in enumerate(names) if n not in model.dh_fixed]
    fixed = [k for k, n in enumerate(names) if n in model.dh_fixed]
    stands_for = np.linalg.lstsq(J[:, kept], J[:, fixed], rcond=None)[0]  # (K, F): J_F = J_K A
    x = np.r_[np.asarray(model.dh_delta, dtype=float), np.zeros(len(frames))] / scale  # frames: their own moves
    value = x[kept] + stands_for @ x[fixed]
    variance = float(np.sum(residuals**2)) / max(residuals.size - len(kept), 1)
    sigma = np.sqrt(np.clip(np.diag(np.linalg.pinv(J[:, kept].T @ J[:, kept])) * variance, 0.0, None))
    user = scale * np.where([is_angle(n) for n in names], np.degrees(1.0), 1.0)  # solver unit -> mm or deg
    out = []
    for i, k in enumerate(kept):
        coefficients = stands_for[i] * user[k] / user[fixed]
        terms = [{"name": names[f], "coefficient": float(c)} for f, c in zip(fixed, coefficients)
                 if abs(c) >= SHOWN_TERM]
        if terms and names[k] in model.dh_names:  # one identified on its own keeps the fit's delta and sigma
            out.append({"name": names[k], "terms": terms, "value": float(value[i] * user[k]),
                        "sigma": float(sigma[i] * user[k]), "unit": "deg" if is_angle(names[k]) else "mm"})
    return out


def parameter_combinations(model, meas):
    """`identifiable_combinations` of a model on the measurements it was fitted on (None when the fit kept
    every parameter, or the rows have no joints): what ``trajcomp calibrate`` prints."""
    joints, _, _, errors = _data(model, meas)
    return _combinations(model, meas, joints, errors)


def _combinations(model, meas, joints, errors):
    if joints is None or not model.dh_fixed:
        return None
    used = ~np.isin(meas.lines, list(model.report.get("outlier_lines") or []))
    residuals = errors["dh" if "dh" in errors else _after_mode(model)][used]
    return identifiable_combinations(model, joints[used], residuals, rotation=meas.measured_orientation is not None)


def combination_text(combination):
    """``"d2 + d3 + d4 - a5 - 2.026 alpha4"``: a combination's terms, coefficients of 1 left out."""
    text = combination["name"]
    for term in combination["terms"]:
        c = term["coefficient"]
        sign = "+" if c > 0 else "−"
        size = "" if abs(abs(c) - 1.0) < 5e-4 else f"{abs(c):.3g} "
        text += f" {sign} {size}{term['name']}"
    return text


def _after_mode(model):
    """The mode whose errors at the fit's own points are an honest 'after' map.

    A lattice grid reproduces its nodes, so its fit errors there are zero by
    construction: the map then shows the model before the grid.
    """
    lattice = [m for m in ("grid", "composite") if isinstance(model.error_field(m), ResidualGrid)]
    honest = [m for m in model.modes if m not in lattice]
    return model.method if model.method in honest else honest[-1]


def _files_and_robot(model, files, options):
    return {"files": list(files), "robot": {"name": model.nominal.name, "source": model.nominal.source},
            "options": options or {}}


def held_out_check(model, tolerance):
    """The calibration's headline criterion: 95 % of the held-out errors of the model's mode within the tolerance.

    Held out with the interpolator the compensation uses (`trajcomp.model.landing`);
    a model without them falls back to its k-fold cross-validation, else the
    criterion is not evaluated.
    """
    mode = model.method
    data = landing.of_model(model)
    if data is not None and mode in data.held_out:
        return accuracy_check(data.held_out[mode], mode, tolerance, "held-out (with its own interpolator)")
    cv = model.report.get("cross_validation") or {}
    return accuracy_check(cv.get(mode), mode, tolerance, f"{cv.get('folds', 'k')}-fold cross-validation", missing=(
        "no held-out errors: calibrated with --folds 0, so the fit statistics flatter the model"))


def calibration_report(model, meas, *, criteria=None, files=(), options=None):
    """The calibration report of a model and the measurements it was identified from.

    Parameters
    ----------
    model : CompensationModel
        As returned by `trajcomp.calibration.calibrate.calibrate` (its ``report`` holds
        the fit and cross-validation statistics).
    meas : Measurements
        The measurements (all rows; outliers are marked by line).
    criteria : Criteria, optional
        Its tolerance judges the held-out accuracy of the model's mode
        (`held_out_check`; default 0.1 mm).
    files : sequence of dict
        `trajcomp.report.provenance.file_entry` of inputs and outputs.
    options : dict, optional
        The run's options as given.

    Returns
    -------
    Report
    """
    criteria = criteria or Criteria()
    joints, position, measured, errors = _data(model, meas)
    stored = model.report
    outlier_lines = list(stored.get("outlier_lines") or [])
    excluded = np.isin(meas.lines, outlier_lines)
    cv = stored.get("cross_validation")
    after = _after_mode(model)
    missing = []
    if model.grid is None and model.residual is None:
        missing.append("no grid: this model has no residual grid (method " + model.method + "), so there is no "
                       "grid box; targets are compensated by the parameter or linear model everywhere")
    if cv is None:
        missing.append("no cross-validation: calibrate ran with --folds 0; the fit statistics flatter the model")
    command = np.degrees(joints) if joints is not None else (
        position if meas.orientation is None else np.hstack([position, meas.orientation]))
    iso = iso9283(position[~excluded], measured[~excluded], (measured - errors[after])[~excluded], after,
                  command[~excluded])
    if not iso["available"]:
        missing.append("no repeatability: " + iso["note"])
    rotations = fk(model.nominal, joints)[:, :3, :3] if joints is not None else (
        None if meas.orientation is None else abc_to_matrix(meas.orientation))
    tool = matrix_to_pose(model.nominal.T_flange_tool)
    tool[3:] = np.degrees(tool[3:])
    identified_tool = [model.dh_delta[model.dh_names.index(n)] if n in model.dh_names else 0.0
                       for n in ("tool_x", "tool_y", "tool_z")]
    doc = header("calibration", "calibrate")
    doc.update({
        "provenance": _files_and_robot(model, files, options),
        "criteria": criteria.as_dict(),
        "verdict": verdict([held_out_check(model, criteria.tolerance)]),
        "method": model.method,
        "modes": list(model.modes),
        "points": len(meas),
        "used": int((~excluded).sum()),
        "fit": {m: s for m, s in (stored.get("fit") or {}).items() if isinstance(s, dict)},
        "cross_validation": None if cv is None else {
            "folds": cv["folds"], "interpolation": cv.get("interpolation"),
            "modes": {m: s for m, s in cv.items() if isinstance(s, dict)}},
        "held_out": None if "landing" not in stored else {
            "method": stored["landing"]["method"], "modes": stored["landing"]["held_out"]},
        "reliability": stored.get("reliability"),
        "iso9283": iso,
        "trends": trends(position[~excluded], errors["none"][~excluded]),
        "linear": None if model.linear is None else model.linear.to_dict(),
        "maps_note": _maps_note(model, after, "fit"),
        "parameters": None if not model.dh_names else {
            "identified": [{"name": n, "delta": float(np.degrees(d) if is_angle(n) else d),
                            "sigma": float(np.degrees(s) if is_angle(n) else s), "unit": "deg" if is_angle(n) else "mm"}
                           for n, d, s in zip(model.dh_names, model.dh_delta, model.dh_sigma)],
            "fixed": [{"name": n, "reason": r} for n, r in model.dh_fixed.items()],
            "combinations": _combinations(model, meas, joints, errors),
            "condition_number": (stored.get("identifiability") or {}).get("condition")},
        "joint_errors": _joint_errors(model),
        "outliers": {"file": meas.path, "lines": outlier_lines},
        "validity": {
            "measured_box": {"lower": position.min(axis=0).tolist(), "upper": position.max(axis=0).tolist()},
            "grids": {name: None if getattr(model, name, None) is None or getattr(getattr(model, name), "kind", "") == "joint"
                      else grid_box(getattr(model, name)) for name in ("grid", "residual", "residual_field")
                      if name != "residual_field" or model.residual_field is not None},
            "orientations": orientations(rotations),
            "tool": {"pose": tool.tolist(),
                     "identified_offset_mm": [float(v) for v in identified_tool]
                     if any(n.startswith("tool_") for n in model.dh_names) else None},
            "note": "Targets outside the grid box get the parameter model only. A model measured with one tool in "
                    "few orientations does not locate the flange: targets on another tool or far from the measured "
                    "orientations may miss by tenths of a millimetre.",
        },
        "warnings": list(stored.get("warnings") or []),
        "missing": missing,
    })
    return Report(doc, _figures(doc, position, errors, excluded, after, model, "fit"))


def _joint_errors(model):
    """The joint-angle error model of the composite, as the report states it (None without one)."""
    residual = model.residual
    if getattr(residual, "kind", None) != "joint":
        return None
    names, _ = residual.terms
    families = {family: sum(n.startswith(family) for n in names) for family in ("gear", "grav", "spline")}
    return {
        "terms": families,
        "splines": model.report.get("joint_splines"),
        "field_on_top": None if model.residual_field is None else model.residual_field.kind,
        "measured_range_deg": {"lower": np.degrees(residual.lower).round(3).tolist(),
                               "upper": np.degrees(residual.upper).round(3).tolist()},
        "beyond_range": "a spline term is held at its value at the edge of the measured range of its joint (no shape "
                        "is extrapolated), the gear and gravity terms are evaluated where the joints are; a target more "
                        "than 5 deg beyond the range of any joint is outside the calibrated region (flagged, its "
                        "landing estimate grows with the joints' distance from the measured ones)",
    }


def validation_report(model, meas, *, criteria, files=(), options=None):
    """The validation report: a model's accuracy per mode on measurements it was not fitted to, with a verdict.

    The verdict is the model-accuracy criterion of the compliance report: the
    95th percentile |error| of the model's method within ``criteria.tolerance``.

    Returns
    -------
    Report
        Its document has ``modes: {mode: {n, mean, rms, p95, max, signed_mean, std}}``.
    """
    joints, position, measured, errors = _data(model, meas)
    stats = {m: ErrorStats.from_errors(e).as_dict() for m, e in errors.items()}
    check = accuracy_check(stats[model.method], model.method, criteria.tolerance, "validation measurement")
    doc = header("validation", "validate")
    doc.update({
        "provenance": _files_and_robot(model, files, options),
        "criteria": criteria.as_dict(),
        "verdict": verdict([check]),
        "method": model.method,
        "points": len(meas),
        "modes": stats,
        "trends": trends(position, errors["none"]),
        "maps_note": _maps_note(model, model.method, "validation"),
        "warnings": [],
        "missing": [],
    })
    return Report(doc, _figures(doc, position, errors, np.zeros(len(position), dtype=bool), model.method, model,
                                "validation"))


def _maps_note(model, after, data):
    if data == "validation":
        return (f"|measured − predicted| at the validation points with no compensation (before) and with mode "
                f"{after} (after). Note the different colour scales; each ends at the 99th percentile of its "
                "map, and a map with points above it says so (they take the top colour).")
    why = "" if after == model.method else (
        f" The {model.method} mode is not shown: its grid reproduces the measured nodes, so its errors there are "
        "zero by construction; the cross-validation above is its honest accuracy.")
    return (f"|measured − predicted| at the measured points with no compensation (before) and with mode {after} "
            f"(after, fit).{why} Note the different colour scales; each ends at the 99th percentile of its map, "
            "and a map with points above it says so (they take the top colour).")


def _figures(doc, position, errors, excluded, after, model, data):
    field = model.error_field(model.method)
    box = None if field is None else grid_box(field)
    box = None if box is None else (box["lower"], box["upper"])
    keep = ~excluded
    maps = [("before (none)", np.linalg.norm(errors["none"][keep], axis=1)),
            (f"after ({after})", np.linalg.norm(errors[after][keep], axis=1))]
    tables = ({"fit": doc["fit"]} | ({f"{doc['cross_validation']['folds']}-fold CV": doc["cross_validation"]["modes"]}
                                      if doc["cross_validation"] else {})
              | ({"held out (own interpolator)": doc["held_out"]["modes"]} if doc["held_out"] else {})
              ) if data == "fit" else {"validation": doc["modes"]}
    return (
        Figure("statistics", "Mean and 95th percentile |error| per mode",
               "Log scale; lower is better. A grid reproduces its own nodes, so its fit errors are zero (below "
               f"{plots.ZERO:g} mm: rounding), drawn as 0 at the foot of the axis with no bar; the held-out figures "
               "are its accuracy." if data == "fit" else "Log scale; lower is better.",
               lambda: plots.mode_statistics(tables)),
        Figure("trends", "Error per axis against each commanded coordinate",
               "Each error component (measured − commanded) against each commanded coordinate, with its "
               "least-squares line; red lines mark strong linear relations (R² ≥ 0.5).",
               lambda: plots.error_trends(position, errors["none"], doc["trends"], excluded)),
        Figure("maps", "Error maps", doc["maps_note"], lambda: plots.error_maps(position[keep], maps, box)),
        *([Figure("reliability", "Stated quantile against the true held-out errors",
                  "Each point is a bin of held-out rows of one class, at its mean stated quantile and the same "
                  "quantile of its true errors. On the dashed diagonal the estimate is calibrated; below it, "
                  "conservative; above it, it misses. The growth with distance was fitted on these same errors "
                  "and scaled to cover 95 % of the rows inside their fit's box and 95 % of those outside it.",
                  lambda: plots.reliability(doc["reliability"]))] if doc.get("reliability") else []),
    )
