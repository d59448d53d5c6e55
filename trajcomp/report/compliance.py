"""The compliance report of a compensated (and re-timed) program, as a JSON-ready dict.

Built from the run's `trajcomp.compensation.program_rewrite.ProgramReport` (one row per
compensated target, motion order), the nominal robot, the model and, when
the program was re-timed, the `trajcomp.timing` result. Every criterion of
the verdict is stated with its threshold; each failing one counts and
lists the targets or lines it concerns. Measures, statistics and verdict
cover every target; a long program's table is summarised
(`trajcomp.report.per_target`). What the run could not provide (no
compensable motion, no grid in the mode, no re-timing) is listed under
``missing`` instead of being shown empty.
"""

import dataclasses

import numpy as np

from trajcomp.model import landing
from trajcomp.report import compliance_figures, plots
from trajcomp.report.measured import measured_check, measured_summary
from trajcomp.report.measures import BRANCH_NAMES
from trajcomp.report.document import Figure, Report
from trajcomp.report.provenance import grid_box, header
from trajcomp.report.per_target import ARRAYS, ROWS, TIMES, flag_bits, full_data, statistics, table_rows, target_json, \
    target_measures
from trajcomp.report.verdict import (FAIL, LISTED, NOT_EVALUATED, PASS, Check, Criteria, accuracy_check, check,
                                     not_evaluated, verdict)

TIMING_SLACK = 0.01  # relative: a peak up to 1 % over its limit passes (the timing's own dense check)


AS_WRITTEN = "no compensation model: the program runs as written (retime)"
MODEL_MEASURES = ("correction_mm", "correction_deg", "convergence_mm")  # per-target measures a model gives
MODEL_FIELDS = ("correction_mm", "correction_deg", "correction_norm_mm", "correction_norm_deg", "convergence_mm",
                "outside_grid")  # a target's JSON fields that need a model (the landing ones are None without)


def target_checks(report, measures, criteria, has_grid, mode, model=None):
    """The per-target criteria of the verdict and their failing masks.

    Without compensation (``model`` None) the landing, grid and coverage
    criteria are not evaluated; without targets, none is. A target passes
    the landing criterion (``residual``) only with an estimate within the
    tolerance (none, from a model without held-out errors: every target
    fails it); one beyond the measured orientations, on a tool the model
    cannot place or in an unmeasured posture also fails the criterion that
    says why (orientation and tool: unless its estimate is within the
    tolerance; posture: always, as the estimate cannot see gear and
    compliance errors of another branch).

    Returns
    -------
    checks : list of Check
    masks : dict of str to ndarray of bool, shape (N,)
        Failing targets of each evaluated criterion.
    """
    labels = report.labels
    c = criteria
    statements = {
        "residual": f"estimated landing error of every target within {c.tolerance:g} mm",
        "outside_grid": ("every target inside the measured grid (and the joint range of a joint residual), or its "
                         f"estimated landing error within {c.tolerance:g} mm" if has_grid else
                         f"every target inside the measured volume, or its estimated landing error within "
                         f"{c.tolerance:g} mm"),
        "orientation": (f"every target's orientation within the measured ones (+{landing.ORIENTATION_MARGIN:g} deg), "
                        f"or its estimated landing error within {c.tolerance:g} mm"),
        "tool": (f"every target on the measured TCP, or the model places other tools, or its estimated landing "
                 f"error within {c.tolerance:g} mm"),
        "posture": "every target in an arm posture (shoulder/elbow/wrist branch) the calibration measured",
        "configuration": "every target keeps its declared posture (arm branch and joint turns)",
        "joint_limits": f"every joint at least {c.limit_margin:g} deg from its limits",
        "singularity": (f"every target at least {c.singularity_margin:g} deg from elbow and wrist singularities "
                        f"and {c.shoulder_margin:g} mm from the shoulder singularity"),
    }
    if not len(labels):
        return [not_evaluated(key, text, "no compensated target") for key, text in statements.items()], {}
    v = measures.values
    masks = {"configuration": measures.changed,
             "joint_limits": v["limit_distance_deg"] < c.limit_margin,
             "singularity": ((v["shoulder_mm"] < c.shoulder_margin) | (v["elbow_deg"] < c.singularity_margin)
                             | (v["wrist_deg"] < c.singularity_margin))}
    details = {
        "configuration": f"{int(masks['configuration'].sum())} targets changed branch or turned a joint by half a turn",
        "joint_limits": f"smallest distance {v['limit_distance_deg'].min():.2f} deg",
        "singularity": (f"smallest: shoulder {v['shoulder_mm'].min():.1f} mm, elbow {v['elbow_deg'].min():.2f} deg, "
                        f"wrist {v['wrist_deg'].min():.2f} deg"),
    }
    skipped = {}
    if model is None:
        skipped = dict.fromkeys(("residual", "outside_grid", "orientation", "tool", "posture"), AS_WRITTEN)
    else:
        found = _landing_checks(report, v, c.tolerance, model, has_grid)
        for key, (mask, detail) in found.items():
            if mask is None:
                skipped[key] = detail
            else:
                masks[key], details[key] = mask, detail
    masks = {key: mask for key, mask in masks.items() if key not in skipped}
    checks = [not_evaluated(key, text, skipped[key]) if key in skipped
              else check(key, text, masks[key], labels, details[key]) for key, text in statements.items()]
    return checks, masks


def _landing_checks(report, v, tolerance, model, has_grid):
    """``{criterion: (failing mask or None, detail)}`` of the landing and coverage criteria (None: not evaluated).

    A target outside the measured grid (a mode without one: outside the box
    of the measured positions) fails unless its estimate, which grows with
    the distance beyond what was measured (`trajcomp.model.landing`), is
    within the tolerance.
    """
    data = report.landing
    unknown = np.ones(len(report.labels), bool)  # a target passes only with an estimate within the tolerance
    outside = np.asarray(report.outside_grid, dtype=bool)
    where = "grid" if has_grid else "measured volume"
    if data is None:
        return {"residual": (unknown, "no landing estimate: the run was compensated without the model's statistics"),
                "outside_grid": (outside, f"{int(outside.sum())} of {len(outside)} targets outside the {where}"),
                **dict.fromkeys(("orientation", "tool", "posture"),
                                (None, "the run has no landing estimate (compensated without the model's statistics)"))}
    estimate, convergence = v["landing_estimate_mm"], v["convergence_mm"]
    within = estimate <= tolerance  # False where there is no estimate
    out = {"outside_grid": (outside & ~within, f"{int(outside.sum())} of {len(outside)} targets outside the {where}, "
                                               f"{int((outside & ~within).sum())} of them with an estimate above the "
                                               "tolerance")}
    if np.isnan(v["held_out_mm"]).all():
        out["residual"] = (unknown, "no landing estimate: the model has no held-out errors (calibrated with --folds 0 "
                                    "or by an older trajcomp), so no target is known to land within the tolerance; "
                                    "calibrate with --folds 5")
    else:
        worst = int(np.nanargmax(estimate)) if np.isfinite(estimate).any() else 0
        out["residual"] = (~within, f"largest {estimate[worst]:.4f} mm at {report.labels[worst]} (held-out "
                                    f"{v['held_out_mm'][worst]:.4f} + unseen {v['unseen_mm'][worst]:.4f} mm); "
                                    f"{int((~within).sum())} targets above; convergence at most {convergence.max():.1e} mm")
    beyond = v["orientation_beyond_deg"] > 0
    out["orientation"] = (beyond & ~within, "every target within the measured orientations" if not beyond.any() else (
        f"{int(beyond.sum())} targets beyond the measured orientations (up to {v['orientation_beyond_deg'].max():.1f} "
        f"deg beyond), {int((beyond & ~within).sum())} of them with an estimate above the tolerance"))
    other = np.asarray(data["other_tool"], dtype=bool)
    if not other.any():
        out["tool"] = (other, "every target on the measured TCP")
    elif model.places_other_tools:
        out["tool"] = (np.zeros(len(other), bool), f"{int(other.sum())} targets on another tool; the model places "
                                                   f"other tools ({model.other_tools_reason})")
    else:
        out["tool"] = (other & ~within, f"{int(other.sum())} targets on a tool other than the measured TCP, "
                                        f"{int((other & ~within).sum())} of them with an estimate above the tolerance; "
                                        f"the model cannot place other tools: {model.other_tools_reason}")
    posture = np.asarray(data["unmeasured_posture"], dtype=bool)
    measured = ", ".join(BRANCH_NAMES[b] for b in model.postures) or "not recorded"
    out["posture"] = (posture, f"{int(posture.sum())} targets in a posture not measured (measured: {measured})")
    return out


def _track_entry(timing):
    """A moving track's part of the timing (`trajcomp.timing.track.TrackTiming`) as plain data, or None."""
    track = getattr(timing, "track", None)
    if track is None:
        return None
    return {"field": track.field,
            "velocity": {"peak": track.peak_velocity, "limit": track.limit_velocity, "unit": "mm/s"},
            "acceleration": {"peak": track.peak_acceleration, "limit": track.limit_acceleration, "unit": "mm/s^2"},
            "not_timed": [{"waypoint": str(timing.labels[k]), "why": why} for k, why in track.left[:ROWS]]}


def timing_section(timing, before=None, times=True):
    """The timing dict of a `trajcomp.timing.result.TimingResult`, with the cycle time ``before`` (s) if known.

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
    lowered = getattr(timing, "lowered", ())
    run_time, starts = getattr(timing, "run_time_speeds", ()), getattr(timing, "unknown_starts", ())
    kept = getattr(timing, "not_modelled", ())
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
        "not_retimed": {"count": len(run_time),
                        "reason": "speed set at run time: the motion is timed at the arm's limits, its field is left "
                                  "as written",
                        "motions": [{"waypoint": str(timing.labels[k]), "why": why} for k, why in run_time[:ROWS]]},
        "unknown_start": {"count": len(starts),
                          "reason": "start not unique (a call, a loop, a branch or a jump can lead to it) or not "
                                    "known: the motion is not timed, its field is left as written (it runs no faster "
                                    "than programmed); its timing and limits are not checked",
                          "motions": [{"waypoint": str(timing.labels[k]), "why": why} for k, why in starts[:ROWS]]},
        "not_modelled": {"count": len(kept),
                         "reason": "no time written where the controller would not run it as timed (a RAPID AccSet "
                                   "ramp below 100 %: it keeps a time by cruising faster behind softer ramps): the "
                                   "field is left as written, so the motion runs no faster than programmed; timed as "
                                   "at full ramps",
                         "motions": [{"waypoint": str(timing.labels[k]), "why": why} for k, why in kept[:ROWS]]},
        "lowered": {"count": len(lowered),
                    "motions": [{"waypoint": str(timing.labels[k]), "detail": text} for k, text in lowered[:ROWS]]},
        "track": _track_entry(timing),
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
    return _listed_check(section, "speeds", "every timed motion's speed known to the re-timing (none set at run time)",
                         "not_retimed", FAIL, "every speed stated or provably constant",
                         "not re-timed, speed set at run time (left as written)")


def modelled_check(section):
    """The criterion that every time the timing would write runs as timed, or what was left as written instead.

    A time the controller would not run as timed (a RAPID AccSet ramp
    below 100 %) is not written: the motion keeps its field, so it runs no
    faster than programmed, as a motion whose start is not unique does. Not
    a failure: the criterion is not evaluated for them and lists them; it
    passes where there are none.
    """
    return _listed_check(section, "modelled", "every time the re-timing would write run by the controller as timed",
                         "not_modelled", NOT_EVALUATED, "no field left as written for a ramp the timing does not "
                         "model", "without a time written, the controller would not run it as timed (left as "
                         "written: no faster than programmed)")


def starts_check(section):
    """The criterion that every motion was timed from its one start, or what is unknown.

    A motion whose start is not unique (the first of a loop, after a call
    or a branch) or not known (after a call of a routine the read does not
    include) is not timed: its field is left as written, so it runs no
    faster than programmed, but its time and limits were not checked. Not
    a failure (the program is as safe as written): the criterion is not
    evaluated for them and lists them; it passes where there are none.
    """
    return _listed_check(section, "starts",
                         "every motion timed from the one position it starts at on every path the program can take",
                         "unknown_start", NOT_EVALUATED,
                         "every timed motion's start is the motion before it on every path",
                         "not timed, start not unique or not known (left as written: no faster than programmed; "
                         "their timing and limits not checked)")


def _listed_check(section, id, statement, key, status, clean, found):
    """A criterion over the motions the timing section lists under ``key``: passed where there are none (``clean``
    says so), else ``status`` with how many were ``found`` and the first one's reason."""
    if section is None:
        return not_evaluated(id, statement, "the program was not re-timed")
    listed = section[key]
    if not listed["count"]:
        return Check(id, statement, PASS, clean)
    return Check(id, statement, status, f"{listed['count']} motion(s) {found}: {listed['motions'][0]['why']}",
                 targets=tuple(m["waypoint"] for m in listed["motions"][:LISTED]),
                 failing=listed["count"] if status == FAIL else 0)


def compliance_report(report, robot, *, criteria=None, model=None, model_info=None, mode=None, files=(),
                      options=None, timing=None, cycle_time_before=None, command="compensate", workers=1,
                      measured=None):
    """The compliance report of one run (schema ``trajcomp-report/1``, kind ``compliance``).

    Parameters
    ----------
    report : ProgramReport
        What the compensation did (`trajcomp.compensation.program_rewrite.ProgramReport`).
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
        The re-timing of the corrected program (`trajcomp.timing.result.TimingResult`).
    cycle_time_before : float, optional
        Cycle time of the program before, s.
    command : str
        The command that ran (``compensate``, ``retime``).
    workers : int
        Processes that share the per-target measures (`target_measures`).
    measured : ndarray, shape (N,), optional
        The measured landing of each target of a validation run, mm, NaN where
        not measured (`trajcomp.report.measured.measured_landing`): tabulated
        beside the estimate, summarised, and judged (criterion ``measured``).

    Returns
    -------
    Report
    """
    criteria = criteria or Criteria()
    mode = mode or (model.method if model is not None else None)
    has_grid = model is not None and model.error_field(mode) is not None
    report = _outside_measured(report, model, has_grid)
    measures = target_measures(report, robot, workers)
    checks, masks = target_checks(report, measures, criteria, has_grid, mode, model)
    flags = flag_bits(masks) if masks else np.zeros(len(measures), np.uint8)
    index, table = table_rows(flags, measures)
    missing = []
    if not len(measures):
        missing.append("no compensable motion: the program has no Cartesian target a motion uses, "
                       "so there is nothing to tabulate or plot")
    if model is None:
        missing.append(f"{AS_WRITTEN}, so there are no corrections, landing estimates or grid: those fields of "
                       "the summary and the targets are null")
    if model is not None and not has_grid:
        missing.append(f"no grid: mode {mode} of this model uses no residual grid, so there is no grid box; the "
                       "outside check is against the box of the measured positions")
    long_times = timing is not None and len(timing.t) > ROWS  # its time stamps go to the sidecar
    section = None if timing is None else timing_section(timing, cycle_time_before, times=not long_times)
    if section is None:
        missing.append("no timing: the program was not re-timed, so there are no cycle time and no peak "
                       "joint velocity, acceleration or jerk")
    if model is not None:
        checks.insert(1, _model_accuracy(model, mode, has_grid, criteria.tolerance, measures))
    seen = measured is not None and np.isfinite(measured).any()
    if seen:
        checks.insert(2, measured_check(measured, report.labels, criteria.tolerance))
    lines = tuple(_line_and_file(place)[0] for place, *_ in report.not_compensated)
    if model is None:
        checks.append(not_evaluated("uncompensated", "every motion compensated", AS_WRITTEN))
    else:
        checks.append(Check("uncompensated", "every motion compensated", FAIL if lines else PASS,
                            f"{len(lines)} motion(s) left as written" if lines else "no motion left as written",
                            lines=lines[:ROWS], failing=len(lines)))
    checks.append(timing_check(section))
    checks.append(speeds_check(section))
    checks.append(modelled_check(section))
    checks.append(starts_check(section))
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
        "targets": _with_measured(_as_run(target_json(report, robot, measures, flags, index), model is not None),
                                  measured, index),
        "measured": measured_summary(measured, measures.values["landing_estimate_mm"], criteria.tolerance)
        if seen and "landing_estimate_mm" in measures.values else None,
        "not_compensated": [_not_compensated_entry(place, text, reason)
                            for place, text, reason in report.not_compensated[:ROWS]],
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
    figures = _figures(report, robot, measures, doc, model.error_field(mode) if has_grid else None, timing,
                       compensated=model is not None)
    return Report(doc, figures, data)


TIMELINE = 4000  # instants at which the joint motion figure samples the timed program


def _outside_measured(report, model, has_grid):
    """The report with its targets outside the box of the measured positions counted outside the grid too, for a
    mode without a grid (the box stands for it): the criterion, the summary, the targets' rows and the figure
    count the same targets."""
    data = None if has_grid or model is None else landing.of_model(model)
    if data is None or not len(report.labels):
        return report
    beyond = landing.outside_box(np.asarray(report.T_target)[:, :3, 3], data.positions)[1] > 0
    return dataclasses.replace(report, outside_grid=np.asarray(report.outside_grid, dtype=bool) | beyond)


def _figures(report, robot, measures, doc, field, timing=None, compensated=True):
    """The compliance figures, drawn lazily; none without targets, no grid or correction without a model."""
    figures = []
    n = len(measures)
    if n:
        box = None if field is None else grid_box(field)
        box = None if box is None else (box["lower"], box["upper"])
        c, v = doc["criteria"], measures.values
        envelope = plots.envelope_note(n)
        data = report.landing or {}
        posture = data.get("unmeasured_posture")
        orientation = None if "orientation_beyond_deg" not in v else v["orientation_beyond_deg"] > 0
        figures += [
            Figure("targets", "Targets and the measured grid" if compensated else "Targets",
                   "Targets in motion order (base frame)"
                   + ("; crosses lie outside the grid, where only the model applies; triangles are in an arm posture "
                      "the calibration did not measure and diamonds beyond the measured orientations (inside the "
                      "grid box, but not where the model was measured)." if compensated else
                      " (no compensation model: no grid).") + plots.path_note(n),
                   lambda: compliance_figures.targets_and_grid(report.T_target[:, :3, 3], np.asarray(report.outside_grid, bool),
                                                  box, posture, orientation)),
        ]
        if compensated:
            figures.append(Figure(
                "targets", "Corrections and landing estimates",
                "Top: size of the correction per target. Bottom (log scale): the landing estimate the verdict "
                "judges (held-out errors of the model near the target, widened where its orientation, tool or "
                "posture lies outside what was measured) and the convergence of the compensation (distance from "
                "the target to where the model itself predicts the arm lands: the model agreeing with itself, "
                "not an accuracy), against the tolerance." + envelope,
                lambda: compliance_figures.corrections(v["correction_mm"], v["correction_deg"], v.get("landing_estimate_mm"),
                                          v["convergence_mm"], c["tolerance_mm"])))
        figures += [
            Figure("posture", "Joints within their ranges",
                   "Each written joint as a fraction of its range; shaded: the limit margin." + envelope,
                   lambda: compliance_figures.joint_ranges(np.degrees(np.reshape(report.q, (n, 6))), np.degrees(robot.q_min),
                                              np.degrees(robot.q_max), c["limit_margin_deg"])),
            Figure("posture", "Distance to singularities",
                   "Shoulder: wrist point from the axis-1 plane (mm); elbow: arm bend from stretched or folded; "
                   "wrist: angle between axes 4 and 6 (deg). Red: the margins." + envelope,
                   lambda: compliance_figures.singularities({"shoulder": v["shoulder_mm"], "elbow": v["elbow_deg"],
                                                "wrist": v["wrist_deg"]},
                                               {"shoulder": c["shoulder_margin_mm"], "elbow": c["singularity_margin_deg"],
                                                "wrist": c["singularity_margin_deg"]})),
        ]
    if doc["timing"] is not None:
        figures.append(Figure("timing", "Peaks against limits", "Peak joint velocity, acceleration and jerk of "
                              "the re-timed program as a percentage of the robot's limits (from the 1 kHz check).",
                              lambda: compliance_figures.timing_peaks(doc["timing"])))
    if timing is not None and timing.cycle_time > 0:
        figures.append(Figure(
            "timing", "Joint motion over time against the limits",
            f"The re-timed program sampled at {TIMELINE} instants: each joint's position in its range (shaded: "
            f"the limit margin of {doc['criteria']['limit_margin_deg']:g} deg), |velocity| and |acceleration| as a "
            "percentage of the joint's limit (red: 100 %). Peaks between the instants are in the table above (1 kHz).",
            lambda: _joint_motion(timing, robot, doc["criteria"]["limit_margin_deg"])))
    return tuple(figures)


def _joint_motion(timing, robot, margin):
    """The joint motion figure of a timing (`compliance_figures.joint_motion`), sampled at `TIMELINE` instants."""
    t = np.linspace(0.0, timing.cycle_time, TIMELINE)
    q, qd, qdd = (np.degrees(a) for a in timing.at(t))
    limits = (np.degrees(a) for a in (robot.q_min, robot.q_max, timing.limit_velocity, timing.limit_acceleration))
    return compliance_figures.joint_motion(t, q, qd, qdd, *limits, margin)


def _summary(report, measures, compensated=True):
    """Counts, worst values and statistics over the targets (None where there is no target or no estimate).

    The motions not compensated and the unused points are counted here and
    listed in the document up to `ROWS`. Without compensation (``retime``)
    what needs a model is None (counts, worst values) or left out
    (statistics of `MODEL_MEASURES`).
    """
    n = len(report.labels)
    counts = {"not_compensated": len(report.not_compensated), "unused": len(report.unused)}
    keys = ("correction_max_mm", "correction_max_deg", "estimate_max_mm", "convergence_max_mm",
            "limit_distance_min_deg")
    if not n:
        out = {"targets": 0, "outside_grid": 0, "orientation_beyond": 0, "other_tool": 0, "unmeasured_posture": 0,
               "configuration_changed": 0, **dict.fromkeys(keys), **counts}
    else:
        v, data = measures.values, report.landing
        estimate = v.get("landing_estimate_mm")
        out = {
            **counts,
            "targets": n,
            "outside_grid": int(np.sum(report.outside_grid)),
            "orientation_beyond": 0 if data is None else int(np.sum(v["orientation_beyond_deg"] > 0)),
            "other_tool": 0 if data is None else int(np.sum(data["other_tool"])),
            "unmeasured_posture": 0 if data is None else int(np.sum(data["unmeasured_posture"])),
            "configuration_changed": int(measures.changed.sum()),
            "correction_max_mm": float(v["correction_mm"].max()),
            "correction_max_deg": float(v["correction_deg"].max()),
            "estimate_max_mm": None if estimate is None or np.isnan(estimate).all() else float(np.nanmax(estimate)),
            "convergence_max_mm": float(v["convergence_mm"].max()),
            "limit_distance_min_deg": float(v["limit_distance_deg"].min()),
        }
    out["statistics"] = statistics(measures, report.labels)
    if not compensated:
        out.update(dict.fromkeys(("outside_grid", "orientation_beyond", "other_tool", "unmeasured_posture",
                                  "correction_max_mm", "correction_max_deg", "convergence_max_mm")))
        out["statistics"] = {k: v for k, v in out["statistics"].items() if k not in MODEL_MEASURES}
    return out


def _as_run(rows, compensated):
    """The target rows, with the fields that need a model (`MODEL_FIELDS`) None when there was none (``retime``)."""
    if not compensated:
        for row in rows:
            row.update(dict.fromkeys(MODEL_FIELDS))
    return rows


def _with_measured(rows, measured, index):
    """The target rows with their measured landing (mm, None where not measured), when there is a validation run."""
    if measured is not None:
        for row, value in zip(rows, measured[index].tolist()):
            row["measured_landing_mm"] = None if np.isnan(value) else round(value, 5)
    return rows


def _model_accuracy(model, mode, has_grid, tolerance, measures):
    """The model-accuracy check: the held-out errors of the mode near the targets, same interpolator.

    95 % of the targets' held-out errors nearby (`trajcomp.model.landing`) within
    the tolerance. A model without them (``--folds 0``, or written by an
    older trajcomp) falls back to its cross-validation statistics; a grid's
    fit errors reproduce its own nodes, so a grid mode without
    cross-validation is not evaluated.
    """
    data = landing.of_model(model)
    held = measures.values.get("held_out_mm")
    if data is not None and held is not None and np.isfinite(held).any():
        statement = (f"95 % of the targets' held-out errors nearby (mode {mode}, held out with its own "
                     f"interpolator) within {tolerance:g} mm")
        p95 = float(np.nanpercentile(held, 95))
        overall = data.held_out.get(mode) or {}
        return Check("model_accuracy", statement, PASS if p95 <= tolerance else FAIL,
                     f"p95 over the targets {p95:.4f} mm (largest {np.nanmax(held):.4f}); over all "
                     f"{overall.get('n', 0)} held-out points p95 {overall.get('p95', float('nan')):.4f}, max "
                     f"{overall.get('max', float('nan')):.4f} mm; held out: {data.method}")
    cv = model.report.get("cross_validation") or {}
    if mode in cv:
        return accuracy_check(cv[mode], mode, tolerance, f"{cv['folds']}-fold cross-validation")
    if has_grid:
        return accuracy_check(None, mode, tolerance, "held-out", missing=(
            f"the model has no cross-validation of mode {mode} (calibrated with --folds 0): its fit errors are the "
            "residual grid reproducing its own nodes, not an accuracy; calibrate with --folds 5 to evaluate it"))
    return accuracy_check((model.report.get("fit") or {}).get(mode), mode, tolerance, "calibration fit (in-sample)")


def _line_and_file(place):
    """``(line, file)`` of a place `Program.place` gives: ``12`` -> ``(12, None)``, ``"b.src:12"`` -> ``(12, "b.src")``."""
    if isinstance(place, str):
        file, _, line = place.rpartition(":")
        return int(line), file
    return int(place), None


def _not_compensated_entry(place, text, reason):
    """One motion of the report's ``not_compensated`` list; ``file`` names its file in a program of several files."""
    line, file = _line_and_file(place)
    return {"line": line, **({"file": file} if file else {}), "text": text, "reason": reason}
