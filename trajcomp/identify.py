"""Kinematic identification: least-squares fit of DH deltas, tool and base.

The parameters are deltas to the nominal standard DH table (``a``, ``alpha``,
``d``, ``theta`` per joint; Hayati ``beta`` for links joining nominally
parallel axes, where ``d`` is ill-conditioned), the TCP position in the
flange frame and, for tracker-frame data, the base pose. Which of them the
data can identify is decided by QR with column pivoting of the scaled
Jacobian: redundant or weak parameters stay at their nominal value and are
reported, with the reason. The fit is a (robust) nonlinear least-squares
problem solved by ``scipy.optimize.least_squares``; parameter uncertainties
come from the covariance of the solution.
"""

import dataclasses
import logging

import numpy as np
from scipy.linalg import qr
from scipy.optimize import least_squares

from trajcomp.errors import CalibrationError
from trajcomp.kinematics import fk
from trajcomp.transforms import invert, rotvec_to_matrix

log = logging.getLogger(__name__)

ANGLE_LEVER = 1000.0  # mm: an angle parameter is scaled as its effect at this lever arm
BASE_NAMES = ("base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz")
TOOL_NAMES = ("tool_x", "tool_y", "tool_z")
_FD_STEP = 1e-6  # scaled units (mm, or rad * ANGLE_LEVER)


def candidate_parameters(robot, *, base=False, tool=True):
    """Names of the parameters a fit may adjust, for a standard-DH robot.

    Parameters
    ----------
    robot : Robot
    base : bool
        Include the six base-pose parameters (tracker-frame data).
    tool : bool
        Include the TCP position in the flange frame.

    Returns
    -------
    list of str
        e.g. ``["a1", "alpha1", "d1", "theta1", ..., "beta2", ..., "tool_x"]``.
    """
    std = robot.as_standard()
    names = []
    for i in range(6):
        names += [f"a{i + 1}", f"alpha{i + 1}", f"d{i + 1}", f"theta{i + 1}"]
        if i < 5 and abs(np.sin(std.alpha[i])) < 1e-6:
            names.append(f"beta{i + 1}")
    if base:
        names += BASE_NAMES
    if tool:
        names += TOOL_NAMES
    return names


def is_angle(name):
    """True for parameters in rad, False for those in mm."""
    return name.startswith(("alpha", "theta", "beta", "base_r"))


def apply_deltas(robot, names, delta):
    """The robot with parameter deltas applied.

    Parameters
    ----------
    robot : Robot
        Nominal robot (any convention; the result is standard DH).
    names : sequence of str
        Parameter names, see `candidate_parameters`.
    delta : array_like, shape (P,)
        Deltas in mm or rad.
    """
    std = robot.as_standard()
    table = {key: getattr(std, key).copy() for key in ("a", "alpha", "d", "theta_offset", "beta")}
    base = np.zeros(6)
    tool = np.zeros(3)
    for name, value in zip(names, delta):
        if name.startswith("base_"):
            base[BASE_NAMES.index(name)] = value
        elif name.startswith("tool_"):
            tool[TOOL_NAMES.index(name)] = value
        else:
            kind, joint = name[:-1], int(name[-1]) - 1
            table["theta_offset" if kind == "theta" else kind][joint] += value
    T_base_link0 = std.T_base_link0
    if np.any(base):
        shift = np.eye(4)
        shift[:3, :3] = rotvec_to_matrix(base[3:])
        shift[:3, 3] = base[:3]
        T_base_link0 = shift @ T_base_link0
    T_flange_tool = std.T_flange_tool.copy()
    T_flange_tool[:3, 3] += tool
    return std.replace(T_base_link0=T_base_link0, T_flange_tool=T_flange_tool, **table)


def _scales(names):
    return np.array([1.0 / ANGLE_LEVER if is_angle(n) else 1.0 for n in names])


def position_jacobian(robot, q, names, delta):
    """d(TCP position)/d(scaled parameter), by forward differences.

    Returns
    -------
    ndarray, shape (3 N, P)
        Rows ordered x1, y1, z1, x2, ...; columns per scaled parameter
        (mm per mm, or mm per ``ANGLE_LEVER`` rad).
    """
    scales = _scales(names)
    base = fk(apply_deltas(robot, names, delta), q)[:, :3, 3].ravel()
    jac = np.empty((base.size, len(names)))
    for k in range(len(names)):
        step = np.array(delta, dtype=float)
        step[k] += _FD_STEP * scales[k]
        jac[:, k] = (fk(apply_deltas(robot, names, step), q)[:, :3, 3].ravel() - base) / _FD_STEP
    return jac


@dataclasses.dataclass(frozen=True)
class Identifiability:
    """Which candidate parameters the measurement set can identify.

    Attributes
    ----------
    kept : list of str
    fixed : dict
        ``{name: reason}`` for parameters left at their nominal value.
    condition : float
        Condition number of the scaled Jacobian of the kept parameters.
    """

    kept: list
    fixed: dict
    condition: float


def analyse_identifiability(jac, names, rtol=1e-3):
    """Pick an identifiable parameter subset by QR with column pivoting.

    Parameters
    ----------
    jac : ndarray, shape (M, P)
        Scaled Jacobian (see `position_jacobian`).
    names : sequence of str
    rtol : float
        A parameter is kept while its pivot ``|R_kk|`` is at least ``rtol``
        times the largest; below that its effect is redundant with the kept
        ones (or too weak to estimate) and it is fixed.
    """
    _, r, perm = qr(jac, mode="economic", pivoting=True)
    diag = np.zeros(len(names))  # fewer rows than parameters: the rest have no pivot
    diag[: min(r.shape)] = np.abs(np.diag(r))
    keep = diag >= rtol * diag[0]
    kept = sorted((names[p] for p in perm[keep]), key=names.index)
    fixed = {}
    for p, d in zip(perm[~keep], diag[~keep]):
        reason = "redundant with kept parameters" if d < 1e-6 * diag[0] else "too weakly observed by these measurements"
        fixed[names[p]] = f"{reason} (pivot {d / diag[0]:.1e})"
    sub = jac[:, [names.index(n) for n in kept]]
    sv = np.linalg.svd(sub, compute_uv=False)
    return Identifiability(kept, fixed, float(sv[0] / sv[-1]))


@dataclasses.dataclass(frozen=True, eq=False)
class DHFit:
    """Result of `identify_dh`.

    Attributes
    ----------
    robot : Robot
        Identified robot (standard DH), base frame = the robot's base.
    names : list of str
        Identified parameters.
    delta, sigma : ndarray, shape (P,)
        Deltas to nominal and their standard deviations (mm or rad).
    identifiability : Identifiability
    residuals : ndarray, shape (N, 3)
        Measured minus identified TCP position, mm, base frame.
    outliers : ndarray
        Indices of rows whose residual is a gross outlier.
    T_tracker_base : ndarray, shape (4, 4)
        Base pose in the tracker frame (identity for base-frame data).
    """

    robot: object
    names: list
    delta: np.ndarray
    sigma: np.ndarray
    identifiability: Identifiability
    residuals: np.ndarray
    outliers: np.ndarray
    T_tracker_base: np.ndarray


def best_fit_transform(src, dst):
    """Rigid transform T (4, 4) minimising ``|T src - dst|`` for points (N, 3) (Kabsch)."""
    cs, cd = src.mean(axis=0), dst.mean(axis=0)
    u, _, vt = np.linalg.svd((src - cs).T @ (dst - cd))
    fix = np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))])
    rot = vt.T @ fix @ u.T
    out = np.eye(4)
    out[:3, :3] = rot
    out[:3, 3] = cd - rot @ cs
    return out


def outlier_rows(residuals, threshold=6.0, min_excess=0.5):
    """Indices of rows whose residual is a gross outlier.

    A row is one when its residual norm exceeds the median norm by more than
    ``threshold`` robust standard deviations (1.4826 MAD) *and* by more than
    ``min_excess`` mm: smooth non-geometric errors are not outliers, a
    tracker beam break or a wrong row is.
    """
    norm = np.linalg.norm(residuals, axis=1)
    median = np.median(norm)
    spread = 1.4826 * np.median(np.abs(norm - median))
    return np.flatnonzero(norm > median + max(threshold * spread, min_excess))


def identify_dh(robot, q, measured, *, frame="base", tool=True, loss="linear", rtol=1e-3):
    """Least-squares identification of the robot's kinematic parameters.

    Parameters
    ----------
    robot : Robot
        Nominal robot.
    q : ndarray, shape (N, 6)
        Commanded joint angles, rad.
    measured : ndarray, shape (N, 3)
        Measured TCP positions, mm, in the base frame or (``frame="tracker"``)
        in the tracker frame.
    frame : {"base", "tracker"}
    tool : bool
        Identify the TCP position in the flange frame.
    loss : {"linear", "soft_l1", "huber", "cauchy"}
        Robust loss of scipy.optimize.least_squares; residual scale 0.1 mm.
    rtol : float
        Identifiability threshold, see `analyse_identifiability`.

    Raises
    ------
    CalibrationError
        Too few measurements for the identifiable parameters, or NaN input.
    """
    q = np.asarray(q, dtype=float)
    measured = np.asarray(measured, dtype=float)
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(measured))):
        raise CalibrationError("joint or measured values contain NaN or infinity")
    T_tracker_base = np.eye(4)
    if frame == "tracker":
        T_tracker_base = best_fit_transform(fk(robot, q)[:, :3, 3], measured)
        measured = (invert(T_tracker_base) @ np.column_stack([measured, np.ones(len(measured))]).T).T[:, :3]
    names = candidate_parameters(robot, base=frame == "tracker", tool=tool)
    zero = np.zeros(len(names))
    ident = analyse_identifiability(position_jacobian(robot, q, names, zero), names, rtol)
    kept = ident.kept
    if 3 * len(q) < 2 * len(kept):
        raise CalibrationError(
            f"{len(q)} measured positions are too few to identify {len(kept)} parameters "
            f"(need at least {int(np.ceil(2 * len(kept) / 3))})"
        )
    scales = _scales(kept)

    def residual(x):
        return (fk(apply_deltas(robot, kept, x * scales), q)[:, :3, 3] - measured).ravel()

    def jacobian(x):
        return position_jacobian(robot, q, kept, x * scales)

    sol = least_squares(residual, np.zeros(len(kept)), jac=jacobian, loss=loss, f_scale=0.1, method="trf")
    delta = sol.x * scales
    identified = apply_deltas(robot, kept, delta)
    residuals = measured - fk(identified, q)[:, :3, 3]
    dof = max(residuals.size - len(kept), 1)
    variance = float(np.sum(residuals**2) / dof)
    jac = jacobian(sol.x)
    cov = np.linalg.pinv(jac.T @ jac) * variance
    sigma = np.sqrt(np.clip(np.diag(cov), 0.0, None)) * scales
    log.info("identified %d parameters, fixed %d, rms %.4f mm", len(kept), len(ident.fixed), np.sqrt(variance))
    return DHFit(identified, kept, delta, sigma, ident, residuals, outlier_rows(residuals), T_tracker_base)
