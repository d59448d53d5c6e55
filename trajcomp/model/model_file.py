"""The compensation model's file (YAML, ``format: trajcomp-model/2``): `save_model` and `load_model`.

User units (mm, deg) in the file; a grid with many nodes is stored in a
sidecar ``<model file name>.npz`` named in the YAML, written together with it.
A model file holds a `trajcomp.model.compensation_model.CompensationModel`: its nominal robot
(checked against the DH table on reading), the identified parameters, the
registration, the linear correction and the grids, with the report.
"""

import datetime
import hashlib
import io
import math
import os
import stat
import uuid
import zipfile
from pathlib import Path

import numpy as np
import yaml

from trajcomp import __version__
from trajcomp.support import yaml_text
from trajcomp.support.atomic import recover, write_files_atomic
from trajcomp.errors import IKError, ModelError, RobotError
from trajcomp.model.grid import field_from_dict
from trajcomp.arm.ik import Configuration
from trajcomp.model.joint_errors import KIND as JOINT_KIND
from trajcomp.model.joint_errors import JointResidual
from trajcomp.model.linear import LinearCorrection
from trajcomp.model.compensation_model import CompensationModel
from trajcomp.arm.parameters import TOOL_NAMES, candidate_parameters, is_angle
from trajcomp.support.plain_data import plain
from trajcomp.arm.robot import builtin_robot_names, load_robot
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc, matrix_to_pose, pose_to_matrix

_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)  # libyaml's emitter where built (the same text, 4x faster)

FORMAT = "trajcomp-model/2"
SUFFIXES = (".yaml", ".yml")
_SIDECAR_NODES = 1000  # grids with more nodes go to a sidecar .npz
_SIDECAR_BYTES = 64 << 20  # largest sidecar read, on disk and its arrays unpacked (a 10 mm grid over 1 m^3: 24 MB)
_REGISTRATION_BOUND = 1e5  # mm, |translation| of a tracker registration, base, tool or measured-point offset
_FIELD_BOUND = 1e6  # |value| of a grid, residual or linear correction entry (mm, mm/mm, rad)


def _pose_user(mat):
    pose = matrix_to_pose(mat)
    pose[3:] = np.degrees(pose[3:])
    return [round(float(v), 9) for v in pose]


def _pose_internal(values, where):
    pose = _finite(values, where, count=6)
    if np.abs(pose[:3]).max() > _REGISTRATION_BOUND:
        raise ModelError(f"{where}: a translation beyond {_REGISTRATION_BOUND:g} mm: {pose.tolist()}")
    pose[3:] = np.radians(pose[3:])
    return pose_to_matrix(pose)


def sidecar_path(path):
    """The grid sidecar of model file ``path``: its full name plus ``.npz`` (``model.yaml.npz``).

    Model files end in .yaml or .yml, sidecars in .npz: a sidecar can be
    neither a model file nor another model's sidecar.
    """
    path = Path(path)
    return path.with_name(path.name + ".npz")


def model_files(path):
    """The files of model file ``path``: itself and its grid sidecar (which need not exist), as given and Path."""
    return [path, sidecar_path(path)]


def _check_model_path(path):
    if Path(path).suffix.lower() not in SUFFIXES:
        raise ModelError(f"{path}: a model file name ends in {' or '.join(SUFFIXES)}")


def _robot_fingerprint(robot):
    std = robot.as_standard()
    parts = [std.a, np.degrees(std.alpha), std.d, np.degrees(std.theta_offset), np.degrees(std.beta)]
    return [round(float(v), 6) for part in parts for v in part]


def save_model(path, model):
    """Write a model file and, if its grids are large, its sidecar: both or neither.

    The model names its sidecar's SHA-256 and a calibration id of its own,
    so that a sidecar of another calibration (copied, or left by a write
    that did not complete) is refused on loading, never used silently.

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
            "ref": _ref_from(model.robot_ref, path.parent),
            "dh_fingerprint": _robot_fingerprint(model.nominal),
            "tool": _pose_user(model.nominal.T_flange_tool),
            "track": _track_user(model.nominal.track),
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
    for key in ("grid", "residual", "residual_field"):
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
    doc["calibration_id"] = uuid.uuid4().hex
    if arrays:
        doc["sidecar"] = sidecar_path(path).name
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **arrays)
        files[sidecar_path(path)] = buffer.getvalue()
        doc["sidecar_sha256"] = hashlib.sha256(files[sidecar_path(path)]).hexdigest()
    files[path] = yaml.dump(plain(doc), Dumper=_DUMPER, sort_keys=False, width=100).encode("utf-8")
    write_files_atomic(files)


def _posture_index(text, path):
    """Configuration index of a posture written ``shoulder/elbow/wrist`` (``front/up/positive``)."""
    parts = text.split("/") if isinstance(text, str) else []
    if len(parts) != 3:
        raise ModelError(f"{path}: field postures: expected shoulder/elbow/wrist, got {yaml_text.shown(text)}")
    try:
        return Configuration(*parts).index
    except IKError as exc:
        raise ModelError(f"{path}: field postures: {exc}") from None


def _ref_from(ref, folder):
    """How a model file in ``folder`` names its robot: a built-in name as it is, a robot file by its path relative
    to that folder (``ref`` is a path from the working folder), so that the model is read from any working
    folder and moved together with its robot file."""
    if ref in builtin_robot_names() or not _is_file(Path(ref)):  # a name, or an arm made in code: as it is
        return ref
    return Path(os.path.relpath(Path(ref).resolve(), folder.resolve())).as_posix()


def _found_ref(ref, path):
    """The robot a model file at ``path`` names, as `load_robot` takes it: a built-in name, or the robot file's
    path from the working folder; a relative path is the model's folder's (`_ref_from`), else the working
    folder's (the models of an earlier version named the file as typed)."""
    if not isinstance(ref, str):
        raise ModelError(f"{path}: field robot.ref: expected a robot name, got {yaml_text.shown(ref)}")
    beside = path.parent / ref
    if ref in builtin_robot_names() or Path(ref).is_absolute() or not _is_file(beside):
        return ref
    return str(beside)


def _is_file(path):
    """Whether ``path`` is a file; False for a name longer than the system allows (`Path.is_file` raises)."""
    try:
        return path.is_file()
    except OSError:
        return False


def _same_robot(asked, ref):
    """Whether the robot a caller asks for (a built-in name or a robot file path) is the model's ``ref``."""
    if asked == ref:
        return True
    return _is_file(Path(asked)) and Path(asked).resolve() == Path(ref).resolve()


def _nominal_robot(ref, path):
    """The robot a model names (a built-in name or a robot file); ModelError naming the model's field if not."""
    try:
        return load_robot(ref)
    except RobotError as exc:
        raise ModelError(f"{path}: field robot.ref: {exc}") from None


def _check_names(names, nominal, where):
    """Refuse parameter names the nominal robot has not, or given twice (deltas would be applied twice)."""
    known = set(candidate_parameters(nominal, tool=False, orientation=True, tracker=True)) | set(TOOL_NAMES)
    seen = set()
    for name in names:
        if not isinstance(name, str) or name not in known:
            raise ModelError(f"{where}: {yaml_text.shown(name)} is no parameter of robot {nominal.name}")
        if name in seen:
            raise ModelError(f"{where}: {name} is given twice")
        seen.add(name)


def _check_magnitudes(value, where):
    """Refuse a number in ``value`` (nested lists and mappings) that is not finite or beyond `_FIELD_BOUND`.

    The grids' origins, steps and errors (mm), the linear correction's
    intercepts (mm) and slopes (mm/mm), the joint residual's coefficients
    and joint ranges (rad) are all far below it: beyond it a value is damage
    (``1e308``), which would overflow into infinities downstream.
    """
    if isinstance(value, dict):
        for key, child in value.items():
            _check_magnitudes(child, f"{where}.{key}")
    elif isinstance(value, list):
        for child in value:
            _check_magnitudes(child, where)
    elif isinstance(value, (int, float)) and not isinstance(value, bool) and not abs(value) <= _FIELD_BOUND:
        raise ModelError(f"{where}: {yaml_text.shown(value)} is beyond {_FIELD_BOUND:g} or not finite")


def _check_report(model):
    """Refuse a report whose sections other code reads are not of their shape (the landing data are read now)."""
    report = model.report
    if not isinstance(report, dict):
        raise ModelError(f"field report: expected a mapping, got {yaml_text.shown(report)}")
    for key in ("fit", "cross_validation", "measurements", "identifiability"):
        if not isinstance(report.get(key, {}), dict):
            raise ModelError(f"field report.{key}: expected a mapping, got {yaml_text.shown(report[key])}")
    for key in ("fit", "cross_validation"):
        for mode, stats in report.get(key, {}).items():
            values = [v for value in stats.values() for v in (value if isinstance(value, list) else [value])] \
                if isinstance(stats, dict) else []
            if not all(v is None or isinstance(v, (int, float)) for v in values):
                raise ModelError(f"field report.{key}.{mode}: expected numbers, got {yaml_text.shown(stats)}")
    from trajcomp.model.landing import of_model  # here: the landing estimate's imports are not every command's

    of_model(model)


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
    recover(path.parent)  # a model and sidecar a killed run left half-renamed are completed first
    try:
        doc = yaml_text.load(yaml_text.read(path))
    except (OSError, UnicodeError) as exc:
        raise ModelError(f"{path}: cannot read: {exc}") from exc
    except yaml.YAMLError as exc:
        raise ModelError(f"{path}: not valid YAML: {exc}") from exc
    if not isinstance(doc, dict) or "format" not in doc:
        raise ModelError(f"{path}: not a trajcomp model file (no 'format' key)")
    if doc["format"] != FORMAT:
        raise ModelError(
            f"{path}: format {yaml_text.shown(doc['format'])} is not supported by trajcomp {__version__} "
            f"(expected {FORMAT}); re-run calibrate with this version"
        )
    try:
        info = doc["robot"]
        ref = _found_ref(info["ref"], path)
        if robot is not None and robot != info["name"] and not _same_robot(robot, ref):
            raise ModelError(f"{path}: model is for robot {yaml_text.shown(info['name'])}, not {robot!r}")
        nominal = _nominal_robot(ref, path)
        if _robot_fingerprint(nominal) != info["dh_fingerprint"]:
            raise ModelError(f"{path}: the nominal DH table of robot {yaml_text.shown(info['ref'])} differs from the one calibrated")
        nominal = nominal.replace(T_flange_tool=_pose_internal(info["tool"], f"{path}: field robot.tool"),
                                  track=_track_internal(info.get("track"), nominal, path))
        arrays = _read_sidecar(path, doc.get("sidecar"), doc.get("sidecar_sha256"), doc.get("calibration_id"))
        fields = {}
        for key in ("grid", "residual", "residual_field", "linear"):
            _check_magnitudes(doc.get(key), f"{path}: field {key}")
        for key in ("grid", "residual", "residual_field"):
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
        _check_names(names, nominal, f"{path}: field parameters.name")
        scale = np.array([math.pi / 180.0 if is_angle(n) else 1.0 for n in names])
        delta = _finite([p["delta"] for p in params], f"{path}: field parameters.delta") * scale
        _check_bounds(names, delta, f"{path}: field parameters.delta")
        sigma = _finite([p["sigma"] for p in params], f"{path}: field parameters.sigma") * scale
        target = _finite(doc["measured_frame_in_tcp"], f"{path}: field measured_frame_in_tcp")
        tools = doc["places_other_tools"]
        model = CompensationModel(
            nominal=nominal,
            robot_ref=ref,
            method=doc["method"],
            T_tracker_base=_pose_internal(doc["tracker_to_base"], f"{path}: field tracker_to_base"),
            dh_names=names,
            dh_delta=delta,
            dh_sigma=sigma,
            dh_fixed=dict(doc.get("fixed_parameters") or {}),
            linear=None if doc.get("linear") is None else LinearCorrection.from_dict(doc["linear"]),
            grid=fields.get("grid"),
            residual=fields.get("residual"),
            residual_field=fields.get("residual_field"),
            report=doc.get("report") or {},
            R_tcp_target=abc_to_matrix(np.radians(target.reshape(3))),
            places_other_tools=bool(tools["value"]),
            other_tools_reason=str(tools["reason"]),
            postures=tuple(_posture_index(text, path) for text in doc.get("postures") or ()),
        )
        model.check_mode(model.method)
        _check_report(model)
    except (ModelError, IKError) as exc:
        raise ModelError(str(exc) if str(exc).startswith(str(path)) else f"{path}: {exc}") from None
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ModelError(f"{path}: malformed model field: {yaml_text.shown(exc)}") from exc
    return model


def _track_user(track):
    """The identified track of a model's robot as the file states it (None: no track, or none identified)."""
    if track is None or not track.identified:
        return None
    return {"direction": [float(v) for v in track.actual_direction], "scale": float(track.actual_scale),
            "measured_positions": [float(v) for v in track.measured_positions],
            "straightness": None if track.straightness is None else np.round(track.straightness, 6).tolist(),
            "scatter_mm": None if track.scatter is None else float(track.scatter)}


def _track_internal(entry, nominal, path):
    """The nominal robot's track with the identified one a model file states (``robot.track``), or as it is."""
    if entry is None:
        return nominal.track
    if nominal.track is None:
        raise ModelError(f"{path}: field robot.track: the model identified a track, but robot "
                         f"{yaml_text.shown(nominal.name)} describes none")
    direction = _finite(entry["direction"], f"{path}: field robot.track.direction", 3)
    scale = float(_finite([entry["scale"]], f"{path}: field robot.track.scale", 1)[0])
    positions = _finite(entry["measured_positions"], f"{path}: field robot.track.measured_positions")
    if not 0.5 < scale < 2.0 or not 0.5 < np.linalg.norm(direction) < 1.5:
        raise ModelError(f"{path}: field robot.track: scale {scale:g} or direction {direction.tolist()} is no track's")
    table = entry.get("straightness")
    if table is not None:
        table = _finite(np.ravel(table).tolist(), f"{path}: field robot.track.straightness", 3 * len(positions))
        if np.any(np.diff(positions) <= 0) or np.abs(table).max() > 100.0:
            raise ModelError(f"{path}: field robot.track.straightness: expected a row (mm) per measured position, "
                             "ascending, within 100 mm of the line")
        table = table.reshape(-1, 3)
    scatter = entry.get("scatter_mm")
    if scatter is not None:
        scatter = float(_finite([scatter], f"{path}: field robot.track.scatter_mm", 1)[0])
        if scatter < 0:
            raise ModelError(f"{path}: field robot.track.scatter_mm: expected a positive number, got {scatter:g}")
    return nominal.track.replace(actual_direction=direction / np.linalg.norm(direction), actual_scale=scale,
                                 measured_positions=np.sort(positions), straightness=table, scatter=scatter)


def _finite(values, where, count=None):
    """Float array of ``values`` (a list of ``count`` numbers, any count if None); ModelError naming ``where`` if not.

    The shape is checked before an array is made, and the message quotes at
    most 100 characters of the value (a YAML value may be huge).
    """
    numbers = isinstance(values, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)
    if not numbers or (count is not None and len(values) != count):
        expected = f"a list of {count} numbers" if count else "a list of numbers"
        raise ModelError(f"{where}: expected {expected}, got {yaml_text.shown(values)}")
    array = np.array(values, dtype=float)
    if not np.isfinite(array).all():
        raise ModelError(f"{where}: not finite: {array.tolist()}")
    return array


def _check_bounds(names, delta, where):
    """Refuse parameter deltas (mm, rad) no calibration writes: a DH delta beyond the plausibility bounds, others huge."""
    from trajcomp.arm.parameters import ANGLE_BOUND, LENGTH_BOUND

    for name, value in zip(names, delta):
        registration = name.startswith(("base_", "target_", "tool_", "gear", "grav"))
        bound = (math.pi if registration else ANGLE_BOUND) if is_angle(name) else \
            (_REGISTRATION_BOUND if registration else LENGTH_BOUND)
        if abs(value) > bound:
            shown, limit = (f"{math.degrees(value):.6g} deg", f"{math.degrees(bound):g} deg") if is_angle(name) \
                else (f"{value:.6g} mm", f"{bound:g} mm")
            raise ModelError(f"{where}: {name} = {shown} is beyond the {limit} a calibration writes")


def _array_bytes(archive, member, where):
    """Bytes of the array an ``.npy`` member of an ``.npz`` holds, from its header (nothing else is unpacked).

    Raises
    ------
    ModelError
        A member that is not an ``.npy`` array of numbers, or whose header
        states another size than the member's (numpy would allocate what the
        header states before reading: terabytes for a crafted header).
    """
    readers = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
    if not member.filename.endswith(".npy"):
        raise ModelError(f"{where}: member {member.filename[:100]!r} is not an array (.npy)")
    with archive.open(member) as handle:
        version = np.lib.format.read_magic(handle)
        if version not in readers:
            raise ModelError(f"{where}: member {member.filename[:100]!r}: .npy version {version} is not read")
        shape, _, dtype = readers[version](handle)
        stated = math.prod(shape) * dtype.itemsize
        if dtype.hasobject or stated != member.file_size - handle.tell():
            raise ModelError(f"{where}: member {member.filename[:100]!r} states {stated} bytes of {dtype} in "
                             f"{member.file_size - handle.tell()}")
    return stated


def _read_sidecar(path, name, sha256=None, calibration=None):
    """Arrays of a model's sidecar ``name`` (a plain file name beside the model), ``{}`` without one.

    The sidecar must be a regular file (not a FIFO or a device), at most
    64 MiB on disk and unpacked (sizes read from the arrays' headers before
    anything is unpacked), and of the SHA-256 the model names; its arrays
    must be numbers within `_FIELD_BOUND`.
    """
    if not name:
        return {}
    if not isinstance(name, str) or Path(name).name != name or name in (".", "..") or name == path.name:
        raise ModelError(f"{path}: field sidecar: {str(name)[:100]!r} must be the name of a file beside the model, "
                         "not the model")
    sidecar = path.parent / name
    try:
        found = sidecar.stat()
        if not stat.S_ISREG(found.st_mode):
            raise ModelError(f"{path}: sidecar {sidecar} is not a regular file")
        if found.st_size > _SIDECAR_BYTES:
            raise ModelError(f"{path}: sidecar {sidecar} holds {found.st_size} bytes, more than a model's grid "
                             f"({_SIDECAR_BYTES} bytes)")
        data = sidecar.read_bytes()
    except OSError as exc:
        raise ModelError(f"{path}: sidecar {sidecar} cannot be read: {exc.strerror}") from exc
    if sha256 is not None and hashlib.sha256(data).hexdigest() != sha256:
        raise ModelError(f"{path}: sidecar {sidecar} is not the one written with this model (calibration "
                         f"{calibration}): its SHA-256 differs; a sidecar of another calibration, or a copy that did "
                         "not complete: calibrate again or restore the pair")
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            unpacked = sum(_array_bytes(archive, member, f"{path}: sidecar {sidecar}") for member in archive.infolist())
        if unpacked > _SIDECAR_BYTES:
            raise ModelError(f"{path}: sidecar {sidecar} unpacks to {unpacked} bytes, more than a model's grid "
                             f"({_SIDECAR_BYTES} bytes)")
        with np.load(io.BytesIO(data), allow_pickle=False) as loaded:
            arrays = {k: loaded[k] for k in loaded.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise ModelError(f"{path}: sidecar {sidecar} cannot be read: {str(exc)[:200]}") from exc
    for key, array in arrays.items():
        if not np.issubdtype(array.dtype, np.number) or not np.all(np.abs(array) <= _FIELD_BOUND):
            raise ModelError(f"{path}: sidecar {sidecar}: array {key} holds values that are not finite numbers "
                             f"within {_FIELD_BOUND:g}")
    return arrays
