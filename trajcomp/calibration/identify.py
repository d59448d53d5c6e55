"""Kinematic identification: one robust least-squares fit of the whole arm.

Unknowns (see `trajcomp.arm.parameters`): DH deltas, the TCP position in the
flange frame, for 6-DoF data the orientation of the measured frame, for
tracker-frame data the base registration, and optionally the joint-error
terms of `trajcomp.model.joint_errors`. All are refined together by Gauss-Newton
on the analytic Jacobian, vectorized over the N measurements, starting from
the nominal robot (and a best-fit registration of its TCP positions).

Residuals per measurement: the position error (mm) and, when orientations
are measured, the orientation error (rotation vector, rad) times
``orientation_weight`` (mm per rad): the stated weighting of one against the
other. A robust loss (iteratively re-weighted) bounds the pull of any one
measurement; gross outliers are reported by row, not silently dropped.
Which parameters the data identify on their own is decided by QR with
column pivoting of the scaled Jacobian over the whole parameter set, and
reported; every candidate is then refined, but only along the directions
of parameter space the data identify (a truncated pseudo-inverse: singular
values below ``rtol`` times the largest are not used). A combination the
data cannot see stays at its starting value (the nominal arm), instead of
one pivoted parameter absorbing the whole confounded effect: measured at
one tool orientation, the wrist and tool parameters are such combinations,
and moving them spoils every other orientation. Where a hidden combination
joins the arm with a frame of the measurement (base z of the tracker
registration with d1), the frame moves and the arm stays at nominal
(`trajcomp.arm.parameters.prior_weights`).
"""

import dataclasses
import functools
import logging

import numpy as np

from trajcomp.calibration.options import LOSSES, ORIENTATION_WEIGHT
from trajcomp.model import joint_errors
from trajcomp.errors import CalibrationError
from trajcomp.model.joint_errors import SplineBasis
from trajcomp.arm.kinematics import fk
from trajcomp.arm.parameters import (
    BASE_NAMES,
    TARGET_NAMES,
    apply_deltas,
    candidate_parameters,
    is_robot_parameter,
    pose_jacobian,
    prior_weights,
    scales,
)
from trajcomp.arm.transforms import invert, matrix_to_rotvec, mean_rotation, rotvec_to_matrix
from trajcomp.support.parallel import share_blocks

log = logging.getLogger(__name__)

ROBUST_SCALE = 3.0  # the loss turns robust beyond this many median residual norms
MAX_ITERATIONS = 50
STEP_TOLERANCE = 1e-7  # mm (or rad * ANGLE_LEVER): converged when no scaled parameter moves more
COST_TOLERANCE = 1e-5  # or when a step lowers the weighted cost by less than this fraction (its RMS by 5 ppm)
MEASUREMENTS_PER_SPLINE = 3  # a knot step is tried only with at least this many measurements per spline term
BOOTSTRAP_DRAWS = 1000  # random weightings of the held-out regions that share the chosen knot step's penalties out


@dataclasses.dataclass(frozen=True)
class Identifiability:
    """Which candidate parameters the measurement set can identify.

    Attributes
    ----------
    kept : list of str
    fixed : dict
        ``{name: reason}`` for parameters the data do not identify on their
        own: they move only within the combinations the data do identify.
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
        Scaled Jacobian (columns per mm, or per ``ANGLE_LEVER`` rad).
    names : sequence of str
    rtol : float
        A parameter is kept while its pivot ``|R_kk|`` is at least ``rtol``
        times the largest; below that its effect is redundant with the kept
        ones (or too weak to estimate) and it is fixed.
    """
    from scipy.linalg import qr  # here: compensating never needs it

    if jac.shape[0] > jac.shape[1]:
        jac = np.linalg.qr(jac, mode="r")  # same pivots and singular values, P x P: cheap to pivot
    _, r, perm = qr(jac, mode="economic", pivoting=True)
    diag = np.zeros(len(names))  # fewer rows than parameters: the rest have no pivot
    diag[: min(r.shape)] = np.abs(np.diag(r))
    keep = diag >= rtol * diag[0]
    kept = sorted((names[p] for p in perm[keep]), key=names.index)
    fixed = {}
    for p, d in zip(perm[~keep], diag[~keep]):
        reason = "redundant with kept parameters" if d < 1e-6 * diag[0] else "too weakly observed by these measurements"
        fixed[names[p]] = f"{reason} (pivot {d / diag[0]:.1e})"
    sv = np.linalg.svd(jac[:, [names.index(n) for n in kept]], compute_uv=False)
    return Identifiability(kept, fixed, float(sv[0] / sv[-1]))


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


def robust_weights(norms, loss):
    """IRLS weights (N,) of residual norms (N,) for a loss, scale `ROBUST_SCALE` median norms."""
    if loss not in LOSSES:
        raise CalibrationError(f"unknown loss {loss!r} (one of {', '.join(LOSSES)})")
    if loss == "linear":
        return np.ones_like(norms)
    z = norms / max(ROBUST_SCALE * np.median(norms), 1e-9)
    if loss == "huber":
        return np.where(z <= 1.0, 1.0, 1.0 / np.maximum(z, 1.0))
    if loss == "soft_l1":
        return 1.0 / np.sqrt(1.0 + z**2)
    return 1.0 / (1.0 + z**2)


@dataclasses.dataclass(frozen=True, eq=False)
class KinematicFit:
    """Result of `identify`.

    Attributes
    ----------
    robot : Robot
        Identified robot (standard DH, identified TCP position), base frame
        = the robot's base.
    names : list of str
        Identified parameters (DH, tool, registration, target, joint terms).
    delta : ndarray, shape (P,)
        Change from the start, mm or rad (joint terms: their coefficients).
        For ``base_*`` and ``target_*`` the change is the pose (rotation
        vector) of the final frame in the starting one.
    sigma : ndarray, shape (P,)
        Standard deviation of ``delta``, same units (a property, computed
        from ``normal`` and ``variance`` when first asked: it takes an
        eigendecomposition of the normal equations, which a joint fit with
        hundreds of spline terms makes dear and no caller of those needs).
    identifiability : Identifiability
    joint_errors : JointResidual
        The identified joint-error terms (empty without them).
    residuals : ndarray, shape (N, 3)
        Measured minus identified TCP position, mm, base frame.
    rotation_residuals : ndarray, shape (N, 3), or None
        Measured relative to identified orientation (rotation vector, rad, base axes).
    weights : ndarray, shape (N,)
        Final robust weight of each measurement (1 = full weight).
    outliers : ndarray of int
        Rows whose residual is a gross outlier (`outlier_rows`).
    T_tracker_base : ndarray, shape (4, 4)
        Base pose in the tracker frame (identity for base-frame data).
    R_tcp_target : ndarray, shape (3, 3)
        Orientation of the measured frame in the TCP frame (identity without orientations).
    orientation_weight : float
        mm per rad of the orientation residuals.
    normal : ndarray, shape (P, P)
        Normal equations of the weighted rows, solver units (`scales`).
    variance : float
        Weighted residual variance per degree of freedom, mm^2.
    rtol : float
        As `identify`'s: the directions ``normal`` sees below it are left
        out of ``sigma``.
    """

    robot: object
    names: list
    delta: np.ndarray
    identifiability: Identifiability
    joint_errors: object
    residuals: np.ndarray
    rotation_residuals: np.ndarray
    weights: np.ndarray
    outliers: np.ndarray
    T_tracker_base: np.ndarray
    R_tcp_target: np.ndarray
    orientation_weight: float
    normal: np.ndarray = dataclasses.field(repr=False)
    variance: float
    rtol: float

    @functools.cached_property
    def sigma(self):
        """Standard deviations (P,) of ``delta``, mm or rad."""
        eigenvalues, vectors = _seen(self.normal, self.rtol)
        return scales(self.names) * np.sqrt(vectors**2 @ (1.0 / eigenvalues) * self.variance)


class _Jacobian:
    """Derivative of the residual rows: dense columns, and spline columns kept as joint column times basis.

    A spline term's column is the column of its joint's DH angle times the
    term's basis value, non-zero for 4 terms of each joint at each row
    (`trajcomp.model.joint_errors.SplineBasis.support`): with hundreds of
    spline terms the normal equations are assembled from those 4 per joint
    and row (`normal_equations`) instead of a dense (N, rows, P) array.

    Parameters
    ----------
    dense : ndarray, shape (N, rows, D)
        Columns of the parameters ``dense_index`` (D,).
    theta : ndarray, shape (N, rows, 6)
        Columns of the six DH angles.
    spline_columns : ndarray of int, shape (N, B, 4)
        Parameter index of the non-zero spline terms of each of the B spline joints ``spline_joints`` (B,), per row.
    spline_values : ndarray, shape (N, B, 4)
        Their basis values.
    size : int
        Number of parameters P.
    """

    def __init__(self, dense, theta, dense_index, spline_columns, spline_values, spline_joints, size):
        self.dense, self.theta, self.dense_index, self.size = dense, theta, dense_index, size
        self.spline_columns, self.spline_values, self.spline_joints = spline_columns, spline_values, spline_joints

    def with_splines(self, problem):
        """This Jacobian, of a problem without spline terms, for ``problem``: the same parameters with spline
        terms appended (`_Problem.with_splines`), at the same point with those terms zero."""
        return _Jacobian(self.dense, self.theta, self.dense_index, problem.spline_columns, problem.spline_values,
                         problem.spline_joints, len(problem.names))

    def matrix(self):
        """Dense Jacobian (N * rows, P), for problems without spline terms."""
        return self.dense.reshape(-1, self.size)

    def rows(self, pick):
        """The Jacobian of the measurements ``pick`` (index or mask over N) alone."""
        return _Jacobian(self.dense[pick], self.theta[pick], self.dense_index, self.spline_columns[pick],
                         self.spline_values[pick], self.spline_joints, self.size)

    def apply(self, step):
        """Change (N, rows) of the residual rows for a parameter step (P,) (solver units times scale)."""
        out = self.dense @ step[self.dense_index]
        spline_angles = np.einsum("nbk,nbk->nb", self.spline_values, step[self.spline_columns])
        return out + np.einsum("nrb,nb->nr", self.theta[:, :, self.spline_joints], spline_angles)

    def normal_equations(self, residual, weights, scale):
        """``(A^T W A, A^T W b)`` (P, P), (P,) of the scaled Jacobian A and residual rows b, rows weighted."""
        from scipy import sparse  # here: compensating never needs it

        dense = self.dense * scale[self.dense_index]
        rooted = dense.reshape(-1, dense.shape[2]) * np.sqrt(np.repeat(weights, dense.shape[1]))[:, None]
        normal = np.zeros((self.size, self.size))
        gradient = np.zeros(self.size)
        normal[np.ix_(self.dense_index, self.dense_index)] = rooted.T @ rooted  # one symmetric product (BLAS syrk)
        gradient[self.dense_index] = np.einsum("nrp,nr->p", dense, weights[:, None] * residual)
        if not len(self.spline_joints):
            return normal, gradient
        # the spline columns: spread (P, N * B) takes the column of joint b's angle at row n to its 4 terms
        count, joints = self.spline_columns.shape[:2]
        spread = sparse.csc_matrix(((self.spline_values * scale[self.spline_columns]).ravel(),
                                    self.spline_columns.ravel(), np.arange(0, 4 * count * joints + 1, 4)),
                                   shape=(self.size, count * joints))
        theta = self.theta[:, :, self.spline_joints]  # (N, rows, B)
        weighted = weights[:, None, None] * theta
        products = np.matmul(weighted.transpose(0, 2, 1), theta)  # (N, B, B): block n of a block-diagonal matrix
        pairs = sparse.csr_matrix((products.ravel(), np.repeat(np.arange(count * joints).reshape(count, 1, joints),
                                                                joints, axis=1).ravel(),
                                   np.arange(0, count * joints * joints + 1, joints)), shape=(count * joints,) * 2)
        normal += (spread @ pairs @ spread.T).toarray()
        cross = spread @ np.matmul(weighted.transpose(0, 2, 1), dense).reshape(count * joints, dense.shape[2])  # (P, D)
        normal[:, self.dense_index] += cross
        normal[self.dense_index, :] += cross.T
        gradient += spread @ np.einsum("nrb,nr->nb", weighted, residual).ravel()
        return normal, gradient


class _Problem:
    """State and residuals of one fit: the robot, frames and joint terms being refined."""

    def __init__(self, start, nominal, q, measured, rotation, T_tracker_base, R_tcp_target, weight, basis=None):
        self.start, self.nominal, self.q = start, nominal, q
        self.measured, self.rotation = measured, rotation
        self.T_tracker_base, self.R_tcp_target, self.weight = T_tracker_base, R_tcp_target, weight
        self.basis = basis

    def setup(self, names, features=None):
        """Take the parameters ``names`` (the residual's columns), all starting at 0.

        ``features`` (N, T) are those of their joint-error terms when at hand.
        """
        self.names = list(names)
        index = {n: k for k, n in enumerate(self.names)}
        self.terms = [n for n in names if joint_errors.is_term(n) and not joint_errors.is_spline(n)]
        self.features = joint_errors.features(self.nominal, self.q, self.terms) if features is None else features
        self.term_index = np.array([index[n] for n in self.terms], dtype=int)
        self.term_joints = np.eye(6)[[joint_errors.term_joint(n) for n in self.terms]].reshape(-1, 6)  # (T, 6)
        self.spline_joints = np.array(sorted({joint_errors.term_joint(n) for n in names if joint_errors.is_spline(n)}),
                                      dtype=int)
        columns, values = [np.zeros((len(self.q), 0, 4), dtype=int)], [np.zeros((len(self.q), 0, 4))]
        for j in self.spline_joints:
            local, basis_values = self.basis.support(self.q, j)
            own = np.array([index[f"spline{j + 1}_{k}"] for k in range(self.basis.intervals(j) + 3)])
            columns.append(own[local][:, None])
            values.append(basis_values[:, None])
        self.spline_columns, self.spline_values = np.concatenate(columns, axis=1), np.concatenate(values, axis=1)
        self.dense_index = np.array([k for k, n in enumerate(self.names) if not joint_errors.is_spline(n)], dtype=int)
        # a dense column is a column of pose_jacobian: a geometric parameter's, or a term's joint angle's times its feature
        self.geometric = [n for n in self.names if not joint_errors.is_term(n)]
        dense_names = [self.names[k] for k in self.dense_index]
        self.dense_source = np.array([len(self.geometric) + joint_errors.term_joint(n) if joint_errors.is_term(n)
                                      else self.geometric.index(n) for n in dense_names], dtype=int)
        with_ones = np.column_stack([self.features, np.ones(len(self.q))])  # the last column: a geometric parameter's
        self.dense_factor = with_ones[:, [self.terms.index(n) if joint_errors.is_term(n) else -1 for n in dense_names]]
        self.roughness = np.zeros((len(names), len(names)))
        if len(self.spline_joints):
            self.roughness = self.basis.roughness(self.names) * self.basis.penalty * len(self.q)
        self.x = np.zeros(len(names))

    def with_splines(self, basis):
        """This set-up problem (without spline terms) with the spline terms of ``basis`` appended to its
        parameters, a new problem sharing its measurements and joint-error features."""
        problem = _Problem(self.start, self.nominal, self.q, self.measured, self.rotation, self.T_tracker_base,
                           self.R_tcp_target, self.weight, basis)
        problem.setup(self.names + basis.names(), self.features)
        return problem

    def state(self, x):
        """Robot, joint errors, registration and target rotation at parameter vector x."""
        robot_names = [n for n in self.names if is_robot_parameter(n) and not joint_errors.is_term(n)]
        robot = apply_deltas(self.start, robot_names, [v for n, v in zip(self.names, x) if n in robot_names])
        term_names = [n for n in self.names if joint_errors.is_term(n)]
        terms = joint_errors.JointResidual(term_names, [v for n, v in zip(self.names, x) if joint_errors.is_term(n)],
                                           basis=self.basis if len(self.spline_joints) else None)
        T_tb, R_target = self.T_tracker_base.copy(), self.R_tcp_target.copy()
        pick = {n: v for n, v in zip(self.names, x)}
        if any(n in pick for n in BASE_NAMES):
            step = np.eye(4)
            step[:3, :3] = rotvec_to_matrix([pick.get(n, 0.0) for n in BASE_NAMES[3:]])
            step[:3, 3] = [pick.get(n, 0.0) for n in BASE_NAMES[:3]]
            T_tb = T_tb @ step
        if any(n in pick for n in TARGET_NAMES):
            R_target = R_target @ rotvec_to_matrix([pick.get(n, 0.0) for n in TARGET_NAMES])
        return robot, terms, T_tb, R_target

    def evaluate(self, x, jacobian=True):
        """Residual rows (N, 3 or 6) and, optionally, their `_Jacobian` at x."""
        robot, _, T_tb, R_target = self.state(x)
        offsets = (self.features * x[self.term_index]) @ self.term_joints
        offsets[:, self.spline_joints] += np.einsum("nbk,nbk->nb", self.spline_values, x[self.spline_columns])
        q = self.q + offsets @ np.linalg.inv(self.nominal.joint_map).T
        thetas = [f"theta{j}" for j in range(1, 7)]
        T_tcp, jac = pose_jacobian(robot, q, self.geometric + thetas, R_target) if jacobian else (fk(robot, q), None)
        T_base_tracker = invert(T_tb)
        measured = self.measured @ T_base_tracker[:3, :3].T + T_base_tracker[:3, 3]
        rows = [T_tcp[:, :3, 3] - measured]
        if self.rotation is not None:
            R_measured = T_base_tracker[:3, :3] @ self.rotation
            R_predicted = T_tcp[:, :3, :3] @ R_target
            rows.append(self.weight * matrix_to_rotvec(R_predicted @ np.swapaxes(R_measured, 1, 2)))
        residual = np.concatenate(rows, axis=1)
        if not jacobian:
            return residual, None
        width = residual.shape[1]
        jac = jac[:, :width]
        jac[:, 3:] *= self.weight
        dense = jac[:, :, self.dense_source] * self.dense_factor[:, None, :]
        return residual, _Jacobian(dense, jac[:, :, len(self.geometric):], self.dense_index, self.spline_columns,
                                   self.spline_values, self.spline_joints, len(self.names))

    def penalty(self, x, scale):
        """The roughness penalty of the spline terms at x (scaled units)."""
        z = x / scale
        return float(z @ self.roughness @ z)


def _row_norms(residual):
    return np.linalg.norm(residual, axis=1)


def identifiability(robot, q, *, rotation=False, frame="base", tool=True, joint_terms=False, rtol=1e-3):
    """Which parameters measurements of the nominal robot at joints q would identify.

    Parameters
    ----------
    robot : Robot
    q : ndarray, shape (N, 6)
        Planned joint angles, rad.
    rotation : bool
        Orientations measured too (6-DoF).
    frame, tool, joint_terms, rtol
        As `identify`.

    Returns
    -------
    Identifiability
    """
    q = np.asarray(q, dtype=float)
    seen = fk(robot, q)
    problem = _Problem(robot, robot, q, seen[:, :3, 3], seen[:, :3, :3] if rotation else None, np.eye(4), np.eye(3),
                       ORIENTATION_WEIGHT)
    names = candidate_parameters(robot, tool=tool, orientation=rotation, tracker=frame == "tracker")
    return _identifiable(problem, names + (joint_errors.term_names() if joint_terms else []), rtol)[0]


def _identifiable(problem, names, rtol):
    """`Identifiability` of candidate ``names`` in ``problem`` at its start, and the problem's residual rows and
    `_Jacobian` there (``problem`` is left set up with ``names``)."""
    problem.setup(names)
    residual, jac = problem.evaluate(problem.x)
    return analyse_identifiability(jac.matrix() * scales(names), names, rtol), (residual, jac)


def identify(robot, q, measured, *, rotation=None, frame="base", tool=True, joint_terms=False, splines=None,
             loss="huber", rtol=1e-3, orientation_weight=ORIENTATION_WEIGHT, nominal=None, T_tracker_base=None,
             R_tcp_target=None, start_values=None, identifiability=None):
    """Robust least-squares identification of the arm, its TCP and the tracker registration.

    Parameters
    ----------
    robot : Robot
        Starting robot (the nominal one, or an identified one to refine).
    q : ndarray, shape (N, 6)
        Commanded joint angles, rad.
    measured : ndarray, shape (N, 3)
        Measured positions of the measured point, mm, in the base frame or
        (``frame="tracker"``) in the tracker frame.
    rotation : ndarray, shape (N, 3, 3), optional
        Measured orientations of the measured frame, same frame as ``measured``.
    frame : {"base", "tracker"}
    tool : bool
        Identify the TCP position in the flange frame.
    joint_terms : bool
        Also identify the joint-error terms (`trajcomp.model.joint_errors`).
    splines : SplineBasis, optional
        Also identify these spline terms of the joint angles, with their
        roughness penalty (they are not subject to the identifiability
        analysis: the penalty decides how much of each the data carry).
    loss : {"linear", "soft_l1", "huber", "cauchy"}
        Robust loss on each measurement's residual norm, scale `ROBUST_SCALE`
        median norms.
    rtol : float
        Identifiability threshold, see `analyse_identifiability`.
    orientation_weight : float
        mm per rad of orientation residual.
    nominal : Robot, optional
        Robot of the joint-error features (default: ``robot``).
    T_tracker_base, R_tcp_target : ndarray, optional
        Given registration (4, 4) and measured-frame orientation (3, 3): kept
        fixed. Default: estimated, starting from a best fit of ``robot``.
    start_values : dict, optional
        ``{name: value}`` the fit starts from (an earlier fit's parameters,
        mm or rad); the others start at 0.
    identifiability : Identifiability, optional
        What these measurements identify of the candidate parameters from
        this ``robot``, when known (an earlier fit's with the same
        arguments but ``splines`` and ``start_values``): not analysed again.

    Returns
    -------
    KinematicFit

    Raises
    ------
    CalibrationError
        Too few measurements for the identifiable parameters, or NaN input.
    """
    q = np.asarray(q, dtype=float)
    measured = np.asarray(measured, dtype=float)
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(measured))) or (
        rotation is not None and not np.all(np.isfinite(rotation))
    ):
        raise CalibrationError("joint or measured values contain NaN or infinity")
    nominal = robot if nominal is None else nominal
    start_tcp = fk(robot, q)
    register = frame == "tracker" and T_tracker_base is None
    if T_tracker_base is None:
        T_tracker_base = best_fit_transform(start_tcp[:, :3, 3], measured) if frame == "tracker" else np.eye(4)
    orient = rotation is not None and R_tcp_target is None
    if R_tcp_target is None:
        R_tcp_target = np.eye(3)
        if rotation is not None:
            in_base = invert(T_tracker_base)[:3, :3] @ rotation
            R_tcp_target = mean_rotation(np.swapaxes(start_tcp[:, :3, :3], 1, 2) @ in_base)
    names = candidate_parameters(robot, tool=tool, orientation=orient, tracker=register)
    if joint_terms:
        names += joint_errors.term_names()
    problem = _Problem(robot, nominal, q, measured, rotation, T_tracker_base, R_tcp_target, orientation_weight,
                       splines)
    ident, start = (identifiability, None) if identifiability is not None else _identifiable(problem, names, rtol)
    kept = ident.kept
    rows = 3 if rotation is None else 6  # residuals per measurement
    if rows * len(q) < 2 * len(kept):
        raise CalibrationError(
            f"{len(q)} measurements are too few to identify {len(kept)} parameters "
            f"(need at least {int(np.ceil(2 * len(kept) / rows))})"
        )
    if splines is not None or start_values or start is None:  # other parameters or another start than analysed
        names += [] if splines is None else splines.names()
        problem.setup(names)
        problem.x = np.array([(start_values or {}).get(name, 0.0) for name in names])
        start = None
    scale = scales(names)
    x, weights, jac, residual = _solve(problem, scale, loss, rtol, start)
    normal, _ = jac.normal_equations(residual, weights, scale)
    x = scale * _least_cost(normal + problem.roughness, x / scale, prior_weights(names), rtol)
    fit = _fit_result(problem, x, weights, normal, ident, rtol)
    log.info("identified %d parameters, fixed %d, rms %.4f mm", len(kept), len(ident.fixed),
             np.sqrt(np.mean(np.sum(fit.residuals**2, axis=1))))
    return fit


def _fit_result(problem, x, weights, normal, identifiability, rtol, rows=slice(None)):
    """The `KinematicFit` of ``problem`` at parameters x (P,), over its measurements ``rows`` (default: all).

    ``weights`` are those rows' robust weights and ``normal`` their normal
    equations (P, P) in solver units, which give the standard deviations.
    """
    residual = problem.evaluate(x, jacobian=False)[0][rows]
    robot_fit, terms, T_tb, R_target = problem.state(x)
    variance = float(np.sum(weights[:, None] * residual**2) / max(residual.size - len(identifiability.kept), 1))
    position = -residual[:, :3]
    rotation_residuals = None if problem.rotation is None else -residual[:, 3:] / problem.weight
    return KinematicFit(
        robot=robot_fit, names=problem.names, delta=x, identifiability=identifiability,
        joint_errors=terms, residuals=position, rotation_residuals=rotation_residuals, weights=weights,
        outliers=outlier_rows(position), T_tracker_base=T_tb, R_tcp_target=R_target, orientation_weight=problem.weight,
        normal=normal, variance=variance, rtol=rtol,
    )


class Linearisation:
    """The least-squares problem of a fit linearised at its parameters, to refit it without some of its rows.

    The residual rows, their Jacobian, robust weights and normal equations
    are taken once, at parameters x (a converged fit); the fit of every row
    but a held-out set is then one Gauss-Newton step from x, with the normal
    equations of the rows held out taken off and the roughness penalty
    scaled to the rows kept, as `identify` scales it (`without`). What the
    step leaves out is of second order in the change of the parameters,
    which holding out a part of the rows keeps small (ur10-ipa, a fifth of
    5,891 rows held out: a second step moves the held-out mean error by
    less than 0.01 micrometre).

    Parameters
    ----------
    problem : _Problem
        The problem, set up with the fit's parameter names.
    x : ndarray, shape (P,)
        The fit's parameters, mm or rad.
    weights : ndarray, shape (N,), optional
        Robust weights of the rows (default: those of ``loss`` at x).
    loss : str
        Robust loss (`LOSSES`) giving the default weights.
    identifiability : Identifiability, optional
        The fit's, recorded in the refits (needed by `fit_without`).
    rtol : float
        As `identify`'s: a refit does not step along directions the normal
        equations see below ``rtol`` times their best, and leaves them out
        of its standard deviations.
    ridge : bool
        Step through a Cholesky factorisation with a relative ridge instead
        (`_penalised_step`: cheaper than the eigendecomposition `rtol` needs;
        the selection's candidates, which step from no spline terms at all).
    parts : list of ndarray of int, optional
        Row indices partitioning the rows (held-out regions): the normal
        equations of the whole are summed from theirs, which are kept in
        ``parts`` as ``(rows, Jacobian of the rows, normal equations)``.
    evaluated : tuple, optional
        ``problem.evaluate(x)`` (residual rows and `_Jacobian`) when at hand.
    """

    def __init__(self, problem, x, weights=None, loss="huber", identifiability=None, rtol=1e-3, ridge=False,
                 parts=None, evaluated=None):
        self.problem, self.x, self.identifiability = problem, np.asarray(x, dtype=float), identifiability
        self.rtol, self.ridge = rtol, ridge
        self.scale = scales(problem.names)
        self.residual, self.jac = problem.evaluate(self.x) if evaluated is None else evaluated
        self.weights = robust_weights(_row_norms(self.residual), loss) if weights is None else weights
        if parts is None:
            self.normal, self.gradient = self.jac.normal_equations(self.residual, self.weights, self.scale)
            return
        self.parts = []
        for rows in parts:
            jac = self.jac.rows(rows)
            self.parts.append((rows, jac, jac.normal_equations(self.residual[rows], self.weights[rows], self.scale)))
        self.normal = sum(held[0] for _, _, held in self.parts)
        self.gradient = sum(held[1] for _, _, held in self.parts)

    def held_out(self, rows):
        """Normal equations (P, P), (P,) of the measurements ``rows`` (indices) alone, in solver units."""
        return self.jac.rows(rows).normal_equations(self.residual[rows], self.weights[rows], self.scale)

    def without(self, rows, roughness=None, held=None):
        """Parameters (P,), mm or rad, refitted to every measurement but ``rows`` (indices).

        ``roughness`` (P, P) is the roughness penalty per measurement
        (default: the problem's own); ``held`` the `held_out` normal
        equations of ``rows`` when they are at hand.
        """
        normal, gradient = self.held_out(rows) if held is None else held
        per_row = self.problem.roughness / len(self.residual) if roughness is None else roughness
        penalty = per_row * (len(self.residual) - len(rows))
        matrix = self.normal - normal + penalty
        gradient = self.gradient - gradient + penalty @ (self.x / self.scale)
        step = _penalised_step(matrix, gradient) if self.ridge else -_truncated_solve(matrix, gradient, self.rtol)
        return self.x + self.scale * step

    def shared(self, rows, shares):
        """Parameters (P,), mm or rad, refitted to every measurement but ``rows`` (indices) at each of several
        roughness penalties and averaged (a model shared by penalties, `SplineChoice.shares`).

        ``shares`` are ``(weight, penalty)`` (`SplineBasis.penalty`), the
        most weight first, weights summing to 1. The first refit is
        `without`'s at its penalty; the others are solved in the directions
        its normal equations see (`_seen`): the penalties differ on the
        spline terms alone, which every penalty makes seen, and one
        eigendecomposition serves them all.
        """
        normal, gradient = self.held_out(rows) if len(rows) else (0.0, 0.0)
        rough = self._roughness * (len(self.residual) - len(rows))
        first = shares[0][1]
        eigenvalues, directions = _seen(self.normal - normal + rough * first, self.rtol)
        seen_rough = directions.T @ rough @ directions
        values = []
        for _, penalty in shares:
            vector = directions.T @ (self.gradient - gradient + (rough * penalty) @ (self.x / self.scale))
            if penalty == first:
                step = vector / eigenvalues
            else:
                step = np.linalg.solve(np.diag(eigenvalues) + (penalty - first) * seen_rough, vector)
            values.append(self.x - self.scale * (directions @ step))
        return np.average(values, axis=0, weights=[weight for weight, _ in shares])

    @functools.cached_property
    def _roughness(self):
        """The spline terms' second-difference matrix (P, P) (`SplineBasis.roughness`), per unit penalty and row."""
        return self.problem.basis.roughness(self.problem.names)

    def fit_without(self, rows):
        """The `KinematicFit` refitted to every measurement but ``rows`` (indices), its statistics over those."""
        held = self.held_out(rows)
        kept = np.setdiff1d(np.arange(len(self.residual)), rows)
        return _fit_result(self.problem, self.without(rows, held=held), self.weights[kept], self.normal - held[0],
                           self.identifiability, self.rtol, kept)


def linearise(start, q, measured, parameters, *, rotation=None, nominal=None, R_tcp_target=None, basis=None,
              loss="huber", orientation_weight=ORIENTATION_WEIGHT, identifiability=None):
    """The least-squares problem of `identify` in the base frame, linearised at a fit's parameters.

    Parameters
    ----------
    start : Robot
        The robot the parameters' deltas apply to.
    q : ndarray, shape (N, 6)
        Commanded joint angles, rad.
    measured : ndarray, shape (N, 3)
        Measured positions, mm, base frame.
    parameters : dict
        ``{name: value}`` of the fit: DH and tool deltas (mm, rad) and
        joint-error terms (spline terms of ``basis``); no registration.
    rotation : ndarray, shape (N, 3, 3), optional
        Measured orientations, base frame.
    nominal : Robot, optional
        Robot of the joint-error features (default: ``start``).
    R_tcp_target : ndarray, shape (3, 3), optional
        Orientation of the measured frame in the TCP frame, kept fixed (default: identity).
    basis : SplineBasis, optional
        The spline terms' knots and roughness penalty.
    loss : str
        Robust loss giving the rows' weights at the fit.
    orientation_weight : float
        mm per rad of orientation residual.
    identifiability : Identifiability, optional
        The fit's, recorded in refits (needed by `Linearisation.fit_without`).

    Returns
    -------
    Linearisation
    """
    problem = _Problem(start, start if nominal is None else nominal, q, measured, rotation, np.eye(4),
                       np.eye(3) if R_tcp_target is None else R_tcp_target, orientation_weight, basis)
    problem.setup(list(parameters))
    return Linearisation(problem, list(parameters.values()), loss=loss, identifiability=identifiability)


def _least_cost(normal, z, cost, rtol):
    """The solution z (P,) moved along the combinations the normal equations do not see to its least weighted norm.

    Moving along those combinations does not change the fit; among them the
    one minimising ``sum((cost * z)**2)`` keeps the costly parameters (the
    arm's) nearest to where they started.
    """
    eigenvalues, vectors = np.linalg.eigh(normal)
    unseen = vectors[:, eigenvalues < rtol**2 * eigenvalues.max(initial=0.0)]
    if unseen.shape[1] == 0:
        return z
    weighted = unseen * cost[:, None] ** 2
    return z - unseen @ np.linalg.solve(unseen.T @ weighted, weighted.T @ z)


def _seen(normal, rtol):
    """Eigenvalues (S,) and eigenvectors (P, S) of normal equations ``A^T A`` (P, P): the directions A sees at
    ``rtol`` of its best or above.

    A singular value of A is the square root of an eigenvalue of ``A^T A``:
    directions whose singular value is below ``rtol`` times the largest are
    left out (a step has no component along them).
    """
    eigenvalues, vectors = np.linalg.eigh(normal)
    seen = eigenvalues >= rtol**2 * eigenvalues.max(initial=0.0)
    return eigenvalues[seen], vectors[:, seen]


def _truncated_solve(normal, vector, rtol):
    """The truncated pseudo-inverse of normal equations (P, P) (`_seen`) times ``vector`` (P,).

    Through the eigenvectors, without forming the (P, P) inverse, whose
    product takes half as long again as the eigendecomposition itself at
    the joint fits' 721 parameters.
    """
    eigenvalues, vectors = _seen(normal, rtol)
    return vectors @ ((vectors.T @ vector) / eigenvalues)


def _solve(problem, scale, loss, rtol, start=None):
    """Iteratively re-weighted Gauss-Newton with step halving, from ``problem.x`` (``start``: the residual rows and
    `_Jacobian` there, when at hand).

    Each step solves the normal equations of the scaled, weighted problem
    (P x P, cheap for any N), the spline terms' roughness penalty added, by
    `_truncated_solve`: no step along a direction the data do not
    identify. Returns the parameters x (P,), the final weights (N,), the
    `_Jacobian` and the residual rows at x.
    """
    x = problem.x
    residual, jac = problem.evaluate(x) if start is None else start
    for _ in range(MAX_ITERATIONS):
        weights = robust_weights(_row_norms(residual), loss)
        normal, gradient = jac.normal_equations(residual, weights, scale)
        normal += problem.roughness
        gradient += problem.roughness @ (x / scale)
        step = -_truncated_solve(normal, gradient, rtol)
        cost = float(np.sum(weights[:, None] * residual**2)) + problem.penalty(x, scale)
        for _ in range(30):  # halve until the weighted cost does not grow
            trial = x + step * scale
            trial_residual, trial_jac = problem.evaluate(trial)
            if float(np.sum(weights[:, None] * trial_residual**2)) + problem.penalty(trial, scale) <= cost * (1 + 1e-12):
                break
            step = step / 2
        lowered = cost - (float(np.sum(weights[:, None] * trial_residual**2)) + problem.penalty(trial, scale))
        x, residual, jac = trial, trial_residual, trial_jac
        if np.max(np.abs(step), initial=0.0) < STEP_TOLERANCE or lowered < COST_TOLERANCE * cost:
            break
    return x, robust_weights(_row_norms(residual), loss), jac, residual


@dataclasses.dataclass(frozen=True)
class SplineChoice:
    """What `select_splines` chose, and why.

    Attributes
    ----------
    fit : KinematicFit or None
        The joint fit with the chosen spline terms, at the penalty of the
        most weight (None: the candidate without spline terms won).
    basis : SplineBasis or None
        The chosen knots, at that penalty.
    table : list of dict
        Every candidate with its held-out mean position error: ``step_deg``
        and ``penalty`` of its spline terms (step 0 = none),
        ``held_out_mm`` and, when residual fields were tried on top,
        ``with_field_mm`` with the best of them, its kind ``field_kind``;
        the sharing penalties' ``share`` (`_Candidates.shares`).
    regions : str
        How the held-out regions were drawn.
    field : str or None
        The kind of the residual field the chosen candidate takes on top (None: none).
    shares : tuple
        ``(weight, penalty)`` of each penalty of the chosen knot step that
        shares the choice (`_Candidates.shares`; weights summing to 1, the
        most first: ``basis``'s): the joint model is the weighted mean of
        the fits at them (`Linearisation.shared`). Empty without splines.
    """

    fit: object
    basis: object
    table: list
    regions: str
    field: object = None
    shares: tuple = ()


def region_folds(position, folds):
    """Held-out regions: ``folds`` slabs of equal count along the longest extent of commanded positions (N, 3).

    Returns
    -------
    list of ndarray of int
        Row indices of each region.
    str
        The regions in words.
    """
    axis = int(np.argmax(np.ptp(position, axis=0)))
    order = np.argsort(position[:, axis], kind="stable")
    edges = position[order[np.linspace(0, len(order) - 1, folds + 1).round().astype(int)], axis]
    return (np.array_split(order, folds),
            f"{folds} slabs of the commanded positions along {'xyz'[axis]} (edges {np.round(edges, 1).tolist()} mm)")


class _Candidates:
    """Held-out scoring of linearised candidate fits over regions, keeping the best (`select_splines`)."""

    def __init__(self, regions, fields):
        self.regions, self.fields = regions, fields or {}
        self.table, self.best, self.scored = [], None, []

    def result(self):
        """``(table, best, scored)``: what `merge` takes (plain data, passed between processes)."""
        return self.table, self.best, self.scored

    def merge(self, table, best, scored):
        """Take the table entries, the best and the scores of candidates scored after these (`result`)."""
        self.table += table
        self.scored += scored
        if best is not None and (self.best is None or best[0] < self.best[0]):
            self.best = best

    def shares(self):
        """``(weight, basis, (step_deg, penalty))`` of the penalties of the best candidate's knot step, with its
        field on top.

        A penalty's weight is how often it scores best among them when the
        held-out regions are weighted at random (`BOOTSTRAP_DRAWS` draws
        of flat Dirichlet weights, seeded: the same rows share out the
        same): the penalties the regions cannot tell apart share the
        model, instead of the one a region's noise ranks first. The
        candidate without spline terms is alone in its step. Penalties
        that never score best are left out; the most weight first.
        """
        _, field, basis = self.best
        step = None if basis is None else basis.step.tobytes()
        same = [(regions, payload, key) for kind, regions, payload, key in self.scored if kind == field
                and (payload is None if basis is None else payload is not None and payload.step.tobytes() == step)]
        draws = np.random.default_rng(0).dirichlet(np.ones(len(self.regions)), BOOTSTRAP_DRAWS)
        wins = np.bincount((draws @ np.array([regions for regions, _, _ in same]).T).argmin(axis=1),
                           minlength=len(same)) / BOOTSTRAP_DRAWS
        return [(float(wins[k]), *same[k][1:]) for k in np.argsort(-wins, kind="stable") if wins[k] > 0]

    def linearise(self, problem, x, weights, evaluated):
        """The `Linearisation` of a candidate's problem at x (P,), evaluated there (``evaluated``: residual rows,
        `_Jacobian`), with the regions' normal equations."""
        return Linearisation(problem, x, weights, ridge=True, parts=self.regions, evaluated=evaluated)

    def score(self, entry, linear, roughness, payload):
        """Held-out mean errors of one candidate (without and with each field on top), added to the table.

        ``roughness`` (P, P) is its roughness penalty per measurement.
        """
        plain, on_top = [], {kind: [] for kind in self.fields}
        count = len(linear.residual)
        for rows, jac, held in linear.parts:
            step = linear.without(rows, roughness, held) - linear.x
            plain.append(np.linalg.norm(linear.residual[rows, :3] + jac.apply(step)[:, :3], axis=1))
            if not self.fields:
                continue
            moved = linear.residual[:, :3] + linear.jac.apply(step)[:, :3]
            train = np.setdiff1d(np.arange(count), rows)
            for kind, field in self.fields.items():
                predicted = field(train, moved[train], rows)
                on_top[kind].append(np.linalg.norm(moved[rows] - predicted, axis=1))
        entry["held_out_mm"] = round(float(np.concatenate(plain).mean()), 5)
        scores = [(entry["held_out_mm"], None)]
        self.scored += [(kind, [float(e.mean()) for e in errors], payload, (entry["step_deg"], entry["penalty"]))
                        for kind, errors in [(None, plain), *on_top.items()]]
        if on_top:
            means = {kind: float(np.concatenate(errors).mean()) for kind, errors in on_top.items()}
            entry["field_kind"] = min(means, key=means.get)
            entry["with_field_mm"] = round(means[entry["field_kind"]], 5)
            scores.append((entry["with_field_mm"], entry["field_kind"]))
        self.table.append(entry)
        for mean, field in scores:
            if self.best is None or mean < self.best[0]:
                self.best = (mean, field, payload)


def select_splines(fit, start, nominal, q, measured, *, rotation=None, joints=(0, 1, 2, 3, 4), steps=(2.0, 4.0, 8.0),
                   penalties=(1e-5, 1e-4, 1e-3, 1e-2), folds=4, position=None,
                   orientation_weight=ORIENTATION_WEIGHT, fields=None, loss="huber", workers=1):
    """Choose the joint model's spline terms (and a residual field on top) by held-out regions, and fit them.

    For each knot step and penalty, the spline terms and the parameters of
    ``fit`` are fitted together on all regions but one (`region_folds`) and
    the mean position error is taken on the region held out, without and
    with each of the residual ``fields`` fitted on the training regions'
    residuals on top; the candidate (and field) with the least held-out
    error over all regions wins, the candidate without spline terms (``fit``'s
    parameters refitted the same way) included. Its knot step is kept and
    its penalty shared: each penalty of that step weighs by how often it
    scores best when the regions are weighted at random
    (`_Candidates.shares`), and the model is the weighted mean of their
    fits (`SplineChoice.shares`): which of two penalties wins often turns
    on one region's noise. A knot step giving more than one
    spline term per `MEASUREMENTS_PER_SPLINE` measurements is not tried.
    Rows are never interleaved: a region's neighbours are not in its
    training set. The candidates are linearised at ``fit`` (its errors are
    milliradians: one Gauss-Newton step of `identify` with the spline terms
    added); the chosen spline terms are then fitted on all rows by
    `identify` itself, iterated to convergence with the robust loss, at the
    penalty of the most weight.

    Parameters
    ----------
    fit : KinematicFit
        Joint fit of the measurements in the base frame (``joint_terms``),
        from ``start``.
    start, nominal : Robot
        The robot ``fit`` started from and the robot of the joint features.
    q : ndarray, shape (N, 6)
        Commanded joints, rad.
    measured : ndarray, shape (N, 3)
        Measured positions, mm, base frame.
    rotation : ndarray, shape (N, 3, 3), optional
        Measured orientations, base frame.
    joints : tuple of int
        0-based joints given spline terms.
    steps : tuple of float
        Knot steps tried, deg.
    penalties : tuple of float
        Roughness penalties tried (`SplineBasis.penalty`).
    folds : int
        Number of held-out regions (0: no selection, the first step and
        penalty are fitted, with the first of the ``fields`` on top when
        there are any).
    position : ndarray, shape (N, 3), optional
        Commanded positions the regions are drawn in and the field is
        fitted over (default: FK of ``start``).
    orientation_weight : float
        mm per rad of orientation residual.
    fields : dict, optional
        Residual fields tried on top, by kind: ``field(train (T,),
        residuals (T, 3), held (H,)) -> (H, 3)``, mm, fitted on the residuals
        of the training rows (indices) and evaluated at the held-out ones.
    loss : str
        Robust loss of the final fit (`identify`).
    workers : int
        Processes scoring the knot steps (`trajcomp.support.parallel.share_blocks`); the choice does not depend on
        it.

    Returns
    -------
    SplineChoice
    """
    position = fk(start, q)[:, :3, 3] if position is None else position
    regions, words = region_folds(position, folds) if folds > 1 else ([], "none: the one candidate given is fitted")
    lower, upper = q.min(axis=0), q.max(axis=0)
    if not regions:
        spacing = np.zeros(6)
        spacing[list(joints)] = np.radians(steps[0])
        basis = SplineBasis(lower, upper, spacing, penalties[0])
        return SplineChoice(_spline_fit(fit, start, nominal, q, measured, rotation, basis, orientation_weight, loss),
                            basis, [], words, field=next(iter(fields or {}), None), shares=((1.0, basis.penalty),))
    tried = [None]  # no splines, then each knot step with enough measurements per spline term
    for step in steps:
        spacing = np.zeros(6)
        spacing[list(joints)] = np.radians(step)
        if len(q) < MEASUREMENTS_PER_SPLINE * len(SplineBasis(lower, upper, spacing).names()):
            continue  # too sparse for this many terms: the penalty alone would shape them
        tried.append((step, SplineBasis(lower, upper, spacing, 1.0)))

    # every candidate is linearised at fit: one evaluation of its residual and Jacobian, before the workers fork
    plain = _Problem(start, nominal, q, measured, rotation, np.eye(4), fit.R_tcp_target, orientation_weight)
    plain.setup(list(fit.names))
    residual, jac = plain.evaluate(fit.delta)

    def scored(k):
        """`_Candidates.result` of the candidates of ``tried[k]`` (its penalties)."""
        candidates = _Candidates(regions, fields)
        if tried[k] is None:
            candidates.score({"step_deg": 0.0, "penalty": 0.0},
                             candidates.linearise(plain, fit.delta, fit.weights, (residual, jac)),
                             np.zeros((len(plain.names),) * 2), None)
            return candidates.result()
        step, basis = tried[k]
        problem = plain.with_splines(basis)
        x = np.concatenate([fit.delta, np.zeros(len(problem.names) - len(fit.names))])
        linear = candidates.linearise(problem, x, fit.weights, (residual, jac.with_splines(problem)))
        rough = basis.roughness(problem.names)
        for penalty in penalties:
            candidates.score({"step_deg": step, "penalty": penalty}, linear, rough * penalty,
                             dataclasses.replace(basis, penalty=penalty))
        return candidates.result()

    candidates = _Candidates(regions, fields)
    for result in share_blocks(scored, len(tried), workers):
        candidates.merge(*result)
    _, on_top, _ = candidates.best
    shares = candidates.shares()
    basis = shares[0][1]
    if basis is None:
        return SplineChoice(None, None, candidates.table, words, on_top)
    weights = {key: weight for weight, _, key in shares}
    for entry in candidates.table:
        if (entry["step_deg"], entry["penalty"]) in weights:
            entry["share"] = weights[(entry["step_deg"], entry["penalty"])]
    return SplineChoice(_spline_fit(fit, start, nominal, q, measured, rotation, basis, orientation_weight, loss), basis,
                        candidates.table, words, on_top, tuple((weight, member.penalty) for weight, member, _ in shares))


def _spline_fit(fit, start, nominal, q, measured, rotation, basis, orientation_weight, loss):
    """The joint fit with spline terms ``basis`` added, by `identify` from ``start`` (the kinematic fit) and ``fit``."""
    return identify(start, q, measured, rotation=rotation, joint_terms=True, splines=basis, loss=loss,
                    nominal=nominal, orientation_weight=orientation_weight, R_tcp_target=fit.R_tcp_target,
                    start_values=dict(zip(fit.names, fit.delta)), identifiability=fit.identifiability)


def _penalised_step(matrix, gradient):
    """Step (P,) in solver units minimising the linearised cost of normal equations ``matrix`` (P, P) (roughness
    included) and ``gradient`` (P,).

    A relative ridge of 1e-9 on the diagonal settles the exact redundancies
    (a spline's constant with its joint's zero, d2 with d3) at no cost to
    the fit.
    """
    from scipy.linalg import cho_factor, cho_solve

    matrix = matrix.copy()
    matrix[np.diag_indices_from(matrix)] += 1e-9 * np.abs(np.diag(matrix)).max()
    return -cho_solve(cho_factor(matrix, overwrite_a=True), gradient)
