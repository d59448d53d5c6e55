"""Pose and rotation conversions: hand-written definitions and round trips (hypothesis)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from trajcomp.arm.transforms import (
    abc_to_matrix,
    invert,
    matrix_to_abc,
    matrix_to_pose,
    matrix_to_quat,
    matrix_to_rotvec,
    pose_to_matrix,
    quat_to_matrix,
    rotation_angle_between,
    rotvec_to_matrix,
)

angle = st.floats(-np.pi, np.pi)
angles3 = st.tuples(angle, angle, angle).map(np.array)
unit_quat = arrays(float, 4, elements=st.floats(-1, 1)).filter(lambda v: np.linalg.norm(v) > 0.1).map(
    lambda v: v / np.linalg.norm(v)
)
rotvec = arrays(float, 3, elements=st.floats(-1, 1)).map(lambda v: v * min(1.0, 3.1 / max(np.linalg.norm(v), 1e-300)))
position = arrays(float, 3, elements=st.floats(-3000, 3000))


def rz(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def ry(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def rx(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


@given(angles3)
def test_abc_is_intrinsic_zyx(abc):
    np.testing.assert_allclose(abc_to_matrix(abc), rz(abc[0]) @ ry(abc[1]) @ rx(abc[2]), atol=1e-12)


@given(angles3)
def test_abc_round_trip_through_matrix(abc):
    mat = abc_to_matrix(abc)
    back = matrix_to_abc(mat)
    np.testing.assert_allclose(abc_to_matrix(back), mat, atol=1e-12)
    assert abs(back[1]) <= np.pi / 2 + 1e-12


@given(unit_quat)
def test_quaternion_is_scalar_first(quat):
    w, x, y, z = quat
    expected = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])
    np.testing.assert_allclose(quat_to_matrix(quat), expected, atol=1e-12)
    back = matrix_to_quat(expected)
    assert back[0] >= 0
    assert min(np.abs(back - quat).max(), np.abs(back + quat).max()) < 1e-9  # q and -q are one rotation


@given(rotvec)
def test_rotation_vector_is_rodrigues(vec):
    theta = np.linalg.norm(vec)
    k = vec / theta if theta > 0 else np.zeros(3)
    skew = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    expected = np.eye(3) + np.sin(theta) * skew + (1 - np.cos(theta)) * skew @ skew
    np.testing.assert_allclose(rotvec_to_matrix(vec), expected, atol=1e-12)
    np.testing.assert_allclose(matrix_to_rotvec(expected), vec, atol=1e-9)


@given(rotvec, rotvec)
def test_rotation_angle_between_is_the_relative_angle(a, b):
    ra, rb = rotvec_to_matrix(a), rotvec_to_matrix(b)
    expected = np.linalg.norm(matrix_to_rotvec(ra.T @ rb))
    assert abs(rotation_angle_between(ra, rb) - expected) < 1e-9


@given(st.floats(1e-12, 1e-6))
def test_rotation_angle_between_resolves_tiny_angles(theta):
    assert abs(rotation_angle_between(np.eye(3), rotvec_to_matrix([0.0, theta, 0.0])) - theta) < 1e-6 * theta


@settings(max_examples=50)
@given(position, angles3)
def test_pose_round_trip_and_inverse(pos, abc):
    pose = np.r_[pos, abc]
    mat = pose_to_matrix(pose)
    np.testing.assert_allclose(mat[:3, 3], pos)
    np.testing.assert_allclose(pose_to_matrix(matrix_to_pose(mat)), mat, atol=1e-9)
    np.testing.assert_allclose(invert(mat) @ mat, np.eye(4), atol=1e-9)
    stack = np.stack([mat, invert(mat)])
    np.testing.assert_allclose(invert(stack), np.linalg.inv(stack), atol=1e-9)
