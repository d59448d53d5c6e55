"""Measurement CSV: standard layout, column mapping, located errors."""

import numpy as np
import pytest

from trajcomp.errors import ReadError
from trajcomp.measurements import Measurements, parse_mapping, read_measurements, write_measurements


def write(tmp_path, text, name="m.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_standard_layout_converts_degrees_and_skips_comments(tmp_path):
    path = write(tmp_path, "# a comment\nj1,j2,j3,j4,j5,j6,mx,my,mz\n# another\n90,0,0,0,0,-45,1,2,3\n")
    meas = read_measurements(path)
    np.testing.assert_allclose(meas.joints, [[np.pi / 2, 0, 0, 0, 0, -np.pi / 4]])
    np.testing.assert_allclose(meas.measured, [[1, 2, 3]])
    assert meas.lines.tolist() == [4] and meas.position is None


def test_write_then_read_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    meas = Measurements(joints=rng.uniform(-3, 3, (7, 6)), position=rng.uniform(-900, 900, (7, 3)),
                        orientation=rng.uniform(-3, 3, (7, 3)), measured=rng.uniform(-900, 900, (7, 3)),
                        lines=np.arange(7))
    write_measurements(tmp_path / "out.csv", meas)
    back = read_measurements(tmp_path / "out.csv")
    for field in ("joints", "position", "orientation", "measured"):
        np.testing.assert_allclose(getattr(back, field), getattr(meas, field), atol=1e-6)


def test_column_mapping_with_sums(tmp_path):
    path = write(tmp_path, "x_t,y_t,z_t,x_dif,y_dif,z_dif\n100,200,300,0.5,-0.25,1\n")
    meas = read_measurements(path, parse_mapping("x=x_t,y=y_t,z=z_t,mx=x_t+x_dif,my=y_t+y_dif,mz=z_t-z_dif"))
    np.testing.assert_allclose(meas.measured, [[100.5, 199.75, 299.0]])


@pytest.mark.parametrize(
    "text, message",
    [
        ("j1,j2,j3,j4,j5,j6\n1,2,3,4,5,abc\n", r"m.csv:2: field j6: not a number: 'abc'"),
        ("x,y,z,mx,my,mz\n1,2,3,4,5,nan\n", r"m.csv:2: field mz: not a finite number"),
        ("x,y,z\n1,2\n", r"m.csv:2: expected 3 fields"),
        ("x,y,mx,my,mz\n1,2,3,4,5\n", r"lacks z"),
        ("mx,my,mz\n1,2,3\n", r"need commanded joints"),
        ("x,y,z\n", r"no data rows"),
    ],
)
def test_bad_input_names_file_line_and_field(tmp_path, text, message):
    with pytest.raises(ReadError, match=message):
        read_measurements(write(tmp_path, text))


def test_mapping_errors(tmp_path):
    path = write(tmp_path, "a,b,c\n1,2,3\n")
    with pytest.raises(ReadError, match="no column 'q'"):
        read_measurements(path, {"x": "q", "y": "b", "z": "c"})
    with pytest.raises(ReadError, match="unknown field 'w'"):
        parse_mapping("w=a")
