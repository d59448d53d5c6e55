"""Fixtures shared by several test modules."""

import pytest

from trajcomp.cli import main


@pytest.fixture(scope="session")
def kuka_model(tmp_path_factory):
    """A composite model of the virtual KR6 around the example weld path (README commands)."""
    folder = tmp_path_factory.mktemp("kuka")
    plan, meas, model = folder / "plan.csv", folder / "meas.csv", folder / "kuka.yaml"
    assert main(["plan", "--robot", "kuka_kr6_r900", "--cube", "400,-50,650", "--side", "200", "--step", "50",
                 "-o", str(plan)]) == 0
    assert main(["simulate", str(plan), "--robot", "kuka_kr6_r900", "--seed", "1", "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", "kuka_kr6_r900", "--grid-step", "50", "--folds", "0",
                 "-o", str(model)]) == 0
    return model
