"""Waypoints a linear motion reaches in another turn of a joint than declared: the joints each is reached with.

The reference is a plain loop over the motions: a joint motion goes to
its declared joints, a linear one turns each joint by its declared change
wrapped to less than half a turn.
"""

import importlib

import numpy as np
import pytest

from trajcomp.program_items import JOINT, LINEAR
from trajcomp.robot import load_robot
from trajcomp.timing import Moves, retime

retime_module = importlib.import_module("trajcomp.timing.retime")  # the module, not the function
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
