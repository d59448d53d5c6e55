"""Inverse kinematics: round trips on every branch, branch choice, limits, failures, refinement."""

import functools

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from trajcomp.errors import IKError
from trajcomp.arm.ik import (
    POS_TOL,
    ROT_TOL,
    Configuration,
    IKResult,
    configuration_of,
    ik,
    ik_all,
    ik_family,
    ik_near,
    ik_numeric,
)
from trajcomp.arm.kinematics import fk, jacobian, link_frames
from trajcomp.arm.robot import builtin_robot_names, load_robot
from trajcomp.arm.transforms import rotation_angle_between

ROBOTS = builtin_robot_names()
SPHERICAL = ["kuka_kr6_r900", "abb_irb4600", "fanuc_lrmate200id"]


@functools.cache
def robot_named(name):
    return load_robot(name)


def random_q(robot, n, seed, margin=0.0):
    """Uniform joint angles (n, 6), rad, at least ``margin`` rad inside the limits."""
    return np.random.default_rng(seed).uniform(robot.q_min + margin, robot.q_max - margin, (n, 6))


def pose_errors(T_a, T_b):
    """Position (mm) and orientation (rad) differences of pose stacks."""
    return np.linalg.norm(T_a[..., :3, 3] - T_b[..., :3, 3], axis=-1), rotation_angle_between(
        T_a[..., :3, :3], T_b[..., :3, :3]
    )


def perturbed(robot, seed, length=0.5, angle=np.radians(0.05)):
    """An 'identified' arm: the nominal one with random DH deltas (mm, rad)."""
    rng = np.random.default_rng(seed)
    return robot.replace(
        a=robot.a + rng.normal(0, length, 6),
        d=robot.d + rng.normal(0, length, 6),
        alpha=robot.alpha + rng.normal(0, angle, 6),
        theta_offset=robot.theta_offset + rng.normal(0, angle, 6),
        beta=rng.normal(0, angle, 6),
    )


def well_conditioned(robot, q, ratio=0.05):
    """Mask of configurations away from singularities (scaled Jacobian's inverse condition number)."""
    sv = np.linalg.svd(jacobian(robot, q) * np.array([1, 1, 1, 1000, 1000, 1000])[:, None], compute_uv=False)
    return sv[:, -1] > ratio * sv[:, 0]


# ---------------------------------------------------------------- families


def test_families_of_the_builtin_arms():
    assert {name: ik_family(robot_named(name)) for name in ROBOTS} == {
        "abb_irb4600": "spherical",
        "fanuc_lrmate200id": "spherical",
        "kuka_kr6_r900": "spherical",
        "ur10": "ur",
        "ur5": "ur",
    }


@pytest.mark.parametrize("name", ROBOTS)
def test_identified_models_leave_the_family(name):
    assert ik_family(perturbed(robot_named(name), 0)) is None


def test_modified_table_gets_the_closed_form():
    kuka = robot_named("kuka_kr6_r900")
    modified = kuka.replace(convention="modified", a=np.r_[0.0, kuka.a[:5]], alpha=np.r_[0.0, kuka.alpha[:5]])
    assert ik_family(modified) == "spherical"
    q = random_q(kuka, 1000, 7)
    result = ik(modified, fk(kuka, q), seed=q)
    assert result.success.all()
    np.testing.assert_allclose(result.q, q, atol=1e-9)


# ---------------------------------------------------------------- round trips


@pytest.mark.parametrize("name", ROBOTS)
def test_round_trip_every_branch(name):
    robot = robot_named(name)
    q = random_q(robot, 10_000, 1)
    T = fk(robot, q)
    q_all, valid = ik_all(robot, T, seed=q)
    assert q_all.shape == (10_000, 8, 6) and valid.shape == (10_000, 8)

    # every valid branch reaches the pose, inside the limits
    pos, rot = pose_errors(fk(robot, q_all[valid]), np.broadcast_to(T[:, None], valid.shape + (4, 4))[valid])
    assert pos.max() < POS_TOL and rot.max() < ROT_TOL
    assert robot.within_limits(q_all[valid]).all()
    assert valid.sum(axis=1).min() >= 1

    # the original joints are the branch of their own configuration, turned to the seed exactly
    index = np.array([c.index for c in configuration_of(robot, q)])
    rows = np.arange(len(q))
    assert valid[rows, index].all()
    np.testing.assert_allclose(q_all[rows, index], q, atol=1e-7)

    # and every branch has the configuration of its number
    branch = np.broadcast_to(np.arange(8), valid.shape)[valid]
    assert np.array_equal([c.index for c in configuration_of(robot, q_all[valid])], branch)


@pytest.mark.parametrize("name", ROBOTS)
def test_single_pose(name):
    robot = robot_named(name)
    T = fk(robot, robot.home)
    result = ik(robot, T)
    assert result.q.shape == (1, 6) and result.success[0]
    np.testing.assert_allclose(result.q[0], robot.home, atol=1e-9)
    assert ik_all(robot, T)[0].shape == (1, 8, 6)


# ---------------------------------------------------------------- branch choice


@pytest.mark.parametrize("name", ROBOTS)
def test_seed_picks_the_nearest_valid_branch(name):
    robot = robot_named(name)
    rng = np.random.default_rng(2)
    q = random_q(robot, 2000, 2)
    T = fk(robot, q)
    seed = np.clip(q + rng.normal(0, 0.5, q.shape), robot.q_min, robot.q_max)
    weights = np.array([3.0, 2.0, 2.0, 1.0, 1.0, 0.5])
    result = ik(robot, T, seed=seed, weights=weights)
    q_all, valid = ik_all(robot, T, seed=seed)
    distance = np.where(valid, (((q_all - seed[:, None]) ** 2) @ weights), np.inf)
    assert result.success.all()
    np.testing.assert_allclose(((result.q - seed) ** 2) @ weights, distance.min(axis=1), rtol=1e-9, atol=1e-12)

    # away from singularities (where branches meet) a seed near the joints returns them
    regular = well_conditioned(robot, q)
    q, T = q[regular], T[regular]
    near = ik(robot, T, seed=np.clip(q + rng.normal(0, 1e-3, q.shape), robot.q_min, robot.q_max))
    np.testing.assert_allclose(near.q, q, atol=1e-7)


@pytest.mark.parametrize("name", ROBOTS)
def test_config_selects_the_branch(name):
    robot = robot_named(name)
    q = random_q(robot, 500, 3)
    T = fk(robot, q)
    _, valid = ik_all(robot, T, seed=q)
    for index in range(8):
        config = Configuration.from_index(index)
        result = ik(robot, T, seed=q, config=config)
        np.testing.assert_array_equal(result.success, valid[:, index])
        assert {c.index for c in configuration_of(robot, result.q[result.success])} <= {index}
        assert set(result.reason[~result.success]) <= {"joint limits", "unreachable"}
    per_target = [Configuration.from_index(i) for i in np.arange(len(q)) % 8]
    mixed = ik(robot, T, seed=q, config=per_target)
    np.testing.assert_array_equal(mixed.success, valid[np.arange(len(q)), np.arange(len(q)) % 8])


def test_configuration_flags_and_index():
    for index in range(8):
        assert Configuration.from_index(index).index == index
    assert Configuration("back", "down", "negative").index == 7
    assert str(Configuration()) == "front/up/positive"
    with pytest.raises(IKError, match="elbow"):
        Configuration("front", "high", "positive")
    with pytest.raises(IKError):
        Configuration.from_index(8)


def test_configuration_of_known_poses():
    kuka = robot_named("kuka_kr6_r900")
    # home, tool down: in front of A1, elbow up, A5 > 0
    assert configuration_of(kuka, np.radians([0, -90, 90, 0, 90, 0])) == Configuration("front", "up", "positive")
    assert configuration_of(kuka, np.radians([0, -90, 90, 0, -30, 0])).wrist == "negative"
    # upper arm leaning back 60 deg beyond the vertical: the wrist centre is behind A1
    assert configuration_of(kuka, np.radians([0, -150, 60, 0, 30, 0])).shoulder == "back"
    # upper arm nearly level, forearm raised steeply: the elbow is below the line shoulder-wrist
    assert configuration_of(kuka, np.radians([0, -10, -60, 0, 30, 0])).elbow == "down"


# ---------------------------------------------------------------- turns and limits


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-2 * np.pi, 2 * np.pi), min_size=6, max_size=6),
    st.lists(st.floats(-2 * np.pi, 2 * np.pi), min_size=6, max_size=6),
)
@example([0.0, 3.0, 2.0, 1e-09, 3.0, 0.0], [0.0, 0.0, 0.0, 4.0, 0.0, 0.0])  # 1e-9 + 2 pi rounded an ulp beyond 2 pi
def test_ur_turns_stay_inside_limits_and_nearest_the_seed(q, seed):
    robot = robot_named("ur5")
    q, seed = np.array(q), np.array(seed)
    q_all, valid = ik_all(robot, fk(robot, q), seed=seed)
    turned = q_all[valid]
    assert robot.within_limits(turned).all()
    for shift in (-2 * np.pi, 2 * np.pi):
        other = turned + shift
        inside = (other >= robot.q_min) & (other <= robot.q_max)
        assert np.all(~inside | (np.abs(turned - seed) <= np.abs(other - seed) + 1e-9))


def test_ur_keeps_multi_turn_values_near_the_seed():
    robot = robot_named("ur10")
    q = np.radians([300.0, -200.0, 100.0, 250.0, -300.0, 350.0])
    T = fk(robot, q)
    np.testing.assert_allclose(ik(robot, T, seed=q + 0.1).q[0], q, atol=1e-9)
    other_turn = q - np.radians([360, -360, 0, 360, -360, 360])
    np.testing.assert_allclose(ik(robot, T, seed=other_turn).q[0], other_turn, atol=1e-9)


def test_limits_exclude_branches():
    kuka = robot_named("kuka_kr6_r900")
    narrow = kuka.replace(q_min=np.r_[kuka.q_min[:4], 0.0, kuka.q_min[5]])
    q = random_q(narrow, 500, 4)
    T = fk(kuka, q)
    _, valid_full = ik_all(kuka, T, seed=q)
    q_all, valid = ik_all(narrow, T, seed=q)
    negative = np.array([Configuration.from_index(b).wrist == "negative" for b in range(8)])
    assert not valid[:, negative].any()
    np.testing.assert_array_equal(valid[:, ~negative], valid_full[:, ~negative])
    result = ik(narrow, T, seed=q, config=Configuration("front", "up", "negative"))
    assert not result.success.any()
    assert set(result.reason) <= {"joint limits", "unreachable"} and "joint limits" in set(result.reason)
    assert np.isnan(result.q).all()


# ---------------------------------------------------------------- failures and singularities


@pytest.mark.parametrize("name", ROBOTS)
def test_unreachable_targets_fail_and_are_named(name):
    robot = robot_named(name)
    T = fk(robot, np.stack([robot.home] * 3))
    T[1, :3, 3] += 10_000.0
    result = ik(robot, T)
    np.testing.assert_array_equal(result.success, [True, False, True])
    assert result.reason[1] == "unreachable" and np.isnan(result.q[1]).all()
    assert not ik_all(robot, T)[1][1].any()
    with pytest.raises(IKError, match=r"prog\.src: no IK solution for 1 of 3 targets \(target 1: unreachable\)"):
        result.raise_on_failure("prog.src")
    assert ik(robot, T[[0, 2]]).raise_on_failure("prog.src").success.all()


@pytest.mark.parametrize("name", ROBOTS)
def test_wrist_singularity_takes_the_free_joint_from_the_seed(name):
    robot = robot_named(name)
    q = np.radians([20.0, -60.0, 50.0, 30.0, 0.0, -40.0]) if name.startswith("ur") else np.radians(
        [20.0, 10.0, 20.0, 30.0, 0.0, -40.0]
    )
    T = fk(robot, q)
    seed = q + np.radians([2.0, 2.0, -2.0, 25.0, 3.0, -15.0])
    result = ik(robot, T, seed=seed)
    assert result.success[0]
    assert result.residual_pos[0] < POS_TOL and result.residual_rot[0] < ROT_TOL
    free = 5 if ik_family(robot) == "ur" else 3
    assert result.q[0, free] == pytest.approx(seed[free], abs=1e-12)
    np.testing.assert_array_equal(ik(robot, T, seed=seed).q, result.q)


def test_wrist_centre_on_axis_1_takes_joint_1_from_the_seed():
    abb = robot_named("abb_irb4600")

    def wrist_x(q2):
        return link_frames(abb, np.array([[0.0, q2, -1.2, 0.0, 0.5, 0.0]]))[0, 5, 0, 3]

    q = np.array([0.0, brentq(wrist_x, -1.5, 0.0, xtol=1e-15), -1.2, 0.0, 0.5, 0.0])
    assert abs(wrist_x(q[1])) < 1e-10
    seed = q + np.array([0.4, 0.05, 0.05, 0.1, 0.1, 0.1])
    result = ik(abb, fk(abb, q), seed=seed)
    assert result.success[0]
    assert result.q[0, 0] == pytest.approx(seed[0], abs=1e-12)


def test_bad_arguments_raise():
    robot = robot_named("kuka_kr6_r900")
    with pytest.raises(IKError, match="seed"):
        ik(robot, np.tile(np.eye(4), (3, 1, 1)), seed=np.zeros((2, 6)))
    with pytest.raises(IKError, match="targets"):
        ik(robot, np.eye(3))


# ---------------------------------------------------------------- identified models


@pytest.mark.parametrize("name", ROBOTS)
def test_ik_near_refines_a_perturbed_model(name):
    nominal = robot_named(name)
    real = perturbed(nominal, 5)
    q = random_q(nominal, 3000, 5, margin=0.05)  # the identified solution may lie past a limit
    q = q[well_conditioned(nominal, q)][:1000]
    assert len(q) == 1000
    T = fk(real, q)
    result = ik_near(real, nominal, T, seed=q)
    assert result.success.all()
    assert result.residual_pos.max() < POS_TOL and result.residual_rot.max() < ROT_TOL
    np.testing.assert_allclose(result.q, q, atol=1e-7)
    pos, rot = pose_errors(fk(real, result.q), T)
    assert pos.max() < POS_TOL and rot.max() < ROT_TOL
    # quadratic convergence: from the nominal closed form a few iterations suffice
    start = ik(nominal, T, seed=q).q
    assert ik_numeric(real, T, start, max_iter=3).success.all()


def test_arm_without_closed_form_is_solved_numerically_from_the_seed():
    nominal = robot_named("fanuc_lrmate200id")
    real = perturbed(nominal, 6)
    q = random_q(nominal, 500, 6, margin=0.05)
    q = q[well_conditioned(nominal, q)]
    rng = np.random.default_rng(6)
    result = ik(real, fk(real, q), seed=q + rng.normal(0, 0.02, q.shape))
    assert result.success.all()
    np.testing.assert_allclose(result.q, q, atol=1e-7)
    with pytest.raises(IKError, match="no closed-form IK"):
        ik(real, fk(real, q), seed=q, config=Configuration())
    with pytest.raises(IKError, match="no closed-form family"):
        ik_all(real, fk(real, q))


def test_numeric_failures_have_reasons():
    nominal = robot_named("ur5")
    real = perturbed(nominal, 8)
    T = fk(real, np.stack([nominal.home] * 3))
    T[1, :3, 3] += 5_000.0
    start = np.stack([nominal.home] * 3)
    start[2] = np.nan
    result = ik_numeric(real, T, start, max_iter=20)
    np.testing.assert_array_equal(result.success, [True, False, False])
    assert result.reason[1] in ("not converged", "singular")
    assert result.reason[2] == "unreachable"
    near = ik_near(real, nominal, T)
    assert list(near.reason) == ["", "unreachable", ""]


def test_a_reason_taken_from_other_rows_is_kept_whole():
    """A reason longer than any of the rows it replaces is not cut to their text width: with_rows of a result
    whose reasons are all "" (numpy text of width 1) once named a UR10 target of a real program "not converg"."""
    n = 3
    solved = IKResult(np.zeros((n, 6)), np.ones(n, dtype=bool), np.zeros(n), np.zeros(n), np.array(["", "", ""]))
    failed = IKResult(np.full((1, 6), np.nan), np.zeros(1, dtype=bool), np.full(1, np.nan), np.full(1, np.nan),
                      np.array(["not converged"]))
    both = solved.with_rows([1], failed)
    assert list(both.reason) == ["", "not converged", ""] and list(solved.reason) == ["", "", ""]
    with pytest.raises(IKError, match=r"\(target 1: not converged\)$"):
        both.raise_on_failure()
