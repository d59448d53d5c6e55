"""Program CSV (conventions.md): one target per row, TCP poses in the robot base frame.

Columns ``x,y,z,a,b,c`` (mm, deg; A, B, C intrinsic Z-Y'-X''), optional
``motion`` (PTP | LIN), ``speed`` (mm/s), ``zone`` (mm), ``j1..j6`` (deg)
and ``t`` (s, written by re-timing). A row with empty pose fields and
joints is a joint target. ``#`` lines are comments. Any other column (an
id, a comment) is kept as it is, except a name close to a known one (``xx``,
``speeed``: a typo would silently drop data) and a column given twice.
A pose or joint group given in part, and a file without target rows, are
refused too.

CSV programs are CAM paths of up to millions of rows, so they are read and
written as columns, a block of rows at a time (`Program.from_tables`): no
object per row. Writing a program read from CSV keeps every column, row and
byte; the edited rows get their new pose and, where the program knows their
joints, ``j1..j6`` (added as columns when the file has none); `with_times`
sets the ``t`` column.
"""

import contextlib
import difflib
import gc
import itertools
import math
import re

import numpy as np

from trajcomp.formats._text import (
    ANGLE_LIMIT,
    JOINT_LIMIT,
    LENGTH_LIMIT,
    active_axes,
    decimals,
    encode_text,
    fail,
    finite,
    format_number,
    near_angle,
    read_source,
)
from trajcomp.parallel import map_blocks
from trajcomp.program import JOINT, LINEAR, MotionTable, Program, Source, Statement, TargetTable, repeated
from trajcomp.transforms import abc_to_matrix, matrix_to_abc, matrix_to_pose, pose_to_matrix

POSE = ("x", "y", "z", "a", "b", "c")
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
MIN_PLACES = dict.fromkeys(POSE[:3], 3) | dict.fromkeys(POSE[3:], 4) | dict.fromkeys(JOINTS, 4)
LIMITS = dict.fromkeys(POSE[:3], LENGTH_LIMIT) | dict.fromkeys(POSE[3:], ANGLE_LIMIT) | dict.fromkeys(JOINTS, JOINT_LIMIT)
KINDS = {"PTP": JOINT, "LIN": LINEAR}
KNOWN = POSE + JOINTS + ("motion", "speed", "zone", "t")
BLOCK = 16_384  # rows parsed or formatted together: vectorized, with bounded temporary memory
_BARE_ZERO = re.compile(r"^(-?)0\.")  # the 0 of 0.5 and -0.5, for a file that writes .5
_QUOTED_COMMA = re.compile(r',(?=(?:[^"]*"[^"]*")*[^"]*$)')  # a comma outside double quotes


def _split(text):
    """The lines of a text and the line endings after them: ``text == "".join(interleaved)``.

    Returns
    -------
    lines : list of str
        Without line endings; the empty piece after a final line ending included.
    endings : list of str
        ``\n``, ``\r\n`` or ``\r`` after each line but the last.
    """
    if "\r" not in text:
        lines = text.split("\n")
        return lines, ["\n"] * (len(lines) - 1)
    parts = re.split(r"(\r\n|\r|\n)", text)
    return parts[0::2], parts[1::2]


def _cells(line):
    """The raw cells of a CSV line: ``",".join(cells) == line``; commas inside quotes kept."""
    return _QUOTED_COMMA.split(line) if '"' in line else line.split(",")


def _value(cell):
    """A cell's value: stripped, quotes removed."""
    value = cell.strip()
    if len(value) > 1 and value[0] == value[-1] == '"':
        return value[1:-1].replace('""', '"')
    return value


def _is_statement(line):
    stripped = line.lstrip()
    return not stripped or stripped[0] == "#"


def read(path, workers=1):
    """Read a program CSV, its blocks of rows parsed by ``workers`` processes (`trajcomp.parallel.map_blocks`).

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
        axis_position=np.zeros(n, dtype=bool),
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
                               TargetTable.of_rows(pose, joints, rows), text, sources=(source,))


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
    ``workers`` processes (`trajcomp.parallel.map_blocks`): poses (N, 4, 4), joints (N, 6) rad (without joint
    columns one read-only row of NaN for all, not an N x 6 array), kinds, speeds and zones (N,)."""
    n = len(rows)
    pose, joints, kind, speed, zone = (np.empty((n, 4, 4)), np.empty((n, 6)) if "j1" in header else None,
                                       np.empty(n, dtype=object), np.empty(n), np.empty(n))  # filled by blocks
    firsts = range(0, n, BLOCK)

    def parsed(k):
        block = rows[firsts[k] : firsts[k] + BLOCK]
        return _parse_block(name, header, [lines[m - 1] for m in block.tolist()], block)

    with _collection_paused():
        for k, columns in zip(firsts, map_blocks(parsed, len(firsts), workers)):
            part = slice(k, k + BLOCK)
            pose[part], kind[part], speed[part], zone[part] = columns[0], *columns[2:]
            if joints is not None:
                joints[part] = columns[1]
    if joints is None:
        joints = np.broadcast_to(np.full(6, np.nan), (n, 6))
    return pose, joints, kind, speed, zone


@contextlib.contextmanager
def _collection_paused():
    """Cyclic garbage collection paused while rows are split into millions of short-lived lists and tuples
    (they hold no cycles, yet their count triggers full collections: a third of the time of reading)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


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
        if number is None or np.any(~empty[column] & ~(np.abs(number) <= LIMITS.get(column, np.inf))):
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


def _numbers(cells):
    """Values (B,) of a column's cells (B,) (NaN where empty) and which are empty; values None if a cell is no number.

    Canonical numbers (`_canonical`, the common case) are read from their
    digits at once; a column of few distinct cells (speeds, zones) converts
    each distinct one; other plain numbers are converted from the Python
    str at once; cells with quotes or empty ones go through a str array.
    """
    found = _canonical(cells) if len(cells) else None
    if found is not None and found[1] is not None:
        return found[1], np.zeros(len(cells), dtype=bool)
    distinct = set(cells) if len(cells) >= 64 else None
    try:
        if distinct is not None and len(distinct) <= len(cells) // 8:
            distinct = list(distinct)
            lookup = dict(zip(distinct, np.array(distinct, dtype=float).tolist()))
            return np.fromiter(map(lookup.__getitem__, cells), dtype=float, count=len(cells)), \
                np.zeros(len(cells), dtype=bool)
        return np.array(cells, dtype=float), np.zeros(len(cells), dtype=bool)
    except ValueError:
        pass
    text = _stripped(cells)
    empty = text == ""
    number = np.full(len(cells), np.nan)
    try:
        number[~empty] = text[~empty].astype(float)
    except ValueError:
        return None, empty
    return number, empty


def _stripped(cells):
    """The values (B,) of cells (B,) as a str array: spaces and surrounding quotes removed."""
    text = np.array(cells, dtype=str)
    if _plain(cells):
        return text
    text = np.strings.strip(text)
    return np.where(np.strings.startswith(text, '"'), np.strings.strip(np.strings.strip(text, '"')), text)


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
        finite(row[column], name, number, line, f"field {column}", LIMITS.get(column, math.inf))
    kind = row.get("motion", "").upper()
    if kind and kind not in KINDS:
        fail(name, number, line, f"field motion: expected PTP or LIN, got {kind!r}")


def write(program, path, workers=1):
    """The CSV text of a program: patched in place if read from CSV, else generated.

    A program read from CSV gives its content as a generator of encoded
    pieces, a block of lines each, made while `trajcomp.atomic` writes them
    (by ``workers`` processes, `trajcomp.parallel.map_blocks`): the whole
    output is never held in memory.
    """
    if program.format == "csv" and program.sources:
        return {path: _patched_pieces(program, program.sources[0], workers)}
    return {path: _emit(program).encode("utf-8")}


def _patched_pieces(program, source, workers=1):
    """The encoded pieces of ``source``'s text with the edited targets' numbers rewritten (`_patched_block`), and
    j1..j6 appended when the file has no such columns; `BLOCK` lines a piece."""
    targets = program.target_table()
    order = np.argsort(targets.line, kind="stable")
    numbers = targets.line[order]
    text = source.text
    spans = list(_line_spans(text, BLOCK))
    header_block, header_at, header = _header_in(text, spans)
    add_joints = header is not None and "j1" not in header and bool(
        np.isfinite(targets.joints[targets.edited]).all(axis=1).any())
    times = None
    if program.times is not None:  # by target (each CSV row is a motion and its target)
        times = np.full(len(targets), np.nan)
        motions = program.motion_table()
        times[motions.target[motions.target >= 0]] = program.times[motions.target >= 0]
    suffix = ("" if times is None or "t" in header else ",t") + ("," + ",".join(JOINTS) if add_joints else "")
    rest = Source(source.name, "", "utf-8") if source.encoding == "utf-8-sig" else source  # BOM: first piece only

    def piece(k):
        first, start, end = spans[k]
        chunk = text[start:end]
        a, b = np.searchsorted(numbers, [first, first + _count_lines(chunk) - chunk.endswith("\n")])
        rows = order[a:b]
        patched = _patched_block(chunk, header_at if k == header_block else -1, header if k >= header_block else None,
                                 numbers[a:b] - first, targets.pose[rows], targets.is_joint[rows],
                                 targets.joints[rows], targets.edited[rows], add_joints, suffix,
                                 None if times is None else time_texts(times[rows]))
        return encode_text(source if k == 0 else rest, patched)

    with _collection_paused():
        yield from map_blocks(piece, len(spans), workers)


def _header_in(text, spans):
    """``(block, at, names)``: the span (of `_line_spans`) holding the header, its line's index there and the
    column names; ``(len(spans), -1, None)`` when every line is blank or a comment."""
    for k, (_, start, end) in enumerate(spans):
        lines = _split(text[start:end])[0]
        at = next((i for i, line in enumerate(lines) if not _is_statement(line)), -1)
        if at >= 0:
            return k, at, [_value(c).lower() for c in _cells(lines[at])]
    return len(spans), -1, None


def _line_spans(text, size):
    """``(first, start, end)`` of ``text`` in chunks of about ``size`` lines (by the mean line length), each cut
    after a ``\n``: the number (1-based) of the chunk's first line and its place ``text[start:end]``, line endings
    included (a ``\r\n`` is never cut; a file of bare ``\r`` endings is one chunk)."""
    width = max(1, size * len(text) // (text.count("\n") + 1))  # characters of about ``size`` lines
    first, start = 1, 0
    while True:
        end = text.find("\n", start + width - 1) + 1
        if not end or end == len(text):
            yield first, start, len(text)
            return
        yield first, start, end
        first += _count_lines(text[start:end]) - 1  # its last piece, empty, is the next chunk's first line
        start = end


def _count_lines(chunk):
    """Number of `_split` pieces of a chunk, the last (possibly empty) one included."""
    if "\r" not in chunk:
        return chunk.count("\n") + 1
    return len(_split(chunk)[0])


def _patched_block(chunk, header_at, header, at, pose, is_joint, joints, edited, add_joints, suffix="", times=None):
    """The text of a block of lines with its target rows patched: a pure function of plain values.

    Parameters
    ----------
    chunk : str
        Lines with their line endings (`_line_spans`).
    header_at : int
        Index of the header among the chunk's lines, -1 if elsewhere.
    header : list of str or None
        Column names (None: no header yet, so no target rows).
    at : ndarray of int, shape (R,)
        Indices of the target rows among the chunk's lines.
    pose, is_joint, joints, edited : ndarray, shape (R, 4, 4), (R,), (R, 6), (R,)
        The targets of those rows (`TargetTable`).
    add_joints : bool
        Append j1..j6 (every target row).
    suffix : str
        Appended to the header line: the names of the columns added.
    times : list of str, length R, optional
        The rows' ``t`` cells (`_patched_rows`).
    """
    if not len(at) or not (add_joints or edited.any() or times is not None):
        if header_at < 0 or not suffix:
            return chunk
        at = at[:0]
    count = len(at)
    if count and "\r" not in chunk and at[-1] - at[0] == count - 1:  # the rows: a run of lines, as usual
        start = 0
        for _ in range(int(at[0])):
            start = chunk.find("\n", start) + 1
        body = chunk[start:]
        ending = "\n" if body.endswith("\n") else ""
        body = body[: len(body) - len(ending)]
        if body.count("\n") == count - 1:  # and they end the chunk
            head = chunk[:start]
            if header_at >= 0 and suffix:
                head = head.split("\n")
                head[header_at] += suffix
                head = "\n".join(head)
            return head + _patched_rows(body, count, header, pose, is_joint, joints, edited, add_joints,
                                        times) + ending
    lines, endings = _split(chunk)
    if header_at >= 0:
        lines[header_at] += suffix
    if count:
        at = at.tolist()
        rows = _patched_rows("\n".join([lines[k] for k in at]), count, header, pose, is_joint, joints, edited,
                             add_joints, times).split("\n")
        for k, line in zip(at, rows):
            lines[k] = line
    return _joined(lines, endings)


def _patched_rows(rows, n, header, pose, is_joint, joints, edited, add_joints, times=None):
    """Target rows with the edited ones' numbers rewritten, their ``t`` cells set to ``times`` (appended as the last
    cell when the header has no ``t``) and j1..j6 appended if asked: ``rows`` is the text of ``n`` rows joined by
    ``\n``, as is the result.

    Each number column is either formatted at once (`_column`) or given as
    cells; the rows are joined by one %-operation.
    """
    width = len(header)
    flat = rows.replace("\n", ",").split(",") if '"' not in rows else None
    if flat is None or len(flat) != n * width:
        columns = [list(c) for c in zip(*map(_cells, rows.split("\n")))]
    else:
        columns = [flat[j::width] for j in range(width)]
    del flat, rows
    specs = ["%s"] * width
    updates = {}
    if "x" in header:
        updates |= _pose_columns(columns, header, pose, np.flatnonzero(edited & ~is_joint))
    if "j1" in header:
        given = np.flatnonzero(edited & np.isfinite(joints).all(axis=1))
        for c, values in zip(JOINTS, np.degrees(joints[given]).T):
            updates[c] = _column(columns[header.index(c)], given, values, MIN_PLACES[c])
    for c, (spec, column) in updates.items():
        specs[header.index(c)], columns[header.index(c)] = spec, column
    if times is not None and "t" in header:  # keeping each cell's quotes and spaces
        j = header.index("t")
        columns[j] = _in_cells(columns[j], _stripped(columns[j]), np.ones(n, dtype=bool), times)
    elif times is not None:
        specs.append("%s")
        columns.append(times)
    if add_joints:
        known = np.isfinite(joints).all(axis=1)
        if known.all():
            degrees = np.degrees(joints)
            specs += ["%.4f"] * 6
            columns += [_no_negative_zero(d, 4).tolist() for d in degrees.T]
        else:
            specs.append("%s")
            columns.append(_degrees_cells(joints))
    flat = [None] * (n * len(columns))
    for j, column in enumerate(columns):
        flat[j :: len(columns)] = column
    del columns
    return "\n".join([",".join(specs)] * n) % tuple(flat)


def _pose_columns(columns, header, pose, rows):
    """``{column: (spec, items)}`` (`_column`) of x..c: raw cells of each column (B,), poses (B, 4, 4), the edited
    Cartesian rows (R,)."""
    out = {c: _column(columns[header.index(c)], rows, values, MIN_PLACES[c])
           for c, values in zip(POSE[:3], pose[rows, :3, 3].T)}
    if not len(rows):
        return out
    abc = [columns[header.index(c)] for c in POSE[3:]]
    canonical = [_canonical(column) for column in abc]
    picked = rows.tolist() if len(rows) < len(abc[0]) else None
    old_abc = np.stack([
        found[1][rows] if found is not None and found[1] is not None else
        _numbers(column if picked is None else [column[k] for k in picked])[0]
        for column, found in zip(abc, canonical)], axis=1)
    rotation = pose[rows, :3, :3]
    turned = np.abs(rotation - abc_to_matrix(np.radians(old_abc))).max(axis=(1, 2), initial=0.0) > 1e-12
    angles = near_angle(np.degrees(matrix_to_abc(rotation[turned])), old_abc[turned])
    for c, values, column, found in zip(POSE[3:], angles.T, abc, canonical):
        out[c] = _column(column, rows[turned], values, MIN_PLACES[c], found)
    return out


_UNKNOWN = object()


def _column(cells, rows, values, min_places, canonical=_UNKNOWN):
    """How a column writes new ``values`` (R,) in its ``rows`` (R,): ``(spec, items)`` for the row %-operation.

    ``cells`` (B,) are the column's raw cells (``canonical``: their
    `_canonical`, if known). A column of canonical numbers, all rows given,
    is written as floats with its spec ``%.<d>f``: a number that reads back
    equal to its old cell is then that very text. Any other column goes the
    exact way (`_written`, `_in_cells`) and gives its cells with ``%s``.
    """
    if len(rows) == len(cells) and len(cells):
        found = _canonical(cells, values=False) if canonical is _UNKNOWN else canonical
        if found is not None and found[0] >= min_places and np.abs(values).max() < 1e14 / 10.0 ** found[0]:
            return f"%.{found[0]}f", _no_negative_zero(values, found[0]).tolist()
    if not len(rows):
        return "%s", cells
    rows = rows.tolist()
    picked = [cells[k] for k in rows]
    old = _stripped(picked)
    changed, texts = _written(values, old, min_places)
    out = list(cells)
    for k, cell in zip(rows, _in_cells(picked, old, changed, texts)):
        out[k] = cell
    return "%s", out


_ASCII_NUMBER = np.zeros(256, dtype=bool)
_ASCII_NUMBER[np.frombuffer(b"0123456789-.,", dtype=np.uint8)] = True


def _canonical(cells, values=True):
    """``(d, values)`` if every cell (str, B > 0) is a number as ``%.<d>f`` writes it, with the same ``d``, else None.

    Canonical: an optional ``-``, an integer part without leading zeros, a
    point and ``d`` digits; no sign ``+``, exponent, space, quote or
    negative zero. Two such texts of at most 15 digits are equal exactly
    when they read as the same float. ``values`` (B,) are the floats the
    cells state (exactly ``float(cell)``: an integer of at most 15 digits
    divided by ``10**d``, both exact, the division correctly rounded), or
    None for a cell of more digits (or when not asked for).
    """
    first = cells[0]
    dot = first.find(".")
    if dot < 0:
        return None
    places = len(first) - dot - 1
    joined = ",".join(cells) + ","
    try:
        data = np.frombuffer(joined.encode("ascii"), dtype=np.uint8)
    except UnicodeEncodeError:
        return None
    if not _ASCII_NUMBER[data].all():
        return None
    ends = np.flatnonzero(data == 44)
    dots = np.flatnonzero(data == 46)
    if len(ends) != len(cells) or len(dots) != len(cells) or np.any(ends - dots != places + 1):
        return None
    starts = np.concatenate([[0], ends[:-1] + 1])
    negative = data[starts] == 45
    digits = starts + negative  # where the integer part begins
    if np.count_nonzero(data == 45) != np.count_nonzero(negative) or np.any(dots <= digits):
        return None  # a - inside a number, or no integer digit (.5, -.5, -)
    if np.any((data[digits] == 48) & (dots != digits + 1)):
        return None  # a leading zero
    if negative.any() and "-0." + "0" * places + "," in joined:  # a - only starts a cell
        return None  # -0.000
    width = int((ends - digits).max())  # digits and the point
    if width - 1 > 15 or not values:
        return places, None
    at = ends[:, None] - width + np.arange(width)  # each cell right-aligned: the point in one column
    digit = np.where(at >= digits[:, None], data[np.maximum(at, 0)].astype(np.int64) - 48, 0)
    mantissa = np.delete(digit, width - 1 - places, axis=1) @ 10 ** np.arange(width - 2, -1, -1, dtype=np.int64)
    return places, np.where(negative, -mantissa, mantissa) / 10.0**places


def _no_negative_zero(values, places):
    """``values`` with those that round to 0 at ``places`` decimals set to +0.0 (never ``-0.000``)."""
    return np.where(np.round(values, places) == 0.0, 0.0, values)


def _in_cells(cells, values, changed, texts):
    """Cells (B,) (str) with the changed values replaced by ``texts``, keeping the spaces or quotes around them."""
    texts = texts.tolist() if isinstance(texts, np.ndarray) else texts
    if changed.all() and _plain(cells):
        return texts
    return [cell.replace(value, text, 1) if change and cell != value else (text if change else cell)
            for cell, value, change, text in zip(cells, values.tolist(), changed.tolist(), texts)]


def _plain(texts):
    """Whether no text (sequence of str) holds a quote, space or tab: cells then are their values."""
    joined = "".join(texts)
    return not ('"' in joined or " " in joined or "\t" in joined)


def _written(values, old, min_places):
    """How a file that wrote ``old`` (B,) writes ``values`` (B,): ``(changed (B,), texts (B,))``.

    The decimals of the old text (at least ``min_places``), ``.5`` kept
    bare where the file writes it so; ``changed`` is False where the number
    reads back equal to the old one (its text is then kept).
    """
    texts = _numbers_text(values, _decimals(old), min_places)
    before = np.full(len(old), np.nan)
    given = old != ""
    before[given] = np.array(old[given].tolist(), dtype=float)  # from Python str: 4x faster than a str array's astype
    changed = np.array(texts, dtype=float) != before
    bare = np.strings.startswith(old, ".") | np.strings.startswith(old, "-.") | np.strings.startswith(old, "+.")
    if (bare & changed).any():  # only a leading 0 goes: 10.5 stays 10.5 (an unanchored replace wrote 1.5)
        texts = list(texts)
        for k in np.flatnonzero(bare & changed).tolist():
            texts[k] = _BARE_ZERO.sub(r"\1.", texts[k], count=1)
    return changed, texts


def _decimals(texts):
    """Digits after the decimal point of number texts (B,) (`decimals`), ndarray of int."""
    texts = np.asarray(texts, dtype=str)
    dot = np.strings.find(texts, ".")
    places = np.where(dot >= 0, np.strings.str_len(texts) - dot - 1, 0)
    exponent = (np.strings.find(texts, "e") >= 0) | (np.strings.find(texts, "E") >= 0)
    places[exponent] = [decimals(t) for t in texts[exponent]]
    return places


def _numbers_text(values, places, min_places):
    """Texts (list of str) of values (B,) with ``max(places, min_places)`` decimals each, never ``-0``."""
    places = np.maximum(places, min_places)
    texts = np.empty(len(values), dtype=object)
    for p in np.unique(places):
        pick = places == p
        chosen = values[pick]
        texts[pick] = _formatted(np.where(np.round(chosen, p) == 0.0, 0.0, chosen), f"%.{p}f")
    return texts.tolist()


def _formatted(values, spec):
    """Texts (list of str) of values (N, ...) formatted row by row with ``spec`` (a %-format of one row).

    One %-operation over all rows: about twice as fast as formatting each number.
    """
    values = np.asarray(values, dtype=float).reshape(len(values), -1)
    if not len(values):
        return []
    return ("\n".join([spec] * len(values)) % tuple(values.ravel().tolist())).split("\n")


def _degrees_cells(joints):
    """The appended j1..j6 cells of each target (N,): joints (N, 6) rad as deg, 4 decimals; empty where none."""
    known = np.isfinite(joints).all(axis=1)
    degrees = np.degrees(joints)
    degrees = np.where((np.round(degrees, 4) == 0.0) | ~known[:, None], 0.0, degrees)
    cells = _formatted(degrees, ",".join(["%.4f"] * 6))
    return cells if known.all() else np.where(known, cells, ",,,,,").tolist()


def with_times(program, times):
    """The program with its ``t`` column (s, to the ns) to be set by the writer, added after the last column when the
    file has none (before the joints the writer appends).

    Parameters
    ----------
    program : Program
        Read from a CSV file.
    times : ndarray, shape (M,)
        Time stamp of each motion (row), s, in motion order.

    Returns
    -------
    Program
        With `Program.times`: the cells are made a block at a time as the
        program is written, never as a second copy of its text.
    """
    return program.replace(times=np.asarray(times, dtype=float))


def time_texts(times):
    """The ``t`` cells (list of str) of time stamps (N,), s, as the writer writes them: to the ns."""
    return _numbers_text(np.asarray(times, dtype=float), np.zeros(len(times), dtype=int), 9)


def _joined(lines, endings):
    """The text of `_split`'s lines and endings."""
    if endings.count("\n") == len(endings):
        return "\n".join(lines)
    return "".join(map(str.__add__, lines[:-1], endings)) + lines[-1]


def _emit(program):
    """A new program CSV; poses must already be in the base frame (see postprocess.convert)."""
    active_axes(program, 0, "program CSV")
    targets = program.targets
    used = [i for m in program.motions if m.target is not None for i in (m.via, m.target) if i is not None]
    with_joints = all(targets[i].joints is not None for i in used)
    columns = list(POSE) + ["motion", "speed", "zone"] + (list(JOINTS) if with_joints else [])
    rows = [",".join(columns)]
    for motion in program.motions:
        if motion.target is None:
            rows.append(f"# not converted: {motion.text}")
            continue
        if motion.via is not None:
            rows.append(_row_text(targets[motion.via], motion, LINEAR, with_joints))
        rows.append(_row_text(targets[motion.target], motion, motion.kind, with_joints))
    return "\n".join(rows) + "\n"


def _row_text(target, motion, kind, with_joints):
    if target.pose is None:
        cells = [""] * 6
    else:
        pose = matrix_to_pose(target.pose)
        cells = [format_number(v, 6) for v in pose[:3]] + [format_number(v, 9) for v in np.degrees(pose[3:])]
    speed = format_number(motion.speed, 3) if motion.speed is not None and motion.speed_unit == "mm/s" else ""
    zone = format_number(motion.zone, 3) if motion.zone is not None else ""
    cells += ["PTP" if kind == JOINT else "LIN", speed, zone]
    if with_joints:
        cells += [format_number(v, 9) for v in np.degrees(target.joints)]
    return ",".join(cells)
