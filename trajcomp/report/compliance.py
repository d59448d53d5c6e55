"""The compliance report of a compensated (and re-timed) program, as a JSON-ready dict.

Built from the run's `trajcomp.postprocess.ProgramReport` (one row per
compensated target, motion order), the nominal robot, the model and, when
the program was re-timed, the `trajcomp.timing` result. Every criterion of
the verdict is stated with its threshold; each failing one lists the
targets or lines it concerns. What the run could not provide (no
compensable motion, no grid in the mode, no re-timing) is listed under
``missing`` instead of being shown empty.
"""

import numpy as np

from trajcomp.report import plots
from trajcomp.report.document import Figure, Report
from trajcomp.report.measures import branch_changes, joint_jumps, limit_distances, singularity_distances
from trajcomp.report.provenance import grid_box, header
from trajcomp.report.verdict import FAIL, PASS, Check, Criteria, accuracy_check, check, not_evaluated, verdict
from trajcomp.transforms import matrix_to_pose

TIMING_SLACK = 0.01  # relative: a peak up to 1 % over its limit passes (the timing's own dense check)


def _poses(T):
    """Pose rows x, y, z (mm), a, b, c (deg) of matrices (N, 4, 4)."""
    if not len(T):
        return np.zeros((0, 6))
    pose = matrix_to_pose(T)
    pose[:, 3:] = np.degrees(pose[:, 3:])
    return pose


def _round(array, digits):
    return np.round(np.asarray(array, dtype=float), digits).tolist()


def target_rows(report, robot):
    """Per-target measures (dict of arrays, N rows) and the JSON rows of the targets table.

    Parameters
    ----------
    report : ProgramReport
    robot : Robot
        The nominal robot (limits, branches, singularities).
    """
    n = len(report.labels)
    q, q_planned = report.q.reshape(n, 6), report.q_planned.reshape(n, 6)
    changed, branch_planned, branch = branch_changes(robot, q_planned, q)
    measures = {
        "limit": np.degrees(limit_distances(robot, q)).reshape(n, 6),
        "singular": singularity_distances(robot, q),
        "jump": np.degrees(joint_jumps(q)).reshape(n, 6),
        "changed": changed,
        "correction_mm": np.linalg.norm(report.correction[:, :3], axis=1),
        "correction_deg": np.linalg.norm(report.correction[:, 3:], axis=1),
    }
    singular = measures["singular"]
    columns = {  # every column rounded and made plain once: N rows of Python values
        "target": _round(_poses(report.T_target), 4),
        "command": _round(_poses(report.T_command), 4),
        "correction_mm": _round(report.correction[:, :3], 4),
        "correction_deg": _round(report.correction[:, 3:], 5),
        "correction_norm_mm": _round(measures["correction_mm"], 4),
        "correction_norm_deg": _round(measures["correction_deg"], 5),
        "predicted_residual_mm": np.asarray(report.predicted_residual, dtype=float).tolist(),
        "outside_grid": np.asarray(report.outside_grid, dtype=bool).tolist(),
        "joints_deg": _round(np.degrees(q), 4),
        "planned_joints_deg": _round(np.degrees(q_planned), 4),
        "configuration_changed": np.asarray(changed, dtype=bool).tolist(),
        "limit_distance_deg": _round(measures["limit"], 3),
        "shoulder_mm": _round(singular["shoulder"], 2),
        "elbow_deg": _round(singular["elbow"], 3),
        "wrist_deg": _round(singular["wrist"], 3),
        "jump_deg": _round(measures["jump"], 3),
    }
    rows = []
    for k in range(n):
        row = {name: values[k] for name, values in columns.items()}
        rows.append({
            "label": report.labels[k],
            "line": int(report.lines[k]),
            "tool": report.tools[k],
            "frame": report.frames[k],
            "target": row["target"],
            "command": row["command"],
            "correction_mm": row["correction_mm"],
            "correction_deg": row["correction_deg"],
            "correction_norm_mm": row["correction_norm_mm"],
            "correction_norm_deg": row["correction_norm_deg"],
            "predicted_residual_mm": row["predicted_residual_mm"],
            "outside_grid": row["outside_grid"],
            "joints_deg": row["joints_deg"],
            "planned_joints_deg": row["planned_joints_deg"],
            "posture_source": report.posture_source[k],
            "declared": report.declared[k],
            "written": report.written[k],
            "branch_planned": branch_planned[k],
            "branch": branch[k],
            "configuration_changed": row["configuration_changed"],
            "limit_distance_deg": row["limit_distance_deg"],
            "singularity": {"shoulder_mm": row["shoulder_mm"], "elbow_deg": row["elbow_deg"],
                            "wrist_deg": row["wrist_deg"]},
            "jump_deg": row["jump_deg"],
        })
    return measures, rows


AS_WRITTEN = "no compensation model: the program runs as written (retime)"


def target_checks(report, measures, criteria, has_grid, mode, compensated=True):
    """The per-target criteria of the verdict (list of Check); without compensation, its criteria are not evaluated."""
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
        return [not_evaluated(key, text, "no compensated target") for key, text in statements.items()]
    residual = report.predicted_residual
    checks = [check("residual", statements["residual"], residual > c.tolerance, labels,
                    f"largest {residual.max():.2e} mm")]
    if not compensated:
        checks = [not_evaluated("residual", statements["residual"], AS_WRITTEN),
                  not_evaluated("outside_grid", statements["outside_grid"], AS_WRITTEN)]
    elif has_grid:
        outside = report.outside_grid
        checks.append(check("outside_grid", statements["outside_grid"], outside, labels,
                            f"{int(outside.sum())} of {len(labels)} targets outside"))
    else:
        checks.append(not_evaluated("outside_grid", statements["outside_grid"],
                                    f"mode {mode} uses no grid: every target gets the same kind of correction"))
    changed = measures["changed"]
    checks.append(check("configuration", statements["configuration"], changed, labels,
                        f"{int(changed.sum())} targets changed branch or turned a joint by half a turn"))
    limit = measures["limit"].min(axis=1)
    checks.append(check("joint_limits", statements["joint_limits"], limit < c.limit_margin, labels,
                        f"smallest distance {limit.min():.2f} deg"))
    singular = measures["singular"]
    near = ((singular["shoulder"] < c.shoulder_margin) | (singular["elbow"] < c.singularity_margin)
            | (singular["wrist"] < c.singularity_margin))
    checks.append(check("singularity", statements["singularity"], near, labels,
                        f"smallest: shoulder {singular['shoulder'].min():.1f} mm, elbow {singular['elbow'].min():.2f} deg, "
                        f"wrist {singular['wrist'].min():.2f} deg"))
    return checks


def timing_section(timing, before=None):
    """The timing dict of a `trajcomp.timing` result (contract 3), with the cycle time ``before`` (s) if known."""
    limits = {"velocity": ("peak_velocity", "limit_velocity", "deg/s"),
              "acceleration": ("peak_acceleration", "limit_acceleration", "deg/s^2"),
              "jerk": ("peak_jerk", "limit_jerk", "deg/s^3")}
    joints = []
    for j in range(6):
        row = {"joint": j + 1}
        for name, (peak, limit, unit) in limits.items():
            p, lim = float(np.degrees(getattr(timing, peak)[j])), float(np.degrees(getattr(timing, limit)[j]))
            row[name] = {"peak": p, "limit": lim if np.isfinite(lim) else None, "unit": unit,
                         "ratio": p / lim if np.isfinite(lim) and lim > 0 else None}
        joints.append(row)
    segments = [{"kind": s.kind, "first": int(s.first), "last": int(s.last), "duration_s": float(s.duration),
                 "speed": getattr(s, "speed", None)} for s in timing.segments]
    return {
        "cycle_time_s": float(timing.cycle_time),
        "cycle_time_before_s": None if before is None else float(before),
        "within_limits": bool(timing.within_limits),
        "joints": joints,
        "segments": segments,
        "t_s": _round(timing.t, 4),
    }


def timing_check(section):
    """The timing criterion (a Check) of a timing section, or not evaluated without one."""
    statement = f"joint velocity, acceleration and jerk within the robot's limits (+{TIMING_SLACK:.0%})"
    if section is None:
        return not_evaluated("timing", statement, "the program was not re-timed")
    over = [f"J{row['joint']} {name} {q['peak']:.1f} > {q['limit']:.1f} {q['unit']}"
            for row in section["joints"] for name, q in row.items()
            if name != "joint" and q["ratio"] is not None and q["ratio"] > 1 + TIMING_SLACK]
    failed = over or not section["within_limits"]
    detail = "; ".join(over) or ("the dense check of the timed path exceeds a limit" if failed else
                                 f"cycle time {section['cycle_time_s']:.3f} s")
    return Check("timing", statement, FAIL if failed else PASS, detail)


def compliance_report(report, robot, *, criteria=None, model=None, model_info=None, mode=None, files=(),
                      options=None, timing=None, cycle_time_before=None, command="compensate"):
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

    Returns
    -------
    Report
    """
    criteria = criteria or Criteria()
    mode = mode or (model.method if model is not None else None)
    has_grid = model is not None and model.error_field(mode) is not None
    measures, rows = target_rows(report, robot)
    missing = []
    if not rows:
        missing.append("no compensable motion: the program has no Cartesian target a motion uses, "
                       "so there is nothing to tabulate or plot")
    if model is not None and not has_grid:
        missing.append(f"no grid: mode {mode} of this model uses no residual grid, so there is no grid box "
                       "and no outside-grid check")
    section = None if timing is None else timing_section(timing, cycle_time_before)
    if section is None:
        missing.append("no timing: the program was not re-timed, so there are no cycle time and no peak "
                       "joint velocity, acceleration or jerk")
    checks = target_checks(report, measures, criteria, has_grid, mode, compensated=model is not None)
    if model is not None:
        cv = model.report.get("cross_validation") or {}
        source = f"{cv['folds']}-fold cross-validation" if mode in cv else "calibration fit"
        stats = cv.get(mode) or (model.report.get("fit") or {}).get(mode)
        checks.insert(1, accuracy_check(stats, mode, criteria.tolerance, source))
    lines = tuple(int(line) for line, *_ in report.not_compensated)
    if model is None:
        checks.append(not_evaluated("uncompensated", "every motion compensated", AS_WRITTEN))
    else:
        checks.append(Check("uncompensated", "every motion compensated", FAIL if lines else PASS,
                            f"{len(lines)} motion(s) left as written" if lines else "no motion left as written",
                            lines=lines))
    checks.append(timing_check(section))
    doc = header("compliance", command)
    doc.update({
        "provenance": {"files": list(files), "robot": {"name": robot.name, "source": robot.source},
                       "model": model_info, "mode": mode, "options": options or {}},
        "criteria": criteria.as_dict(),
        "verdict": verdict(checks),
        "summary": _summary(report, measures),
        "targets": rows,
        "not_compensated": [{"line": int(line), "text": text, "reason": reason}
                            for line, text, reason in report.not_compensated],
        "unused": list(report.unused),
        "joint_targets": {"mode": report.joint_mode, "labels": list(report.joint_targets)},
        "warnings": list(report.warnings),
        "timing": section,
        "missing": missing,
    })
    return Report(doc, _figures(report, robot, measures, doc, model.error_field(mode) if has_grid else None))


def _figures(report, robot, measures, doc, field):
    """The compliance figures, drawn lazily; none without targets."""
    figures = []
    if doc["targets"]:
        target = np.array([row["target"] for row in doc["targets"]])
        box = None if field is None else grid_box(field)
        box = None if box is None else (box["lower"], box["upper"])
        c = doc["criteria"]
        figures += [
            Figure("targets", "Targets and the measured grid",
                   "Targets in motion order (base frame); crosses lie outside the grid, where only the model applies.",
                   lambda: plots.targets_and_grid(target[:, :3], report.outside_grid, box)),
            Figure("targets", "Corrections and predicted residuals",
                   "Top: size of the correction per target. Bottom: distance from the target to where the model "
                   "predicts the arm lands with the command (log scale), against the tolerance.",
                   lambda: plots.corrections(measures["correction_mm"], measures["correction_deg"],
                                             report.predicted_residual, c["tolerance_mm"])),
            Figure("posture", "Joints within their ranges",
                   "Each written joint as a fraction of its range; shaded: the limit margin.",
                   lambda: plots.joint_ranges(np.degrees(report.q), np.degrees(robot.q_min), np.degrees(robot.q_max),
                                              c["limit_margin_deg"])),
            Figure("posture", "Distance to singularities",
                   "Shoulder: wrist point from the axis-1 plane (mm); elbow: arm bend from stretched or folded; "
                   "wrist: angle between axes 4 and 6 (deg). Red: the margins.",
                   lambda: plots.singularities(measures["singular"], {"shoulder": c["shoulder_margin_mm"],
                                                                      "elbow": c["singularity_margin_deg"],
                                                                      "wrist": c["singularity_margin_deg"]})),
        ]
    if doc["timing"] is not None:
        figures.append(Figure("timing", "Peaks against limits", "Peak joint velocity, acceleration and jerk of "
                              "the re-timed program as a percentage of the robot's limits.",
                              lambda: plots.timing_peaks(doc["timing"])))
    return tuple(figures)


def _summary(report, measures):
    """Counts and worst values over the targets (None where there is no target)."""
    n = len(report.labels)
    if not n:
        return {"targets": 0, "outside_grid": 0, "configuration_changed": 0, "correction_max_mm": None,
                "correction_max_deg": None, "residual_max_mm": None, "limit_distance_min_deg": None}
    return {
        "targets": n,
        "outside_grid": int(np.sum(report.outside_grid)),
        "configuration_changed": int(measures["changed"].sum()),
        "correction_max_mm": float(measures["correction_mm"].max()),
        "correction_max_deg": float(measures["correction_deg"].max()),
        "residual_max_mm": float(report.predicted_residual.max()),
        "limit_distance_min_deg": float(measures["limit"].min()),
    }
