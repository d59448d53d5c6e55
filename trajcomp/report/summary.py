"""The one-screen text summary of a report (for stderr)."""

from pathlib import Path

from trajcomp.report.verdict import FAIL, NOT_EVALUATED, PASS

NAMED = 6  # targets named per failed criterion


def _concerns(criterion):
    named = [*criterion["targets"], *(f"line {line}" for line in criterion["lines"])]
    total = max(criterion["failing"], len(named))
    more = f" (+{total - NAMED} more)" if total > NAMED else ""
    return ", ".join(named[:NAMED]) + more


HEADLINE = ("residual", "model_accuracy", "measured")  # criteria whose figures are shown even when they pass


def verdict_lines(verdict):
    """One line per failed or headline criterion (status, id, what was found and, when failed, what it concerns),
    one per reason criteria were not evaluated (naming them), then one line naming the other criteria that pass."""
    out, passed, unevaluated = [], [], {}
    for c in verdict["criteria"]:
        if c["status"] == PASS and c["id"] not in HEADLINE:
            passed.append(c["id"])
            continue
        if c["status"] == NOT_EVALUATED:
            unevaluated.setdefault(c["detail"], []).append(c["id"])
            continue
        status = "FAIL" if c["status"] == FAIL else "pass"
        concerns = f": {_concerns(c)}" if c["status"] == FAIL and (c["targets"] or c["lines"]) else ""
        out.append(f"  {status}  {c['id']:<15} {c['detail']}{concerns}")
    out += [f"    --  not evaluated: {', '.join(ids)}: {why}" for why, ids in unevaluated.items()]
    if passed:
        out.append(f"  pass  {', '.join(passed)} (the report has what each found)")
    return out


def judges_landing(verdict):
    """Whether a criterion the tolerance sets (`HEADLINE`) was evaluated: else no tolerance is shown."""
    return any(c["id"] in HEADLINE and c["status"] != NOT_EVALUATED for c in verdict["criteria"])


def summary_lines(doc):
    """The summary of a report document (list of str, at most about 20 lines)."""
    verdict = doc.get("verdict")
    files = [Path(f["path"]).name for f in doc["provenance"]["files"] if f["role"] in ("program", "measurements")]
    what = f"{doc['kind']} report of {', '.join(files) or 'the run'} (robot {doc['provenance']['robot']['name']})"
    if verdict is None:
        out = [what]
    else:
        criteria = doc.get("criteria") or {}
        tolerance = f", tolerance {criteria['tolerance_mm']:g} mm" if criteria and judges_landing(verdict) else ""
        out = [f"verdict: {verdict['result'].upper()}{tolerance}: {what}", *verdict_lines(verdict)]
    summary = doc.get("summary")
    if summary and summary["targets"] and summary["correction_max_mm"] is None:
        out.append(f"  {summary['targets']} targets, run as written (no compensation model)")
    elif summary and summary["targets"]:
        estimate = summary.get("estimate_max_mm")
        out.append(f"  {summary['targets']} targets; largest correction {summary['correction_max_mm']:.3f} mm, "
                   f"{summary['correction_max_deg']:.3f} deg; {summary['outside_grid']} outside the grid"
                   + ("" if estimate is None else f"; largest landing estimate {estimate:.3f} mm"))
    out += [f"  missing: {m}" for m in doc["missing"]]
    return out
