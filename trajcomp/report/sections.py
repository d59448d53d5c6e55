"""The sections of each kind of report page, as HTML fragments (figures are appended by `html.render`)."""

from pathlib import Path

from trajcomp.report.markup import Raw, esc, key_values, table
from trajcomp.report.summary import judges_landing

SHOWN = 30  # targets named per criterion before "and N more"


def concerns(criterion):
    """What a failed criterion concerns, as text."""
    named = [*criterion["targets"], *(f"line {line}" for line in criterion["lines"])]
    total = max(criterion["failing"], len(named))
    more = f" … and {total - SHOWN} more" if total > SHOWN else ""
    return ", ".join(named[:SHOWN]) + more


def headline(doc):
    """One line saying what the report is about."""
    files = doc["provenance"]["files"]
    inputs = [Path(f["path"]).name for f in files if f["role"] in ("program", "measurements")]
    what = {"compliance": "Program", "calibration": "Calibration from", "validation": "Validation on"}[doc["kind"]]
    return f"{what} {', '.join(inputs) or '(in memory)'} · robot {doc['provenance']['robot']['name']}"


def verdict_section(verdict):
    badge = {"pass": "pass", "fail": "fail", "not evaluated": "na"}
    named = [concerns(c) if c["status"] == "fail" else "" for c in verdict["criteria"]]
    rows = [(Raw(f'<span class="badge {badge[c["status"]]}">{esc(c["status"])}</span>'), c["statement"], c["detail"])
            + ((what,) if any(named) else ()) for c, what in zip(verdict["criteria"], named)]
    return table(("status", "criterion", "found", *(("concerns",) if any(named) else ())), rows)


def missing_section(missing):
    return '<div class="callout">' + "".join(f"<p>{esc(m)}</p>" for m in missing) + "</div>"


def stats_table(named):
    """Rows of per-mode statistics dicts: n, mean, RMS, p95, max, signed means."""
    rows = [(mode, s["n"], *(f"{s[k]:.4f}" for k in ("mean", "rms", "p95", "max")),
             *(f"{v:+.4f}" for v in s["signed_mean"])) for mode, s in named.items() if isinstance(s, dict)]
    return table(("mode", "n", "mean", "RMS", "p95", "max", "dx", "dy", "dz"), rows, numeric=range(1, 9))


def files_table(files):
    return table(("role", "file", "bytes", "SHA-256"),
                 [(f["role"], f["path"], f["bytes"], Raw(f'<span class="hash">{esc(f["sha256"])}</span>'))
                  for f in files], numeric=(2,))


def options_table(options):
    return key_values([(k, v) for k, v in options.items()]) if options else "<p>default options</p>"


def _vector(values, digits):
    return " ".join(f"{v:.{digits}f}" for v in values)


# ------------------------------------------------------------------ compliance


def compliance_sections(doc):
    parts = [("verdict", "Verdict", verdict_section(doc["verdict"]) + _criteria_text(doc["criteria"], doc["verdict"]))]
    if doc["missing"]:
        parts.append(("missing", "Not available in this run", missing_section(doc["missing"])))
    parts.append(("targets", "Targets", _targets(doc)))
    parts.append(("not_compensated", "Motions not compensated", _not_compensated(doc)))
    if doc["targets"]:
        parts.append(("posture", "Posture: joint limits and singularities", _posture_text(doc)))
    parts.append(("timing", "Timing", _timing(doc["timing"])))
    if doc["targets"]:
        parts.append(("table", "Targets one by one", _target_tables(doc)))
    if doc["warnings"]:
        parts.append(("warnings", "Warnings", "<ul>" + "".join(f"<li>{esc(w)}</li>" for w in doc["warnings"]) + "</ul>"))
    parts.append(("provenance", "Provenance", _compliance_provenance(doc)))
    return parts


def _criteria_text(criteria, verdict):
    """The criteria's settings; the tolerance only when a criterion it sets was evaluated (not in a run without
    a model)."""
    settings = [f"joint limit margin {criteria['limit_margin_deg']:g} deg",
                f"singularity margins {criteria['singularity_margin_deg']:g} deg (elbow, wrist) and "
                f"{criteria['shoulder_margin_mm']:g} mm (shoulder)"]
    if judges_landing(verdict):
        settings.insert(0, f"tolerance {criteria['tolerance_mm']:g} mm")
    text = "; ".join(settings)
    return (f"<p>{text[0].upper()}{text[1:]}. A criterion that cannot be evaluated does not fail the run; it says "
            "why.</p>")


def _shown(value, spec, unit=""):
    """A number formatted with ``spec`` (and ``unit``), or a dash for None (not measured, no model)."""
    return "—" if value is None else f"{value:{spec}}{unit}"


def _names(names, total=None):
    """A list of names (of ``total``, all by default) as text, the first `SHOWN` of them."""
    total = len(names) if total is None else total
    more = f" … and {total - SHOWN} more" if total > SHOWN else ""
    return ", ".join(names[:SHOWN]) + more or "none"


STATISTICS = {"correction_mm": "correction, position", "correction_deg": "correction, orientation",
              "landing_estimate_mm": "landing estimate", "held_out_mm": "held-out error nearby",
              "unseen_mm": "unseen (orientation, tool, posture, track)", "orientation_beyond_deg": "orientation beyond measured",
              "convergence_mm": "convergence (model vs itself)", "limit_distance_deg": "nearest joint limit",
              "shoulder_mm": "shoulder singularity", "elbow_deg": "elbow singularity",
              "wrist_deg": "wrist singularity", "jump_deg": "largest joint change"}


def _statistics_table(statistics):
    """Distribution of each per-target measure over all targets."""
    rows = [(STATISTICS[name], s["unit"], *(f"{s[k]:.4g}" for k in ("min", "p5", "median", "mean", "p95", "max")),
             f"#{s['worst']} {s['worst_label']}") for name, s in statistics.items()]
    return table(("measure", "unit", "min", "p5", "median", "mean", "p95", "max", "worst target"), rows,
                 numeric=range(2, 8))


def _full_data(doc):
    """Where the data of every target are, for a summarised table."""
    data = doc["full_data"]
    if data["path"] is None:
        return ("the per-target data of every target were not written (the JSON went to standard output); "
                "--report PATH writes them beside the report")
    return (f"the data of every target are in {data['path']} beside this page "
            f"(NumPy: numpy.load(\"{data['path']}\"); arrays {', '.join(data['arrays'])})")


def _targets(doc):
    s, shown = doc["summary"], doc["target_table"]
    if not doc["targets"]:
        return "<p>No target was compensated.</p>"
    lead = key_values([
        ("targets (run as written)" if doc["provenance"]["model"] is None else "compensated targets", s["targets"]),
        ("tabulated below", "every target" if shown["complete"] else f"{shown['rows']} of {shown['targets']}"),
        ("flagged (failing a per-target criterion)", shown["flagged"]),
        ("outside the grid", _shown(s["outside_grid"], "d")),
        ("beyond the measured orientations", _shown(s["orientation_beyond"], "d")),
        ("on a tool the model cannot place", _shown(s["other_tool"], "d")),
        ("in an arm posture not measured", _shown(s["unmeasured_posture"], "d")),
        ("posture changed", s["configuration_changed"]),
        ("largest correction", "—" if s["correction_max_mm"] is None
         else f"{s['correction_max_mm']:.4f} mm, {s['correction_max_deg']:.4f} deg"),
        ("largest landing estimate", "—" if s["estimate_max_mm"] is None
         else f"{s['estimate_max_mm']:.4f} mm (tolerance {doc['criteria']['tolerance_mm']:g} mm)"),
        ("largest convergence residual", "—" if s["convergence_max_mm"] is None
         else f"{s['convergence_max_mm']:.1e} mm (the model agreeing with itself)"),
        ("smallest joint limit distance", f"{s['limit_distance_min_deg']:.2f} deg"),
        ("unused points (left as written)", _names(doc["unused"], s["unused"])),
        ("joint targets", f"{doc['joint_targets']['mode']}: "
                          f"{_names(doc['joint_targets']['labels'], doc['joint_targets']['count'])}"),
    ])
    return lead + f"<h3>Statistics over all {s['targets']} targets</h3>" + _statistics_table(s["statistics"])


def _target_tables(doc):
    shown, why, lead = doc["target_table"], {}, ""
    if not shown["complete"]:
        lead = (f'<div class="callout"><p>Summarised: {esc(shown["selection"])}.</p>'
                f"<p>{esc(_full_data(doc))}.</p></div>")
        for name, indices in shown["worst"].items():
            for k in indices:
                why.setdefault(k, []).append(f"worst {STATISTICS[name]}")
    targets = doc["targets"]

    def marker(columns):
        """Cells of failing targets to highlight: {criterion: columns}."""
        return lambda r, col: any(col in cols and key in targets[r]["flags"] for key, cols in columns.items())

    def reason(t):
        return ("; ".join([*t["flags"], *why.get(t["index"], [])]),) if why else ()

    extra = ("shown for",) if why else ()

    def where(t):
        places = ["outside grid" if t["outside_grid"] else "", "posture not measured" if t["unmeasured_posture"] else "",
                  f"orientation {t['orientation_beyond_deg']:.1f}° beyond measured" if t["orientation_beyond_deg"] else "",
                  "tool the model cannot place" if t["other_tool"] else ""]
        return ", ".join(p for p in places if p) or "measured"

    measured = doc.get("measured")
    flagged = marker({"residual": (3,), "outside_grid": (7,), "orientation": (7,), "tool": (7,), "posture": (7,)})
    if measured:  # the measured landing beside the estimate: red where it exceeds the estimate or the tolerance
        tolerance = doc["criteria"]["tolerance_mm"]

        def missed(t):
            value = t.get("measured_landing_mm")
            return value is not None and (value > tolerance or value > (t["landing_estimate_mm"] or 0.0))

        def bad(r, col):
            return missed(targets[r]) if col == 4 else flagged(r, col - (col > 4))
    rows = [(t["index"], t["label"], t["line"], _shown(t["landing_estimate_mm"], ".4f"),
             *((_shown(t.get("measured_landing_mm"), ".4f"),) if measured else ()), _shown(t["held_out_mm"], ".4f"),
             _shown(t["unseen_mm"], ".4f"), _shown(t["convergence_mm"], ".0e"), where(t), *reason(t)) for t in targets]
    estimates = table(("#", "target", "line", "landing estimate mm", *(("measured landing mm",) if measured else ()),
                       "held-out nearby mm", "unseen mm", "convergence mm", "where the measurements cover it", *extra),
                      rows, numeric={0, 2, 3, 4, 5, 6, *((7,) if measured else ())}, bad=bad if measured else flagged)
    if all(t["landing_estimate_mm"] is None and t["held_out_mm"] is None for t in targets):
        estimates = "<p>No landing estimate: the program runs as written, without a compensation model.</p>"
    rows = [(t["index"], t["label"], *(f"{v:.3f}" for v in t["target"]), *(f"{v:.3f}" for v in t["command"]),
             *(("—",) * 3 if t["correction_mm"] is None else (f"{v:+.4f}" for v in t["correction_mm"])),
             _shown(t["correction_norm_deg"], ".4f")) for t in targets]
    poses = table(("#", "target", "x", "y", "z", "a", "b", "c", "cmd x", "cmd y", "cmd z", "cmd a", "cmd b", "cmd c",
                   "dx", "dy", "dz", "d°"), rows, numeric={0, *range(2, 18)}, css="wide")
    rows = []
    for t in targets:
        limit = t["limit_distance_deg"]
        nearest = min(range(6), key=limit.__getitem__)
        branch = t["branch"] if t["branch"] == t["branch_planned"] else f"{t['branch_planned']} → {t['branch']}"
        config = t["declared"] if t["declared"] == t["written"] else f"{t['declared'] or '—'} → {t['written']}"
        rows.append((t["index"], t["label"], config or "—", t["posture_source"], branch,
                     *(f"{v:.2f}" for v in t["joints_deg"]), f"{limit[nearest]:.2f} (J{nearest + 1})",
                     f"{t['singularity']['shoulder_mm']:.0f}", f"{t['singularity']['elbow_deg']:.1f}",
                     f"{t['singularity']['wrist_deg']:.1f}", f"{max(t['jump_deg'], key=abs):+.2f}", *reason(t)))
    posture = table(("#", "target", "configuration declared → written", "from", "branch", "J1", "J2", "J3",
                     "J4", "J5", "J6", "nearest limit", "shoulder mm", "elbow °", "wrist °", "max jump °",
                     *extra), rows, numeric={0, *range(5, 16)},
                    bad=marker({"configuration": (2, 4), "joint_limits": (11,), "singularity": (12, 13, 14)}),
                    css="wide")
    return (lead + "<h3>Landing estimates</h3><p>How far from its target the arm may land, the figure the verdict "
            "judges: held-out (the largest error of the model near the target at measured points held out of its "
            "fit, with the mode and interpolator the compensation used) + unseen (what the measurements could not "
            "see at the target's orientation, tool and posture) + convergence (the compensation's own residual: "
            "the model agreeing with itself, not an accuracy).</p>" + _measured_text(doc) + '<div class="scroll">'
            + estimates + "</div>"
            + "<h3>Poses and corrections</h3><p>Target and command (cmd: the pose sent to the controller) in the "
            "robot base frame (mm; A, B, C in deg); dx, dy, dz = command − target (mm); d° the orientation "
            "correction (deg).</p>" + '<div class="scroll">' + poses + "</div>"
            + "<h3>Posture</h3><p>Written joints (deg), where the posture comes from, the branch "
            "(shoulder/elbow/wrist) they put the arm in, the distance to the nearest joint limit (deg), the distance "
            "to each singularity, and the largest joint change from the previous target.</p>" + '<div class="scroll">' + posture + "</div>")


def _measured_text(doc):
    """What the validation run's measured landings say of the estimates (empty without one)."""
    m = doc.get("measured")
    if not m:
        return ""
    return (f"<p>Measured landing: where the validation run measured the arm, {m['targets']} of "
            f"{doc['summary']['targets']} targets: mean {m['mean_mm']:.4f} mm, largest {m['max_mm']:.4f} mm, "
            f"{m['above_tolerance']} above the tolerance. The estimate covered {m['covered']:.1%} of them (the "
            f"estimate is a 95 % quantile) and was {m['sharpness']:.2f} times the measured landing (median). Red: "
            "a measured landing above its estimate or the tolerance.</p>")


def _not_compensated(doc):
    if not doc["not_compensated"]:
        return "<p>Every motion was compensated.</p>"
    listed, total = len(doc["not_compensated"]), doc["summary"]["not_compensated"]
    which = "These motions were" if listed == total else f"{total} motions were (the first {listed} listed)"
    return (f'<div class="callout"><p>{which} left exactly as written; they do not land where the '
            "model would put them.</p></div>"
            + table(("line", "statement", "why"),
                    [(f"{m['file']}:{m['line']}" if "file" in m else m["line"], Raw(f"<code>{esc(m['text'])}</code>"),
                      m["reason"]) for m in doc["not_compensated"]], numeric=(0,)))


def _posture_text(doc):
    return ("<p>Each written joint against its position limits, and how far each target is from the three "
            "singularities of the arm (where a small correction can swing joints fast or switch branch).</p>")


def _timing(section):
    if section is None:
        return '<div class="callout"><p>The program was not re-timed: no cycle time and no peak values.</p></div>'
    before = section["cycle_time_before_s"]
    lead = key_values([
        ("cycle time", f"{section['cycle_time_s']:.3f} s"
                       + ("" if before is None else f" (before: {before:.3f} s, {section['cycle_time_s'] - before:+.3f} s)")),
        ("within limits (dense check)", "yes" if section["within_limits"] else "no"),
        ("segments by kind", "; ".join(f"{k['count']} {kind}, {k['duration_s']:.3f} s"
                                       for kind, k in section["segments_by_kind"].items()) or "none"),
        ("segments", _names([f"{s['kind']} {s['first']}–{s['last']} {s['duration_s']:.3f} s" for s in section["segments"]],
                    section["segment_count"])),
        ("not re-timed: speed set at run time (left as written)",
         _names([f"{m['waypoint']} ({m['why']})" for m in section["not_retimed"]["motions"]],
                section["not_retimed"]["count"])),
        ("no time written: the controller would not run it as timed (left as written)",
         _names([f"{m['waypoint']} ({m['why']})" for m in section["not_modelled"]["motions"]],
                section["not_modelled"]["count"])),
        ("not timed: start not unique or not known (left as written; timing and limits not checked)",
         _names([f"{m['waypoint']} ({m['why']})" for m in section["unknown_start"]["motions"]],
                section["unknown_start"]["count"])),
        ("slower than timed: a speed lowered or a time raised where a limit binds",
         _names([m["detail"] for m in section["lowered"]["motions"]], section["lowered"]["count"])),
    ])
    rows = []
    for row in section["joints"]:
        cells = [f"J{row['joint']}"]
        for name in ("velocity", "acceleration", "jerk"):
            q = row[name]
            cells += ["not bounded" if q["peak"] is None else f"{q['peak']:.1f}",
                      "—" if q["limit"] is None else f"{q['limit']:.1f}",
                      "—" if q["ratio"] is None else f"{q['ratio']:.0%}"]
        rows.append(cells)
    over = {(r, c) for r, row in enumerate(section["joints"]) for c, name in ((3, "velocity"), (6, "acceleration"),
            (9, "jerk")) if row[name]["ratio"] is not None and row[name]["ratio"] > 1.01}
    return lead + table(("joint", "peak vel. deg/s", "limit", "%", "peak acc. deg/s²", "limit", "%",
                         "peak jerk deg/s³", "limit", "%"), rows, numeric=range(1, 10),
                        bad=lambda r, c: (r, c) in over)


def _model_table(model):
    if model is None:
        return "<p>No model.</p>"
    grid = model["grid"]
    box = "none" if grid is None else (f"{grid['kind']} ({grid['interpolation']}) from {_vector(grid['lower'], 1)} "
                                       f"to {_vector(grid['upper'], 1)} mm")
    cv = model.get("cross_validation") or {}
    out = key_values([
        ("file", model["path"]), ("SHA-256", Raw(f'<span class="hash">{esc(model["sha256"] or "none (no file)")}</span>')),
        ("created", model["created"]), ("written by trajcomp", model["trajcomp_version"]),
        ("robot", model["robot"]), ("method / mode used", f"{model['method']} / {model['mode']}"),
        ("modes available", ", ".join(model["modes"])), ("grid", box),
        ("measurements", (model.get("measurements") or {}).get("file")),
    ])
    out += "<h3>Fit (|error|, mm)</h3>" + stats_table(model["fit"])
    if cv:
        out += (f"<h3>{cv['folds']}-fold cross-validation (|error|, mm; interpolator {esc(cv.get('interpolation'))})</h3>"
                + stats_table({k: v for k, v in cv.items() if isinstance(v, dict)}))
    return out


def _compliance_provenance(doc):
    p = doc["provenance"]
    return ("<h3>Files</h3>" + files_table(p["files"])
            + "<h3>Robot</h3>" + key_values([("name", p["robot"]["name"]), ("source", p["robot"]["source"])])
            + "<h3>Model</h3>" + _model_table(p["model"])
            + "<h3>Options</h3>" + options_table(p["options"]))


# ------------------------------------------------------------------ calibration and validation


def calibration_sections(doc):
    parts = []
    if doc.get("verdict"):
        parts.append(("verdict", "Verdict", verdict_section(doc["verdict"])))
    if doc["missing"]:
        parts.append(("missing", "Not available from these data", missing_section(doc["missing"])))
    parts.append(("statistics", "Accuracy per mode", _statistics(doc)))
    if doc["kind"] == "calibration":
        parts.append(("iso9283", "ISO 9283 pose accuracy and repeatability", _iso(doc["iso9283"])))
    parts.append(("trends", "Error against the commanded coordinates", _trends(doc["trends"])))
    parts.append(("maps", "Error maps before and after", f"<p>{esc(doc['maps_note'])}</p>"))
    if doc.get("reliability"):
        parts.append(("reliability", "Reliability of the landing estimate", _reliability(doc["reliability"])))
    if doc["kind"] == "calibration":
        parts.append(("parameters", "Identified parameters", _parameters(doc["parameters"])))
        if doc.get("joint_errors"):
            parts.append(("joint_errors", "Joint-angle error model", _joint_errors(doc["joint_errors"])))
        parts.append(("validity", "What the model is valid for", _validity(doc["validity"])))
        parts.append(("outliers", "Outliers", _outliers(doc["outliers"])))
    if doc["warnings"]:
        parts.append(("warnings", "Warnings", "<ul>" + "".join(f"<li>{esc(w)}</li>" for w in doc["warnings"]) + "</ul>"))
    p = doc["provenance"]
    parts.append(("provenance", "Provenance", "<h3>Files</h3>" + files_table(p["files"])
                  + "<h3>Robot</h3>" + key_values([("name", p["robot"]["name"]), ("source", p["robot"]["source"])])
                  + "<h3>Options</h3>" + options_table(p["options"])))
    return parts


def _reliability(r):
    percent = f"{100 * r['quantile']:g} %"
    def stated(c):
        low, high = (f"{f(b['stated_mm'] for b in c['bins']):.4f}" for f in (min, max))
        return low if low == high else f"{low} – {high}"

    rows = [(name, c["rows"], f"{c['covered']:.1%}", stated(c)) for name, c in r["classes"].items()]
    return (f"<p>The landing estimate states the {percent} quantile of a target's landing error. Here is its held-out "
            f"part (mode {esc(r['mode'])}) at measured points held out of the fit that predicted them, at their "
            "distance from that fit's points, against their true error, per way of holding out: within the "
            f"stated quantile should be about {percent} (more: conservative).</p>"
            + table(("held out as", "rows", "within the stated quantile", "stated quantile mm"), rows,
                    numeric={1, 2, 3}))


def _statistics(doc):
    if doc["kind"] == "validation":
        return (f"<p>|measured − predicted| on {doc['points']} points, per mode (mm). "
                "Norms are the headline; signed per-axis means can cancel.</p>" + stats_table(doc["modes"]))
    out = ("<p>|measured − predicted| per mode (mm). Norms are the headline; signed per-axis means can cancel. "
           "The fit is on the measurements the model was identified from; cross-validation holds each fold out.</p>"
           "<h3>Fit</h3>" + stats_table(doc["fit"]))
    cv, held = doc["cross_validation"], doc["held_out"]
    if cv is not None:
        out += (f"<h3>{cv['folds']}-fold cross-validation (interpolator {esc(cv['interpolation'])})</h3>"
                + stats_table(cv["modes"]))
    if held is not None:
        out += ("<h3>Held out with the compensation's own interpolator (the verdict's figures)</h3>"
                f"<p>{esc(held['method'])}. The compensation judges each target by the largest of these errors "
                "near it, widened where its orientation, tool or posture lies outside what was measured.</p>"
                + stats_table(held["modes"]))
    return out


def _iso(iso):
    if not iso["available"]:
        return f'<div class="callout"><p>{esc(iso["note"])}</p></div>'
    rows = [(k + 1, _vector(p["position"], 1), p["cycles"], f"{p['ap_mm']:.4f}",
             "—" if p["ap_model_mm"] is None else f"{p['ap_model_mm']:.4f}", f"{p['rp_mm']:.4f}")
            for k, p in enumerate(iso["poses"])]
    return (f"<p>{esc(iso['note'])}</p>"
            + key_values([("poses measured repeatedly", len(iso["poses"])),
                          ("cycles per pose", f"{iso['cycles_min']}–{iso['cycles_max']}"),
                          ("AP (largest, nominal command)", f"{iso['ap_max_mm']:.4f} mm"),
                          (f"AP (largest, {iso['mode']} model)", "—" if iso["ap_model_max_mm"] is None
                           else f"{iso['ap_model_max_mm']:.4f} mm"),
                          ("RP (largest)", f"{iso['rp_max_mm']:.4f} mm")])
            + table(("pose", "commanded x y z (mm)", "cycles", "AP mm", f"AP {iso['mode']} mm", "RP mm"), rows,
                    numeric=(0, 2, 3, 4, 5)))


def _trends(trends):
    rows = [(name, *(f"{trends[name][axis]['slope_mm_per_m']:+.3f} (R² {trends[name][axis]['r2']:.2f})"
                     for axis in ("x", "y", "z"))) for name in ("dx", "dy", "dz")]
    return ("<p>Slope of each error axis against each commanded coordinate (mm per m, least squares), as in "
            "the paper's plots: strong linear relations are what the indirect (linear) correction removes.</p>"
            + table(("error", "vs x", "vs y", "vs z"), rows, numeric=(1, 2, 3)))


def _parameters(params):
    if params is None:
        return '<div class="callout"><p>No kinematic model was identified (method without DH).</p></div>'
    combinations = params.get("combinations") or []
    hidden = {c["name"] for c in combinations} | {f["name"] for f in params["fixed"]}  # no delta read as the arm's
    rows = [(p["name"], f"{p['delta']:+.5f}", f"{p['sigma']:.5f}", p["unit"],
             "" if p["sigma"] == 0 else f"{abs(p['delta']) / p['sigma']:.1f}") for p in params["identified"]
            if p["name"] not in hidden]
    out = (f"<p>{len(rows)} parameters identified on their own (deltas to the nominal table with one standard "
           f"deviation); condition number of the scaled Jacobian {params['condition_number']:.1f}.</p>"
           + table(("parameter", "delta", "σ", "unit", "|delta|/σ"), rows, numeric=(1, 2, 4)))
    if combinations:
        from trajcomp.report.calibration import combination_text

        out += ("<h3>Identified only in combination</h3><p>The data see these parameters only together: each row is "
                "a combination the measurements determine (lengths in mm, angles in deg; a coefficient is the "
                "combination's unit per the term's), not the separate deltas, which the fit spreads at least cost "
                "from the nominal arm and an engineer should not read as errors of the arm.</p>"
                + table(("combination", "value", "σ", "unit"),
                        [(combination_text(c), f"{c['value']:+.5f}", f"{c['sigma']:.5f}", c["unit"])
                         for c in combinations],
                        numeric=(1, 2)))
    if params["fixed"]:
        out += ("<h3>Not identified on their own (moved only within combinations the data see)</h3>"
                + table(("parameter", "why"), [(f["name"], f["reason"]) for f in params["fixed"]]))
    return out


def _joint_errors(j):
    terms = ", ".join(f"{count} {family}" for family, count in j["terms"].items() if count) or "none"
    out = f"<p>Terms: {esc(terms)}. Beyond the measured joint range: {esc(j['beyond_range'])}.</p>"
    out += table(("joint", "measured from (deg)", "to (deg)"),
                 [(k + 1, f"{lo:.1f}", f"{hi:.1f}") for k, (lo, hi) in
                  enumerate(zip(j["measured_range_deg"]["lower"], j["measured_range_deg"]["upper"]))], numeric=(1, 2))
    splines = j.get("splines")
    if splines:
        shares = [c for c in splines.get("candidates", ()) if c.get("share")]
        penalty = (f"penalty {splines['penalty']:g}" if len(shares) < 2 else "the weighted mean of its fits at "
                   "penalties " + ", ".join(f"{c['penalty']:g} ({c['share']:.0%})" for c in shares))
        chosen = (f"knots every {splines['step_deg']:g} deg on joints {splines['joints']}, {penalty}"
                  if splines["step_deg"] else "no spline terms")
        if j.get("field_on_top"):
            chosen += f", a {j['field_on_top']} field over the commanded positions on top"
        out += f"<p>Chosen on held-out regions ({esc(splines.get('regions', ''))}): {esc(chosen)}.</p>"
        if splines.get("candidates"):
            out += table(("knot step (deg)", "penalty", "held-out mean |error| (mm)", "with the field on top (mm)",
                          "share of the model"),
                         [(f"{c['step_deg']:g}", f"{c['penalty']:g}", f"{c['held_out_mm']:.4f}",
                           f"{c['with_field_mm']:.4f}" if "with_field_mm" in c else "-",
                           f"{c['share']:.1%}" if c.get("share") else "-")
                          for c in splines["candidates"]], numeric=(0, 1, 2, 3, 4))
    return out


def _validity(v):
    grids = [(name, "none" if g is None else f"{g['kind']} ({g['interpolation']}), {_vector(g['lower'], 1)} to "
              f"{_vector(g['upper'], 1)} mm" + ("" if g["step"] is None else f", step {_vector(g['step'], 1)} mm"))
             for name, g in v["grids"].items()]
    o = v["orientations"]
    return key_values([
        ("measured positions", f"{_vector(v['measured_box']['lower'], 1)} to {_vector(v['measured_box']['upper'], 1)} mm"),
        *grids,
        ("orientations", "unknown (positions only)" if o is None else
         f"{o['distinct']} distinct; largest deviation from their mean {o['max_deviation_deg']:.1f} deg; "
         f"e.g. A B C {'; '.join(_vector(e, 1) for e in o['examples'])}"),
        ("tool (TCP in the flange frame)", f"{_vector(v['tool']['pose'], 3)} (mm, deg)"),
        ("identified TCP offset", "not identified" if v["tool"]["identified_offset_mm"] is None
         else f"{_vector(v['tool']['identified_offset_mm'], 4)} mm"),
        ("note", v["note"]),
    ])


def _outliers(outliers):
    if not outliers["lines"]:
        return "<p>No measurement was left out.</p>"
    return (f"<p>{len(outliers['lines'])} rows were left out as gross outliers (residual far beyond the others), "
            f"by line of {esc(outliers['file'])}:</p><p class=\"mono\">{esc(', '.join(map(str, outliers['lines'])))}</p>")


def build(report):
    """Title, subtitle and the sections ``[(key, heading, html)]`` of a report page."""
    doc = report.doc
    if doc["kind"] == "compliance":
        title = f"Compliance report · {doc['command']}"
        subtitle = "Is the corrected program safe to run and within tolerance? Criteria, evidence, provenance."
        return title, subtitle, compliance_sections(doc)
    title = "Calibration report" if doc["kind"] == "calibration" else "Validation report"
    subtitle = ("How accurate is the model, on which data, and where is it valid?" if doc["kind"] == "calibration"
                else "How accurate is the model on measurements it was not fitted to?")
    return title, subtitle, calibration_sections(doc)
