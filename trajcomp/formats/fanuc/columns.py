"""The FANUC LS at-once read: the grammar's written forms (`trajcomp.formats.fanuc.grammar`) executed as columns.

The /MN motion lines that `grammar.WRITTEN_MOTION` matches have their
fields located piece by piece (`grammar.MOTION_PIECES`) from the
characters each piece is made of, and their numbers read together; the
/POS entries are located by the delimiters of `grammar.POSITION_LAYOUT`.
Whatever the written forms do not cover is left to the line-by-line read
of `trajcomp.formats.fanuc.reader`, which names what it refuses.
"""

import functools
import itertools

import numpy as np

from trajcomp.formats.fanuc import grammar
from trajcomp.formats.fanuc.grammar import SPEED_UNITS
from trajcomp.formats.number_fields import character_table, offset_type, read_numbers, text_codes
from trajcomp.formats.text import ANGLE_LIMIT, LENGTH_LIMIT
from trajcomp.programs.items import JOINT, LINEAR

MOTIONS_AT_ONCE = 16384  # motion lines whose fields are found together: bounds the offset arrays of a long program
_BLANK, _DIGIT = " \t", "0123456789"


def written_motions(by_line, starts, ends, in_mn, points, unread):
    """The /MN motion lines written as a CAM post-processor writes them (`grammar.WRITTEN_MOTION`), read at once.

    The pattern only finds the lines; their fields are located from the
    characters' classes (`_line_fields`) and their numbers read at once
    (`trajcomp.formats.number_fields`). A line to a position the /POS
    section lacks or leaves untaught is left out: the one-by-one read then
    names it.

    Returns
    -------
    dict of ndarray
        Over the K motions, in line order: ``line``, ``kind`` (object),
        ``target`` (index), ``value`` (the speed, mm/s, rad/s, % or s),
        ``unit`` (object), ``zone`` (mm, NaN: FINE or CNT0), ``speed``
        (K, 2) the offsets of the speed field; ``start``, ``end`` those of
        the line.
    """
    mn = np.flatnonzero(in_mn)
    begin = int(starts[mn[0] - 1]) if len(mn) else 0
    stop = (int(starts[mn[-1]]) if mn[-1] < len(starts) else len(by_line)) if len(mn) else 0
    found = (m.start() for m in grammar.WRITTEN_MOTION.finditer(by_line, begin, stop))
    parts = []
    while at := list(itertools.islice(found, MOTIONS_AT_ONCE)):
        line = np.searchsorted(starts, at, side="right")
        parts.append((line, *_line_fields(by_line, np.array(at, dtype=np.int64), int(ends[line[-1] - 1]))))
    line, read, numbers, speed_at, is_joint, value, scale, unit, zone, unnumbered = (
        np.concatenate(column) for column in zip(*parts)) if parts else (
        np.zeros(0, dtype=np.int64), np.zeros(0, dtype=bool), np.zeros(0, dtype=np.int64),
        np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=bool), np.zeros(0), np.zeros(0), np.zeros(0, dtype=object),
        np.zeros(0), np.zeros(0, dtype=bool))
    continued = unnumbered & ~np.isin(line - 1, line)  # ":L P[3] ..;" after a line not read at once may continue
    for k in np.flatnonzero(continued).tolist():  # it (`_instructions`): only one after a ";" is surely not
        continued[k] = not by_line[int(starts[line[k] - 2]):int(ends[line[k] - 2])].rstrip().endswith(";")
    known = np.array(sorted(n for n in points if n < grammar.WRITTEN_NUMBERS), dtype=np.int64)
    slot = np.minimum(np.searchsorted(known, numbers), max(len(known) - 1, 0))
    good = read & ~continued & in_mn[line] & (known[slot] == numbers if len(known)
                                               else np.zeros(len(line), dtype=bool))
    good &= ~np.isin(numbers, np.array([n for n in unread if n < grammar.WRITTEN_NUMBERS], dtype=np.int64))
    keep = np.flatnonzero(good)
    index = np.array([points[n] for n in known.tolist()], dtype=np.int64)
    return {"line": line[keep], "kind": np.array([LINEAR, JOINT], dtype=object)[is_joint[keep].astype(np.int64)],
            "target": index[slot[keep]] if len(keep) else np.zeros(0, dtype=np.int64),
            "speed": speed_at[keep], "start": starts[line[keep] - 1].astype(offset_type(by_line)),
            "end": ends[line[keep] - 1].astype(offset_type(by_line)),
            "value": value[keep] * scale[keep], "unit": unit[keep],
            "zone": np.where(zone[keep] == 0.0, np.nan, zone[keep])}


def _line_fields(by_line, at, stop):
    """The fields of K motion lines starting at offsets ``at`` (K,) that `grammar.WRITTEN_MOTION` matches, ``stop`` the
    end of the last, located by `_pieces` from the written pieces of the grammar (`grammar.MOTION_PIECES`). A line
    whose blanks or digits run longer than `_MOST_SKIPPED` is not read.

    Returns
    -------
    tuple of ndarray (K,)
        Whether the line is read; the position number; the offsets (K, 2)
        of the speed field (number and unit); whether the motion is J; the
        speed's number; its unit's scale and unit (`SPEED_UNITS`); the CNT
        number (0 for FINE); whether the line has no number (``:L P[3] ..``).
    """
    codes = text_codes(by_line[at[0]:stop])
    piece, read = _pieces(codes, at - at[0], grammar.MOTION_PIECES)
    (kind, _), (unit, unit_end) = piece["kind"], piece["unit"]
    numbers = [read_numbers(codes, *piece[name])[0] for name in ("position", "speed", "zone")]
    scale, names = np.ones(len(at)), np.empty(len(at), dtype=object)
    for spelling, (factor, name) in SPEED_UNITS.items():
        spelt = ((unit_end - unit) == len(spelling)) & (codes[unit] == ord(spelling[0]))  # one unit to each
        scale[spelt], names[spelt] = factor, name
    return (read, numbers[0].astype(np.int64), np.stack([piece["speed"][0], unit_end], axis=1) + at[0],
            codes[kind] == ord("J"), numbers[1], scale, names, np.nan_to_num(numbers[2]),
            piece["number"][0] == piece["number"][1])


def _pieces(codes, at, pieces):
    """Execute a form's written pieces (`grammar.Piece`, ``(name, piece)`` in order) on K texts that its written
    pattern matches from ``at`` (K,): each piece starts past the blanks before it and ends at a literal's width or
    at the first character not among its characters (`_skip`).

    Returns
    -------
    dict of str: (ndarray, ndarray)
        The start and end offsets (K,) of each piece, by name.
    read : ndarray of bool, shape (K,)
        Whether every piece was located within `_MOST_SKIPPED` moves.
    """
    read, spans = np.ones(len(at), dtype=bool), {}
    for name, piece in pieces:
        if piece.blanks:
            at, past = _skip(codes, at, _BLANK)
            read &= past
        if piece.characters is None:
            end = at + piece.width
        else:
            end, past = _skip(codes, at, piece.characters)
            read &= past
        spans[name], at = (at, end), end
    return spans, read


def _among(codes, characters):
    """Whether each character code (L,) is one of ``characters`` (ASCII), as a boolean array (L,)."""
    return _table(characters)[codes if codes.dtype == np.uint8 else np.minimum(codes, 255)]  # 255 (ÿ): in no set


_table = functools.lru_cache(maxsize=None)(character_table)  # a character set's look-up table (256,), made once


_MOST_SKIPPED = 64  # characters `_skip` passes at most (a field of a long run of blanks is read one by one)


def _skip(codes, at, characters, step=1, over=True):
    """The offsets (K,) reached from ``at`` (K,) moving by ``step`` past the characters among ``characters``
    (``over``; else past those not among them), and whether each stopped within `_MOST_SKIPPED` moves.

    The caller knows a character that stops each: no move leaves the text.
    """
    at = at.copy()
    for _ in range(_MOST_SKIPPED):
        moving = _among(codes[at], characters) == over
        if not moving.any():
            return at, np.ones(len(at), dtype=bool)
        at += step * moving
    return at, _among(codes[at], characters) != over


POSITIONS_AT_ONCE = 8192  # /POS entries whose fields are found together (`MOTIONS_AT_ONCE`)
_SPACE = " \t\n\r\f\v"  # white space a field may have around it (`\s` has more: such an entry goes one by one)
_WIDEST_WORD = 32  # characters of the widest frame, tool or CONFIG text read at once


def written_positions(masked, start, end):
    """The positions of the /POS section written as the pendant writes them (`grammar.POSITION_LAYOUT`), read at once.

    An entry is found by its delimiters (any white space around them,
    keywords in any case, a comment ``P[n: "..."]`` allowed), one block of
    entries at a time (`_entry_fields`). A position whose numbers or
    configuration the one-by-one read would refuse, or written otherwise,
    is left out: that read then names it.

    Returns
    -------
    dict
        Over the G positions kept, in text order: ``at`` (G, 2) the offsets
        of each entry, ``number`` (G, 2) those of its P number, ``p`` that
        number (int), ``uf``, ``ut`` (object: str) its frame and tool
        numbers, ``config`` (object: tuple), ``xyzwpr`` (G, 6) its numbers
        (mm, deg), ``spans`` (G, 2, 7) the offsets of X, Y, Z, W, P, R and
        CONFIG.
    """
    heads = entry_heads(masked, start, end)
    parts = [_entry_fields(masked, heads[k:k + POSITIONS_AT_ONCE], int(heads[k + POSITIONS_AT_ONCE])
                           if k + POSITIONS_AT_ONCE < len(heads) else end)
             for k in range(0, len(heads), POSITIONS_AT_ONCE)]
    empty = {"at": np.zeros((0, 2), dtype=np.int64), "number": np.zeros((0, 2), dtype=np.int64),
             "p": np.zeros(0, dtype=np.int64), "xyzwpr": np.zeros((0, 6)), "uf": objects([]), "ut": objects([]),
             "config": objects([]), "spans": np.zeros((0, 2, 7), dtype=np.int64)}
    return {key: np.concatenate([p[key] for p in parts]) for key in empty} if parts else empty


HEADS_AT_ONCE = 1 << 22  # characters of a /POS section looked at together for the starts of its entries


def entry_heads(masked, start, end):
    """The offsets (ascending) in ``masked[start:end]`` where a /POS entry (`_POS`) may start: each ``P[``."""
    parts = [np.zeros(0, dtype=np.int64)]
    for lo in range(start, end, HEADS_AT_ONCE):
        codes = text_codes(masked[lo:min(lo + HEADS_AT_ONCE + 1, end)])  # one more: a P[ across the block's end
        parts.append(np.flatnonzero((codes[:-1] == ord("P")) & (codes[1:] == ord("["))) + lo)
    return np.concatenate(parts)


def _entry_fields(masked, heads, stop):
    """`written_positions` of the entries starting at ``heads`` (B,), the last ending by ``stop``."""
    codes = text_codes(masked[heads[0]:stop])
    head = heads - heads[0]
    delimiter = np.flatnonzero(_among(codes, grammar.LAYOUT_DELIMITERS))
    first = np.searchsorted(delimiter, head)
    count = np.diff(np.append(first, len(delimiter)))
    found = []
    for layout in (grammar.POSITION_LAYOUT, grammar.COMMENTED_LAYOUT):
        rows = np.flatnonzero(count == len(layout))
        at = delimiter[first[rows, None] + np.arange(len(layout))]
        found.append(_layout_fields(codes, at, layout) + (rows,))
    good, fields, ends, rows = (np.concatenate(column) for column in zip(*found))
    order = np.argsort(rows[good], kind="stable")
    fields, ends, rows = fields[good][order], ends[good][order], rows[good][order]  # (G, fields, 2), text order
    xyzwpr = np.stack([read_numbers(codes, *fields[:, 3 + k].T)[0] for k in range(6)], axis=1)
    words = [_distinct_words(codes, *fields[:, k].T, check) for k, check in ((1, str), (2, str), (9, grammar.config))]
    good = (np.abs(xyzwpr) <= np.array([LENGTH_LIMIT] * 3 + [ANGLE_LIMIT] * 3)).all(axis=1)  # NaN: no number
    for _, read in words:
        good &= read
    words = [values for values, _ in words]
    keep = np.flatnonzero(good)
    fields = fields[keep] + heads[0]
    return {"at": np.stack([heads[rows[keep]], ends[keep] + heads[0]], axis=1), "number": fields[:, 0],
            "p": read_numbers(codes, *(fields[:, 0] - heads[0]).T)[0].astype(np.int64), "xyzwpr": xyzwpr[keep],
            "uf": words[0][keep], "ut": words[1][keep], "config": words[2][keep],
            "spans": fields[:, 3:].transpose(0, 2, 1)}


def _layout_fields(codes, at, layout):
    """Whether the E entries whose delimiters are at ``at`` (E, D) are written as ``layout`` states (E,), the offsets
    (E, 10, 2) of their `grammar.LAYOUT_FIELDS` and the end of each (E,).

    A word is found past the white space after the delimiter before it and
    before its own (`_skip`).
    """
    good = (codes[at] == np.array([ord(c) for c, _ in layout])).all(axis=1)
    fields = np.zeros((len(at), len(grammar.LAYOUT_FIELDS), 2), dtype=np.int64)
    for j, (_, before) in enumerate(layout[1:], start=1):
        if before is None:
            continue
        if before is grammar.NEXT_TO:
            good &= at[:, j] == at[:, j - 1] + 1
            continue
        start, past = _skip(codes, at[:, j - 1] + 1, _SPACE)
        end, before_end = _skip(codes, at[:, j] - 1, _SPACE, step=-1)
        end += 1  # the word before the delimiter is text[start:end], if any
        good &= past & before_end
        if before == "config":  # as written between the quotes
            opening = max(k for k in range(j) if layout[k][0] == "'")
            fields[:, grammar.LAYOUT_FIELDS.index(before)] = np.stack([at[:, opening] + 1, at[:, j]], axis=1)
        elif before in grammar.UNITS:  # a number and its unit
            unit = grammar.UNITS[before]
            good &= (end - start > len(unit)) & _spelt(codes, end - len(unit), unit)
            number_end, past = _skip(codes, np.maximum(end - len(unit) - 1, 0), _SPACE, step=-1)
            number_end = np.maximum(number_end + 1, start)
            good &= past
            fields[:, grammar.LAYOUT_FIELDS.index(before)] = np.stack([start, number_end], axis=1)
        elif before in grammar.LAYOUT_FIELDS:  # a whole number
            good &= (start < at[:, j]) & (_skip(codes, start, _DIGIT)[0] >= end) & (end - start <= 15)
            fields[:, grammar.LAYOUT_FIELDS.index(before)] = np.stack([start, end], axis=1)
        else:
            good &= start == at[:, j] if before == "" else (end - start == len(before)) & _spelt(codes, start,
                                                                                                  before)
    return good, fields, at[:, -1] + 1


def _spelt(codes, start, word):
    """Whether ``word`` (upper case) is written at each of ``start`` (N,), in any case."""
    spelt = np.ones(len(start), dtype=bool)
    for k, c in enumerate(word):
        spelt &= (codes[start + k] == ord(c)) | (codes[start + k] == ord(c.lower()))
    return spelt


def _distinct_words(codes, start, end, value):
    """``value(text)`` of each of N pieces ``text[start:end]``, taken once per distinct text.

    Returns
    -------
    values : ndarray of object, shape (N,)
    read : ndarray of bool, shape (N,)
        Whether the value is not None and the piece is at most `_WIDEST_WORD` characters (others go one by one).
    """
    length = np.minimum(end - start, _WIDEST_WORD + 1)
    column = np.arange(int(length.max(initial=0)))
    matrix = np.zeros((len(start), len(column) + 1), dtype=codes.dtype)  # a row: the length, the characters
    matrix[:, 0] = length
    matrix[:, 1:] = np.where(column < length[:, None], codes[np.minimum(start[:, None] + column, len(codes) - 1)], 0)
    rows = matrix.view(np.dtype((np.void, matrix.itemsize * matrix.shape[1]))).reshape(-1)
    _, first, inverse = np.unique(rows, return_index=True, return_inverse=True)
    values = objects([value("".join(map(chr, codes[start[k]:end[k]].tolist()))) for k in first.tolist()])
    read = np.array([v is not None for v in values], dtype=bool) & (matrix[first, 0] <= _WIDEST_WORD)
    inverse = inverse.reshape(-1)
    return values[inverse], read[inverse]


def objects(values):
    """An object array (N,) of ``values`` (tuples and arrays stay elements)."""
    out = np.empty(len(values), dtype=object)
    out[:] = list(values) if len(values) else []
    return out
