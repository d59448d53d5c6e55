"""The calibration report's reliability plot: the landing estimate's stated quantile against the true held-out
errors."""

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import chi2

from trajcomp.calibration.calibrate import reliability
from trajcomp.calibration.measurements import read_measurements
from trajcomp.model.model_file import load_model
from trajcomp.report import calibration_report
from test_report_outputs import _self_contained, _valid


def test_a_stated_quantile_that_is_the_true_one_covers_95_percent_and_lies_on_the_diagonal():
    """Errors of a known 3-D Gaussian: their exact 95 % quantile covers 95 % of them in every bin; twice it, all."""
    rng = np.random.default_rng(0)
    sigma = rng.uniform(0.05, 0.06, 40000)  # mm per axis, a different size per row
    true = np.linalg.norm(rng.normal(size=(40000, 3)) * sigma[:, None], axis=1)
    exact = sigma * np.sqrt(chi2.ppf(0.95, 3))
    classes = np.where(np.arange(40000) < 20000, "exact", "twice")
    out = reliability(np.where(classes == "exact", exact, 2 * exact), true, classes, "composite", bins=4)
    assert out["mode"] == "composite" and out["quantile"] == 0.95 and list(out["classes"]) == ["exact", "twice"]
    exact_class, twice_class = out["classes"]["exact"], out["classes"]["twice"]
    assert exact_class["rows"] == 20000 and exact_class["covered"] == pytest.approx(0.95, abs=0.006)
    assert twice_class["covered"] > 0.9999
    for b in exact_class["bins"]:
        assert b["rows"] == 5000 and b["covered"] == pytest.approx(0.95, abs=0.012)
        assert b["true_quantile_mm"] == pytest.approx(b["stated_mm"], rel=0.04)  # near the diagonal
    for b in twice_class["bins"]:
        assert b["true_quantile_mm"] < 0.6 * b["stated_mm"]  # far below it: conservative


def test_bins_are_equal_counts_in_the_order_of_the_stated_quantile():
    stated = np.array([4.0, 1.0, 3.0, 2.0, 5.0])
    true = np.array([1.0, 2.0, 3.5, 1.0, 0.0])
    out = reliability(stated, true, np.array(["k"] * 5), "dh", bins=2)["classes"]["k"]
    assert [b["rows"] for b in out["bins"]] == [3, 2]  # stated 1, 2, 3 then 4, 5
    assert [b["stated_mm"] for b in out["bins"]] == [2.0, 4.5]
    assert [b["covered"] for b in out["bins"]] == pytest.approx([1 / 3, 1.0], abs=1e-4)  # 2 > 1; 1 <= 2, 3.5 > 3
    assert out["bins"][0]["true_quantile_mm"] == pytest.approx(2.0 + 0.9 * (3.5 - 2.0))  # 1, 2, 3.5: at 0.95 * 2
    assert out["covered"] == pytest.approx(3 / 5)


def test_the_calibration_report_plots_the_holdout_classes_of_a_lattice_at_their_stated_quantile(kuka_model):
    """The fixture's grid (one orientation, idw8): node planes held out, each at one step from the fit that
    predicted it inside the lattice (so one stated quantile: that of the interior's RMS), and outer layers."""
    model = load_model(kuka_model)
    meas = read_measurements(Path(kuka_model).parent / "meas.csv")
    report = calibration_report(model, meas)
    doc = _valid(json.loads(report.json_text()))
    r = doc["reliability"]
    assert r["mode"] == model.method == "composite" and list(r["classes"]) == ["node planes", "outer layers"]
    growth = model.report["landing"]["growth"]["composite"]
    interior = growth["rms_mm"] * np.sqrt(chi2.ppf(0.95, 3) / 3.0)  # an isotropic error of that RMS
    planes = r["classes"]["node planes"]
    assert [b["stated_mm"] for b in planes["bins"]] == pytest.approx([interior] * len(planes["bins"]), rel=1e-5)
    assert planes["rows"] + r["classes"]["outer layers"]["rows"] == doc["held_out"]["modes"]["composite"]["n"]
    layers = r["classes"]["outer layers"]["bins"]
    assert min(b["stated_mm"] for b in layers) > interior  # beyond the fit's box the stated quantile grows
    assert "reliability" in [f.section for f in report.figures]
    page = report.html_text()
    assert '<section id="reliability">' in page and len(_self_contained(page)) == len(report.figures)


def test_the_plot_draws_each_bin_and_turns_to_log_axes_when_its_values_span_a_decade():
    from trajcomp.report import plots

    def data(far):
        bins = [{"rows": 10, "stated_mm": s, "true_quantile_mm": t, "covered": 1.0}
                for s, t in ((0.1, 0.09), (far, 0.5))]
        return {"mode": "dh", "quantile": 0.95, "classes": {"k": {"rows": 20, "covered": 1.0, "bins": bins}}}

    for far, scale in ((0.6, "linear"), (1.6, "log")):
        ax = plots.reliability(data(far)).axes[0]
        assert ax.get_xscale() == ax.get_yscale() == scale
        np.testing.assert_allclose(ax.collections[0].get_offsets(), [[0.1, 0.09], [far, 0.5]])
        assert ax.get_xlim()[1] >= far and ax.get_ylim() == ax.get_xlim()  # square, the diagonal through both
