"""A long run timed in windows: the same timing as in one piece, continuous at the joins, within the limits."""

import numpy as np
import pytest

from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot
from trajcomp.timing import Moves, retime, toppra_run
import trajcomp.timing.retiming as retime_module

UR10 = load_robot("ur10")


@pytest.fixture(scope="module")
def helix():
    n = 3001
    angle = np.linspace(0.0, 2.0 * np.pi * 6, n)
    T = np.tile(fk(UR10, UR10.home), (n, 1, 1))
    T[:, 0, 3] += 60.0 * (np.cos(angle) - 1.0)
    T[:, 1, 3] += 60.0 * np.sin(angle)
    T[:, 2, 3] += np.linspace(0.0, -80.0, n)
    return ik(UR10, T, seed=UR10.home).raise_on_failure().q


@pytest.fixture(scope="module")
def whole_and_windowed(helix):
    moves = Moves.from_joints(helix, UR10, tcp_speed=250.0, zone=0.5)
    whole = retime(moves, UR10)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(retime_module, "WINDOW", 1000)
        windowed = retime(moves, UR10)
    return whole, windowed


def test_a_windowed_run_is_timed_as_the_whole_run(whole_and_windowed):
    whole, windowed = whole_and_windowed
    assert len(whole.pieces) == 1 and len(windowed.pieces) == 3
    assert len(windowed.segments) == 1 and windowed.within_limits
    np.testing.assert_allclose(windowed.t, whole.t, rtol=0, atol=1e-6 * whole.cycle_time)
    assert np.all(np.diff(windowed.t) > 0)  # every waypoint stamped, in order


def test_windows_solved_one_by_one_give_the_timing_of_windows_solved_together(helix, whole_and_windowed):
    """The passes across windows: each window its own problem (bounds handed over at the joins) or all three
    laid end to end as one (one set of sweeps) are the same recurrence."""
    _, together = whole_and_windowed
    moves = Moves.from_joints(helix, UR10, tcp_speed=250.0, zone=0.5)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(retime_module, "WINDOW", 1000)
        patch.setattr(toppra_run, "GROUP_POINTS", 1)
        alone = retime(moves, UR10)
    np.testing.assert_allclose(alone.t, together.t, rtol=1e-12, atol=0)


def test_at_a_join_position_and_velocity_are_continuous_and_the_limits_hold(whole_and_windowed):
    _, windowed = whole_and_windowed
    for start, run, _ in windowed.pieces[1:]:  # each join: the waypoint two windows share
        assert windowed.t[run.first] == start
        before, after = windowed.at(np.array([start - 1e-9])), windowed.at(np.array([start + 1e-9]))
        np.testing.assert_allclose(before[0], after[0], atol=1e-8)  # q (rad): both paths meet at the waypoint
        assert np.max(np.abs(before[1] - after[1]) / UR10.v_max) < 1e-6  # joint velocity: no step
        # finite differences of the stamped waypoints across the join (independent of the laws)
        k = np.arange(run.first - 20, run.first + 21)
        dt = np.diff(windowed.t[k])
        v = np.diff(windowed.q[k], axis=0) / dt[:, None]
        a = np.diff(v, axis=0) / (0.5 * (dt[:-1] + dt[1:]))[:, None]
        assert np.all(np.abs(v) <= UR10.v_max * 1.01)
        assert np.all(np.abs(a) <= UR10.a_max * 1.02)
    t = np.arange(0.0, windowed.cycle_time, 1e-3)
    _, qd, qdd = windowed.at(t)
    assert np.all(np.abs(qd).max(axis=0) <= UR10.v_max * 1.01)
    assert np.all(np.abs(qdd).max(axis=0) <= UR10.a_max * 1.01)


def test_a_window_is_fitted_from_its_own_rows_as_from_the_whole_sequence(helix):
    """`window_path` sees only the window's rows (what a worker process would get); same path as run_path."""
    from trajcomp.timing.path import run_path
    from trajcomp.timing.windows import window_path

    labels = [f"P{k}" for k in range(len(helix))]
    moves = Moves.from_joints(helix, UR10, tcp_speed=250.0, zone=0.5, labels=labels)
    lo, hi, part = 700, 2100, (900, 1900)
    rows = moves.rows(lo, hi + 1)
    assert len(rows) == hi - lo + 1 and rows.labels[0] == "P700" and rows.labels[-1] == "P2100"
    assert list(rows.labels[2:4]) == ["P702", "P703"]
    reference = run_path(moves, UR10, lo, hi, 0.005, part=part)
    got = window_path(rows, UR10, lo, 0.005, part)
    assert (got.first, got.last) == (reference.first, reference.last) == part
    for name in ("s_waypoints", "grid", "tcp_lengths", "grid_rate"):
        np.testing.assert_array_equal(getattr(got, name), getattr(reference, name))
    np.testing.assert_array_equal(got.path.spline.c, reference.path.spline.c)
    assert got.deviation == reference.deviation


def test_a_long_path_evaluates_its_derivatives_without_holding_them():
    """A spline of more than KEPT_DERIVATIVES coefficients: derivatives from its own coefficients, as scipy's."""
    from scipy.interpolate import make_interp_spline

    from trajcomp.timing.path import JointPath

    s = np.linspace(0.0, 3.0, 6000)
    q = np.column_stack([np.sin((j + 1) * s) for j in range(6)])
    spline = make_interp_spline(s, q, k=3)
    long_path, short_path = JointPath(spline), JointPath(make_interp_spline(s[::4], q[::4], k=3))
    assert long_path._derivatives is None and short_path._derivatives is not None
    at = np.linspace(0.0, 3.0, 777)
    for order in (0, 1, 2):  # the same up to rounding (a second derivative: rounding over the knot spacing squared)
        np.testing.assert_allclose(long_path(at, order), spline.derivative(order)(at), rtol=1e-8, atol=1e-8)
    inner = at[(at > 0.1) & (at < 2.9)]  # the curve itself, away from the interpolation's ends
    np.testing.assert_allclose(long_path(inner, 1)[:, 2], 3.0 * np.cos(3.0 * inner), atol=1e-6)
    np.testing.assert_allclose(long_path(inner, 2)[:, 2], -9.0 * np.sin(3.0 * inner), atol=1e-4)
    np.testing.assert_allclose(short_path(inner, 2), long_path(inner, 2), atol=1e-3)


def test_corner_lengths_in_blocks_are_the_chords_between_the_waypoints(helix, monkeypatch):
    """A long run's programmed lengths are placed a block of motions at a time (bounded memory): each is still
    the chord between its waypoints' TCP positions."""
    import trajcomp.timing.moves as moves_module

    moves = Moves.from_joints(helix[:700], UR10, zone=0.5)
    k = np.arange(1, len(moves))
    monkeypatch.setattr(moves_module, "CORNER_BLOCK", 64)
    tcp = fk(UR10, moves.q)[:, :3, 3]
    np.testing.assert_array_equal(moves_module.corner_lengths(moves, UR10, k),
                                  np.linalg.norm(tcp[k] - tcp[k - 1], axis=1))
