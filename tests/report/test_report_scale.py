"""Compliance report of a long program: verdict and statistics over every target, a bounded table, the sidecar.

A crafted 50,000-target run (a slow sweep of the KR6 R900 with a few targets
made to fail each per-target criterion) is judged; counts, statistics and
flags are checked against numpy computations made here from the run's own
inputs, the document against the shipped schema, its size against a bound.
"""

import json
import re

import jsonschema
import numpy as np
import pytest

from trajcomp.arm.kinematics import fk
from trajcomp.model.model_file import load_model
from trajcomp.compensation.program_rewrite import ProgramReport
from trajcomp.report import compliance_report, schema, summary_lines
from trajcomp.report import per_target, plots
from trajcomp.report.measures import singularity_distances
from trajcomp.report.per_target import FLAGS, ROWS, WORST, TargetMeasures, worst_targets
from trajcomp.arm.robot import load_robot
from trajcomp.timing import Segment

KUKA = load_robot("kuka_kr6_r900")
N = 50_000
RESIDUAL = [10, 20_000, N - 1]
OUTSIDE = list(range(30_000, 30_100))
FLIP, LIMIT, WRIST = 40_000, 123, 7_777
# The failing targets of each per-target criterion (0-based, ascending), as crafted in `_sweep`: the targets outside
# the grid have an estimate above the tolerance (an outside target within it passes), so the landing fails there too.
EXPECTED = {"residual": sorted(RESIDUAL + OUTSIDE), "outside_grid": OUTSIDE, "configuration": [FLIP], "joint_limits": [LIMIT],
            "singularity": [WRIST]}


class Labels:
    """A lazy sequence of labels, as a table-backed program gives them (`ProgramReport.labels`)."""

    def __len__(self):
        return N

    def __getitem__(self, k):
        return f"sweep.csv:{k + 2}"


def _sweep(outside):
    """The crafted run (ProgramReport) with the targets ``outside`` (0-based) outside the grid."""
    k = np.arange(N)
    planned = np.tile(np.radians([0.0, -90.0, 90.0, 0.0, 60.0, 0.0]), (N, 1))
    planned[:, 0] = np.radians(np.linspace(-20.0, 20.0, N))
    planned[:, 4] += np.radians(10.0 * np.sin(k / 700.0))
    planned[LIMIT, 1] = np.radians(44.5)  # 0.5 deg from the A2 limit (45 deg)
    planned[WRIST, 4] = np.radians(2.0)  # 2 deg from the wrist singularity
    q = planned + np.radians(0.01) * np.cos(k / 300.0)[:, None]
    q[FLIP, 3:] = planned[FLIP, 3:] + np.radians([180.0, 0.0, 180.0])  # the same pose, wrist flipped
    q[FLIP, 4] = -planned[FLIP, 4]
    T_target = fk(KUKA, planned)
    correction = np.zeros((N, 6))
    correction[:, 0] = 1.0 + 0.5 * np.sin(k / 1000.0)
    correction[:, 5] = 0.02 * np.cos(k / 900.0)
    T_command = T_target.copy()
    T_command[:, :3, 3] += correction[:, :3]
    residual = 1e-6 * (1.0 + np.sin(k / 50.0) ** 2)
    residual[RESIDUAL] = 0.3
    mask = np.zeros(N, bool)
    mask[outside] = True
    return ProgramReport(
        labels=Labels(), lines=k + 2, tools=(None,) * N, frames=(None,) * N, T_target=T_target,
        T_command=T_command, correction=correction, q=q, q_planned=planned, declared=("",) * N,
        written=("",) * N, posture_source=("previous",) * N, outside_grid=mask, predicted_residual=residual,
        landing=crafted_landing(residual, held_out=np.where(mask, 0.2, 0.02)))


def crafted_landing(residual, held_out=0.02):
    """The landing fields of a crafted run: a held-out error of ``held_out`` mm (one, or (N,)) near the targets."""
    n = len(residual)
    zeros, none = np.zeros(n), np.zeros(n, bool)
    return {"estimate_mm": held_out + residual, "held_out_mm": np.full(n, held_out), "unseen_mm": zeros,
            "orientation_beyond_deg": zeros, "unmeasured_posture": none, "other_tool": none}


@pytest.fixture(scope="module")
def model(kuka_model):
    return load_model(kuka_model)


@pytest.fixture(scope="module")
def sweep(model):
    report = _sweep(OUTSIDE)
    return report, compliance_report(report, KUKA, model=model, mode="composite")


def test_the_verdict_counts_and_names_every_failing_target(sweep):
    report, result = sweep
    criteria = {c["id"]: c for c in result.doc["verdict"]["criteria"]}
    for key, failing in EXPECTED.items():
        assert criteria[key]["status"] == "fail"
        assert criteria[key]["failing"] == len(failing)
        assert criteria[key]["targets"] == [f"sweep.csv:{k + 2}" for k in failing]
    assert criteria["model_accuracy"]["failing"] == 0 and not result.passed
    line = next(text for text in summary_lines(result.doc) if "outside_grid" in text)
    assert "(+94 more)" in line  # 100 outside, 6 named


def test_statistics_cover_every_target(sweep):
    report, result = sweep
    q = np.degrees(report.q)
    lower, upper = np.degrees(KUKA.q_min), np.degrees(KUKA.q_max)
    singular = singularity_distances(KUKA, report.q)
    expected = {
        "correction_mm": np.linalg.norm(report.correction[:, :3], axis=1),
        "correction_deg": np.abs(report.correction[:, 5]),
        "landing_estimate_mm": report.landing["estimate_mm"],
        "held_out_mm": report.landing["held_out_mm"],
        "unseen_mm": report.landing["unseen_mm"],
        "orientation_beyond_deg": report.landing["orientation_beyond_deg"],
        "convergence_mm": report.predicted_residual,
        "limit_distance_deg": np.minimum(q - lower, upper - q).min(axis=1),
        "wrist_deg": np.degrees(np.arcsin(np.abs(np.sin(report.q[:, 4])))),  # axes 4 and 6 meet at A5
        "shoulder_mm": singular["shoulder"],
        "elbow_deg": singular["elbow"],
        "jump_deg": np.abs(np.diff(q, axis=0, prepend=q[:1])).max(axis=1),
    }
    stats = result.doc["summary"]["statistics"]
    assert set(stats) == set(expected)
    for name, values in expected.items():
        s = stats[name]
        p5, median, p95 = np.percentile(values, [5, 50, 95])
        np.testing.assert_allclose([s["min"], s["p5"], s["median"], s["mean"], s["p95"], s["max"]],
                                   [values.min(), p5, median, values.mean(), p95, values.max()], rtol=1e-9,
                                   atol=1e-9, err_msg=name)
        worst = np.argmin(values) if name in ("limit_distance_deg", "shoulder_mm", "elbow_deg", "wrist_deg") \
            else np.argmax(values)
        assert values[s["worst"] - 1] == pytest.approx(values[worst]), name
    assert stats["limit_distance_deg"]["worst"] == LIMIT + 1 and stats["wrist_deg"]["worst"] == WRIST + 1
    summary = result.doc["summary"]
    assert summary["targets"] == N and summary["outside_grid"] == len(OUTSIDE)
    assert summary["correction_max_mm"] == pytest.approx(expected["correction_mm"].max())


def test_the_table_holds_every_flagged_target_and_the_worst(sweep):
    report, result = sweep
    doc = result.doc
    table, rows = doc["target_table"], doc["targets"]
    flagged = sorted({k for failing in EXPECTED.values() for k in failing})
    assert not table["complete"] and table["targets"] == N and table["flagged"] == len(flagged)
    assert table["rows"] == len(rows) <= ROWS
    index = [row["index"] for row in rows]
    assert index == sorted(set(index))
    assert set(k + 1 for k in flagged) <= set(index)
    for row in rows:
        k = row["index"] - 1
        want = [key for key, failing in EXPECTED.items() if k in failing]
        assert row["flags"] == want and row["label"] == f"sweep.csv:{k + 2}"
    assert set(table["worst"]["landing_estimate_mm"][:3]) == {k + 1 for k in RESIDUAL}
    stats = doc["summary"]["statistics"]
    for name, worst in table["worst"].items():  # the worst target of each measure first, every listed one tabulated
        assert worst[0] == stats[name]["worst"] and 1 <= len(worst) <= WORST and set(worst) <= set(index), name
    limit_row = next(row for row in rows if row["index"] == LIMIT + 1)
    assert min(limit_row["limit_distance_deg"]) == pytest.approx(0.5, abs=1e-2)
    assert f"all {len(flagged)} flagged targets" in table["selection"]


def test_the_document_is_valid_and_small_and_the_sidecar_holds_every_target(sweep, tmp_path):
    report, result = sweep
    files = result.write(tmp_path / "sweep", json_only=True)
    assert [f.name for f in files] == ["sweep.json", "sweep.targets.npz"]
    doc = json.loads(files[0].read_text())
    errors = [e.message for e in jsonschema.Draft202012Validator(schema()).iter_errors(doc)]
    assert not errors, errors[:3]
    assert files[0].stat().st_size < 1_000_000
    assert doc["full_data"]["path"] == "sweep.targets.npz" and doc["full_data"]["rows"] == N
    with np.load(files[1]) as data:
        assert set(data.files) == set(doc["full_data"]["arrays"])
        np.testing.assert_array_equal(data["line"], report.lines)
        np.testing.assert_allclose(data["joints_deg"], np.degrees(report.q), atol=1e-4)
        names = list(data["flag_names"])
        assert names == list(FLAGS)
        for key, failing in EXPECTED.items():
            assert np.array_equal(np.flatnonzero(data["flags"] & (1 << names.index(key))), failing), key
        assert data["branch"][FLIP] != data["branch_planned"][FLIP]
        assert np.flatnonzero(data["configuration_changed"]).tolist() == [FLIP]
    assert json.loads(result.json_text())["full_data"]["path"] is None  # to stdout: not written


def test_a_page_of_a_long_program_stays_small(sweep):
    _, result = sweep
    page = result.html_text()
    assert len(page.encode()) < 5_000_000
    assert len(re.findall(r"<svg ", page)) == 4 and "<img " not in page  # drawn as SVG, no matplotlib PNG
    assert "Summarised: " in page and "sweep.targets.npz" not in page  # not written: no sidecar to name
    assert all(f"sweep.csv:{k + 2}<" in page for k in OUTSIDE)  # every flagged target has its row


def test_more_flagged_targets_than_rows_fill_the_table_and_say_so(model):
    outside = list(range(1_000, 1_000 + 3 * ROWS))
    result = compliance_report(_sweep(outside), KUKA, model=model, mode="composite")
    table = result.doc["target_table"]
    criterion = next(c for c in result.doc["verdict"]["criteria"] if c["id"] == "outside_grid")
    assert table["rows"] == ROWS and table["flagged"] == len(outside) + 6
    assert criterion["failing"] == len(outside) and len(criterion["targets"]) == ROWS
    assert f"of the {len(outside) + 6} flagged targets" in table["selection"]


def test_the_envelope_keeps_every_extreme():
    values = np.sin(np.arange(10_001) / 37.0)
    values[4321], values[9999] = 5.0, -7.0
    x, lower, upper = plots.envelope(values, points=100)
    assert len(x) <= 100 and upper.max() == 5.0 and lower.min() == -7.0
    width = -(-len(values) // 100)
    np.testing.assert_array_equal(upper[:-1], values[:width * (len(x) - 1)].reshape(-1, width).max(axis=1))
    assert x[0] == pytest.approx((width + 1) / 2) and x[-1] <= len(values)
    short = np.arange(5.0)
    x, lower, upper = plots.envelope(short, points=100)
    assert x.tolist() == [1, 2, 3, 4, 5] and lower is short and upper is short


def test_the_worst_places_are_separate_local_extremes_worst_first():
    k = np.arange(3_000)
    wave = np.sin(2 * np.pi * k / 100.0)  # 30 crests near k = 25 + 100 i, each a run of near-equal neighbours
    wave[[525, 1_725]] = [3.0, 2.0]
    plateau = np.ones(3_000)
    plateau[[7, 8, 9]] = 0.5  # a plateau of three equally worst targets (a minimum measure)
    values = {name: wave for name in ("correction_mm", "correction_deg", "convergence_mm", "jump_deg")}
    values.update({name: plateau for name in ("limit_distance_deg", "shoulder_mm", "elbow_deg", "wrist_deg")})
    measures = TargetMeasures(values, np.zeros(3_000, np.uint8), np.zeros(3_000, np.uint8), np.zeros(3_000, bool))
    worst = worst_targets(measures, count=5)
    crests = 25 + 100 * np.arange(30)
    expected = [525, 1_725, *sorted(set(crests) - {525, 1_725}, key=lambda c: (-wave[c], c))[:3]]
    assert worst["correction_mm"].tolist() == expected  # one target per crest, not its neighbours
    assert worst["limit_distance_deg"].tolist()[:1] == [7]  # the first of the plateau, as numpy's argmin


def test_a_long_path_keeps_a_marker_near_every_target_and_every_isolated_one():
    from scipy.spatial import cKDTree

    k = np.arange(200_000)
    points = np.c_[500.0 + 80.0 * np.cos(k / 900.0), 150.0 + 80.0 * np.sin(k / 900.0)]  # a circle run ~35 times
    points[123_456] = [900.0, -300.0]  # one target far off the path
    kept = plots.one_per_cell(points, cells=400)
    assert 123_456 in kept and np.all(np.diff(kept) > 0) and len(kept) < 5_000
    cell = (points.max(axis=0) - points.min(axis=0)) / 400
    distance, _ = cKDTree(points[kept]).query(points)
    assert distance.max() <= np.hypot(*cell)  # every target within one raster cell of a drawn marker
    short = points[:plots.POINTS]
    assert plots.one_per_cell(short).tolist() == list(range(plots.POINTS))


def test_the_segments_of_a_program_of_exact_stops_are_counted_and_listed_up_to_the_bound():
    from trajcomp.report.compliance import timing_section
    from trajcomp.report.sections import _timing

    stops = 3 * ROWS  # every motion an exact stop: one segment each
    kinds = np.where(np.arange(stops) % 3 == 0, "ruckig", "toppra")
    segments = tuple(Segment(str(kind), k, k + 1, 0.5 + k % 7, jerk_limited=kind == "ruckig")
                     for k, kind in enumerate(kinds))
    section = timing_section(_timing_result(segments, stops + 1), times=False)
    durations = np.array([s.duration for s in segments])
    assert section["segment_count"] == stops and len(section["segments"]) == ROWS and "t_s" not in section
    assert [s["first"] for s in section["segments"]] == list(range(ROWS))
    for kind in ("ruckig", "toppra"):
        assert section["segments_by_kind"][kind]["count"] == np.count_nonzero(kinds == kind)
        assert section["segments_by_kind"][kind]["duration_s"] == pytest.approx(durations[kinds == kind].sum())
    text = _timing(section)  # the page's timing section
    assert f"… and {stops - 30} more" in text and "toppra 1–2 1.500 s" in text



def test_motions_not_compensated_unused_points_and_joint_targets_are_counted_and_listed_up_to_the_bound(model):
    import dataclasses

    many = ROWS + 500
    report = dataclasses.replace(
        _sweep([]), not_compensated=tuple((k + 9, f"LIN P[{k}]", "run-time position") for k in range(many)),
        unused=tuple(f"U{k}" for k in range(many)), joint_targets=tuple(f"J{k}" for k in range(many)))
    doc = compliance_report(report, KUKA, model=model, mode="composite").doc
    assert doc["summary"]["not_compensated"] == doc["summary"]["unused"] == doc["joint_targets"]["count"] == many
    assert [m["line"] for m in doc["not_compensated"]] == list(range(9, ROWS + 9))
    assert doc["unused"] == [f"U{k}" for k in range(ROWS)] and len(doc["joint_targets"]["labels"]) == ROWS
    uncompensated = next(c for c in doc["verdict"]["criteria"] if c["id"] == "uncompensated")
    assert uncompensated["failing"] == many and uncompensated["lines"] == list(range(9, ROWS + 9))
    assert jsonschema.Draft202012Validator(schema()).is_valid(doc)


def _timing_result(segments, waypoints):
    """A stand-in `trajcomp.timing.result.TimingResult` of ``waypoints`` within the limits."""
    from types import SimpleNamespace

    six = np.ones(6)
    return SimpleNamespace(peak_velocity=six, limit_velocity=2 * six, peak_acceleration=six,
                           limit_acceleration=2 * six, peak_jerk=six, limit_jerk=np.full(6, np.inf),
                           segments=segments, cycle_time=100.0, within_limits=True, peak_speed_ratio=0.0,
                           jerk_limited_segments=sum(s.jerk_limited for s in segments), notices=(),
                           jerk_measured=np.zeros(6, bool), t=np.linspace(0.0, 100.0, waypoints))


def test_the_times_of_a_long_joint_program_go_to_the_sidecar(tmp_path):
    empty = np.zeros((0, 6))
    report = ProgramReport(labels=(), lines=np.zeros(0, int), tools=(), frames=(), T_target=np.zeros((0, 4, 4)),
                           T_command=np.zeros((0, 4, 4)), correction=empty, q=empty, q_planned=empty, declared=(),
                           written=(), posture_source=(), outside_grid=np.zeros(0, bool),
                           predicted_residual=np.zeros(0))  # joint targets only: no Cartesian target
    waypoints = ROWS + 1
    segment = Segment("toppra", 0, waypoints - 1, 100.0)
    result = compliance_report(report, KUKA, timing=_timing_result((segment,), waypoints), command="retime")
    files = result.write(tmp_path / "joints", json_only=True)
    doc = json.loads(files[0].read_text())
    assert "t_s" not in doc["timing"] and doc["target_table"]["complete"] and doc["full_data"]["rows"] == 0
    assert jsonschema.Draft202012Validator(schema()).is_valid(doc)
    with np.load(files[1]) as data:
        np.testing.assert_array_equal(data["t_s"], np.linspace(0.0, 100.0, waypoints))
    short = compliance_report(report, KUKA, timing=_timing_result((segment,), ROWS), command="retime")
    assert len(short.doc["timing"]["t_s"]) == ROWS and short.data is None


def test_the_measures_on_two_processes_equal_those_of_one(sweep, monkeypatch):
    """Blocks split between processes (jumps measured across their boundaries) give the same measures."""
    monkeypatch.setattr(per_target, "BLOCK", 3 * per_target.CHUNK + 5)
    report, _ = sweep
    one, two = per_target.target_measures(report, KUKA, workers=1), per_target.target_measures(report, KUKA, workers=2)
    for name, values in one.values.items():
        np.testing.assert_array_equal(two.values[name], values, err_msg=name)
    for name in ("branch", "branch_planned", "changed"):
        np.testing.assert_array_equal(getattr(two, name), getattr(one, name))
    assert one.changed.tolist().count(True) == 1 and one.changed[FLIP]


def test_without_a_grid_the_box_of_the_measured_positions_counts_outside_for_every_part_of_the_report(model):
    """A mode without a grid (here dh) judges targets against the box of the measured positions: the run the
    compliance report is made from counts those targets outside the grid, so that the criterion, the summary, the
    targets' rows and the figure, which all read it, take the same targets (the summary counted the grid's alone)."""
    from trajcomp.model import landing
    from trajcomp.report.compliance import _outside_measured

    report = _sweep(OUTSIDE)
    beyond = landing.outside_box(report.T_target[:, :3, 3], landing.of_model(model).positions)[1] > 0
    assert 0 < beyond.sum() < N  # the sweep crosses the measured box
    for mode, expected in (("dh", beyond | report.outside_grid), ("composite", report.outside_grid)):
        has_grid = model.error_field(mode) is not None
        counted = _outside_measured(report, model, has_grid).outside_grid
        np.testing.assert_array_equal(counted, expected)
