"""Waypoints a linear motion reaches in another turn of a joint than declared: the joints each is reached with.

The reference is a plain loop over the motions: a joint motion goes to
its declared joints, a linear one turns each joint by its declared change
wrapped to less than half a turn.
"""

import numpy as np
import pytest

from trajcomp.errors import TimingError
from trajcomp.arm.ik import Configuration, configuration_of, ik
from trajcomp.arm.kinematics import fk
from trajcomp.programs.items import JOINT, LINEAR
from trajcomp.arm.robot import load_robot
from trajcomp.timing import Moves, retime
import trajcomp.timing.retiming as retime_module

UR10 = load_robot("ur10")
TURN = 2.0 * np.pi


def reached_by_loop(declared, kinds):
    """Reference: the joints (M, 6) a chain from declared[0] reaches its waypoints with."""
    out = declared.copy()
    for k in range(1, len(declared)):
        change = declared[k] - declared[k - 1]
        out[k] = declared[k] if kinds[k] == JOINT else out[k - 1] + (change + np.pi) % TURN - np.pi
    return out


@pytest.mark.parametrize("block", [7, 65536])
def test_the_continued_joints_match_a_loop_over_the_motions(monkeypatch, block):
    monkeypatch.setattr(retime_module, "_BLOCK", block)
    rng = np.random.default_rng(3)
    m = 60
    declared = np.cumsum(rng.normal(0.0, 0.05, (m, 6)), axis=0)
    declared[[10, 11, 12, 40]] += TURN * np.array([1, 0, 0, 0, 0, -1])  # declared a turn off
    declared[25:33, 2] += TURN  # ... over several waypoints, across a block boundary
    declared[50, 4] += 0.6 * np.pi  # a large step: the wrapping path in its block
    kinds = np.array([LINEAR] * m, dtype=object)
    kinds[[30, 45]] = JOINT  # a joint motion goes to the declared turn
    reference = reached_by_loop(declared, kinds)
    got = np.empty((m - 1, 6))
    for lo, hi, values in retime_module._continued(declared[0], declared, kinds[1:]):
        got[lo - 1 : hi - 1] = values
    np.testing.assert_allclose(got, reference[1:], atol=1e-9)


def test_a_linear_chain_reaches_a_waypoint_declared_a_turn_off_continuously_and_warns():
    q = UR10.home + np.linspace(0.0, 0.4, 40)[:, None] * np.array([0.5, -0.2, 0.3, 0.2, 0.3, 0.6])
    declared = q.copy()
    declared[15:20, 5] += TURN  # J6 declared one turn up on waypoints 15..19
    moves = Moves.from_joints(declared, UR10, kind=LINEAR, zone=1.0)
    before = moves.q.copy()
    result = retime(moves, UR10)
    np.testing.assert_allclose(result.q, q, atol=1e-9)  # reached continuously, not a turn off
    np.testing.assert_array_equal(moves.q, before)  # the caller's Moves is left as it was
    assert len(result.warnings) == 5 and all("J6 at" in w for w in result.warnings)
    plain = retime(Moves.from_joints(q, UR10, kind=LINEAR, zone=1.0), UR10)
    assert result.cycle_time == pytest.approx(plain.cycle_time, rel=1e-9)
    assert plain.warnings == () and plain.q is not None


KUKA = load_robot("kuka_kr6_r900")


def near_singular_line(offset, wrist):
    """Joints (2, 6) at both ends of an 80 mm LIN of the KUKA passing ``offset`` mm from its wrist
    singularity (A5 = 0), both in the configuration with ``wrist`` flag, as IK gives them (within +-180 deg)."""
    q_singular = np.radians([10.0, -80.0, 100.0, 0.0, 0.0, 20.0])
    ends = np.tile(fk(KUKA, q_singular), (2, 1, 1))
    ends[:, :3, 3] += offset * np.array([0.0, 0.0, 1.0]) + np.outer([-40.0, 40.0], [0.0, 1.0, 0.0])
    arm = configuration_of(KUKA, q_singular + np.radians([0.0, 0.0, 0.0, 0.0, 5.0, 0.0]))
    return ik(KUKA, ends, config=Configuration(arm.shoulder, arm.elbow, wrist), seed=q_singular).q


def test_a_line_near_the_wrist_singularity_turning_a4_more_than_half_a_turn_is_timed():
    """A4 turns by -184.6 deg along this LIN (0.5 mm from the singular point): wrapping the declared change to
    +175.4 deg sent the path the other way and refused it (a 360 deg jump); it is timed, A4 and A6 swinging
    the way the path goes, and reaches the declared joints."""
    q = near_singular_line(-0.5, "negative")
    result = retime(Moves.from_joints(q, KUKA, tcp_speed=250.0), KUKA)
    np.testing.assert_allclose(result.q, q, atol=1e-9)
    assert result.within_limits and result.warnings == ()
    sampled, _, _ = result.at(np.arange(0.0, result.cycle_time, 1e-3))
    a4 = np.degrees(sampled[:, 3])
    assert np.abs(np.diff(a4)).max() < 5.0 and np.ptp(a4) > 175.0  # one continuous swing of half a turn


def test_a_line_whose_end_is_declared_in_the_turn_the_path_reaches_keeps_that_turn():
    """On an arm with A4 and A6 ranges of +-350 deg, this LIN turns A4 by -180.9 deg: the end declared at
    A4 -268.2 deg (the turn the path reaches) is kept, not wrapped to +91.8 deg (which was refused)."""
    wide = KUKA.replace(q_min=np.radians([-170, -190, -120, -350, -120, -350]),
                        q_max=np.radians([170, 45, 156, 350, 120, 350]))
    q = near_singular_line(-0.5, "positive")
    declared = q.copy()
    declared[1, 3] -= TURN  # A4 -268.2 deg
    declared[1, 5] += TURN  # A6 286.6 deg
    result = retime(Moves.from_joints(declared, wide, tcp_speed=250.0), wide)
    np.testing.assert_allclose(result.q, declared, atol=1e-9)
    assert result.within_limits and result.warnings == ()


def test_a_line_between_two_declared_configurations_is_refused_as_such():
    q = near_singular_line(5.0, "positive")
    flipped = q[1] + np.radians([0.0, 0.0, 0.0, 180.0, 0.0, 180.0])
    flipped[4] = -flipped[4]  # the same pose with the wrist flipped: another configuration
    np.testing.assert_allclose(fk(KUKA, flipped), fk(KUKA, q[1]), atol=1e-9)
    moves = Moves.from_joints(np.array([q[0], flipped]), KUKA, labels=["P1 (weld.dat:3)", "P2 (weld.dat:4)"])
    with pytest.raises(TimingError, match=r"P2 \(weld.dat:4\): its target is declared in configuration "
                                          r"\w+/\w+/negative, its start in \w+/\w+/positive; a linear"):
        retime(moves, KUKA)
