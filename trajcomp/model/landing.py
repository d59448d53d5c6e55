"""Per-target landing estimate: how far from its target the real arm may land with a compensated command.

The compliance verdict judges each target by this estimate (not by the
compensation's own convergence, which only says that the model agrees with
itself). It adds two parts, both from what `calibrate` measured:

held-out
    The mode's errors at measured points held out of its fit, with the same
    interpolator as the compensation: a lattice field (idw8, trilinear) is
    refitted with every other node plane along one axis left out and
    evaluated at the planes left out (the same interpolator over cells twice
    as long along that axis, so the figure errs on the safe side); the
    scattered fields, the joint residual and the parametric modes by k-fold
    cross-validation. Near a target: the largest held-out |error| of the
    `NEAREST` held-out points nearest to it, read from a lookup lattice over
    the measured box (`LOOKUP` nodes per axis) that `calibrate` stores.
unseen
    What the measurements could not see. The arm's kinematic parameters
    are known only as far as the measured configurations constrain them:
    a linear Gaussian posterior, its prior the size of the identified
    deltas (the unseen parameters of an arm are taken to be as far off as
    the seen ones; see `posterior`), its noise the fit's residual. Where the target's orientation, tool or posture differs from
    the measured ones, the parameters the measurements could not see move
    its landing: the estimate adds ``|J' mu| + 2 sqrt(trace(J' C J'^T))``
    mm, with ``C`` the posterior covariance, ``mu`` the expected parameter
    error the mode leaves (the pull of the posterior mean away from the
    identified parameters, for modes without a kinematic model the whole
    arm error) and ``J'`` the position Jacobian at the target's joints and
    tool. For a mode whose error field lies over commanded positions (the
    paper's grid measured in one orientation), the field already absorbed
    what the measured configuration at the target's position sees, so
    ``J'`` is the difference of the target's Jacobian and that of the
    measured orientation and tool at the same position (in a measured
    posture): zero at a measured orientation, growing with the tilt.

The sum is a bound meant to cover the true landing error of 95 % of the
targets or more (``tests/benchmarks/bench_accuracy.py tilt`` measures it).
"""

import dataclasses

import numpy as np

from trajcomp.errors import ModelError
from trajcomp.arm.ik import ik
from trajcomp.arm.ik_closed_form import ik_family
from trajcomp.model.joint_errors import KIND as JOINT_KIND
from trajcomp.arm.parameters import ANGLE_LEVER, candidate_parameters, is_angle, is_robot_parameter, pose_jacobian
from trajcomp.model.stats import ErrorStats
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc, mean_rotation, rotation_angle_between

NEAREST = 20  # held-out points whose largest error bounds the error near a target (about 1.5 cells of a lattice)
LOOKUP = 11  # nodes per axis of the lookup lattice of the held-out errors
COVERAGE = 2.0  # standard deviations (of the RMS norm) the unseen part adds: >= 95 % of a 3-D Gaussian |error|
ORIENTATION_MARGIN = 1.0  # deg beyond the measured orientations' largest deviation still counted as measured
PRIOR_FLOOR = (1e-3, 1e-6)  # mm, rad: smallest prior of a length and an angle parameter
NUISANCE_PRIOR = (1e3, 1.0)  # mm, rad: registration and measured-frame parameters, practically free
EXTRA = ("theta6",)  # the zero of joint 6: unseen by a point on its axis, it moves a sideways tool


@dataclasses.dataclass(frozen=True, eq=False)
class LandingData:
    """What `calibrate` stores for the landing estimate of a model. Internal units mm, rad.

    Attributes
    ----------
    held_out : dict of str to dict
        Per mode, `ErrorStats` dict of its held-out errors (same interpolator).
    method : str
        How the errors were held out, in words.
    origin, step : ndarray, shape (3,)
        Lookup lattice of the errors near a point, mm (step 0 on an axis
        the measurements do not extend along).
    near : dict of str to ndarray, shape (nx, ny, nz)
        Per mode, the largest held-out |error| of the `NEAREST` held-out
        points nearest each lookup node, mm.
    names : list of str
        Parameters of the posterior (robot, then registration and
        measured-frame parameters).
    shift : ndarray, shape (P,)
        Posterior mean minus the identified parameters, mm or rad.
    covariance : ndarray, shape (P, P)
        Posterior covariance, mm and rad.
    identified : ndarray, shape (P,)
        Identified parameters relative to the nominal robot (zero where left at nominal).
    reference : ndarray, shape (3, 3)
        Mean measured TCP orientation (base frame).
    spread : float
        Largest angle of a measured TCP orientation from ``reference``, rad.
    """

    held_out: dict
    method: str
    origin: np.ndarray
    step: np.ndarray
    near: dict
    names: list
    shift: np.ndarray
    covariance: np.ndarray
    identified: np.ndarray
    reference: np.ndarray
    spread: float

    def to_dict(self):
        """Plain data in user units (mm, deg), for the model file's report."""
        scale = _user_scale(self.names)
        return {
            "held_out": self.held_out,
            "method": self.method,
            "lookup": {"origin": self.origin.tolist(), "step": self.step.tolist(), "nearest": NEAREST,
                       "near_mm": {mode: np.round(v, 5).tolist() for mode, v in self.near.items()}},
            "parameters": {"names": list(self.names), "shift": (self.shift * scale).tolist(),
                           "identified": (self.identified * scale).tolist(),
                           "covariance": (self.covariance * np.outer(scale, scale)).tolist()},
            "orientation": {"reference_abc_deg": np.degrees(matrix_to_abc(self.reference)).tolist(),
                            "spread_deg": float(np.degrees(self.spread))},
        }

    @classmethod
    def from_dict(cls, data):
        """Read `to_dict` back; ModelError on a malformed entry."""
        try:
            lookup, parameters = data["lookup"], data["parameters"]
            names = list(parameters["names"])
            scale = _user_scale(names)
            near = {mode: np.array(v, dtype=float) for mode, v in lookup["near_mm"].items()}
            return cls(
                held_out=dict(data["held_out"]), method=str(data["method"]),
                origin=np.array(lookup["origin"], dtype=float).reshape(3),
                step=np.array(lookup["step"], dtype=float).reshape(3), near=near, names=names,
                shift=np.array(parameters["shift"], dtype=float).reshape(len(names)) / scale,
                identified=np.array(parameters["identified"], dtype=float).reshape(len(names)) / scale,
                covariance=np.array(parameters["covariance"], dtype=float).reshape(len(names), len(names))
                / np.outer(scale, scale),
                reference=abc_to_matrix(np.radians(np.array(data["orientation"]["reference_abc_deg"], dtype=float))),
                spread=float(np.radians(data["orientation"]["spread_deg"])),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelError(f"report.landing: malformed entry: {exc!r}") from None

    def near_errors(self, mode, points):
        """Held-out |error| near points (N, 3) mm in ``mode`` (N,): the lookup node nearest each point."""
        values = self.near[mode]
        shape = np.array(values.shape)
        step = np.where(self.step > 0, self.step, 1.0)
        node = np.clip(np.rint((points - self.origin) / step), 0, shape - 1).astype(int)
        return values[node[:, 0], node[:, 1], node[:, 2]]


def _user_scale(names):
    """Per-parameter factor (P,) from internal (mm, rad) to user units (mm, deg)."""
    return np.array([np.degrees(1.0) if is_angle(name) else 1.0 for name in names])


def near_lookup(points, errors):
    """Lookup lattice of the largest held-out error near each of its nodes.

    Parameters
    ----------
    points : ndarray, shape (M, 3)
        Positions of the held-out points, mm.
    errors : dict of str to ndarray, shape (M,)
        Their held-out |error| per mode, mm.

    Returns
    -------
    origin, step : ndarray, shape (3,)
    near : dict of str to ndarray, shape (nx, ny, nz)
    """
    lower, upper = points.min(axis=0), points.max(axis=0)
    flat = upper - lower < 1e-6
    count = np.where(flat, 1, LOOKUP)
    step = np.where(flat, 0.0, (upper - lower) / np.maximum(count - 1, 1))
    axes = [lower[a] + step[a] * np.arange(count[a]) for a in range(3)]
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    k = min(NEAREST, len(points))
    nearest = np.empty((len(nodes), k), dtype=int)
    for start in range(0, len(nodes), 64):  # (64, M) distances at a time
        nearest[start:start + 64] = np.argpartition(_distances(nodes[start:start + 64], points), k - 1, axis=1)[:, :k]
    near = {mode: e[nearest].max(axis=1).reshape(*count) for mode, e in errors.items()}
    return lower, step, near


def _distances(nodes, points):
    """Euclidean distances (K, M) mm from nodes (K, 3) to points (M, 3).

    Summed one axis at a time: the same sums in the same order as
    ``np.linalg.norm(nodes[:, None] - points[None], axis=2)`` (so the same
    values, ties included), without its (K, M, 3) array and its reduction
    along the short last axis (6 times faster).
    """
    squared = np.zeros((len(nodes), len(points)))
    for axis in range(3):
        along = nodes[:, axis, None] - points[None, :, axis]
        squared += along * along
    return np.sqrt(squared)


def posterior(robot, identified, joints, rotation, *, frame, residuals, R_tcp_target, fitted, hidden=0):
    """Posterior mean shift, covariance and identified values of the arm's parameters (linear Gaussian).

    The posterior rests on the measured positions only (orientations
    measured by a 6-DoF tracker would narrow it further: it errs on the
    safe side there).

    Parameters
    ----------
    robot : Robot
        Nominal robot.
    identified : Robot
        The identified robot (the linearisation point).
    joints : ndarray, shape (N, 6)
        Measured configurations, rad.
    rotation : ndarray or None
        Measured orientations (only whether there are any matters: the
        measured frame's orientation is then a parameter).
    frame : {"base", "tracker"}
        Tracker-frame data add the registration as parameters.
    residuals : ndarray, shape (N, 3)
        Measured minus identified positions, base frame, mm.
    R_tcp_target : ndarray, shape (3, 3)
    fitted : dict of str to float
        Identified deltas from the nominal robot, mm or rad.
    hidden : int
        How many of the robot parameters of ``fitted`` the data do not
        identify on their own: a fit that moves only along the identified
        combinations (the minimum-norm solution) spreads the error over all
        of them, so their RMS understates the size of one parameter's error
        by ``sqrt(P / (P - hidden))``, which the prior puts back. Lengths and
        angles then bound each other through `ANGLE_LEVER` (an angle error
        at least the length error over 1 m, and the reverse).

    Returns
    -------
    names : list of str
        Robot parameters (with `EXTRA`), then registration and measured-frame ones.
    shift, covariance, deltas : ndarray, shapes (P,), (P, P), (P,)
        Posterior mean minus identified, posterior covariance and identified
        deltas (zero for the parameters left at nominal and the nuisance ones).
    """
    names = candidate_parameters(robot, tool=True, orientation=rotation is not None, tracker=frame == "tracker")
    names = names[:names.index("tool_x")] + list(EXTRA) + names[names.index("tool_x"):]
    robot_part = np.array([is_robot_parameter(n) for n in names])
    angle = np.array([is_angle(n) for n in names])
    lengths = [abs(v) for n, v in fitted.items() if is_robot_parameter(n) and not is_angle(n)]
    angles = [abs(v) for n, v in fitted.items() if is_robot_parameter(n) and is_angle(n)]
    seen = len(lengths) + len(angles)
    spread = np.sqrt(seen / max(seen - hidden, 1))
    length, turn = spread * _rms(lengths, PRIOR_FLOOR[0]), spread * _rms(angles, PRIOR_FLOOR[1])
    length, turn = max(length, turn * ANGLE_LEVER), max(turn, length / ANGLE_LEVER)
    prior = np.where(angle, turn, length)
    prior = np.where(robot_part, prior, np.where(angle, NUISANCE_PRIOR[1], NUISANCE_PRIOR[0]))
    jac = pose_jacobian(identified, joints, names, R_tcp_target)[1][:, :3, :].reshape(-1, len(names))
    residual = residuals.reshape(-1)
    noise = max(float(np.sqrt(np.mean(residual**2))), 1e-4)
    information = jac.T @ jac / noise**2 + np.diag(1.0 / prior**2)
    covariance = np.linalg.inv(information)
    deltas = np.array([fitted.get(n, 0.0) if is_robot_parameter(n) else 0.0 for n in names])
    shift = covariance @ (jac.T @ residual / noise**2 - np.where(robot_part, deltas, 0.0) / prior**2)
    return names, shift, (covariance + covariance.T) / 2.0, deltas


def _rms(values, floor):
    """Root mean square of a list of values, at least ``floor`` (``floor`` for an empty list)."""
    return max(float(np.sqrt(np.mean(np.square(values)))), floor) if values else floor


def orientation_reference(rotations):
    """Mean measured orientation (3, 3) and the largest angle (rad) of a measured one from it."""
    reference = mean_rotation(rotations)
    return reference, float(rotation_angle_between(rotations, reference[None]).max())


def build(held, points, method, parameters, rotations):
    """`LandingData` from held-out errors, the posterior and the measured orientations.

    Parameters
    ----------
    held : dict of str to ndarray, shape (M, 3)
        Held-out errors per mode at ``points``, mm.
    points : ndarray, shape (M, 3)
        Commanded positions of the held-out rows, mm.
    method : str
        How they were held out, in words.
    parameters : tuple
        `posterior` output ``(names, shift, covariance, deltas)``.
    rotations : ndarray, shape (N, 3, 3), or None
        Commanded TCP orientations of the measurements (None: unknown, any
        orientation counts as measured).
    """
    origin, step, near = near_lookup(points, {mode: np.linalg.norm(e, axis=1) for mode, e in held.items()})
    names, shift, covariance, deltas = parameters
    reference, spread = (np.eye(3), np.pi) if rotations is None else orientation_reference(rotations)
    stats = {mode: ErrorStats.from_errors(e).as_dict() for mode, e in held.items()}
    return LandingData(stats, method, origin, step, near, list(names), shift, covariance, deltas, reference, spread)


def of_model(model):
    """The model's `LandingData`, or None for a model calibrated without held-out errors (``--folds 0``)."""
    data = (model.report or {}).get("landing")
    return None if data is None else LandingData.from_dict(data)


@dataclasses.dataclass(frozen=True, eq=False)
class Estimate:
    """Landing estimates of N targets, mm, and what they rest on.

    Attributes
    ----------
    held_out, unseen : ndarray, shape (N,)
        The two parts (see the module docstring), mm; NaN without held-out errors.
    orientation : ndarray, shape (N,)
        Angle of the target orientation from the mean measured one beyond
        the measured spread, deg (0 within it).
    """

    held_out: np.ndarray
    unseen: np.ndarray
    orientation: np.ndarray

    @property
    def total(self):
        """The landing estimate (N,), mm: held-out plus unseen."""
        return self.held_out + self.unseen


def estimate(model, mode, q, T_target, tool=None, postures=None, other_tool=False):
    """Landing estimate of compensated targets.

    Parameters
    ----------
    model : CompensationModel
    mode : str
    q : ndarray, shape (N, 6)
        Commanded joints, rad.
    T_target : ndarray, shape (N, 4, 4)
        Targets, base frame, mm.
    tool : ndarray, shape (4, 4), optional
        The program's tool (TCP in the flange frame); default the measured TCP.
    postures : ndarray of bool, shape (N,), optional
        Targets in an arm posture the calibration did not measure: their
        reference configuration is taken in a measured posture.
    other_tool : bool
        ``tool`` is not the measured TCP. With a model that cannot place
        other tools, the measured TCP's offset error stays with the
        measured tool, unknown for the program's: the estimate adds the
        identified offset and `COVERAGE` times the posterior RMS of the
        offset.

    Returns
    -------
    Estimate
    """
    n = len(q)
    data = of_model(model)
    if data is None:
        nan = np.full(n, np.nan)
        return Estimate(nan, nan.copy(), np.zeros(n))
    position = T_target[:, :3, 3]
    angle = rotation_angle_between(T_target[:, :3, :3], data.reference[None])
    beyond = np.degrees(np.maximum(angle - data.spread, 0.0))
    robot_rows = np.array([is_robot_parameter(name) for name in data.names])
    names = [name for name, keep in zip(data.names, robot_rows) if keep]
    covariance = data.covariance[np.ix_(robot_rows, robot_rows)]
    identified = model.identified if model.dh_names else model.nominal.as_standard()
    at_target = identified if tool is None else identified.replace(T_flange_tool=tool)
    jac = pose_jacobian(at_target, q, names)[1][:, :3, :]
    by_position = mode in ("none", "linear", "grid") or (mode == "composite" and model.error_field(mode) is not None)
    if by_position and data.spread < np.radians(ORIENTATION_MARGIN):
        jac = jac - _reference_jacobian(model, identified, data, T_target, q, names, postures)
    if mode in ("none", "linear", "grid"):
        mean = (data.identified + data.shift)[robot_rows]
    elif mode == "composite" and getattr(model.residual, "kind", None) == JOINT_KIND:
        mean = np.zeros(len(names))
    else:
        mean = data.shift[robot_rows]
    unseen = np.linalg.norm(jac @ mean, axis=1) + COVERAGE * np.sqrt(
        np.maximum(np.einsum("nip,pq,niq->n", jac, covariance, jac), 0.0))
    if other_tool and not model.places_other_tools and "tool_x" in names:
        offset = [names.index(name) for name in ("tool_x", "tool_y", "tool_z")]
        unseen = unseen + np.linalg.norm(data.identified[robot_rows][offset]) + COVERAGE * np.sqrt(
            np.trace(covariance[np.ix_(offset, offset)]))
    if not names:  # no kinematic model: nothing tells how another orientation or tool lands
        unseen = np.where((beyond > 0) | other_tool, np.nan, unseen)
    return Estimate(data.near_errors(mode, position), unseen, beyond)


def _reference_jacobian(model, identified, data, T_target, q, names, postures):
    """Position Jacobian (N, 3, P) of the measured TCP at each target's position in the measured orientation.

    Solved with the nominal robot near the target's joints (in the first
    measured posture for targets in another one, on arms with a closed
    form); a position the measured orientation cannot reach gets zero (no
    part of the error counted as absorbed).
    """
    T_ref = np.array(T_target)
    T_ref[:, :3, :3] = data.reference
    solved = ik(model.nominal, T_ref, seed=q)
    q_ref, ok = np.array(solved.q), np.array(solved.success)
    if postures is not None and postures.any() and model.postures and ik_family(model.nominal) is not None:
        rows = np.flatnonzero(postures)
        other = ik(model.nominal, T_ref[rows], seed=q[rows], config=model.postures[0])
        q_ref[rows], ok[rows] = other.q, other.success
    ok &= np.isfinite(q_ref).all(axis=1)
    jac = np.zeros((len(q), 3, len(names)))
    if ok.any():
        jac[ok] = pose_jacobian(identified, q_ref[ok], names)[1][:, :3, :]
    return jac
