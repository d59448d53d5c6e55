"""The RAPID reader: a module's declarations and motion instructions into a `Program` (see `trajcomp.formats.rapid`)."""

import dataclasses
import re
from itertools import chain, repeat
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError
from trajcomp.formats.configuration import distinct_tuples
from trajcomp.formats.number_fields import NUMBER, BLANK, offset_type, read_numbers, text_codes
from trajcomp.formats.rapid import grammar
from trajcomp.formats.forms import Cursor, written_lines
from trajcomp.formats.rapid.task_data import TaskData, changed_at, shared_by_tasks, task_folders
from trajcomp.formats.text import (
    JOINT_LIMIT,
    LENGTH_LIMIT,
    DeclaredElsewhere,
    Lines,
    check_closed,
    code_of,
    fail,
    finite,
    integer,
    mask,
    name_offsets,
    read_source,
    runs_between,
    spans,
    split_top,
    statement_text,
    unresolved,
    whole_circle,
)
from trajcomp.programs import flow
from trajcomp.programs.flow import Step, Unknown
from trajcomp.programs.program import Program
from trajcomp.programs.items import CIRCULAR, LINEAR, Motion, SpanColumns, SpanTable, Statement, Target, replaced
from trajcomp.programs.tables import (
    ItemRows,
    MotionTable,
    StatementTable,
    TargetTable,
    TextSlices,
    joined_targets,
    repeated,
)
from trajcomp.arm.transforms import quat_to_matrix

# a robtarget's numbers' spans, named by their fields (`grammar.ROBTARGET`)
POSITION, QUAT, CONF = (tuple(name for name, _ in record.fields) for record in (grammar.POS, grammar.ORIENT,
                                                                              grammar.CONFDATA))
EXTAX = ("ea", "eb", "ec", "ed", "ee", "ef")
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
UNUSED_AXIS = 8.9e9  # ABB writes 9E9 for an external axis that is not used
QUAT_TOLERANCE = 0.01  # |norm - 1| a stated quaternion may have (written with few decimals)
PREDEFINED = {"tool0": np.eye(4)}, {"wobj0": np.eye(4)}  # need no declaration

MOTION_SPANS = ("speed", "via_name", "target_name")  # a motion's spans, in this order
_NAME = re.compile(r"^[A-Za-z]\w*$")
_NUMBER = re.compile(NUMBER)
_WORD = re.compile(r"[A-Za-z]\w*")
VMAX = 5000.0  # mm/s, v_tcp of the predefined speeddata vmax
# every predefined speeddata (v5 .. v7000, vmax) is [v_tcp, 500, 5000, 1000] (RAPID reference, speeddata)
PREDEFINED_V_ORI = 500.0  # deg/s
PREDEFINED_V_LEAX = 5000.0  # mm/s, linear external axes
VARIABLE = ("VAR", "PERS")  # the storages of a speeddata a program may change (a CONST it may not)


ROWS_AT_ONCE = 16384  # values whose delimiters are found together (`_value_fields`): bounds the arrays


def pose(values):
    """T (4, 4) from x, y, z (mm) and a quaternion [w, x, y, z]."""
    T = np.eye(4)
    T[:3, :3] = quat_to_matrix(values[3:7])
    T[:3, 3] = values[:3]
    return T


class _WrittenPoints:
    """The robtargets of a module declared on one line as RAPID tools write them (`grammar.WRITTEN_POINT`), read at once.

    A declaration whose numbers the statement-by-statement read would
    refuse (out of range, not a rotation, a configuration that is not a
    whole number) is left out: that read then names it; so are the lines
    ``excluded`` (numbers: part of a statement spread over several lines).

    Attributes
    ----------
    table : TargetTable or None
        The N points as columns (no object each): names (`TextSlices`) and
        spans (`SpanColumns`) in the module's text; None if there are none.
    line, start, end : ndarray of int, shape (N,)
        Line and offsets of each declaration (to its ``;``).
    shared : ndarray of bool, shape (N,)
        Whether other modules may assign the point (PERS or VAR, not LOCAL).
    """

    def __init__(self, source, masked, lines, codes, found):
        self.table, self.line, self.start, self.end = None, *(np.zeros(0, dtype=np.int64) for _ in range(3))
        self.shared = np.zeros(0, dtype=bool)  # found (N, 6, 2): the line, LOCAL / TASK, storage, name, value, ';'
        numbers, field_start, field_end, laid_out = _value_fields(codes, found[:, 4, 0], found[:, 4, 1],
                                                                  grammar.ROBTARGET.layout) if len(found) else [[]] * 4
        if not np.any(laid_out):
            return
        if not laid_out.all():
            found, numbers, field_start, field_end = (a[laid_out] for a in (found, numbers, field_start, field_end))
        local = np.zeros(len(found), dtype=bool)  # a storage prefix (LOCAL, TASK) is rare: read one by one
        for k in np.flatnonzero(found[:, 1, 1] > found[:, 1, 0]).tolist():
            local[k] = "LOCAL" in masked[found[k, 1, 0]:found[k, 1, 1]].upper()
        shared = (np.bitwise_or(codes[found[:, 2, 0]], 0x20) != ord("c")) & ~local  # PERS or VAR, not LOCAL
        keep, self.table = _robtargets(source.text, lines, numbers, found[:, 3], field_start, field_end)
        self.start, self.end, self.shared = found[keep, 0, 0], found[keep, 5, 1], shared[keep]
        self.line = self.table.line


def _written_lines(masked, codes, lines, excluded):
    """The lines of each of the `grammar.WRITTEN_FORMS` (`forms.written_lines`) but those ``excluded``.

    Parameters
    ----------
    masked : str
        The module's text, comments and strings blanked.
    codes : ndarray, shape (L,)
        Its character codes (`trajcomp.formats.number_fields.text_codes`).
    lines : Lines
    excluded : set of int
        Lines left to the statement-by-statement read (`_Spread`).

    Returns
    -------
    list of ndarray, shape (N_k, groups_k + 1, 2)
        Per form, the offsets of each line's match and of its groups (`forms.written_lines`), ascending.
    """
    found = written_lines(grammar.WRITTEN_FORMS, masked, codes)
    if excluded:
        found = [rows[~np.isin(np.searchsorted(lines.starts, rows[:, 0, 0], side="right"), list(excluded))]
                 for rows in found]
    return found


def _runs_between(masked, found):
    """The runs of text between the lines read at once (``found``: `_written_lines`' matches of each form), which
    open and close no block and change no data (`runs_between`)."""
    read_at_once = np.concatenate([matches[:, 0] for matches in found])
    lines_read = read_at_once[np.argsort(read_at_once[:, 0], kind="stable")]
    return runs_between(lines_read[:, 0], lines_read[:, 1], len(masked))


def _check_blocks(source, masked, runs):
    """`check_closed` of a module's blocks (`grammar.BLOCKS`: MODULE, routines, IF, FOR, WHILE, TEST), over the
    ``runs`` of lines between those read at once (`_runs_between`)."""
    check_closed(source, masked, grammar.BLOCK_OPENS, grammar.BLOCK_CLOSES, grammar.BLOCKS, runs,
                 grammar.OUTSIDE_MODULES)


def _line_matches(pattern, text, start=0, end=None):
    """The matches of ``pattern`` at the start of each line of ``text[start:end]`` (as ``^`` with ``re.M`` before
    it; ``start`` a line's start or the line break before one), in order: those after its first line begin at the
    line break before theirs.

    The text is searched for line breaks: a pattern anchored by ``^`` is
    tried at every character, which costs a long module seconds.
    """
    end = len(text) if end is None else end
    first = pattern.match(text, start, end)
    return chain([first] if first else [], re.compile("\n" + pattern.pattern, pattern.flags).finditer(text, start, end))


def _value_fields(codes, start, end, layout):
    """Offsets of the numbers of N values ``text[start:end]`` laid out as ``layout`` (``"[[,,],[,,,]]"``: their
    delimiters, a number between ``[`` or ``,`` and ``,`` or ``]``, blanks around it or not, nothing between the
    others), found at once.

    Parameters
    ----------
    codes : ndarray, shape (L,)
        The text's character codes (`trajcomp.formats.number_fields.text_codes`).
    start, end : ndarray of int, shape (N,)
        Offsets of each value, ascending.
    layout : str
        Every delimiter (``[``, ``,``, ``]``) of a value, in order.

    Returns
    -------
    numbers : ndarray, shape (N, F)
        The F numbers of each value, read from their characters
        (`trajcomp.formats.number_fields.read_numbers`, a column at a time).
    field_start, field_end : ndarray of int, shape (N, F)
        Offsets of each value's numbers' texts.
    laid_out : ndarray of bool, shape (N,)
        Whether the value has exactly these delimiters and every number is
        one (`read_numbers`) where read at once; a value that is not is read
        statement by statement, which names what is wrong.
    """
    delimiters = np.array([ord(c) for c in layout])
    gaps = np.arange(len(layout) - 1)
    numbered = np.isin(delimiters[:-1], [ord("["), ord(",")]) & np.isin(delimiters[1:], [ord(","), ord("]")])
    fields, empty = gaps[numbered], gaps[~numbered]
    n = len(start)
    field_start, field_end = (np.zeros((n, len(fields)), dtype=offset_type(codes)) for _ in range(2))
    laid_out = np.zeros(n, dtype=bool)
    for lo in range(0, n, ROWS_AT_ONCE):
        rows = slice(lo, lo + ROWS_AT_ONCE)
        first_at = int(start[rows][0])
        region = codes[first_at:int(end[rows].max())]
        at = np.flatnonzero((region == ord(",")) | (region == ord("[")) | (region == ord("]"))) + first_at
        first = np.searchsorted(at, start[rows])
        good = np.searchsorted(at, end[rows]) - first == len(layout)
        found = at[np.minimum(first[:, None] + np.arange(len(layout)), len(at) - 1)]  # (rows, delimiters)
        good &= (codes[found] == delimiters).all(axis=1) & (found[:, empty + 1] == found[:, empty] + 1).all(axis=1)
        field_start[rows], field_end[rows] = _unpadded(codes, found[:, fields] + 1, found[:, fields + 1])
        laid_out[rows] = good
    numbers = np.full((n, len(fields)), np.nan)
    rows = np.flatnonzero(laid_out)
    for j in range(len(fields)):  # a column at a time: fields of one width together, a column's transients only
        numbers[rows, j], is_number = read_numbers(codes, field_start[rows, j], field_end[rows, j])
        laid_out[rows[~is_number]] = False
    return numbers, field_start, field_end, laid_out


def _unpadded(codes, start, end):
    """Offsets ``start, end`` (N, F) of fields less the blanks around their texts (RoboDK writes ``[x, y, z]``)."""
    shape = start.shape
    end = end.ravel().astype(np.int64)
    start = Cursor(codes, end).blanks(start.ravel())
    while len(back := np.flatnonzero((end > start) & BLANK[np.minimum(codes[np.maximum(end - 1, 0)], 127)])):
        end[back] -= 1
    return start.reshape(shape), end.reshape(shape)


def _robtargets(text, lines, numbers, name, field_start, field_end):
    """The robtargets of N texts ``[[x,y,z],[q1..q4],[cf1..cfx],[ea..ef]]`` written without blanks, read at once.

    Parameters
    ----------
    text : str
        The module's text.
    lines : Lines
        Its lines.
    numbers : ndarray, shape (N, 17)
        x .. q4, cf1 .. cfx, ea .. ef.
    name : ndarray of int, shape (N, 2)
        Offsets of each name (empty for an inline target).
    field_start, field_end : ndarray of int, shape (N, 17)
        Offsets of the numbers' texts (`_value_fields`).

    Returns
    -------
    keep : ndarray of int, shape (n,)
        The rows the statement-by-statement read would not refuse (out of
        range, not a rotation, a configuration that is not a whole number):
        that read names the others.
    table : TargetTable
        Those n targets, no object each: names (`TextSlices`) and spans
        (`SpanColumns`) in ``text``.
    """
    position, quat, config, external = numbers[:, :3], numbers[:, 3:7], numbers[:, 7:11], numbers[:, 11:]
    good = (np.isfinite(numbers[:, :11]) & (np.abs(numbers[:, :11]) <= LENGTH_LIMIT)).all(axis=1)
    good &= (np.isfinite(external) & (np.abs(external) <= 1e10)).all(axis=1)
    norm = np.full(len(quat), np.inf)
    norm[good] = np.linalg.norm(quat[good], axis=1)  # of numbers within range only (1e308 squared overflows)
    good &= np.abs(norm - 1.0) <= QUAT_TOLERANCE - 1e-9  # at the bound: as the one read
    good &= (config == np.trunc(config)).all(axis=1)
    keep = np.flatnonzero(good)
    n = len(keep)
    rows = slice(None) if n == len(good) else keep  # every row kept: views of the columns, not copies
    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = quat_to_matrix(quat[rows])
    T[:, :3, 3] = position[rows]
    unused_axis = np.abs(external[rows]) >= UNUSED_AXIS
    unused = unused_axis.all(axis=1)
    offset = offset_type(text)  # the spans as int32 where they fit: 88 bytes a point less
    start, end = (np.ascontiguousarray(field[rows, :11], dtype=offset) for field in (field_start, field_end))  # x..cfx
    name = np.ascontiguousarray(name[rows])  # not a view holding every group of the lines read (48 bytes a point)
    none = repeated(None, n)
    return keep, TargetTable(
        T, np.zeros(n, dtype=bool), np.broadcast_to(np.nan, (n, 6)),  # no joints: one NaN row shared
        np.searchsorted(lines.starts, start[:, 0], side="right"),
        tuple(distinct_tuples(config[rows].astype(int))), none, none,
        (None,) * n if unused.all() else tuple(None if u else e for u, e in zip(
            unused.tolist(), np.where(unused_axis, np.nan, external[rows]))),
        np.zeros(n, dtype=bool), TextSlices(text, name[:, 0], name[:, 1]),
        SpanColumns(0, text, POSITION + QUAT + CONF, start, end))


def _declares_data(masked, piece=1 << 20):
    """Whether a module's masked text holds the word speeddata or num in any case (`_Reader.scan_data`).

    Looked for in lower-case copies of pieces of ``piece`` characters (a
    case-blind pattern search is ten times slower; a copy of the whole
    text would add its size to the read's peak).
    """
    return any("speeddata" in part or "num" in part
               for part in (masked[max(k - 8, 0):k + piece].lower() for k in range(0, len(masked), piece)))


class _WrittenMotions:
    """The motions of a module written one a line as CAM tools write them (`grammar.WRITTEN_MOTION`, `grammar.WRITTEN_INLINE`),
    as columns.

    What a motion's instruction states besides its point (kind, speed,
    zone, tool, work object) is read once per distinct text (``combo``)
    and stretch of the program between other statements (`_Reader.read_at_once`),
    by the statement-by-statement read itself; each motion's point is
    resolved with the others (`_resolve`).

    Attributes
    ----------
    line, start, end : ndarray of int, shape (M,)
        Line and offsets of each instruction (to its ``;``).
    name : ndarray of int, shape (M, 2)
        Offsets of its point's name; -1 for an inline target.
    inline : ndarray of int, shape (M,)
        Row of `table` of its inline target; -1 for a name.
    speed : ndarray of int, shape (M, 2)
        Offsets of its speed data (with ``\\V`` / ``\\T``).
    combo : ndarray of int, shape (M,)
        Code of its instruction, speed, zone, tool and work object texts.
    table : TargetTable or None
        The inline targets (`grammar.WRITTEN_INLINE`, `_robtargets`).
    """

    def __init__(self, text, masked, lines, codes, named, inline):
        combos = {}  # code of each distinct instruction, speed, zone, tool and work object text

        def combo(found, target):  # the text of each motion but its point (``target``: the group of its point)
            return [combos.setdefault(masked[i:j] + masked[k:end], len(combos))
                    for i, j, k, end in found[:, [1, 1, target, 4], [0, 1, 1, 1]].tolist()]

        self.table = None
        if len(inline):
            numbers, field_start, field_end, laid_out = _value_fields(codes, inline[:, 2, 0], inline[:, 2, 1],
                                                                      grammar.ROBTARGET.layout)
            if not laid_out.all():
                inline, numbers, field_start, field_end = (a[laid_out] for a in (inline, numbers, field_start,
                                                                                    field_end))
        if len(inline):
            keep, self.table = _robtargets(text, lines, numbers, np.repeat(field_start[:, :1], 2, axis=1), field_start,
                                           field_end)
            inline = inline[keep]  # a target refused: read one by one, which names it
        # line start, end (its ';'), name, speed, combo, row of `table` of an inline target (-1: a name)
        columns = [np.zeros((0, 8), dtype=np.int64)]
        if len(named):
            columns.append(np.c_[named[:, 0, 0], named[:, 4, 1], named[:, 2], named[:, 3], combo(named, 2),
                                 np.full(len(named), -1)])
        if len(inline):
            columns.append(np.c_[inline[:, 0, 0], inline[:, 4, 1], np.full((len(inline), 2), -1), inline[:, 3],
                                 combo(inline, 2), np.arange(len(inline))])
        columns = np.concatenate(columns)
        columns = columns[np.argsort(columns[:, 0], kind="stable")].astype(offset_type(text))  # int32 under 2 GB
        self.line = np.searchsorted(lines.starts, columns[:, 0], side="right")
        self.start, self.end = columns[:, 0], columns[:, 1]
        self.name, self.speed, self.combo, self.inline = columns[:, 2:4], columns[:, 4:6], columns[:, 6], columns[:, 7]
        self.proto = np.zeros(len(self.line), dtype=int)  # index into `_Reader.protos` (`_Reader.read_at_once`)
        self.parameter = np.zeros(len(self.line), dtype=bool)  # the point is a routine parameter
        self.target = np.full(len(self.line), -1)  # the target index of an inline target (`_Reader.read_at_once`)

    def __len__(self):
        return len(self.line)


def _statements(source, masked, lines=None, skipped=None):
    """``(line, start, end)`` of each statement: declarations and motions up to their ``;``, a routine's head
    up to the ``)`` of its parameters, else one line.

    ``skipped``: bool (L + 1,) of the lines read at once (`_written_points`,
    `_WrittenMotions`), left out; `_Spread` names one a statement begun
    before it runs into.
    """
    lines = lines or Lines(source.text)
    out, pending = [], None
    if skipped is None:
        numbered = iter(lines)
    else:
        numbers = np.flatnonzero(~skipped[1:]) + 1
        starts = np.asarray(lines.starts)
        numbered = zip(numbers.tolist(), starts[numbers - 1].tolist(),
                       np.append(starts, len(source.text))[numbers].tolist())
    previous = 0
    for number, start, end in numbered:
        if skipped is not None:
            end = start + len(source.text[start:end].rstrip("\r\n"))
            if number > previous + 1 and pending is not None:
                raise _Spread(previous + 1)
            previous = number
            if start == end and number == len(lines.starts):
                break
        if pending is not None:
            if pending[2] in masked[start:end]:
                out.append((pending[0], pending[1], start + masked[start:end].index(pending[2]) + 1))
                pending = None
            continue
        text = statement_text(masked, start, end)
        closer = ";" if grammar.STARTS_DECLARATION.match(text) or grammar.STARTS_MOTION.match(text) else \
            ")" if grammar.STARTS_ROUTINE.match(text) else None
        if closer is not None and closer not in text:
            pending = (number, start, closer)
        elif closer == ";":
            out.append((number, start, start + text.index(";") + 1))
        else:
            out.append((number, start, end))
    if pending is not None:
        if skipped is not None and previous < len(lines.starts) and skipped[previous + 1:].any():
            raise _Spread(previous + 1 + int(np.argmax(skipped[previous + 1:])))
        fail(source.name, pending[0], source.text[pending[1]:pending[1] + 80], f"statement without '{pending[2]}'")
    return out


class _Spread(Exception):
    """A statement spread over several lines runs into a line read at once (``args[0]``: its number)."""


def _bare(argument):
    """An argument without its optional parts (``\\V:=...``, ``\\WObj:=...``, ``\\NoEOffs``)."""
    return argument.partition("\\")[0].strip()


@dataclasses.dataclass(frozen=True)
class _Run:
    """Motions read at once (``rows`` of `_WrittenMotions`), in program order between the reader's items."""

    rows: np.ndarray


@dataclasses.dataclass(frozen=True)
class _Named:
    """A motion argument naming a point, resolved once the whole module is read."""

    name: str
    line: int
    parameter: bool = False  # a parameter of the routine the motion is in


class _Reader:
    def __init__(self, source, index=0):
        self.source, self.index = source, index  # the module read, and its index among the program's sources
        self.targets, self.items, self.points = [], [], {}
        self.shared = set()  # lower names of the module's points other modules may assign (PERS, VAR, not LOCAL)
        self.companions = {}  # file -> (source index, Source, masked text, {line: (start, end)}) of other modules read
        self.tools, self.frames = dict(PREDEFINED[0]), dict(PREDEFINED[1])
        self.active = {"tool": {"tool0": "tool0"}, "wobj": {"wobj0": "wobj0"}}  # lower name -> key of its value
        self.why = {}  # lower name of a tool or work object -> why its value is known only at run time
        self.wobj_parts = {}  # lower name -> (uframe, oframe)
        self.unset = {}  # lower point name -> why its value is known only at run time
        self.params = set()
        # lower name of a speeddata or num -> (storage, type, value text, line, shared by the controller's tasks:
        # `shared_by_tasks`); None if declared twice
        self.data = {}
        # lower name of a VAR or PERS speeddata or num -> (value, why) a straight-line assignment gave it
        self.in_force = {}
        self.touched = {}  # lower name of a VAR or PERS speeddata or num -> first line of a statement changing it
        self.task = None  # the other modules of the task (`DeclaredElsewhere`): the points they declare and assign
        self.task_data = None  # ... and the speeddata and num they declare or may change (`TaskData`)
        self.scanned = None  # the masked text, `Lines` and runs `scan_data` looked at
        self.motion_spans = SpanTable(MOTION_SPANS)  # the spans of the motions read one by one, in order
        self.protos = []  # Motion of each distinct instruction of motions read at once (`read_at_once`)
        self.steps = []  # what the module does besides moving, in order (`trajcomp.programs.flow`)
        self.routine = None  # the line of the routine (PROC, FUNC, TRAP) the statements read are in; None: none
        self.declared = {}  # routine (its line; None: the module) -> {lower point name: line of its declaration}

    def statement(self, masked, line, start, end):
        """Read the statement at ``start:end`` (line ``line``): a declaration, a motion, an assignment ..."""
        text, original = statement_text(masked, start, end), self.source.text[start:end]
        if (block := grammar.ROUTINE_OPENS.match(text) or grammar.ROUTINE_CLOSES.match(text)) \
                and "MODULE" not in block[1].upper():
            self.routine = line if block.re is grammar.ROUTINE_OPENS else None
        if m := grammar.ROUTINE.match(text):
            # parameters: separated by commas, an optional one introduced by '\' (alternatives by '|')
            self.params = {_WORD.findall(p.split("{")[0])[-1].lower() for p in re.split(r"[,\\|]", m.group(1))
                           if _WORD.findall(p.split("{")[0])}
        if m := grammar.DECLARATION.match(text):
            self.declaration(m, start, line, original)
        elif m := grammar.DECLARATION_WITHOUT_VALUE.match(text):
            for name in re.split(r"\s*,\s*", m.group(1)):
                self.unset[name.lower()] = f"{name} is declared without a value (set at run time, line {line})"
        elif grammar.STARTS_MOTION.match(text) and (m := grammar.INSTRUCTION.match(text)):
            motion, offsets = self.motion(m.group(1), m.group(2), start + m.start(2), line, original)
            self.motion_spans.add(offsets)
            self.items.append(motion)
            return
        elif m := grammar.ASSIGNMENT.match(text):
            self.assignment(m, line, original)
        else:
            self.flow_step(text, line, original)
        self.flow(text, line, original)
        self.items.append(Statement(line, original))

    def flow_step(self, text, line, original):
        """Note a statement that changes the order the module runs in or its speed (`trajcomp.programs.flow.Step`)."""
        if m := grammar.ROUTINE_NAME.match(text):
            self.steps.append(Step("routine", m.group(1), line=line, source=self.index))
            return
        if (m := grammar.LABEL.match(text)) and m.group(1).lower() not in grammar.FLOW_STEPS:  # not DEFAULT:
            self.steps.append(Step("label", m.group(1), line=line, source=self.index))
            return
        if m := grammar.VELSET.pattern.match(text):
            override, why = self.constant(m.group(1).strip(), "num", line, original, "VelSet override")
            top, top_why = self.constant(m.group(2).strip(), "num", line, original, "VelSet max")
            self.steps.append(Step("set", "velset", (override, top, why or top_why), line, self.index))
            return
        if m := grammar.ACCSET.pattern.match(text):
            acc, why = self.constant(m.group(1).strip(), "num", line, original, "AccSet Acc")
            ramp, ramp_why = self.constant(m.group(2).strip(), "num", line, original, "AccSet Ramp")
            fine, fine_why = (100.0, "") if m.group(3) is None else self.constant(
                m.group(3).strip(), "num", line, original, "AccSet \\FinePointRamp")
            self.steps.append(Step("set", "accset", (acc, ramp, fine, why or ramp_why or fine_why), line, self.index))
            return
        if grammar.WAITS.match(text):
            self.steps.append(Step("wait", line=line, source=self.index))
            return
        word = _WORD.match(text.strip())
        if text.strip().startswith("%"):  # a late-bound call: %"name"%;
            self.steps.append(Step("call", "%", "a routine named at run time", line, self.index))
            return
        if word is None:
            return
        kind = grammar.FLOW_STEPS.get(word.group().lower())
        if kind == "if" and word.group().lower() == "if" and not re.search(r"\bTHEN\s*$", text, re.I):
            self.steps.append(Step("if", line=line, source=self.index))  # IF cond instruction; on one line
            inner = re.match(r"^\s*IF\s+.*?\s([A-Za-z]\w*\b[^;]*;)\s*$", text, re.I | re.S)
            if inner:
                self.flow_step(inner.group(1), line, original)
            self.steps.append(Step("endif", line=line, source=self.index))
        elif kind == "jump":
            target = re.match(r"^\s*GOTO\s+(\w+)", text, re.I)
            self.steps.append(Step("jump", target.group(1) if target else "", False, line, self.index))
        elif kind is not None:
            self.steps.append(Step(kind, line=line, source=self.index))
        elif (word.group().lower() not in grammar.BUILT_IN and word.group().lower() not in grammar.NOT_CALLS
              and not grammar.STARTS_DECLARATION.match(text) and re.match(r"^\s*[A-Za-z]\w*\s*(;|\s|\\)", text)):
            self.steps.append(Step("call", word.group(), "a routine of another module of the task, which may move "
                                                         "the arm and set speeds", line, self.index))

    def read_at_once(self, points, motions, is_motion, rows, first_inline):
        """Take lines read at once (in program order; ``rows`` of ``points`` or, where ``is_motion``, of
        ``motions``): the points and inline targets become targets (rows of the table of both, the inline
        ones from row ``first_inline``); the motions a `_Run`, read with the state in force here.

        Each distinct text of the motions' instructions (but their points) is
        read once, by `motion` on its first line: what it states (speed,
        zone, tool, work object, or why one is known at run time only) is
        that of each motion writing it.
        """
        for at in np.split(np.arange(len(rows)), np.flatnonzero(np.diff(is_motion)) + 1) if len(rows) else ():
            part = rows[at]  # a run of points, or of motions, in program order (rows of two tables: not sorted)
            if not is_motion[at[0]]:
                self.points_at_once(points, part)
                continue
            inline = part[motions.inline[part] >= 0]  # their inline targets, in order
            motions.target[inline] = len(self.targets) + np.arange(len(inline))
            self.targets.extend((first_inline + motions.inline[inline]).tolist())
        run = rows[is_motion]
        if not len(run):
            return
        codes, first = np.unique(motions.combo[run], return_index=True)
        proto = np.empty(codes.max() + 1, dtype=int)
        for code, row in sorted(zip(codes.tolist(), run[first].tolist()), key=lambda pair: pair[1]):
            start, end = int(motions.start[row]), int(motions.end[row])
            original = self.source.text[start:end]  # no comment or string inside: as masked
            m = grammar.INSTRUCTION.match(original)
            count = len(self.targets)
            motion, _ = self.motion(m.group(1), m.group(2), start + m.start(2), int(motions.line[row]), original)
            del self.targets[count:]  # an inline target read again: the motions' own are taken above
            proto[code] = len(self.protos)
            self.protos.append(motion)
        motions.proto[run] = proto[motions.combo[run]]
        if self.params:
            motions.parameter[run] = [self.source.text[a:b].lower() in self.params
                                      for a, b in motions.name[run].tolist()]
        self.items.append(_Run(run))

    def points_at_once(self, points, rows):
        """Add points ``rows`` (K,) of ``points`` (`_WrittenPoints`) as targets, in order (a name declared twice in a
        scope refused: `once`)."""
        if not len(rows):
            return
        keys = _lowered(self.source.text, points.table.name.start[rows], points.table.name.end[rows])
        self.once(keys, points.line[rows])
        first = len(self.targets)
        self.points.update(zip(keys, range(first, first + len(keys))))
        self.targets.extend(rows.tolist())  # rows of the table
        self.shared.update(key for key, shared in zip(keys, points.shared[rows].tolist()) if shared)

    def once(self, keys, lines):
        """Refuse points ``keys`` (lower names) declared at ``lines`` where the module, or the routine the reader is
        in, declares one of them already, whatever the case (``p3``, ``P3``: RAPID is not case-sensitive), as the
        controller refuses to load such a module."""
        declared = self.declared.setdefault(self.routine, {})  # lower name -> line of its declaration
        new = dict(zip(keys, np.asarray(lines).tolist()))
        if len(new) == len(keys) and declared.keys().isdisjoint(new):
            declared.update(new)
            return
        for key, line in zip(keys, np.asarray(lines).tolist()):
            if key in declared:
                text = self.source.text.splitlines()[line - 1]
                name = re.search(rf"\b{re.escape(key)}\b", text, re.I)
                where = "a module" if self.routine is None else "a routine"
                fail(self.source.name, line, text, f"{name.group() if name else key} is declared again (first at "
                                                   f"line {declared[key]}): {where} declares a name once")
            declared[key] = line

    def scan_data(self, masked, lines, runs):
        """Note the module's speeddata and num declarations (a motion may use one declared further down), and
        where a statement other than its declaration and motions may change a VAR or PERS speeddata or num
        (``lines``: the module's `Lines`; ``runs``: the offsets of the text between the lines read at once,
        `_runs_between`, which only declare points or use a speeddata)."""
        self.scanned = masked, lines, runs
        if not _declares_data(masked):  # a CAM module declares none: its lines are not tried
            return
        for m in (m for start, end in runs for m in _line_matches(grammar.SPEED_DECLARATION, masked, start, end)):
            key = m.group(3).lower()
            entry = (m.group(1).upper(), m.group(2).lower(), (m.group(4) or "").strip(), lines.number(m.start(1)),
                     shared_by_tasks(m))
            self.data[key] = entry if key not in self.data else None
        for key, entry in self.data.items():
            if entry is not None and entry[0] in VARIABLE and (line := changed_at(masked, lines, key, runs)):
                self.touched[key] = line

    def flow(self, text, line, original):
        """Follow the VAR and PERS speeddata and num a statement (not a motion) gives a value or may change.

        An assignment of a literal (or a constant) is in force for the
        motions after it while the code runs straight: a routine's start, a
        branch, a loop, a label or any instruction but those of `grammar.STRAIGHT`
        (a routine call may change it) ends it.
        """
        if not self.touched:
            return
        if m := grammar.ASSIGNMENT.match(text):
            key = m.group(1).lower()
            if key in self.touched:
                self.in_force[key] = (None, f"{m.group(1)} is changed at run time (line {line})") if m.group(2) \
                    else self.constant(m.group(3).strip(), self.data[key][1], line, original, m.group(1))
            return
        word = _WORD.match(text.strip())
        if word and word.group().lower() not in grammar.STRAIGHT and not grammar.STARTS_DECLARATION.match(text):
            self.in_force.clear()

    def constant(self, name, typ, line, original, field, depth=0):
        """``(value, why)`` of a speeddata (its v_tcp, v_ori and v_leax: mm/s, deg/s, mm/s, v_leax None when not a
        number) or num named ``name``: stated, or why it is not.

        Stated: a literal, ``vN``, ``vmax``, a CONST of this module whose
        value is one of these, a VAR or PERS speeddata or num where its value
        is known (`variable`), or one of these another module of the task
        declares (`declared_elsewhere`). Routine parameters, other VAR and
        PERS data and data declared nowhere are set at run time: value None.
        """
        if typ == "num" and _NUMBER.fullmatch(name):
            return self.number(name, line, original, field), ""
        if typ == "speeddata" and (m := grammar.PREDEFINED_SPEED.match(name)):
            return (self.number(m.group(1), line, original, field), PREDEFINED_V_ORI, PREDEFINED_V_LEAX), ""
        if typ == "speeddata" and (m := grammar.SPEEDDATA_VALUE.match(name)):
            v_leax = None if m.group(3) is None else self.number(m.group(3), line, original, field)
            return (self.number(m.group(1), line, original, field), self.number(m.group(2), line, original, field),
                    v_leax), ""
        if typ == "speeddata" and name.lower() == "vmax":
            return (VMAX, PREDEFINED_V_ORI, PREDEFINED_V_LEAX), ""
        key = name.lower()
        if key in self.params:
            return None, f"{name}: routine parameter, set at run time"
        if not _NAME.match(name):
            return None, f"{field} {name}: computed at run time"
        if key not in self.data:
            return self.declared_elsewhere(name, typ, original, field, depth)
        entry = self.data[key]
        if entry is None:
            return None, f"{name}: declared more than once in this module, which one applies is known at run time"
        storage, declared, value, at, shared = entry
        if storage in VARIABLE and declared == typ:
            return self.variable(name, storage, declared, value, at, shared, original, field, depth)
        if storage != "CONST":
            return None, f"{name}: {storage} {declared}, set at run time (line {at})"
        if declared != typ or depth > 8 or not value:
            return None, f"{name}: {declared} {value}, known at run time (line {at})"
        return self.constant(value, typ, at, original, field, depth + 1)

    def variable(self, name, storage, typ, value, at, shared, original, field, depth):
        """``(value, why)`` of VAR or PERS (``storage``) speeddata or num (``typ``) ``name``, declared at line
        ``at`` with ``value`` (``shared``: a PERS every task of the controller shares, `shared_by_tasks`), where a
        motion or a speed setting uses it.

        Known: the value a straight-line assignment before the motion gave it
        (`flow`), or its declared value if no statement of the module, and
        none of another module of the task, may change it (only motions use
        it; `task_data.may_change`): a VAR's value as the program starts, a
        PERS's as declared, since nothing gives it another (a PERS another
        module declares too starts at the value of the module loaded
        first: set at run time). A PERS shared by the controller's tasks
        (not TASK nor LOCAL) holds its declared value only where none of
        the other tasks may change it, which is known only when they are
        all read, in a backup (`TaskData.other_tasks_change`). Else set at
        run time.
        """
        key = name.lower()
        if key in self.in_force:
            return self.in_force[key]
        if key in self.touched:
            return None, (f"{name}: {storage} {typ} the module changes (line {self.touched[key]}) and does not "
                          "assign a literal in the code running straight to this motion: set at run time")
        elsewhere = self.task_data.changed(key) if self.task_data is not None else ""
        if elsewhere or not value:
            return None, f"{name}: {storage} {typ}, set at run time ({elsewhere or f'declared at line {at}'})"
        if storage == "PERS" and self.task_data is not None and (again := self.task_data.declared(key)):
            return None, (f"{name}: PERS {typ} also declared in {again[0][0].name}:{again[0][1]}: its value is "
                          "that of the module loaded first, set at run time")
        if storage == "PERS" and (why := self.pers_changed(key, value, shared)):
            return None, f"{name}: PERS {typ}, set at run time: {why}"
        return self.constant(value, typ, at, original, field, depth + 1)

    def pers_changed(self, key, value, shared):
        """Why PERS ``key`` (made to be shared), declared with ``value``, may hold another value than that as the
        program runs though no statement of its task names it so, or ``""``: the task calls a routine no module
        of it declares (`TaskData.unknown_call`), or, ``shared`` by the controller's tasks (`shared_by_tasks`),
        another task may change it (`TaskData.other_tasks_change`)."""
        if self.task_data is None:
            return ""
        if called := self.task_data.unknown_call(*self.scanned[:2]) if self.scanned else "":
            return f"{called} calls a routine no module of the task declares, which may change it"
        return self.task_data.other_tasks_change(key, value) if shared else ""

    def declared_elsewhere(self, name, typ, original, field, depth):
        """``(value, why)`` of a speeddata or num ``name`` this module does not declare, as another module of its task
        declares it (`TaskData.declared`): a CONST, or a VAR or PERS no module changes, whose value is
        stated (a literal, ``vN``, ``vmax``: a name in it would be looked up in that module). Else set at run time.
        """
        key = name.lower()
        found = self.task_data.declared(key) if self.task_data is not None else []
        if not found:
            return None, f"{name}: {typ} not declared in this module, set at run time"
        file, at, storage, declared, value, shared = found[0]
        where = f"{file.name}:{at}"
        if len(found) > 1:
            return None, f"{name}: declared in {where} and {found[1][0].name}:{found[1][1]}, set at run time"
        if not value:
            return None, f"{name}: {storage} {declared} declared without a value in {where}, set at run time"
        if declared != typ or depth > 8 or _NAME.match(value) and not (
                typ == "speeddata" and (grammar.PREDEFINED_SPEED.match(value) or value.lower() == "vmax")):
            return None, f"{name}: {storage} {declared} {value} of {where}, known at run time"
        if storage != "CONST":
            changed = changed_at(*self.scanned[:2], key, self.scanned[2]) if self.scanned else 0
            if changed:
                return None, f"{name}: {storage} {declared} of {where}, set at run time (changed at line {changed})"
            if elsewhere := self.task_data.changed(key):
                return None, f"{name}: {storage} {declared} of {where}, set at run time ({elsewhere})"
            if storage == "PERS" and (why := self.pers_changed(key, value, shared)):
                return None, f"{name}: PERS {declared} of {where}, set at run time: {why}"
        return self.constant(value, typ, at, original, f"{field} ({where})", depth + 1)

    def number(self, text, line, original, field, limit=LENGTH_LIMIT):
        return finite(text, self.source.name, line, original, field, limit)

    def literal(self, kind, text, offset, name, line, original):
        """A Target from a robtarget or jointtarget literal starting at ``offset``."""
        label = name or kind
        if kind == "jointtarget":
            m = grammar.JOINTTARGET_VALUE.match(text)
            if not m:
                fail(self.source.name, line, original, "malformed jointtarget")
            joints = np.radians([self.number(m.group(k), line, original, f"{label} joint {k}", JOINT_LIMIT)
                                 for k in range(1, 7)])
            return Target(name=name, line=line, joints=joints, spans=spans(self.index, m, JOINTS, offset),
                          external=self.external(m, 7, line, original, label))
        m = grammar.ROBTARGET_VALUE.match(text)
        if not m:
            fail(self.source.name, line, original, "malformed robtarget")
        values = np.array([self.number(m.group(k), line, original, f"{label} {r}")
                           for k, r in enumerate(POSITION + QUAT, start=1)])
        self.check_quaternion(values[3:], line, original, label)
        config = tuple(integer(m.group(k), self.source.name, line, original, f"{label} confdata {c}")
                       for k, c in zip(range(8, 12), CONF))
        return Target(name=name, line=line, pose=pose(values), config=config,
                      spans=spans(self.index, m, POSITION + QUAT + CONF, offset),
                      external=self.external(m, 12, line, original, label))

    def check_quaternion(self, quat, line, original, label):
        norm = np.linalg.norm(quat)
        if abs(norm - 1.0) > QUAT_TOLERANCE:
            fail(self.source.name, line, original, f"{label}: quaternion of length {norm:.4g}, not a rotation")

    def external(self, m, first, line, original, label):
        """External axes eax_a..eax_f, NaN where unused (9E9); None if all are unused."""
        values = np.array([self.number(m.group(k), line, original, f"{label} extax {e}", 1e10)
                           for k, e in zip(range(first, first + 6), EXTAX)])
        values[np.abs(values) >= UNUSED_AXIS] = np.nan
        return None if np.isnan(values).all() else values

    def frame_values(self, kind, d, line, original, name):
        """The pose numbers of a tooldata (tframe) or wobjdata (uframe, oframe) match, checked."""
        groups = d.groups()[-7 * (1 if kind == "tooldata" else 2):]  # x, y, z, q1 .. q4 of its tframe, uframe, oframe
        numbers = [self.number(g, line, original, f"{name} {kind}") for g in groups]
        for start in range(0, len(numbers), 7):
            self.check_quaternion(numbers[start + 3:start + 7], line, original, name)
        return numbers

    def point(self, name, target, original):
        """Add a point the module declares (``original``: its declaration, whose storage says whether other
        modules may assign it: PERS or VAR, not LOCAL)."""
        storage = grammar.STORAGE.match(original)
        if storage and storage.group(2).upper() != "CONST" and "LOCAL" not in storage.group(1).upper():
            self.shared.add(name.lower())
        self.once([name.lower()], [target.line])
        self.points[name.lower()] = len(self.targets)
        self.targets.append(target)

    def declaration(self, m, start, line, original):
        kind, name, value = m.group(1).lower(), m.group(2), m.group(3)
        offset = start + m.start(3)
        if kind in ("robtarget", "jointtarget"):
            self.point(name, self.literal(kind, value, offset, name, line, original), original)
            return
        pattern = grammar.TOOLDATA_VALUE if kind == "tooldata" else grammar.WOBJDATA_VALUE
        d = pattern.match(value)
        if not d:
            fail(self.source.name, line, original, f"malformed {kind}")
        numbers = self.frame_values(kind, d, line, original, name)
        group = "tool" if kind == "tooldata" else "wobj"
        if (d.group(1).upper() == "TRUE") != (kind == "tooldata"):
            what = "stationary tool (robhold FALSE)" if kind == "tooldata" else "robot-held work object"
            self.why[name.lower()] = f"{name}: {what}, not supported"
            return
        self.active[group][name.lower()] = name
        if kind == "tooldata":
            self.tools[name] = pose(numbers)
        else:
            self.wobj_parts[name.lower()] = (pose(numbers[:7]), pose(numbers[7:]))
            self.frames[name] = self.wobj_parts[name.lower()][0] @ self.wobj_parts[name.lower()][1]

    def assignment(self, m, line, original):
        """``tool.tframe := [..]``, ``wobj.uframe := [..]``: a new value from here on; other assignments at run time."""
        name, key = m.group(1), m.group(1).lower()
        field, value = m.group(2).lower(), m.group(3)
        literal = grammar.POSE_VALUE.match(value)
        if key in self.active["tool"] and key != "tool0":
            if field == ".tframe" and literal:
                numbers = [self.number(g, line, original, name) for g in literal.groups()]
                self.check_quaternion(numbers[3:], line, original, name)
                self.tools[f"{name} line {line}"] = pose(numbers)
                self.active["tool"][key] = f"{name} line {line}"
                self.why.pop(key, None)
            else:
                self.why[key] = f"{name} is changed at run time (line {line})"
        elif key in self.active["wobj"] and key != "wobj0":
            parts = self.wobj_parts.get(key)
            if field in (".uframe", ".oframe") and literal and parts is not None:
                numbers = [self.number(g, line, original, name) for g in literal.groups()]
                self.check_quaternion(numbers[3:], line, original, name)
                parts = (pose(numbers), parts[1]) if field == ".uframe" else (parts[0], pose(numbers))
                self.wobj_parts[key] = parts
                self.frames[f"{name} line {line}"] = parts[0] @ parts[1]
                self.active["wobj"][key] = f"{name} line {line}"
                self.why.pop(key, None)
            else:
                self.why[key] = f"{name} is changed at run time (line {line})"

    def position(self, piece, start, joints, line, original):
        """Target index of an inline literal (a jointtarget where ``joints``), `_Named` for a name, None for an
        expression."""
        text = _bare(piece)
        if text.startswith("["):
            shift = start + len(piece) - len(piece.lstrip())
            self.targets.append(self.literal("jointtarget" if joints else "robtarget",
                                             text, shift, "", line, original))
            return len(self.targets) - 1
        return _Named(text, line, text.lower() in self.params) if _NAME.match(text) else None

    def frame_name(self, group, text, line):
        """(key of the tool or work object named ``text``, why it is known only at run time)."""
        if not _NAME.match(text):
            return text, f"{group} {text} computed at run time"
        key = text.lower()
        return self.active[group].get(key, text), self.why.get(key, "")

    def motion(self, instruction, rest, start, line, original):
        """The `Motion` of an instruction (its points: target indices or `_Named`) and its spans' offsets
        ``{role: (start, end)}`` (`MOTION_SPANS`)."""
        read = grammar.MOTIONS.get(instruction.upper())
        text = " ".join(original.split())
        if read is None:
            return Motion(kind=LINEAR, line=line, text=text,
                          reason=f"{instruction}: instruction not read by trajcomp, left as written"), {}
        kind, count = read.kind, read.points
        pieces = split_top(rest, start)
        options = {k.lower(): (v or "").strip() for p, _ in pieces for k, v in grammar.OPTION.findall(p)
                   if k.lower() in grammar.MOTION_OPTIONS}
        positional = [(p, s) for p, s in pieces if not p.strip().startswith("\\")]
        tool_at = len(positional) - 1 if read.tool_last else count + 2
        if len(positional) < count + 3 or tool_at >= len(positional):
            fail(self.source.name, line, original, f"{instruction} needs {count + 3} arguments")
        found = [self.position(p, s, read.joints, line, original) for p, s in positional[:count]]
        roles = ("via_name", "target_name")[2 - count:]
        offsets = (  # where re-timing writes, the points' names (`trajcomp.formats.uses`)
            {"speed": _stripped_offsets(*positional[count])}
            | {role: name_offsets(p, s) for role, (p, s), point in zip(roles, positional, found)
               if isinstance(point, _Named)})
        speed_text = _bare(positional[count][0])
        zones = [_bare(p) for p, _ in positional[count + 1:tool_at + 1] if grammar.PREDEFINED_ZONE.match(_bare(p))]
        tool, tool_why = self.frame_name("tool", _bare(positional[tool_at][0]), line)
        frame, frame_why = self.frame_name("wobj", options.get("wobj", "wobj0"), line)
        reason = "" if None not in found else (
            "position computed at run time: " + " ".join(positional[found.index(None)][0].split()))
        data, speed_why = self.constant(speed_text, "speeddata", line, original, "speed")
        (speed, orientation, external), speed_unit = data or (None, None, None), "mm/s"
        if options.get("v"):  # \V:= the TCP speed, in place of the speeddata's (its v_ori and v_leax stay)
            speed, speed_why = self.constant(options["v"], "num", line, original, "\\V")
        if options.get("t"):  # \T:= the motion's time: the speeds are not used
            (speed, speed_why), speed_unit = self.constant(options["t"], "num", line, original, "\\T"), "s"
            orientation = external = None
        return Motion(
            kind=kind,
            target=found[-1],
            via=found[0] if kind == CIRCULAR else None,
            speed=speed,
            speed_unit=speed_unit,
            zone=self.zone(options.get("z"), zones, line, original),
            tool=tool,
            frame=frame,
            line=line,
            text=text,
            reason=reason or tool_why or frame_why,
            speed_why=speed_why,
            orientation_speed=float(np.radians(orientation)) if orientation else None,
            external_speed=external,
        ), offsets

    def declared_in(self, file, line):
        """The declaration another module of the task makes at ``file``:``line`` (a point, a tool or a work
        object), read by a `_Reader` of that module; None if it is declared without a value.

        The module is read once, as a companion source (`Source`): a point
        is corrected there, for every module that uses it.
        """
        if file not in self.companions:
            source = read_source(file, companion=True)
            masked = mask(source.text, "!")
            statements = {number: (start, end) for number, start, end in _statements(source, masked)}
            self.companions[file] = (self.index + len(self.companions) + 1, source, masked, statements)
        index, source, masked, statements = self.companions[file]
        start, end = statements[line]
        m = grammar.DECLARATION.match(masked[start:end])
        if m is None:
            return None
        module = _Reader(source, index)
        module.declaration(m, start, line, source.text[start:end])
        return module

    def point_in(self, file, line):
        """Target index of the point another module declares at ``file``:``line``, or why it is known only at
        run time (declared without a value)."""
        module = self.declared_in(file, line)
        if module is None:
            return f"{Path(file).name}:{line} declares it without a value (set at run time)"
        self.targets.append(module.targets[-1])
        return len(self.targets) - 1

    def frame_in(self, file, line, name, group):
        """The tool (``group`` "tool") or work object another module declares at ``file``:``line``: its name as
        declared, and why its value is known only at run time (``""`` if it is not)."""
        module = self.declared_in(file, line)
        if module is None:
            return name, f"{name}: {Path(file).name}:{line} declares it without a value (set at run time)"
        self.tools |= module.tools
        self.frames |= module.frames
        declared = module.active[group].get(name.lower())
        return (declared, "") if declared else (name, module.why.get(name.lower(), ""))

    def zone(self, option, zones, line, original):
        """mm of ``\\Z:=`` or ``zN``; None for fine or zonedata the module names."""
        if option and _NUMBER.fullmatch(option):
            return self.number(option, line, original, "\\Z") or None
        m = grammar.PREDEFINED_ZONE.match(zones[0]) if zones else None
        if m is None or m.group(2) is None:
            return None
        return self.number(m.group(2), line, original, "zone") or None


def _stripped_offsets(piece, at):
    """``(start, end)`` of an argument without its surrounding white space (the speed data and its \\V / \\T)."""
    start = at + len(piece) - len(piece.lstrip())
    return start, start + len(piece.strip())


def read(path):
    """Read a RAPID module, its motions as the controller runs them (`trajcomp.programs.flow`: PROC calls, IF,
    TEST, WHILE, FOR, GOTO, waits; VelSet's override and max on every motion they can reach, `_flow_speeds`).

    Raises
    ------
    ReadError
        Malformed text, numbers out of range, a quaternion that is not a
        rotation, or motions to points the module does not declare.
    """
    program, steps = _read(path)
    return flow.program_followed(program, steps, {"velset": (100.0, VMAX, ""), "accset": (100.0, 100.0, 100.0, "")},
                                 _flow_speeds, settings=True)


def _flow_speeds(table, reached):
    """A RAPID module's speed columns under the VelSet that can reach each motion (`trajcomp.programs.flow`).

    VelSet override, max runs a motion's TCP, orientation and linear
    external axes' speeds (v_tcp, v_ori, v_leax) at override % and its
    TCP speed at most max mm/s, and a ``\\T`` at 100 / override times as
    long, whatever the max: the controller does not
    hold a motion with a stated time to VelSet's max (RAPID reference,
    VelSet's limitations), so a time is read and written as such (a time
    written for a motion without one is at least its length over the max,
    the speed read here). Several VelSets
    reaching a motion: the lowest override and max; one set at run time:
    the motion's speed is so (left as written).

    AccSet acc, ramp [\\FinePointRamp:=f] runs the motion's accelerations
    at acc % of the arm's (the lowest of those reaching it:
    ``acceleration_share``); a ramp below 100 % (f for a motion to a fine
    point) only softens how fast they build up (the jerk): a speed (a
    line's speed data, ``\\V``) cruises at it behind softer ramps, never
    faster, so the motion is timed as at 100 %; a time (``\\T``) would be
    kept by cruising faster, which ``time_why`` says: the write-back, which
    knows what it would write, leaves such a field as written and lists it.
    """
    speed = np.array(table.speed, dtype=float)
    orientation = np.array(table.orientation_speed, dtype=float)
    external = np.array(table.external_speed, dtype=float)
    why, time_why = np.array(table.speed_why, dtype=object), np.array(table.time_why, dtype=object)
    share = np.full(len(table), np.nan)
    for r, settings in enumerate(reached.settings):
        rows = np.arange(len(table))[reached.rows(r)]
        rows = rows[why[rows] == ""]  # a speed data set at run time: left as written anyway
        velsets, accsets = settings["velset"], settings["accset"]
        unknown = [f"{name}: {v.why if isinstance(v, Unknown) else v[-1]}"
                   for name, found in (("VelSet", velsets), ("AccSet", accsets))
                   for v in found if isinstance(v, Unknown) or v[-1]]
        if unknown:
            why[rows] = unknown[0]
            continue
        acc, ramp = min(v[0] for v in accsets), min(v[1] for v in accsets)
        ramp = np.where(np.isnan(table.zone[rows]), min(ramp, min(v[2] for v in accsets)), ramp)
        time_why[rows[ramp < 100.0]] = [f"AccSet ramp {r:g} %: softer ramps, which the controller would make up for "
                                         "by cruising faster to keep a time" for r in ramp[ramp < 100.0]]
        if acc < 100.0:
            share[rows] = acc / 100.0
        override, top = min(v[0] for v in velsets) / 100.0, min(v[1] for v in velsets)
        timed = table.speed_unit[rows] == "s"
        speed[rows[timed]] /= override
        paced = rows[~timed]
        tcp = np.where(np.isnan(speed[paced]), VMAX, speed[paced])
        speed[paced] = np.where((override < 1.0) | (top < tcp), np.minimum(tcp * override, top), speed[paced])
        orientation[paced] *= override
        external[paced] *= override
    return {"speed": speed, "orientation_speed": orientation, "external_speed": external, "speed_why": why,
            "acceleration_share": share, "time_why": time_why}


def _read(path):
    """The module (`read`) in file order, and its flow steps."""
    source = read_source(path)
    masked = mask(source.text, "!")
    module = grammar.MODULE.search(masked)
    if not module:
        raise ReadError(f"{path}: not a RAPID module: no MODULE line")
    folders, other_tasks = task_folders(path)
    modules = (".mod", ".modx", ".sys", ".prg")
    lines, excluded, codes = Lines(source.text), set(), text_codes(masked)
    while True:  # a statement spread over lines that look read-at-once takes them back (`_Spread`): rare
        reader = _Reader(source)
        reader.task = DeclaredElsewhere(Path(path), folders, modules, grammar.TASK_POINT, "!", assignment=grammar.ASSIGNED)
        reader.task_data = TaskData(path, folders, modules, other_tasks)
        found_points, named, inline = _written_lines(masked, codes, lines, excluded)
        runs = _runs_between(masked, (found_points, named, inline))
        if not excluded:  # first: the module's blocks closed, checked where they may open or close
            _check_blocks(source, masked, runs)
        reader.scan_data(masked, lines, runs)
        points = _WrittenPoints(source, masked, lines, codes, found_points)
        motions = _WrittenMotions(source.text, masked, lines, codes, named, inline)
        skipped = np.zeros(len(lines.starts) + 1, dtype=bool)
        skipped[points.line] = True
        skipped[motions.line] = True
        try:
            statements = _statements(source, masked, lines, skipped)
            break
        except _Spread as spread:
            excluded.add(spread.args[0])
    bulk = np.concatenate([points.line, motions.line])
    order = np.argsort(bulk, kind="stable")
    at_once, is_motion = bulk[order], order >= len(points.line)
    row_of = np.where(is_motion, order - len(points.line), order)  # row of points / motions
    table = _stacked(points.table, motions.table)  # the points then the inline targets read at once
    first_inline = 0 if points.table is None else len(points.table)  # row of `table` of the first inline target
    next_bulk = 0
    for line, start, end in statements + [(len(lines.starts) + 1, len(source.text), len(source.text))]:
        stop = int(np.searchsorted(at_once, line))
        if stop > next_bulk:  # the lines read at once before this statement: points, then runs of motions
            reader.read_at_once(points, motions, is_motion[next_bulk:stop], row_of[next_bulk:stop], first_inline)
            next_bulk = stop
        if start == len(source.text):
            break
        reader.statement(masked, line, start, end)
    items = _resolve(reader, reader.task, DeclaredElsewhere(Path(path), folders, modules, grammar.TASK_FRAME, "!"), motions)
    companions = tuple(source for _, source, _, _ in reader.companions.values())
    sources = (source, *companions)
    if table is None and not len(motions):  # nothing read at once: the program of objects
        return Program("rapid", module.group(1), items[0], tuple(reader.targets), reader.tools, reader.frames,
                       sources), reader.steps
    objects, bulk_motions = items
    statement_table = StatementTable(points.line, TextSlices(source.text, points.start, points.end))
    motion_table = MotionTable.merged([MotionTable.of([item for item in objects if isinstance(item, Motion)]),
                                       bulk_motions])
    statements = StatementTable.merged([[item for item in objects if isinstance(item, Statement)], statement_table])
    targets = _targets(reader.targets, table)
    if isinstance(targets, TargetTable):
        return Program.from_tables("rapid", module.group(1), statements, motion_table, targets, sources,
                                   tools=reader.tools, frames=reader.frames), reader.steps
    return Program("rapid", module.group(1), ItemRows(statements, motion_table), targets, reader.tools, reader.frames,
                   sources), reader.steps
def _resolve(reader, task, frames, motions):
    """The items with named points resolved; points assigned at run time and routine arguments found.

    A point another module of the task declares (``task``, `DeclaredElsewhere`)
    is read from that module (`_Reader.point_in`) unless some module
    assigns it; so is one of the module's own PERS or VAR points that
    another module assigns. So are tools and work objects another module
    declares (``frames``).

    Returns
    -------
    items : tuple of Motion and Statement
        Those read one by one.
    motions : MotionTable
        Those read at once (``motions``, `_WrittenMotions`).
    """
    assigned = {}
    for item in reader.items:
        if isinstance(item, Statement) and (m := grammar.ASSIGNMENT.match(code_of(item.text, "!"))):
            assigned.setdefault(m.group(1).lower(), f"line {item.line}")
    missing = []

    def lookup(ref):
        if not isinstance(ref, _Named):
            return ref, ""
        key = ref.name.lower()
        if ref.parameter:
            return None, f"{ref.name}: routine parameter, known at run time"
        if key not in reader.points and key not in reader.unset and (found := task.find(key)):
            declared = reader.point_in(*found)
            if isinstance(declared, str):
                reader.unset[key] = f"{ref.name}: {declared}"
            else:
                reader.points[key] = declared
                reader.shared.add(key)
        if key in reader.points:
            if changed := assigned.get(key) or (task.assigned(key) if key in reader.shared else ""):
                return None, f"{ref.name} is changed at run time ({changed})"
            return reader.points[key], ""
        if key in reader.unset:
            return None, reader.unset[key]
        missing.append((ref.name, ref.line))
        return None, ""

    def named(text):
        words = {w.lower() for w in _WORD.findall(mask(text, "!"))}
        return tuple(reader.points[w] for w in sorted(words) if w in reader.points)

    def elsewhere(name, group):
        """A tool (``group`` "tool") or work object the module uses but does not declare: its name as another
        module declares it, and why its value is known only at run time (some module assigns it)."""
        if name is None or name in (reader.tools if group == "tool" else reader.frames):
            return name, ""
        what = "tool" if group == "tool" else "work object"
        if where := assigned.get(name.lower()) or task.assigned(name.lower()):
            return name, f"{what} {name} is changed at run time ({where})"
        found = frames.find(name.lower())
        return reader.frame_in(*found, name, group) if found else (name, "")

    items = []
    motion_spans = reader.motion_spans.columns(reader.index, reader.source.text)  # the motions' rows, in order
    motion_rows = iter(range(len(motion_spans)))
    bulk_target = np.full(len(motions), -1)
    bulk_reason = np.empty(len(motions), dtype=object)
    refs, frames_of = {}, [None] * len(reader.protos)  # ((tool, why), (frame, why)) of each proto
    for item in reader.items:
        if isinstance(item, _Run):  # as a Motion below, without an object each
            _resolve_run(item.rows, motions, reader, lookup, elsewhere, named, frames_of, assigned, bulk_target,
                         bulk_reason, refs)
            continue
        if isinstance(item, Motion):
            (via, via_why), (target, why) = lookup(item.via), lookup(item.target)
            (tool, tool_why), (frame, frame_why) = elsewhere(item.tool, "tool"), elsewhere(item.frame, "wobj")
            item = replaced(item, tool=tool, frame=frame, spans=motion_spans.row(next(motion_rows)))
            reason = via_why or why or item.reason or tool_why or frame_why
            if reason:
                item = dataclasses.replace(item, target=None, via=None, reason=reason, refs=named(item.text)
                                           + tuple(i for i in (via, target) if isinstance(i, int)))
            else:
                item = whole_circle(replaced(item, target=target, via=via))
        elif not grammar.DECLARATION.match(code_of(item.text, "!")) and (names := named(item.text)):
            item = dataclasses.replace(item, refs=names)
        items.append(item)
    if missing:
        unresolved(reader.source.name, missing, "no module of its folder declares them either")
    return tuple(items), _motion_table(reader, motions, bulk_target, bulk_reason, refs, frames_of)


def _resolve_run(rows, motions, reader, lookup, elsewhere, named, frames_of, assigned, target, reason, refs):
    """Resolve the points of motions ``rows`` (K,) of ``motions`` read at once (`_resolve`), in program order.

    A point the module declares, that no statement assigns and other
    modules may not, is taken at once; the others (routine parameters,
    points assigned at run time or declared elsewhere) by ``lookup`` one by
    one, as is each instruction text's (proto's) tool and work object by
    ``elsewhere`` on its first motion. Fills ``target`` (-1 where
    ``reason`` says why not), ``reason`` and ``refs`` at ``rows``, and
    ``frames_of`` at the motions' protos.
    """
    text = reader.source.text
    proto = motions.proto[rows]
    start, end = motions.name[rows].T
    point = start >= 0  # a name; else an inline target, its target index already known
    keys = _lowered(text, start[point], end[point])
    index = motions.target[rows].copy()
    index[point] = list(map(reader.points.get, keys, repeat(-1)))
    one_by_one = np.zeros(len(rows), dtype=bool)
    one_by_one[point] = motions.parameter[rows[point]] | (index[point] < 0)
    if assigned or reader.shared:  # a point that may change at run time
        one_by_one[point] |= np.array([key in assigned or key in reader.shared for key in keys], dtype=bool)
    first_of_proto = np.zeros(len(rows), dtype=bool)
    first_of_proto[np.unique(proto, return_index=True)[1]] = True
    why = np.full(len(rows), "", dtype=object)
    for k in np.flatnonzero(one_by_one | first_of_proto).tolist():  # in program order: the other modules read so
        if one_by_one[k]:
            found, why[k] = lookup(_Named(text[start[k]:end[k]], int(motions.line[rows[k]]),
                                          bool(motions.parameter[rows[k]])))
            index[k] = -1 if found is None else found
        if frames_of[proto[k]] is None:
            frames_of[proto[k]] = (elsewhere(reader.protos[proto[k]].tool, "tool"),
                                   elsewhere(reader.protos[proto[k]].frame, "wobj"))
    protos, of_row = np.unique(proto, return_inverse=True)
    of_proto = np.array([reader.protos[p].reason or frames_of[p][0][1] or frames_of[p][1][1]
                         for p in protos.tolist()], dtype=object)
    reason[rows] = np.where(why != "", why, of_proto[of_row])
    listed = np.flatnonzero(reason[rows] != "")
    for k in listed.tolist():
        row = int(rows[k])
        refs[row] = named(text[motions.start[row]:motions.end[row]]) + ((int(index[k]),) if index[k] >= 0 else ())
    taken = np.ones(len(rows), dtype=bool)
    taken[listed] = False
    target[rows[taken]] = index[taken]


def _lowered(text, start, end):
    """The pieces ``text[start:end]`` (K,) in lower case: list of str (names: no line break)."""
    if not len(start):
        return []
    return "\n".join([text[a:b] for a, b in zip(start.tolist(), end.tolist())]).lower().split("\n")


def _motion_table(reader, motions, target, reason, refs, frames_of):
    """The `MotionTable` of the motions read at once, their points resolved (`_resolve`): ``target`` (M,), -1
    where ``reason`` (M,) says why not; ``refs`` ``{row: target indices}``; ``frames_of`` the tool and work
    object of each proto (`_Reader.read_at_once`)."""
    protos = reader.protos

    def column(values, dtype=object):
        return np.array(values, dtype=dtype)[motions.proto] if protos else np.zeros(0, dtype=dtype)

    def number(value):
        return np.nan if value is None else value

    m, text = len(motions), reader.source.text
    given = np.zeros((m, 3), dtype=bool)
    given[:, 0], given[:, 2] = True, motions.name[:, 0] >= 0  # the speed; a name (none for an inline target)
    offset = offset_type(text)  # the spans as int32 where they fit
    start = np.where(given, np.c_[motions.speed[:, 0], np.zeros(m, dtype=offset), motions.name[:, 0]], -1).astype(offset)
    end = np.where(given, np.c_[motions.speed[:, 1], np.zeros(m, dtype=offset), motions.name[:, 1]], -1).astype(offset)
    return MotionTable(
        kind=column([p.kind for p in protos]), target=target, via=np.full(m, -1),
        speed=column([number(p.speed) for p in protos], float), speed_unit=column([p.speed_unit for p in protos]),
        zone=column([number(p.zone) for p in protos], float),
        tool=column([None if f is None else f[0][0] for f in frames_of]),
        frame=column([None if f is None else f[1][0] for f in frames_of]),
        line=motions.line, axis_position=np.zeros(m, dtype=bool),
        orientation_speed=column([number(p.orientation_speed) for p in protos], float),
        external_speed=column([number(p.external_speed) for p in protos], float),
        source=np.full(m, reader.index), text=_Instructions(text, motions.start, motions.end),
        reason=reason,
        speed_why=column([p.speed_why for p in protos]), refs=refs,
        spans=SpanColumns(reader.index, text, MOTION_SPANS, start, end))


class _Instructions(TextSlices):
    """The instructions of motions given by their offsets, each as `Motion.text` writes it (one line, single
    blanks), built on access."""

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [" ".join(t.split()) for t in super().__getitem__(k)]
        return " ".join(super().__getitem__(k).split())



def _targets(targets, table):
    """The program's targets: ``targets`` in order, each a row of ``table`` (int, a point read at once) or a
    `Target`; as one `TargetTable` when all lie in the module (`joined_targets`), else a tuple of `Target`."""
    joined = joined_targets(targets, table, JOINTS) if table is not None else None
    return joined if joined is not None else tuple(table.target(t) if isinstance(t, int) else t for t in targets)


def _stacked(first, second):
    """One `TargetTable` of the rows of two (either may be None) whose spans are columns of the same text and
    roles (the points and the inline targets read at once)."""
    if first is None or second is None:
        return second if first is None else first

    def joined(a, b):
        return np.concatenate([a, b]) if isinstance(a, np.ndarray) else tuple(a) + tuple(b)

    names = TextSlices(first.name.text, *(np.concatenate([getattr(first.name, k), getattr(second.name, k)])
                                          for k in ("start", "end")))
    spans = SpanColumns(0, first.spans.text, first.spans.roles, np.concatenate([first.spans.start, second.spans.start]),
                        np.concatenate([first.spans.end, second.spans.end]))
    return TargetTable(**{name: joined(getattr(first, name), getattr(second, name)) for name in
                          ("pose", "is_joint", "joints", "line", "config", "tool", "frame", "external", "edited")},
                       name=names, spans=spans)
