"""The program CSV writer: a program read from CSV patched in place, a block of lines at a time, its edited rows
rewritten in the file's own number format; any other program written as a new CSV (see
`trajcomp.formats.csv`)."""

import numpy as np

from trajcomp.formats.csv.cells import (
    BLOCK,
    JOINTS,
    POSE,
    _canonical,
    _cells,
    _is_statement,
    _numbers,
    _plain,
    _split,
    _stripped,
    _value,
)
from trajcomp.formats.fixed_text import joined_rows
from trajcomp.formats.file_writing import active_axes, written_speed
from trajcomp.formats.number_writing import BARE_ZERO, column_decimals, floor_places, format_number
from trajcomp.formats.pose_encoding import turned_abc
from trajcomp.formats.text_edits import encode_text
from trajcomp.support.parallel import map_blocks
from trajcomp.programs.items import JOINT, LINEAR, Source
from trajcomp.arm.transforms import matrix_to_pose

MIN_PLACES = dict.fromkeys(POSE[:3], 3) | dict.fromkeys(POSE[3:], 4) | dict.fromkeys(JOINTS, 4)


def write(program, path, workers=1):
    """The CSV text of a program: patched in place if read from CSV, else generated.

    A program read from CSV gives its content as a generator of encoded
    pieces, a block of lines each, made while `trajcomp.support.atomic` writes them
    (by ``workers`` processes, `trajcomp.support.parallel.map_blocks`): the whole
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
    cells; the rows are laid out together (`joined_rows`).
    """
    width = len(header)
    flat = rows.replace("\n", ",").split(",") if '"' not in rows else None
    if flat is None or len(flat) != n * width:
        columns = [list(c) for c in zip(*map(_cells, rows.split("\n")))]
    else:
        columns = [flat[j::width] for j in range(width)]
    del flat, rows
    updates = {}
    if "x" in header:
        updates |= _pose_columns(columns, header, pose, np.flatnonzero(edited & ~is_joint))
    if "j1" in header:
        given = np.flatnonzero(edited & np.isfinite(joints).all(axis=1))
        for c, values in zip(JOINTS, np.degrees(joints[given]).T):
            updates[c] = _column(columns[header.index(c)], given, values, MIN_PLACES[c])
    for c, column in updates.items():
        columns[header.index(c)] = column
    if times is not None and "t" in header:  # keeping each cell's quotes and spaces
        j = header.index("t")
        columns[j] = _in_cells(columns[j], _stripped(columns[j]), np.ones(n, dtype=bool), times)
    elif times is not None:
        columns.append(times)
    if add_joints:
        known = np.isfinite(joints).all(axis=1)
        if known.all():
            columns += [(_no_negative_zero(d, 4), 4) for d in np.degrees(joints).T]
        else:
            columns.append(_degrees_cells(joints))
    return joined_rows(columns)


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
    turned, angles = turned_abc(pose[rows, :3, :3], old_abc)
    for c, values, column, found in zip(POSE[3:], angles.T, abc, canonical):
        out[c] = _column(column, rows[turned], values, MIN_PLACES[c], found)
    return out


_UNKNOWN = object()


def _column(cells, rows, values, min_places, canonical=_UNKNOWN):
    """How a column writes new ``values`` (R,) in its ``rows`` (R,): a column of `joined_rows`.

    ``cells`` (B,) are the column's raw cells (``canonical``: their
    `_canonical`, if known). A column of canonical numbers, all rows given,
    is written as ``(values, d)``, floats formatted as ``%.<d>f``: a number
    that reads back equal to its old cell is then that very text. Any other
    column goes the exact way (`_written`, `_in_cells`) and gives its cells.
    """
    if len(rows) == len(cells) and len(cells):
        found = _canonical(cells, values=False) if canonical is _UNKNOWN else canonical
        if found is not None and found[0] >= min_places and np.abs(values).max() < 1e14 / 10.0 ** found[0]:
            return _no_negative_zero(values, found[0]), found[0]
    if not len(rows):
        return cells
    rows = rows.tolist()
    picked = [cells[k] for k in rows]
    old = _stripped(picked)
    changed, texts = _written(values, old, min_places)
    out = list(cells)
    for k, cell in zip(rows, _in_cells(picked, old, changed, texts)):
        out[k] = cell
    return out


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


def _written(values, old, min_places):
    """How a file that wrote ``old`` (B,) writes ``values`` (B,): ``(changed (B,), texts (B,))``.

    The decimals of the old text (at least ``min_places``), ``.5`` kept
    bare where the file writes it so; ``changed`` is False where the number
    reads back equal to the old one (its text is then kept).
    """
    texts = _numbers_text(values, column_decimals(old), min_places)
    before = np.full(len(old), np.nan)
    given = old != ""
    before[given] = np.array(old[given].tolist(), dtype=float)  # from Python str: 4x faster than a str array's astype
    changed = np.array(texts, dtype=float) != before
    bare = np.strings.startswith(old, ".") | np.strings.startswith(old, "-.") | np.strings.startswith(old, "+.")
    if (bare & changed).any():  # only a leading 0 goes: 10.5 stays 10.5 (an unanchored replace wrote 1.5)
        texts = list(texts)
        for k in np.flatnonzero(bare & changed).tolist():
            texts[k] = BARE_ZERO.sub(r"\1.", texts[k], count=1)
    return changed, texts


def _numbers_text(values, places, min_places):
    """Texts (list of str) of values (B,) with ``max(places, min_places)`` decimals each (at most 20), never ``-0``.

    A float holds 17 significant digits: the decimals a cell wrote beyond 20
    (a 400-digit fraction) carry nothing, and rounding to them overflows.
    """
    places = np.minimum(np.maximum(places, min_places), 20)
    texts = np.empty(len(values), dtype=object)
    for p in np.unique(places):
        pick = places == p
        chosen = values[pick]
        texts[pick] = _formatted(np.where(np.round(chosen, p) == 0.0, 0.0, chosen)[:, None], p)
    return texts.tolist()


def _formatted(values, places):
    """Texts (list of str) of the rows of values (N, K), each number as ``%.<places>f``, joined by ``,``."""
    if not len(values):
        return []
    return joined_rows([(column, places) for column in np.asarray(values, dtype=float).T]).split("\n")


def _degrees_cells(joints):
    """The appended j1..j6 cells of each target (N,): joints (N, 6) rad as deg, 4 decimals; empty where none."""
    known = np.isfinite(joints).all(axis=1)
    degrees = np.degrees(joints)
    degrees = np.where((np.round(degrees, 4) == 0.0) | ~known[:, None], 0.0, degrees)
    cells = _formatted(degrees, 4)
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
    value, _ = written_speed(motion, "csv")
    speed = format_number(floor_places(value, 3), 3) if value is not None else ""  # mm/s, rounded down
    zone = format_number(motion.zone, 3) if motion.zone is not None else ""
    cells += ["PTP" if kind == JOINT else "LIN", speed, zone]
    if with_joints:
        cells += [format_number(v, 9) for v in np.degrees(target.joints)]
    return ",".join(cells)
