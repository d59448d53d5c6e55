"""The measurement CSV (conventions.md): read with located errors, write atomically.

Columns: ``j1..j6`` commanded joints (deg), ``x,y,z[,a,b,c]`` commanded TCP
pose (mm, deg), ``mx,my,mz`` measured TCP position (mm), optional
``mrx,mry,mrz`` measured orientation (deg). Other layouts are read through an
explicit column mapping ``{field: expression}`` where an expression is a
column name or a sum/difference of columns, e.g. ``{"mx": "x_t+x_dif"}``.
"""

import csv
import dataclasses
import io
import math
import re
from pathlib import Path

import numpy as np

from trajcomp.atomic import write_atomic
from trajcomp.errors import ReadError

JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
POSITION = ("x", "y", "z")
ORIENTATION = ("a", "b", "c")
MEASURED = ("mx", "my", "mz")
MEASURED_ORIENTATION = ("mrx", "mry", "mrz")
FIELDS = JOINTS + POSITION + ORIENTATION + MEASURED + MEASURED_ORIENTATION


@dataclasses.dataclass(frozen=True, eq=False)
class Measurements:
    """Commanded and measured TCP data of N rows. Internal units: mm, rad.

    Attributes
    ----------
    joints : ndarray, shape (N, 6), or None
        Commanded joint angles, rad.
    position : ndarray, shape (N, 3), or None
        Commanded TCP position, mm.
    orientation : ndarray, shape (N, 3), or None
        Commanded TCP orientation A, B, C, rad.
    measured : ndarray, shape (N, 3), or None
        Measured TCP position, mm.
    measured_orientation : ndarray, shape (N, 3), or None
        Measured TCP orientation A, B, C, rad.
    lines : ndarray, shape (N,)
        Line number of each row in its file (for messages).
    path : str
        Where the rows came from.
    """

    joints: np.ndarray = None
    position: np.ndarray = None
    orientation: np.ndarray = None
    measured: np.ndarray = None
    measured_orientation: np.ndarray = None
    lines: np.ndarray = None
    path: str = "<memory>"

    def __len__(self):
        return len(self.lines)

    def subset(self, index):
        """The rows selected by an index array or boolean mask."""
        changes = {
            f.name: getattr(self, f.name)[index]
            for f in dataclasses.fields(self)
            if isinstance(getattr(self, f.name), np.ndarray)
        }
        return dataclasses.replace(self, **changes)

    def require_measured(self):
        """Raise ReadError unless the measured columns mx, my, mz are present."""
        if self.measured is None:
            raise ReadError(f"{self.path}: measured columns mx, my, mz are required")


_TERM = re.compile(r"\s*([+-]?)\s*([^+\-\s][^+\-]*?)\s*(?=[+-]|$)")


def _parse_expression(expression, header, path, field):
    """Column terms ``[(sign, index), ...]`` of a mapping expression like ``x_t+x_dif``."""
    terms = []
    for sign, name in _TERM.findall(expression):
        if name not in header:
            raise ReadError(
                f"{path}: column mapping {field}={expression!r}: no column {name!r} "
                f"(header: {', '.join(header)})"
            )
        terms.append((-1.0 if sign == "-" else 1.0, header.index(name)))
    if not terms:
        raise ReadError(f"{path}: column mapping {field}={expression!r} names no column")
    return terms


def parse_mapping(text):
    """Parse a CLI mapping ``"j1=joint_1,mx=x_t+x_dif"`` into a dict.

    Raises
    ------
    ReadError
        On an entry without ``=`` or an unknown target field.
    """
    mapping = {}
    for entry in filter(None, (e.strip() for e in text.split(","))):
        field, sep, expression = entry.partition("=")
        field = field.strip()
        if not sep or not expression.strip():
            raise ReadError(f"column mapping entry {entry!r}: expected FIELD=COLUMN")
        if field not in FIELDS:
            raise ReadError(f"column mapping entry {entry!r}: unknown field {field!r} (one of {', '.join(FIELDS)})")
        mapping[field] = expression.strip()
    return mapping


def read_measurements(path, mapping=None):
    """Read a measurement CSV.

    Parameters
    ----------
    path : str or Path
    mapping : dict, optional
        ``{field: expression}`` for files in another layout; fields not in
        the mapping are read from columns of their own name when present.

    Returns
    -------
    Measurements

    Raises
    ------
    ReadError
        Naming the file, line and field of a missing, non-numeric or
        non-finite value, an incomplete column group, or an empty file.
    """
    path = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeError) as exc:
        raise ReadError(f"{path}: cannot read: {exc}") from exc
    rows = [
        (number, row)
        for number, row in enumerate(csv.reader(io.StringIO(text)), start=1)
        if row and any(cell.strip() for cell in row) and not row[0].lstrip().startswith("#")
    ]
    if not rows:
        raise ReadError(f"{path}: no header row")
    header_line, header = rows[0]
    header = [cell.strip() for cell in header]
    mapping = dict(mapping or {})
    for field in FIELDS:
        if field not in mapping and field in header:
            mapping[field] = field
    terms = {field: _parse_expression(expr, header, path, field) for field, expr in mapping.items()}
    data = rows[1:]
    if not data:
        raise ReadError(f"{path}: header on line {header_line} but no data rows")
    values = {field: np.empty(len(data)) for field in terms}
    for r, (number, row) in enumerate(data):
        if len(row) != len(header):
            raise ReadError(f"{path}:{number}: expected {len(header)} fields as in the header, got {len(row)}")
        for field, field_terms in terms.items():
            total = 0.0
            for sign, column in field_terms:
                cell = row[column].strip()
                try:
                    number_value = float(cell)
                except ValueError:
                    raise ReadError(f"{path}:{number}: field {header[column]}: not a number: {cell!r}") from None
                if not math.isfinite(number_value):
                    raise ReadError(f"{path}:{number}: field {header[column]}: not a finite number: {cell!r}")
                total += sign * number_value
            values[field][r] = total

    def group(names, scale=1.0, required=False):
        present = [n for n in names if n in values]
        if not present:
            if required:
                raise ReadError(f"{path}: columns {', '.join(names)} are required")
            return None
        if len(present) != len(names):
            missing = [n for n in names if n not in values]
            raise ReadError(f"{path}: line {header_line}: column group {','.join(names)} lacks {', '.join(missing)}")
        return np.column_stack([values[n] for n in names]) * scale

    deg = math.pi / 180.0
    joints = group(JOINTS, deg)
    position = group(POSITION)
    if joints is None and position is None:
        raise ReadError(f"{path}: line {header_line}: need commanded joints j1..j6 or a commanded pose x,y,z")
    return Measurements(
        joints=joints,
        position=position,
        orientation=group(ORIENTATION, deg),
        measured=group(MEASURED),
        measured_orientation=group(MEASURED_ORIENTATION, deg),
        lines=np.array([number for number, _ in data]),
        path=path,
    )


def format_measurements(meas, comments=(), extra=None):
    """CSV text of measurements in the standard layout (user units: mm, deg).

    Parameters
    ----------
    meas : Measurements
    comments : sequence of str
        Lines written first, after ``# ``.
    extra : dict, optional
        Further columns ``{name: ndarray (N,)}``, written last as given.
    """
    columns = []
    for names, array, scale in (
        (JOINTS, meas.joints, 180.0 / math.pi),
        (POSITION, meas.position, 1.0),
        (ORIENTATION, meas.orientation, 180.0 / math.pi),
        (MEASURED, meas.measured, 1.0),
        (MEASURED_ORIENTATION, meas.measured_orientation, 180.0 / math.pi),
    ):
        if array is not None:
            columns.append((names, array * scale))
    for name, values in (extra or {}).items():
        columns.append(((name,), np.asarray(values, dtype=float)[:, None]))
    header = [name for names, _ in columns for name in names]
    table = np.column_stack([array for _, array in columns])
    out = io.StringIO()
    for comment in comments:
        out.write(f"# {comment}\n")
    out.write(",".join(header) + "\n")
    for row in table:
        out.write(",".join(f"{v:.6f}" for v in row) + "\n")
    return out.getvalue()


def write_measurements(path, meas, comments=(), extra=None):
    """Write measurements atomically in the standard layout; see `format_measurements`."""
    write_atomic(path, format_measurements(meas, comments, extra))
