"""The measurement CSV (docs/conventions.md): read with located errors, write atomically.

Columns: ``j1..j6`` commanded joints (deg), ``x,y,z[,a,b,c]`` commanded TCP
pose (mm, deg), ``mx,my,mz`` measured TCP position (mm), optional
``mrx,mry,mrz`` measured orientation (deg), optional ``track`` the track
position of a robot on a track (mm) and ``temperature`` (deg C). Files in another
layout (other column names, delimiter, decimal comma, units, rotation
conventions) are read through an explicit `trajcomp.calibration.layout.Layout`,
never by guessing.
"""

import csv
import dataclasses
import io
import math
import operator
import re

import numpy as np

from trajcomp.support.atomic import write_atomic
from trajcomp.calibration.layout import (
    FIELDS,
    JOINTS,
    MEASURED,
    MEASURED_ORIENTATION,
    MEASURED_QUATERNION,
    ORIENTATION,
    POSITION,
    QUATERNION,
    TRACK,
    TEMPERATURE,
    Layout,
    parse_mapping,
    rotation_to_abc,
)
from trajcomp.errors import ReadError

__all__ = ["Measurements", "parse_mapping", "read_measurements", "format_measurements", "write_measurements"]

MAX_FIELD = 1000  # characters: no number in a measurement file is longer
MAX_ROWS = 1_000_000  # data rows of one measurement file (a tracker run of 5,892 poses is a large one): 57 s, 288 MB
MAX_COLUMNS = 1000  # fields of one row
_BLOCK = 16384  # rows converted to numbers at once


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
        Measured orientation A, B, C, rad (of the measured frame).
    lines : ndarray, shape (N,)
        Line number of each row in its file (for messages).
    path : str
        Where the rows came from.
    frame : str or None
        Frame of the measured columns when the file's layout states it
        (``base`` or ``tracker``).
    track : ndarray, shape (N,), or None
        Track position of each row (a robot on a track), mm.
    temperature : ndarray, shape (N,), or None
        The hall's temperature at each row, deg C (optional column).
    """

    joints: np.ndarray = None
    position: np.ndarray = None
    orientation: np.ndarray = None
    measured: np.ndarray = None
    measured_orientation: np.ndarray = None
    lines: np.ndarray = None
    path: str = "<memory>"
    frame: str = None
    track: np.ndarray = None
    temperature: np.ndarray = None

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


def _rows(path, layout, max_rows=MAX_ROWS, why="split the file"):
    """Non-empty, non-comment rows ``(line, cells)`` of a file as they are read, the decimal mark made '.'.

    Streamed: a damaged file is refused at its first bad row, not once all
    of it is in memory. A field longer than `MAX_FIELD` characters, a row of
    more than `MAX_COLUMNS` fields and more than ``max_rows`` data rows (at the
    first row beyond: nothing more is read) are refused, the message saying
    ``why``.
    """
    try:
        with open(path, encoding="utf-8-sig", newline="") as handle:
            reader = csv.reader(handle, delimiter=layout.delimiter)
            count = 0
            for row in reader:
                number = reader.line_num
                if not row or row[0].lstrip().startswith("#") or not "".join(row).strip():
                    continue
                if max(map(len, row)) > MAX_FIELD:
                    long = next(cell for cell in row if len(cell) > MAX_FIELD)
                    raise ReadError(
                        f"{path}:{number}: a field of {len(long)} characters is too long (at most {MAX_FIELD})"
                    )
                if len(row) > MAX_COLUMNS:
                    raise ReadError(f"{path}:{number}: {len(row)} fields, more than the {MAX_COLUMNS} a row may have")
                count += 1
                if count > max_rows + 1:
                    raise ReadError(f"{path}:{number}: more than {max_rows} data rows; {why}")
                yield number, [cell.replace(",", ".") for cell in row] if layout.decimal == "," else row
    except (OSError, UnicodeError) as exc:
        raise ReadError(f"{path}: cannot read: {exc}") from exc
    except csv.Error as exc:
        raise ReadError(f"{path}:{reader.line_num}: {exc}") from None


def _combined(table, terms):
    """The sum (N,) of a mapping expression's signed columns ``[(sign, index), ...]`` of ``table`` (a view for one
    column unsigned: the fields of a standard file take no memory of their own)."""
    (sign, first), *others = terms
    total = table[:, first] if sign == 1.0 else sign * table[:, first]
    for sign, column in others:
        total = total + sign * table[:, column]
    return total


def _table(path, header, columns, rows):
    """The numbers of ``columns`` (indices into ``header``) of every data row, and the rows' line numbers.

    Rows are converted a block at a time (a few rows first, then up to
    `_BLOCK`): memory holds the numbers and one block of text, and a file
    damaged early is refused after its first rows. A row with another
    field count than the header, a cell that is not a number or not finite,
    are refused naming the first such row's line and field.

    Returns
    -------
    table : ndarray, shape (N, len(columns))
    lines : ndarray of int, shape (N,)
    """
    blocks, lines, cells, numbers = [], [], [], []
    size = 64
    pick = operator.itemgetter(*columns) if len(columns) > 1 else lambda row: [row[c] for c in columns]

    def convert():
        nonlocal size
        if cells:
            blocks.append(_numbers(path, header, columns, cells, numbers))
            lines.append(np.array(numbers))
            cells.clear()
            numbers.clear()
            size = min(2 * size, _BLOCK)

    for number, row in rows:
        if len(row) != len(header):
            convert()  # a bad cell in an earlier row is named first
            raise ReadError(f"{path}:{number}: expected {len(header)} fields as in the header, got {len(row)}")
        cells.append(pick(row))
        numbers.append(number)
        if len(cells) >= size:
            convert()
    convert()
    table = np.concatenate(blocks) if blocks else np.empty((0, len(columns)))
    return table, np.concatenate(lines) if lines else np.empty(0, dtype=int)


def _numbers(path, header, columns, cells, numbers):
    """Float array (n, len(columns)) of a block of text ``cells``; ReadError at the first bad one, by line and field.

    numpy converts a block at once (it reads a number as ``float()`` does); a
    block it refuses, or holding a NaN or infinity, is read again cell by
    cell to name the first bad one.
    """
    try:
        block = np.array(cells, dtype=np.float64)
    except ValueError:
        block = None
    if block is not None and np.isfinite(block).all():
        return block
    checked = []
    for number, row in zip(numbers, cells):
        checked.append([])
        for column, cell in zip(columns, row):
            cell = cell.strip()
            try:
                value = float(cell)
            except ValueError:
                raise ReadError(f"{path}:{number}: field {header[column]}: not a number: {cell!r}") from None
            if not math.isfinite(value):
                raise ReadError(f"{path}:{number}: field {header[column]}: not a finite number: {cell!r}")
            checked[-1].append(value)
    return np.array(checked)


def read_measurements(path, layout=None, max_rows=MAX_ROWS, why="split the file"):
    """Read a measurement file.

    Parameters
    ----------
    path : str or Path
    layout : Layout or dict, optional
        The file's layout (a plain dict is taken as its ``columns``); fields
        not mapped are read from columns of their own name when present.
    max_rows : int
        Data rows read at most; a file of more is refused at the first row
        beyond (the message ends with ``why``: what to do about it).

    Returns
    -------
    Measurements

    Raises
    ------
    ReadError
        Naming the file, line and field of a missing, non-numeric or
        non-finite value, an over-long field, an incomplete column group, a
        bad orientation, or an empty file.
    """
    path = str(path)
    if layout is None or isinstance(layout, dict):
        layout = Layout(columns=dict(layout or {}))
    rows = _rows(path, layout, max_rows, why)
    first = next(rows, None)
    if first is None:
        raise ReadError(f"{path}: no header row")
    header_line, header = first
    header = [cell.strip() for cell in header]
    mapping = dict(layout.columns)
    for field in FIELDS:
        if field not in mapping and field in header:
            mapping[field] = field
    terms = {field: _parse_expression(expr, header, path, field) for field, expr in mapping.items()}
    columns = sorted({column for field_terms in terms.values() for _, column in field_terms})
    table, lines = _table(path, header, columns, rows)
    if not len(lines):
        raise ReadError(f"{path}:{header_line}: a header but no data rows below it")
    at = {column: k for k, column in enumerate(columns)}
    values = {field: _combined(table, [(sign, at[column]) for sign, column in field_terms])
              for field, field_terms in terms.items()}

    def group(names, scale=1.0):
        present = [n for n in names if n in values]
        if not present:
            return None
        if len(present) != len(names):
            missing = [n for n in names if n not in values]
            raise ReadError(f"{path}:{header_line}: column group {','.join(names)} lacks {', '.join(missing)}")
        return np.column_stack([values[n] for n in names]) * scale

    def rotation(name, euler_fields, quaternion_fields):
        convention = layout.convention(name)
        fields = quaternion_fields if convention == "quaternion" else euler_fields
        other = euler_fields if convention == "quaternion" else quaternion_fields
        if any(n in values for n in other):
            raise ReadError(f"{path}: {','.join(other)} need the rotation convention of {name} to be "
                            f"{'an Euler sequence or rotvec' if convention == 'quaternion' else 'quaternion'}")
        raw = group(fields)
        if raw is None:
            return None
        try:
            return rotation_to_abc(raw, convention, layout.scale(name))
        except ValueError as exc:
            bad = re.search(r"row (\d+)", str(exc))
            where = f"{path}:{lines[int(bad.group(1))]}" if bad else path
            raise ReadError(f"{where}: {name}: {exc}") from None

    joints = group(JOINTS, layout.scale("joints"))
    position = group(POSITION, layout.scale("position"))
    if joints is None and position is None:
        raise ReadError(f"{path}:{header_line}: need commanded joints j1..j6 or a commanded pose x,y,z")
    return Measurements(
        joints=joints,
        position=position,
        orientation=rotation("orientation", ORIENTATION, QUATERNION),
        measured=group(MEASURED, layout.scale("measured")),
        measured_orientation=rotation("measured_orientation", MEASURED_ORIENTATION, MEASURED_QUATERNION),
        temperature=values.get("temperature"),
        lines=lines,
        path=path,
        frame=layout.frame,
        track=None if (track := group(TRACK, layout.scale("track"))) is None else track[:, 0],
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
        (TEMPERATURE, None if meas.temperature is None else meas.temperature[:, None], 1.0),
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


def read_validation_run(path):
    """The rows of a validation run (`Measurements`); ReadError without commanded joints or measured positions."""
    meas = read_measurements(path)
    if meas.joints is None or meas.measured is None:
        raise ReadError(f"{meas.path}: measured landings need the commanded joints j1..j6 (as written) and the "
                        "measured positions mx, my, mz")
    return meas
