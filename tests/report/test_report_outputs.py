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
    assert not re.search(r"<script|<link|<iframe|@import|url\((?!#)", page, re.IGNORECASE)  # url(#id): in the page
    assert not re.search(r"(src|href)\s*=\s*[\"'](?!data:|#)", page, re.IGNORECASE)
    assert "https://" not in page and "http://" not in page.replace('xmlns="http://www.w3.org/2000/svg"', "")
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
    page = (tmp_path / "weld-report.html").read_text()
    assert _self_contained(page) == []  # no PNG: the compliance figures are inline SVG
    assert len(re.findall(r'<svg xmlns="http://www.w3.org/2000/svg" ', page)) == 6
    clips = re.findall(r'<clipPath id="([^"]+)"', page)
    assert len(clips) == len(set(clips)) > 6  # one per panel, unique in the page (a repeated id clips elsewhere)


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


@pytest.mark.parametrize("options", [["--json-only"], []])
def test_a_compliance_report_imports_no_matplotlib(tmp_path, kuka_model, options):
    """--json-only draws nothing; the page's figures are SVG written directly (matplotlib took seconds a page)."""
    script = (f"import sys; from trajcomp.cli import main; "
              f"code = main(['compensate', {str(EXAMPLE)!r}, '--model', {str(kuka_model)!r}, '-o', "
              f"{str(tmp_path / 'w.src')!r}, '--report', {str(tmp_path / 'r')!r}, *{options!r}]); "
              f"print(code, 'matplotlib' in sys.modules)")
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True,
                         cwd=Path(__file__).resolve().parents[2])
    assert run.stdout.split() == ["0", "False"]
    assert (tmp_path / "r.json").exists()
    if options:
        assert not (tmp_path / "r.html").exists()
    else:
        assert (tmp_path / "r.html").read_text().count("<svg ") == 6


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


def test_iso9283_takes_one_position_in_other_orientations_as_other_poses_not_cycles():
    position = np.repeat([[500.0, 0.0, 400.0]], 5, axis=0)
    orientation = np.array([[0.0, 180.0, 0.0]] * 3 + [[30.0, 180.0, 0.0], [0.0, 150.0, 0.0]])
    measured = position + [[1.0, 0, 0], [1.0, 0.02, 0], [1.0, -0.02, 0], [-2.0, 0, 0], [0, 2.0, 0]]  # its own error
    pose = np.hstack([position, orientation])
    got = iso9283(position, measured, None, "none", pose)
    assert got["cycles_max"] == 3 and len(got["poses"]) == 1  # the three visits of the first pose alone
    distances = np.array([0.0, 0.02, 0.02])  # from the barycentre, 1 mm off in x
    assert got["rp_max_mm"] == pytest.approx(distances.mean() + 3.0 * distances.std(ddof=1))
    assert got["ap_max_mm"] == pytest.approx(1.0)
    assert iso9283(position, measured, None, "none")["rp_max_mm"] > 2.0  # taken as cycles of one: the errors' spread


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
    assert len(figures) == len(report.figures) == 4  # statistics, trends, maps, reliability


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


# issue 38: reports without blemishes

def test_command_angles_are_shown_next_to_the_written_ones(tmp_path, kuka_model):
    """A command C of 180.077 (as the program writes it) was shown as -179.923."""
    program = tmp_path / "p.csv"
    program.write_text("x,y,z,a,b,c,motion\n500,50,700,0,0,180,PTP\n520,50,700,0,0,-180,LIN\n")
    assert main(["compensate", str(program), "--model", str(kuka_model), "-o", str(tmp_path / "o.csv"),
                 "--retime", "none", "--report", str(tmp_path / "r"), "--json-only"]) in (0, 1)
    doc = json.loads((tmp_path / "r.json").read_text())
    written = np.loadtxt(tmp_path / "o.csv", delimiter=",", skiprows=1, usecols=(3, 4, 5))
    for row, c_written in zip(doc["targets"], written[:, 2]):
        assert abs(row["command"][5] - row["target"][5]) < 1.0  # within the correction of the target's angle
        assert row["command"][5] == pytest.approx(c_written, abs=1e-3)  # and as the output writes it


def test_the_concerns_column_is_shown_only_when_a_criterion_fails():
    from trajcomp.report.sections import verdict_section

    passed = {"result": "pass", "criteria": [{"id": "residual", "statement": "s", "detail": "d", "status": "pass",
                                              "targets": [], "lines": [], "failing": 0}]}
    assert "concerns" not in verdict_section(passed)
    failed = {"result": "fail", "criteria": [dict(passed["criteria"][0], status="fail", targets=["P1 (a.src:3)"],
                                                  failing=1)]}
    assert "<th>concerns</th>" in verdict_section(failed) and "P1 (a.src:3)" in verdict_section(failed)


def test_zero_errors_of_a_grid_are_drawn_as_zeros_not_as_bars_to_1e_20():
    from trajcomp.report import plots

    stats = {"none": {"mean": 2.0, "p95": 2.3}, "grid": {"mean": 3e-21, "p95": 0.0}, "dh": {"mean": 0.02, "p95": 0.04}}
    fig = plots.mode_statistics({"fit": stats})
    ax = fig.axes[0]
    heights = [bar.get_height() for bar in ax.patches]
    assert all(h > 1e-3 for h in heights if np.isfinite(h))  # no bar for a zero
    assert ax.get_ylim()[0] >= 1e-3  # the axis does not reach down to the rounding noise
    assert [t.get_text() for t in ax.texts] == ["0", "0"]  # the grid's mean and p95, written as zeros
    assert ax.get_legend() is None and fig.legends  # the legend below the axes, off the bars


def test_the_orientation_correction_axis_starts_at_zero():
    """A correction of 0.0003 deg spanned the whole axis and looked like large swings."""
    from trajcomp.report import compliance_figures

    page = compliance_figures.corrections(np.array([2.0, 2.1, 2.2]), np.array([0.0962, 0.0963, 0.0961]),
                                          np.array([0.03, 0.03, 0.03]), np.array([1e-7, 2e-7, 1e-7]), 0.1)
    right = [float(v) for v in re.findall(r'<text x="9[0-9][0-9](?:\.\d)?" y="[\d.]+">([\d.]+)</text>', page)]
    assert right[0] == 0.0 and right[-1] >= 0.096  # from zero to the largest, not 0.0961 to 0.0963


def test_parameters_the_data_see_only_together_are_shown_as_their_combinations(tmp_path):
    """d2, d3, d4, a5, theta4 were listed as deltas with sigma; the data see a combination of them only."""
    from trajcomp.arm.kinematics import fk
    from trajcomp.arm.parameters import apply_deltas, is_angle
    from trajcomp.calibration.measurements import read_measurements
    from trajcomp.report.calibration import combination_text

    plan, meas, model_path = tmp_path / "plan.csv", tmp_path / "meas.csv", tmp_path / "m.yaml"
    assert main(["plan", "--robot", "ur10", "--cube", "300,-100,300", "--side", "400", "--step", "100",
                 "-o", str(plan)]) == 0
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", "ur10", "--method", "dh", "--folds", "0",
                 "-o", str(model_path), "--report", str(tmp_path / "cal")]) == 1  # --folds 0: verdict not evaluated
    doc = _valid(json.loads((tmp_path / "cal.json").read_text()))
    combinations = doc["parameters"]["combinations"]
    assert any(combination_text(c).startswith("d2 + d3") for c in combinations)
    page = (tmp_path / "cal.html").read_text()
    fixed = {f["name"] for f in doc["parameters"]["fixed"]}
    own = page[page.index("identified on their own"):page.index("Identified only in combination")]
    assert not any(f"<td>{name}</td>" in own for name in fixed)  # no delta of theirs read as the arm's
    # independent check: moving along what a combination leaves out does not move the arm
    model = load_model(model_path)
    joints = read_measurements(meas).joints
    base = fk(model.identified, joints)[:, :3, 3]

    def moved(changes):
        names = list(model.dh_names)
        delta = np.array(model.dh_delta, dtype=float)
        for name, amount in changes.items():
            delta[names.index(name)] += np.radians(amount) if is_angle(name) else amount
        return np.abs(fk(apply_deltas(model.nominal, names, delta), joints)[:, :3, 3] - base).max()

    for name in fixed:  # a fixed parameter moved, and every kept one by what its combination says: no motion
        terms = {c["name"]: term["coefficient"] for c in combinations for term in c["terms"] if term["name"] == name}
        alone = moved({name: 0.1})
        hidden = moved({name: 0.1, **{k: -0.1 * coefficient for k, coefficient in terms.items()}})
        assert hidden < 0.05 * alone or alone < 1e-6, (name, terms, alone, hidden)


def test_tracker_frame_data_show_the_arm_s_combination_the_registration_leaves(tmp_path):
    """With the tracker registration refined too, base z and the turn about it take d1 and theta1; the arm's
    own combination is d2 + d3 + d4 (parallel axes), and it is the virtual arm's true one."""
    from trajcomp.arm.robot import load_robot
    from trajcomp.calibration.virtual_arm import VirtualRobot
    from trajcomp.report.calibration import combination_text

    plan, meas = tmp_path / "plan.csv", tmp_path / "tilted.csv"
    assert main(["plan", "--robot", "ur10", "--cube", "300,-100,300", "--side", "400", "--step", "100",
                 "--orientations", "5", "-o", str(plan)]) == 0
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "--tracker", "2400,-1300,150,175,0,0",
                 "--six-dof", "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", "ur10", "--frame", "tracker", "--folds", "0",
                 "-o", str(tmp_path / "m.yaml"), "--report", str(tmp_path / "cal"), "--json-only"]) == 1  # not evaluated
    params = _valid(json.loads((tmp_path / "cal.json").read_text()))["parameters"]
    assert {f["name"] for f in params["fixed"]} >= {"d1", "theta1", "d3", "d4"}
    assert [combination_text(c) for c in params["combinations"]] == ["d2 + d3 + d4"]
    nominal = load_robot("ur10").as_standard()
    true = VirtualRobot.create(load_robot("ur10"), "paper", seed=1).true_robot.as_standard()
    truth = float(np.sum(true.d[1:4] - nominal.d[1:4]))  # -0.081 mm; the separate deltas are -0.37 to +0.27
    assert params["combinations"][0]["value"] == pytest.approx(truth, abs=0.05)
