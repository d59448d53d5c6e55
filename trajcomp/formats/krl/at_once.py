"""The KRL reader's at-once strategy: the grammar's one-line forms run over a whole text, their fields read as columns.

The grammar's forms (`trajcomp.formats.krl.grammar`: `WRITTEN_POINT`
declarations of a data list, `WRITTEN_MOTION` and `INLINE_MOTION` lines
of a .src) are found at once from the characters' codes, and by their
patterns on the lines laid out otherwise (`trajcomp.formats.forms.written_lines`);
their numbers are read from the characters
(`trajcomp.formats.number_fields`). Every other line goes to the line
reader (`trajcomp.formats.krl.reader`).
"""

import numpy as np

from trajcomp.formats.forms import written_lines
from trajcomp.formats.krl.grammar import (
    GLOBAL_WORD, INLINE_MOTION, LIMITS, MOTION_GROUPS, POINT_FIELDS, POSE, SHARED, STATUS_LARGEST, WRITTEN_MOTION,
    WRITTEN_POINT,
)
from trajcomp.formats.number_fields import DIGIT as _DIGIT, offset_type, read_numbers, text_codes
from trajcomp.formats.number_fields import spells as _spells, spelt as _spelt
from trajcomp.formats.text import LENGTH_LIMIT
from trajcomp.programs.tables import TargetTable, TextSlices, read_only, repeated
from trajcomp.programs.items import SpanColumns
from trajcomp.arm.transforms import pose_to_matrix

AT_ONCE = 65536  # points or motions whose fields are read together: bounds the arrays held
_LONGEST_WHOLE = 24  # digits of an S or T read at once


def written_points(index, masked, lines):
    """The Cartesian points of a data list declared as KUKA writes them (`WRITTEN_POINT`), read at once.

    The lines are found by the form (`written_lines`), their numbers read
    from the characters `AT_ONCE` points at a time. A declaration whose
    numbers a line-by-line read would refuse (no number, out of range, S
    or T beyond their bits) is left out: that read then names it.

    Parameters
    ----------
    index : int
        The data list's source index.
    masked : str
        Its text, comments and strings blanked (`trajcomp.formats.text.mask`).
    lines : Lines
        Its lines.

    Returns
    -------
    line : ndarray of int, shape (N,)
        The line of each point (ascending).
    table : TargetTable or None
        The points as columns (no object each): names and spans (`SpanColumns`) in the data list's text.
    shared : ndarray of bool, shape (N,)
        The points declared GLOBAL.
    """
    offset = offset_type(masked)
    codes = text_codes(masked)
    found, = written_lines((WRITTEN_POINT,), masked, codes)
    fields = [0] + WRITTEN_POINT.group(*POINT_FIELDS)
    configs = {}  # one tuple per distinct (S, T): a path's points mostly share theirs
    blocks = []
    for lo in range(0, len(found), AT_ONCE):
        regs = found[lo:lo + AT_ONCE]
        start, end = regs[:, fields, 0], regs[:, fields, 1]
        numbers, read = _field_numbers(codes, start, end)
        shared = _declared_global(masked, codes, regs[read])
        blocks.append(_written_block(start[read], end[read], numbers[read], shared, offset, configs))
    if not blocks:
        return np.zeros(0, dtype=int), None, np.zeros(0, dtype=bool)
    pose, start, end, config, external, shared = (
        np.concatenate(parts) if isinstance(parts[0], np.ndarray) else sum(parts, ()) for parts in zip(*blocks))
    if not len(start):
        return np.zeros(0, dtype=int), None, np.zeros(0, dtype=bool)
    line = np.searchsorted(lines.starts, start[:, 0], side="right")
    n = len(line)
    none = repeated(None, n)
    table = TargetTable(pose, np.zeros(n, dtype=bool), np.broadcast_to(np.nan, (n, 6)), line, config, none, none,
                        external, np.zeros(n, dtype=bool), TextSlices(lines.text, start[:, 1], end[:, 1]),
                        SpanColumns(index, lines.text, POSE + ("s", "t"), start[:, 2:], end[:, 2:]))
    return line, table, shared


def _declared_global(masked, codes, regs):
    """Whether each of K declarations (``regs`` (K, groups + 1, 2): `WRITTEN_POINT`'s) is GLOBAL (K,) bool:
    `GLOBAL_WORD` among its qualifiers (rare: looked for one by one), or a point named so."""
    (qualifiers,), (name,) = WRITTEN_POINT.group("qualifiers"), WRITTEN_POINT.group("name")
    shared = (regs[:, name, 1] - regs[:, name, 0] == len(SHARED)) & _spells(codes, regs[:, name, 0], SHARED)
    for k in np.flatnonzero(regs[:, qualifiers, 1] > regs[:, qualifiers, 0]).tolist():
        shared[k] |= GLOBAL_WORD.search(masked, int(regs[k, qualifiers, 0]), int(regs[k, qualifiers, 1])) is not None
    return shared


def _made_of(codes, start, end, table, longest):
    """Whether each field ``[start, end)`` (K,) is 1 to ``longest`` characters all in ``table`` (`character_table`)."""
    width = end - start
    window = int(min(width.max(initial=0), longest))
    inside = np.arange(window) < width[:, None]
    return (width >= 1) & (width <= longest) & (table[_spelt(codes, start, window)] | ~inside).all(axis=1)


def _field_numbers(codes, start, end):
    """The numbers of point declarations' fields X..C, S, T, E1..E6, read at once.

    Parameters
    ----------
    codes : ndarray, shape (L,)
    start, end : ndarray of int, shape (K, 16)
        The fields' offsets: the line, the name, X..C, S, T, E1..E6 (-1 where not written).

    Returns
    -------
    numbers : ndarray, shape (K, 14)
        X..C, S, T, E1..E6; NaN where not written.
    read : ndarray of bool, shape (K,)
        Whether each written field is a number as `WRITTEN_POINT` states it (S and T digits only).
    """
    given = start[:, 2:] >= 0
    numbers = np.full(given.shape, np.nan)
    read = np.ones(given.shape, dtype=bool)
    numbers[given], read[given] = read_numbers(codes, start[:, 2:][given], end[:, 2:][given])
    status = given[:, 6:8]
    read[:, 6:8][status] &= _made_of(codes, start[:, 8:10][status], end[:, 8:10][status], _DIGIT, _LONGEST_WHOLE)
    return numbers, read.all(axis=1)


def _written_block(start, end, numbers, shared, offset, configs):
    """Some point declarations as columns, less those a line-by-line read would refuse (`written_points`).

    Parameters
    ----------
    start, end : ndarray of int, shape (K, 16)
        Offsets of the declarations' fields (`_field_numbers`).
    numbers : ndarray, shape (K, 14)
        Their numbers (`_field_numbers`).
    shared : ndarray of bool, shape (K,)
        Declared GLOBAL.
    offset : type
        The integer type of offsets.
    configs : dict
        ``{(S, T): (S, T)}``: one tuple per distinct status and turn, shared by every block.

    Returns
    -------
    pose : ndarray, shape (k, 4, 4)
    start, end : ndarray of ``offset``, shape (k, 10)
        The declaration's start (start only) and name, then x, y, z, a, b, c, s, t (-1 where not written).
    config, external : tuple, length k
        ``(S, T)`` or ``()``; E1..E6 as written (ndarray) or None.
    shared : ndarray of bool, shape (k,)
        Declared GLOBAL.
    """
    given = start[:, 2:] >= 0  # x..c, s, t, e1..e6
    pose, status, external = numbers[:, :6], numbers[:, 6:8], numbers[:, 8:]
    limits = np.array([LIMITS[p] for p in POSE])
    good = np.isfinite(pose).all(axis=1) & (np.abs(pose) <= limits).all(axis=1)
    good &= ~given[:, 6] | (status <= list(STATUS_LARGEST.values())).all(axis=1)
    good &= (np.isfinite(external) & (np.abs(external) <= LENGTH_LIMIT) | ~given[:, 8:]).all(axis=1)
    keep = np.flatnonzero(good)
    vector = pose[keep]
    vector[:, 3:] = np.radians(vector[:, 3:])
    turns = STATUS_LARGEST["t"] + 1  # S and T as one whole number: S * turns + T
    key = np.where(given[keep, 6], status[keep, 0] * turns + status[keep, 1], -1).astype(np.int64)
    distinct, which = np.unique(key, return_inverse=True)
    words = np.empty(len(distinct), dtype=object)
    for k, word in enumerate(distinct.tolist()):
        words[k] = configs.setdefault(divmod(word, turns), divmod(word, turns)) if word >= 0 else ()
    config = tuple(words[which.ravel()].tolist())
    counts = given[keep, 8:].sum(axis=1)
    external = _shared_rows(external[keep], counts) if counts.any() else (None,) * len(keep)
    return (pose_to_matrix(vector), start[keep, :10].astype(offset), end[keep, :10].astype(offset), config, external,
            shared[keep])


def _shared_rows(values, counts):
    """Each row's first ``counts`` values as an array, one read-only array per distinct row (a path's points
    mostly share their external axes: E1..E6 of a track that does not move), None where the count is 0.

    Parameters
    ----------
    values : ndarray, shape (K, 6)
    counts : ndarray of int, shape (K,)

    Returns
    -------
    tuple, length K
    """
    bits = np.where(np.arange(values.shape[1]) < counts[:, None], values, 0.0).view(np.int64)  # -0.0 kept apart
    distinct, which = np.unique(np.c_[counts, bits], axis=0, return_inverse=True)
    arrays = np.empty(len(distinct), dtype=object)
    for k, row in enumerate(distinct):
        arrays[k] = read_only(row[1:1 + row[0]].view(np.float64)) if row[0] else None
    return tuple(arrays[which.ravel()].tolist())


def written_motions(index, masked, lines):
    """The motions of a .src written as `WRITTEN_MOTION` (``LIN XP1 C_DIS``) or `INLINE_MOTION` (``LIN {X ..}
    C_DIS``), as columns, and the inline points of the latter.

    The lines are found by the forms (`written_lines`); an inline point's
    numbers are read from the characters (`_field_numbers`), `AT_ONCE`
    points at a time; a point a line-by-line read would refuse (no number,
    out of range, S or T beyond their bits) leaves its motion to that
    read, which names it.

    Parameters
    ----------
    index : int
        The .src's source index.
    masked : str
        Its text, comments and strings blanked (`trajcomp.formats.text.mask`).
    lines : Lines
        Its lines.

    Returns
    -------
    columns : dict of ndarray, each shape (N,)
        ``line``; ``start``, ``end``: the line's text (its line ending
        left out by `_Stripped`); ``keyword_start``, ``keyword_end``,
        ``name_start``, ``name_end`` (-1 for an inline point); ``joint``:
        PTP / SPTP; ``approximated``: an approximation (C_DIS ...) is
        written; ``inline``: the row of ``inline`` of its point, -1 for a name.
    inline : TargetTable or None
        The inline points (their lines ascending), spans in the .src; None if there is none.
    """
    codes = text_codes(masked)
    named, inline = written_lines((WRITTEN_MOTION, INLINE_MOTION), masked, codes)
    points = _InlinePoints(codes, offset_type(masked))
    blocks = [np.c_[_motion_groups(named, WRITTEN_MOTION), np.full(len(named), -1)]]  # to a name: no inline row
    fields = [0] + INLINE_MOTION.group(*POINT_FIELDS)
    for lo in range(0, len(inline), AT_ONCE):
        regs = inline[lo:lo + AT_ONCE]
        groups = _motion_groups(regs, INLINE_MOTION)
        groups[:, 6:8] = -1  # no name
        blocks.append(points.motions(groups, regs[:, fields, 0], regs[:, fields, 1]))
    at = np.concatenate(blocks)
    at = at[np.argsort(at[:, 0], kind="stable")]  # the motions to names and to inline points, in line order
    columns = dict(zip(("start", "end", "keyword_start", "keyword_end"), at[:, :4].T))
    columns |= {"name_start": at[:, 6], "name_end": at[:, 7], "joint": at[:, 4] >= 0, "approximated": at[:, 8] >= 0,
                "line": np.searchsorted(lines.starts, at[:, 0], side="right"), "inline": at[:, 10]}
    return columns, points.table(index, lines)


def _motion_groups(regs, form):
    """The line and the `MOTION_GROUPS` of K motions found written in ``form`` (``regs`` (K, groups + 1, 2)), as
    (K, 10) int64: the (start, end) of each (-1 where not written)."""
    return regs[:, [0] + form.group(*MOTION_GROUPS)].reshape(-1, 10).astype(np.int64)


class _InlinePoints:
    """The inline points of motions read at once (`written_motions`), block after block, as one `TargetTable`.

    Parameters
    ----------
    codes : ndarray, shape (L,)
        The masked .src's character codes (`text_codes`).
    offset : type
        The integer type of its offsets.
    """

    def __init__(self, codes, offset):
        self.codes, self.offset = codes, offset
        self.blocks, self.count = [], 0
        self.configs = {}  # one tuple per distinct (S, T), shared by every block

    def motions(self, groups, start, end):
        """The motion rows (k, 11) of K motions to inline points, their points read and kept.

        ``groups`` (K, 10) as `_motion_groups`'; ``start``, ``end`` (K, 16)
        their points' fields (the line, an empty name, X..C, S, T, E1..E6).
        A point whose numbers a line-by-line read would refuse
        (`_written_block`) leaves its motion out: that read names it. The
        rows: the groups, then the row of the motion's point in `table`.
        """
        numbers, read = _field_numbers(self.codes, start, end)
        block = _written_block(start[read], end[read], numbers[read], np.zeros(np.count_nonzero(read), dtype=bool),
                               self.offset, self.configs)
        groups = groups[read][np.isin(start[read, 0], block[1][:, 0])]  # the motions of the points kept
        rows = np.c_[groups, self.count + np.arange(len(groups))]
        self.count += len(groups)
        self.blocks.append(block)
        return rows

    def table(self, index, lines):
        """The points as a `TargetTable` (their spans in source ``index``, of `Lines` ``lines``); None if there is
        none."""
        if not self.count:
            return None
        pose, start, end, config, external, _ = (
            np.concatenate(parts) if isinstance(parts[0], np.ndarray) else sum(parts, ())
            for parts in zip(*self.blocks))
        n = len(start)
        none = repeated(None, n)
        return TargetTable(pose, np.zeros(n, dtype=bool), np.broadcast_to(np.nan, (n, 6)),
                           np.searchsorted(lines.starts, start[:, 0], side="right"), config, none, none, external,
                           np.zeros(n, dtype=bool), None,
                           SpanColumns(index, lines.text, POSE + ("s", "t"), start[:, 2:], end[:, 2:]))
