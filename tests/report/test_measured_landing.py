"""`compensate --measured`: a validation run's measured landings beside the landing estimates in the compliance
report."""

import json
from pathlib import Path

import numpy as np
import pytest

from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import pose_to_matrix
from trajcomp.calibration.virtual_arm import VirtualRobot
from trajcomp.cli import main
from test_report_outputs import _valid

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "programs" / "kuka" / "weld.src"


@pytest.fixture(scope="module")
def run(kuka_model, tmp_path_factory):
    """The weld program compensated, and a validation run of it on the virtual arm the model was measured on
    (``simulate --seed 1``): every target but one measured, as j1..j6 as written and mx, my, mz (a row measures
    every target written with its joints: the weld starts and ends at one point)."""
    folder = tmp_path_factory.mktemp("measured")
    assert main(["compensate", str(EXAMPLE), "--model", str(kuka_model), "-o", str(folder / "weld.src"),
                 "--retime", "none", "--report", str(folder / "plain")]) == 0
    targets = json.loads((folder / "plain.json").read_text())["targets"]
    joints = np.array([t["joints_deg"] for t in targets])
    arm = VirtualRobot.create(load_robot("kuka_kr6_r900"), "paper", 1)
    noise = np.random.default_rng(3).normal(0.0, 0.003, (len(joints), 3))  # the tracker's
    landed = arm.reached_poses(np.radians(joints))[:, :3, 3] + noise
    skipped = next(k for k in range(len(joints)) if (np.abs(joints - joints[k]).max(axis=1) < 0.01).sum() == 1)
    measured = np.arange(len(joints)) != skipped
    rows = ["j1,j2,j3,j4,j5,j6,mx,my,mz"] + [",".join(f"{v:.6f}" for v in (*q, *m))
                                             for q, m in zip(joints[measured], landed[measured])]
    (folder / "run.csv").write_text("\n".join(rows) + "\n")
    same = np.abs(joints[:, None] - joints[None]).max(axis=2) < 0.01  # (N, N): one command
    assert same.sum() > len(joints)  # a command measured twice
    landed = (same & measured) @ landed / np.maximum((same & measured).sum(axis=1), 1)[:, None]  # its rows' mean
    target = np.array([pose_to_matrix(np.r_[t["target"][:3], np.radians(t["target"][3:])])[:3, 3] for t in targets])
    expected = np.linalg.norm(landed - target, axis=1)
    expected[skipped] = np.nan
    return folder, targets, expected


def test_the_measured_landing_of_each_target_is_its_distance_from_where_the_run_measured_it(run, kuka_model, capsys):
    folder, plain, expected = run
    assert main(["compensate", str(EXAMPLE), "--model", str(kuka_model), "-o", str(folder / "weld.src"),
                 "--retime", "none", "--measured", str(folder / "run.csv"), "--report", str(folder / "rep")]) == 0
    assert "pass  measured        largest measured landing" in capsys.readouterr().err
    doc = _valid(json.loads((folder / "rep.json").read_text()))
    shown = np.array([np.nan if t["measured_landing_mm"] is None else t["measured_landing_mm"] for t in doc["targets"]])
    np.testing.assert_allclose(shown, expected, atol=2e-5)  # NaN (not measured) where expected
    seen = np.isfinite(expected)
    estimate = np.array([t["landing_estimate_mm"] for t in plain])[seen]
    m = doc["measured"]
    assert m["targets"] == len(plain) - 1 and m["max_mm"] == pytest.approx(expected[seen].max(), abs=2e-5)
    assert m["covered"] == pytest.approx(np.mean(estimate >= expected[seen]), abs=1e-9)
    assert m["sharpness"] == pytest.approx(np.median(estimate / expected[seen]), rel=1e-3)
    assert [f["path"] for f in doc["provenance"]["files"] if f["role"] == "validation run"] == [str(folder / "run.csv")]
    page = (folder / "rep.html").read_text()
    header = page[page.index("<h3>Landing estimates"):].split("</thead>")[0]
    columns = [c.split(">", 1)[1] for c in header.split("</th>")[:-1]]
    assert columns[3:5] == ["landing estimate mm", "measured landing mm"]
    assert f"{len(plain) - 1} of {len(plain)} targets" in page


def test_a_measured_landing_above_the_tolerance_fails_and_a_row_of_other_joints_is_refused(run, kuka_model, capsys):
    folder, plain, expected = run
    tolerance = float(np.nanmean(expected))  # some measured landings above it, some not
    argv = ["compensate", str(EXAMPLE), "--model", str(kuka_model), "-o", str(folder / "weld.src"), "--retime", "none",
            "--measured", str(folder / "run.csv"), "--json-only", "--report", str(folder / "tight")]
    assert main([*argv, "--tolerance", f"{tolerance:.6f}"]) == 1
    criteria = {c["id"]: c for c in json.loads((folder / "tight.json").read_text())["verdict"]["criteria"]}
    worst = np.flatnonzero(expected > tolerance)
    assert criteria["measured"]["status"] == "fail" and criteria["measured"]["failing"] == len(worst)
    assert criteria["measured"]["targets"] == [plain[k]["label"] for k in worst]
    capsys.readouterr()
    text = (folder / "run.csv").read_text().splitlines()
    (folder / "other.csv").write_text("\n".join([*text, "1,2,3,4,5,6,400,0,600"]) + "\n")
    argv[argv.index(str(folder / "run.csv"))] = str(folder / "other.csv")
    assert main(argv) == 2
    assert f"other.csv:{len(text) + 1}: j1..j6: no target of the program was written with these joints" in (
        capsys.readouterr().err)
