"""The compensation model and its file (YAML, ``format: trajcomp-model/1``).

A model holds everything `calibrate` identified for one robot: the DH deltas
with their uncertainties and the parameters left at nominal, the tracker
registration, the paper's linear correction, the grid of raw errors and the
grid of residuals left after the DH model, with fit and cross-validation
statistics. It predicts where the real arm ends for a command, in each mode:

``none``       the commanded position;
``linear``     commanded + linear error model (the paper's indirect correction);
``dh``         forward kinematics of the identified robot;
``grid``       commanded + interpolated raw error;
``composite``  identified robot + residual: a field over the commanded
               position (the paper's grid, for single-orientation data), or
               joint-angle errors over the configuration (`JointResidual`,
               for data at several orientations: right at any orientation).

It also says whether it can place a tool other than the one measured
(`CompensationModel.places_other_tools`, with the reason).

User units (mm, deg) in the file; a grid with many nodes is stored in a
sidecar ``<model file name>.npz`` named in the YAML, written together with it.
"""

import dataclasses
import datetime
import io
import math
import zipfile
from pathlib import Path

import numpy as np
import yaml

from trajcomp import __version__, yaml_text
from trajcomp.atomic import write_files_atomic
from trajcomp.errors import ModelError
from trajcomp.grid import field_from_dict
from trajcomp.ik import Configuration, branch_index
from trajcomp.joint_errors import KIND as JOINT_KIND
from trajcomp.joint_errors import JointResidual
from trajcomp.kinematics import fk
from trajcomp.linear import LinearCorrection
from trajcomp.parameters import apply_deltas, is_angle
from trajcomp.robot import load_robot
from trajcomp.transforms import abc_to_matrix, matrix_to_abc, matrix_to_pose, pose_to_matrix

FORMAT = "trajcomp-model/2"
SUFFIXES = (".yaml", ".yml")
MODES = ("none", "linear", "dh", "grid", "composite")
_SIDECAR_NODES = 1000  # grids with more nodes go to a sidecar .npz


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
        ``{name: reason}`` of parameters left at nominal.
    linear : LinearCorrection or None
    grid : residual field or None
        Interpolated raw errors (measured - commanded) over commanded positions.
    residual : residual field, JointResidual or None
        Residuals after the DH model: a field over the commanded position,
        or joint-angle errors over the configuration.
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
        Arm branches (`trajcomp.ik.Configuration` indices) the measurements
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
    R_tcp_target: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(3))
    places_other_tools: bool = False
    other_tools_reason: str = "not stated"
    postures: tuple = ()

    def unmeasured_posture(self, q, outside="model"):
        """Mask (N,) of commanded joints q (N, 6) rad in an arm branch the calibration did not measure.

        All False when the model does not record its postures.

        Raises
        ------
        ModelError
            With the ``error`` policy, naming the first such row and its branch.
        """
        q = np.atleast_2d(q)
        if not self.postures:
            return np.zeros(len(q), dtype=bool)
        branch = branch_index(self.nominal, q)
        out = ~np.isin(branch, self.postures)
        if outside == "error" and out.any():
            first = int(np.flatnonzero(out)[0])
            raise ModelError(
                f"target {first}: arm posture {Configuration.from_index(branch[first])} was never measured (the "
                f"calibration measured {', '.join(str(Configuration.from_index(b)) for b in self.postures)}; "
                f"{int(out.sum())} targets in other postures)"
            )
        return out

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
            Joints outside the range a joint residual was fitted on: without
            the joint errors (flagged), with those at the nearest joints of
            the range, or a ModelError.
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

    def error_field(self, mode):
        """The field over commanded positions ``mode`` adds (raw-error grid, residual grid), else None."""
        field = {"grid": self.grid, "composite": self.residual}.get(mode)
        return None if getattr(field, "kind", None) == JOINT_KIND else field

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
            Points outside the grid that took the ``outside`` policy.
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
        term, flagged = evaluate_field(field, position, interpolation, outside)
        return base + term, flagged


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
        return q if self.joints is None else self.joints.reached(self.nominal, q, self._policy)

    def fk(self, q):
        """TCP poses (N, 4, 4) reached for commanded joints q (N, 6) rad."""
        return fk(self.robot, self.reached_joints(np.atleast_2d(q)))

    def commanded_joints(self, q_reached):
        """Commanded joints (N, 6) rad under which the arm takes ``q_reached``."""
        return q_reached if self.joints is None else self.joints.commanded(self.nominal, q_reached, self._policy)

    @property
    def _policy(self):
        return "extrapolate" if self.outside == "error" else self.outside


def evaluate_field(field, points, interpolation=None, outside="model"):
    """A residual field's value at points (N, 3), with the outside policy of `CompensationModel.predict`."""
    inside = field.contains(points)
    if outside == "error" and not inside.all():
        first = int(np.flatnonzero(~inside)[0])
        raise ModelError(
            f"target {first} at {np.round(points[first], 3).tolist()} mm is outside the "
            f"compensation grid ({int((~inside).sum())} targets outside)"
        )
    values = field.evaluate(points, method=interpolation, outside="clamp")
    if outside == "model":
        values = np.where(inside[:, None], values, 0.0)
    return values, ~inside


def _pose_user(mat):
    pose = matrix_to_pose(mat)
    pose[3:] = np.degrees(pose[3:])
    return [round(float(v), 9) for v in pose]


def _pose_internal(values, where):
    try:
        pose = np.array(values, dtype=float).reshape(6)
    except (TypeError, ValueError):
        raise ModelError(f"{where}: expected [x, y, z, a, b, c], got {values!r}") from None
    if not np.isfinite(pose).all():
        raise ModelError(f"{where}: not finite: {pose.tolist()}")
    pose[3:] = np.radians(pose[3:])
    return pose_to_matrix(pose)


def sidecar_path(path):
    """The grid sidecar of model file ``path``: its full name plus ``.npz`` (``model.yaml.npz``).

    Model files end in .yaml or .yml, sidecars in .npz: a sidecar can be
    neither a model file nor another model's sidecar.
    """
    path = Path(path)
    return path.with_name(path.name + ".npz")


def _check_model_path(path):
    if Path(path).suffix.lower() not in SUFFIXES:
        raise ModelError(f"{path}: a model file name ends in {' or '.join(SUFFIXES)}")


def _robot_fingerprint(robot):
    std = robot.as_standard()
    parts = [std.a, np.degrees(std.alpha), std.d, np.degrees(std.theta_offset), np.degrees(std.beta)]
    return [round(float(v), 6) for part in parts for v in part]


def save_model(path, model):
    """Write a model file and, if its grids are large, its sidecar: both or neither.

    Parameters
    ----------
    path : str or Path
        The model file (``.yaml`` or ``.yml``); a sidecar is written beside
        it as `sidecar_path`.

    Raises
    ------
    ModelError
        A file name not ending in .yaml or .yml.
    WriteError
        A file cannot be written (nothing on disk has changed).
    """
    _check_model_path(path)
    path = Path(path)
    arrays = {}
    doc = {
        "format": FORMAT,
        "trajcomp_version": __version__,
        "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "robot": {
            "name": model.nominal.name,
            "ref": model.robot_ref,
            "dh_fingerprint": _robot_fingerprint(model.nominal),
            "tool": _pose_user(model.nominal.T_flange_tool),
        },
        "method": model.method,
        "tracker_to_base": _pose_user(model.T_tracker_base),
        "measured_frame_in_tcp": [round(float(v), 9) for v in np.degrees(matrix_to_abc(model.R_tcp_target))],
        "places_other_tools": {"value": bool(model.places_other_tools), "reason": model.other_tools_reason},
        "postures": [str(Configuration.from_index(b)) for b in model.postures],
        "parameters": [
            {
                "name": name,
                "delta": float(math.degrees(d) if is_angle(name) else d),
                "sigma": float(math.degrees(s) if is_angle(name) else s),
                "unit": "deg" if is_angle(name) else "mm",
            }
            for name, d, s in zip(model.dh_names, model.dh_delta, model.dh_sigma)
        ],
        "fixed_parameters": dict(model.dh_fixed),
        "linear": None if model.linear is None else model.linear.to_dict(),
    }
    for key in ("grid", "residual"):
        field = getattr(model, key)
        if field is None:
            doc[key] = None
            continue
        entry = field.to_dict()
        big = {k: v for k, v in entry.items() if isinstance(v, list) and np.size(v) > 3 * _SIDECAR_NODES}
        for name, value in big.items():
            arrays[f"{key}.{name}"] = np.asarray(value)
            entry[name] = {"sidecar": f"{key}.{name}"}
        doc[key] = entry
    doc["report"] = model.report
    files = {}
    if arrays:
        doc["sidecar"] = sidecar_path(path).name
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **arrays)
        files[sidecar_path(path)] = buffer.getvalue()
    files[path] = yaml.safe_dump(_plain(doc), sort_keys=False, width=100).encode("utf-8")
    write_files_atomic(files)


def _posture_index(text, path):
    """Configuration index of a posture written ``shoulder/elbow/wrist`` (``front/up/positive``)."""
    parts = str(text).split("/")
    if len(parts) != 3:
        raise ModelError(f"{path}: field postures: expected shoulder/elbow/wrist, got {text!r}")
    return Configuration(*parts).index


def _plain(value):
    """Numpy scalars and arrays turned into plain Python for YAML."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value


def load_model(path, robot=None):
    """Read a model file.

    Parameters
    ----------
    path : str or Path
    robot : str, optional
        The robot the caller expects; a model of another robot is an error.

    Raises
    ------
    ModelError
        Not a trajcomp model, another format version, another robot, a
        nominal robot whose DH table changed since calibration, a missing or
        unsafe sidecar, a non-finite number or a malformed field (named).
    """
    path = Path(path)
    try:
        doc = yaml_text.load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeError) as exc:
        raise ModelError(f"{path}: cannot read: {exc}") from exc
    except yaml.YAMLError as exc:
        raise ModelError(f"{path}: not valid YAML: {exc}") from exc
    if not isinstance(doc, dict) or "format" not in doc:
        raise ModelError(f"{path}: not a trajcomp model file (no 'format' key)")
    if doc["format"] != FORMAT:
        raise ModelError(
            f"{path}: format {doc['format']!r} is not supported by trajcomp {__version__} "
            f"(expected {FORMAT}); re-run calibrate with this version"
        )
    try:
        info = doc["robot"]
        if robot is not None and robot not in (info["name"], info["ref"]):
            raise ModelError(f"{path}: model is for robot {info['name']!r}, not {robot!r}")
        nominal = load_robot(info["ref"])
        if _robot_fingerprint(nominal) != info["dh_fingerprint"]:
            raise ModelError(f"{path}: the nominal DH table of robot {info['ref']!r} differs from the one calibrated")
        nominal = nominal.replace(T_flange_tool=_pose_internal(info["tool"], f"{path}: field robot.tool"))
        arrays = _read_sidecar(path, doc.get("sidecar"))
        fields = {}
        for key in ("grid", "residual"):
            entry = doc.get(key)
            if entry is not None:
                entry = {
                    k: arrays[v["sidecar"]] if isinstance(v, dict) and "sidecar" in v else v
                    for k, v in entry.items()
                }
                joint = entry.get("kind") == JOINT_KIND
                fields[key] = JointResidual.from_dict(entry) if joint else field_from_dict(entry)
        params = doc.get("parameters") or []
        names = [p["name"] for p in params]
        scale = np.array([math.pi / 180.0 if is_angle(n) else 1.0 for n in names])
        delta = _finite([p["delta"] for p in params], f"{path}: field parameters.delta") * scale
        sigma = _finite([p["sigma"] for p in params], f"{path}: field parameters.sigma") * scale
        target = _finite(doc["measured_frame_in_tcp"], f"{path}: field measured_frame_in_tcp")
        tools = doc["places_other_tools"]
        model = CompensationModel(
            nominal=nominal,
            robot_ref=info["ref"],
            method=doc["method"],
            T_tracker_base=_pose_internal(doc["tracker_to_base"], f"{path}: field tracker_to_base"),
            dh_names=names,
            dh_delta=delta,
            dh_sigma=sigma,
            dh_fixed=dict(doc.get("fixed_parameters") or {}),
            linear=None if doc.get("linear") is None else LinearCorrection.from_dict(doc["linear"]),
            grid=fields.get("grid"),
            residual=fields.get("residual"),
            report=doc.get("report") or {},
            R_tcp_target=abc_to_matrix(np.radians(target.reshape(3))),
            places_other_tools=bool(tools["value"]),
            other_tools_reason=str(tools["reason"]),
            postures=tuple(_posture_index(text, path) for text in doc.get("postures") or ()),
        )
    except ModelError as exc:
        raise ModelError(str(exc) if str(exc).startswith(str(path)) else f"{path}: {exc}") from None
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ModelError(f"{path}: malformed model field: {exc!r}") from exc
    model.check_mode(model.method)
    return model


def _finite(values, where):
    """Float array of ``values``; ModelError naming ``where`` if one is not a finite number."""
    try:
        array = np.array(values, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{where}: expected numbers, got {values!r}") from None
    if not np.isfinite(array).all():
        raise ModelError(f"{where}: not finite: {array.tolist()}")
    return array


def _read_sidecar(path, name):
    """Arrays of a model's sidecar ``name`` (a plain file name beside the model), ``{}`` without one."""
    if not name:
        return {}
    if not isinstance(name, str) or Path(name).name != name or name in (".", "..") or name == path.name:
        raise ModelError(f"{path}: field sidecar: {name!r} must be the name of a file beside the model, not the model")
    sidecar = path.parent / name
    try:
        with np.load(sidecar, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise ModelError(f"{path}: sidecar {sidecar} cannot be read: {exc}") from exc
    for key, array in arrays.items():
        if not np.issubdtype(array.dtype, np.number) or not np.isfinite(array).all():
            raise ModelError(f"{path}: sidecar {sidecar}: array {key} holds values that are not finite numbers")
    return arrays
