"""Measurement CSV: standard layout, column mapping, located errors."""

from pathlib import Path

import numpy as np
import pytest
from conftest import real_data
from scipy.spatial.transform import Rotation

from trajcomp.calibration.layout import Layout, load_layout
from trajcomp.arm.robot import load_robot
from trajcomp.errors import CalibrationError, ReadError
from trajcomp.calibration.measurements import Measurements, parse_mapping, read_measurements, write_measurements


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


def test_a_temperature_column_is_read_by_its_mapping_and_written_back(tmp_path):
    path = write(tmp_path, "j1,j2,j3,j4,j5,j6,mx,my,mz,air\n0,0,0,0,0,0,1,2,3,21.5\n0,0,0,0,0,0,1,2,3,22.25\n")
    assert read_measurements(path).temperature is None  # not a standard column name: never guessed
    meas = read_measurements(path, parse_mapping("temperature=air"))
    np.testing.assert_allclose(meas.temperature, [21.5, 22.25])
    write_measurements(tmp_path / "back.csv", meas)
    np.testing.assert_allclose(read_measurements(tmp_path / "back.csv").temperature, [21.5, 22.25])
    np.testing.assert_allclose(meas.subset([1]).temperature, [22.25])


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


# ------------------------------------------------------------- layouts


def test_layout_file_reads_a_european_export(tmp_path):
    """';' separated, decimal comma, joints in rad, positions in m, measured orientation intrinsic X-Y-Z."""
    layout = write(tmp_path, """
delimiter: ";"
decimal: ","
frame: tracker
columns: {j1: q1, j2: q2, j3: q3, j4: q4, j5: q5, j6: q6, x: gx, y: gy, z: gz,
          mx: px, my: py, mz: pz, mrx: rx, mry: ry, mrz: rz}
units: {joints: rad, position: m}
rotations: {measured_orientation: XYZ}
""", "layout.yaml")
    path = write(tmp_path, "q1;q2;q3;q4;q5;q6;gx;gy;gz;px;py;pz;rx;ry;rz\r\n"
                           "0,5;-1,25;1;0;1,5;0;0,75;-0,5;1,25;750,5;-499,25;1250;10;-20,5;30\r\n")
    meas = read_measurements(path, load_layout(layout))
    np.testing.assert_allclose(meas.joints, [[0.5, -1.25, 1.0, 0.0, 1.5, 0.0]])
    np.testing.assert_allclose(meas.position, [[750.0, -500.0, 1250.0]])
    np.testing.assert_allclose(meas.measured, [[750.5, -499.25, 1250.0]])
    expected = Rotation.from_euler("XYZ", [10, -20.5, 30], degrees=True)
    got = Rotation.from_euler("ZYX", meas.measured_orientation[0])  # A, B, C = intrinsic Z-Y'-X''
    assert (expected.inv() * got).magnitude() < 1e-12
    assert meas.frame == "tracker" and meas.lines.tolist() == [2]


@pytest.mark.parametrize("convention, values", [
    ("xyz", "10,20,30"), ("rotvec", "0.1,-0.2,0.3"), ("quaternion", "0.9,0.1,-0.2,0.3"), ("ZYX", "40,-10,5")])
def test_rotation_conventions_match_scipy(tmp_path, convention, values):
    numbers = [float(v) for v in values.split(",")]
    names = ["a", "b", "c"] if convention != "quaternion" else ["qw", "qx", "qy", "qz"]
    path = write(tmp_path, f"x,y,z,{','.join(names)}\n1,2,3,{values}\n")
    unit = "rad" if convention == "rotvec" else "deg"
    meas = read_measurements(path, Layout(units={"orientation": unit}, rotations={"orientation": convention}))
    if convention == "quaternion":
        expected = Rotation.from_quat(numbers, scalar_first=True)
    elif convention == "rotvec":
        expected = Rotation.from_rotvec(numbers)
    else:
        expected = Rotation.from_euler(convention, numbers, degrees=True)
    assert (expected.inv() * Rotation.from_euler("ZYX", meas.orientation[0])).magnitude() < 1e-12


@pytest.mark.parametrize("text, message", [
    ("columns: {w: a}\n", "unknown field 'w'"),
    ("columns: {x: a, y: a}\n", "fields x and y both read 'a'"),
    ("decimal: ','\ndelimiter: ','\n", "cannot also be the delimiter"),
    ("units: {joints: furlong}\n", "'furlong' is not a unit"),
    ("rotations: {orientation: XYX1}\n", "Euler sequence"),
    ("colums: {x: a}\n", "unknown keys colums"),
    ("frame: world\n", "frame: expected one of base, tracker"),
    ("[1, 2]\n", "expected a mapping"),
])
def test_layout_file_errors_name_the_file_and_key(tmp_path, text, message):
    with pytest.raises(ReadError, match=message):
        load_layout(write(tmp_path, text, "layout.yaml"))


def test_an_over_long_field_is_an_error_not_a_crash(tmp_path):
    for size in (5000, 200000):  # beyond our bound, and beyond the csv module's own limit
        path = write(tmp_path, "j1,j2,j3,j4,j5,j6,mx,my,mz\n1,2,3,4,5,6,7,8," + "9" * size + "\n")
        with pytest.raises(ReadError, match=r"m.csv:2: .*(too long|field larger)"):
            read_measurements(path)


def test_a_zero_quaternion_names_its_line(tmp_path):
    path = write(tmp_path, "x,y,z,qw,qx,qy,qz\n1,2,3,1,0,0,0\n4,5,6,0,0,0,0\n")
    with pytest.raises(ReadError, match=r"m.csv:3: orientation: zero quaternion"):
        read_measurements(path, Layout(rotations={"orientation": "quaternion"}))


EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "columns"


@pytest.mark.parametrize("name, file, rows", [("ur10-ipa", "grid_A.csv", 5892), ("ur5-grid", "grid.csv", 1000)])
def test_the_shipped_layouts_read_the_real_files_as_their_authors_wrote_them(name, file, rows):
    path = real_data(name, file)
    meas = read_measurements(path, load_layout(EXAMPLES / f"{name}.yaml"))
    assert len(meas) == rows and meas.measured.shape == (rows, 3)
    if name == "ur10-ipa":  # line 3 of the file: elbow_joint -1,15395 rad, measurement_z -414,74345 mm
        assert meas.lines[1] == 3 and meas.joints[1, 2] == pytest.approx(-1.15395)
        assert meas.measured[1, 2] == pytest.approx(-414.74345) and meas.frame == "tracker"
    else:  # reached = commanded + difference, as the layout states
        np.testing.assert_allclose(meas.measured[0], [-430.32784075885013 - 2.144122241149887,
                                                      -6.2740647628546 - 3.5212622371454003,
                                                      -98.6368469428076 + 0.8144149428075877])


def test_a_damaged_file_is_refused_at_its_first_bad_row_and_rows_are_bounded(tmp_path, monkeypatch):
    import trajcomp.calibration.measurements as measurements

    path = tmp_path / "headers.csv"
    with open(path, "w") as handle:  # a header repeated: refused at line 2, not once 100,000 rows are in memory
        handle.write("j1,j2,j3,j4,j5,j6\n" * 100_000)
    read = []
    real_rows = measurements._rows

    def counted(*args):
        for row in real_rows(*args):
            read.append(row)
            yield row

    monkeypatch.setattr(measurements, "_rows", counted)
    with pytest.raises(ReadError, match=r"headers\.csv:2: field j1: not a number: 'j1'"):
        read_measurements(path)
    assert len(read) <= 65  # the header and the first block of rows
    path.write_text("j1,j2,j3,j4,j5,j6\n" + "0,1,2,3,4,5\n" * 4)
    with pytest.raises(ReadError, match=r"headers\.csv:5: more than 3 data rows; split the file"):
        read_measurements(path, max_rows=3)
    path.write_text("j1,j2,j3,j4,j5,j6\n" + "0,1,2,3,4,5\n" * 3)
    assert len(read_measurements(path, max_rows=3)) == 3
    assert measurements.read_measurements.__defaults__[1] == measurements.MAX_ROWS == 1_000_000


def test_calibrate_refuses_more_rows_than_it_fits_at_the_first_row_beyond(tmp_path, monkeypatch, capsys):
    import trajcomp.calibration.calibrate as calibration
    from trajcomp.cli import main

    monkeypatch.setattr(calibration, "MAX_ROWS", 5)  # the bound (100,000), read by the command when it runs
    path = tmp_path / "meas.csv"
    path.write_text("# many\nj1,j2,j3,j4,j5,j6,mx,my,mz\n" + "0,-90,90,-90,-90,0,1,2,3\n" * 6 + "0,0,0,0,0,0,x,y,z\n")
    assert main(["calibrate", str(path), "--robot", "ur10", "-o", str(tmp_path / "m.yaml")]) == 2
    err = capsys.readouterr().err  # line 8 is the 6th data row: refused there, line 9 (not numbers) never read
    assert f"{path}:8: more than 5 data rows; calibrate fits at most 5" in err
    assert not (tmp_path / "m.yaml").exists()
    # the library refuses as well (Measurements built in memory)
    path.with_name("seven.csv").write_text("j1,j2,j3,j4,j5,j6,mx,my,mz\n" + "0,-90,90,-90,-90,0,1,2,3\n" * 7)
    with pytest.raises(CalibrationError, match=r"7 measurements; calibrate fits at most 5"):
        calibration.calibrate(load_robot("ur10"), read_measurements(path.with_name("seven.csv")))
