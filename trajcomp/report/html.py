"""One self-contained HTML page per report: inline CSS, figures as inline SVG or PNG data URIs, no script, no
network.

The page reads top-down as a sign-off sheet: verdict first (each criterion
with what it concerns), then what is missing, then the evidence, then
provenance. It prints on A4 (navigation hidden, figures and table rows kept
whole, table headers repeated).
"""

import base64
import io

from trajcomp.report import sections
from trajcomp.report.markup import esc
from trajcomp.report.verdict import FAIL, PASS

STYLE = """
:root { --ink: #1d2733; --muted: #5d6b7a; --line: #d5dbe2; --pass: #1e7d45; --fail: #b42318; --na: #8a6d00;
        --band: #f4f6f8; }
* { box-sizing: border-box; }
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif;
       color: var(--ink); margin: 0 auto; max-width: 1180px; padding: 24px 28px 60px; }
h1 { font-size: 24px; margin: 0 0 4px; }
h2 { font-size: 19px; margin: 34px 0 10px; padding-bottom: 4px; border-bottom: 2px solid var(--line); }
h3 { font-size: 15px; margin: 20px 0 6px; }
p.sub { color: var(--muted); margin: 0 0 16px; }
.banner { display: flex; align-items: center; gap: 18px; padding: 14px 18px; border-radius: 6px; margin: 14px 0;
          border: 2px solid; }
.banner.pass { border-color: var(--pass); background: #eaf6ee; }
.banner.fail { border-color: var(--fail); background: #fdeceb; }
.banner.none { border-color: var(--line); background: var(--band); }
.banner .word { font-size: 28px; font-weight: 800; letter-spacing: 1px; }
.banner.pass .word { color: var(--pass); } .banner.fail .word { color: var(--fail); }
.badge { display: inline-block; min-width: 86px; white-space: nowrap; text-align: center; padding: 1px 8px; border-radius: 10px;
         font-size: 12px; font-weight: 700; color: #fff; }
.badge.pass { background: var(--pass); } .badge.fail { background: var(--fail); }
.badge.na { background: #b9a55c; }
nav { font-size: 13px; color: var(--muted); margin-bottom: 8px; }
nav a { color: var(--muted); margin-right: 12px; }
table { border-collapse: collapse; width: 100%; margin: 6px 0 12px; font-size: 13px; }
th, td { border-bottom: 1px solid var(--line); padding: 4px 7px; text-align: left; vertical-align: top; }
th { background: var(--band); font-weight: 600; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
td.num { white-space: nowrap; }
table.wide th { font-size: 11px; }
tr:nth-child(even) td { background: #fafbfc; }
td.bad { color: var(--fail); font-weight: 700; background: #fdeceb !important; }
table.wide { font-size: 11.5px; }
table.kv th { width: 230px; }
code, .mono { font-family: ui-monospace, "SFMono-Regular", Menlo, Consolas, monospace; font-size: 12px; }
.hash { font-family: ui-monospace, Menlo, Consolas, monospace; font-size: 11px; word-break: break-all; }
.callout { border-left: 4px solid #b9a55c; background: #fbf7e6; padding: 8px 12px; margin: 10px 0; }
.callout p { margin: 3px 0; }
figure { margin: 12px 0 20px; break-inside: avoid; }
figure img, figure svg { max-width: 100%; height: auto; display: block; border: 1px solid var(--line); }
figure svg { width: 100%; }
figcaption { color: var(--muted); font-size: 12.5px; margin-top: 4px; }
.scroll { overflow-x: auto; }
footer { margin-top: 40px; color: var(--muted); font-size: 12px; }
@page { size: A4; margin: 14mm 12mm; }
@media print {
  body { max-width: none; padding: 0; font-size: 11px; }
  nav { display: none; }
  .scroll { overflow: visible; }
  table.wide { font-size: 8px; }
  tr, .banner, .callout { break-inside: avoid; }
  thead { display: table-header-group; }
  h2 { break-after: avoid; }
}
"""


def figure_html(figure):
    """A `Figure` drawn, as a <figure>: its SVG inline, or a matplotlib figure as an embedded PNG."""
    fig = figure.draw()
    caption = f"<figcaption><b>{esc(figure.title)}.</b> {esc(figure.caption)}</figcaption></figure>"
    if isinstance(fig, str):
        return f"<figure>{fig}{caption}"
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=120, metadata={"Software": None})
    fig.clear()
    import matplotlib.pyplot as plt

    plt.close(fig)
    data = base64.b64encode(buffer.getvalue()).decode("ascii")
    return f'<figure><img alt="{esc(figure.title)}" src="data:image/png;base64,{data}">{caption}'


def banner(verdict, what):
    """The verdict banner (or a neutral one for reports without a verdict)."""
    if verdict is None:
        return f'<div class="banner none"><div>{esc(what)}</div></div>'
    result = verdict["result"]
    failed = sum(c["status"] == "fail" for c in verdict["criteria"])
    evaluated = sum(c["status"] != "not evaluated" for c in verdict["criteria"])
    failing = [c["statement"] for c in verdict["criteria"] if c["status"] == "fail"]
    text = (f"{failed} of {evaluated} evaluated criteria fail: " + "; ".join(failing) if failed
            else f"all {evaluated} evaluated criteria pass"
            + (f": {verdict['criteria'][0]['statement']} ({verdict['criteria'][0]['detail']})"
               if len(verdict["criteria"]) == 1 else ""))
    return (f'<div class="banner {result if result in (PASS, FAIL) else "none"}"><div class="word">{result.upper()}</div>'
            f"<div>{esc(what)}<br>{esc(text)}</div></div>")


def render(report):
    """The HTML page of a `Report`."""
    doc = report.doc
    title, subtitle, parts = sections.build(report)
    figures = {}
    for figure in report.figures:
        figures.setdefault(figure.section, []).append(figure_html(figure))
    nav = " ".join(f'<a href="#{key}">{esc(heading)}</a>' for key, heading, _ in parts)
    body = []
    for key, heading, content in parts:
        body.append(f'<section id="{key}"><h2>{esc(heading)}</h2>{content}{"".join(figures.get(key, []))}</section>')
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{esc(title)}</title>
<style>{STYLE}</style></head>
<body>
<h1>{esc(title)}</h1>
<p class="sub">{esc(subtitle)}</p>
{banner(doc.get("verdict"), sections.headline(doc))}
<nav>{nav}</nav>
{"".join(body)}
<footer>trajcomp {esc(doc["trajcomp_version"])} · schema {esc(doc["schema"])} · created {esc(doc["created"])}
· the same data as JSON beside this file</footer>
</body></html>
"""
