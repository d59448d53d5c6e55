"""The dense 1 kHz check and the grid refinement it drives, on a blended program.

The reproducer: 30 random lines at 500 mm/s with 2 mm zones on the UR10.
Its TCP speed is measured independently of the timing's Jacobians (forward
kinematics of the timed joints every 1 ms, finite differences), its cycle
time against TOPP-RA on a grid 16 times finer (the reachability passes,
tested against toppra in `test_timing_reachability.py`).
"""

import dataclasses
import tracemalloc

import numpy as np
import pytest

from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot
from trajcomp.timing import Moves, plan_segments, retime
from trajcomp.timing import check
from trajcomp.timing.check import dense_check, dense_checks, segment_peaks
from trajcomp.timing.path import run_path, tcp_speeds
from trajcomp.timing.toppra_run import toppra_laws

UR10 = load_robot("ur10")
REFINE = 16


def random_lines(n, seed, robot=UR10):
    """Joints (n, 6) of n random TCP positions within 150 mm of the home pose, one orientation."""
    rng = np.random.default_rng(seed)
    T = np.tile(fk(robot, robot.home), (n, 1, 1))
    T[:, :3, 3] += rng.uniform(-150.0, 150.0, (n, 3))
    return ik(robot, T, seed=robot.home).raise_on_failure().q


def reference(moves, result, robot):
    """Cycle time (s) of TOPP-RA on the same paths with REFINE times their first grid, and its worst 1 kHz ratio."""
    moves = dataclasses.replace(moves, q=result.q)  # the joints the timing ran through (turns kept)
    total, worst = 0.0, 0.0
    for kind, first, last in plan_segments(moves, "toppra"):
        if kind == "untimed":
            continue
        run = run_path(moves, robot, first, last)
        if run.path is None:
            continue
        run = run.refined(moves, robot, (run.grid[:-1, None] + np.outer(np.diff(run.grid),
                                                                         np.arange(1, REFINE) / REFINE)).ravel())
        law = toppra_laws([run], moves, robot)[0]
        total += law.duration
        worst = max(worst, segment_peaks(run, law, moves, robot, jerk=False).worst)
    return total, worst


@pytest.fixture(scope="module")
def blended():
    moves = Moves.from_joints(random_lines(30, 1), UR10, tcp_speed=500.0, zone=2.0)
    return moves, retime(moves, UR10)


def test_the_tcp_speed_of_a_blended_program_never_exceeds_the_programmed_one(blended):
    moves, result = blended
    t = np.arange(0.0, result.cycle_time, 1e-3)
    q, qd, qdd = result.at(t)
    p = fk(UR10, q)[:, :3, 3]
    speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / 1e-3  # mean speed of each millisecond
    assert speed.max() <= 500.0 * 1.0005
    assert speed.max() >= 500.0 * 0.99  # the programmed speed is reached
    assert np.all(np.abs(qd) <= UR10.v_max * 1.0005)
    assert np.all(np.abs(qdd) <= UR10.a_max * 1.0005)
    assert result.within_limits and result.peak_speed_ratio <= 1.0005


def test_a_blended_program_is_timed_within_3_percent_of_a_feasible_reference(blended):
    """Lowering the limits of the whole run for an overshoot in a blend made this 1.59x the reference."""
    moves, result = blended
    cycle, worst = reference(moves, result, UR10)
    assert worst <= 1.01  # the reference is itself feasible within 1 % at 1 kHz
    assert result.cycle_time <= 1.03 * cycle


@pytest.mark.parametrize("name", ["ur10", "fanuc_lrmate200id", "kuka_kr6_r900"])
def test_the_tcp_speed_is_the_derivative_of_the_tcp_position(name):
    """`tcp_speeds` (no Jacobian formed) against central differences of forward kinematics, two tools."""
    robot = load_robot(name)
    rng = np.random.default_rng(3)
    q, qd = robot.home + rng.uniform(-0.5, 0.5, (40, 6)), rng.uniform(-1.0, 1.0, (40, 6))
    tool = np.array([[0.0, 1.0, 0.0, 10.0], [1.0, 0.0, 0.0, 20.0], [0.0, 0.0, -1.0, 150.0], [0.0, 0.0, 0.0, 1.0]])
    moves = dataclasses.replace(Moves.from_joints(q, robot), tools=np.array([np.eye(4), tool]), tool=np.arange(40) % 2)
    h = 1e-6
    expected = [np.linalg.norm(fk(robot.replace(T_flange_tool=moves.tools[moves.tool[i]]), q[i] + h * qd[i])[:3, 3]
                               - fk(robot.replace(T_flange_tool=moves.tools[moves.tool[i]]), q[i] - h * qd[i])[:3, 3])
                / (2 * h) for i in range(40)]
    np.testing.assert_allclose(tcp_speeds(robot, moves, np.arange(40), q, qd), expected, rtol=1e-6)


def test_the_dense_check_in_blocks_measures_what_one_block_does(blended, monkeypatch):
    """Samples taken a few at a time (runs split across blocks, jerk differenced across them) give the same
    peaks and overshoot positions as all at once."""
    moves, result = blended
    stop = Moves.from_joints(UR10.home + np.array([[0.0] * 6, [0.4, -0.3, 0.5, 0.2, 0.1, 0.6]]), UR10, stop=True)
    joint = retime(stop, UR10)
    runs, laws = zip(*[(run, law) for _, run, law in result.pieces + joint.pieces])
    jerk = [False] * len(result.pieces) + [True]
    whole = dense_checks(list(runs), list(laws), moves, UR10, jerk=jerk, over=0.9)
    assert jerk[-1] and np.all(np.isfinite(whole[-1][0].jerk)) and sum(len(s) for _, s in whole) > 1000
    monkeypatch.setattr(check, "BLOCK", 97)
    blocks = dense_checks(list(runs), list(laws), moves, UR10, jerk=jerk, over=0.9)
    for (peaks, s), (peaks_in_blocks, s_in_blocks) in zip(whole, blocks):
        for field in dataclasses.fields(peaks):
            np.testing.assert_array_equal(getattr(peaks_in_blocks, field.name), getattr(peaks, field.name))
        np.testing.assert_array_equal(s_in_blocks, s)


def test_the_dense_checks_memory_does_not_grow_with_the_duration():
    """A 200 mm line at 8 and at 4 mm/s (25 and 50 s between two stops): the check holds one block of
    samples at a time (all at once: 80 MB at 50 s, 164 MB at 200 s)."""
    start = fk(UR10, UR10.home)
    end = start.copy()
    end[0, 3] -= 200.0
    q = ik(UR10, np.array([start, end]), seed=UR10.home).raise_on_failure().q
    peak_mb = []
    for speed in (8.0, 4.0):
        moves = Moves.from_joints(q, UR10, tcp_speed=speed, stop=True)
        (_, run, law), = retime(moves, UR10).pieces
        tracemalloc.start()
        peaks, _ = dense_check(run, law, moves, UR10, jerk=False)
        peak_mb.append(tracemalloc.get_traced_memory()[1] / 1e6)
        tracemalloc.stop()
        assert law.duration > 200.0 / speed and 0.999 < peaks.speed_ratio <= 1.0005
    assert peak_mb[1] < 1.05 * peak_mb[0] and peak_mb[1] < 40.0


def test_a_run_of_more_than_an_hour_between_two_stops_is_timed_not_refused():
    """A layer of wire-arc additive manufacturing runs 999 motions at 15-30 cm/min, blended, for 4,578 s between
    two stops (Creearc/welding_project, layers_splitter/data/cub.ls): a controller runs it, and the check's memory
    is flat in the duration, so a run beyond an hour is timed (it was refused as "a speed no process uses"). A
    200 mm line at 0.055 mm/s, 3,636 s: its check takes seconds per million samples."""
    start = fk(UR10, UR10.home)
    end = start.copy()
    end[0, 3] -= 200.0
    q = ik(UR10, np.array([start, end]), seed=UR10.home).raise_on_failure().q
    timing = retime(Moves.from_joints(q, UR10, tcp_speed=0.055, stop=True), UR10)
    assert timing.cycle_time > 3600.0 and timing.within_limits
