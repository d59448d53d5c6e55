"""The timing on the controller's path: limits held at 1 kHz where the arm really runs (issue 34, item 5).

The reference (`tests.timing.controller_path`) builds the programmed
geometry from the waypoints' poses alone (lines, and each corner's blend
within its zone), places the TCP on it with the timing's own speed
profile, solves IK every millisecond and takes finite differences.
"""

import dataclasses

import numpy as np
import pytest

from tests.timing.controller_path import controller_check
from tests.timing.test_timing_dense import random_lines, reference
from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot
from trajcomp.timing import Moves, retime

UR10 = load_robot("ur10")
WITHIN = 1.005  # the limits hold within 0.5 % at 1 kHz on the programmed path
TOLERANCE = 0.005  # mm, the path tolerance


@pytest.mark.parametrize("seed,speed,zone", [(7, 1000.0, 2.0), (3, 500.0, 5.0), (11, 200.0, 0.5)])
def test_a_blended_program_holds_the_limits_on_the_programmed_path(seed, speed, zone):
    """Random lines within 150 mm of home: the timed path is the lines outside the zones (within the path
    tolerance) and the blends inside them; the cycle time stays within 3 % of TOPP-RA on a 16x grid."""
    moves = Moves.from_joints(random_lines(10, seed), UR10, tcp_speed=speed, zone=zone)
    result = retime(moves, UR10)
    checked = controller_check(moves, result, UR10)
    assert checked.worst <= WITHIN and checked.speed_ratio <= WITHIN
    assert checked.deviation_outside_zones <= TOLERANCE and checked.deviation <= TOLERANCE
    assert checked.acceleration_ratio.max() >= 0.99  # acceleration-limited somewhere: the check bites
    cycle, worst = reference(moves, result, UR10)
    assert worst <= 1.01 and result.cycle_time <= 1.03 * cycle


def test_the_reference_sees_a_timing_faster_than_the_limits():
    """The same path run 10 % faster than timed: the reference measures the 1.1^2 acceleration."""
    moves = Moves.from_joints(random_lines(10, 3), UR10, tcp_speed=np.inf, zone=5.0)
    result = retime(moves, UR10)
    faster = dataclasses.replace(result, t=result.t / 1.1,
                                 pieces=tuple((start / 1.1, run, law.stretched(1.0 / 1.1))
                                              for start, run, law in result.pieces))
    assert controller_check(moves, result, UR10).acceleration_ratio.max() <= WITHIN
    assert controller_check(moves, faster, UR10).acceleration_ratio.max() >= 1.2


def test_short_exact_stops_hold_the_limits_on_their_lines():
    """LINs of 1-60 mm from rest to rest (timed on their joint lines before: 1.049x on the controller's path)."""
    rng = np.random.default_rng(5)
    T = np.tile(fk(UR10, UR10.home), (31, 1, 1))
    steps = rng.normal(size=(30, 3))
    steps *= (rng.uniform(1.0, 60.0, 30) / np.linalg.norm(steps, axis=1))[:, None]
    T[1:, :3, 3] += np.cumsum(steps, axis=0)
    moves = Moves.from_joints(ik(UR10, T, seed=UR10.home).raise_on_failure().q, UR10, tcp_speed=1000.0, stop=True)
    checked = controller_check(moves, retime(moves, UR10), UR10)
    assert checked.worst <= WITHIN and checked.deviation <= TOLERANCE


def near_wrist_singularity(degrees, half=100.0):
    """Joints at both ends of a 200 mm LIN of the UR10 whose wrist (J5) passes ``degrees`` from its singularity
    in the middle: of 200 random directions through that pose, the one swinging J4 most, J5 keeping its sign."""
    q_middle = UR10.home.copy()
    q_middle[4] = np.radians(degrees)
    middle = fk(UR10, q_middle)
    best = None
    for direction in np.random.default_rng(0).normal(size=(200, 3)):
        T = np.tile(middle, (201, 1, 1))
        T[:, :3, 3] += np.outer(np.linspace(-half, half, 201), direction / np.linalg.norm(direction))
        solved = ik(UR10, T, seed=q_middle)
        if not solved.success.all() or np.max(np.abs(np.diff(solved.q, axis=0))) > 0.2:
            continue
        if np.min(np.abs(solved.q[:, 4])) >= 0.999 * q_middle[4] and (best is None or np.ptp(solved.q[:, 3]) > best[0]):
            best = np.ptp(solved.q[:, 3]), solved.q[[0, -1]]
    return best[1]


def test_a_line_near_the_wrist_singularity_holds_the_limits_on_the_line():
    """J5 0.1 deg from its singularity, J4 swinging 200 deg along 200 mm (issue 34: J4 at 1.94x)."""
    q = near_wrist_singularity(0.1)
    moves = Moves.from_joints(q, UR10, tcp_speed=250.0, stop=True)
    checked = controller_check(moves, retime(moves, UR10), UR10)
    assert checked.worst <= WITHIN and checked.deviation <= TOLERANCE
    assert checked.acceleration_ratio[3] >= 0.99  # J4 binds
