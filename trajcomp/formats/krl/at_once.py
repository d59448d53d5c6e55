"""The KRL reader's at-once strategy: the forms CAM post-processors write a line each, read as columns.

The grammar's `WRITTEN_POINT` declarations of a data list and its
`WRITTEN_MOTION` and `INLINE_MOTION` lines of a .src are found from the
characters' codes with tables the grammar generates
(`trajcomp.formats.krl.grammar`), their numbers read from the characters
(`trajcomp.formats.number_fields`); a line written in a way the tables do
not lay out is matched by the form's pattern. Every other line goes to
the line reader (`trajcomp.formats.krl.reader`).
"""

import numpy as np

from trajcomp.formats.krl.grammar import (
    APPROXIMATIONS, CARTESIAN_TYPES, GLOBAL_WORD, INLINE_BLANKS, INLINE_MOTION, INLINE_POINT, LIMITS, MOTION_KEYWORDS,
    MOTIONS, POSE, SHARED, STATUS_LARGEST, WITH, WRITTEN_MOTION, WRITTEN_POINT, declaration_heads, member_layouts,
)
from trajcomp.formats.number_fields import BLANK as _BLANK, DIGIT as _DIGIT, WORD_CHARACTER as _WORD_CHARACTER
from trajcomp.formats.number_fields import character_table as _character_table, line_bounds as _line_bounds
from trajcomp.formats.number_fields import offset_type, read_numbers, text_codes
from trajcomp.formats.number_fields import spells as _spells, spelt as _spelt, starts_with as _starts_with
from trajcomp.formats.text import LENGTH_LIMIT
from trajcomp.programs.tables import TargetTable, TextSlices, every_row, read_only, repeated
from trajcomp.programs.items import JOINT, SpanColumns
from trajcomp.arm.transforms import pose_to_matrix


def written_points(index, masked, lines):
    """The Cartesian points of a data list declared as KUKA writes them (`WRITTEN_POINT`), read at once.

    The lines written exactly as `_written_layout` knows them are found
    from their characters, `AT_ONCE` lines at a time; the other lines are
    matched by `WRITTEN_POINT` one by one. The numbers are read from the
    characters (`trajcomp.formats.number_fields`). A declaration whose
    numbers a line-by-line read would refuse (out of range, S or T beyond
    their bits) is left out: that read then names it.

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
    starts, ends = _line_bounds(codes)
    configs = {}  # one tuple per distinct (S, T): a path's points mostly share theirs
    blocks, taken = [], np.zeros(len(starts), dtype=bool)
    for lo in range(0, len(starts), AT_ONCE):
        at, start, end, shared = _written_layout(codes, starts[lo:lo + AT_ONCE], ends[lo:lo + AT_ONCE])
        numbers, read = _field_numbers(codes, start, end)
        taken[lo + at[read]] = True
        blocks.append(_written_block(start[read], end[read], numbers[read], shared[read], offset, configs))
    others, matched = np.flatnonzero(~taken), False
    for lo in range(0, len(others), AT_ONCE):
        found = [m for k in others[lo:lo + AT_ONCE].tolist() if not masked[starts[k]:ends[k]].isspace()
                 and (m := WRITTEN_POINT.match(masked, int(starts[k]), int(ends[k])))]
        if not found:
            continue
        matched = True
        regs = np.array([m.regs for m in found], dtype=np.int64)  # absent groups: (-1, -1)
        shared = np.array([GLOBAL_WORD.search(masked, m.start(), m.end()) is not None for m in found], dtype=bool)
        numbers = _field_numbers(codes, regs[:, :, 0], regs[:, :, 1])[0]
        blocks.append(_written_block(regs[:, :, 0], regs[:, :, 1], numbers, shared, offset, configs))
    pose, start, end, config, external, shared = (
        np.concatenate(parts) if isinstance(parts[0], np.ndarray) else sum(parts, ()) for parts in zip(*blocks))
    if not len(start):
        return np.zeros(0, dtype=int), None, np.zeros(0, dtype=bool)
    if matched:  # the lines matched one by one among the others: in line order
        order = np.argsort(start[:, 0], kind="stable")
        pose, start, end, shared = pose[order], start[order], end[order], shared[order]
        config, external = (tuple(column[k] for k in order.tolist()) for column in (config, external))
    line = np.searchsorted(lines.starts, start[:, 0], side="right")
    n = len(line)
    none = repeated(None, n)
    table = TargetTable(pose, np.zeros(n, dtype=bool), np.broadcast_to(np.nan, (n, 6)), line, config, none, none,
                        external, np.zeros(n, dtype=bool), TextSlices(lines.text, start[:, 1], end[:, 1]),
                        SpanColumns(index, lines.text, POSE + ("s", "t"), start[:, 2:], end[:, 2:]))
    return line, table, shared


AT_ONCE = 65536  # lines or motions whose fields are found and read together: bounds the arrays held
_HEADS = declaration_heads()  # the declaration starts read at once (upper case): one space after each word
_LONGEST_NAME = 64  # characters of a point name read at once (a longer one: `WRITTEN_POINT`)
_LONGEST_WHOLE = 24  # digits of an S or T read at once
_LAYOUTS = member_layouts()  # the members of a point read at once, by their count


def _made_of(codes, start, end, table, longest):
    """Whether each field ``[start, end)`` (K,) is 1 to ``longest`` characters all in ``table`` (`_character_table`)."""
    width = end - start
    window = int(min(width.max(initial=0), longest))
    inside = np.arange(window) < width[:, None]
    return (width >= 1) & (width <= longest) & (table[_spelt(codes, start, window)] | ~inside).all(axis=1)


def _written_layout(codes, starts, ends):
    """The point declarations among lines written exactly ``DECL E6POS XP1={X 1.5,Y 2,Z 3,A 0,B 90,C 0,S 2,T 35}``.

    One space after each word and member name and none elsewhere (no
    blank at the line's start), E6POS, POS or FRAME, GLOBAL or not, any
    case, S and T and E1..Ek as `WRITTEN_POINT` has them, a line ending
    ``\\n`` or ``\\r\\n``: a subset of what `WRITTEN_POINT` matches, found
    from the characters' codes. The fields' contents are not checked here
    (`_field_numbers`).

    Parameters
    ----------
    codes : ndarray, shape (L,)
        The masked text's character codes (`text_codes`).
    starts, ends : ndarray of int, shape (B,)
        Offsets of the lines' starts and of their ``\\n`` (or the text's end).

    Returns
    -------
    at : ndarray of int, shape (K,)
        The lines declaring a point so (indices into ``starts``).
    start, end : ndarray of int, shape (K, 16)
        Offsets of `WRITTEN_POINT`'s groups: the declaration (its line,
        ``\\r`` included), the name, X..C, S, T, E1..E6 (-1 where not written).
    shared : ndarray of bool, shape (K,)
        Declared GLOBAL (`GLOBAL_WORD` in the declaration: the word or a point named so).
    """
    none = np.zeros(0, dtype=np.int64)
    if not len(starts) or not len(codes):
        return none, none.reshape(0, 16), none.reshape(0, 16), np.zeros(0, dtype=bool)
    carriage = (ends > starts) & (codes[np.maximum(ends - 1, 0)] == ord("\r"))
    close = ends - carriage - 1  # the "}" closing the declaration
    candidate = np.flatnonzero((close > starts) & (codes[np.maximum(close, 0)] == ord("}")))
    start_at, close = starts[candidate], close[candidate]
    head_end, shared = np.full(len(candidate), -1), np.zeros(len(candidate), dtype=bool)
    heads = _spelt(codes, start_at, max(map(len, _HEADS)))
    for head in _HEADS:
        spelt = _starts_with(heads, head)
        head_end[spelt] = start_at[spelt] + len(head)
        shared[spelt] = f" {SHARED} " in head
    brace, alone, commas = _braces(codes, starts, ends, start_at, close)
    good = (head_end >= 0) & alone
    name_end = np.where(good, brace - 1, head_end)
    good &= (codes[np.maximum(name_end, 0)] == ord("=")) & _made_of(codes, head_end, name_end, _WORD_CHARACTER,
                                                                     _LONGEST_NAME)
    shared |= (name_end - head_end == len(SHARED)) & _spells(codes, head_end, SHARED)
    start, end = np.full((len(candidate), 16), -1), np.full((len(candidate), 16), -1)
    start[:, 0], end[:, 0] = start_at, ends[candidate]
    start[:, 1], end[:, 1] = head_end, name_end
    written = _member_fields(codes, commas, brace + 1, close, good, start, end)
    return candidate[written], start[written], end[written], shared[written]


def _braces(codes, starts, ends, line_start, close):
    """The first ``{`` of lines, whether it is their only one before their aggregate's close, and the commas.

    Parameters
    ----------
    codes : ndarray, shape (L,)
    starts, ends : ndarray of int, shape (B,)
        The lines looked at (`_line_bounds`).
    line_start, close : ndarray of int, shape (K,)
        The starts of some of them and the offset of the ``}`` that closes each one's aggregate.

    Returns
    -------
    brace : ndarray of int, shape (K,)
        The first ``{`` from each line's start.
    alone : ndarray of bool, shape (K,)
        Whether it lies before ``close`` and no other ``{`` lies between them.
    commas : ndarray of int, shape (C,)
        The offsets of the commas of the B lines.
    """
    base, top = int(starts[0]), int(ends[-1])
    block = codes[base:top]
    opens = np.flatnonzero(block == ord("{")) + base
    commas = np.flatnonzero(block == ord(",")) + base
    first = np.searchsorted(opens, line_start)
    brace = opens[np.minimum(first, len(opens) - 1)] if len(opens) else np.full(len(line_start), -1)
    second = opens[np.minimum(first + 1, len(opens) - 1)] if len(opens) else brace
    return brace, (first < len(opens)) & (brace < close) & ((first + 1 >= len(opens)) | (second > close)), commas


def _member_fields(codes, commas, first, close, good, start, end, gap=0):
    """The members of aggregates ``{X 1.5,Y 2,Z 3,A 0,B 90,C 0,S 2,T 35,E1 0}`` as a point declaration or an
    inline point writes them (`_LAYOUTS`: each member's name and one space, ``gap`` blanks after each comma, no
    other blank), found from the characters' codes.

    Parameters
    ----------
    codes : ndarray, shape (L,)
        The masked text's character codes (`text_codes`).
    commas : ndarray of int, shape (C,)
        The offsets of the commas of the lines looked at (ascending).
    first, close : ndarray of int, shape (K,)
        The offsets of each aggregate's first member name and of its ``}``.
    good : ndarray of bool, shape (K,)
        The aggregates to look at (the others are not written so).
    start, end : ndarray of int, shape (K, 16)
        Filled in place: the offsets of the fields X..C, S, T, E1..E6 (columns 2-15) of the aggregates written so.
    gap : int
        The blanks after each comma.

    Returns
    -------
    ndarray of bool, shape (K,)
        The aggregates written so.
    """
    count = np.searchsorted(commas, close) - np.searchsorted(commas, first) + 1  # members
    written = np.zeros(len(first), dtype=bool)
    for members, layouts in _LAYOUTS.items():
        rows = np.flatnonzero(good & (count == members))
        if not len(rows):
            continue
        comma = commas[np.searchsorted(commas, first[rows])[:, None] + np.arange(members - 1)]
        name_at = np.concatenate([first[rows, None], comma + 1 + gap], axis=1)
        member_end = np.concatenate([comma, close[rows, None]], axis=1)
        names = _spelt(codes, name_at.ravel(), 3).reshape(len(rows), members, 3)  # "X ", "E1 "
        for layout in layouts:
            spelt = np.ones(len(rows), dtype=bool)
            field_start = np.empty((len(rows), members), dtype=np.int64)
            for k, (member, _) in enumerate(layout):
                spelt &= _starts_with(names[:, k], member + " ")
                field_start[:, k] = name_at[:, k] + 1 + len(member)
            spelt &= (member_end > field_start).all(axis=1)
            fields = [field for _, field in layout]
            start[rows[spelt][:, None], fields] = field_start[spelt]
            end[rows[spelt][:, None], fields] = member_end[spelt]
            written[rows[spelt]] = True
    return written


def _field_numbers(codes, start, end):
    """The numbers of point declarations' fields X..C, S, T, E1..E6, read at once.

    Parameters
    ----------
    codes : ndarray, shape (L,)
    start, end : ndarray of int, shape (K, 16)
        The fields' offsets (`_written_layout`).

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
        Offsets of the declarations' fields (`_written_layout`).
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

    The lines written exactly as `_motion_layout` knows them are found from
    their characters, `AT_ONCE` lines at a time; the other lines are matched
    by `WRITTEN_MOTION`, then `INLINE_MOTION`, one by one. An inline
    point's numbers are read from the characters (`_field_numbers`); a
    point a line-by-line read would refuse (out of range, S or T beyond
    their bits) leaves its motion to that read, which names it.

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
    starts, ends = _line_bounds(codes)
    blocks, taken = [], np.zeros(len(starts), dtype=bool)
    points = _InlinePoints(codes, offset_type(masked))
    for lo in range(0, len(starts), AT_ONCE):
        at, groups = _motion_layout(codes, starts[lo:lo + AT_ONCE], ends[lo:lo + AT_ONCE])
        taken[lo + at] = True
        blocks.append(np.c_[groups, np.full(len(groups), -1)])  # to a name: no inline row
        at, groups, start, end = _inline_layout(codes, starts[lo:lo + AT_ONCE], ends[lo:lo + AT_ONCE])
        taken[lo + at] = True
        blocks.append(points.motions(groups, start, end))
    others = np.flatnonzero(~taken)
    for lo in range(0, len(others), AT_ONCE):
        found, inline = [], []
        for k in others[lo:lo + AT_ONCE].tolist():
            if masked[starts[k]:ends[k]].isspace():  # a comment's line: the patterns would look at each blank
                continue
            if m := WRITTEN_MOTION.match(masked, int(starts[k]), int(ends[k])):
                found.append(m)
            elif m := INLINE_MOTION.match(masked, int(starts[k]), int(ends[k])):
                inline.append(m)
        named = np.array([m.regs for m in found], dtype=np.int64).reshape(-1, 10)  # (start, end) of groups 0-4
        blocks.append(np.c_[named, np.full(len(named), -1)])
        regs = np.array([m.regs for m in inline], dtype=np.int64).reshape(-1, 19, 2)  # absent groups: (-1, -1)
        groups = regs[:, [0, 1, 2, 3, 18]].reshape(-1, 10)
        groups[:, 6:8] = -1  # no name
        blocks.append(points.motions(groups, regs[:, INLINE_POINT, 0], regs[:, INLINE_POINT, 1]))
    at = np.concatenate(blocks)
    if len(others):  # the lines matched one by one among the others: in line order
        at = at[np.argsort(at[:, 0], kind="stable")]
    columns = dict(zip(("start", "end", "keyword_start", "keyword_end"), at[:, :4].T))
    columns |= {"name_start": at[:, 6], "name_end": at[:, 7], "joint": at[:, 4] >= 0, "approximated": at[:, 8] >= 0,
                "line": np.searchsorted(lines.starts, at[:, 0], side="right")}
    inline = at[:, 10] >= 0
    order = at[inline, 10]  # the points' rows in line order (those found by the pattern come after the others)
    at[inline, 10] = np.arange(len(order))
    columns["inline"] = at[:, 10]
    return columns, points.table(index, lines, order)


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
        """The motion rows (k, 11) of K motions found (`_inline_layout`), their points read and kept.

        ``groups`` (K, 10) as `_motion_layout`'s; ``start``, ``end`` (K, 16)
        their points' fields as `_written_layout`'s. A point whose numbers a
        line-by-line read would refuse (`_written_block`) leaves its motion
        out: that read names it. The rows: the groups, then the row of the
        motion's point in `table`.
        """
        numbers, read = _field_numbers(self.codes, start, end)
        block = _written_block(start[read], end[read], numbers[read], np.zeros(np.count_nonzero(read), dtype=bool),
                               self.offset, self.configs)
        groups = groups[read][np.isin(start[read, 0], block[1][:, 0])]  # the motions of the points kept
        rows = np.c_[groups, self.count + np.arange(len(groups))]
        self.count += len(groups)
        self.blocks.append(block)
        return rows

    def table(self, index, lines, order):
        """The points as a `TargetTable`, rows ``order`` (N,) of those read (their spans in source ``index``, of
        `Lines` ``lines``); None if there is none."""
        if not self.count:
            return None
        pose, start, end, config, external, _ = (
            np.concatenate(parts) if isinstance(parts[0], np.ndarray) else sum(parts, ())
            for parts in zip(*self.blocks))
        if not every_row(order, len(order)):
            pose, start, end = pose[order], start[order], end[order]
            config, external = (tuple(column[k] for k in order.tolist()) for column in (config, external))
        n = len(start)
        none = repeated(None, n)
        return TargetTable(pose, np.zeros(n, dtype=bool), np.broadcast_to(np.nan, (n, 6)),
                           np.searchsorted(lines.starts, start[:, 0], side="right"), config, none, none, external,
                           np.zeros(n, dtype=bool), None,
                           SpanColumns(index, lines.text, POSE + ("s", "t"), start[:, 2:], end[:, 2:]))


_LONGEST_MOTION = 64  # characters of a motion line read at once (a longer one: `WRITTEN_MOTION`)
_NAME_START = _character_table("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz_")


def _motion_keywords(spelt, keyword_start, follows):
    """The motion keyword (`MOTION_KEYWORDS`) each row of characters spells from a column, ``follows`` after it.

    Parameters
    ----------
    spelt : ndarray, shape (K, W)
        Rows of characters (`_spelt`).
    keyword_start : ndarray of int, shape (K,)
        The column each row's keyword would start at.
    follows : str
        What must follow the keyword (upper case).

    Returns
    -------
    keyword_end : ndarray of int, shape (K,)
        The column after the keyword; -1 where the row spells none so.
    joint : ndarray of bool, shape (K,)
        The keyword is a joint motion's (`MOTIONS`).
    """
    keyword_end, joint = np.full(len(spelt), -1), np.zeros(len(spelt), dtype=bool)
    for keyword in MOTION_KEYWORDS:
        word = keyword + follows
        columns = np.minimum(keyword_start[:, None] + np.arange(len(word)), spelt.shape[1] - 1)
        spells = _starts_with(np.take_along_axis(spelt, columns, axis=1), word)
        keyword_end[spells] = keyword_start[spells] + len(keyword)
        joint[spells] = MOTIONS[keyword] == JOINT
    return keyword_end, joint


def _motion_layout(codes, starts, ends):
    """The motion lines written exactly ``LIN XP1`` or ``PTP XP1 C_PTP``, found from the characters' codes.

    Blanks (spaces, tabs) before the keyword, one space between the words
    and none after, any case, a line ending ``\\n`` or ``\\r\\n``: a subset
    of what `WRITTEN_MOTION` matches.

    Parameters
    ----------
    codes : ndarray, shape (L,)
        The masked text's character codes (`text_codes`).
    starts, ends : ndarray of int, shape (B,)
        Offsets of the lines' starts and of their ``\\n`` (or the text's end).

    Returns
    -------
    at : ndarray of int, shape (K,)
        The lines written so (indices into ``starts``).
    groups : ndarray of int, shape (K, 10)
        `WRITTEN_MOTION`'s groups 0-4 as ``Match.regs`` gives them (start, end; -1 where not written): the line
        (``\\r`` included), the keyword, the keyword if PTP or SPTP, the point's name, the approximation.
    """
    carriage = (ends > starts) & (codes[np.maximum(ends - 1, 0)] == ord("\r")) if len(codes) else ends > ends
    length = ends - carriage - starts
    candidate = np.flatnonzero((length >= min(map(len, MOTION_KEYWORDS)) + 2) & (length <= _LONGEST_MOTION))
    width = int(length[candidate].max(initial=0)) + 1  # a character past the longest line: the name's end
    column = np.arange(width)
    spelt = _spelt(codes, starts[candidate], width)
    spelt[column >= length[candidate, None]] = 0  # past the line: no character
    keyword_start = np.argmin(_BLANK[spelt], axis=1)  # the first character not blank
    keyword_end, joint = _motion_keywords(spelt, keyword_start, " ")
    name_start = np.minimum(keyword_end + 1, width - 1)
    name_end = np.where(~_WORD_CHARACTER[spelt] & (column > name_start[:, None]), column, width).min(axis=1)
    good = (keyword_end >= 0) & _NAME_START[np.take_along_axis(spelt, name_start[:, None], axis=1)[:, 0]]
    name_length = name_end - name_start
    for word in (WITH,) + APPROXIMATIONS:  # not a name (`WRITTEN_MOTION`'s look-ahead)
        good &= (name_length != len(word)) | ~_spells(codes, starts[candidate] + name_start, word)
    approximation_start, approximation_end = name_end + 1, np.full(len(candidate), -1)
    for word in APPROXIMATIONS:
        spells = _spells(codes, starts[candidate] + name_end, " " + word)
        approximation_end[spells] = approximation_start[spells] + len(word)
    approximated = approximation_end >= 0
    line_end = length[candidate]
    good &= (name_end == line_end) | (approximated & (approximation_end == line_end))
    approximated &= name_end < line_end
    at = candidate[good]
    offset = starts[at, None]
    good_keyword_start, good_keyword_end = keyword_start[good] + starts[at], keyword_end[good] + starts[at]
    joint = joint[good]
    groups = np.stack([starts[at], ends[at], good_keyword_start, good_keyword_end,
                       np.where(joint, good_keyword_start, -1), np.where(joint, good_keyword_end, -1),
                       name_start[good] + offset[:, 0], name_end[good] + offset[:, 0],
                       np.where(approximated[good], approximation_start[good] + offset[:, 0], -1),
                       np.where(approximated[good], approximation_end[good] + offset[:, 0], -1)], axis=1)
    return at, groups.reshape(-1, 10)


_LONGEST_INDENT = 16  # blanks before an inline motion's keyword read at once (more: `INLINE_MOTION`)
_INLINE_TYPES = tuple(f"{typ}:" for typ in CARTESIAN_TYPES)  # the types an inline point may state


def _inline_layout(codes, starts, ends):
    """The inline motion lines written exactly ``LIN {X 1.5,Y 2,Z 3,A 0,B 90,C 0}`` or ``PTP {X ..,S 2,T 35} C_PTP``,
    found from the characters' codes.

    Blanks (spaces, tabs) before the keyword, one space after it and
    before the approximation, the point's type (`_INLINE_TYPES`) and one
    space or none, the members as `_member_fields` knows them (one space
    after each comma or none), nothing after, any case, a line ending ``\\n`` or ``\\r\\n``: a subset
    of what `INLINE_MOTION` matches. The fields' contents are not checked
    here (`_field_numbers`).

    Parameters
    ----------
    codes : ndarray, shape (L,)
        The masked text's character codes (`text_codes`).
    starts, ends : ndarray of int, shape (B,)
        Offsets of the lines' starts and of their ``\\n`` (or the text's end).

    Returns
    -------
    at : ndarray of int, shape (K,)
        The lines written so (indices into ``starts``).
    groups : ndarray of int, shape (K, 10)
        As `_motion_layout`'s (the name: -1).
    start, end : ndarray of int, shape (K, 16)
        Offsets of the point's fields as `_written_layout`'s: the line, an
        empty name before the first member, X..C, S, T, E1..E6 (-1 where not written).
    """
    none = np.zeros(0, dtype=np.int64)
    if not len(starts) or not len(codes):
        return none, none.reshape(0, 10), none.reshape(0, 16), none.reshape(0, 16)
    carriage = (ends > starts) & (codes[np.maximum(ends - 1, 0)] == ord("\r"))
    line_end = ends - carriage
    approximation_start = np.full(len(starts), -1)
    for word in APPROXIMATIONS:
        spells = (line_end - starts > len(word) + 2) & _spells(codes, np.maximum(line_end - len(word) - 1, 0),
                                                               " " + word)
        approximation_start[spells] = line_end[spells] - len(word)
    approximated = approximation_start >= 0
    close = np.where(approximated, approximation_start - 2, line_end - 1)  # the "}" closing the point
    candidate = np.flatnonzero((close > starts) & (codes[np.maximum(close, 0)] == ord("}")))
    start_at, close, approximated = starts[candidate], close[candidate], approximated[candidate]
    width = _LONGEST_INDENT + max(map(len, MOTION_KEYWORDS)) + 2
    spelt = _spelt(codes, start_at, width)
    keyword_start = np.minimum(np.argmin(_BLANK[spelt], axis=1), _LONGEST_INDENT)  # the first character not blank
    keyword_end, joint = _motion_keywords(spelt, keyword_start, " {")
    keyword_start, keyword_end = keyword_start + start_at, np.where(keyword_end >= 0, keyword_end + start_at, -1)
    brace, alone, commas = _braces(codes, starts, ends, start_at, close)
    good = (keyword_end >= 0) & alone & (brace == keyword_end + 1)
    start, end = np.full((len(candidate), 16), -1), np.full((len(candidate), 16), -1)
    start[:, 0], end[:, 0] = start_at, ends[candidate]
    first = brace + 1  # the first member's name: after the point's type if written (`E6POS: `)
    for typ in _INLINE_TYPES:
        typed = _spells(codes, first, typ) & (first == brace + 1)
        first[typed] += len(typ) + (codes[np.minimum(brace[typed] + len(typ) + 1, len(codes) - 1)] == ord(" "))
    start[:, 1] = end[:, 1] = first  # an empty name, where `INLINE_MOTION` has it
    written = _member_fields(codes, commas, first, close, good, start, end)
    for gap in range(1, INLINE_BLANKS + 1):  # ", Y 2": the same blanks after each comma
        written |= _member_fields(codes, commas, first, close, good & ~written, start, end, gap=gap)
    groups = np.stack([start_at, ends[candidate], keyword_start, keyword_end, np.where(joint, keyword_start, -1),
                       np.where(joint, keyword_end, -1), np.full(len(candidate), -1), np.full(len(candidate), -1),
                       np.where(approximated, close + 2, -1), np.where(approximated, line_end[candidate], -1)],
                      axis=1)
    return candidate[written], groups[written], start[written], end[written]
