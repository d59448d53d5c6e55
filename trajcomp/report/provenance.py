"""Where a report's numbers come from: files with their SHA-256, the model, the software."""

import datetime
import hashlib
import platform
from pathlib import Path

import yaml

from trajcomp import __version__
from trajcomp.support import yaml_text
from trajcomp.support.atomic import sha256_of
from trajcomp.errors import ReadError



def sha256(path):
    """Hex SHA-256 of a file's bytes."""
    try:
        return sha256_of(path)
    except OSError as exc:
        raise ReadError(f"{path}: cannot read for its checksum: {exc.strerror}") from exc


def file_entry(role, path, data=None, staged=None):
    """``{"role", "path", "sha256", "bytes"}`` of a file on disk, of the ``data`` (bytes) about to be written to it,
    or of its content ``staged`` in a set of outputs (`trajcomp.support.atomic.FileSet.digest`: SHA-256, bytes)."""
    if staged is not None:
        return {"role": role, "path": str(path), "sha256": staged[0], "bytes": staged[1]}
    if data is None:
        return {"role": role, "path": str(path), "sha256": sha256(path), "bytes": Path(path).stat().st_size}
    return {"role": role, "path": str(path), "sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data)}


def model_entry(path, model, mode):
    """What a report says about the model used: file, checksum, date, method, mode, statistics.

    Parameters
    ----------
    path : str or Path or None
        The model file as given; None for a model in memory (then no file,
        checksum or date).
    model : CompensationModel
    mode : str
        The mode the run used.
    """
    try:
        header = {} if path is None else yaml_text.load(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeError, yaml.YAMLError) as exc:
        raise ReadError(f"{path}: cannot read the model file again for the report: {exc}") from exc
    report = model.report
    field = model.error_field(mode)
    return {
        "path": "(a model in memory)" if path is None else str(path),
        "sha256": None if path is None else sha256(path),
        "created": header.get("created"),
        "trajcomp_version": header.get("trajcomp_version"),
        "robot": model.robot_ref,
        "method": model.method,
        "mode": mode,
        "modes": list(model.modes),
        "grid": None if field is None else grid_box(field),
        "measurements": report.get("measurements"),
        "fit": {m: s for m, s in (report.get("fit") or {}).items() if isinstance(s, dict)},
        "cross_validation": report.get("cross_validation"),
    }


def grid_box(field):
    """``{"kind", "lower", "upper", "step", "shape"}`` of a residual field (mm); step and shape for lattices."""
    lattice = getattr(field, "lattice", None)
    if lattice is not None:
        lower, upper = lattice.origin, lattice.upper
        extra = {"step": lattice.step.tolist(), "shape": list(lattice.shape)}
    else:
        lower, upper = field.lower, field.upper
        extra = {"step": None, "shape": None}
    kind = getattr(field, "kind", "grid")
    return {"kind": kind, "interpolation": getattr(field, "method", kind),
            "lower": [float(v) for v in lower], "upper": [float(v) for v in upper], **extra}


def header(kind, command):
    """The fields every report starts with."""
    return {
        "schema": "trajcomp-report/1",
        "kind": kind,
        "command": command,
        "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "trajcomp_version": __version__,
        "python": platform.python_version(),
    }
