"""Arm configuration data of each robot language, computed from joint angles.

A Cartesian target is reached by several joint solutions; each language
names the one it means with its own flags. All of them are read from three
geometric facts of a spherical-wrist arm plus the joint angles:

``behind``
    The wrist centre lies behind the axis of joint 1: its coordinate along
    the arm's forward direction (x of the frame turning with joint 1) is
    negative. KUKA "overhead area", ABB "wrist centre behind axis 1",
    FANUC "B" (back).
``elbow_front``
    The wrist centre lies in front of the line through the axes of joints 2
    and 3 (seen with the upper arm pointing up, towards the forward
    direction); the other side is the other elbow solution. KUKA S bit 1,
    ABB "in front of the lower arm", FANUC "U" (up).
``wrist_negative``
    Joint 5 is negative: KUKA S bit 2, ABB cfx bit 0. FANUC counts the
    other sign as flipped: "F" when J5 > 0 (a tool pointing down with J4 = 0
    is J5 = -90 deg, the common 'N U T').

Definitions: KUKA S and T (KSS system software manual, "Status" and
"Turn"): S bit 0 overhead, bit 1 wrist in front of the A2-A3 line, bit 2
A5 < 0; T bit i set when axis i+1 < 0. ABB confdata (RAPID reference):
cf1, cf4, cf6 = quadrant ``floor(q / 90 deg)`` of joints 1, 4, 6; cfx for
spherical-wrist arms = 4 * behind axis 1 + 2 * behind the lower arm +
(axis 5 negative). FANUC CONFIG ``'F/N U/D T/B, t1, t4, t6'`` with the turn
number ``floor((q + 180 deg) / 360 deg)`` of joints 1, 4 and 6.
"""

import dataclasses

import numpy as np

from trajcomp.kinematics import link_frames


@dataclasses.dataclass(frozen=True, eq=False)
class ArmConfiguration:
    """Configuration facts of N joint vectors (each an ndarray of bool, shape (N,))."""

    behind: np.ndarray
    elbow_front: np.ndarray
    wrist_negative: np.ndarray


def arm_configuration(robot, q):
    """The geometric configuration facts of joint vectors.

    Parameters
    ----------
    robot : Robot
        A 6-axis arm with a spherical wrist (axes 4, 5, 6 meet at the origin
        of DH frame 4).
    q : array_like, shape (N, 6)
        Joint angles, rad.

    Returns
    -------
    ArmConfiguration
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    frames = link_frames(robot, q)
    axis1 = frames[:, 0, :3, 3]
    forward = frames[:, 1, :3, 0]
    joint2, joint3, wrist = frames[:, 1, :3, 3], frames[:, 2, :3, 3], frames[:, 4, :3, 3]
    up = np.array([0.0, 0.0, 1.0])
    side = np.cross(up, forward)
    elbow = np.cross(joint3 - joint2, wrist - joint3)
    return ArmConfiguration(
        behind=np.einsum("ni,ni->n", wrist - axis1, forward) < 0.0,
        elbow_front=np.einsum("ni,ni->n", elbow, side) > 0.0,
        wrist_negative=q[:, 4] < 0.0,
    )


def kuka_status_turn(robot, q):
    """KUKA status and turn ``(S, T)`` of joint vectors q (N, 6), rad: list of int pairs."""
    q = np.atleast_2d(q)
    arm = arm_configuration(robot, q)
    status = arm.behind * 1 + arm.elbow_front * 2 + arm.wrist_negative * 4
    turn = (q < 0.0) @ (1 << np.arange(6))
    return [(int(s), int(t)) for s, t in zip(status, turn)]


def abb_confdata(robot, q):
    """ABB confdata ``(cf1, cf4, cf6, cfx)`` of joint vectors q (N, 6), rad: list of int tuples."""
    q = np.atleast_2d(q)
    arm = arm_configuration(robot, q)
    quadrant = np.floor(q[:, [0, 3, 5]] / (np.pi / 2) + 1e-9).astype(int)
    cfx = arm.behind * 4 + (~arm.elbow_front) * 2 + arm.wrist_negative * 1
    return [(*map(int, quad), int(x)) for quad, x in zip(quadrant, cfx)]


def fanuc_config(robot, q):
    """FANUC CONFIG ``(flip, elbow, front, t1, t4, t6)`` of joint vectors q (N, 6), rad.

    ``flip`` is ``"F"`` (J5 > 0) or ``"N"``, ``elbow`` ``"U"`` or ``"D"``, ``front``
    ``"T"`` or ``"B"``; t1, t4, t6 are turn numbers (int).
    """
    q = np.atleast_2d(q)
    arm = arm_configuration(robot, q)
    turns = np.floor((q[:, [0, 3, 5]] + np.pi) / (2 * np.pi) - 1e-12).astype(int)
    return [
        ("F" if flip else "N", "U" if up else "D", "B" if back else "T", *map(int, turn))
        for flip, up, back, turn in zip(q[:, 4] > 0.0, arm.elbow_front, arm.behind, turns)
    ]
