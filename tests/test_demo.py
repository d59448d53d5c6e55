"""The demo's cubes fit every arm; the protocol reaches the noise floor on an arm other than the paper's."""

import numpy as np
import pytest

from trajcomp.paper_protocol import PAPER_CUBES, Cube, demo_cubes, run_demo
from trajcomp.errors import TrajcompError
from trajcomp.arm.kinematics import fk
from trajcomp.calibration.measurement_plan import default_orientation, grid_points, plan_grid
from trajcomp.arm.robot import builtin_robot_names, load_robot
from trajcomp.arm.transforms import abc_to_matrix


def test_the_paper_arm_gets_the_paper_cubes():
    assert demo_cubes(load_robot("ur10")) == PAPER_CUBES


def test_a_half_size_arm_gets_the_paper_cubes_halved_about_its_shoulder():
    ur10 = load_robot("ur10")
    half = ur10.replace(a=ur10.a / 2, d=ur10.d / 2)
    # Shoulder of the UR10 at z = d1 = 127.3, of the half arm at 63.65:
    # corner = 63.65 ez + (corner_paper - 127.3 ez) / 2, by hand.
    assert demo_cubes(half) == (Cube("large", (150, -50, 150), 250, 50), Cube("small", (250, 50, 250), 50, 5))


@pytest.mark.parametrize("name", builtin_robot_names())
def test_every_vertex_of_both_cubes_is_reached_within_the_joint_limits(name):
    robot = load_robot(name)
    large, small = demo_cubes(robot)
    assert (large.side / large.step, small.side / small.step) == (5, 10)
    assert np.all(np.asarray(small.corner) >= large.corner)
    assert np.all(np.add(small.corner, small.side) <= np.add(large.corner, large.side))
    for cube in (large, small):
        q = plan_grid(robot, cube.corner, cube.side, cube.step, one_posture=False).joints  # as the demo
        assert robot.within_limits(q).all()
        reached = fk(robot, q)
        np.testing.assert_allclose(reached[:, :3, 3], grid_points(cube.corner, cube.side, cube.step), atol=1e-6)
        np.testing.assert_allclose(reached[:, :3, :3], np.broadcast_to(
            abc_to_matrix(default_orientation(robot)), reached[:, :3, :3].shape), atol=1e-9)


def test_an_arm_that_reaches_no_placement_is_refused_with_its_name():
    ur10 = load_robot("ur10")
    stiff = ur10.replace(q_min=ur10.home - 0.01, q_max=ur10.home + 0.01)
    with pytest.raises(TrajcompError, match="robot ur10: no placement"):
        demo_cubes(stiff)


def test_composite_reaches_the_noise_floor_on_another_arm():
    virtual, results = run_demo(load_robot("fanuc_lrmate200id"), "paper", seed=1)
    floor = virtual.profile.noise_sigma * np.sqrt(8 / np.pi)  # mean |noise| of one point, 0.0151 mm
    for result in results:
        assert result.stats["none"].mean > 20 * floor  # 0.51-0.55 mm as measured
        assert result.stats["composite"].mean < 1.3 * floor  # 0.0143 / 0.0176 mm as measured
