"""The motion lines a CAM post-processor writes in URScript, read together as columns (`CamLines`).

Our converter writes ``movel(p[x, y, z, rx, ry, rz], v=0.050000,
r=0.001000)`` one a line; RoboDK writes ``movel(pose_trans(ref_frame,
p[...]),accel_mss,speed_ms,t=0,r=0.001)`` and ``movej([q1, ..., q6],
...)``. A line of this shape alone on its line (a ``movel``, ``movej`` or
``movep`` to a pose literal, a joint list literal or ``pose_trans`` of a
variable and a pose literal, whose options ``a``, ``v``, ``t``, ``r`` are
numbers or variable names, named or positional) is found by one regular
expression over the masked script; its numbers are parsed and checked as
arrays. A line whose numbers the line-by-line read would refuse (out of
range, not finite) or whose options name one twice is left to that read,
which names it (`trajcomp.formats.urscript.reader`).
"""

import dataclasses
import itertools
import re

import numpy as np

from trajcomp.formats.text import JOINT_LIMIT, LENGTH_LIMIT, NUMBER
from trajcomp.programs.tables import TextSlices

FUNCTIONS = ("movel", "movej", "movep")
OPTIONS = ("a", "v", "t", "r")
# the option each positional argument is, per function (URScript's signatures; -1: none, ignored)
POSITIONAL = np.array([[0, 1, 2, 3], [0, 1, 2, 3], [0, 1, 3, -1]])
SLOTS = 4  # options a line may give
_NAME = r"[A-Za-z_]\w*"
# Groups tile the line from its start to the call's ")" (so that their offsets are the sums of their lengths):
# 1 indent, 2 function, 3 "(", 4-6 "pose_trans(" frame ",", 7 "p", 8 "[", 9-19 the six numbers (odd) and the commas
# between them (even), 20 "]", 21 the ")" of pose_trans, 22 blanks, then per option 6 groups: ",", its name, "=",
# its value as a number or as a variable name, blanks.
_OPTION = rf"(?:(,[ \t]*)(?:([avtr])([ \t]*=[ \t]*))?(?:({NUMBER})|({_NAME}))([ \t]*))?"
_CAM_LINE = re.compile(
    r"(?m)^([ \t]*)(movel|movej|movep)([ \t]*\([ \t]*)"
    rf"(?:(pose_trans[ \t]*\([ \t]*)({_NAME})([ \t]*,[ \t]*))?(p?)(\[[ \t]*)"
    + r"([ \t]*,[ \t]*)".join([f"({NUMBER})"] * 6)
    + r"([ \t]*\])(?(4)([ \t]*\)))([ \t]*)" + _OPTION * SLOTS + r"\)[ \t]*(?=[\r\n]|\Z)")
_GROUPS = 22 + 6 * SLOTS
_NUMBERS = np.arange(8, 19, 2)  # columns (0-based groups) of the six numbers
_SLOT = 22 + 6 * np.arange(SLOTS)  # first column of each option
_LAST = np.concatenate([[19, 20], _SLOT + 3, _SLOT + 4])  # what may end the call's last argument
LINES_AT_ONCE = 16384  # matches turned into arrays together: bounds the objects a long script's read makes


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
    option : ndarray of float, shape (B, 3)
        The literal value of v, t and r; NaN where not given or given by a variable.
    option_name : ndarray of object, shape (B, 3)
        The variable giving v, t and r; None where none does.
    option_start, option_end : ndarray of int, shape (B, 3)
        Offsets of v's, t's and r's values; -1 where not given.
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


def cam_lines(masked, line_starts):
    """The CAM-shaped motion lines of a masked script whose numbers are within range, read together.

    Parameters
    ----------
    masked : str
        The script, comments and strings blanked (`trajcomp.formats.text.mask`).
    line_starts : ndarray of int
        Offsets of its lines (`trajcomp.formats.text.Lines.starts`).

    Returns
    -------
    CamLines
    """
    found = _CAM_LINE.finditer(masked)
    parts = []
    while chunk := list(itertools.islice(found, LINES_AT_ONCE)):
        parts.append(_columns(chunk, line_starts))
    if not parts:
        return _columns([], line_starts)
    return CamLines(**{f.name: np.concatenate([getattr(p, f.name) for p in parts])
                       for f in dataclasses.fields(CamLines)})


def _columns(matches, line_starts):
    """`CamLines` of some matches of `_CAM_LINE`, the ones a line-by-line read would refuse left out."""
    b = len(matches)
    groups = np.array([m.groups("") for m in matches], dtype=object).reshape(b, _GROUPS)
    start = np.fromiter((m.start() for m in matches), dtype=np.int64, count=b)
    stop = np.fromiter((m.end() for m in matches), dtype=np.int64, count=b)
    length = np.fromiter(map(len, groups.ravel().tolist()), dtype=np.int64, count=groups.size).reshape(b, _GROUPS)
    group_end = start[:, None] + np.cumsum(length, axis=1)
    group_start = group_end - length
    function = np.select([groups[:, 1] == name for name in FUNCTIONS], range(len(FUNCTIONS)), 0)
    is_joint = length[:, 6] == 0
    framed = length[:, 4] > 0
    values = np.array(groups[:, _NUMBERS].ravel().tolist(), dtype=float).reshape(b, 6)
    limit = np.where(is_joint, np.radians(JOINT_LIMIT), LENGTH_LIMIT / 1000.0)
    good = (np.isfinite(values) & (np.abs(values) <= limit[:, None])).all(axis=1) & ~(framed & is_joint)

    given = length[:, _SLOT + 3] + length[:, _SLOT + 4] > 0  # (B, SLOTS)
    named = length[:, _SLOT + 1] > 0
    positional = np.cumsum(given & ~named, axis=1) - 1
    code = np.where(named, np.select([groups[:, _SLOT + 1] == o for o in OPTIONS], range(len(OPTIONS)), -1),
                    POSITIONAL[function[:, None], np.clip(positional, 0, SLOTS - 1)])
    code[~given] = -1
    for c in range(len(OPTIONS)):
        good &= (code == c).sum(axis=1) <= 1  # an option given twice: the line-by-line read's rules decide
    rows = np.arange(b)
    option = np.full((b, 3), np.nan)
    option_name = np.full((b, 3), None, dtype=object)
    option_start, option_end = np.full((b, 3), -1, dtype=np.int64), np.full((b, 3), -1, dtype=np.int64)
    for j, c in enumerate((1, 2, 3)):  # v, t, r
        has = (code == c).any(axis=1)
        slot = _SLOT[np.argmax(code == c, axis=1)]
        literal = has & (length[rows, slot + 3] > 0)
        number = np.array(groups[rows[literal], slot[literal] + 3].tolist(), dtype=float)
        option[literal, j] = number
        good[literal] &= np.isfinite(number)
        by_name = has & ~literal
        option_name[by_name, j] = groups[rows[by_name], slot[by_name] + 4]
        value = np.where(literal, slot + 3, slot + 4)
        option_start[has, j] = group_start[rows, value][has]
        option_end[has, j] = group_end[rows, value][has]
    end = np.where(length[:, _LAST] > 0, group_end[:, _LAST], -1).max(axis=1)
    columns = CamLines(
        line=np.searchsorted(line_starts, start, side="right"), function=function, is_joint=is_joint, values=values,
        number_start=group_start[:, _NUMBERS], number_end=group_end[:, _NUMBERS],
        frame=np.where(framed, groups[:, 4], None), option=option, option_name=option_name,
        option_start=option_start, option_end=option_end, end=end, start=group_start[:, 1], stop=stop)
    return columns.rows(good)
