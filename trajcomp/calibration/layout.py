"""How a measurement file is laid out: the explicit column mapping.

trajcomp never guesses a layout. The standard measurement CSV
(docs/conventions.md) needs no mapping; any other file is read through a
`Layout`, given on the command line (``--columns j1=joint_1,mx=x_t+x_dif``)
or as a YAML mapping file (``--columns-file layout.yaml``)::

    # every key but `columns` is optional; the values shown are the defaults
    delimiter: ","             # one character; ";" for many European exports
    decimal: "."               # "," for a decimal comma (then delimiter is not ",")
    frame: base                # frame of the measured columns: base or tracker
    columns:                   # field: column name, or a sum/difference of columns
      j1: joint_1
      mx: x_t + x_dif
      temperature: air_temp    # optional: the hall's temperature at each row, deg C
    units:                     # unit of the values in the file, per field group
      joints: deg              # deg | rad
      position: mm             # x, y, z: mm | cm | m | um | in
      orientation: deg         # a, b, c (not quaternions): deg | rad
      measured: mm             # mx, my, mz
      measured_orientation: deg
    rotations:                 # convention of the orientation groups
      orientation: ZYX         # KUKA A, B, C = intrinsic Z-Y'-X''
      measured_orientation: ZYX

A rotation convention is a scipy Euler sequence (upper case intrinsic,
lower case extrinsic, e.g. ``XYZ``, ``xyz``), ``rotvec`` (axis times angle)
or ``quaternion``: then the group's fields are ``qw, qx, qy, qz`` (commanded)
or ``mqw, mqx, mqy, mqz`` (measured), scalar first. Orientations are
converted to A, B, C when read.
"""

import dataclasses
import math
import re

import numpy as np
import yaml

from trajcomp.support import yaml_text
from trajcomp.errors import ReadError
from trajcomp.arm.transforms import matrix_to_abc

JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
POSITION = ("x", "y", "z")
ORIENTATION = ("a", "b", "c")
QUATERNION = ("qw", "qx", "qy", "qz")
MEASURED = ("mx", "my", "mz")
MEASURED_ORIENTATION = ("mrx", "mry", "mrz")
MEASURED_QUATERNION = ("mqw", "mqx", "mqy", "mqz")
TRACK = ("track",)  # the track position of a robot on a track (mm), optional
TEMPERATURE = ("temperature",)  # deg C, optional: recorded by calibrate, compared by recalibrate
FIELDS = (JOINTS + POSITION + ORIENTATION + QUATERNION + MEASURED + MEASURED_ORIENTATION + MEASURED_QUATERNION
          + TRACK + TEMPERATURE)
GROUPS = {
    "joints": JOINTS,
    "position": POSITION,
    "orientation": ORIENTATION,
    "measured": MEASURED,
    "measured_orientation": MEASURED_ORIENTATION,
    "track": TRACK,
}
ROTATION_GROUPS = {
    "orientation": (ORIENTATION, QUATERNION),
    "measured_orientation": (MEASURED_ORIENTATION, MEASURED_QUATERNION),
}
LENGTH_UNITS = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "um": 1e-3, "in": 25.4}
ANGLE_UNITS = {"deg": math.pi / 180.0, "rad": 1.0}
FRAMES = ("base", "tracker")
ABC = "ZYX"
_KEYS = {"delimiter", "decimal", "frame", "columns", "units", "rotations"}
_EULER = re.compile(r"^(?:[XYZ]{3}|[xyz]{3})$")


@dataclasses.dataclass(frozen=True)
class Layout:
    """The layout of a measurement file.

    Attributes
    ----------
    columns : dict
        ``{field: expression}``; fields not named are read from columns of
        their own name when present.
    delimiter, decimal : str
        Field separator and decimal mark, one character each.
    frame : str or None
        Frame of the measured columns (``base``, ``tracker``), None: not stated.
    units : dict
        ``{group: unit}`` of `GROUPS` (missing: mm and deg).
    rotations : dict
        ``{group: convention}`` of the orientation groups (missing: ``ZYX``).
    source : str
        Where the layout comes from, for messages.
    """

    columns: dict = dataclasses.field(default_factory=dict)
    delimiter: str = ","
    decimal: str = "."
    frame: str = None
    units: dict = dataclasses.field(default_factory=dict)
    rotations: dict = dataclasses.field(default_factory=dict)
    source: str = "column mapping"

    def __post_init__(self):
        where = self.source
        for field, expression in self.columns.items():
            if field not in FIELDS:
                raise ReadError(f"{where}: columns: unknown field {field!r} (one of {', '.join(FIELDS)})")
            if not isinstance(expression, str) or not expression.strip():
                raise ReadError(f"{where}: columns: field {field}: expected a column name, got {expression!r}")
        seen = {}
        for field, expression in self.columns.items():
            key = re.sub(r"\s+", "", expression)
            if key in seen:
                raise ReadError(f"{where}: columns: fields {seen[key]} and {field} both read {expression!r}")
            seen[key] = field
        for name, value in (("delimiter", self.delimiter), ("decimal", self.decimal)):
            if not isinstance(value, str) or len(value) != 1 or value in "\r\n\"":
                raise ReadError(f"{where}: {name}: expected one character, got {value!r}")
        if self.decimal not in ".,":
            raise ReadError(f"{where}: decimal: expected '.' or ',', got {self.decimal!r}")
        if self.decimal == self.delimiter:
            raise ReadError(f"{where}: decimal {self.decimal!r} cannot also be the delimiter")
        if self.frame is not None and self.frame not in FRAMES:
            raise ReadError(f"{where}: frame: expected one of {', '.join(FRAMES)}, got {self.frame!r}")
        for group, unit in self.units.items():
            allowed = ANGLE_UNITS if group in ("joints", "orientation", "measured_orientation") else LENGTH_UNITS
            if group not in GROUPS or unit not in allowed:
                raise ReadError(
                    f"{where}: units: {group}: {unit!r} is not a unit of a field group "
                    f"(groups {', '.join(GROUPS)}; lengths {', '.join(LENGTH_UNITS)}; angles {', '.join(ANGLE_UNITS)})"
                )
        for group, convention in self.rotations.items():
            if group not in ROTATION_GROUPS or not (
                convention in ("rotvec", "quaternion") or (isinstance(convention, str) and _EULER.match(convention))
            ):
                raise ReadError(
                    f"{where}: rotations: {group}: {convention!r}: expected an orientation group "
                    f"({', '.join(ROTATION_GROUPS)}) and an Euler sequence (e.g. ZYX, xyz), rotvec or quaternion"
                )

    def scale(self, group):
        """Factor from the file's unit of ``group`` to mm or rad."""
        unit = self.units.get(group)
        if group in ("joints", "orientation", "measured_orientation"):
            return ANGLE_UNITS[unit or "deg"]
        return LENGTH_UNITS[unit or "mm"]

    def convention(self, group):
        """Rotation convention of an orientation group."""
        return self.rotations.get(group, ABC)


def parse_mapping(text):
    """The `Layout` of a command-line mapping ``"j1=joint_1,mx=x_t+x_dif"``.

    Raises
    ------
    ReadError
        On an entry without ``=``, an unknown target field or a field given twice.
    """
    columns = {}
    for entry in filter(None, (e.strip() for e in str(text).split(","))):
        field, sep, expression = entry.partition("=")
        field = field.strip()
        if not sep or not expression.strip():
            raise ReadError(f"column mapping entry {entry!r}: expected FIELD=COLUMN")
        if field in columns:
            raise ReadError(f"column mapping: field {field} is given twice")
        columns[field] = expression.strip()
    if not columns:
        raise ReadError(f"column mapping {text!r}: expected FIELD=COLUMN,... (e.g. j1=joint_1,mx=x_t+x_dif)")
    return Layout(columns=columns, source="--columns")


def load_layout(path):
    """Read a YAML mapping file (see the module docstring).

    Raises
    ------
    ReadError
        Unreadable file, invalid YAML, an unknown key, field, unit or convention.
    """
    path = str(path)
    try:
        doc = yaml_text.load(yaml_text.read(path))
    except (OSError, UnicodeError) as exc:
        raise ReadError(f"{path}: cannot read: {exc}") from exc
    except yaml.YAMLError as exc:
        raise ReadError(f"{path}: not valid YAML: {exc}") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("columns", {}), dict):
        raise ReadError(f"{path}: expected a mapping with a 'columns' mapping (field: column)")
    unknown = set(doc) - _KEYS
    if unknown:
        raise ReadError(f"{path}: unknown keys {', '.join(sorted(unknown))} (allowed: {', '.join(sorted(_KEYS))})")
    for key in ("units", "rotations"):
        if not isinstance(doc.get(key) or {}, dict):
            raise ReadError(f"{path}: {key}: expected a mapping of field group to value")
    return Layout(
        columns={str(k): v for k, v in (doc.get("columns") or {}).items()},
        delimiter=doc.get("delimiter", ","),
        decimal=doc.get("decimal", "."),
        frame=doc.get("frame"),
        units=dict(doc.get("units") or {}),
        rotations=dict(doc.get("rotations") or {}),
        source=path,
    )


def rotation_to_abc(values, convention, scale):
    """A, B, C (N, 3) rad of orientations in a file's convention.

    Parameters
    ----------
    values : ndarray, shape (N, 3) or (N, 4)
        Euler angles or a rotation vector (in the file's angle unit), or
        quaternions scalar first.
    convention : str
        Euler sequence, ``rotvec`` or ``quaternion``.
    scale : float
        File angle unit to rad (ignored for quaternions).
    """
    if convention == ABC:
        return values * scale
    from scipy.spatial.transform import Rotation  # here: reading A, B, C files never needs scipy

    if convention == "quaternion":
        norm = np.linalg.norm(values, axis=1)
        if np.any(norm < 1e-9):
            raise ValueError(f"zero quaternion in row {int(np.argmax(norm < 1e-9))}")
        rotation = Rotation.from_quat(values / norm[:, None], scalar_first=True)
    elif convention == "rotvec":
        rotation = Rotation.from_rotvec(values * scale)
    else:
        rotation = Rotation.from_euler(convention, values * scale)
    return matrix_to_abc(rotation.as_matrix())
