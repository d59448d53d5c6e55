"""The example plugin in plugins/trajcomp-points works through the entry-point hook."""

from pathlib import Path

import numpy as np
import pytest
from conftest import install_plugin

from trajcomp import formats
from trajcomp.errors import ReadError

PLUGIN = Path(__file__).resolve().parents[2] / "plugins" / "trajcomp-points"


@pytest.fixture
def points_plugin(monkeypatch):
    """The plugin's entry point, as installing the package would declare it."""
    install_plugin(monkeypatch, PLUGIN, "points", "trajcomp_points")


def test_plugin_reads_writes_and_converts(points_plugin, tmp_path):
    source = tmp_path / "path.pts"
    source.write_text("# exported path\nPTP 600.000 -100.000 500.000 0.000 90.000 0.000\nLIN 650.250 0.000 480.125 10.000 80.000 5.000\n")
    assert "points" in [f.name for f in formats.formats()]
    program = formats.read(source)
    formats.write(tmp_path / "copy.pts", program)
    assert (tmp_path / "copy.pts").read_text() == source.read_text()
    formats.write(tmp_path / "path.csv", program)
    back = formats.read(tmp_path / "path.csv")
    np.testing.assert_allclose(back.cartesian_targets().T, program.cartesian_targets().T, atol=1e-6)


def test_plugin_errors_name_file_and_line(points_plugin, tmp_path):
    bad = tmp_path / "bad.pts"
    bad.write_text("LIN 1 2 3\n")
    with pytest.raises(ReadError, match=r"bad.pts:1: expected PTP\|LIN"):
        formats.read(bad)
