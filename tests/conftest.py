"""Fixtures shared by several test modules."""

import importlib.metadata
import os
import sys
from pathlib import Path

from trajcomp.support.threads import THREAD_VARIABLES

for _name in THREAD_VARIABLES:  # one BLAS thread per test worker, as the CLI runs (set before numpy loads): the
    os.environ.setdefault(_name, "1")  # in-process commands with OpenBLAS's threads beside the other worker's pools
    # made the suite's CPU time vary from 9 to 12 minutes

import pytest  # noqa: E402

from trajcomp import formats  # noqa: E402
from trajcomp.cli import main  # noqa: E402


REAL_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"  # beside the clone, not in it
REAL_DATA_SOURCES = {  # a folder of shared/data: where its data come from (the tests skip without them)
    "ur5-grid": "a UR5's 1,000 laser-tracker grid poses, UR5/3D_UR5_uncalibrated_grid_cleaned.csv of the public "
                "repository pauljac7700/serial_robots_datasets (MIT)",
    "ur10-ipa": "a UR10's laser-tracker measurements at 23 tool orientations, Series_A of the public repository "
                "christianlandgraf/ipa-robot-accuracy (MIT)",
}
DATA_HOME = "a folder shared/data beside the clone (the data are not part of the repository)"


def real_data(name, file):
    """The path of ``file`` of the real data set ``name``; the test is skipped, saying where the data come
    from, when it is absent."""
    path = REAL_DATA / name / file
    if not path.exists():
        pytest.skip(f"needs the real data {name}/{file}: {REAL_DATA_SOURCES[name]}, in {DATA_HOME}")
    return path


def install_plugin(monkeypatch, folder, name, module):
    """Make a plugin in ``folder`` importable and declare its entry point, as installing it would.

    The format registry is restored when the test ends.
    """
    monkeypatch.syspath_prepend(str(folder))
    monkeypatch.delitem(sys.modules, module, raising=False)
    entry = importlib.metadata.EntryPoint(name, module, formats.ENTRY_POINT_GROUP)
    monkeypatch.setattr(formats, "entry_points", lambda group: [entry] if group == formats.ENTRY_POINT_GROUP else [])
    monkeypatch.setattr(formats, "_FORMATS", dict(formats._FORMATS))
    monkeypatch.setattr(formats, "_PLUGINS", {"loaded": False, "failed": {}})


def calibrated_model(folder, robot, corner, side, step, folds=3, orientations="1"):
    """A composite model of the virtual ``robot`` (seed 1) calibrated on the cube at ``corner`` ("x,y,z", mm) of
    ``side`` and ``step`` mm with ``folds`` folds through the CLI, as the README runs it: the model file
    ``model.yaml`` in ``folder``.

    ``orientations`` is `trajcomp plan --orientations`: by default the paper's one orientation, a grid
    model over positions, for the tests of programs, reports and timing, which are not about tilted
    targets (the default plan's five orientations: ``"auto"``, as `test_cli` runs them).
    """
    plan, meas, model = folder / "plan.csv", folder / "meas.csv", folder / "model.yaml"
    assert main(["plan", "--robot", robot, f"--cube={corner}", "--side", str(side), "--step", str(step),
                 "--orientations", orientations, "-o", str(plan)]) == 0
    assert main(["simulate", str(plan), "--robot", robot, "--seed", "1", "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", robot, "--grid-step", str(step), "--folds", str(folds),
                 "-o", str(model)]) == 0
    return model


@pytest.fixture(scope="session")
def kuka_model(tmp_path_factory):
    """A composite model of the virtual KR6 around the example weld path (README commands)."""
    return calibrated_model(tmp_path_factory.mktemp("kuka"), "kuka_kr6_r900", "400,-50,650", 200, 50)


@pytest.fixture(scope="session")
def fanuc_model(tmp_path_factory):
    """A composite model of the virtual LR Mate 200iD (a 200 mm cube at 50 mm steps)."""
    return calibrated_model(tmp_path_factory.mktemp("fanuc"), "fanuc_lrmate200id", "300,-100,300", 200, 50)


@pytest.fixture(scope="session")
def abb_model(tmp_path_factory):
    """A composite model of the virtual IRB 4600 (a 400 mm cube at 100 mm steps around the test modules' points)."""
    return calibrated_model(tmp_path_factory.mktemp("abb"), "abb_irb4600", "1050,-50,950", 400, 100)


@pytest.fixture
def makerless(tmp_path):
    """``makerless(name)``: the path of a copy of built-in robot ``name`` whose description names no maker.

    Any language's program may run on such an arm (`trajcomp.formats.check_robot_language`): for tests of a
    language's writing and timing on one geometry, where a KUKA arm would run no URScript.
    """
    from importlib import resources

    def copy(name):
        text = resources.files("trajcomp.arm.robots").joinpath(f"{name}.yaml").read_text(encoding="utf-8")
        path = tmp_path / f"{name}-makerless.yaml"
        path.write_text("".join(line for line in text.splitlines(keepends=True) if not line.startswith("vendor:")))
        return str(path)

    return copy
