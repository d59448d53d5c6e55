"""Kinematic parameters of an arm and their analytic Jacobian.

A calibration adjusts, from the nominal robot:

- per joint ``j`` of the standard DH table: ``a{j}``, ``alpha{j}``,
  ``d{j}``, ``theta{j}`` (offset) and, for a link joining nominally parallel
  axes, the Hayati twist ``beta{j}`` (where ``d`` is ill-conditioned);
- ``tool_x``, ``tool_y``, ``tool_z``: the TCP position in the flange frame.
  With it, link 6 (a6, alpha6, d6, theta6) is left out: after joint 6 the
  chain to the TCP is one rigid transform, which the tool already spans;
- ``target_rx``, ``target_ry``, ``target_rz``: orientation of the frame a
  6-DoF tracker measures in the TCP frame (rotation vector, target axes),
  only when orientations are measured;
- ``base_x`` ... ``base_rz``: the base pose in the tracker frame (translation,
  rotation vector in base axes), only for tracker-frame data.

Every parameter moves the TCP as a unit twist: a translation along an axis
or a rotation about an axis through a point, both known from the DH frames
at each configuration. `pose_jacobian` builds the derivative of the TCP
position and orientation for all N configurations at once; no finite
differences. Lengths mm, angles rad.
"""

import numpy as np

from trajcomp.arm.kinematics import frame_columns, in_blocks

ANGLE_LEVER = 1000.0  # mm: an angle parameter is scaled as its effect at this lever arm
FRAME_COST = 0.01  # a frame parameter costs this many times an arm parameter along a hidden combination
TOOL_NAMES = ("tool_x", "tool_y", "tool_z")
TARGET_NAMES = ("target_rx", "target_ry", "target_rz")
BASE_NAMES = ("base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz")
LENGTH_BOUND = 20.0  # mm, the largest plausible |delta| of a DH length (a bought arm: tenths of a mm)
ANGLE_BOUND = np.radians(3.0)  # rad, the largest plausible |delta| of a DH angle (a bought arm: hundredths of a deg)
_PARALLEL = 1e-6  # |sin(alpha)| below which consecutive axes are parallel


def candidate_parameters(robot, *, tool=True, orientation=False, tracker=False):
    """Names of the parameters a fit may adjust.

    Parameters
    ----------
    robot : Robot
    tool : bool
        Include the TCP position in the flange frame (and leave link 6 out).
    orientation : bool
        Orientations are measured: include the measured frame's orientation.
    tracker : bool
        Measurements in the tracker frame: include the base registration.

    Returns
    -------
    list of str
        e.g. ``["a1", "alpha1", "d1", "theta1", ..., "beta2", ..., "tool_x", ...]``.
    """
    std = robot.as_standard()
    names = []
    for i in range(5 if tool else 6):
        names += [f"a{i + 1}", f"alpha{i + 1}", f"d{i + 1}", f"theta{i + 1}"]
        if i < 5 and abs(np.sin(std.alpha[i])) < _PARALLEL:
            names.append(f"beta{i + 1}")
    if tool:
        names += TOOL_NAMES
    if orientation:
        names += TARGET_NAMES
    if tracker:
        names += BASE_NAMES
    return names


def is_angle(name):
    """True for parameters in rad, False for those in mm."""
    return name.startswith(("alpha", "theta", "beta", "base_r", "target_r"))


def scales(names):
    """Per-parameter scale (P,): 1 for mm, 1 / `ANGLE_LEVER` for angles and joint-error terms (solver units).

    A joint-error term's basis function is of order one (sin, cos, a
    B-spline, or a lever in m), so its coefficient acts as an angle.
    """
    return np.array([1.0 / ANGLE_LEVER if is_angle(n) or n.startswith(("gear", "grav", "spline")) else 1.0
                     for n in names])


def prior_weights(names):
    """Per-parameter cost (P,) of moving a parameter along a combination the data do not identify.

    1 for the arm's parameters (the nominal arm is a prior: its data sheet),
    `FRAME_COST` for the frames of the measurement (tracker registration,
    measured target), which have no prior: a combination the data see only
    together with the arm (base z with d1, the turn about base z with
    theta1) moves the frame and leaves the arm at nominal.
    """
    return np.array([FRAME_COST if n.startswith(("base_", "target_")) else 1.0 for n in names])


def is_robot_parameter(name):
    """True for the DH and tool parameters (those that change the arm, see `apply_deltas`)."""
    return not name.startswith(("base_", "target_"))


def apply_deltas(robot, names, delta):
    """The robot with DH and tool parameter deltas applied.

    Parameters
    ----------
    robot : Robot
        Nominal robot (any convention; the result is standard DH).
    names : sequence of str
        Parameter names, see `candidate_parameters`; registration and
        target parameters are ignored (they are not part of the arm).
    delta : array_like, shape (P,)
        Deltas in mm or rad.
    """
    std = robot.as_standard()
    table = {key: getattr(std, key).copy() for key in ("a", "alpha", "d", "theta_offset", "beta")}
    T_flange_tool = std.T_flange_tool.copy()
    for name, value in zip(names, delta):
        if name in TOOL_NAMES:
            T_flange_tool[TOOL_NAMES.index(name), 3] += value
        elif is_robot_parameter(name):
            kind, joint = name[:-1], int(name[-1]) - 1
            table["theta_offset" if kind == "theta" else kind][joint] += value
    return std.replace(T_flange_tool=T_flange_tool, **table)


def pose_jacobian(robot, q, names, R_tcp_target=None):
    """TCP pose and its derivative with respect to each parameter.

    Parameters
    ----------
    robot : Robot
        The current estimate (standard DH after `apply_deltas`).
    q : ndarray, shape (N, 6)
        Joint angles, rad.
    names : sequence of str
        Parameters, see `candidate_parameters`.
    R_tcp_target : ndarray, shape (3, 3), optional
        Current orientation of the measured frame in the TCP frame.

    Returns
    -------
    T_tcp : ndarray, shape (N, 4, 4)
        TCP poses in the base frame.
    jac : ndarray, shape (N, 6, P)
        Rows 0-2: TCP position (mm per mm or per rad); rows 3-5: rotation of
        the measured frame about the base axes (rad per mm or rad). A
        registration parameter ``base_*`` moves the base in the tracker
        frame; its column is the apparent motion of the TCP in the base
        frame (the measurements move the opposite way).
    """
    std = robot.as_standard()
    return in_blocks(lambda q: _jacobian_block(std, q, names, R_tcp_target, 6), np.atleast_2d(q))


def position_jacobian(robot, q, names):
    """Rows 0-2 of `pose_jacobian`: the derivative (N, 3, P) of the TCP position (mm per mm or per rad) with
    respect to each parameter at joints q (N, 6) rad, without the orientation rows' work."""
    std = robot.as_standard()
    return in_blocks(lambda q: _jacobian_block(std, q, names, None, 3)[1:], np.atleast_2d(q))[0]


def _jacobian_block(std, q, names, R_tcp_target, rows):
    """`pose_jacobian` ``(T_tcp (n, 4, 4), jac (n, rows, P))`` of a block of joints q (n, 6) of a standard DH robot
    (``rows`` 3: the position rows alone), built as columns with n last (`frame_columns`)."""
    columns = frame_columns(std, q)  # (7, 4, 3, n): column k (axes, origin) of DH frame i
    link6 = np.zeros((len(q), 4, 4))  # as `link_frames` lays it out
    link6[:, :3, :] = columns[6].transpose(2, 1, 0)
    link6[:, 3, 3] = 1.0
    flange = link6 @ std.T_link6_flange
    tcp = flange @ std.T_flange_tool
    p = tcp[:, :3, 3].T
    jac = np.zeros((len(names), rows, len(q)))

    def rotation(column, axis, point):
        lever = p - point
        jac[column, 0] = axis[1] * lever[2] - axis[2] * lever[1]  # axis x lever, as np.cross computes it
        jac[column, 1] = axis[2] * lever[0] - axis[0] * lever[2]
        jac[column, 2] = axis[0] * lever[1] - axis[1] * lever[0]
        if rows > 3:
            jac[column, 3:] = axis

    for k, name in enumerate(names):
        if name in TOOL_NAMES:
            jac[k, :3] = flange[:, :3, TOOL_NAMES.index(name)].T
        elif name in TARGET_NAMES:
            if rows > 3:
                R_target = tcp[:, :3, :3] @ (np.eye(3) if R_tcp_target is None else R_tcp_target)
                jac[k, 3:] = R_target[:, :, TARGET_NAMES.index(name)].T
        elif name in BASE_NAMES:
            axis = np.eye(3)[BASE_NAMES.index(name) % 3][:, None]
            if name in BASE_NAMES[:3]:
                jac[k, :3] = axis
            else:
                rotation(k, axis, np.zeros((3, 1)))
        else:
            kind, j = name[:-1], int(name[-1])
            before, after = columns[j - 1], columns[j]
            # x axis of link j before its Hayati twist Ry(beta): Rx(alpha) keeps it
            cb, sb = np.cos(std.beta[j - 1]), np.sin(std.beta[j - 1])
            x_link = cb * after[0] + sb * after[2]
            if kind == "theta":
                rotation(k, before[2], before[3])
            elif kind == "d":
                jac[k, :3] = before[2]
            elif kind == "a":
                jac[k, :3] = x_link
            elif kind == "alpha":
                rotation(k, x_link, after[3])
            elif kind == "beta":
                rotation(k, after[1], after[3])
            else:
                raise ValueError(f"unknown parameter {name!r}")
    return tcp, np.ascontiguousarray(jac.transpose(2, 1, 0))
