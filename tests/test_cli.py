"""The CLI contract: exit codes, outputs, nothing half-written."""

from pathlib import Path

import numpy as np
import pytest
from conftest import real_data

from trajcomp.cli import main
from trajcomp.model.model_file import load_model

UR5_COLUMNS = ",".join([f"j{i}=joint_{i}" for i in range(1, 7)] + ["x=x_t", "y=y_t", "z=z_t",
                        "mx=x_t+x_dif", "my=y_t+y_dif", "mz=z_t+z_dif"])


def test_plan_simulate_calibrate_validate_predict(tmp_path, capsys):
    plan, meas, model = tmp_path / "plan.csv", tmp_path / "meas.csv", tmp_path / "model.yaml"
    assert main(["plan", "--robot", "ur10", "--cube", "300,-100,300", "--side", "400", "--step", "100",
                 "--orientations", "1", "-o", str(plan)]) == 0  # one orientation: a grid model, whose step is checked
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", "ur10", "--grid-step", "100", "-o", str(model)]) == 0
    assert "cross-validation" in capsys.readouterr().out
    per_axis = tmp_path / "per-axis.yaml"
    assert main(["calibrate", str(meas), "--robot", "ur10", "--grid-step", "100,100,100", "--folds", "0",
                 "-o", str(per_axis)]) == 0
    assert main(["calibrate", str(meas), "--robot", "ur10", "--grid-step", "100,100,50", "--folds", "0",
                 "-o", str(per_axis)]) == 2
    assert "differs from the expected (100.000, 100.000, 50.000) mm along z" in capsys.readouterr().err
    second = tmp_path / "run2.csv"
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "--run", "2", "-o", str(second)]) == 0
    assert main(["validate", str(model), str(second), "--tolerance", "0.5"]) == 0
    assert main(["validate", str(model), str(second), "--tolerance", "0.0001"]) == 1
    predicted = tmp_path / "pred.csv"
    assert main(["predict", str(model), str(plan), "-o", str(predicted)]) == 0
    assert "px,py,pz" in predicted.read_text()


def test_a_grid_step_no_lattice_checks_is_said_to_be_unused(tmp_path, capsys):
    """Several orientations give a joint-angle model with a scattered field on top: no lattice for the step."""
    plan, meas, model = tmp_path / "plan.csv", tmp_path / "meas.csv", tmp_path / "model.yaml"
    assert main(["plan", "--robot", "ur10", "--cube", "300,-100,300", "--side", "200", "--step", "100",
                 "-o", str(plan)]) == 0
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", "ur10", "--grid-step", "100", "--folds", "0",
                 "-o", str(model)]) == 0
    warnings = load_model(model).report["warnings"]
    assert any(w.startswith("--grid-step is not used: it checks the nodes of a lattice field") for w in warnings)


def test_unreachable_targets_are_reported_with_exit_1(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    assert main(["plan", "--robot", "ur5", "--cube", "0,0,0", "--side", "2000", "--step", "1000", "-o", str(plan)]) == 1
    assert "unreachable target" in plan.read_text()
    assert "unreachable" in capsys.readouterr().err


def test_bad_input_exits_2_and_leaves_the_output_alone(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("j1,j2,j3,j4,j5,j6,mx,my,mz\n1,2,3,4,5,6,7,8,oops\n")
    out = tmp_path / "model.yaml"
    out.write_text("precious\n")
    assert main(["calibrate", str(bad), "--robot", "ur10", "-o", str(out)]) == 2
    assert "bad.csv:2: field mz" in capsys.readouterr().err
    assert out.read_text() == "precious\n"
    assert main(["plan", "--robot", "no_such_robot", "--cube", "0,0,0", "--side", "1", "--step", "1", "-o", str(out)]) == 2
    assert out.read_text() == "precious\n"


def test_usage_errors_exit_2():
    with pytest.raises(SystemExit) as exit_info:
        main(["plan", "--robot", "ur10", "--cube", "1,2", "--side", "1", "--step", "1", "-o", "x.csv"])
    assert exit_info.value.code == 2


def test_real_ur5_grid_calibrates_far_below_its_raw_error(tmp_path, capsys):
    model = tmp_path / "ur5.yaml"
    assert main(["calibrate", str(real_data("ur5-grid", "grid.csv")), "--robot", "ur5", "--columns", UR5_COLUMNS,
                 "--interpolation", "knn", "-o", str(model)]) == 0
    cv = capsys.readouterr().out.split("cross-validation")[1]
    rows = {line.split()[0]: float(line.split()[2]) for line in cv.splitlines()[2:] if line.strip()}
    assert rows["none"] > 2.0  # 2.63 mm mean as measured
    assert rows["composite"] < 0.12  # best published on these data: 0.155 mm


def test_demo_runs_the_protocol_and_compensates_a_program(tmp_path, capsys):
    assert main(["demo", "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    rows = {tuple(line.split()[:2]): float(line.split()[2]) for line in out.splitlines()
            if line.startswith(("large", "small"))}
    assert {mode for _, mode in rows} == {"none", "linear", "dh", "idw8", "trilinear", "composite"}
    assert rows[("large", "composite")] < rows[("large", "none")] / 20
    for name in ("model-large.yaml", "model-small.yaml", "program.csv", "program-compensated.csv"):
        assert (tmp_path / name).exists()
    planned, compensated = (float(line.split("mean")[1].split()[0]) for line in out.splitlines() if "lands" in line)
    assert compensated < planned / 20


def test_running_a_command_imports_no_other_command(tmp_path):
    """Start-up: `trajcomp formats` and `--version` do not import the calibration or report stack."""
    import subprocess
    import sys

    code = ("import sys\nfrom trajcomp.cli import main\ntry:\n    main({argv})\nfinally:\n"
            "    print(sorted(m for m in sys.modules if m.startswith(('trajcomp.commands.', 'trajcomp.calibration.calibrate', "
            "'trajcomp.report', 'matplotlib', 'scipy.interpolate'))))")
    for argv, allowed in ((["formats"], ["trajcomp.commands._args", "trajcomp.commands.formats"]), (["--version"], [])):
        done = subprocess.run([sys.executable, "-c", code.format(argv=argv)], capture_output=True, text=True)
        assert done.stdout.strip().splitlines()[-1] == str(allowed), (argv, done.stdout, done.stderr)


def test_the_list_of_commands_imports_none_of_them_nor_numpy():
    """`trajcomp --help` lists every command with its one-line help from `trajcomp.commands.COMMANDS` alone."""
    import subprocess
    import sys

    from trajcomp.commands import COMMANDS

    code = ("import sys\nfrom trajcomp.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "print([m for m in sys.modules if m == 'numpy' or m.startswith('trajcomp.commands.')])")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.stdout.strip().splitlines()[-1] == "[]", (done.stdout, done.stderr)
    for name, summary in COMMANDS.items():
        assert f"{name}" in done.stdout and summary in done.stdout


@pytest.mark.parametrize("user_setting, threads", [(None, 1), ("2", 2)])
def test_a_run_computes_on_one_blas_thread_unless_the_user_says(user_setting, threads):
    """The CLI pins BLAS / OpenMP to one thread per process before numpy loads; a user's setting wins."""
    import os
    import subprocess
    import sys

    pytest.importorskip("threadpoolctl")
    code = ("from trajcomp.cli import main\nmain(['formats'])\nimport numpy, threadpoolctl\n"
            "print(sorted({pool['num_threads'] for pool in threadpoolctl.threadpool_info()}))")
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                                             "MKL_NUM_THREADS")}
    if user_setting is not None:
        env.update(OPENBLAS_NUM_THREADS=user_setting, OMP_NUM_THREADS=user_setting)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert done.stdout.strip().splitlines()[-1] == str([threads])


@pytest.mark.parametrize("argv", [
    ["calibrate", "meas.csv", "--robot", "ur10", "--columns", "foo", "-o", "m.yaml"],
    ["calibrate", "meas.csv", "--robot", "ur10", "--interpolation", "bogus", "-o", "m.yaml"],
    ["calibrate", "meas.csv", "--robot", "ur10", "--seed", "-1", "-o", "m.yaml"],
    ["calibrate", "meas.csv", "--robot", "ur10", "--grid-step", "100,100", "-o", "m.yaml"],
    ["plan", "--robot", "ur10", "--cube", "0,0,0", "--side", "100", "--step", "nan", "-o", "p.csv"],
    ["plan", "--robot", "ur10", "--cube", "0,0,0", "--side", "inf", "--step", "10", "-o", "p.csv"],
    ["plan", "--robot", "ur10", "--cube", "0,0,0", "--side", "100", "--step", "10", "--orientations", "0", "-o", "p.csv"],
    ["simulate", "plan.csv", "--robot", "ur10", "--seed", "-1", "-o", "m.csv"],
    ["simulate", "plan.csv", "--robot", "ur10", "--run", "-3", "-o", "m.csv"],
    ["demo", "--seed", "-1", "-o", "demo"],
])
def test_inputs_that_crashed_are_usage_errors(argv, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert "error: argument" in capsys.readouterr().err


def test_an_over_long_csv_field_exits_2_naming_the_line(tmp_path, capsys):
    path = tmp_path / "long.csv"
    path.write_text("j1,j2,j3,j4,j5,j6,mx,my,mz\n1,2,3,4,5,6,7,8," + "9" * 200000 + "\n")
    assert main(["calibrate", str(path), "--robot", "ur10", "-o", str(tmp_path / "m.yaml")]) == 2
    assert "long.csv:2:" in capsys.readouterr().err


def test_tracker_frame_six_dof_data_through_plan_simulate_calibrate_validate_predict(tmp_path, capsys):
    """Several orientations, a tracker frame, orientations measured; then the tracker is moved."""
    plan, meas, model = tmp_path / "plan.csv", tmp_path / "meas.csv", tmp_path / "model.yaml"
    tracker = "2400,-1300,150,175,0.5,-1"
    assert main(["plan", "--robot", "ur10", "--cube", "300,-100,300", "--side", "400", "--step", "100",
                 "--orientations", "5", "-o", str(plan)]) == 0
    assert "the identification needs" in capsys.readouterr().err
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "--tracker", tracker, "--six-dof",
                 "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", "ur10", "--frame", "tracker", "--folds", "0", "-o", str(model)]) == 0
    err = capsys.readouterr().err
    base = [float(v) for v in err.split("base in the tracker frame: ")[1].split("\n")[0].replace(" mm", "")
            .replace(" deg", "").split(",")]
    np.testing.assert_allclose(base, [2400, -1300, 150, 175, 0.5, -1], atol=0.2)  # d1, theta1 trade with z, rz
    assert "other tools: yes" in err
    second = tmp_path / "run2.csv"
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "--run", "2", "--tracker", tracker,
                 "--six-dof", "-o", str(second)]) == 0
    assert main(["validate", str(model), str(second), "--frame", "tracker", "--tolerance", "0.05"]) == 0
    assert "composite orientation |error|" in capsys.readouterr().out
    predicted = tmp_path / "pred.csv"
    assert main(["predict", str(model), str(second), "--frame", "tracker", "-o", str(predicted)]) == 0
    rows = np.genfromtxt([line for line in predicted.read_text().splitlines() if not line.startswith("#")],
                         delimiter=",", names=True)
    landed = np.column_stack([rows["px"] - rows["mx"], rows["py"] - rows["my"], rows["pz"] - rows["mz"]])
    assert np.linalg.norm(landed, axis=1).mean() < 0.03  # predicted in the tracker frame, where it measured
    moved, reference = tmp_path / "moved.csv", tmp_path / "reference.csv"
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "--run", "3",
                 "--tracker=-2000,800,-100,10,0,30", "--six-dof", "-o", str(moved)]) == 0
    lines = moved.read_text().splitlines()
    reference.write_text("\n".join(lines[:2] + lines[2::40]) + "\n")  # a few rows measured in the new placement
    assert main(["validate", str(model), str(moved), "--frame", "tracker", "--tolerance", "0.05"]) == 2
    assert "Or a tracker moved since its registration (--register" in capsys.readouterr().err
    assert main(["validate", str(model), str(moved), "--frame", "tracker", "--register", str(reference),
                 "--tolerance", "0.05"]) == 0


def test_ctrl_c_exits_130_with_a_line_and_no_traceback(tmp_path, monkeypatch, capsys):
    import trajcomp.commands.robots as robots

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(robots, "run", interrupted)
    assert main(["robots"]) == 130
    err = capsys.readouterr().err
    assert err == "trajcomp: interrupted: what was not finished was not written\n"


def _crashing(monkeypatch):
    import trajcomp.commands.robots as robots

    def crash(args):
        raise ZeroDivisionError("x" * 5000)  # an unexpected exception whose text is long

    monkeypatch.setattr(robots, "run", crash)


def test_an_unexpected_exception_exits_3_as_a_bug_with_its_traceback_saved(monkeypatch, capsys):
    _crashing(monkeypatch)
    assert main(["robots"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "this is a bug" in err and "ZeroDivisionError: " + "x" * 200 + "..." in err
    saved = Path(err.rsplit("traceback saved in ", 1)[1].strip())
    assert "Traceback (most recent call last)" in saved.read_text() and "def crash" not in err
    saved.unlink()


def test_debug_prints_the_traceback_of_a_crash(monkeypatch, capsys):
    _crashing(monkeypatch)
    assert main(["--debug", "robots"]) == 3
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err and err.rstrip().endswith("traceback above")


def test_sigterm_exits_143_like_an_interrupt_and_leaves_no_temporary(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    script = (
        "import sys, time\n"
        "import trajcomp.support.atomic as atomic, trajcomp.commands.robots as robots\n"
        "from trajcomp.cli import main\n"
        "def slow():\n"
        "    print('writing', flush=True); yield b'a'; time.sleep(30); yield b'b'\n"
        "robots.run = lambda args: atomic.write_files_atomic({'out.txt': slow()})\n"
        "sys.exit(main(['robots']))\n"
    )
    process = subprocess.Popen([sys.executable, "-c", script], cwd=tmp_path, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    assert process.stdout.readline() == "writing\n"
    time.sleep(0.2)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=20)
    assert process.returncode == 143 and "terminated (SIGTERM)" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def _turn_program(path):
    """A UR10 CSV path whose 4th LIN waypoint declares J6 a turn below where the linear motion reaches it."""
    from trajcomp.arm.kinematics import fk
    from trajcomp.arm.robot import load_robot
    from trajcomp.arm.transforms import matrix_to_pose

    robot = load_robot("ur10")
    q = robot.home + np.linspace(0.0, 0.3, 5)[:, None] * np.array([0.5, -0.2, 0.3, 0.2, 0.3, 0.6])
    declared = q.copy()
    declared[3, 5] -= 2 * np.pi
    poses = matrix_to_pose(fk(robot, q))
    rows = [f"{','.join(f'{v:.6f}' for v in [*p[:3], *np.degrees(p[3:])])},{'PTP,' if k == 0 else 'LIN,100'},"
            + ",".join(f"{v:.6f}" for v in np.degrees(d)) for k, (p, d) in enumerate(zip(poses, declared))]
    path.write_text("x,y,z,a,b,c,motion,speed,j1,j2,j3,j4,j5,j6\n" + "\n".join(rows) + "\n")
    return path


def test_every_stderr_warning_is_in_the_report(tmp_path, capsys):
    """The re-timing's warning of a LIN reaching a waypoint in another turn was on stderr only (`"warnings": []`)."""
    import json

    program = _turn_program(tmp_path / "turn.csv")
    assert main(["retime", str(program), "--robot", "ur10", "-o", str(tmp_path / "out.csv"),
                 "--report", str(tmp_path / "r"), "--json-only"]) == 0
    printed = [line.removeprefix("warning: ") for line in capsys.readouterr().err.splitlines()
               if line.startswith("warning: ")]
    assert printed == ["the linear motion reaches turn.csv:5 with J6 at 7.7 deg, not -352.3 (a linear or circular "
                       "motion turns continuously; the declared turn applies to joint motions)"]
    assert json.loads((tmp_path / "r.json").read_text())["warnings"] == printed


def test_outside_error_names_each_target_by_file_and_line(kuka_model, tmp_path, capsys):
    program = tmp_path / "p.csv"
    program.write_text("x,y,z,a,b,c,motion\n500,50,750,0,90,0,PTP\n500,50,950,0,90,0,LIN\n500,50,700,0,90,0,LIN\n")
    assert main(["compensate", str(program), "--model", str(kuka_model), "--outside", "error",
                 "-o", str(tmp_path / "out.csv")]) == 2
    assert ("p.csv: 1 of 3 targets lie outside the calibrated region (--outside error): p.csv:3: outside the grid"
            in capsys.readouterr().err)
    assert not (tmp_path / "out.csv").exists()


def test_the_output_keeps_the_input_language_unless_to_says_otherwise(kuka_model, tmp_path, capsys):
    """`-o out.src` from a CSV silently wrote KRL."""
    program = tmp_path / "p.csv"
    program.write_text("x,y,z,a,b,c,motion,speed\n500,50,750,0,90,0,PTP,\n520,50,750,0,90,0,LIN,50\n")
    base = ["compensate", str(program), "--model", str(kuka_model), "--retime", "none"]
    assert main(base + ["-o", str(tmp_path / "out.src")]) == 2
    assert ("out.src: '.src' is the extension of krl programs, but the input is a csv program: the output keeps the "
            "input's language (name it *.csv), or give --to krl" in capsys.readouterr().err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.csv"]
    assert main(base + ["-o", str(tmp_path / "out.src"), "--to", "krl"]) == 0
    src = (tmp_path / "out.src").read_text()
    assert src.count("PTP ") == 1 and src.count("LIN ") == 1
    assert "S " in (tmp_path / "out.dat").read_text()  # configuration data computed from the corrected joints
    assert main(base + ["-o", str(tmp_path / "out.script"), "--to", "urscript"]) == 2  # a UR program for a KR6
    assert "a Universal Robots program (urscript) cannot run on robot kuka_kr6_r900" in capsys.readouterr().err


def test_plan_keeps_one_arm_posture_and_lists_the_targets_it_cannot_reach(tmp_path, capsys):
    """7 of the paper cube's 216 targets were silently planned in another arm branch (sign-flipped errors)."""
    from trajcomp.arm.ik import branch_index
    from trajcomp.calibration.measurements import read_measurements
    from trajcomp.arm.robot import load_robot

    plan = tmp_path / "plan.csv"
    assert main(["plan", "--robot", "ur10", "--cube", "300,-100,300", "--side", "500", "--step", "100",
                 "--orientations", "1", "-o", str(plan)]) == 1  # the paper's one orientation
    err = capsys.readouterr().err
    corners = ["800.000,400.000,700.000", "800.000,-100.000,800.000", "800.000,100.000,800.000",
               "800.000,200.000,800.000", "800.000,300.000,800.000", "700.000,400.000,800.000",
               "800.000,400.000,800.000"]
    for corner in corners:
        assert (f"unreachable target {corner} at 90.00,0.00,180.00 deg: not in the grid's arm posture "
                "front/down/negative, only in back/up/negative") in err
    assert "7 of 216 targets are unreachable" in err
    rows = read_measurements(plan)
    assert len(rows) == 209 and set(branch_index(load_robot("ur10"), rows.joints).tolist()) == {3}


def test_motions_left_untimed_are_in_the_report_warnings(tmp_path, capsys):
    """After a motion computed at run time the arm's position is unknown: the next motion is not timed, and says so."""
    import json
    import shutil

    examples = Path(__file__).resolve().parents[1] / "examples" / "programs" / "kuka"
    src = (examples / "weld.src").read_text().replace("  LIN P4\n", "  LIN_REL {Z 10}\n  LIN P4\n")
    (tmp_path / "weld.src").write_text(src)
    shutil.copy(examples / "weld.dat", tmp_path / "weld.dat")
    (tmp_path / "out").mkdir()
    assert main(["retime", str(tmp_path / "weld.src"), "-o", str(tmp_path / "out" / "weld.src"), "--robot",
                 "kuka_kr6_r900", "--report", str(tmp_path / "r"), "--json-only"]) == 0
    printed = [line.removeprefix("warning: ") for line in capsys.readouterr().err.splitlines()
               if line.startswith("warning: ")]
    assert any(w.startswith("not timed (the arm's position before the motion is unknown): motions to P4")
               for w in printed)
    assert json.loads((tmp_path / "r.json").read_text())["warnings"] == printed


# command-line conventions (issue 38)

def test_python_dash_m_trajcomp_runs_the_cli():
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "trajcomp", "--version"], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parents[1])
    assert done.returncode == 0 and done.stdout.startswith("trajcomp ")


def test_exit_codes_are_in_the_help_of_the_tool_and_of_each_command(capsys):
    for argv in (["--help"], ["validate", "--help"], ["compensate", "--help"]):
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        assert exit_info.value.code == 0
        shown = capsys.readouterr().out
        assert "exit codes" in shown and "  2    bad usage or bad input" in shown and "  1    the work ran" in shown


def test_a_mistyped_option_prints_the_usage_of_its_command(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["validate", "model.yaml", "validation.csv", "--tolerence", "0.05"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: trajcomp validate ") and "--tolerance MM" in err
    assert "trajcomp validate: error: unrecognized arguments: --tolerence 0.05" in err


@pytest.fixture(scope="module")
def ur10_run(tmp_path_factory):
    """A UR10 model and a second measuring run of it."""
    folder = tmp_path_factory.mktemp("ur10")
    plan, meas, model, second = (folder / n for n in ("plan.csv", "meas.csv", "model.yaml", "run2.csv"))
    assert main(["plan", "--robot", "ur10", "--cube", "300,-100,300", "--side", "400", "--step", "100",
                 "-o", str(plan)]) == 0
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "-o", str(meas)]) == 0
    assert main(["calibrate", str(meas), "--robot", "ur10", "--grid-step", "100", "--folds", "0",
                 "-o", str(model)]) == 0
    assert main(["simulate", str(plan), "--robot", "ur10", "--seed", "1", "--run", "1", "-o", str(second)]) == 0
    return model, second


@pytest.mark.parametrize("name", ["-", "/dev/stdout"])
def test_validate_json_to_stdout_is_all_stdout_holds(ur10_run, tmp_path, capsys, monkeypatch, name):
    import json

    model, second = ur10_run
    monkeypatch.chdir(tmp_path)
    assert main(["validate", str(model), str(second), "--tolerance", "0.5", "--json", name]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["verdict"]["result"] == "pass"  # the whole of stdout is one JSON document
    assert "|measured - predicted|" in err and "verdict: PASS" in err  # the table and summary on stderr
    assert list(tmp_path.iterdir()) == []  # no file named -


def test_see_the_report_only_when_a_report_was_asked_for(kuka_model, tmp_path, capsys):
    program = tmp_path / "p.csv"
    program.write_text("x,y,z,a,b,c,motion\n500,50,750,0,90,0,PTP\n520,50,750,0,90,0,LIN\n")
    base = ["compensate", str(program), "--model", str(kuka_model), "--retime", "none", "--tolerance", "1e-9"]
    assert main(base + ["-o", str(tmp_path / "a.csv")]) == 1
    err = capsys.readouterr().err
    assert "trajcomp: the program is written but fails its verdict (residual, model_accuracy)\n" in err
    assert "see the report" not in err
    assert main(base + ["-o", str(tmp_path / "b.csv"), "--report", str(tmp_path / "b")]) == 1
    assert "fails its verdict (residual, model_accuracy); see the report" in capsys.readouterr().err


def test_locations_read_file_line_field_message(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("badmeas.csv").write_text("j1,j2,mx\n")
    assert main(["calibrate", "badmeas.csv", "--robot", "ur10", "-o", "m.yaml"]) == 2
    assert "trajcomp: error: badmeas.csv:1: " in capsys.readouterr().err
    Path("nocmd.csv").write_text("mx,my,mz\n1,2,3\n")
    assert main(["calibrate", "nocmd.csv", "--robot", "ur10", "-o", "m.yaml"]) == 2
    assert "trajcomp: error: nocmd.csv:1: need commanded joints" in capsys.readouterr().err
    # convert's warnings name the file of the motion, not a bare line
    weld = (Path(__file__).resolve().parents[1] / "examples" / "programs" / "abb" / "Weld.mod").read_text()
    Path("W.mod").write_text(weld.replace("MODULE Weld", "MODULE Weld\n  PERS speeddata vWeld := [20,500,5000,1000];\n"
                                          "  PERS num nFeed := 20;")  # a PERS num: set at run time
                             .replace("  PROC main()\n", "  PROC main()\n    vWeld.v := nFeed;\n")
                             .replace("MoveL P3, v20", "MoveL P3, vWeld"))
    assert main(["convert", "W.mod", "W.csv", "--robot", "abb_irb4600"]) == 1
    warnings = [line for line in capsys.readouterr().err.splitlines() if line.startswith("trajcomp: warning:")]
    assert warnings[-1] == ("trajcomp: warning: W.mod:14: speed of 'MoveL P3, vWeld, z5, tool0;': vWeld is changed "
                            "at run time (line 11): written at csv's slowest speed, set it before running")
    assert all(line.startswith("trajcomp: warning: W.mod:1") for line in warnings)
    assert main(["convert", "W.mod", "W.src", "--robot", "ur10"]) == 2
    assert "W.src: a KUKA program (krl) cannot run on robot ur10" in capsys.readouterr().err
    assert main(["convert", "W.mod", "W2.mod", "--robot", "ur10"]) == 2
    assert "W2.mod: an ABB program (rapid) cannot run on robot ur10" in capsys.readouterr().err


def test_a_batch_names_each_refused_file_once_and_leaves_no_empty_folder(kuka_model, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for folder in ("progs/good", "progs/bad/deep"):
        Path(folder).mkdir(parents=True)
    Path("progs/good/p.csv").write_text("x,y,z,a,b,c,motion\n500,50,750,0,90,0,PTP\n")
    Path("progs/bad/deep/bad1.csv").write_text("x,y,z,a,b,c\n1,2,3\n")
    assert main(["compensate", "progs", "--model", str(kuka_model), "--retime", "none", "-o", "out/",
                 "--jobs", "1"]) == 2
    err = capsys.readouterr().err
    assert "ERROR progs/bad/deep/bad1.csv:2: expected 6 fields, got 3: '1,2,3'\n" in err
    assert err.count("bad1.csv") == 1
    assert sorted(str(p) for p in Path("out").rglob("*")) == ["out/good", "out/good/p.csv", "out/summary.json"]
    assert main(["compensate", "progs/bad", "--model", str(kuka_model), "-o", "refused/", "--report",
                 "refused/reports", "--jobs", "1"]) == 2
    assert sorted(str(p) for p in Path("refused").rglob("*")) == ["refused/summary.json"]  # no empty report folder


def test_retime_without_a_model_claims_no_tolerance(tmp_path, capsys):
    examples = Path(__file__).resolve().parents[1] / "examples" / "programs" / "abb"
    assert main(["retime", str(examples / "Weld.mod"), "-o", str(tmp_path / "Weld.mod"), "--robot",
                 "abb_irb4600"]) == 0
    err = capsys.readouterr().err
    assert "verdict: PASS: compliance report of Weld.mod" in err and "tolerance" not in err
    unevaluated = [line for line in err.splitlines() if "not evaluated" in line]
    assert unevaluated == ["    --  not evaluated: residual, outside_grid, orientation, tool, posture, uncompensated: "
                           "no compensation model: the program runs as written (retime)"]
    with pytest.raises(SystemExit):
        main(["retime", str(examples / "Weld.mod"), "-o", str(tmp_path / "W.mod"), "--robot", "abb_irb4600",
              "--tolerance", "0.1"])


def test_calibrate_prints_parameters_seen_only_together_as_their_combinations(ur10_run, tmp_path, capsys):
    """d2, d3, d4, a5, theta4 were printed as identified deltas and, on the next line, as not identified."""
    model, _ = ur10_run
    meas = Path(model).parent / "meas.csv"
    assert main(["calibrate", str(meas), "--robot", "ur10", "--grid-step", "100", "--folds", "0",
                 "-o", str(tmp_path / "m.yaml")]) == 0
    lines = {line.split(":")[0]: line for line in capsys.readouterr().err.splitlines()}
    fixed = [item.split(" (")[0] for item in lines["not identified on their own"].split(": ", 1)[1].split("), ")]
    own = [item.split()[0] for item in lines[next(k for k in lines if k.startswith("identified 25 parameters"))]
           .split(": ", 1)[1].split(", ")]
    assert "d3" in fixed and not set(fixed) & set(own)
    assert "d2 + d3" in lines["identified in combination"] and "d2" not in own


def test_another_librarys_log_records_are_printed_from_warning_up_on_one_line():
    import io
    import logging

    from trajcomp.cli import _warnings

    handler = _warnings()
    handler.setStream(io.StringIO())
    nanny, api = logging.Logger("distributed.nanny"), logging.Logger("trajcomp.api")  # apart from the logging tree
    for logger in (nanny, api):  # that other tests' runs configure
        logger.addHandler(handler)
    nanny.info("Start Nanny at: 'tcp://127.0.0.1:41935'")  # as Dask logs at INFO
    try:
        raise RuntimeError("Nanny failed to start worker process")
    except RuntimeError:
        nanny.exception("Failed to start\nworker")
    api.warning("a.csv: 2 of 9 targets lie outside the compensation grid")
    assert handler.stream.getvalue().splitlines() == [
        "trajcomp: warning: distributed.nanny: Failed to start worker (RuntimeError: Nanny failed to start worker process)",
        "trajcomp: warning: a.csv: 2 of 9 targets lie outside the compensation grid",
    ]
