"""The position rows of the parameter Jacobian (`trajcomp.arm.parameters.position_jacobian`)."""

import numpy as np
import pytest

from trajcomp.arm.kinematics import BLOCK
from trajcomp.arm.parameters import candidate_parameters, pose_jacobian, position_jacobian
from trajcomp.arm.robot import load_robot
from trajcomp.arm.transforms import rotvec_to_matrix


@pytest.mark.parametrize("name", ["ur10", "kuka_kr6_r900"])
def test_position_jacobian_is_the_position_rows_of_the_pose_jacobian(name):
    """Every kind of parameter (Hayati beta, tool, target, registration), over more than one block of rows;
    `pose_jacobian` itself is checked against finite differences in tests/calibration/test_identify.py."""
    robot = load_robot(name)
    q = np.random.default_rng(3).uniform(-2.5, 2.5, (BLOCK + 5, 6))
    names = candidate_parameters(robot, orientation=True, tracker=True)
    _, jac = pose_jacobian(robot, q, names, rotvec_to_matrix([0.2, -1.0, 0.4]))
    rows = position_jacobian(robot, q, names)
    assert rows.shape == (len(q), 3, len(names))
    np.testing.assert_array_equal(rows, jac[:, :3, :])
