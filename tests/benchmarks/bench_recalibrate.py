"""Re-calibration benchmark (issue 37): a series A model carried into the UR10's later campaigns (not a timed test).

Run:  python tests/benchmarks/bench_recalibrate.py

Real UR10 of ../shared/data/ur10-ipa (or $TRAJCOMP_DATA/ur10-ipa; skipped where absent). The model is
what a user gets: ``calibrate`` of series A (all 5,892 rows, default
options). Each later campaign (series B: 4 months later, series D: 8
months later, each with the tracker placed anew) is cut into five slabs of
its commanded positions (`trajcomp.calibration.identify.region_folds`); for
each slab, 30 rows of the other four are measured for the update, and the
slab is predicted: held out by region, never interleaved. The 30 rows are
chosen as ``plan --update`` chooses them among the other slabs'
configurations (representative where they identify the update, else
D-optimal) or at random. Per campaign: composite mean |error| of the
held-out slabs with the registration alone (``validate --register``), with
the update's parameters alone and with what ``recalibrate`` writes (the
parameters, and the kriging correction of what they leave at the rows
where it predicts the rows' regions better), the verdict of ``check``, the
parameters updated. Targets: composite mean <= 0.15 mm on each campaign,
never worse than the registration alone.

Then the issue's own wording, "30 rows of the campaign, the rest of it
predicted": 30 random rows (five draws), all other rows of the campaign
predicted. Held out in time (months later, the tracker placed anew) but
not by region: the rest lies between the 30 rows. Shown beside the slabs,
never instead of them.

Then the same-day update: a model of series A's planes x = 650, 850 mm,
updated from 30 rows of its unseen planes x = 750, 950 (chosen the same
way, held out by slab along y within those planes), against the model as
it was (same tracker): target a change of the mean of at most 0.005 mm.

Then the floors: the repeatability of series B from its revisited
configurations, and what a full calibration of each later campaign alone
reaches on the same held-out slabs (the best a model of that campaign's own
rows can do under this protocol; also with bench_accuracy.py ur10fields's
best class on top, a kriging over the joints), and what the series A model's update and
correction reach when fitted on every row of the other slabs, not 30.
"""

import os
import sys
import time
from pathlib import Path

from trajcomp.support.threads import THREAD_VARIABLES

for _name in THREAD_VARIABLES:  # one BLAS / OpenMP thread, as the CLI computes (set before numpy loads)
    os.environ.setdefault(_name, "1")

import numpy as np  # noqa: E402

from trajcomp.arm.robot import load_robot  # noqa: E402
from trajcomp.arm.transforms import abc_to_matrix, pose_to_matrix  # noqa: E402
from trajcomp.calibration import recalibrate  # noqa: E402
from trajcomp.calibration.calibrate import calibrate, commanded, mode_errors, to_base  # noqa: E402
from trajcomp.calibration.identify import region_folds  # noqa: E402
from trajcomp.calibration.layout import Layout, load_layout  # noqa: E402
from trajcomp.calibration.measurements import read_measurements  # noqa: E402
from trajcomp.support.parallel import usable_cores  # noqa: E402
from pose_fields import JointKriging, choose_on_slabs  # noqa: E402  (this folder is on the script's path)

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(os.environ.get("TRAJCOMP_DATA", ROOT.parent / "shared" / "data")) / "ur10-ipa"
LAYOUT = ROOT / "examples" / "columns" / "ur10-ipa.yaml"
UR10_TOOL = pose_to_matrix([0.0, 0.0, 109.0, np.pi / 2, 0.0, 0.0])  # Trafo_TM_F_init.txt, inverted
GOAL = Layout(columns={"x": "Goal x", "y": "Goal y", "z": "Goal z"}, delimiter=";", decimal=",", units={"position": "m"})
CAMPAIGNS = {"series B (4 months later)": "series_B_joint_configurations.csv",
             "series D (8 months later)": "series_D_iso_cubes.csv"}
ROWS = 30
SLABS = 5
TARGET = 0.15  # mm, composite mean on the rest of each campaign
SAME_DAY = 0.005  # mm, the largest change of the mean a same-day update may make


def composite_error(model, joints, position, measured):
    """|measured - composite prediction| (N,) mm of tracker-frame rows under the model's registration."""
    predicted = model.predict("composite", joints, position, outside="clamp")[0]
    return np.linalg.norm(to_base(model.T_tracker_base, measured) - predicted, axis=1)


def update_rows(model, joints, train, how, rng, groups):
    """The rows of ``train`` measured for the update: as ``plan --update`` chooses them, or at random."""
    if how == "random":
        return rng.choice(train, ROWS, replace=False)
    return train[recalibrate.choose_rows(model, joints[train], ROWS, groups, oriented=True)[0]]


def carried(model, meas, how, groups, splits=None):
    """Held-out errors (registration alone, the update's parameters alone, as updated) of a campaign's slabs
    (or of ``splits``: ``[(rows, held)]``, the rows given), with each `Update`."""
    joints, position = commanded(model.nominal, meas)
    rotation = abc_to_matrix(meas.measured_orientation)
    regions, words = region_folds(position, SLABS)
    rng = np.random.default_rng(0)
    errors, updates = {"registered": [], "parameters": [], "updated": []}, []
    for held in regions if splits is None else splits:
        if splits is None:
            rows = update_rows(model, joints, np.setdiff1d(np.arange(len(meas)), held), how, rng, groups)
        else:
            rows, held = held
        result = recalibrate.update(model, joints[rows], position[rows], meas.measured[rows], rotation[rows], groups)
        for key, fitted in (("registered", result.registered.model), ("parameters", result.base.model),
                            ("updated", result.model)):
            errors[key].append(composite_error(fitted, joints[held], position[held], meas.measured[held]))
        updates.append(result)
    return {key: np.concatenate(value) for key, value in errors.items()}, updates, words


def carry(model, meas, how, splits=None):
    """`carried` with all groups, or, where the rows refuse the tool, the groups the refusal advises."""
    try:
        return recalibrate.GROUPS, carried(model, meas, how, recalibrate.GROUPS, splits)
    except recalibrate.UpdateRefused:
        groups = ("registration", "zeros", "scale")  # what the refusal advises: --only without the tool
        return groups, carried(model, meas, how, groups, splits)


def campaign_table(model):
    print(f"\n== series A model ({model.report['measurements']['rows']} rows, composite, cross-validated mean "
          f"{recalibrate.expected_error(model):.4f} mm) carried into later campaigns: {ROWS} rows of the campaign per "
          f"held-out slab ({SLABS} slabs), composite mean |error| mm of the held-out slabs")
    print(f"{'campaign':28s}{'rows chosen':>13s}{'groups':>30s}{'register':>10s}{'params':>8s}{'update':>9s}"
          f"{'applied':>9s}{'corrected':>10s}{'verdicts':>36s}")
    for label, name in CAMPAIGNS.items():
        meas = read_measurements(DATA / name, load_layout(LAYOUT))
        for how in ("plan --update", "random"):
            groups, (errors, updates, words) = carry(model, meas, how)
            row(label, how, groups, errors, updates)
        shown = updates[0].changes()
        print(f"  first slab's update ({words}): " + ", ".join(
            f"{n} {v:+.4f}+-{s:.4f} {u}" for n, v, s, u in shown if not n.startswith("base_")))
    print(f"targets: update mean <= {TARGET} mm, never worse than the registration alone")


def row(label, how, groups, errors, updates):
    """One line of a campaign table: mean |error| registered, parameters alone and updated, what was taken."""
    verdicts = {}
    for result in updates:
        verdicts[result.verdict()[0]] = verdicts.get(result.verdict()[0], 0) + 1
    applied = sum(result.applied == "update" for result in updates)
    corrected = sum(result.correction is not None for result in updates)
    mean, registered = errors["updated"].mean(), errors["registered"].mean()
    flag = "ok" if mean <= TARGET and mean <= registered + 1e-9 else "MISSED"
    print(f"{label:28s}{how:>13s}{','.join(groups):>30s}{registered:10.4f}{errors['parameters'].mean():8.4f}"
          f"{mean:9.4f}{f'{applied}/{len(updates)}':>9s}{f'{corrected}/{len(updates)}':>10s}"
          f"{', '.join(f'{n} {k}' for k, n in verdicts.items()):>36s}  {flag}")


def wording_table(model, draws=5):
    """The issue's wording: 30 random rows of each campaign, all its other rows predicted (held out in time)."""
    print(f"\n== the issue's wording: {ROWS} random rows of the campaign ({draws} draws), every other row of it "
          "predicted (held out in time, not by region: reported beside the slabs, not instead)")
    for label, name in CAMPAIGNS.items():
        meas = read_measurements(DATA / name, load_layout(LAYOUT))
        rng = np.random.default_rng(1)
        splits = []
        for _ in range(draws):
            rows = rng.choice(len(meas), ROWS, replace=False)
            splits.append((rows, np.setdiff1d(np.arange(len(meas)), rows)))
        groups, (errors, updates, _) = carry(model, meas, "random", splits)
        row(label, "random", groups, errors, updates)


def same_day_table(robot, meas_a):
    goal = read_measurements(DATA / "grid_A.csv", GOAL)
    plane = np.round(goal.position[:, 0])
    train, test = np.isin(plane, (650, 850)), np.flatnonzero(np.isin(plane, (750, 950)))
    model = calibrate(robot, meas_a.subset(train), workers=usable_cores())
    held = meas_a.subset(test)
    joints, position = commanded(robot, held)
    rotation = abc_to_matrix(held.measured_orientation)
    regions, words = region_folds(position, SLABS)
    before, after, applied, corrected = [], [], 0, 0
    for slab in regions:
        others = np.setdiff1d(np.arange(len(test)), slab)
        rows = others[recalibrate.choose_rows(model, joints[others], ROWS, oriented=True)[0]]
        result = recalibrate.update(model, joints[rows], position[rows], held.measured[rows], rotation[rows])
        applied += result.applied == "update"
        corrected += result.correction is not None
        before.append(composite_error(model, joints[slab], position[slab], held.measured[slab]))
        after.append(composite_error(result.model, joints[slab], position[slab], held.measured[slab]))
    before, after = np.concatenate(before), np.concatenate(after)
    change = after.mean() - before.mean()
    print(f"\n== same day: model of series A's planes x = 650, 850 mm, updated from {ROWS} rows of its unseen planes "
          f"x = 750, 950 (held out: {words}): composite mean |error| of the held-out "
          f"slabs {before.mean():.4f} mm as it was, {after.mean():.4f} updated (applied on {applied}/{len(regions)}, "
          f"corrected on {corrected}/{len(regions)}); "
          f"change {change:+.4f} mm (target |change| <= {SAME_DAY}) "
          + ("ok" if abs(change) <= SAME_DAY else "MISSED"))


def floor_table(robot, model):
    meas = read_measurements(DATA / CAMPAIGNS["series B (4 months later)"], load_layout(LAYOUT))
    joints, _ = commanded(robot, meas)
    _, index, counts = np.unique(np.round(joints, 4), axis=0, return_inverse=True, return_counts=True)
    index = index.ravel()
    pairs = [np.flatnonzero(index == k)[:2] for k in np.flatnonzero(counts > 1)]
    gaps = np.array([np.linalg.norm(meas.measured[a] - meas.measured[b]) for a, b in pairs])
    print(f"\n== floors: series B revisits {len(pairs)} configurations (same commanded joints, same tracker "
          f"placement): |difference| mean {gaps.mean():.4f} mm, p95 {np.percentile(gaps, 95):.4f}: one visit's "
          f"mean deviation about {gaps.mean() / np.sqrt(2):.4f} mm")
    for label, name in CAMPAIGNS.items():
        meas = read_measurements(DATA / name, load_layout(LAYOUT))
        joints, position = commanded(robot, meas)
        errors = {"dh": [], "composite": [], "kriged": []}
        for held in region_folds(position, SLABS)[0]:
            train = np.setdiff1d(np.arange(len(meas)), held)
            own = calibrate(robot, meas.subset(train), folds=0)
            found = mode_errors(own, joints[held], position[held], to_base(own.T_tracker_base, meas.measured[held]))
            for mode in ("dh", "composite"):
                errors[mode].append(np.linalg.norm(found[mode], axis=1))
            left = mode_errors(own, joints[train], position[train], to_base(own.T_tracker_base,
                                                                            meas.measured[train]))["composite"]
            length, nugget, _ = choose_on_slabs(position[train], joints[train], left)
            field = JointKriging(joints[train], left, length, nugget)
            errors["kriged"].append(np.linalg.norm(found["composite"] - field.evaluate(joints[held]), axis=1))
        print(f"{label}: a full calibration of the campaign's own other slabs ({len(meas)} rows in all) predicts its "
              f"held-out slabs at composite {np.concatenate(errors['composite']).mean():.4f}, dh "
              f"{np.concatenate(errors['dh']).mean():.4f} mm mean; with a kriging over the joints on top (the UR10's "
              f"best class of bench_accuracy.py ur10fields, chosen on slabs of the training rows) "
              f"{np.concatenate(errors['kriged']).mean():.4f}")
        print(f"{label}: the series A model's update and correction fitted on every row of the other slabs instead of "
              f"{ROWS}: held-out slabs at {all_rows_floor(model, meas):.4f} mm mean")


def all_rows_floor(model, meas):
    """Mean |error| mm of a campaign's held-out slabs, the update's parameters and correction fitted on all the
    other slabs' rows: the same model classes with some 20-40 times the rows."""
    joints, position = commanded(model.nominal, meas)
    rotation = abc_to_matrix(meas.measured_orientation)
    errors = []
    for held in region_folds(position, SLABS)[0]:
        train = np.setdiff1d(np.arange(len(meas)), held)
        for groups in (recalibrate.GROUPS, ("registration", "zeros", "scale")):  # the second where the tool is refused
            try:
                fitted = recalibrate.fit(model, joints[train], position[train], meas.measured[train], rotation[train],
                                         recalibrate.parameter_names(groups, tracker=True, oriented=True))
                break
            except recalibrate.UpdateRefused:
                continue
        seen = recalibrate.fit(fitted.model, joints[held], position[held], meas.measured[held], None, ()).residual
        correction = recalibrate.correction(position[train], fitted.residual)
        errors.append(np.linalg.norm(seen - correction.evaluate(position[held]), axis=1))
    return np.concatenate(errors).mean()


def main():
    if not DATA.is_dir():
        print(f"{DATA} not present: skipped")
        return
    robot = load_robot("ur10").replace(T_flange_tool=UR10_TOOL)
    meas_a = read_measurements(DATA / "grid_A.csv", load_layout(LAYOUT))
    start = time.perf_counter()
    model = calibrate(robot, meas_a, workers=usable_cores())
    print(f"series A calibrated in {time.perf_counter() - start:.1f} s")
    campaign_table(model)
    wording_table(model)
    same_day_table(robot, meas_a)
    floor_table(robot, model)


if __name__ == "__main__":
    sys.exit(main())
