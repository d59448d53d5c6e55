"""The program CSV reader: the header and target rows into the columns of a `Program`, a block of rows at a time
(see `trajcomp.formats.csv`)."""

import difflib
import itertools
import math

import numpy as np

from trajcomp.formats.csv.cells import (
    BLOCK,
    JOINTS,
    POSE,
    _cells,
    _is_statement,
    _numbers,
    _split,
    _value,
)
from trajcomp.formats.text import ANGLE_LIMIT, JOINT_LIMIT, LENGTH_LIMIT, fail, finite, read_source
from trajcomp.support.parallel import map_blocks
from trajcomp.programs.program import Program
from trajcomp.programs.items import JOINT, LINEAR, Statement
from trajcomp.programs.tables import MotionTable, TargetTable, Rows, repeated
from trajcomp.arm.transforms import pose_to_matrix

LIMITS = dict.fromkeys(POSE[:3], LENGTH_LIMIT) | dict.fromkeys(POSE[3:], ANGLE_LIMIT) | dict.fromkeys(JOINTS, JOINT_LIMIT)
KINDS = {"PTP": JOINT, "LIN": LINEAR}
KNOWN = POSE + JOINTS + ("motion", "speed", "zone", "t")
NOT_NEGATIVE = {"speed": "a TCP speed, mm/s", "zone": "a blending radius, mm"}  # columns no controller reads below 0


def read(path, workers=1):
    """Read a program CSV, its blocks of rows parsed by ``workers`` processes (`trajcomp.support.parallel.map_blocks`).

    Raises ReadError with file:line, field and text.
    """
    source = read_source(path)
    lines, endings = _split(source.text)
    if lines and not lines[-1]:
        lines.pop()
    statement, starts, lengths = _layout(source.text, lines)
    number = int(np.argmin(statement)) + 1 if len(lines) and not statement.all() else None
    if number is None:
        fail(source.name, 1, source.text[:80], "not a program CSV: no header row")
    header = _header([_value(c).lower() for c in _cells(lines[number - 1])], source.name, number, lines[number - 1])
    statement[number - 1] = True
    rows = np.flatnonzero(~statement) + 1
    if not len(rows):
        fail(source.name, len(lines), source.text[-80:], "no target rows after the header")
    statements = [Statement(n, lines[n - 1]) for n in np.flatnonzero(statement) + 1]
    n = len(rows)
    pose, joints, kind, speed, zone = _parse_rows(source.name, header, lines, rows, workers)
    motions = MotionTable(
        kind=kind, target=np.arange(n), via=np.full(n, -1), speed=speed,
        speed_unit=repeated("mm/s", n), zone=np.where(zone == 0.0, np.nan, zone),
        tool=repeated(None, n), frame=repeated(None, n), line=rows,
        axis_position=np.zeros(n, dtype=bool), text=Rows(n, lambda k: text(int(rows[k]))),
    )
    if starts is None:
        lengths = np.fromiter(map(len, lines), dtype=int, count=len(lines))
        ending_lengths = np.fromiter(map(len, endings[: len(lines) - 1]), dtype=int, count=len(lines) - 1)
        starts = np.concatenate([[0], np.cumsum(lengths[:-1] + ending_lengths)])
    del lines

    def text(number):
        start = starts[number - 1]
        return source.text[start : start + lengths[number - 1]].strip()

    return Program.from_tables("csv", source.name.rsplit(".", 1)[0], statements, motions,
                               TargetTable.of_rows(pose, joints, rows), sources=(source,))


_ROW_START = np.zeros(256, dtype=bool)
_ROW_START[0x21:0x7F] = True
_ROW_START[ord("#")] = False  # a line starting with any other printable ASCII character is no statement


def _layout(text, lines):
    """``(statement, starts, lengths)`` of a text's lines (`_split`, the empty last piece left out).

    ``statement`` (L,) marks blank and comment lines (`_is_statement`):
    found from the first byte of each line where the text has ``\n``
    endings only, the doubtful lines (a space, ``#``, a non-ASCII start)
    checked one by one. ``starts`` and ``lengths`` (L,) are the lines'
    offsets in ``text``, or None where the text is not ASCII or has other
    endings.
    """
    if "\r" in text or not lines:
        return np.array([_is_statement(line) for line in lines], dtype=bool), None, None
    data = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)  # a \n byte is a \n character
    ends = np.flatnonzero(data == 10)
    starts = np.concatenate([[0], ends + 1])[: len(lines)]
    first = np.zeros(len(lines), dtype=np.uint8)
    inside = starts < len(data)
    first[inside] = data[starts[inside]]
    statement = ~_ROW_START[first]
    for k in np.flatnonzero(statement).tolist():
        statement[k] = _is_statement(lines[k])
    if len(data) != len(text):
        return statement, None, None
    return statement, starts, np.append(ends, len(data))[: len(lines)] - starts


def _parse_rows(name, header, lines, rows, workers):
    """Columns of the target rows (N,) (line numbers) of ``lines``, a `BLOCK` of rows at a time (`_parse_block`) by
    ``workers`` processes (`trajcomp.support.parallel.map_blocks`): poses (N, 4, 4), joints (N, 6) rad (without joint
    columns one read-only row of NaN for all, not an N x 6 array), kinds, speeds and zones (N,)."""
    n = len(rows)
    pose, joints, kind, speed, zone = (np.empty((n, 4, 4)), np.empty((n, 6)) if "j1" in header else None,
                                       np.empty(n, dtype=object), np.empty(n), np.empty(n))  # filled by blocks
    firsts = range(0, n, BLOCK)

    def parsed(k):
        block = rows[firsts[k] : firsts[k] + BLOCK]
        return _parse_block(name, header, [lines[m - 1] for m in block.tolist()], block)

    for k, columns in zip(firsts, map_blocks(parsed, len(firsts), workers)):
        part = slice(k, k + BLOCK)
        pose[part], kind[part], speed[part], zone[part] = columns[0], *columns[2:]
        if joints is not None:
            joints[part] = columns[1]
    if joints is None:
        joints = np.broadcast_to(np.full(6, np.nan), (n, 6))
    return pose, joints, kind, speed, zone


def _header(names, source_name, number, line):
    """The column names, checked: a whole pose or joint group, no column twice, no near-miss of a known name."""
    groups = [group for group in (POSE, JOINTS) if any(c in names for c in group)]
    if not groups:
        fail(source_name, number, line, "not a program CSV: the header needs x,y,z,a,b,c or j1..j6")
    twice = sorted({c for c in names if names.count(c) > 1})
    if twice:
        fail(source_name, number, line, f"column {', '.join(twice)} given twice")
    for group in groups:
        missing = [c for c in group if c not in names]
        if missing:
            fail(source_name, number, line, f"column {', '.join(missing)} missing: {','.join(group)} go together")
    for name in names:
        close = difflib.get_close_matches(name, KNOWN, n=1, cutoff=0.6) if name not in KNOWN else []
        if close:
            fail(source_name, number, line, f"unknown column {name!r}: did you mean {close[0]!r}?")
    return names


def _parse_block(name, header, lines, numbers):
    """Columns of a block of B target rows: poses (B, 4, 4), joints (B, 6) rad, kinds, speeds, zones (B,).

    Parsed as arrays; a block with any mistake is checked row by row, which
    names the first one (`_check_row`).
    """
    b, width = len(lines), len(header)
    joined = ",".join(lines)
    if '"' not in joined and all(map((width - 1).__eq__, map(str.count, lines, itertools.repeat(",")))):
        flat = joined.split(",")  # one split of the block: every row has its fields
        columns = {c: flat[j::width] for j, c in enumerate(header)}
        del flat
    else:
        cells = [_cells(line) for line in lines]
        if any(len(row) != width for row in cells):
            _check_rows(name, header, lines, numbers)
        columns = dict(zip(header, zip(*cells)))
        del cells
    del joined
    values, empty = {}, {}
    for column in [c for c in header if c in LIMITS or c in ("speed", "zone")]:
        number, empty[column] = _numbers(columns[column])
        if number is None or np.any(~empty[column] & ~(np.abs(number) <= LIMITS.get(column, np.inf))) \
                or column in NOT_NEGATIVE and np.any(number < 0):
            _check_rows(name, header, lines, numbers)
        values[column] = number
    none = np.zeros(b, dtype=bool)
    pose_given = ~np.all([empty[c] for c in POSE], axis=0) if "x" in header else none
    joints_given = ~np.all([empty[c] for c in JOINTS], axis=0) if "j1" in header else none
    partial = pose_given & (np.any([empty[c] for c in POSE], axis=0) if "x" in header else none)
    partial |= joints_given & (np.any([empty[c] for c in JOINTS], axis=0) if "j1" in header else none)
    kinds = {cell: _value(cell).upper() for cell in set(columns.get("motion", ()))}  # the few distinct cells
    if partial.any() or not np.all(pose_given | joints_given) or not set(kinds.values()) <= {"", *KINDS}:
        _check_rows(name, header, lines, numbers)
    pose = np.full((b, 4, 4), np.nan)
    if pose_given.any():
        vectors = np.stack([values[c][pose_given] for c in POSE], axis=1)
        vectors[:, 3:] = np.radians(vectors[:, 3:])
        pose[pose_given] = pose_to_matrix(vectors)
    joints = np.full((b, 6), np.nan)
    if joints_given.any():
        joints[joints_given] = np.radians(np.stack([values[c][joints_given] for c in JOINTS], axis=1))
    ptp = {cell for cell, kind in kinds.items() if kind == "PTP"}
    is_ptp = np.fromiter((cell in ptp for cell in columns["motion"]), bool, b) if ptp else np.zeros(b, dtype=bool)
    kind = np.array([LINEAR, JOINT], dtype=object)[is_ptp.astype(np.intp)]  # shared str objects
    return pose, joints, kind, values.get("speed", np.full(b, np.nan)), values.get("zone", np.full(b, np.nan))


def _check_rows(name, header, lines, numbers):
    """ReadError naming the first mistake of a block (file:line, field, text), checking row by row."""
    for line, number in zip(lines, numbers):
        _check_row(name, header, line, int(number))
    raise AssertionError(f"{name}: a block of rows flagged as faulty has no faulty row")


def _check_row(name, header, line, number):
    cells = [_value(c) for c in _cells(line)]
    if len(cells) != len(header):
        fail(name, number, line, f"expected {len(header)} fields, got {len(cells)}")
    row = dict(zip(header, cells))
    groups = [group for group in (POSE, JOINTS) if group[0] in row and any(row[c] for c in group)]
    if not groups:
        fail(name, number, line, "a row needs x,y,z,a,b,c or j1..j6")
    for column in [c for group in groups for c in group] + [c for c in ("speed", "zone") if row.get(c)]:
        value = finite(row[column], name, number, line, f"field {column}", LIMITS.get(column, math.inf))
        if column in NOT_NEGATIVE and value < 0:
            fail(name, number, line, f"field {column}: {row[column][:40]!r} is negative ({NOT_NEGATIVE[column]})")
    kind = row.get("motion", "").upper()
    if kind and kind not in KINDS:
        fail(name, number, line, f"field motion: expected PTP or LIN, got {kind!r}")
