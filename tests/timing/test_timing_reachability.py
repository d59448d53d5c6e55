"""The vectorized reachability passes against toppra's own TOPP-RA (seidel solver) on the same problem."""

import numpy as np
import pytest
import toppra
import toppra.algorithm
import toppra.constraint

from trajcomp.arm.ik import ik
from trajcomp.arm.kinematics import fk
from trajcomp.arm.robot import load_robot
from trajcomp.timing import Moves
from trajcomp.timing.path import run_path
from trajcomp.timing import reachability
from trajcomp.timing.reachability import squared_speeds

UR10 = load_robot("ur10")


def helix_joints(n, turns=3, radius=60.0, rise=-80.0):
    angle = np.linspace(0.0, 2.0 * np.pi * turns, n)
    T = np.tile(fk(UR10, UR10.home), (n, 1, 1))
    T[:, 0, 3] += radius * (np.cos(angle) - 1.0)
    T[:, 1, 3] += radius * np.sin(angle)
    T[:, 2, 3] += np.linspace(0.0, rise, n)
    return ik(UR10, T, seed=UR10.home).raise_on_failure().q


class SpeedBound(toppra.constraint.LinearConstraint):
    """0 <= x_i <= x_max_i, as toppra takes it."""

    def __init__(self, x_max):
        super().__init__()
        self.dof, self.x_max = 6, x_max

    def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
        return None, None, None, None, None, None, np.column_stack([np.zeros_like(self.x_max), self.x_max])


def toppra_speeds(run, x_max, acceleration):
    limits = toppra.constraint.JointAccelerationConstraint(
        acceleration, discretization_scheme=toppra.constraint.DiscretizationType.Interpolation)
    solver = toppra.algorithm.TOPPRA([SpeedBound(x_max), limits], run.path, gridpoints=run.grid,
                                     solver_wrapper="seidel")
    _, sd, _, _ = solver.compute_parameterization(0.0, 0.0, return_data=True)
    return sd**2


def test_the_speeds_are_toppras_on_a_blended_helix_with_tcp_and_joint_limits():
    for tcp_speed in (250.0, np.inf):  # TCP speed binding, then joint velocity and acceleration alone
        moves = Moves.from_joints(helix_joints(1500), UR10, tcp_speed=tcp_speed, zone=0.5)
        run = run_path(moves, UR10, 0, len(moves) - 1)
        x_max = np.minimum(run.speed_bound(moves)[0], 1e12)
        ours = squared_speeds(run.grid, run.path(run.grid, 1), run.path(run.grid, 2), UR10.a_max, x_max,
                              rest=[0, len(run.grid) - 1])
        reference = toppra_speeds(run, x_max, UR10.a_max)
        np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-5 * reference.max())
        assert ours[0] == ours[-1] == 0.0


def test_rest_points_split_the_grid_into_independent_runs():
    q = helix_joints(400)
    moves = Moves.from_joints(q, UR10)
    run = run_path(moves, UR10, 0, len(moves) - 1)
    dq, ddq, x_max = run.path(run.grid, 1), run.path(run.grid, 2), np.minimum(run.speed_bound(moves)[0], 1e12)
    middle = len(run.grid) // 2
    whole = squared_speeds(run.grid, dq, ddq, UR10.a_max, x_max, rest=[0, middle, len(run.grid) - 1])
    halves = [squared_speeds(run.grid[part], dq[part], ddq[part], UR10.a_max, x_max[part], rest=[0, -1])
              for part in (slice(0, middle + 1), slice(middle, None))]
    np.testing.assert_array_equal(whole, np.r_[halves[0], halves[1][1:]])
    assert whole[middle] == 0.0 and np.all(whole[1:middle] > 0)


def sequential_speeds(s, dq, ddq, acceleration, x_max):
    """Reference: the two TOPP-RA passes as plain loops over the grid (rest at both ends)."""
    from trajcomp.timing.reachability import Bands

    bands = Bands.of_path(np.diff(s), dq, ddq, acceleration)
    x_max = x_max.copy()
    x_max[[0, -1]] = 0.0
    h = np.append(bands.largest_x(x_max[:-1]), 0.0)
    for i in range(len(s) - 2, -1, -1):
        sigma, w = bands.sigma[i], bands.w[i]
        rising = sigma > 0
        h[i] = min(h[i], np.min((h[i + 1] + w[rising]) / sigma[rising], initial=np.inf))
    x = h.copy()
    x[0] = 0.0
    for i in range(len(s) - 1):
        x[i + 1] = min(h[i + 1], np.min(bands.sigma[i] * x[i] + bands.w[i]))
    return np.maximum(x, 0.0)


@pytest.mark.parametrize("longest_chunk", [16, 256])
def test_ramps_across_many_chunks_settle_to_the_sequential_passes(monkeypatch, longest_chunk):
    """A helix at its joint limits on a 6,000-point grid with its speed bound cut to 1 % in three places:
    ramps of hundreds of grid points, across many chunks of 16 (several rounds of sweeps) or within few."""
    monkeypatch.setattr(reachability, "LONGEST_CHUNK", longest_chunk)
    moves = Moves.from_joints(helix_joints(3000), UR10)
    run = run_path(moves, UR10, 0, len(moves) - 1)
    run = run.refined(moves, UR10, 0.5 * (run.grid[1:] + run.grid[:-1]))
    dq, ddq, x_max = run.path(run.grid, 1), run.path(run.grid, 2), np.minimum(run.speed_bound(moves)[0], 1e12)
    x_max[[len(x_max) // 5, len(x_max) // 2, 4 * len(x_max) // 5]] *= 0.01
    ours = squared_speeds(run.grid, dq, ddq, UR10.a_max, x_max, rest=[0, len(run.grid) - 1])
    np.testing.assert_allclose(ours, sequential_speeds(run.grid, dq, ddq, UR10.a_max, x_max), rtol=1e-12, atol=0)
    ramp = np.flatnonzero(ours < 0.999 * np.minimum(x_max, run.speed_bound(moves)[0]))
    assert len(ramp) > 1000  # long ramps: the test exercises what it says
