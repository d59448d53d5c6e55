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
from trajcomp.kinematics import dh_link_transforms, fk, fk_and_jacobian, in_blocks, jacobian, link_frames
from trajcomp.transforms import invert

BRANCHES = 8
POS_TOL = 1e-6  # mm, accepted TCP position error of an IK solution
ROT_TOL = 1e-9  # rad, accepted TCP orientation error of an IK solution

UNREACHABLE = "unreachable"
JOINT_LIMITS = "joint limits"
SINGULAR = "singular"
NOT_CONVERGED = "not converged"

_ZERO = 1e-9  # tolerance of the family tests on DH numbers (mm, rad)
_SINGULAR_SIN = 1e-10  # |sin| of joint 5 (or distance/mm on axis 1) below which a joint is free
_REACH_SLACK = 1e-9  # relative slack on cos/sin arguments before a target counts as unreachable
_LIMIT_TOL = 1e-9  # rad, as Robot.within_limits
_ROT_SCALE = 1000.0  # mm/rad, weight of orientation against position error in Gauss-Newton
_MAX_STEP = 0.3  # rad, largest joint step of one Gauss-Newton iteration


@dataclasses.dataclass(frozen=True)
class Configuration:
    """One of the eight arm configurations (branches) of a closed-form arm.

    Defined geometrically from the DH frames, so the flags mean the same for
    every family (`configuration_of` computes them from joint angles):

    shoulder : {"front", "back"}
        "back" when the wrist point (origin of DH frame 5: the wrist centre
        of a spherical wrist) lies behind axis 1, i.e. its coordinate along
        the x axis of DH frame 1 is negative (KUKA "overhead", ABB "behind
        axis 1", FANUC "B").
    elbow : {"up", "down"}
        "up" when the elbow (axis 3) lies above the line from axis 2 to the
        origin of DH frame 4, seen in the arm plane with the wrist to the
        right and the base z axis up (for a spherical-wrist arm in front of
        axis 1 this is KUKA status bit 1 and FANUC "U").
    wrist : {"positive", "negative"}
        Sign of the triple product ``(a4 x a6) . a5`` of the joint axes
        (sin q5 for the built-in spherical-wrist arms; "negative" is KUKA
        status bit 2 and ABB cfx bit 0).
    """

    shoulder: str = "front"
    elbow: str = "up"
    wrist: str = "positive"

    _VALUES = (("front", "back"), ("up", "down"), ("positive", "negative"))

    def __post_init__(self):
        for name, allowed in zip(("shoulder", "elbow", "wrist"), self._VALUES):
            value = getattr(self, name)
            if value not in allowed:
                raise IKError(f"configuration {name}: expected one of {', '.join(allowed)}, got {value!r}")

    @property
    def index(self):
        """Branch number 0..7: 4 * back + 2 * down + negative."""
        flags = (self.shoulder, self.elbow, self.wrist)
        return sum(4 >> i for i, (value, allowed) in enumerate(zip(flags, self._VALUES)) if value == allowed[1])

    @classmethod
    def from_index(cls, index):
        """The configuration of branch ``index`` (0..7)."""
        if not 0 <= int(index) < BRANCHES:
            raise IKError(f"configuration index must be 0..7, got {index}")
        bits = [(int(index) >> shift) & 1 for shift in (2, 1, 0)]
        return cls(*(allowed[bit] for allowed, bit in zip(cls._VALUES, bits)))

    def __str__(self):
        return f"{self.shoulder}/{self.elbow}/{self.wrist}"


@dataclasses.dataclass(frozen=True, eq=False)
class IKResult:
    """Joint solutions of N targets.

    Attributes
    ----------
    q : ndarray, shape (N, 6)
        Joint angles, rad; NaN where the target failed.
    success : ndarray of bool, shape (N,)
    residual_pos : ndarray, shape (N,)
        TCP position error of the solution, mm (NaN without a solution).
    residual_rot : ndarray, shape (N,)
        TCP orientation error of the solution, rad (NaN without a solution).
    reason : ndarray of str, shape (N,)
        ``""`` on success, else one of ``"unreachable"``, ``"joint limits"``,
        ``"singular"``, ``"not converged"``.
    """

    q: np.ndarray
    success: np.ndarray
    residual_pos: np.ndarray
    residual_rot: np.ndarray
    reason: np.ndarray

    def with_rows(self, rows, other):
        """A copy with rows ``rows`` (M,) taken from ``other``, an IKResult of M targets."""
        fields = {}
        for field in dataclasses.fields(self):
            values = getattr(self, field.name).copy()
            values[rows] = getattr(other, field.name)
            fields[field.name] = values
        return IKResult(**fields)

    def raise_on_failure(self, label="targets", names=None):
        """Raise IKError naming the failed targets and why; else return self.

        Parameters
        ----------
        label : str
            Names the set of targets in the message (e.g. a program file).
        names : sequence of str, length N, optional
            Names of the targets (label and line); default ``target k`` (0-based).
        """
        failed = np.flatnonzero(~self.success)
        if failed.size:
            name = (lambda i: f"target {i}") if names is None else names.__getitem__
            shown = ", ".join(f"{name(i)}: {self.reason[i]}" for i in failed[:5])
            more = f" and {failed.size - 5} more" if failed.size > 5 else ""
            raise IKError(f"{label}: no IK solution for {failed.size} of {len(self.success)} targets ({shown}{more})")
        return self


def ik_family(robot):
    """The closed-form family of a robot: ``"ur"``, ``"spherical"`` or None (numerical IK only)."""
    std = robot.as_standard()
    a, alpha, d = std.a, std.alpha, std.d
    joint_map = robot.joint_map
    wrist_diagonal = np.diag(np.diag(joint_map)[3:])
    integral = np.allclose(joint_map, np.round(joint_map)) and np.isclose(abs(np.linalg.det(joint_map)), 1.0)
    uncoupled_wrist = (
        np.allclose(joint_map[3:, :3], 0.0)
        and np.allclose(joint_map[:3, 3:], 0.0)
        and np.allclose(joint_map[3:, 3:], wrist_diagonal)
    )

    def perpendicular(angle):
        return abs(np.cos(angle)) < _ZERO

    def parallel(angle):
        return abs(np.sin(angle)) < _ZERO and np.cos(angle) > 0

    common = (
        integral
        and uncoupled_wrist
        and not np.any(np.abs(std.beta[:5]) > _ZERO)
        and perpendicular(alpha[0])
        and parallel(alpha[1])
        and perpendicular(alpha[3])
        and perpendicular(alpha[4])
        and abs(a[3]) < _ZERO
        and abs(a[4]) < _ZERO
        and abs(a[1]) > _ZERO
        and np.hypot(a[2], d[3] * np.sin(alpha[2])) > _ZERO
    )
    if not common:
        return None
    if abs(d[4]) < _ZERO:
        return "spherical"
    if parallel(alpha[2]):
        return "ur"
    return None


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


def ik_numeric(robot, T_base_tcp, q0, *, tol_pos=POS_TOL, tol_rot=ROT_TOL, max_iter=30):
    """Damped Gauss-Newton IK on the full pose, all targets iterating together.

    Meant for identified models close to a nominal arm: from a start within a
    few mm / tenths of a degree it converges quadratically, in 2-4 iterations.
    The damping (the weighted error squared, Sugihara 2011) keeps steps
    bounded near singularities and vanishes at the solution.

    Parameters
    ----------
    robot : Robot
    T_base_tcp : array_like, shape (N, 4, 4) or (4, 4)
        Target TCP poses, base frame, mm.
    q0 : array_like, shape (N, 6) or (6,)
        Start joint angles, rad (e.g. the nominal closed-form solution).
        Rows with NaN fail at once with reason "unreachable".
    tol_pos, tol_rot : float
        Convergence tolerances, mm and rad.
    max_iter : int

    Returns
    -------
    IKResult
        Failure reasons: "not converged" ("singular" when the Jacobian at the
        last iterate is rank deficient), "joint limits" when the converged
        solution leaves the limits, "unreachable" for a NaN start.
    """
    T = _pose_stack(T_base_tcp)
    q0 = np.broadcast_to(np.asarray(q0, dtype=float), (len(T), 6))

    def solve(T, q):
        q = q.copy()
        started = np.all(np.isfinite(q), axis=1)
        res_pos = np.full(len(T), np.nan)
        res_rot = np.full(len(T), np.nan)
        active = np.flatnonzero(started)
        for iteration in range(max_iter + 1):
            pose, jac = fk_and_jacobian(robot, q[active])
            error = pose_error(pose, T[active])
            res_pos[active] = _norm(error[:, :3])
            res_rot[active] = _norm(error[:, 3:])
            done = (res_pos[active] < tol_pos) & (res_rot[active] < tol_rot)
            active, error, jac = active[~done], error[~done], jac[~done]
            if not active.size or iteration == max_iter:
                break
            q[active] += _gauss_newton_step(jac, error)
        converged = started & (res_pos < tol_pos) & (res_rot < tol_rot)
        inside = robot.within_limits(q)
        reason = np.full(len(T), "", dtype=object)
        reason[~started] = UNREACHABLE
        if active.size:
            sv = np.linalg.svd(_scaled(jacobian(robot, q[active])), compute_uv=False)
            reason[active] = np.where(sv[:, -1] < 1e-8 * sv[:, 0], SINGULAR, NOT_CONVERGED)
        reason[converged & ~inside] = JOINT_LIMITS
        success = converged & inside
        return np.where(success[:, None], q, np.nan), success, res_pos, res_rot, reason.astype(str)

    return IKResult(*in_blocks(solve, T, q0))


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
    return in_blocks(lambda q: (frames_branch_index(robot, link_frames(robot, q)),), np.atleast_2d(q))[0]


def frames_branch_index(robot, frames):
    """`branch_index` (N,) of link frames (N, 7, 4, 4) (`trajcomp.kinematics.link_frames`)."""
    origin0, z0 = frames[:, 0, :3, 3], frames[:, 0, :3, 2]
    x1 = frames[:, 1, :3, 0]
    shoulder, elbow, wrist_point = (frames[:, i, :3, 3] for i in (1, 2, 5))
    forward = np.einsum("ni,ni->n", wrist_point - origin0, x1)
    up = z0 * _up_sign(robot)
    ahead = np.sign(forward)[:, None] * x1
    w, e = frames[:, 4, :3, 3] - shoulder, elbow - shoulder
    cross = _dot(w, ahead) * _dot(e, up) - _dot(w, up) * _dot(e, ahead)
    axes = np.einsum("njk,ji->nik", frames[:, :6, :3, 2], robot.joint_map)
    triple = _dot(np.cross(axes[:, 3], axes[:, 5]), axes[:, 4])
    return 4 * (forward < 0) + 2 * (cross <= 0) + (triple < 0)


# ---------------------------------------------------------------- closed form


def _closed_form_family(robot):
    family = ik_family(robot)
    if family is None:
        raise IKError(f"robot {robot.name}: DH table of no closed-form family; use ik_numeric or ik_near")
    return family


def _branches(robot, family, T, seed):
    """Joint angles (N, 8, 6) of all branches, reachable and inside-limits masks (N, 8)."""
    theta, reachable = _dh_branches(robot, family, T, robot.dh_angles(seed))
    q, inside = turn_towards(robot, robot.joint_angles(theta), seed[:, None, :])
    return q, reachable, inside & reachable


def _dh_branches(robot, family, T, theta_seed):
    """DH angles (N, 8, 6) of the branches in configuration order and the reachable mask (N, 8)."""
    std = robot.as_standard()
    a, alpha, d = std.a, std.alpha, std.d
    sa1, s4, s5 = np.sin(alpha[0]), np.sin(alpha[3]), np.sin(alpha[4])
    # Link 6 beyond Rz(theta6) Tz(d6) is fixed: fold it into the flange.
    link6_rest = dh_link_transforms(a[5], alpha[5], 0.0, np.zeros((1, 1)), std.beta[5])[0, 0]
    X = invert(std.T_base_link0) @ T @ invert(link6_rest @ std.T_link6_flange @ std.T_flange_tool)
    R = X[:, None, :3, :3]
    p = X[:, :3, 3] - d[5] * X[:, :3, 2]  # origin of DH frame 5, DH frame 0

    # Branch signs: forward side of axis 1, elbow, joint 5 (see Configuration).
    bits = (np.arange(BRANCHES)[:, None] >> np.array([2, 1, 0])) & 1
    side, elbow_sign, wrist_sign = (1 - 2 * bits).T
    L3 = np.hypot(a[2], d[3] * np.sin(alpha[2]))
    beta = np.arctan2(-d[3] * np.sin(alpha[2]), a[2])
    elbow_sign = elbow_sign * side * np.sign(-a[1] * sa1 * _up_sign(robot))
    wrist_sign = wrist_sign * np.sign(-np.prod(np.diag(robot.joint_map)[3:]) * s4 * s5)

    # Joint 1: the wrist point's offset along z1 is s = d2 + d3 + d4 cos(alpha3).
    s = d[1] + d[2] + d[3] * np.cos(alpha[2])
    r = np.hypot(p[:, 0], p[:, 1])[:, None]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # r ~ 0: on the axis, handled below
        ratio = s * sa1 / r
    on_axis = r < _SINGULAR_SIN
    reachable = on_axis | (np.abs(ratio) <= 1.0 + _REACH_SLACK)
    lean = np.arcsin(np.clip(np.nan_to_num(ratio), -1.0, 1.0))
    theta1 = np.arctan2(p[:, 1], p[:, 0])[:, None] + np.where(side > 0, lean, np.pi - lean)
    theta1 = np.where(on_axis, theta_seed[:, None, 0], theta1)
    turn1 = _cos_sin(theta1)
    forward = p[:, None, 0] * turn1[0] + p[:, None, 1] * turn1[1] - a[0]
    height = np.broadcast_to(sa1 * (p[:, None, 2] - d[0]), forward.shape)

    theta = np.empty(theta1.shape + (6,))
    theta[..., 0] = theta1
    if family == "spherical":
        theta2, theta3, planar_ok = _planar(forward, height, a[1], L3, beta, elbow_sign)
        turn23 = _cos_sin(theta2 + theta3)
        x36, z36 = (_into_link(turn23, alpha[2], _into_link(turn1, alpha[0], _column(R, j))) for j in (0, 2))
        r13, r23, r33 = z36  # column 2 of R_36 = R_03^T R
        sin5 = np.hypot(r13, r23)
        theta5 = np.arctan2(wrist_sign * sin5, -s4 * s5 * r33)
        toward = wrist_sign * s5
        theta4 = np.where(sin5 < _SINGULAR_SIN, theta_seed[:, None, 3], np.arctan2(toward * r23, toward * r13))
        x6 = _into_link(_cos_sin(theta5), alpha[4], _into_link(_cos_sin(theta4), alpha[3], x36))
        theta6 = np.arctan2(x6[1], x6[0])
    else:
        r31, r32, r33 = (_into_link(turn1, alpha[0], _column(R, j))[2] for j in range(3))  # row 2 of R_16 = R_01^T R
        sin5 = np.hypot(r31, r32)
        theta5 = np.arctan2(wrist_sign * sin5, -s4 * s5 * r33)
        toward = wrist_sign * s4
        theta6 = np.where(sin5 < _SINGULAR_SIN, theta_seed[:, None, 5], np.arctan2(-toward * r32, toward * r31))
        # theta2 + theta3 + theta4 is the angle in the arm plane of column 0 of R_14 = R_01^T R W^T,
        # W = Rx(alpha4) Rz(theta5) Rx(alpha5) Rz(theta6) the wrist's rotation.
        wrist_x = _into_link(_cos_sin(theta6), 0.0, _into_link(_cos_sin(theta5), alpha[4], (1.0, 0.0, 0.0)))
        x14 = _into_link(turn1, alpha[0], tuple(sum(R[..., i, k] * wrist_x[k] for k in range(3)) for i in range(3)))
        theta234 = np.arctan2(x14[1], x14[0])
        # Axis 4 lies d5 before the wrist point along z4 = (s4 sin, -s4 cos) in the arm plane.
        theta2, theta3, planar_ok = _planar(
            forward - d[4] * s4 * np.sin(theta234), height + d[4] * s4 * np.cos(theta234), a[1], L3, beta, elbow_sign
        )
        theta4 = theta234 - theta2 - theta3
    theta[..., 1], theta[..., 2], theta[..., 3], theta[..., 4], theta[..., 5] = theta2, theta3, theta4, theta5, theta6
    reachable = reachable & planar_ok
    theta[~reachable] = np.nan
    return theta, reachable


def _planar(x, y, a2, L3, beta, elbow_sign):
    """Two-link planar IK: theta2, theta3 placing ``Rz(t2) [(a2, 0) + L3 Rz(t3 + beta) e_x]`` at (x, y)."""
    cos3 = (x**2 + y**2 - a2**2 - L3**2) / (2.0 * a2 * L3)
    ok = np.abs(cos3) <= 1.0 + _REACH_SLACK
    cos3 = np.clip(cos3, -1.0, 1.0)
    sin3 = elbow_sign * np.sqrt(1.0 - cos3**2)
    theta2 = np.arctan2(y, x) - np.arctan2(L3 * sin3, a2 + L3 * cos3)
    return theta2, np.arctan2(sin3, cos3) - beta, ok


def turn_towards(robot, q, ref):
    """Joints q (..., 6), rad, each moved by whole turns inside the limits nearest ``ref`` (..., 6); and the mask
    (...) of rows whose every joint has a turn inside the limits."""
    turn = 2.0 * np.pi
    with np.errstate(invalid="ignore"):
        lowest = np.ceil((robot.q_min - _LIMIT_TOL - q) / turn)
        highest = np.floor((robot.q_max + _LIMIT_TOL - q) / turn)
        k = np.clip(np.round((ref - q) / turn), lowest, highest)
        inside = np.all(lowest <= highest, axis=-1)
    return q + turn * k, inside


def _up_sign(robot):
    """+1 or -1: the sign making DH z0 point up (along the base z axis)."""
    return -1.0 if robot.as_standard().T_base_link0[2, 2] < 0 else 1.0


# ---------------------------------------------------------------- numerical


def _scaled(jac):
    """Jacobian (N, 6, 6) with the orientation rows in mm (times `_ROT_SCALE`)."""
    return jac * np.array([1.0, 1.0, 1.0, _ROT_SCALE, _ROT_SCALE, _ROT_SCALE])[:, None]


def _gauss_newton_step(jac, error):
    """Damped Gauss-Newton joint step (N, 6) for pose errors (N, 6)."""
    jac = _scaled(jac)
    error = error * np.array([1.0, 1.0, 1.0, _ROT_SCALE, _ROT_SCALE, _ROT_SCALE])
    jt = np.swapaxes(jac, 1, 2)
    damping = 0.5 * np.einsum("ni,ni->n", error, error) + 1e-12
    normal = jt @ jac + damping[:, None, None] * np.eye(6)
    step = np.linalg.solve(normal, (jt @ error[:, :, None]))[:, :, 0]
    largest = np.max(np.abs(step), axis=1, keepdims=True)
    return step * np.minimum(1.0, _MAX_STEP / np.maximum(largest, 1e-300))


def pose_error(T_current, T_target):
    """Pose error (N, 6): target minus current position (mm), rotation vector of R_t R_c^T (rad).

    The rotation vector is computed here rather than with scipy: four times
    faster on this hot path, NaN-tolerant, and exact for the small angles
    that matter (atan2 of the skew part, not arccos of the trace).
    """
    err = np.empty((len(T_current), 6))
    err[:, :3] = T_target[:, :3, 3] - T_current[:, :3, 3]
    current, target = T_current[:, :3, :3], T_target[:, :3, :3]
    axis = err[:, 3:]  # half the skew part of R_t R_c^T: the sum over columns k of current_k x target_k, halved
    for i, (u, v) in enumerate(((1, 2), (2, 0), (0, 1))):
        axis[:, i] = _dot(current[:, u], target[:, v]) - _dot(current[:, v], target[:, u])
    axis *= 0.5
    sin = _norm(axis)
    angle = np.arctan2(sin, 0.5 * (np.einsum("nij,nij->n", current, target) - 1.0))
    axis *= np.where(sin > 0.0, angle / np.where(sin > 0.0, sin, 1.0), 1.0)[:, None]
    return err


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


def _pose_stack(T):
    T = np.asarray(T, dtype=float)
    if T.shape[-2:] != (4, 4) or T.ndim not in (2, 3):
        raise IKError(f"targets must be poses of shape (N, 4, 4) or (4, 4), got {T.shape}")
    return T.reshape(-1, 4, 4)


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


def _cos_sin(angle):
    """(cos, sin) of angles (...), rad."""
    return np.cos(angle), np.sin(angle)


def _into_link(turn, alpha, v):
    """``(Rz(theta) Rx(alpha))^T v``: vectors v (three components (...)) in the frame of the next DH link.

    ``turn`` is (cos theta, sin theta) (...); alpha a scalar twist, rad. Column
    arithmetic instead of stacked 3x3 products (the closed forms run over N x 8 branches).
    """
    cos, sin = turn
    x, y = cos * v[0] + sin * v[1], cos * v[1] - sin * v[0]
    cos_alpha, sin_alpha = np.cos(alpha), np.sin(alpha)
    return x, cos_alpha * y + sin_alpha * v[2], cos_alpha * v[2] - sin_alpha * y


def _column(R, j):
    """Column j of rotations R (..., 3, 3) as three components (...)."""
    return R[..., 0, j], R[..., 1, j], R[..., 2, j]


def _dot(u, v):
    """Row-wise dot products (N,) of (N, 3) arrays (einsum: faster than sums of products on 3 columns)."""
    return np.einsum("ni,ni->n", u, v)


def _norm(u):
    """Row-wise Euclidean norms (N,) of an (N, 3) array."""
    return np.sqrt(_dot(u, u))
