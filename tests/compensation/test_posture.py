"""The posture a program declares is the one it is solved, compensated and written in.

References are independent of `trajcomp.compensation.posture`: configuration data are
checked by re-encoding joints with the language's encoder, joints against
forward kinematics, and the singular case against a real IK solve.
"""

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from trajcomp import formats
from trajcomp.compensation import posture
from trajcomp.cli import main
from trajcomp.compensation.target_correction import CompensationResult
from trajcomp.formats.configuration import configuration_data, configuration_for, declared_windows
from trajcomp.errors import CompensationError, IKError
from trajcomp.arm.ik import configuration_of, ik, ik_all
from trajcomp.arm.kinematics import fk
from trajcomp.compensation.program_rewrite import compensate_program
from trajcomp.compensation.posture import planned_joints
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import matrix_to_abc

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "programs"
ROBOTS = {"krl": "kuka_kr6_r900", "rapid": "abb_irb4600", "fanuc_ls": "fanuc_lrmate200id"}


@pytest.mark.parametrize("language", sorted(ROBOTS))
def test_declared_windows_invert_every_encoder(language):
    """Decoding the data of random joints gives back their branch, and windows that hold them only."""
    robot = load_robot(ROBOTS[language])
    rng = np.random.default_rng(3)
    q = rng.uniform(robot.q_min, robot.q_max, (2000, 6))
    q[:500, [0, 3, 5]] = np.round(q[:500, [0, 3, 5]] / (np.pi / 2)) * np.pi / 2  # on code boundaries
    configs = configuration_for(configuration_data(language), robot, q)
    branch, lower, upper = declared_windows(configuration_data(language), configs)
    assert np.array_equal(branch, [c.index for c in configuration_of(robot, q)])
    assert np.all((lower <= q) & (q <= upper))
    # a joint one hair across a finite bound has another code
    for side, bound in ((-1, lower), (1, upper)):
        finite = np.isfinite(bound)
        rows, joints = np.nonzero(finite)
        moved = q[rows].copy()
        moved[np.arange(len(rows)), joints] = bound[rows, joints] + side * 1e-6
        again = configuration_for(configuration_data(language), robot, moved)
        assert all(a != configs[r] for a, r in zip(again, rows))


@pytest.mark.parametrize("block", [7, 16_384])
def test_a_long_undeclared_run_keeps_turning_across_planning_blocks(tmp_path, monkeypatch, block):
    """A tool spun 300 deg about its axis in 31 rows: J6 turns on by each step, through the planning blocks."""
    monkeypatch.setattr(posture, "BLOCK", block)
    robot = load_robot("ur10")
    q0 = np.radians([10.0, -100.0, 100.0, -90.0, 90.0, -150.0])
    step = np.radians(10.0)
    T = fk(robot, q0) @ np.array([_rot_z(k * step) for k in range(31)])
    rows = ["x,y,z,a,b,c"] + [",".join(f"{v:.9f}" for v in [*pose[:3, 3], *np.degrees(matrix_to_abc(pose[:3, :3]))])
                              for pose in T]
    (tmp_path / "spin.csv").write_text("\n".join(rows) + "\n")
    plan = planned_joints(formats.read(tmp_path / "spin.csv"), robot)
    plan_q0 = ik(robot, T[:1], seed=robot.home).q[0]
    assert plan.source == ("home",) + ("previous",) * 30
    assert np.allclose(plan.q[:, :5], plan_q0[:5], atol=1e-6)
    assert np.allclose(np.abs(plan.q[:, 5] - plan_q0[5]), step * np.arange(31), atol=1e-6)  # 300 deg, no unwinding


def test_a_target_visited_again_keeps_the_posture_of_its_first_visit(tmp_path):
    """LIN P1, PTP to a joint target on the other wrist branch, LIN P1 again: P1 is solved once, from home."""
    robot = load_robot("kuka_kr6_r900")
    point = "DECL POS P1={X 500,Y 100,Z 600,A 0,B 90,C 0}"  # no S, T: undeclared
    (tmp_path / "one.dat").write_text(f"DEFDAT one\n{point}\nENDDAT\n")
    (tmp_path / "one.src").write_text("DEF one( )\nLIN P1\nEND\n")
    alone = planned_joints(formats.read(tmp_path / "one.src"), robot)
    q_all, valid = ik_all(robot, alone.T_base_tcp)
    flipped = next(k for k in np.flatnonzero(valid[0]) if k != configuration_of(robot, alone.q[0]).index)
    axes = ",".join(f"A{j + 1} {v:.6f}" for j, v in enumerate(np.degrees(q_all[0, flipped])))
    (tmp_path / "again.dat").write_text(f"DEFDAT again\n{point}\nDECL E6AXIS JB={{{axes}}}\nENDDAT\n")
    (tmp_path / "again.src").write_text("DEF again( )\nLIN P1\nPTP JB\nLIN P1\nEND\n")
    plan = planned_joints(formats.read(tmp_path / "again.src"), robot)
    assert plan.source == ("home",)
    np.testing.assert_allclose(plan.q, alone.q, atol=1e-9)


def _rot_z(angle):
    T = np.eye(4)
    T[:2, :2] = [[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]
    return T


def _stand_in(robot, offset):
    """A ``correct`` that moves every target by ``offset`` (mm) and solves the nominal IK next to the seed."""

    def correct(T, tools, seeds, names):
        command = T.copy()
        command[:, :3, 3] += offset
        q = np.array([ik(robot.replace(T_flange_tool=tool), t[None], seed=s).q[0]
                      for t, tool, s in zip(command, tools, seeds)])
        n = len(T)
        return CompensationResult(command, q, np.tile(offset, (n, 1)), np.zeros(n, bool), np.zeros(n))

    return correct


def _krl(tmp_path, points, body):
    """A KRL program (.src + .dat) of E6POS points ``{name: (x, y, z, a, b, c, s, t)}`` and motion lines."""
    dat = ["DEFDAT post"] + [
        f"DECL E6POS {name}={{X {x},Y {y},Z {z},A {a},B {b},C {c},S {s},T {t}}}"
        for name, (x, y, z, a, b, c, s, t) in points.items()
    ] + ["ENDDAT"]
    (tmp_path / "post.dat").write_text("\n".join(dat) + "\n")
    (tmp_path / "post.src").write_text("\n".join(["DEF post( )", *body, "END"]) + "\n")
    return formats.read(tmp_path / "post.src")


def test_kuka_status_and_turn_choose_the_branch_and_turns(tmp_path):
    """S 6 (wrist negative, elbow down) and T bits: the planned joints encode back to exactly those data."""
    robot = load_robot("kuka_kr6_r900")
    q = np.radians([[20.0, -70.0, 100.0, 30.0, 40.0, -20.0]])
    T = fk(robot, q)[0]
    flipped = q[0] + np.radians([0, 0, 0, -180, 0, 180])  # A4 - 180, A5 negated, A6 + 180: same pose
    flipped[4] = -q[0, 4]
    solutions = [q[0], flipped]
    points = {}
    for k, joints in enumerate(solutions):
        s, t = configuration_for(configuration_data("krl"), robot, joints[None])[0]
        points[f"P{k + 1}"] = (*T[:3, 3], *np.degrees(matrix_to_abc(T[:3, :3])), s, t)
    program = _krl(tmp_path, points, ["PTP P1", "PTP P2"])
    plan = planned_joints(program, robot)
    for k, joints in enumerate(plan.q):
        np.testing.assert_allclose(fk(robot, joints[None])[0], T, atol=1e-6)
        assert configuration_for(configuration_data("krl"), robot, joints[None])[0] == program.targets[plan.index[k]].config
    assert plan.source == ("config", "config")
    assert abs(plan.q[1, 4] + plan.q[0, 4]) < 1e-6  # the second is the flipped wrist


def test_undeclared_targets_follow_the_previous_one_not_home(tmp_path):
    """CSV rows without joints after a row with flipped-wrist joints stay in that posture."""
    robot = load_robot("ur10")
    q0 = np.radians([10.0, -100.0, 100.0, -90.0, 90.0, 200.0])  # wrist flipped w.r.t. home, J6 past 180
    T = fk(robot, np.tile(q0, (4, 1)))
    T[:, 0, 3] += np.array([0.0, 5.0, 10.0, 15.0])
    rows = ["x,y,z,a,b,c,j1,j2,j3,j4,j5,j6"]
    for k, pose in enumerate(T):
        xyzabc = ",".join(f"{v:.6f}" for v in [*pose[:3, 3], *np.degrees(matrix_to_abc(pose[:3, :3]))])
        rows.append(xyzabc + ("," + ",".join(f"{v:.6f}" for v in np.degrees(q0)) if k == 0 else ",,,,,,"))
    path = tmp_path / "p.csv"
    path.write_text("\n".join(rows) + "\n")
    program = formats.read(path)
    plan = planned_joints(program, robot)
    assert plan.source == ("joints", "previous", "previous", "previous")
    home_branch = configuration_of(robot, ik(robot, T[:1], seed=robot.home).q[0]).index
    assert home_branch != configuration_of(robot, q0).index
    assert all(c.index == configuration_of(robot, q0).index for c in configuration_of(robot, plan.q))
    assert np.all(np.abs(plan.q - q0) < np.radians(5.0))  # J6 stays past 180 deg, no unwinding


def test_a_posture_that_cannot_reach_the_target_is_named_with_its_line(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    program = _krl(tmp_path, {"PGOOD": (445, 0, 790, 0, 90, 0, 2, 2), "PFAR": (2445, 0, 790, 0, 90, 0, 2, 2)},
                   ["PTP PGOOD", "PTP PFAR"])
    with pytest.raises(IKError, match=r"PFAR \(post\.dat:3\).*configuration \(2, 2\)"):
        planned_joints(program, robot)


def test_a_correction_that_swings_the_wrist_near_a_singularity_is_refused(tmp_path):
    """Wrist almost straight (A5 = 0.05 deg): a 0.5 mm correction turns A4/A6 by tens of degrees."""
    robot = load_robot("kuka_kr6_r900")
    q = np.radians([[0.0, -80.0, 100.0, 0.0, 0.05, 0.0]])
    T = fk(robot, q)[0]
    s, t = configuration_for(configuration_data("krl"), robot, q)[0]
    program = _krl(tmp_path, {"P1": (*T[:3, 3], *np.degrees(matrix_to_abc(T[:3, :3])), s, t)}, ["PTP P1"])
    offset = np.array([0.0, 0.5, 0.0])
    swing = ik(robot, (T + np.pad(offset[:, None], ((0, 1), (3, 0))))[None], seed=q[0]).q[0] - q[0]
    assert np.degrees(np.abs(swing)).max() > 5.0  # the reference: a real IK solve
    with pytest.raises(IKError, match=r"P1 \(post\.dat:2\): J[46] .* deg"):
        compensate_program(program, _stand_in(robot, offset), robot)
    _, report = compensate_program(program, _stand_in(robot, offset), robot, max_joint_change=np.pi)
    assert report.posture_source == ("config",)


def test_an_implausibly_large_correction_is_refused(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    program = _krl(tmp_path, {"P1": (445, 0, 790, 0, 90, 0, 2, 2), "P2": (445, 0, 770, 0, 90, 0, 2, 2)},
                   ["PTP P1", "LIN P2"])
    with pytest.raises(CompensationError, match=r"2 corrections exceed 10 mm.*P1 \(post\.dat:2\): 15\.00 mm"):
        compensate_program(program, _stand_in(robot, np.array([15.0, 0.0, 0.0])), robot)


# ------------------------------------------------------------------ CLI


def _copy_example(tmp_path):
    for name in ("weld.src", "weld.dat"):
        shutil.copy(EXAMPLES / "kuka" / name, tmp_path / name)
    return tmp_path / "weld.src"


def test_output_over_the_input_is_refused_without_in_place(tmp_path, kuka_model, capsys):
    src = _copy_example(tmp_path)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert main(["compensate", str(src), "--model", str(kuka_model), "-o", str(src)]) == 2
    assert "would overwrite the input" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    (tmp_path / "out").mkdir()
    assert main(["compensate", str(src), "--model", str(kuka_model), "-o", str(tmp_path / "out" / "weld.src")]) == 0
    src.chmod(0o640)
    assert main(["compensate", str(src), "--model", str(kuka_model), "--in-place", "-o", str(src)]) == 0
    assert (tmp_path / "weld.src").read_bytes() == (tmp_path / "out" / "weld.src").read_bytes()
    assert (tmp_path / "weld.dat").read_bytes() == (tmp_path / "out" / "weld.dat").read_bytes()
    assert (src.stat().st_mode & 0o777) == 0o640


def test_motions_computed_at_run_time_are_counted_and_fail_the_exit_code(tmp_path, kuka_model, capsys):
    src = _copy_example(tmp_path)
    text = src.read_text()
    src.write_text(text.replace("END", "LIN P1:{X 10}\nEND", 1) if "LIN P1:" not in text else text)
    code = main(["compensate", str(src), "--model", str(kuka_model), "-o", str(tmp_path / "out.src")])
    err = capsys.readouterr().err
    assert code == 1
    assert "1 of" in err and "motions were not compensated" in err
    assert (tmp_path / "out.src").exists()  # written, and said so


def test_bounds_must_be_positive(tmp_path, kuka_model, capsys):
    src = _copy_example(tmp_path)
    for option in ("--max-joint-change", "--max-correction"):
        with pytest.raises(SystemExit) as exit_info:  # argparse: bad usage
            main(["compensate", str(src), "--model", str(kuka_model), option, "nan", "-o", str(tmp_path / "o.src")])
        assert exit_info.value.code == 2
        assert option in capsys.readouterr().err
    assert not (tmp_path / "o.src").exists()


def test_points_passed_to_routines_are_not_compensated_and_moving_external_axes_are_warned(tmp_path):
    """Nothing silent: a point handed to a routine is listed with its line; a track that moves is said."""
    robot = load_robot("kuka_kr6_r900")
    (tmp_path / "post.dat").write_text(
        "DEFDAT post\n"
        "DECL E6POS P1={X 445,Y 0,Z 790,A 0,B 90,C 0,S 2,T 2,E1 0.0}\n"
        "DECL E6POS P2={X 445,Y 0,Z 770,A 0,B 90,C 0,S 2,T 2,E1 800.0}\n"
        "DECL E6POS P3={X 445,Y 0,Z 750,A 0,B 90,C 0,S 2,T 2,E1 0.0}\n"
        "ENDDAT\n")
    (tmp_path / "post.src").write_text("DEF post( )\nPTP P1\nLIN P2\nGRIP(P3, 1)\nEND\n")
    program = formats.read(tmp_path / "post.src")
    _, report = compensate_program(program, _stand_in(robot, np.array([0.1, 0.0, 0.0])), robot)
    assert [(line, text) for line, text, _ in report.not_compensated] == [(4, "GRIP(P3, 1)")]
    assert "P3" in report.not_compensated[0][2]
    assert len(report.warnings) == 1 and "E1" in report.warnings[0] and "fixed" in report.warnings[0]


def _flipped_weld(tmp_path):
    """The example weld program with every point in the flipped-wrist posture (same poses)."""
    robot = load_robot("kuka_kr6_r900")
    program = formats.read(_copy_example(tmp_path))
    plan = planned_joints(program, robot)
    flipped = plan.q + np.radians([0, 0, 0, -180, 0, 180])
    flipped[:, 4] = -plan.q[:, 4]
    np.testing.assert_allclose(fk(robot, flipped), fk(robot, plan.q), atol=1e-9)
    dat = (tmp_path / "weld.dat").read_text()
    for i, (s, t) in zip(plan.index, configuration_for(configuration_data("krl"), robot, flipped)):
        name = program.targets[i].name
        dat = re.sub(rf"(DECL E6POS {name}=.*?)S \d+,T \d+", rf"\g<1>S {s},T {t}", dat)
    (tmp_path / "weld.dat").write_text(dat)
    return tmp_path / "weld.src"


def test_a_posture_the_calibration_never_measured_fails_the_verdict(tmp_path, kuka_model, capsys):
    """The KR6 was measured wrist-positive only: a wrist-flipped program fails the posture criterion (not the grid's)."""
    from trajcomp.model.model_file import load_model

    model = load_model(kuka_model)
    assert len(model.postures) == 1
    src = _flipped_weld(tmp_path)
    (tmp_path / "out").mkdir()
    assert main(["compensate", str(src), "--model", str(kuka_model), "-o", str(tmp_path / "out" / "weld.src")]) == 1
    err = capsys.readouterr().err
    assert "5 targets in a posture not measured" in err and "posture" in err.splitlines()[-1]
    assert "; 0 outside the grid" in err  # inside the grid box: not reported outside the grid
    assert main(["compensate", str(src), "--model", str(kuka_model), "--outside", "error",
                 "-o", str(tmp_path / "out" / "weld.src")]) == 2
    assert "never measured" in capsys.readouterr().err


def test_the_measured_postures_are_kept_in_the_model_file(tmp_path, kuka_model):
    from trajcomp.model.model_file import load_model, save_model

    model = load_model(kuka_model)
    save_model(tmp_path / "again.yaml", model)
    assert load_model(tmp_path / "again.yaml").postures == model.postures
    text = (tmp_path / "again.yaml").read_text()
    assert "postures:\n- front/up/positive" in text or "postures:\n- front/down/positive" in text


def test_declared_joints_outside_the_limits_are_refused_not_turned(tmp_path):
    """j1 = 3000 deg (wrong unit or robot) is not quietly taken as 3000 - 8 * 360 = 120 deg."""
    path = tmp_path / "p.csv"
    path.write_text("x,y,z,a,b,c,j1,j2,j3,j4,j5,j6\n-688,-163.9,627.1,90,0,180,3000,-90,92,-92,-90,0\n")
    with pytest.raises(IKError, match=r"outside the limits of robot ur10 \(p\.csv:2: joints \[3000\.0, -90\.0"):
        planned_joints(formats.read(path), load_robot("ur10"))


def test_a_ptp_to_xhome_is_a_joint_position_kept_not_a_motion_left_uncompensated(tmp_path):
    robot = load_robot("kuka_kr6_r900")
    program = _krl(tmp_path, {"P1": (445, 0, 790, 0, 90, 0, 2, 2)}, ["PTP XHOME", "PTP P1", "PTP XHOME"])
    _, report = compensate_program(program, _stand_in(robot, np.array([0.1, 0.0, 0.0])), robot)
    assert report.not_compensated == ()
    assert report.joint_targets == ("PTP XHOME (line 2)", "PTP XHOME (line 4)")


def test_a_ptp_to_where_the_arm_is_is_kept_as_a_joint_position(tmp_path):
    """``PTP $AXIS_ACT``, which RoboDK's KRC posts and KUKA's BCO runs start with: kept, not a motion left as
    written (which failed every such program's verdict); ``LIN $POS_ACT`` still is one."""
    robot = load_robot("kuka_kr6_r900")
    program = _krl(tmp_path, {"P1": (445, 0, 790, 0, 90, 0, 2, 2)}, ["PTP $AXIS_ACT", "PTP P1", "LIN $POS_ACT"])
    _, report = compensate_program(program, _stand_in(robot, np.array([0.1, 0.0, 0.0])), robot)
    assert [line for line, _, _ in report.not_compensated] == [4]
    assert report.joint_targets == ("PTP $AXIS_ACT (line 2)",)


def test_a_program_in_metres_is_refused_with_the_unit_named(tmp_path):
    """Positions a thousand times too small all lie inside the robot's base: refused, the unit named."""
    robot = load_robot("ur10")
    T = fk(robot, np.radians([[10.0, -100.0, 100.0, -90.0, 90.0, 0.0], [20.0, -90.0, 90.0, -90.0, 90.0, 0.0]]))
    rows = ["x,y,z,a,b,c"] + [",".join(f"{v:.6f}" for v in [*pose[:3, 3] / 1000.0,
                                                          *np.degrees(matrix_to_abc(pose[:3, :3]))]) for pose in T]
    (tmp_path / "metres.csv").write_text("\n".join(rows) + "\n")
    with pytest.raises(IKError, match=r"metres: every target lies within 10 mm of the robot base origin.*metres\?"):
        planned_joints(formats.read(tmp_path / "metres.csv"), robot)


def test_the_chain_check_answers_as_the_nearest_solution_does():
    """The chain's quick check of a proposal gives the nearest-solution search's answer on every kind of row:
    small steps, another branch nearer, coinciding branches, invalid branches, steps at the joint limits."""
    robot = load_robot("ur10")
    rng = np.random.default_rng(11)
    m, branch = 5000, 3
    proposal = np.cumsum(np.vstack([rng.uniform(-1.0, 1.0, 6), rng.normal(0.0, 1e-3, (m, 6))]), axis=0)
    kind = rng.integers(0, 6, m)
    big = kind == 1  # a step of up to a whole turn
    proposal[1:][big] += rng.uniform(-np.pi, np.pi, (big.sum(), 6))
    at_limit = kind == 2  # a joint on, just inside or just beyond its limit
    joint = rng.integers(0, 6, at_limit.sum())
    proposal[1:][at_limit, joint] = robot.q_max[joint] + rng.choice([-1e-7, 0.0, 1e-10, 1e-7], at_limit.sum())
    q_all = rng.uniform(-np.pi, np.pi, (m, 8, 6))
    q_all[:, branch] = proposal[1:] - 2.0 * np.pi * rng.integers(-1, 2, (m, 6))  # the proposal is a turn of it
    valid = rng.random((m, 8)) > 0.2
    valid[:, branch] |= kind != 3  # kind 3: the proposed branch may be invalid
    nearer = kind == 4  # another branch nearer the previous row
    q_all[nearer, 6] = proposal[:-1][nearer] + 1e-6
    valid[nearer, 6] = True
    same = kind == 5  # another branch coincides with the proposed one (a singular target)
    q_all[same, 1] = q_all[same, branch]
    valid[same, 1] = True
    nearest = posture._nearest(robot, q_all, valid, proposal[:-1])
    expected = np.all(np.abs(nearest - proposal[1:]) < 1e-9, axis=1)
    assert 0.3 < expected.mean() < 0.9  # both answers are asked for
    np.testing.assert_array_equal(posture._nearest_is_proposed(robot, q_all, valid, branch, proposal), expected)


def test_a_program_whose_joints_were_solved_for_another_arm_is_refused_naming_both(tmp_path, capsys):
    """A UR10 program (its targets with the joints its generator solved) compensated with a UR5's model."""
    from conftest import calibrated_model

    model = calibrated_model(tmp_path, "ur5", "250,-100,250", 200, 100)
    ur5, ur10 = load_robot("ur5"), load_robot("ur10")
    rng = np.random.default_rng(4)
    targets = np.tile(fk(ur5, ur5.home), (6, 1, 1))
    targets[:, :3, 3] = np.array([270.0, -80.0, 270.0]) + rng.uniform(0.0, 160.0, (6, 3))
    header = "x,y,z,a,b,c,j1,j2,j3,j4,j5,j6,motion"
    for robot, code in ((ur10, 2), (ur5, None)):
        q = ik(robot, targets, seed=robot.home).q
        np.testing.assert_allclose(fk(robot, q)[:, :3, 3], targets[:, :3, 3], atol=1e-6)
        rows = [",".join(f"{v:.6f}" for v in (*T[:3, 3], *np.degrees(matrix_to_abc(T[:3, :3])), *np.degrees(j)))
                + ",PTP" for T, j in zip(targets, q)]
        program = tmp_path / f"{robot.name}.csv"
        program.write_text("\n".join([header, *rows]) + "\n")
        out = tmp_path / f"{robot.name}-out.csv"
        result = main(["compensate", str(program), "--model", str(model), "-o", str(out), "--retime", "none"])
        message = capsys.readouterr().err
        if code == 2:  # refused, nothing written, both arms named
            assert result == 2 and not out.exists()
            assert "robot ur5's TCP" in message and "fit robot ur10" in message and "ur10.csv:2" in message
        else:  # the same targets with the UR5's own joints: compensated
            assert result in (0, 1) and out.exists()


def test_a_program_in_millimetres_where_metres_are_read_is_refused_with_the_unit_named(tmp_path):
    """A URScript whose poses are written in mm (the language reads metres): every target lies hundreds of the
    arm's reaches away; refused naming the unit, where it said only that the targets cannot be reached."""
    robot = load_robot("ur10")
    T = fk(robot, np.radians([[10.0, -100.0, 100.0, -90.0, 90.0, 0.0], [20.0, -90.0, 90.0, -90.0, 90.0, 0.0]]))
    poses = [f"p[{pose[0, 3]:.3f}, {pose[1, 3]:.3f}, {pose[2, 3]:.3f}, 0.0, 3.1416, 0.0]" for pose in T]
    (tmp_path / "mm.script").write_text("def mm():\n" + "".join(f"  movel({p}, a=1.2, v=0.25)\n" for p in poses)
                                        + "end\n")
    with pytest.raises(IKError, match=r"mm: every target lies .* m or more from robot ur10's shoulder, "
                                      r"\d+ times its reach .*in millimetres where the program's language reads metres"):
        planned_joints(formats.read(tmp_path / "mm.script"), robot)
