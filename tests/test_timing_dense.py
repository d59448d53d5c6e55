"""The dense 1 kHz check and the grid refinement it drives, on a blended program.

The reproducer: 30 random lines at 500 mm/s with 2 mm zones on the UR10.
Its TCP speed is measured independently of the timing's Jacobians (forward
kinematics of the timed joints every 1 ms, finite differences), its cycle
time against TOPP-RA on a grid 16 times finer (the reachability passes,
tested against toppra in `test_timing_reachability.py`).
"""

import dataclasses

import numpy as np
import pytest

from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot
from trajcomp.timing import Moves, plan_segments, retime
from trajcomp.timing.check import segment_peaks
from trajcomp.timing.path import run_path
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
