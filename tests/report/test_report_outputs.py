"""Report files: JSON valid against the shipped schema, self-contained HTML, CLI exit codes, calibration figures."""

import base64
import dataclasses
import json
import re
import subprocess
import sys
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from trajcomp.cli import main
from trajcomp.calibration.measurements import Measurements
from trajcomp.model.model_file import load_model
from trajcomp.report import Report, calibration_report, schema
from trajcomp.report.calibration import iso9283, trends

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "programs" / "kuka" / "weld.src"
VALIDATOR = jsonschema.Draft202012Validator(schema())


def _valid(doc):
    errors = [f"{list(e.absolute_path)}: {e.message}" for e in VALIDATOR.iter_errors(doc)]
    assert not errors, errors[:5]
    return doc


def test_the_shipped_schema_is_a_valid_json_schema():
    jsonschema.Draft202012Validator.check_schema(schema())
    assert schema()["properties"]["schema"]["const"] == "trajcomp-report/1"


def _self_contained(page):
    """The figures of a page (PNG bytes), after checking that it loads nothing from anywhere."""
    assert not re.search(r"<script|<link|<iframe|@import|url\(", page, re.IGNORECASE)
    assert not re.search(r"(src|href)\s*=\s*[\"'](?!data:|#)", page, re.IGNORECASE)
    assert "http://" not in page and "https://" not in page
    images = re.findall(r'<img [^>]*src="data:image/png;base64,([A-Za-z0-9+/=]+)"', page)
    return [base64.b64decode(data) for data in images]


def test_compensate_writes_a_valid_report_and_a_self_contained_page(tmp_path, kuka_model, capsys):
    out = tmp_path / "weld.src"
    assert main(["compensate", str(EXAMPLE), "--model", str(kuka_model), "-o", str(out),
                 "--report", str(tmp_path / "weld-report")]) == 0
    err = capsys.readouterr().err
    assert "verdict: PASS" in err and len(err.splitlines()) < 25
    doc = _valid(json.loads((tmp_path / "weld-report.json").read_text()))
    assert doc["kind"] == "compliance" and doc["verdict"]["result"] == "pass"
    roles = {f["role"]: f for f in doc["provenance"]["files"]}
    assert set(roles) == {"program", "output"} and doc["provenance"]["model"]["mode"] == "composite"
    assert [t["label"].split()[0] for t in doc["targets"]] == ["P1", "P2", "P3", "P4", "P5"]
    assert doc["target_table"]["complete"] and doc["full_data"] is None  # a short program: every target, no sidecar
    assert [t["index"] for t in doc["targets"]] == [1, 2, 3, 4, 5] and not any(t["flags"] for t in doc["targets"])
    assert doc["timing"]["within_limits"] and doc["timing"]["cycle_time_before_s"] > 0  # compensate re-times
    figures = _self_contained((tmp_path / "weld-report.html").read_text())
    assert len(figures) == 6 and all(png.startswith(b"\x89PNG\r\n\x1a\n") for png in figures)


def test_retime_writes_a_compliance_report_of_the_program_as_written(tmp_path, capsys):
    """Every retime run has a report: the targets in their declared postures, the timing, the verdict."""
    out = tmp_path / "weld.src"
    assert main(["retime", str(EXAMPLE), "--robot", "kuka_kr6_r900", "-o", str(out),
                 "--report", str(tmp_path / "timed")]) == 0
    assert "verdict: PASS" in capsys.readouterr().err
    doc = _valid(json.loads((tmp_path / "timed.json").read_text()))
    assert doc["command"] == "retime" and doc["verdict"]["result"] == "pass"
    assert doc["timing"]["within_limits"] and doc["timing"]["cycle_time_s"] > 0
    assert len(doc["targets"]) == 5
    no_model = ("correction_mm", "correction_deg", "correction_norm_mm", "correction_norm_deg", "convergence_mm",
                "outside_grid", "landing_estimate_mm", "held_out_mm", "unseen_mm", "orientation_beyond_deg",
                "unmeasured_posture", "other_tool")  # a retime report claims nothing a model gives: it said "0 outside"
    assert all(t[key] is None for t in doc["targets"] for key in no_model)
    assert all(t["command"] == t["target"] for t in doc["targets"])  # written as programmed
    summary = doc["summary"]
    assert summary["outside_grid"] is summary["correction_max_mm"] is summary["convergence_max_mm"] is None
    assert summary["estimate_max_mm"] is summary["unmeasured_posture"] is None
    assert not {"correction_mm", "correction_deg", "convergence_mm", "landing_estimate_mm"} & set(summary["statistics"])
    assert any(m.startswith("no compensation model") for m in doc["missing"])
    ruckig = any(s["kind"] == "ruckig" for s in doc["timing"]["segments"])
    for row in doc["timing"]["joints"]:  # measured on ruckig segments of a jerk-limited arm only, else null (was 0)
        assert (row["jerk"]["peak"] is None) == (not ruckig or row["jerk"]["limit"] is None)
    # PTP P1, LIN P2..P4, PTP P5: KUKA Status and Turn bind PTP targets only
    assert [t["posture_source"] for t in doc["targets"]] == ["config", "previous", "previous", "previous", "config"]
    status = {c["id"]: c["status"] for c in doc["verdict"]["criteria"]}
    assert status["residual"] == status["uncompensated"] == "not evaluated"  # nothing was compensated
    assert status["joint_limits"] == status["timing"] == "pass"


def test_a_failing_verdict_exits_1_with_the_program_written(tmp_path, kuka_model, capsys):
    out = tmp_path / "weld.src"
    code = main(["compensate", str(EXAMPLE), "--model", str(kuka_model), "-o", str(out), "--json-only",
                 "--singularity-margin", "85"])  # the weld path's wrist is 76-87 deg from its singularity
    captured = capsys.readouterr()
    assert code == 1 and out.exists() and (tmp_path / "weld.dat").exists()
    doc = _valid(json.loads(captured.out))
    failed = [c for c in doc["verdict"]["criteria"] if c["status"] == "fail"]
    assert [c["id"] for c in failed] == ["singularity"] and failed[0]["targets"]
    assert "FAIL  singularity" in captured.err


def test_json_only_does_not_import_matplotlib(tmp_path, kuka_model):
    script = (f"import sys; from trajcomp.cli import main; "
              f"code = main(['compensate', {str(EXAMPLE)!r}, '--model', {str(kuka_model)!r}, '-o', "
              f"{str(tmp_path / 'w.src')!r}, '--report', {str(tmp_path / 'r')!r}, '--json-only']); "
              f"print(code, 'matplotlib' in sys.modules)")
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True,
                         cwd=Path(__file__).resolve().parents[2])
    assert run.stdout.split() == ["0", "False"]
    assert (tmp_path / "r.json").exists() and not (tmp_path / "r.html").exists()


def test_validate_json_and_its_verdict(tmp_path, kuka_model):
    folder = Path(kuka_model).parent
    second = tmp_path / "run2.csv"
    assert main(["simulate", str(folder / "plan.csv"), "--robot", "kuka_kr6_r900", "--seed", "1", "--run", "2",
                 "-o", str(second)]) == 0
    path = tmp_path / "validation.json"
    assert main(["validate", str(kuka_model), str(second), "--json", str(path), "--tolerance", "0.5"]) == 0
    doc = _valid(json.loads(path.read_text()))
    assert set(doc["modes"]) == {"none", "linear", "dh", "grid", "composite"}
    assert doc["modes"]["none"]["mean"] > 10 * doc["modes"]["composite"]["mean"]
    tight = doc["modes"]["composite"]["p95"] * 0.9
    assert main(["validate", str(kuka_model), str(second), "--json", str(path), "--tolerance", str(tight)]) == 1
    assert json.loads(path.read_text())["verdict"]["result"] == "fail"


def test_trends_recover_a_linear_error_and_ignore_the_others():
    axis = np.arange(0.0, 500.0, 100.0)
    position = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    errors = np.zeros_like(position)
    errors[:, 0] = 0.002 * position[:, 1] - 0.3  # dx = 2 mm per m of y
    got = trends(position, errors)
    assert got["dx"]["y"]["slope_mm_per_m"] == pytest.approx(2.0)
    assert got["dx"]["y"]["intercept_mm"] == pytest.approx(-0.3)
    assert got["dx"]["y"]["r2"] == pytest.approx(1.0)
    assert got["dx"]["x"]["slope_mm_per_m"] == pytest.approx(0.0, abs=1e-12)
    assert got["dx"]["x"]["r2"] == pytest.approx(0.0, abs=1e-12)  # rounding of sums can leave ~1e-36
    assert got["dz"]["z"] == {"slope_mm_per_m": 0.0, "intercept_mm": 0.0, "r2": 0.0}


def test_iso9283_accuracy_and_repeatability_by_hand():
    command = np.repeat([[500.0, 0.0, 400.0], [600.0, 0.0, 400.0]], 4, axis=0)
    scatter = np.array([[0, 0.1, 0], [0, -0.1, 0], [0, 0, 0.1], [0, 0, -0.1]] * 2)
    measured = command + [1.0, 0.0, 0.0] + scatter  # barycentre 1 mm off in x; every point 0.1 mm from it
    got = iso9283(np.vstack([command, [[0.0, 0.0, 0.0]]]), np.vstack([measured, [[0.0, 0.0, 0.0]]]),
                  np.vstack([command + [1.0, 0.0, 0.0], [[0.0, 0.0, 0.0]]]), "dh")
    assert got["available"] and len(got["poses"]) == 2 and got["cycles_min"] == 4
    assert got["ap_max_mm"] == pytest.approx(1.0)
    assert got["ap_model_max_mm"] == pytest.approx(0.0, abs=1e-12)
    assert got["rp_max_mm"] == pytest.approx(0.1)  # l-bar 0.1, S_l 0
    assert not iso9283(command[::4], measured[::4], None, "dh")["available"]


def test_calibration_report_with_repeats_is_valid_and_embeds_its_figures(kuka_model, tmp_path):
    folder = Path(kuka_model).parent
    model = load_model(kuka_model)
    from trajcomp.calibration.measurements import read_measurements

    meas = read_measurements(folder / "meas.csv")
    twice = Measurements(joints=np.vstack([meas.joints, meas.joints[:5]]),
                         position=np.vstack([meas.position, meas.position[:5]]),
                         measured=np.vstack([meas.measured, meas.measured[:5] + [0.0, 0.02, 0.0]]),
                         lines=np.arange(len(meas) + 5) + 2, path="meas.csv")
    report = calibration_report(model, twice)
    doc = _valid(json.loads(report.json_text()))
    assert doc["iso9283"]["available"] and doc["iso9283"]["cycles_max"] == 2
    assert doc["iso9283"]["rp_max_mm"] == pytest.approx(0.01, abs=1e-9)  # 2 points 0.02 mm apart: l 0.01, S_l 0
    assert doc["parameters"]["identified"] and doc["validity"]["orientations"]["distinct"] == 1
    assert not any(m.startswith("no cross-validation") for m in doc["missing"])  # the fixture ran --folds 3
    no_cv = dataclasses.replace(model, report={k: v for k, v in model.report.items() if k != "cross_validation"})
    assert any(m.startswith("no cross-validation") for m in calibration_report(no_cv, twice).doc["missing"])
    figures = _self_contained(report.html_text())
    assert len(figures) == len(report.figures) == 3


def test_calibrate_report_without_a_grid_says_so(tmp_path, kuka_model):
    meas = Path(kuka_model).parent / "meas.csv"
    # --folds 0: no held-out evidence, so the verdict is not evaluated and the run fails (a pass would claim it)
    assert main(["calibrate", str(meas), "--robot", "kuka_kr6_r900", "--method", "dh", "--folds", "0",
                 "-o", str(tmp_path / "dh.yaml"), "--report", str(tmp_path / "cal"), "--json-only"]) == 1
    doc = _valid(json.loads((tmp_path / "cal.json").read_text()))
    assert doc["verdict"]["result"] == "not evaluated"
    assert doc["validity"]["grids"] == {"grid": None, "residual": None}
    assert any(m.startswith("no grid") for m in doc["missing"])


def test_the_report_path_gets_json_and_html_appended(tmp_path):
    report = Report({"schema": "trajcomp-report/1", "verdict": {"result": "pass", "criteria": []}})
    dotted = report.write(tmp_path / "ur10_path.report", json_only=True)  # README: PATH.json, dots kept
    named = report.write(tmp_path / "cell.json", json_only=True)  # a given .json is not doubled
    assert [f.name for f in dotted + named] == ["ur10_path.report.json", "cell.json"]
    assert json.loads(dotted[0].read_text())["schema"] == "trajcomp-report/1"
