"""Forward kinematics and Jacobian against independent references.

The references are written here from the manufacturers' geometry, not from
the DH tables: a product of exponentials from each joint's axis and a point
on it at the zero pose, plus hand-derived poses.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from trajcomp.arm.kinematics import BLOCK, fk, fk_and_jacobian, frame_columns, jacobian, link_frames
from trajcomp.arm.robot import builtin_robot_names, load_robot, robot_from_yaml
from trajcomp.arm.transforms import invert

X, Y, Z = np.eye(3)


def rot(axis, deg):
    return Rotation.from_rotvec(np.asarray(axis, dtype=float) * np.radians(deg)).as_matrix()


# Joint axes (unit vectors, positive turning direction) and a point on each,
# all joints at zero; the flange pose at zero; the serial joint angle as a
# function of the controller's joint angles. Base frame, mm.
ZERO_POSE_GEOMETRY = {
    # KUKA KR 6 R900 sixx data sheet: A1 height 400, A1-A2 offset 25, A2-A3
    # 455, A3-A4 offset 35, A3-wrist 420, wrist-flange 80. KUKA turns A1, A4,
    # A6 about the negative axes; flange frame = base orientation at zero.
    "kuka_kr6_r900": dict(
        axes=[-Z, Y, Y, -X, Y, -X],
        points=[(0, 0, 0), (25, 0, 400), (480, 0, 400), (900, 0, 435), (900, 0, 435), (900, 0, 435)],
        flange=((980, 0, 435), np.eye(3)),
    ),
    # ABB IRB 4600-60/2.05: axis 2 at (175, 0, 495), upper arm 900, forearm
    # offset 175, axis 3 to wrist 960, wrist to flange 135; tool0 with z out
    # of the flange and x down at zero.
    "abb_irb4600": dict(
        axes=[Z, Y, Y, X, Y, X],
        points=[(0, 0, 0), (175, 0, 495), (175, 0, 1395), (1135, 0, 1570), (1135, 0, 1570), (1135, 0, 1570)],
        flange=((1270, 0, 1570), rot(Y, 90)),
    ),
    # FANUC LR Mate 200iD: J2 at (50, 0, 330), J2-J3 330, J3-J4 offset 35,
    # J3-wrist 335, wrist-faceplate 80. J3 is the forearm angle from the
    # horizontal, so the forearm turns relative to the upper arm by J2 + J3
    # about -y; J4..J6 about the negative forearm/wrist axes; faceplate z out,
    # x up at zero: Rz(0) Ry(-90) Rx(180).
    "fanuc_lrmate200id": dict(
        axes=[Z, Y, -Y, -X, -Y, -X],
        points=[(0, 0, 0), (50, 0, 330), (50, 0, 660), (385, 0, 695), (385, 0, 695), (385, 0, 695)],
        flange=((465, 0, 695), rot(Y, -90) @ rot(X, 180)),
        serial=lambda q: q + np.outer(q[:, 1], [0, 0, 1, 0, 0, 0]),
    ),
    # UR5 after Lynch & Park, "Modern Robotics", example 4.5 (H1 = 89.159,
    # L1 = 425, L2 = 392.25, W1 = 109.15, H2 = 94.65, W2 = 82.3), turned by
    # 180 deg about z into UR's base frame (arm stretched along -x at zero).
    "ur5": dict(
        axes=[Z, -Y, -Y, -Y, -Z, -Y],
        points=[(0, 0, 0), (0, 0, 89.159), (-425, 0, 89.159), (-817.25, 0, 89.159), (-817.25, -109.15, 0),
                (-817.25, 0, -5.491)],
        flange=((-817.25, -191.45, -5.491), np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])),
    ),
    "ur10": dict(
        axes=[Z, -Y, -Y, -Y, -Z, -Y],
        points=[(0, 0, 0), (0, 0, 127.3), (-612, 0, 127.3), (-1184.3, 0, 127.3), (-1184.3, -163.941, 0),
                (-1184.3, 0, 11.6)],
        flange=((-1184.3, -256.141, 11.6), np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])),
    ),
}


def poe_fk(geometry, q):
    """Flange poses (N, 4, 4): product of joint screw motions times the zero pose."""
    serial = geometry.get("serial", lambda q: q)(q)
    out = np.tile(np.eye(4), (len(q), 1, 1))
    for axis, point, angle in zip(geometry["axes"], geometry["points"], serial.T):
        screw = np.tile(np.eye(4), (len(q), 1, 1))
        screw[:, :3, :3] = Rotation.from_rotvec(np.outer(angle, axis)).as_matrix()
        screw[:, :3, 3] = (np.eye(3) - screw[:, :3, :3]) @ np.asarray(point, dtype=float)
        out = out @ screw
    zero = np.eye(4)
    zero[:3, 3], zero[:3, :3] = geometry["flange"]
    return out @ zero


def random_q(robot, n, seed):
    return np.random.default_rng(seed).uniform(robot.q_min, robot.q_max, (n, 6))


def test_every_builtin_robot_has_a_reference():
    assert sorted(ZERO_POSE_GEOMETRY) == builtin_robot_names()


@pytest.mark.parametrize("name", sorted(ZERO_POSE_GEOMETRY))
def test_fk_matches_product_of_exponentials(name):
    robot = load_robot(name)
    q = np.vstack([np.zeros(6), random_q(robot, 500, 1)])
    np.testing.assert_allclose(fk(robot, q, tcp=False), poe_fk(ZERO_POSE_GEOMETRY[name], q), atol=1e-9)


@pytest.mark.parametrize(
    "name, q_deg, position, z_axis",
    [
        # UR upright: upper arm and forearm vertical, wrist 1 turned back to horizontal.
        ("ur5", [0, -90, 0, -90, 0, 0], (0, -191.45, 89.159 + 425 + 392.25 + 94.65), (0, -1, 0)),
        ("ur10", [0, -90, 0, -90, 0, 0], (0, -256.141, 127.3 + 612 + 572.3 + 115.7), (0, -1, 0)),
        # UR base turned by 90 deg: the stretched arm points along -y.
        ("ur5", [90, 0, 0, 0, 0, 0], (191.45, -817.25, -5.491), (1, 0, 0)),
        # KUKA home, tool down: A2 = -90 lifts the upper arm vertical, A3 = +90
        # brings the forearm back level (35 mm offset up), A5 = 90 turns the
        # flange 80 mm down with its x axis down and z forward.
        ("kuka_kr6_r900", [0, -90, 90, 0, 90, 0], (25 + 420, 0, 400 + 455 + 35 - 80), (1, 0, 0)),
        # ABB: axis 2 at +90 lays the upper arm forward, forearm then points down.
        ("abb_irb4600", [0, 90, 0, 0, 0, 0], (175 + 900 + 175, 0, 495 - 960 - 135), (0, 0, -1)),
        # FANUC: J2 tilts the upper arm 90 deg forward; J3 = 0 keeps the forearm level.
        ("fanuc_lrmate200id", [0, 90, 0, 0, 0, 0], (50 + 330 + 335 + 80, 0, 330 + 35), (1, 0, 0)),
    ],
)
def test_fk_hand_derived_poses(name, q_deg, position, z_axis):
    pose = fk(load_robot(name), np.radians(q_deg), tcp=False)
    np.testing.assert_allclose(pose[:3, 3], position, atol=1e-9)
    np.testing.assert_allclose(pose[:3, 2], z_axis, atol=1e-12)


@pytest.mark.parametrize("name", builtin_robot_names())
def test_single_and_stacked_fk_agree_and_tool_is_appended(name):
    robot = load_robot(name)
    tool = np.eye(4)
    tool[:3, :3], tool[:3, 3] = rot(X, 30), (10.0, -20.0, 150.0)
    tooled = robot.replace(T_flange_tool=tool)
    q = random_q(robot, 20, 2)
    stacked = fk(tooled, q)
    np.testing.assert_allclose(stacked, fk(robot, q, tcp=False) @ tool, atol=1e-12)
    np.testing.assert_allclose(fk(tooled, q[3]), stacked[3], atol=1e-12)


@pytest.mark.parametrize("name", builtin_robot_names())
def test_jacobian_matches_central_differences(name):
    tool = np.eye(4)
    tool[:3, 3] = (30.0, 0.0, 120.0)
    robot = load_robot(name).replace(T_flange_tool=tool)
    q = random_q(robot, 50, 3)
    h = 1e-6
    numeric = np.empty((len(q), 6, 6))
    for j in range(6):
        step = np.zeros(6)
        step[j] = h
        plus, minus = fk(robot, q + step), fk(robot, q - step)
        numeric[:, :3, j] = (plus[:, :3, 3] - minus[:, :3, 3]) / (2 * h)
        relative = plus[:, :3, :3] @ np.swapaxes(minus[:, :3, :3], 1, 2)
        numeric[:, 3:, j] = Rotation.from_matrix(relative).as_rotvec() / (2 * h)
    jac = jacobian(robot, q)
    np.testing.assert_allclose(jac[:, :3], numeric[:, :3], atol=1e-5)
    np.testing.assert_allclose(jac[:, 3:], numeric[:, 3:], atol=1e-8)


MODIFIED_YAML = """
name: modified_test
dh:
  convention: modified
  a: [30, 25, 455, 35, 0, 0]
  alpha: [20, 90, 0, 90, -90, 90]
  d: [-400, 10, 0, -420, 0, -80]
  theta_offset: [5, 0, -90, 0, 0, 0]
limits:
  position_min: [-170, -190, -120, -185, -120, -350]
  position_max: [170, 45, 156, 185, 120, 350]
  velocity: [360, 300, 360, 381, 388, 615]
  acceleration: [1500, 1250, 1500, 1600, 1600, 2500]
base: [10, 20, 30, 0, 0, 180]
flange: [0, 0, 5, 0, 90, 0]
"""


def test_modified_dh_matches_its_definition():
    """Modified (proximal) links ``Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i)``, chained by hand."""
    robot = robot_from_yaml(MODIFIED_YAML)
    q = random_q(robot, 100, 4)
    theta = q + robot.theta_offset
    expected = np.tile(robot.T_base_link0, (len(q), 1, 1))
    for i in range(6):
        link = np.tile(np.eye(4), (len(q), 1, 1))
        fixed = np.eye(4)
        fixed[:3, :3] = rot(X, np.degrees(robot.alpha[i]))
        fixed[0, 3] = robot.a[i]
        link[:, :3, :3] = Rotation.from_rotvec(np.outer(theta[:, i], Z)).as_matrix()
        link[:, 2, 3] = robot.d[i]
        expected = expected @ fixed @ link
    np.testing.assert_allclose(fk(robot, q), expected @ robot.T_link6_flange, atol=1e-9)


@pytest.mark.parametrize("name", ["kuka_kr6_r900", "abb_irb4600", "fanuc_lrmate200id"])
def test_modified_table_of_a_standard_arm_gives_identical_fk(name):
    """A standard table whose last link has a = alpha = 0, rewritten with (a, alpha) shifted one joint up."""
    std = load_robot(name)
    assert std.a[5] == 0 and std.alpha[5] == 0
    modified = std.replace(convention="modified", a=np.r_[0.0, std.a[:5]], alpha=np.r_[0.0, std.alpha[:5]])
    q = random_q(std, 200, 5)
    np.testing.assert_allclose(fk(modified, q), fk(std, q), atol=1e-9)
    np.testing.assert_allclose(jacobian(modified, q), jacobian(std, q), atol=1e-9)


def dh_matrix_product(robot, q):
    """Link frames (N, 7, 4, 4) and TCP poses (N, 4, 4) as the plain product of elementary 4 x 4 matrices.

    Standard links ``Rz(theta) Tz(d) Tx(a) Rx(alpha) Ry(beta)``, modified
    links ``Rx(alpha) Tx(a) Rz(theta) Tz(d)``; theta = joint map times q plus
    the offsets. Written independently of trajcomp.arm.kinematics.
    """

    def rotation(axis, angles):
        out = np.tile(np.eye(4), (len(angles), 1, 1))
        out[:, :3, :3] = Rotation.from_rotvec(np.outer(angles, axis)).as_matrix()
        return out

    def translation(axis, length):
        out = np.eye(4)
        out[:3, 3] = np.multiply(axis, length)
        return out

    theta = q @ robot.joint_map.T + robot.theta_offset
    ones = np.ones(len(q))
    frames = [np.tile(robot.T_base_link0, (len(q), 1, 1))]
    for i in range(6):
        if robot.convention == "standard":
            link = (rotation(Z, theta[:, i]) @ translation(Z, robot.d[i]) @ translation(X, robot.a[i])
                    @ rotation(X, robot.alpha[i] * ones) @ rotation(Y, robot.beta[i] * ones))
        else:
            link = (rotation(X, robot.alpha[i] * ones) @ translation(X, robot.a[i])
                    @ rotation(Z, theta[:, i]) @ translation(Z, robot.d[i]))
        frames.append(frames[-1] @ link)
    return np.stack(frames, axis=1), frames[-1] @ robot.T_link6_flange @ robot.T_flange_tool


def varied_robots():
    """Every built-in arm as is, identified-like (DH deltas, Hayati beta != 0, a tool) and the modified table."""
    rng = np.random.default_rng(7)
    tool = np.eye(4)
    tool[:3, :3], tool[:3, 3] = rot([1, 2, 3] / np.sqrt(14), 40), (12.0, -30.0, 140.0)
    robots = {}
    for name in builtin_robot_names():
        robot = load_robot(name)
        robots[name] = robot
        robots[f"{name} identified"] = robot.replace(
            a=robot.a + rng.normal(0, 0.5, 6),
            d=robot.d + rng.normal(0, 0.5, 6),
            alpha=robot.alpha + rng.normal(0, 1e-3, 6),
            theta_offset=robot.theta_offset + rng.normal(0, 1e-3, 6),
            beta=rng.normal(0, 1e-2, 6),
            T_flange_tool=tool,
        )
    robots["modified"] = robot_from_yaml(MODIFIED_YAML).replace(T_flange_tool=tool)
    return robots


VARIED = varied_robots()


@pytest.mark.parametrize("name", sorted(VARIED))
def test_fk_and_link_frames_match_the_product_of_dh_matrices(name):
    """Several blocks of rows (the chain is computed in blocks), joints beyond the limits included."""
    robot = VARIED[name]
    q = np.random.default_rng(8).uniform(-2 * np.pi, 2 * np.pi, (2 * BLOCK + 37, 6))
    frames, tcp = dh_matrix_product(robot, q)
    np.testing.assert_allclose(fk(robot, q), tcp, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fk(robot, q, tcp=False), tcp @ invert(robot.T_flange_tool), rtol=0, atol=1e-9)
    if robot.convention == "standard":  # a modified table's DH frames are those of its standard regrouping
        np.testing.assert_allclose(link_frames(robot, q), frames, rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", sorted(VARIED))
def test_jacobian_matches_central_differences_of_the_dh_product(name):
    robot = VARIED[name]
    q = np.random.default_rng(9).uniform(robot.q_min, robot.q_max, (200, 6))
    h = 1e-5
    numeric = np.empty((len(q), 6, 6))
    for j in range(6):
        step = np.zeros(6)
        step[j] = h
        plus, minus = dh_matrix_product(robot, q + step)[1], dh_matrix_product(robot, q - step)[1]
        numeric[:, :3, j] = (plus[:, :3, 3] - minus[:, :3, 3]) / (2 * h)
        relative = plus[:, :3, :3] @ np.swapaxes(minus[:, :3, :3], 1, 2)
        numeric[:, 3:, j] = Rotation.from_matrix(relative).as_rotvec() / (2 * h)
    pose, jac = fk_and_jacobian(robot, q)
    np.testing.assert_allclose(pose, dh_matrix_product(robot, q)[1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(jac[:, :3], numeric[:, :3], rtol=0, atol=1e-6)
    np.testing.assert_allclose(jac[:, 3:], numeric[:, 3:], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(jacobian(robot, q), jac)


def test_empty_and_single_configurations():
    robot = VARIED["ur10 identified"]
    assert fk(robot, np.empty((0, 6))).shape == (0, 4, 4)
    assert jacobian(robot, np.empty((0, 6))).shape == (0, 6, 6)
    q = np.radians([10.0, -80.0, 70.0, -30.0, 60.0, 5.0])
    np.testing.assert_allclose(fk(robot, q), dh_matrix_product(robot, q[None])[1][0], rtol=0, atol=1e-9)


def test_frame_columns_hold_the_link_frames():
    robot = load_robot("kuka_kr6_r900")
    q = np.random.default_rng(3).uniform(robot.q_min, robot.q_max, (50, 6))
    columns = frame_columns(robot, q)
    assert columns.shape == (7, 4, 3, 50)
    np.testing.assert_array_equal(columns.transpose(3, 0, 2, 1), link_frames(robot, q)[:, :, :3, :])
