"""Inverse kinematics: closed form for two arm families, Gauss-Newton for the rest.

Closed form (all eight branches, vectorized over N targets) holds for the
nominal geometry of two families of standard-DH arms (see `ik_family`):

``"ur"``
    Universal-Robots-like: joints 2, 3, 4 parallel (alpha2 = alpha3 = 0),
    cos(alpha1) = cos(alpha4) = cos(alpha5) = 0, a4 = a5 = 0. The wrist is
    offset (d5 != 0 allowed).
``"spherical"``
    Ortho-parallel arm with a spherical wrist (KUKA, ABB, FANUC, ...):
    cos(alpha1) = 0, alpha2 = 0, cos(alpha4) = cos(alpha5) = 0,
    a4 = a5 = d5 = 0; any alpha3, a1..a3, d1..d4, d6, offsets, base and
    flange frames.

In both, a6, alpha6 and the Hayati twist of link 6 are fixed and folded into
the flange frame; the joint map must be integral with an integral inverse
(direction signs and integer couplings such as FANUC's J2/J3), so a turn of
any joint is a turn of DH angles. Identified (perturbed) models leave these
families and are solved by `ik_numeric`, started from the closed-form
solution of the nominal arm (`ik_near`).

Branches are numbered by their `Configuration` (``index`` 0..7). Lengths are
mm, angles rad; poses T_base_tcp (N, 4, 4) in the robot base frame.
"""

import dataclasses

import numpy as np

from trajcomp.errors import IKError
from trajcomp.arm.ik_closed_form import _branches, _closed_form_family, _up_sign, ik_family, turn_towards
from trajcomp.arm.ik_numeric import _dot, _norm, ik_numeric, pose_error
from trajcomp.arm.ik_types import (
    BRANCHES,
    JOINT_LIMITS,
    NOT_CONVERGED,
    POS_TOL,
    ROT_TOL,
    SINGULAR,
    UNREACHABLE,
    Configuration,
    IKResult,
    _pose_stack,
)
from trajcomp.arm.kinematics import fk, frame_columns, in_blocks

__all__ = [
    "BRANCHES",
    "JOINT_LIMITS",
    "NOT_CONVERGED",
    "POS_TOL",
    "ROT_TOL",
    "SINGULAR",
    "UNREACHABLE",
    "Configuration",
    "IKResult",
    "branch_index",
    "configuration_of",
    "frames_branch_index",
    "ik",
    "ik_all",
    "ik_family",
    "ik_near",
    "ik_numeric",
    "pose_error",
    "turn_towards",
]


def ik_all(robot, T_base_tcp, *, seed=None):
    """All eight closed-form solutions of each target.

    Parameters
    ----------
    robot : Robot
        An arm of a closed-form family (`ik_family`).
    T_base_tcp : array_like, shape (N, 4, 4) or (4, 4)
        Target TCP poses, base frame, mm.
    seed : array_like, shape (N, 6) or (6,), optional
        Joint angles (rad) each value is turned towards: among ``q + 2 pi k``
        inside the limits, the value nearest the seed is returned. At a wrist
        (or axis-1) singularity the free joint takes the seed's value.
        Default: the robot's home configuration.

    Returns
    -------
    q : ndarray, shape (N, 8, 6)
        Joint angles, rad; ``q[:, b]`` has `Configuration.from_index(b)`
        (away from singularities, where flags are ambiguous). NaN where the
        branch does not reach the target.
    valid : ndarray of bool, shape (N, 8)
        Branch reaches the target inside the joint limits.

    Raises
    ------
    IKError
        The robot is of no closed-form family.
    """
    family = _closed_form_family(robot)
    T = _pose_stack(T_base_tcp)
    seed = _seed_stack(robot, seed, len(T))
    q, reachable, inside = in_blocks(lambda t, s: _branches(robot, family, t, s), T, seed)
    return q, reachable & inside


def ik(robot, T_base_tcp, *, seed=None, config=None, weights=None):
    """One verified joint solution per target.

    Closed form when the robot is of a closed-form family (`ik_family`),
    else `ik_numeric` started from ``seed``. Every solution is checked with
    forward kinematics: a target counts as solved only within `POS_TOL` mm
    and `ROT_TOL` rad.

    Parameters
    ----------
    robot : Robot
    T_base_tcp : array_like, shape (N, 4, 4) or (4, 4)
        Target TCP poses, base frame, mm.
    seed : array_like, shape (N, 6) or (6,), optional
        Joint angles, rad. Without ``config``, the branch nearest the seed
        (weighted squared joint distance) is chosen; joint turns are always
        chosen nearest the seed. Default: the robot's home configuration.
    config : Configuration, int or sequence of N of them, optional
        The branch to take (closed-form arms only).
    weights : array_like, shape (6,), optional
        Weights of the joint distance to the seed; default all 1.

    Returns
    -------
    IKResult
        N rows (N = 1 for a single pose).

    Raises
    ------
    IKError
        ``config`` given for an arm without closed form.
    """
    T = _pose_stack(T_base_tcp)
    seed = _seed_stack(robot, seed, len(T))
    family = ik_family(robot)
    if family is None:
        if config is not None:
            raise IKError(f"robot {robot.name}: no closed-form IK, so no configuration choice; use ik_near")
        return ik_numeric(robot, T, seed)
    branch = np.full(len(T), -1) if config is None else _config_indices(config, len(T))
    weights = np.ones(6) if weights is None else np.asarray(weights, dtype=float)

    def solve(T, seed, branch):
        q_all, reachable, inside = _branches(robot, family, T, seed)
        valid = reachable & inside
        distance = np.where(valid, np.einsum("nbj,j->nb", (q_all - seed[:, None]) ** 2, weights), np.inf)
        branch = np.where(branch < 0, np.argmin(distance, axis=1), branch)
        rows = np.arange(len(T))
        solved = valid[rows, branch]
        in_reach = np.where(branch < 0, reachable.any(axis=1), reachable[rows, branch])
        reason = np.where(solved, "", np.where(in_reach, JOINT_LIMITS, UNREACHABLE))
        return _verified(robot, T, np.where(solved[:, None], q_all[rows, branch], np.nan), reason)

    return IKResult(*in_blocks(solve, T, seed, branch))


def ik_near(robot, nominal, T_base_tcp, *, seed=None, config=None, weights=None):
    """IK of a perturbed (identified) arm: branch from the nominal closed form, then refined.

    Parameters
    ----------
    robot : Robot
        The arm to solve, e.g. with identified DH parameters.
    nominal : Robot
        Its nominal arm, of a closed-form family, picking the branch.
    T_base_tcp, seed, config, weights
        As for `ik`, applied to ``nominal``.

    Returns
    -------
    IKResult
        Of ``robot``; targets the nominal arm cannot reach fail with the
        nominal's reason.
    """
    start = ik(nominal, T_base_tcp, seed=seed, config=config, weights=weights)
    if robot is nominal:
        return start
    refined = ik_numeric(robot, T_base_tcp, start.q)
    reason = np.where(start.success, refined.reason, start.reason)
    return dataclasses.replace(refined, reason=reason)


def configuration_of(robot, q):
    """The `Configuration` of joint angles, computed from the link frames.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (N, 6) or (6,)
        Joint angles, rad.

    Returns
    -------
    list of Configuration, or one Configuration for a single q
    """
    configs = [Configuration.from_index(i) for i in branch_index(robot, np.atleast_2d(q))]
    return configs[0] if np.ndim(q) == 1 else configs


def branch_index(robot, q):
    """`Configuration.index` (N,) of joint angles q (N, 6), rad, computed from the link frames."""
    return in_blocks(lambda q: (frames_branch_index(robot, frame_columns(robot, q)),), np.atleast_2d(q))[0]


def frames_branch_index(robot, columns):
    """`branch_index` (N,) of the DH frames' columns (7, 4, 3, N) (`trajcomp.arm.kinematics.frame_columns`)."""
    origin = columns[:, 3].transpose(2, 0, 1)  # (N, 7, 3): the frames' origins
    x1, z = columns[1, 0].T, columns[:6, 2].transpose(2, 0, 1)  # (N, 3) and (N, 6, 3): axes
    shoulder, elbow, wrist_point = (origin[:, i] for i in (1, 2, 5))
    forward = np.einsum("ni,ni->n", wrist_point - origin[:, 0], x1)
    up = z[:, 0] * _up_sign(robot)
    ahead = np.sign(forward)[:, None] * x1
    w, e = origin[:, 4] - shoulder, elbow - shoulder
    cross = _dot(w, ahead) * _dot(e, up) - _dot(w, up) * _dot(e, ahead)
    axes = np.einsum("njk,ji->nik", z, robot.joint_map)
    triple = _dot(np.cross(axes[:, 3], axes[:, 5]), axes[:, 4])
    return 4 * (forward < 0) + 2 * (cross <= 0) + (triple < 0)


# ---------------------------------------------------------------- shared


def _verified(robot, T, q, reason):
    """IKResult fields of candidate solutions q (N, 6), checked by FK; NaN rows failed with ``reason``."""
    res_pos = np.full(len(T), np.nan)
    res_rot = np.full(len(T), np.nan)
    have = np.flatnonzero(np.all(np.isfinite(q), axis=1))
    error = pose_error(fk(robot, q[have]), T[have])
    res_pos[have] = _norm(error[:, :3])
    res_rot[have] = _norm(error[:, 3:])
    accurate = (res_pos < POS_TOL) & (res_rot < ROT_TOL)
    reason = np.where(np.isfinite(res_pos) & ~accurate, NOT_CONVERGED, reason).astype(str)
    return np.where(accurate[:, None], q, np.nan), accurate, res_pos, res_rot, reason


def _seed_stack(robot, seed, n):
    seed = robot.home if seed is None else np.asarray(seed, dtype=float)
    if seed.shape not in ((6,), (n, 6)):
        raise IKError(f"seed must have shape (6,) or ({n}, 6), got {seed.shape}")
    return np.broadcast_to(seed, (n, 6))


def _config_indices(config, n):
    configs = [config] if isinstance(config, (Configuration, int, np.integer)) else list(config)
    index = np.array([c.index if isinstance(c, Configuration) else Configuration.from_index(c).index for c in configs])
    if len(index) not in (1, n):
        raise IKError(f"config: expected one configuration or {n}, got {len(index)}")
    return np.broadcast_to(index, (n,))


def batch_seed(robot, targets):
    """One joint seed (6,) rad for a batch of targets (N, 4, 4).

    The solution nearest the robot's home configuration at the batch's mean
    position (first target's orientation): seeding every target from it keeps
    the batch in one arm posture and on one side of every joint's turn, where
    seeding each from home would flip joint 1 across +-180 deg and mix arm
    postures inside one workspace region.
    """
    centre = targets[:1].copy()
    centre[0, :3, 3] = targets[:, :3, 3].mean(axis=0)
    result = ik(robot, centre, seed=robot.home)
    return result.q[0] if result.success[0] else robot.home
