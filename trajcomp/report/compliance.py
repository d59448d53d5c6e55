"""The compliance report of a compensated (and re-timed) program, as a JSON-ready dict.

Built from the run's `trajcomp.postprocess.ProgramReport` (one row per
compensated target, motion order), the nominal robot, the model and, when
the program was re-timed, the `trajcomp.timing` result. Every criterion of
the verdict is stated with its threshold; each failing one counts and
lists the targets or lines it concerns. Measures, statistics and verdict
cover every target; a long program's table is summarised
(`trajcomp.report.targets`). What the run could not provide (no
compensable motion, no grid in the mode, no re-timing) is listed under
``missing`` instead of being shown empty.
"""

import numpy as np

from trajcomp.report import plots
from trajcomp.report.document import Figure, Report
from trajcomp.report.provenance import grid_box, header
from trajcomp.report.targets import ARRAYS, ROWS, TIMES, flag_bits, full_data, statistics, table_rows, target_json, \
    target_measures
from trajcomp.report.verdict import FAIL, LISTED, PASS, Check, Criteria, accuracy_check, check, not_evaluated, verdict

TIMING_SLACK = 0.01  # relative: a peak up to 1 % over its limit passes (the timing's own dense check)


AS_WRITTEN = "no compensation model: the program runs as written (retime)"
MODEL_MEASURES = ("correction_mm", "correction_deg", "predicted_residual_mm")  # per-target measures a model gives
MODEL_FIELDS = ("correction_mm", "correction_deg", "correction_norm_mm", "correction_norm_deg",
                "predicted_residual_mm", "outside_grid")  # a target's JSON fields that need a model


def target_checks(report, measures, criteria, has_grid, mode, compensated=True):
    """The per-target criteria of the verdict and their failing masks.

    Without compensation the residual and grid criteria are not evaluated;
    without targets, none is.

    Returns
    -------
    checks : list of Check
    masks : dict of str to ndarray of bool, shape (N,)
        Failing targets of each evaluated criterion.
    """
    labels = report.labels
    c = criteria
    statements = {
        "residual": f"predicted residual of every target within {c.tolerance:g} mm",
        "outside_grid": "every target inside the measured grid",
        "configuration": "every target keeps its declared posture (arm branch and joint turns)",
        "joint_limits": f"every joint at least {c.limit_margin:g} deg from its limits",
        "singularity": (f"every target at least {c.singularity_margin:g} deg from elbow and wrist singularities "
                        f"and {c.shoulder_margin:g} mm from the shoulder singularity"),
    }
    if not len(labels):
        return [not_evaluated(key, text, "no compensated target") for key, text in statements.items()], {}
    v = measures.values
    masks = {"residual": v["predicted_residual_mm"] > c.tolerance,
             "outside_grid": np.asarray(report.outside_grid, dtype=bool),
             "configuration": measures.changed,
             "joint_limits": v["limit_distance_deg"] < c.limit_margin,
             "singularity": ((v["shoulder_mm"] < c.shoulder_margin) | (v["elbow_deg"] < c.singularity_margin)
                             | (v["wrist_deg"] < c.singularity_margin))}
    details = {
        "residual": f"largest {v['predicted_residual_mm'].max():.2e} mm",
        "outside_grid": f"{int(masks['outside_grid'].sum())} of {len(labels)} targets outside",
        "configuration": f"{int(masks['configuration'].sum())} targets changed branch or turned a joint by half a turn",
        "joint_limits": f"smallest distance {v['limit_distance_deg'].min():.2f} deg",
        "singularity": (f"smallest: shoulder {v['shoulder_mm'].min():.1f} mm, elbow {v['elbow_deg'].min():.2f} deg, "
                        f"wrist {v['wrist_deg'].min():.2f} deg"),
    }
    skipped = {}
    if not compensated:
        skipped = {"residual": AS_WRITTEN, "outside_grid": AS_WRITTEN}
    elif not has_grid:
        skipped = {"outside_grid": f"mode {mode} uses no grid: every target gets the same kind of correction"}
    masks = {key: mask for key, mask in masks.items() if key not in skipped}
    checks = [not_evaluated(key, text, skipped[key]) if key in skipped
              else check(key, text, masks[key], labels, details[key]) for key, text in statements.items()]
    return checks, masks


def timing_section(timing, before=None, times=True):
    """The timing dict of a `trajcomp.timing` result (contract 3), with the cycle time ``before`` (s) if known.

    ``times``: with the time stamp of every waypoint (``t_s``); a report of
    more than `ROWS` waypoints keeps them in its sidecar instead. The segments (one per stretch
    between exact stops) are counted by kind and listed up to `ROWS`.
    """
    limits = {"velocity": ("peak_velocity", "limit_velocity", "deg/s"),
              "acceleration": ("peak_acceleration", "limit_acceleration", "deg/s^2"),
              "jerk": ("peak_jerk", "limit_jerk", "deg/s^3")}
    measured = {"velocity": np.ones(6, bool), "acceleration": np.ones(6, bool), "jerk": timing.jerk_measured}
    joints = []
    for j in range(6):
        row = {"joint": j + 1}
        for name, (peak, limit, unit) in limits.items():
            p, lim = float(np.degrees(getattr(timing, peak)[j])), float(np.degrees(getattr(timing, limit)[j]))
            p = p if measured[name][j] else None  # a TOPP-RA law does not bound jerk: not a measured 0
            row[name] = {"peak": p, "limit": lim if np.isfinite(lim) else None, "unit": unit,
                         "ratio": p / lim if p is not None and np.isfinite(lim) and lim > 0 else None}
        joints.append(row)
    by_kind = {}
    for segment in timing.segments:
        entry = by_kind.setdefault(segment.kind, {"count": 0, "duration_s": 0.0})
        entry["count"] += 1
        entry["duration_s"] += float(segment.duration)
    segments = [{"kind": s.kind, "first": int(s.first), "last": int(s.last), "duration_s": float(s.duration),
                 "speed": getattr(s, "speed", None), "jerk_limited": bool(s.jerk_limited)}
                for s in timing.segments[:ROWS]]
    as_written, lowered = getattr(timing, "as_written", ()), getattr(timing, "lowered", ())
    section = {
        "cycle_time_s": float(timing.cycle_time),
        "cycle_time_before_s": None if before is None else float(before),
        "within_limits": bool(timing.within_limits),
        "peak_tcp_speed_ratio": float(timing.peak_speed_ratio),
        "jerk_limited_segments": int(timing.jerk_limited_segments),
        "joints": joints,
        "segment_count": len(timing.segments),
        "segments_by_kind": by_kind,
        "segments": segments,
        "not_retimed": {"count": len(as_written), "reason": "speed set at run time: the field is left as written",
                        "motions": [{"waypoint": str(timing.labels[k]), "why": why} for k, why in as_written[:ROWS]]},
        "lowered": {"count": len(lowered),
                    "motions": [{"waypoint": str(timing.labels[k]), "detail": text} for k, text in lowered[:ROWS]]},
    }
    if times:
        section["t_s"] = np.round(np.asarray(timing.t, dtype=float), 4).tolist()
    return section


def timing_check(section):
    """The timing criterion (a Check) of a timing section, or not evaluated without one.

    Its statement is what the dense check measured: joint velocity and
    acceleration and the TCP speed at 1 kHz, and the jerk only where a
    segment bounds it (the others are named as not bounded).
    """
    checked = (f"sampled at 1 kHz: joint velocity and acceleration within the robot's limits and TCP speed within "
               f"the programmed speed (+{TIMING_SLACK:.0%})")
    if section is None:
        return not_evaluated("timing", checked, "the program was not re-timed")
    limited, total = section["jerk_limited_segments"], section["segment_count"]
    if total and limited == total:
        statement = f"{checked}; jerk within the robot's limits"
    elif limited:
        statement = f"{checked}; jerk within the robot's limits in {limited} of {total} segments, not bounded in the others"
    else:
        statement = f"{checked}; jerk not bounded (not checked)"
    over = [f"J{row['joint']} {name} {q['peak']:.1f} > {q['limit']:.1f} {q['unit']}"
            for row in section["joints"] for name, q in row.items()
            if name != "joint" and q["ratio"] is not None and q["ratio"] > 1 + TIMING_SLACK]
    failed = over or not section["within_limits"]
    detail = "; ".join(over) or ("the dense check of the timed path exceeds a limit" if failed else
                                 f"cycle time {section['cycle_time_s']:.3f} s")
    return Check("timing", statement, FAIL if failed else PASS, detail)


def speeds_check(section):
    """The criterion that every timed motion's speed is known (none left as written because it is set at run time)."""
    statement = "every timed motion's speed known to the re-timing (none set at run time)"
    if section is None:
        return not_evaluated("speeds", statement, "the program was not re-timed")
    kept = section["not_retimed"]
    if not kept["count"]:
        return Check("speeds", statement, PASS, "every speed stated or provably constant")
    return Check("speeds", statement, FAIL,
                 f"{kept['count']} motion(s) not re-timed, speed set at run time (left as written): "
                 f"{kept['motions'][0]['why']}", targets=tuple(m["waypoint"] for m in kept["motions"][:LISTED]),
                 failing=kept["count"])


def compliance_report(report, robot, *, criteria=None, model=None, model_info=None, mode=None, files=(),
                      options=None, timing=None, cycle_time_before=None, command="compensate", workers=1):
    """The compliance report of one run (schema ``trajcomp-report/1``, kind ``compliance``).

    Parameters
    ----------
    report : ProgramReport
        What the compensation did (contract 1 of the brief).
    robot : Robot
        The nominal robot.
    criteria : Criteria, optional
        Thresholds of the verdict (defaults: 0.1 mm, 1 deg, 5 deg, 50 mm).
    model : CompensationModel, optional
    model_info : dict, optional
        `trajcomp.report.provenance.model_entry` of the model file.
    mode : str, optional
        The mode used (default: the model's method).
    files : sequence of dict
        `trajcomp.report.provenance.file_entry` of inputs and outputs.
    options : dict, optional
        The run's options as given, for provenance.
    timing : TimingResult, optional
        The re-timing of the corrected program (contract 3).
    cycle_time_before : float, optional
        Cycle time of the program before, s.
    command : str
        The command that ran (``compensate``, ``retime``).
    workers : int
        Processes that share the per-target measures (`target_measures`).

    Returns
    -------
    Report
    """
    criteria = criteria or Criteria()
    mode = mode or (model.method if model is not None else None)
    has_grid = model is not None and model.error_field(mode) is not None
    measures = target_measures(report, robot, workers)
    checks, masks = target_checks(report, measures, criteria, has_grid, mode, compensated=model is not None)
    flags = flag_bits(masks) if masks else np.zeros(len(measures), np.uint8)
    index, table = table_rows(flags, measures)
    missing = []
    if not len(measures):
        missing.append("no compensable motion: the program has no Cartesian target a motion uses, "
                       "so there is nothing to tabulate or plot")
    if model is None:
        missing.append(f"{AS_WRITTEN}, so there are no corrections, predicted residuals or grid: those fields of "
                       "the summary and the targets are null")
    if model is not None and not has_grid:
        missing.append(f"no grid: mode {mode} of this model uses no residual grid, so there is no grid box "
                       "and no outside-grid check")
    long_times = timing is not None and len(timing.t) > ROWS  # its time stamps go to the sidecar
    section = None if timing is None else timing_section(timing, cycle_time_before, times=not long_times)
    if section is None:
        missing.append("no timing: the program was not re-timed, so there are no cycle time and no peak "
                       "joint velocity, acceleration or jerk")
    if model is not None:
        checks.insert(1, _model_accuracy(model, mode, has_grid, criteria.tolerance))
    lines = tuple(int(line) for line, *_ in report.not_compensated)
    if model is None:
        checks.append(not_evaluated("uncompensated", "every motion compensated", AS_WRITTEN))
    else:
        checks.append(Check("uncompensated", "every motion compensated", FAIL if lines else PASS,
                            f"{len(lines)} motion(s) left as written" if lines else "no motion left as written",
                            lines=lines[:ROWS], failing=len(lines)))
    checks.append(timing_check(section))
    checks.append(speeds_check(section))
    data = None
    if not table["complete"] or long_times:
        data = full_data(report, measures, flags, None if timing is None else timing.t)
    doc = header("compliance", command)
    doc.update({
        "provenance": {"files": list(files), "robot": {"name": robot.name, "source": robot.source},
                       "model": model_info, "mode": mode, "options": options or {}},
        "criteria": criteria.as_dict(),
        "verdict": verdict(checks),
        "summary": _summary(report, measures, compensated=model is not None),
        "target_table": table,
        "targets": _as_run(target_json(report, robot, measures, flags, index), model is not None),
        "not_compensated": [{"line": int(line), "text": text, "reason": reason}
                            for line, text, reason in report.not_compensated[:ROWS]],
        "unused": list(report.unused[:ROWS]),
        "joint_targets": {"mode": report.joint_mode, "labels": list(report.joint_targets[:ROWS]),
                          "count": len(report.joint_targets)},
        "warnings": list(report.warnings) + ([] if timing is None else list(timing.notices)),  # all stderr warns
        "timing": section,
        "missing": missing,
        "full_data": None if data is None else {
            "path": None, "format": "npz", "rows": len(measures),
            "arrays": {name: ARRAYS.get(name, TIMES) for name in data}},
    })
    figures = _figures(report, robot, measures, doc, model.error_field(mode) if has_grid else None,
                       compensated=model is not None)
    return Report(doc, figures, data)


def _figures(report, robot, measures, doc, field, compensated=True):
    """The compliance figures, drawn lazily; none without targets, no grid or correction without a model."""
    figures = []
    n = len(measures)
    if n:
        box = None if field is None else grid_box(field)
        box = None if box is None else (box["lower"], box["upper"])
        c, v = doc["criteria"], measures.values
        envelope = plots.envelope_note(n)
        figures += [
            Figure("targets", "Targets and the measured grid" if compensated else "Targets",
                   "Targets in motion order (base frame)"
                   + ("; crosses lie outside the grid, where only the model applies." if compensated else
                      " (no compensation model: no grid).") + plots.path_note(n),
                   lambda: plots.targets_and_grid(report.T_target[:, :3, 3], np.asarray(report.outside_grid, bool),
                                                  box)),
        ]
        if compensated:
            figures.append(Figure(
                "targets", "Corrections and predicted residuals",
                "Top: size of the correction per target. Bottom: distance from the target to where the model "
                "predicts the arm lands with the command (log scale), against the tolerance." + envelope,
                lambda: plots.corrections(v["correction_mm"], v["correction_deg"], v["predicted_residual_mm"],
                                          c["tolerance_mm"])))
        figures += [
            Figure("posture", "Joints within their ranges",
                   "Each written joint as a fraction of its range; shaded: the limit margin." + envelope,
                   lambda: plots.joint_ranges(np.degrees(np.reshape(report.q, (n, 6))), np.degrees(robot.q_min),
                                              np.degrees(robot.q_max), c["limit_margin_deg"])),
            Figure("posture", "Distance to singularities",
                   "Shoulder: wrist point from the axis-1 plane (mm); elbow: arm bend from stretched or folded; "
                   "wrist: angle between axes 4 and 6 (deg). Red: the margins." + envelope,
                   lambda: plots.singularities({"shoulder": v["shoulder_mm"], "elbow": v["elbow_deg"],
                                                "wrist": v["wrist_deg"]},
                                               {"shoulder": c["shoulder_margin_mm"], "elbow": c["singularity_margin_deg"],
                                                "wrist": c["singularity_margin_deg"]})),
        ]
    if doc["timing"] is not None:
        figures.append(Figure("timing", "Peaks against limits", "Peak joint velocity, acceleration and jerk of "
                              "the re-timed program as a percentage of the robot's limits.",
                              lambda: plots.timing_peaks(doc["timing"])))
    return tuple(figures)


def _summary(report, measures, compensated=True):
    """Counts, worst values and statistics over the targets (None where there is no target).

    The motions not compensated and the unused points are counted here and
    listed in the document up to `ROWS`. Without compensation (``retime``)
    what needs a model is None (counts, worst values) or left out
    (statistics of `MODEL_MEASURES`).
    """
    n = len(report.labels)
    counts = {"not_compensated": len(report.not_compensated), "unused": len(report.unused)}
    if not n:
        out = {"targets": 0, "outside_grid": 0, "configuration_changed": 0, "correction_max_mm": None,
               "correction_max_deg": None, "residual_max_mm": None, "limit_distance_min_deg": None, **counts}
    else:
        out = {
            **counts,
            "targets": n,
            "outside_grid": int(np.sum(report.outside_grid)),
            "configuration_changed": int(measures.changed.sum()),
            "correction_max_mm": float(measures.values["correction_mm"].max()),
            "correction_max_deg": float(measures.values["correction_deg"].max()),
            "residual_max_mm": float(measures.values["predicted_residual_mm"].max()),
            "limit_distance_min_deg": float(measures.values["limit_distance_deg"].min()),
        }
    out["statistics"] = statistics(measures, report.labels)
    if not compensated:
        out.update(dict.fromkeys(("outside_grid", "correction_max_mm", "correction_max_deg", "residual_max_mm")))
        out["statistics"] = {k: v for k, v in out["statistics"].items() if k not in MODEL_MEASURES}
    return out


def _as_run(rows, compensated):
    """The target rows, with the fields that need a model (`MODEL_FIELDS`) None when there was none (``retime``)."""
    if not compensated:
        for row in rows:
            row.update(dict.fromkeys(MODEL_FIELDS))
    return rows


def _model_accuracy(model, mode, has_grid, tolerance):
    """The model-accuracy check: held-out (cross-validation) errors; in-sample fit errors only for a mode without grid.

    A residual grid reproduces the nodes it was fitted to, so the fit errors
    of a grid mode are near zero whatever its accuracy between nodes: without
    cross-validation (``calibrate --folds 0``) the criterion is not evaluated.
    """
    cv = model.report.get("cross_validation") or {}
    if mode in cv:
        return accuracy_check(cv[mode], mode, tolerance, f"{cv['folds']}-fold cross-validation")
    if has_grid:
        return accuracy_check(None, mode, tolerance, "held-out", missing=(
            f"the model has no cross-validation of mode {mode} (calibrated with --folds 0): its fit errors are the "
            "residual grid reproducing its own nodes, not an accuracy; calibrate with --folds 5 to evaluate it"))
    return accuracy_check((model.report.get("fit") or {}).get(mode), mode, tolerance, "calibration fit (in-sample)")
