"""The motion lines a CAM post-processor writes in URScript, read together as columns (`CamLines`): the at-once
execution of the grammar's written motion form (`trajcomp.formats.urscript.grammar.CAM_LINE`).

Our converter writes ``movel(p[x, y, z, rx, ry, rz], v=0.050000,
r=0.001000)`` one a line; RoboDK writes ``movel(pose_trans(ref_frame,
p[...]),accel_mss,speed_ms,t=0,r=0.001)`` and ``movej([q1, ..., q6],
...)``. A line of this shape alone on its line (a ``movel``, ``movej`` or
``movep`` to a pose literal, a joint list literal or ``pose_trans`` of a
variable and a pose literal, whose options ``a``, ``v``, ``t``, ``r`` are
numbers or variable names, named or positional) is read with the others
of its layout (its text with each number written ``0``: a CAM post
writes a few), which one regular expression checks once; its numbers are
read from their characters and checked as arrays. A line whose numbers
the line-by-line read would refuse (out of range, not finite) or whose
options name one twice is left to that read, which names it
(`trajcomp.formats.urscript.reader`).

The statements a post writes between them are found the same way
(`PlainLines`): a blank or comment line, or a call of a function that is
no motion nor ``set_tcp`` whose arguments hold no call, list, assignment
or colon (``set_standard_digital_out(5, 0.083)``, ``sleep(0.5)``): a
statement that changes nothing the reader carries.
"""

import dataclasses

import numpy as np

from trajcomp.formats.number_fields import BLANK, WORD_CHARACTER, character_table, read_numbers, text_codes
from trajcomp.formats.text import JOINT_LIMIT, LENGTH_LIMIT
from trajcomp.formats.urscript import grammar
from trajcomp.programs.tables import TextSlices

FUNCTIONS = grammar.WRITTEN
OPTION_COLUMNS = ("v", "t", "r", "a")  # the options of `CamLines`, in its columns' order
# the option (index in `grammar.OPTIONS`) each positional argument is, per function (-1: none, ignored)
POSITIONAL = np.array([[grammar.OPTIONS.index(o) if o in grammar.OPTIONS else -1
                        for o in (grammar.MOTIONS[f].positional + (None,) * grammar.SLOTS)[:grammar.SLOTS]]
                       for f in FUNCTIONS])
_GROUP = grammar.CAM_GROUP
_NUMBERS = np.array([_GROUP[f"number {k}"] for k in range(6)])  # columns (0-based groups) of the six numbers


def _option_columns(part):
    """The column of a part of each option slot (`grammar.CAM_GROUP`), (SLOTS,)."""
    return np.array([_GROUP[f"option {slot} {part}"] for slot in range(grammar.SLOTS)])


_OPTION_NAME, _OPTION_NUMBER, _OPTION_VARIABLE = (_option_columns(part) for part in ("name", "number", "variable"))
_LAST = np.concatenate([[_GROUP["]"], _GROUP[")"]], _OPTION_NUMBER, _OPTION_VARIABLE])  # what may end the last argument
LINES_AT_ONCE = 16384  # lines read together: bounds the arrays a long script's read makes
_NUMBER_CHARACTERS = "0123456789.eE+-"  # what a number is written with (`NUMBER`)
_NUMBER_FIRST = character_table("0123456789.+-")  # what a number starts with
_LINE_START = character_table("\r\nABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz_")  # past the indent of a
# line `grammar.PLAIN` or `grammar.CAM_LINE` may match: its end or a name's first character
_WORD = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_"  # a name's characters (`grammar.NAME`)
_MOST_INDENT = 16  # blanks of an indent passed at once (a longer one: one by one)
_WIDEST_LAYOUT = 512  # characters of the longest line layout read in blocks (a longer line: one by one)


@dataclasses.dataclass(frozen=True, eq=False)
class CamLines:
    """The CAM-shaped motion lines of a script (B,), in line order, their numbers within range.

    Attributes
    ----------
    line : ndarray of int, shape (B,)
    function : ndarray of int, shape (B,)
        Index in `FUNCTIONS`.
    is_joint : ndarray of bool, shape (B,)
        The position is a joint list ``[...]`` (rad), not a pose ``p[...]``.
    values : ndarray, shape (B, 6)
        The position's numbers: x, y, z (m) and a rotation vector (rad), or joints (rad).
    number_start, number_end : ndarray of int, shape (B, 6)
        Their offsets in the script.
    frame : ndarray of object, shape (B,)
        The variable of ``pose_trans(frame, p[...])``, None where the pose is a bare literal.
    option : ndarray of float, shape (B, 4)
        The literal value of v, t, r and a; NaN where not given or given by a variable.
    option_name : ndarray of object, shape (B, 4)
        The variable giving v, t, r and a; None where none does.
    option_start, option_end : ndarray of int, shape (B, 4)
        Offsets of v's, t's, r's and a's values; -1 where not given.
    end : ndarray of int, shape (B,)
        Offset of the end of the call's last argument (where re-timing inserts ``, t=...``).
    start, stop : ndarray of int, shape (B,)
        Offsets of the call and of its line's end.
    """

    line: np.ndarray
    function: np.ndarray
    is_joint: np.ndarray
    values: np.ndarray
    number_start: np.ndarray
    number_end: np.ndarray
    frame: np.ndarray
    option: np.ndarray
    option_name: np.ndarray
    option_start: np.ndarray
    option_end: np.ndarray
    end: np.ndarray
    start: np.ndarray
    stop: np.ndarray

    def __len__(self):
        return len(self.line)

    def rows(self, keep):
        """The lines ``keep`` (a boolean mask or indices)."""
        return CamLines(**{f.name: getattr(self, f.name)[keep] for f in dataclasses.fields(self)})

    def texts(self, text, rows=slice(None)):
        """The instructions of lines ``rows`` as written (`trajcomp.programs.items.Motion.text`), each a str built on
        access."""
        return _Stripped(text, self.start[rows], self.stop[rows])


class _Stripped(TextSlices):
    """Instructions from their call to their line's end, stripped (a comment after the call stays, as read)."""

    def __getitem__(self, k):
        found = super().__getitem__(k)
        return [t.rstrip() for t in found] if isinstance(k, slice) else found.rstrip()


@dataclasses.dataclass(frozen=True, eq=False)
class PlainLines:
    """The statements of a script (P,) that change nothing its reader carries: blank and comment lines and calls of
    other functions than `grammar.CALLS` with plain arguments (the module's docstring), in line order.

    Attributes
    ----------
    line : ndarray of int, shape (P,)
    start, stop : ndarray of int, shape (P,)
        Offsets of each line and of its end (its line ending left out).
    layout : ndarray of int, shape (P,)
        Index in ``layouts``.
    layouts : tuple of str
        The distinct layouts of the lines (each number written ``0``): the names they hold.
    """

    line: np.ndarray
    start: np.ndarray
    stop: np.ndarray
    layout: np.ndarray
    layouts: tuple

    def __len__(self):
        return len(self.line)

    def rows(self, keep):
        """The lines ``keep`` (a boolean mask or indices)."""
        return dataclasses.replace(self, line=self.line[keep], start=self.start[keep], stop=self.stop[keep],
                                   layout=self.layout[keep])


def cam_lines(masked, line_starts):
    """The CAM-shaped motion lines of a masked script whose numbers are within range, and its plain statements, read
    together.

    Parameters
    ----------
    masked : str
        The script, comments and strings blanked (`trajcomp.formats.text.mask`).
    line_starts : ndarray of int
        Offsets of its lines (`trajcomp.formats.text.Lines.starts`).

    Returns
    -------
    CamLines
    PlainLines
    """
    starts = np.asarray(line_starts, dtype=np.int64)
    starts = starts[starts < len(masked)]
    ends = np.append(starts[1:], len(masked))
    blocks = [_block(masked, starts[k:k + LINES_AT_ONCE], ends[k:k + LINES_AT_ONCE], k + 1)
              for k in range(0, len(starts), LINES_AT_ONCE)]
    parts = [part for part, _ in blocks if len(part)] or [_NONE]
    found = CamLines(**{f.name: np.concatenate([getattr(p, f.name) for p in parts])
                        for f in dataclasses.fields(CamLines)})
    plains = [plain for _, plain in blocks] or [_NO_PLAIN]
    first_layout = np.cumsum([0] + [len(plain.layouts) for plain in plains])
    return found, PlainLines(
        line=np.concatenate([plain.line for plain in plains]), start=np.concatenate([plain.start for plain in plains]),
        stop=np.concatenate([plain.stop for plain in plains]),
        layout=np.concatenate([plain.layout + first for plain, first in zip(plains, first_layout.tolist())]),
        layouts=tuple(text for plain in plains for text in plain.layouts))


def _among(codes, table):
    """Whether each character code (L,) is one of a `character_table`'s, as a boolean array (L,)."""
    return table[codes if codes.dtype == np.uint8 else np.minimum(codes, 127)]  # 127 (DEL) is in no table


def _block(masked, starts, ends, first_line):
    """`CamLines` and `PlainLines` of the K lines ``first_line ..`` at offsets ``starts`` .. ``ends`` (K,) of a masked
    script.

    A number is a run of `_NUMBER_CHARACTERS` that starts with a digit, a
    sign or a point after a character that is no word character (a digit
    in a name is none). A line's layout is its text with each number
    written ``0``. Where `grammar.CAM_LINE` matches a layout, its number groups
    are exactly the layout's numbers (each follows ``[``, ``,``, ``=`` or a
    blank and is followed by none of `_NUMBER_CHARACTERS`), so a line of
    that layout matches it too when each of its numbers is one as `NUMBER`
    states it: the layout's groups (`_layout_fields`, once per distinct
    layout) give the line's fields, moved by the widths of the numbers
    before them, and its numbers are read at once from their characters
    (`trajcomp.formats.number_fields.read_numbers`). A line whose layout
    `grammar.PLAIN` matches, naming none of `grammar.CALLS`, is a plain statement.
    """
    begin = int(starts[0])
    codes = text_codes(masked[begin:int(ends[-1])])
    start, end = starts - begin, ends - begin
    after_break = np.where(start > 0, codes[np.maximum(start - 1, 0)] == ord("\n"),
                           begin == 0 or masked[begin - 1] == "\n")  # where `^` matches in `grammar.CAM_LINE`
    word = start.copy()  # the first character past each line's indent
    for _ in range(_MOST_INDENT):
        blank = _among(codes[np.minimum(word, len(codes) - 1)], BLANK) & (word < end)
        if not blank.any():
            break
        word += blank
    else:  # a longer indent, one by one
        for k in np.flatnonzero(_among(codes[np.minimum(word, len(codes) - 1)], BLANK) & (word < end)).tolist():
            rest = masked[begin + word[k]:begin + end[k]]
            word[k] += len(rest) - len(rest.lstrip(" \t"))
    first = codes[np.minimum(word, len(codes) - 1)]
    candidate = after_break & ((word == end) | _among(first, _LINE_START))  # a motion or a plain statement
    digit = codes - ord("0") < 10  # unsigned: the characters below 0 wrap above 9
    number_character = digit | (codes == ord(".")) | (codes == ord("e")) | (codes == ord("E")) | (
        codes == ord("+")) | (codes == ord("-"))
    change = np.flatnonzero(number_character[1:] != number_character[:-1]) + 1
    edges = np.concatenate([[0], change, [len(codes)]])
    edges = edges[(0 if len(codes) and number_character[0] else 1):]  # the runs' starts and ends, alternating
    run_start, run_end = edges[0:-1:2], edges[1::2]
    is_number = _among(codes[run_start], _NUMBER_FIRST) & ~(
        _among(codes[np.maximum(run_start - 1, 0)], WORD_CHARACTER) & (run_start > 0))
    number_start, number_end = run_start[is_number], run_end[is_number]
    kept = ~number_character  # a number's first character stands for it, written 0; other runs stay whole
    kept[run_start] = True
    other = np.flatnonzero(~is_number & (run_end - run_start > 1))
    width = run_end[other] - run_start[other]
    kept[np.repeat(run_start[other] - np.cumsum(width) + width, width) + np.arange(width.sum())] = True
    layout_codes = codes.copy()
    layout_codes[number_start] = ord("0")
    layout_codes = layout_codes[kept]
    hidden = np.concatenate([[0], np.cumsum(number_end - number_start - 1)])  # characters left out before each end
    layout_start = start - hidden[np.searchsorted(number_end, start, side="right")]  # offsets in the layouts
    layout_length = end - hidden[np.searchsorted(number_end, end, side="right")] - layout_start
    rows = np.flatnonzero(candidate & (layout_length <= _WIDEST_LAYOUT))
    if not len(rows):
        return _NONE, _NO_PLAIN
    layout_start, layout_length = layout_start[rows], layout_length[rows]
    widest = int(layout_length.max())
    matrix = np.zeros((len(rows), widest + 1), dtype=np.uint32)
    matrix[:, 0] = layout_length
    column = np.arange(widest)
    matrix[:, 1:] = np.where(column < layout_length[:, None],
                             layout_codes[np.minimum(layout_start[:, None] + column, len(layout_codes) - 1)], 0)
    _, first, layout = np.unique(matrix.view(np.dtype((np.void, 4 * (widest + 1)))).reshape(-1),
                                 return_index=True, return_inverse=True)
    layout = layout.reshape(-1)
    texts = ["".join(map(chr, layout_codes[layout_start[k]:layout_start[k] + layout_length[k]].tolist()))
             for k in first.tolist()]
    plain = _plain_lines(texts, layout, rows, begin + start, begin + end, first_line)
    matched = [(k, m) for k, m in enumerate(map(grammar.CAM_LINE.match, texts)) if m]
    if not matched:
        return _NONE, plain
    fields, layout_good = _layout_fields([m for _, m in matched])
    parts = []
    for row, (k, _) in enumerate(matched):
        lines = rows[layout == k]
        parts.append(_lines_of_layout(codes, fields.rows([row]), texts[k], start[lines],
                                      np.searchsorted(number_start, start[lines]), number_start, number_end,
                                      begin, first_line + lines) if layout_good[row] else _NONE)
    if len(parts) == 1:
        return parts[0], plain
    found = CamLines(**{f.name: np.concatenate([getattr(p, f.name) for p in parts])
                        for f in dataclasses.fields(CamLines)})
    return found.rows(np.argsort(found.line, kind="stable")), plain


def _plain_lines(texts, layout, rows, start, end, first_line):
    """`PlainLines` of the lines ``rows`` of a block whose layouts (``texts`` [``layout``]) `grammar.PLAIN` matches
    without naming one of `grammar.CALLS`; ``start``, ``end``: offsets of the block's lines and of the next (K,)."""
    matches = [grammar.PLAIN.fullmatch(text) for text in texts]
    plain = [k for k, m in enumerate(matches) if m and m.group(1) not in grammar.CALLS]
    ending = np.array([len(matches[k].group(2)) for k in plain], dtype=np.int64)
    code = np.full(len(texts), -1)
    code[plain] = np.arange(len(plain))
    which = code[layout]
    kept = which >= 0
    lines = rows[kept]
    return PlainLines(line=first_line + lines, start=start[lines], stop=end[lines] - ending[which[kept]],
                      layout=which[kept], layouts=tuple(texts[k] for k in plain))


def _lines_of_layout(codes, layout, text, start, first_number, number_start, number_end, begin, line):
    """`CamLines` of the n lines at block offsets ``start`` (n,) of one layout ``text`` whose fields are ``layout``
    (one row, offsets in ``text``), their numbers from ``first_number`` (n,) on; those whose numbers a
    line-by-line read would refuse left out."""
    zeros = np.array([at for at, c in enumerate(text) if c == "0" and (at == 0 or (
        text[at - 1] not in _NUMBER_CHARACTERS and text[at - 1] not in _WORD))], dtype=np.int64)  # its numbers
    numbers = first_number[:, None] + np.arange(len(zeros))  # (n, numbers of the layout)
    values, read = _column_numbers(codes, number_start[numbers], number_end[numbers])
    widths = number_end[numbers] - number_start[numbers] - 1
    shift = np.concatenate([np.zeros((len(start), 1), dtype=np.int64), np.cumsum(widths, axis=1)], axis=1)

    def offsets(at):
        """Offsets in the script (n, m) of the lines' layout offsets ``at`` (m,); -1 stays -1."""
        moved = begin + start[:, None] + at + shift[:, np.searchsorted(zeros, at)]
        return np.where(at >= 0, moved, -1)

    position = values[:, np.searchsorted(zeros, layout.number_start[0])]
    limit = np.radians(JOINT_LIMIT) if layout.is_joint[0] else LENGTH_LIMIT / 1000.0
    good = read.all(axis=1) & (np.isfinite(position) & (np.abs(position) <= limit)).all(axis=1)
    option = np.repeat(layout.option, len(start), axis=0)
    literal = np.flatnonzero(~np.isnan(layout.option[0]))
    option[:, literal] = values[:, np.searchsorted(zeros, layout.option_start[0, literal])]
    good &= np.isfinite(option[:, literal]).all(axis=1)
    n = len(start)
    found = CamLines(
        line=line, function=np.repeat(layout.function, n), is_joint=np.repeat(layout.is_joint, n), values=position,
        number_start=offsets(layout.number_start[0]), number_end=offsets(layout.number_end[0]),
        frame=np.repeat(layout.frame, n), option=option, option_name=np.repeat(layout.option_name, n, axis=0),
        option_start=offsets(layout.option_start[0]), option_end=offsets(layout.option_end[0]),
        end=offsets(layout.end)[:, 0], start=offsets(layout.start)[:, 0], stop=offsets(layout.stop)[:, 0])
    return found if good.all() else found.rows(good)


def _column_numbers(codes, start, end):
    """Values and whether each is a number (`read_numbers`) of fields ``start`` .. ``end`` (n, m), each column's
    fields written as its first read once (a CAM post repeats its orientation and options line after line)."""
    values, read = np.empty(start.shape), np.empty(start.shape, dtype=bool)
    width = end - start
    for j in range(start.shape[1]):
        same = width[:, j] == width[0, j]
        for k in range(int(width[0, j])):
            same &= codes[start[:, j] + k] == codes[start[0, j] + k]
        rows = np.flatnonzero(~same)
        value, number = read_numbers(codes, np.append(start[0, j], start[rows, j]), np.append(end[0, j], end[rows, j]))
        values[:, j], read[:, j] = value[0], number[0]
        values[rows, j], read[rows, j] = value[1:], number[1:]
    return values, read


def _layout_fields(matches):
    """The fields of B layouts `grammar.CAM_LINE` matches (`_block`), as `CamLines` (offsets in each layout, numbers 0,
    ``option`` 0 where a literal gives it), and whether lines of each are read so (B,): not where they give an
    option twice (the line-by-line read's rules decide) or a joint list to ``pose_trans``."""
    b = len(matches)
    groups = np.array([m.groups("") for m in matches], dtype=object).reshape(b, len(_GROUP))
    stop = np.fromiter((m.end() for m in matches), dtype=np.int64, count=b)
    length = np.fromiter(map(len, groups.ravel().tolist()), dtype=np.int64, count=groups.size).reshape(b, len(_GROUP))
    group_end = np.cumsum(length, axis=1)
    group_start = group_end - length
    function = np.select([groups[:, _GROUP["function"]] == name for name in FUNCTIONS], range(len(FUNCTIONS)), 0)
    is_joint = length[:, _GROUP["p"]] == 0
    framed = length[:, _GROUP["frame"]] > 0
    good = ~(framed & is_joint)
    given = length[:, _OPTION_NUMBER] + length[:, _OPTION_VARIABLE] > 0  # (B, SLOTS)
    named = length[:, _OPTION_NAME] > 0
    positional = np.cumsum(given & ~named, axis=1) - 1
    options = grammar.OPTIONS
    code = np.where(named, np.select([groups[:, _OPTION_NAME] == o for o in options], range(len(options)), -1),
                    POSITIONAL[function[:, None], np.clip(positional, 0, grammar.SLOTS - 1)])
    code[~given] = -1
    for c in range(len(options)):
        good &= (code == c).sum(axis=1) <= 1
    rows = np.arange(b)
    option = np.full((b, 4), np.nan)
    option_name = np.full((b, 4), None, dtype=object)
    option_start, option_end = np.full((b, 4), -1, dtype=np.int64), np.full((b, 4), -1, dtype=np.int64)
    for j, c in enumerate(options.index(o) for o in OPTION_COLUMNS):
        has = (code == c).any(axis=1)
        slot = np.argmax(code == c, axis=1)
        number, variable = _OPTION_NUMBER[slot], _OPTION_VARIABLE[slot]
        literal = has & (length[rows, number] > 0)
        option[literal, j] = 0.0
        by_name = has & ~literal
        option_name[by_name, j] = groups[rows[by_name], variable[by_name]]
        value = np.where(literal, number, variable)
        option_start[has, j] = group_start[rows, value][has]
        option_end[has, j] = group_end[rows, value][has]
    end = np.where(length[:, _LAST] > 0, group_end[:, _LAST], -1).max(axis=1)
    fields = CamLines(
        line=np.zeros(b, dtype=np.int64), function=function, is_joint=is_joint, values=np.zeros((b, 6)),
        number_start=group_start[:, _NUMBERS], number_end=group_end[:, _NUMBERS],
        frame=np.where(framed, groups[:, _GROUP["frame"]], None), option=option, option_name=option_name,
        option_start=option_start, option_end=option_end, end=end, start=group_start[:, _GROUP["function"]], stop=stop)
    return fields, good


_NO_PLAIN = PlainLines(line=np.zeros(0, dtype=np.int64), start=np.zeros(0, dtype=np.int64),
                       stop=np.zeros(0, dtype=np.int64), layout=np.zeros(0, dtype=np.int64), layouts=())
_NONE = CamLines(  # no line
    line=np.zeros(0, dtype=np.int64), function=np.zeros(0, dtype=np.int64), is_joint=np.zeros(0, dtype=bool),
    values=np.zeros((0, 6)), number_start=np.zeros((0, 6), dtype=np.int64),
    number_end=np.zeros((0, 6), dtype=np.int64), frame=np.zeros(0, dtype=object), option=np.zeros((0, 4)),
    option_name=np.zeros((0, 4), dtype=object), option_start=np.zeros((0, 4), dtype=np.int64),
    option_end=np.zeros((0, 4), dtype=np.int64), end=np.zeros(0, dtype=np.int64), start=np.zeros(0, dtype=np.int64),
    stop=np.zeros(0, dtype=np.int64))
