"""The compensation model: what `calibrate` identified and what it predicts.

A model holds everything `calibrate` identified for one robot: the DH deltas
with their uncertainties and the parameters not identified on their own, the tracker
registration, the paper's linear correction, the grid of raw errors and the
grid of residuals left after the DH model, with fit and cross-validation
statistics. It predicts where the real arm ends for a command, in each mode:

``none``       the commanded position;
``linear``     commanded + linear error model (the paper's indirect correction);
``dh``         forward kinematics of the identified robot;
``grid``       commanded + interpolated raw error;
``composite``  identified robot + residual: a field over the commanded
               position (the paper's grid), or joint-angle errors over the
               configuration (`JointResidual`: right at any orientation),
               with or without a field over the commanded position on top,
               as chosen on held-out regions.

It also says whether it can place a tool other than the one measured
(`CompensationModel.places_other_tools`, with the reason).

Reading and writing its file is in `trajcomp.model.model_file`.
"""

import dataclasses

import numpy as np

from trajcomp.errors import ModelError
from trajcomp.arm.ik import branch_index
from trajcomp.model.joint_errors import KIND as JOINT_KIND
from trajcomp.arm.kinematics import fk
from trajcomp.arm.parameters import apply_deltas
from trajcomp.model.options import MODES


@dataclasses.dataclass(frozen=True, eq=False)
class CompensationModel:
    """An identified compensation model. Internal units mm, rad.

    Attributes
    ----------
    nominal : Robot
        The nominal robot the model was identified for.
    robot_ref : str
        How the robot was named (built-in name or YAML path).
    method : str
        Default mode (one of `MODES`).
    T_tracker_base : ndarray, shape (4, 4)
        Base pose in the tracker frame (identity for base-frame data).
    dh_names : list of str
        Identified DH/tool/base parameter names (empty: no DH model).
    dh_delta, dh_sigma : ndarray, shape (P,)
        Deltas to nominal and standard deviations, mm or rad.
    dh_fixed : dict
        ``{name: reason}`` of parameters the data do not identify on their own
        (they move only within the combinations the data identify).
    linear : LinearCorrection or None
    grid : residual field or None
        Interpolated raw errors (measured - commanded) over commanded positions.
    residual : residual field, JointResidual or None
        Residuals after the DH model: a field over the commanded position,
        or joint-angle errors over the configuration.
    residual_field : residual field or None
        With a `JointResidual`, the field over the commanded position of the
        residuals it leaves, added on top in mode composite (None: none).
    report : dict
        Fit and cross-validation statistics, warnings, provenance.
    R_tcp_target : ndarray, shape (3, 3)
        Orientation of the frame a 6-DoF tracker measured, in the TCP frame.
    places_other_tools : bool
        True when the model locates the flange, so that a program tool other
        than the measured TCP lands as well: the measurements turned the
        tool about two axes and the default mode's residual does not depend
        on the measured TCP's position.
    other_tools_reason : str
        Why (or why not), in words.
    postures : tuple of int
        Arm branches (`trajcomp.arm.ik.Configuration` indices) the measurements
        were taken in; empty when unknown (positions without joints, or a
        model file written before they were recorded). Errors of another
        branch were never measured: gear and compliance errors follow the
        joints, and a single-branch fit does not separate every wrist
        parameter, so such targets count as outside the calibrated region
        (`unmeasured_posture`).
    """

    nominal: object
    robot_ref: str
    method: str
    T_tracker_base: np.ndarray
    dh_names: list
    dh_delta: np.ndarray
    dh_sigma: np.ndarray
    dh_fixed: dict
    linear: object
    grid: object
    residual: object
    report: dict
    residual_field: object = None
    R_tcp_target: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(3))
    places_other_tools: bool = False
    other_tools_reason: str = "not stated"
    postures: tuple = ()

    def unmeasured_posture(self, q):
        """Mask (N,) of commanded joints q (N, 6) rad in an arm branch the calibration did not measure.

        All False when the model does not record its postures.
        """
        q = np.atleast_2d(q)
        if not self.postures:
            return np.zeros(len(q), dtype=bool)
        return ~np.isin(branch_index(self.nominal, q), self.postures)

    @property
    def identified(self):
        """The identified robot (standard DH)."""
        return apply_deltas(self.nominal, self.dh_names, self.dh_delta)

    def arm(self, mode, tool=None, outside="model"):
        """The arm that mode ``mode`` predicts: where commanded joints really take the TCP.

        Parameters
        ----------
        mode : str
            One of `modes`; ``none``, ``linear`` and ``grid`` use the nominal
            kinematics.
        tool : ndarray, shape (4, 4), optional
            A program tool (TCP in the flange frame), taken as exact; default:
            the measured TCP as identified.
        outside : {"model", "clamp", "error"}
            Joints outside the range a joint residual was fitted on: flagged
            (`Arm.outside_rows`; the joint errors extrapolate as
            `trajcomp.model.joint_errors.JointResidual.offsets` says), or a
            ModelError (``error``).
        """
        self.check_mode(mode)
        robot, joints = self.nominal, None
        if mode in ("dh", "composite"):
            robot = self.identified
            if mode == "composite" and getattr(self.residual, "kind", None) == JOINT_KIND:
                robot, joints = self.residual.robot(robot), self.residual
        if tool is not None:
            robot = robot.replace(T_flange_tool=tool)
        return Arm(robot, joints, self.nominal, outside)

    @property
    def modes(self):
        """The modes this model can predict and compensate in."""
        have = {
            "none": True,
            "linear": self.linear is not None,
            "dh": bool(self.dh_names),
            "grid": self.grid is not None,
            "composite": bool(self.dh_names) and self.residual is not None,
        }
        return tuple(mode for mode in MODES if have[mode])

    def check_mode(self, mode):
        """Raise ModelError unless the model supports ``mode``."""
        if mode not in self.modes:
            raise ModelError(f"mode {mode!r} is not available in this model (available: {', '.join(self.modes)})")

    def error_field(self, mode, tool=None):
        """The field over commanded positions ``mode`` adds (raw-error grid, residual grid), else None.

        ``tool`` (4, 4): the program's tool, None for the measured TCP. A
        field on top of a joint residual holds what the joint model leaves
        at the measured TCP: a tool other than that one takes none (it lands
        as the joint model places it).
        """
        field = {"grid": self.grid, "composite": self.residual}.get(mode)
        if getattr(field, "kind", None) != JOINT_KIND:
            return field
        return self.residual_field if tool is None or same_tool(tool, self.nominal.T_flange_tool) else None

    def predict(self, mode, joints, position, *, interpolation=None, outside="model"):
        """Predicted reached TCP positions.

        Parameters
        ----------
        mode : str
            One of `modes`.
        joints : ndarray, shape (N, 6), or None
            Commanded joint angles, rad (required by ``dh`` and ``composite``).
        position : ndarray, shape (N, 3)
            Commanded TCP positions, mm, base frame.
        interpolation : str, optional
            Override the grids' interpolation method.
        outside : {"model", "clamp", "error"}
            Points outside a grid: no grid term (flagged), the value at the
            nearest point of the grid box, or a ModelError.

        Returns
        -------
        predicted : ndarray, shape (N, 3)
        flagged : ndarray, shape (N,) bool
            Points outside the grid that took the ``outside`` policy, or outside the joint range the joint errors
            were fitted on.
        """
        self.check_mode(mode)
        flagged = np.zeros(len(position), dtype=bool)
        if mode == "none":
            return np.array(position, dtype=float), flagged
        if mode == "linear":
            return position + self.linear.predict_error(position), flagged
        if mode in ("dh", "composite"):
            if joints is None:
                raise ModelError(f"mode {mode} needs the commanded joints")
            arm = self.arm(mode, outside=outside)
            base = arm.fk(joints)[:, :3, 3]
            flagged = arm.outside_rows(joints)
        else:
            base = np.array(position, dtype=float)
        field = self.error_field(mode)
        if field is None:
            return base, flagged
        term, beyond = evaluate_field(field, position, interpolation, outside, joints)
        return base + term, flagged | beyond


@dataclasses.dataclass(frozen=True, eq=False)
class Arm:
    """Where commanded joints take the TCP under a model: kinematics plus joint-angle errors.

    Attributes
    ----------
    robot : Robot
        Kinematics of the real arm as the model knows it.
    joints : JointResidual or None
        Joint-angle errors (None: the arm takes the commanded joints).
    nominal : Robot
        The nominal robot the joint errors' features are computed with.
    """

    robot: object
    joints: object
    nominal: object
    outside: str = "model"

    def outside_rows(self, q):
        """Boolean mask (N,) of commanded joints q (N, 6) outside the joint errors' fitted range.

        Raises
        ------
        ModelError
            With the ``error`` policy, naming the first such row.
        """
        q = np.atleast_2d(q)
        out = np.zeros(len(q), dtype=bool) if self.joints is None else ~self.joints.contains(q)
        if self.outside == "error" and out.any():
            first = int(np.flatnonzero(out)[0])
            raise ModelError(
                f"target {first}: joints {np.round(np.degrees(q[first]), 2).tolist()} deg lie outside the joint range "
                f"the model was calibrated on ({int(out.sum())} targets outside)"
            )
        return out

    def reached_joints(self, q):
        """Joint angles (N, 6) rad the arm takes for commanded joints q (N, 6)."""
        return q if self.joints is None else self.joints.reached(self.nominal, q)

    def fk(self, q):
        """TCP poses (N, 4, 4) reached for commanded joints q (N, 6) rad."""
        return fk(self.robot, self.reached_joints(np.atleast_2d(q)))

    def commanded_joints(self, q_reached):
        """Commanded joints (N, 6) rad under which the arm takes ``q_reached``."""
        return q_reached if self.joints is None else self.joints.commanded(self.nominal, q_reached)


def same_tool(T_a, T_b):
    """True when two tools (4, 4) agree to the precision programs write (0.001 mm, 1e-5 rad)."""
    return np.allclose(T_a[:3, 3], T_b[:3, 3], atol=1e-3) and np.allclose(T_a[:3, :3], T_b[:3, :3], atol=1e-5)


def evaluate_field(field, points, interpolation=None, outside="model", joints=None):
    """A residual field's value at points (N, 3), with the outside policy of `CompensationModel.predict`.

    ``joints`` (N, 6) rad: the commanded joints there, for a field over the wrist angles too (`needs_joints`).
    """
    inside = field.contains(points)
    if outside == "error" and not inside.all():
        first = int(np.flatnonzero(~inside)[0])
        raise ModelError(
            f"target {first} at {np.round(points[first], 3).tolist()} mm is outside the "
            f"compensation grid ({int((~inside).sum())} targets outside)"
        )
    by_joints = {"joints": joints} if getattr(field, "needs_joints", False) else {}
    values = field.evaluate(points, method=interpolation, outside="clamp", **by_joints)
    if outside == "model":
        values = np.where(inside[:, None], values, 0.0)
    return values, ~inside
