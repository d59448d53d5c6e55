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
``composite``  identified robot + interpolated residual.

User units (mm, deg) in the file; a grid with many nodes is stored in a
sidecar ``.npz`` named in the YAML.
"""

import dataclasses
import datetime
import io
import math
from pathlib import Path

import numpy as np
import yaml

from trajcomp import __version__
from trajcomp.atomic import write_atomic
from trajcomp.errors import ModelError
from trajcomp.grid import field_from_dict
from trajcomp.identify import apply_deltas, is_angle
from trajcomp.kinematics import fk
from trajcomp.linear import LinearCorrection
from trajcomp.robot import load_robot
from trajcomp.transforms import matrix_to_pose, pose_to_matrix

FORMAT = "trajcomp-model/1"
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
    residual : residual field or None
        Interpolated residuals after the DH model.
    report : dict
        Fit and cross-validation statistics, warnings, provenance.
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

    @property
    def identified(self):
        """The identified robot (standard DH)."""
        return apply_deltas(self.nominal, self.dh_names, self.dh_delta)

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
        """The interpolated field ``mode`` adds: raw-error grid (grid), residual grid (composite), else None."""
        return {"grid": self.grid, "composite": self.residual}.get(mode)

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
            base = fk(self.identified, joints)[:, :3, 3]
        else:
            base = np.array(position, dtype=float)
        if mode == "dh":
            return base, flagged
        term, flagged = evaluate_field(self.error_field(mode), position, interpolation, outside)
        return base + term, flagged


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
    pose[3:] = np.radians(pose[3:])
    return pose_to_matrix(pose)


def _robot_fingerprint(robot):
    std = robot.as_standard()
    parts = [std.a, np.degrees(std.alpha), std.d, np.degrees(std.theta_offset), np.degrees(std.beta)]
    return [round(float(v), 6) for part in parts for v in part]


def save_model(path, model):
    """Write a model file atomically (and its grid sidecar, if the grid is large).

    Parameters
    ----------
    path : str or Path
        The ``.yaml`` file; a sidecar is written beside it as ``<stem>.npz``.
    """
    path = Path(path)
    arrays = {}
    doc = {
        "format": FORMAT,
        "trajcomp_version": __version__,
        "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "robot": {"name": model.nominal.name, "ref": model.robot_ref, "dh_fingerprint": _robot_fingerprint(model.nominal)},
        "method": model.method,
        "tracker_to_base": _pose_user(model.T_tracker_base),
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
        if big:
            for name, value in big.items():
                arrays[f"{key}.{name}"] = np.asarray(value)
                entry[name] = {"sidecar": f"{key}.{name}"}
        doc[key] = entry
    doc["report"] = model.report
    if arrays:
        doc["sidecar"] = path.with_suffix(".npz").name
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **arrays)
        write_atomic(path.with_suffix(".npz"), buffer.getvalue())
    write_atomic(path, yaml.safe_dump(_plain(doc), sort_keys=False, width=100))


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
        nominal robot whose DH table changed since calibration, a missing
        sidecar or a malformed field (named).
    """
    path = Path(path)
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
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
        arrays = {}
        if doc.get("sidecar"):
            sidecar = path.parent / doc["sidecar"]
            try:
                with np.load(sidecar) as data:
                    arrays = {k: data[k] for k in data.files}
            except OSError as exc:
                raise ModelError(f"{path}: sidecar {sidecar} cannot be read: {exc}") from exc
        fields = {}
        for key in ("grid", "residual"):
            entry = doc.get(key)
            if entry is not None:
                entry = {
                    k: arrays[v["sidecar"]] if isinstance(v, dict) and "sidecar" in v else v
                    for k, v in entry.items()
                }
                fields[key] = field_from_dict(entry)
        params = doc.get("parameters") or []
        names = [p["name"] for p in params]
        scale = np.array([math.pi / 180.0 if is_angle(n) else 1.0 for n in names])
        model = CompensationModel(
            nominal=nominal,
            robot_ref=info["ref"],
            method=doc["method"],
            T_tracker_base=_pose_internal(doc["tracker_to_base"], f"{path}: field tracker_to_base"),
            dh_names=names,
            dh_delta=np.array([p["delta"] for p in params], dtype=float) * scale,
            dh_sigma=np.array([p["sigma"] for p in params], dtype=float) * scale,
            dh_fixed=dict(doc.get("fixed_parameters") or {}),
            linear=None if doc.get("linear") is None else LinearCorrection.from_dict(doc["linear"]),
            grid=fields.get("grid"),
            residual=fields.get("residual"),
            report=doc.get("report") or {},
        )
    except ModelError:
        raise
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelError(f"{path}: malformed model field: {exc!r}") from exc
    model.check_mode(model.method)
    return model
