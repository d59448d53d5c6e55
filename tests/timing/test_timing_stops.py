"""A program of exact stops, timed in batches: each motion gets the timing it gets alone."""

import numpy as np
import pytest

from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk
from trajcomp.programs.items import JOINT, LINEAR
from trajcomp.arm.robot import load_robot
from trajcomp.timing import Moves, retime
from trajcomp.timing.path import run_path
from trajcomp.timing.ruckig_move import ruckig_law
from trajcomp.timing.toppra_run import toppra_laws
import trajcomp.timing.retiming as retime_module

UR10 = load_robot("ur10")


@pytest.fixture(scope="module")
def stops():
    """Moves of 13 waypoints stopping at each: lines on a circle, one repeated waypoint, three joint motions."""
    angle = np.linspace(0.0, 1.5 * np.pi, 10)
    T = np.tile(fk(UR10, UR10.home), (10, 1, 1))
    T[:, 0, 3] += 80.0 * (np.cos(angle) - 1.0)
    T[:, 1, 3] += 80.0 * np.sin(angle)
    q = ik(UR10, T, seed=UR10.home).raise_on_failure().q
    q = np.concatenate([q[:5], q[4:5], q[5:], q[:1] + np.radians([30.0, -10.0, 15.0, 0.0, 20.0, 40.0]), q[:1]])
    kind = np.array([LINEAR] * 11 + [JOINT] * 2, dtype=object)
    kind[7] = JOINT  # a joint motion between lines
    return Moves.from_joints(q, UR10, kind=kind, tcp_speed=np.r_[np.full(8, 250.0), np.full(5, np.inf)], stop=True)


def alone(moves, k):
    """Duration of motion k timed on its own: its path fitted alone, TOPP-RA (lines) or ruckig (joint motions)."""
    run = run_path(moves, UR10, k - 1, k)
    if run.path is None:
        return 0.0
    law = ruckig_law(run, moves, UR10) if moves.kind[k] == JOINT else toppra_laws([run], moves, UR10)[0]
    return law.duration


def test_each_stop_to_stop_motion_takes_the_time_it_takes_alone(stops, monkeypatch):
    monkeypatch.setattr(retime_module, "STOP_BATCH", 4)  # batches of 4, 4, 4 and 0 + a last one of 0
    result = retime(stops, UR10)
    expected = [alone(stops, k) for k in range(1, len(stops))]
    np.testing.assert_allclose(np.diff(result.t), expected, rtol=1e-6, atol=1e-9)
    assert expected[4] == 0.0 and min(np.delete(expected, 4)) > 0.05  # the repeated waypoint takes no time
    assert [s.kind for s in result.segments] == ["toppra"] * 6 + ["ruckig"] + ["toppra"] * 3 + ["ruckig"] * 2
    assert result.within_limits


@pytest.mark.parametrize("repeats", [
    [0, 1, 1, 1],  # a motion, then stops that do not move, the last of the batch among them
    [0, 0, 0],  # no motion moves
])
def test_stops_that_do_not_move_take_no_time_wherever_they_stand(repeats):
    """Repeated waypoints at the end of a batch of stops (a line x1000 in a RAPID program crashed the timing)."""
    q = UR10.home + np.radians(30.0) * np.array(repeats)[:, None] * np.eye(6)[0]
    moves = Moves.from_joints(np.r_[UR10.home[None], q], UR10, kind=np.array([JOINT] * (len(q) + 1), dtype=object),
                              tcp_speed=np.full(len(q) + 1, np.inf), stop=True)
    result = retime(moves, UR10)
    expected = [alone(moves, k) for k in range(1, len(moves))]
    np.testing.assert_allclose(np.diff(result.t), expected, rtol=1e-6, atol=1e-9)
    assert np.count_nonzero(np.diff(result.t)) == int(any(repeats))


def test_every_stop_is_at_rest_and_the_limits_hold_between(stops):
    result = retime(stops, UR10)
    _, qd_stop, _ = result.at(result.t[1:-1])
    assert np.max(np.abs(qd_stop)) < 1e-6  # at rest at each waypoint
    t = np.arange(0.0, result.cycle_time, 1e-3)
    _, qd, qdd = result.at(t)
    assert np.all(np.abs(qd).max(axis=0) <= UR10.v_max * 1.01)
    assert np.all(np.abs(qdd).max(axis=0) <= UR10.a_max * 1.01)


def test_each_stop_path_laid_out_is_its_spline(stops):
    """The laid-out cubic pieces of the stops' paths are each motion's own spline; a motion of fewer than 4
    samples is the not-a-knot spline scipy makes through its samples and its polyline's points at every third
    of the path."""
    from scipy.interpolate import make_interp_spline

    from trajcomp.timing.path import stop_paths
    from trajcomp.timing.samples import run_samples

    paths = stop_paths(stops, UR10, 0, len(stops) - 1)
    short = 0
    for r, i in enumerate(paths.moving.tolist()):
        run = paths.runs[i]
        u = np.linspace(0.0, run.length, 57)
        q = run_samples(stops, UR10, run.first, run.last)[0]
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))]
        dense = np.union1d(s, np.linspace(0.0, s[-1], 4))
        expected = make_interp_spline(dense, make_interp_spline(s, q, k=1)(dense), k=3) if len(q) < 4 else run.path
        for order in range(3):
            scale = max(np.abs(expected(u, order)).max(), 1.0)
            np.testing.assert_allclose(paths.pieces(np.full(len(u), r), u, order), expected(u, order), atol=1e-9 * scale)
            np.testing.assert_allclose(run.path(u, order), expected(u, order), atol=1e-9 * scale)
        short += len(q) < 4
    assert 1 <= short < len(paths.moving)


@pytest.mark.parametrize("block", [None, 250])  # 250 samples: a motion or two per block, the longest alone
def test_stops_checked_together_measure_what_each_measures_alone(stops, block, monkeypatch):
    """The batched 1 kHz check of exact stops gives each motion the peaks of the dense check of it alone."""
    from trajcomp.timing import check
    from trajcomp.timing.check import dense_check, rest_to_rest_checks

    if block is not None:
        monkeypatch.setattr(check, "BLOCK", block)
    from trajcomp.timing.path import stop_paths
    from trajcomp.timing.toppra_run import rest_to_rest_laws

    paths = stop_paths(stops, UR10, 0, len(stops) - 1)
    lines = np.array([r for r, i in enumerate(paths.moving) if stops.kind[i + 1] != JOINT])
    laws = rest_to_rest_laws(paths, lines, stops)
    peaks, worst = rest_to_rest_checks(paths, lines, laws, stops, UR10)
    for r, i in enumerate(paths.moving[lines]):
        run = paths.runs[i]
        alone = toppra_laws([run], stops, UR10)[0]
        np.testing.assert_allclose(laws.law(r).t, alone.t, rtol=1e-9, atol=1e-12)
        expected = dense_check(run, alone, stops, UR10, jerk=False)[0]
        for name in ("velocity", "acceleration", "velocity_ratio", "acceleration_ratio", "speed_ratio"):
            np.testing.assert_allclose(getattr(peaks[r], name), getattr(expected, name), rtol=1e-7, atol=1e-9)
        assert np.isnan(peaks[r].jerk).all() and worst[r] == pytest.approx(expected.worst, rel=1e-7)
