"""The column form of a program: its motions and targets as arrays.

`MotionTable` and `TargetTable` hold all motions and targets of a program as
columns (what the pipeline stages read, see `trajcomp.programs.program`), with the
row helpers that keep long columns from being copied (`rows_of`,
`every_row`, `repeated`, `read_only`), `value_codes` for object columns, and the
sequences that show a table as `Motion` / `Target` objects built on access
(`TargetRows`, `ItemRows`, `LineLabels`).
"""

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np

from trajcomp.programs.items import Motion, SpanColumns, Statement, Target

@dataclasses.dataclass(frozen=True, eq=False)
class MotionTable:
    """The motions of a program as arrays over its M motions, in program order: every field of `Motion`.

    A reader of long programs builds its motions as a table (`block` for
    the rows it reads at once, `of` for the ones it reads one by one,
    `merged` to put them in program order), never an object each; the
    table shows them as `Motion` objects built on access (`motion`).

    Attributes
    ----------
    kind : ndarray of object, shape (M,)
        ``"joint"``, ``"linear"`` or ``"circular"``.
    target, via : ndarray of int, shape (M,)
        Target indices; -1 where the motion has none (run time / no via point).
    speed : ndarray, shape (M,)
        In ``speed_unit``; NaN where the language default applies.
    speed_unit : ndarray of object, shape (M,)
    zone : ndarray, shape (M,)
        Blend radius, mm; NaN for an exact stop.
    tool, frame : ndarray of object, shape (M,)
        Names (None: the robot's tool / the base).
    line : ndarray of int, shape (M,)
    axis_position : ndarray of bool, shape (M,)
    orientation_speed : ndarray, shape (M,)
        Rad/s; NaN where none bounds the motion.
    external_speed : ndarray, shape (M,)
        As `Motion.external_speed`, mm/s; NaN where none bounds the motion.
    acceleration : ndarray, shape (M,)
        As `Motion.acceleration`; NaN where none is stated.
    acceleration_share : ndarray, shape (M,)
        As `Motion.acceleration_share`; NaN where none is stated.
    source : ndarray of int, shape (M,)
        Index of the file each motion is written in.
    text : Sequence of str, length M
        The instructions as written (one line, stripped; built on access where the reader keeps offsets).
    reason, speed_why, start_why, time_why : ndarray of object, shape (M,)
        As `Motion`; ``""`` where none.
    refs : Mapping[int, tuple of int]
        ``{row: target indices}`` of the motions that name targets (`Motion.refs`); the others name none.
    spans : Sequence of Mapping, length M, or None
        Each motion's spans (`Motion.spans`, e.g. `SpanColumns`); None: no motion has any.
    """

    kind: np.ndarray
    target: np.ndarray
    via: np.ndarray
    speed: np.ndarray
    speed_unit: np.ndarray
    zone: np.ndarray
    tool: np.ndarray
    frame: np.ndarray
    line: np.ndarray
    axis_position: np.ndarray
    orientation_speed: np.ndarray = None
    external_speed: np.ndarray = None
    source: np.ndarray = None
    text: Sequence = None
    reason: np.ndarray = None
    speed_why: np.ndarray = None
    refs: Mapping = None
    start_why: np.ndarray = None
    acceleration: np.ndarray = None
    acceleration_share: np.ndarray = None
    spans: Sequence = None
    time_why: np.ndarray = None

    def __post_init__(self):
        m = len(self.line)
        defaults = {"orientation_speed": lambda: np.full(m, np.nan), "external_speed": lambda: np.full(m, np.nan),
                    "source": lambda: np.zeros(m, dtype=int),
                    "text": lambda: repeated("", m), "reason": lambda: repeated("", m),
                    "speed_why": lambda: repeated("", m), "refs": dict, "start_why": lambda: repeated("", m),
                    "time_why": lambda: repeated("", m),
                    "acceleration": lambda: np.broadcast_to(np.nan, (m,)),
                    "acceleration_share": lambda: np.broadcast_to(np.nan, (m,))}
        for name, default in defaults.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, default())

    def __len__(self):
        return len(self.line)

    @classmethod
    def of(cls, motions):
        """The table of `Motion` objects."""
        def column(values, dtype):
            return np.array(values, dtype=dtype).reshape(len(motions))

        def number(value):
            return np.nan if value is None else value

        spans = tuple(m.spans for m in motions)
        return cls(
            kind=column([m.kind for m in motions], object),
            target=column([-1 if m.target is None else m.target for m in motions], int),
            via=column([-1 if m.via is None else m.via for m in motions], int),
            speed=column([number(m.speed) for m in motions], float),
            speed_unit=column([m.speed_unit for m in motions], object),
            zone=column([number(m.zone) for m in motions], float),
            tool=column([m.tool for m in motions], object),
            frame=column([m.frame for m in motions], object),
            line=column([m.line for m in motions], int),
            axis_position=column([m.axis_position for m in motions], bool),
            orientation_speed=column([number(m.orientation_speed) for m in motions], float),
            external_speed=column([number(m.external_speed) for m in motions], float),
            source=column([m.source for m in motions], int),
            text=tuple(m.text for m in motions),
            reason=column([m.reason for m in motions], object),
            speed_why=column([m.speed_why for m in motions], object),
            start_why=column([m.start_why for m in motions], object),
            time_why=column([m.time_why for m in motions], object),
            acceleration=column([number(m.acceleration) for m in motions], float),
            acceleration_share=column([number(m.acceleration_share) for m in motions], float),
            refs={k: m.refs for k, m in enumerate(motions) if m.refs},
            spans=spans if any(spans) else None,
        )

    @classmethod
    def block(cls, kind, target, line, text, *, speed, speed_unit, zone, tool=None, frame=None, spans=None,
              source=0, speed_why=""):
        """The table of M motions a reader read at once: compensable motions of one tool and frame.

        Parameters
        ----------
        kind : str or ndarray of object, shape (M,)
        target : ndarray of int, shape (M,)
            Target indices.
        line : ndarray of int, shape (M,)
        text : Sequence of str, length M
        speed : ndarray, shape (M,)
            NaN where the language default applies.
        speed_unit : str or ndarray of object, shape (M,)
        zone : ndarray, shape (M,)
            Blend radius, mm; NaN for an exact stop.
        tool, frame : str or None
        spans : Sequence of Mapping, length M, optional
        source : int
        speed_why : str or ndarray of object, shape (M,)
        """
        m = len(line)

        def column(value):
            return repeated(value, m) if isinstance(value, str) or value is None else np.asarray(value, dtype=object)

        return cls(
            kind=column(kind), target=np.asarray(target, dtype=int), via=np.full(m, -1),
            speed=np.asarray(speed, dtype=float), speed_unit=column(speed_unit), zone=np.asarray(zone, dtype=float),
            tool=repeated(tool, m), frame=repeated(frame, m), line=np.asarray(line, dtype=int),
            axis_position=np.zeros(m, dtype=bool), source=np.full(m, source), text=text,
            speed_why=column(speed_why), spans=spans,
        )

    @classmethod
    def merged(cls, tables):
        """One table of the rows of several, in program order (by source, then line; stable).

        Object columns that a table holds as a sequence built on access
        (text, spans) stay so: each row is looked up in its table.
        """
        tables = [t for t in tables if len(t)] or tables[:1]
        if len(tables) == 1:
            return tables[0]
        source = np.concatenate([t.source for t in tables])
        line = np.concatenate([t.line for t in tables])
        order = np.lexsort((line, source))
        part = np.repeat(np.arange(len(tables)), [len(t) for t in tables])[order]
        row = np.concatenate([np.arange(len(t)) for t in tables])[order]

        def column(name):
            return np.concatenate([getattr(t, name) for t in tables])[order]

        def sequence(name):
            return Picked([getattr(t, name) for t in tables], part, row)

        new_row = np.empty(len(order), dtype=int)
        new_row[order] = np.arange(len(order))
        offsets = np.cumsum([0] + [len(t) for t in tables])
        refs = {int(new_row[offsets[j] + k]): r for j, t in enumerate(tables) for k, r in t.refs.items()}
        spans = None
        if any(t.spans is not None for t in tables):
            spans = Picked([t.spans if t.spans is not None else repeated({}, len(t)) for t in tables], part, row)
        names = ("kind", "target", "via", "speed", "speed_unit", "zone", "tool", "frame", "axis_position",
                 "orientation_speed", "external_speed", "reason", "speed_why", "start_why", "acceleration",
                 "acceleration_share", "time_why")
        return cls(line=line[order], source=source[order], text=sequence("text"), refs=refs, spans=spans,
                   **{name: column(name) for name in names})

    def with_rows(self, index, **columns):
        """A copy with some columns changed at rows ``index`` (K,): ``target``, ``via``, ``reason`` ... (K,) each;
        ``refs`` a sequence (K,) of tuples, ``spans`` one (K,) of Mappings."""
        index = np.asarray(index, dtype=int)
        changes = {}
        for name, values in columns.items():
            if name == "refs":
                changes[name] = {**self.refs, **{int(k): tuple(r) for k, r in zip(index.tolist(), values)}}
                continue
            if name == "spans":  # each row's spans a Mapping
                spans = list(self.spans) if self.spans is not None else [{}] * len(self)
                for k, row in zip(index.tolist(), values):
                    spans[k] = row
                changes[name] = tuple(spans)
                continue
            column = np.array(getattr(self, name))  # a copy, writeable even of a repeated (read-only) column
            column[index] = values
            changes[name] = column
        return dataclasses.replace(self, **changes)

    def span_offsets(self, role):
        """``(source, start, end)`` (M,) each of the motions' spans of ``role``; -1 where a motion has none.

        Spans held as `SpanColumns` are read as columns, each part of a
        merged table at once (no `Span` object built); other spans one by one.
        """
        out = np.full((3, len(self)), -1, dtype=np.int64)
        if self.spans is None:
            return tuple(out)
        if isinstance(self.spans, Picked):  # a merged table's: each part's rows
            row_of = self.spans.row
            parts = [(spans, np.flatnonzero(self.spans.part == j)) for j, spans in enumerate(self.spans.sequences)]
        else:
            row_of = np.arange(len(self))
            parts = [(self.spans, row_of)]
        for spans, at in parts:
            rows = row_of[at]
            if isinstance(spans, SpanColumns):
                j = spans.column.get(role)
                if j is not None:
                    given = spans.start[rows, j] >= 0
                    at, rows = at[given], rows[given]
                    out[0, at], out[1, at], out[2, at] = spans.source, spans.start[rows, j], spans.end[rows, j]
                continue
            for k, row in zip(at.tolist(), rows.tolist()):
                span = spans[row].get(role)
                if span is not None:
                    out[:, k] = span.source, span.start, span.end
        return tuple(out)

    def motion(self, k):
        """Motion ``k`` as an object."""
        def optional(value, kind):
            return None if (value < 0 if kind is int else np.isnan(value)) else kind(value)

        return Motion(
            kind=self.kind[k], target=optional(self.target[k], int), via=optional(self.via[k], int),
            speed=optional(self.speed[k], float), speed_unit=self.speed_unit[k], zone=optional(self.zone[k], float),
            tool=self.tool[k], frame=self.frame[k], line=int(self.line[k]), text=self.text[k],
            reason=self.reason[k], refs=self.refs.get(k, ()), spans={} if self.spans is None else self.spans[k],
            axis_position=bool(self.axis_position[k]), speed_why=self.speed_why[k], source=int(self.source[k]),
            orientation_speed=optional(self.orientation_speed[k], float), start_why=self.start_why[k],
            external_speed=optional(self.external_speed[k], float),
            acceleration=optional(self.acceleration[k], float),
            acceleration_share=optional(self.acceleration_share[k], float), time_why=self.time_why[k],
        )


@dataclasses.dataclass(frozen=True, eq=False)
class TargetTable:
    """The targets of a program as arrays over its N targets.

    Attributes
    ----------
    pose : ndarray, shape (N, 4, 4)
        T_frame_tcp, mm; NaN for a joint target.
    is_joint : ndarray of bool, shape (N,)
        Joint-space targets (no pose).
    joints : ndarray, shape (N, 6)
        Joints, rad; NaN where the target states none.
    line : ndarray of int, shape (N,)
    config : tuple, length N
        Configuration data (``()`` where none).
    tool, frame : ndarray of object, shape (N,)
        Names the point data state (None: the motion's).
    external : tuple, length N
        External axes (ndarray) or None.
    edited : ndarray of bool, shape (N,)
    name : Sequence of str, length N, or None
        Point names (None: every target is inline, ``""``).
    spans : SpanColumns or None
        Where each target's numbers stand in its source (row k: target k);
        None: the targets have no spans (a CSV's rows).
    """

    pose: np.ndarray
    is_joint: np.ndarray
    joints: np.ndarray
    line: np.ndarray
    config: tuple
    tool: np.ndarray
    frame: np.ndarray
    external: tuple
    edited: np.ndarray
    name: Sequence = None
    spans: SpanColumns = None

    def __len__(self):
        return len(self.line)

    @classmethod
    def of(cls, targets):
        """The table of `Target` objects."""
        n = len(targets)
        nan_pose, nan_joints = np.full((4, 4), np.nan), np.full(6, np.nan)
        return cls(
            pose=np.array([nan_pose if t.pose is None else t.pose for t in targets], dtype=float).reshape(n, 4, 4),
            is_joint=np.array([t.pose is None for t in targets], dtype=bool).reshape(n),
            joints=np.array([nan_joints if t.joints is None else t.joints for t in targets], dtype=float).reshape(n, 6),
            line=np.array([t.line for t in targets], dtype=int).reshape(n),
            config=tuple(t.config for t in targets),
            tool=np.array([t.tool for t in targets], dtype=object).reshape(n),
            frame=np.array([t.frame for t in targets], dtype=object).reshape(n),
            external=tuple(t.external for t in targets),
            edited=np.array([t.edited for t in targets], dtype=bool).reshape(n),
        )

    @classmethod
    def of_rows(cls, pose, joints, line):
        """A table of inline targets in the robot base frame, with the robot's tool (CSV rows).

        Parameters
        ----------
        pose : ndarray, shape (N, 4, 4)
            NaN for joint targets.
        joints : ndarray, shape (N, 6)
            Rad; NaN where none.
        line : ndarray of int, shape (N,)
        """
        n = len(line)
        none = repeated(None, n)
        return cls(pose, np.isnan(pose[:, 0, 0]), joints, np.asarray(line, dtype=int), ((),) * n, none, none,
                   (None,) * n, np.zeros(n, dtype=bool))

    def target(self, i):
        """Target ``i`` as an object."""
        return Target(
            name="" if self.name is None else self.name[i], line=int(self.line[i]),
            pose=None if self.is_joint[i] else self.pose[i],
            joints=None if np.isnan(self.joints[i]).any() else self.joints[i],
            config=self.config[i], tool=self.tool[i], frame=self.frame[i], external=self.external[i],
            edited=bool(self.edited[i]), spans={} if self.spans is None else self.spans.row(i),
        )

    def with_rows(self, index, *, poses=None, joints=None, configs=None):
        """A copy with rows ``index`` replaced and marked edited (see `trajcomp.programs.program.Program.with_targets`)."""
        changes = {"edited": self.edited.copy()}
        changes["edited"][index] = True
        if poses is not None:
            changes["pose"] = _replaced(self.pose, index, poses)
        if joints is not None:
            changes["joints"] = _replaced(self.joints, index, joints)
        if configs is not None:
            config = list(self.config)
            for k, i in enumerate(index):
                config[i] = tuple(configs[k])
            changes["config"] = tuple(config)
        return dataclasses.replace(self, **changes)


def joined_targets(targets, table, roles):
    """One `TargetTable` of a program's targets: rows of a table read at once and a few `Target` read one by one.

    Parameters
    ----------
    targets : sequence of int or Target, length N
        In program order: a row of ``table`` (int) or a `Target` (an axis
        position, a point written otherwise) whose spans lie in the table's source.
    table : TargetTable
        Its spans as `SpanColumns`.
    roles : sequence of str
        The roles of the objects' spans that the table's columns lack (joint values).

    Returns
    -------
    TargetTable or None
        ``table`` itself when ``targets`` are its rows in order; None when a
        target's spans lie in another source (the caller keeps the objects).
    """
    rows = np.array([t if isinstance(t, int) else -1 for t in targets], dtype=int)
    if every_row(rows, len(table)):
        return table
    objects = [t for t in targets if not isinstance(t, int)]
    if any(t.spans and next(iter(t.spans.values())).source != table.spans.source for t in objects):
        return None
    extra = TargetTable.of(objects)
    pick = np.where(rows >= 0, rows, len(table) + np.cumsum(rows < 0) - 1)  # row of [table; extra] of each

    def joined(name):
        values = (getattr(table, name), getattr(extra, name))
        return np.concatenate(values)[pick] if isinstance(values[0], np.ndarray) else \
            tuple(values[0][k] if k < len(table) else values[1][k - len(table)] for k in pick.tolist())

    all_roles = table.spans.roles + tuple(roles)
    start, end = (np.full((len(targets), len(all_roles)), -1, dtype=np.int64) for _ in range(2))
    at_once = np.flatnonzero(rows >= 0)
    start[at_once, :len(table.spans.roles)] = table.spans.start[rows[at_once]]
    end[at_once, :len(table.spans.roles)] = table.spans.end[rows[at_once]]
    column = {role: j for j, role in enumerate(all_roles)}
    for k, target in zip(np.flatnonzero(rows < 0).tolist(), objects):
        for role, span in target.spans.items():
            start[k, column[role]], end[k, column[role]] = span.start, span.end
    part = (pick >= len(table)).astype(int)
    names = repeated("", len(table)) if table.name is None else table.name
    return TargetTable(
        **{name: joined(name) for name in ("pose", "is_joint", "joints", "line", "config", "tool", "frame",
                                           "external", "edited")},
        name=Picked([names, [t.name for t in objects]], part, np.where(part, pick - len(table), pick)),
        spans=SpanColumns(table.spans.source, table.spans.text, all_roles, start, end))


def _replaced(values, index, rows):
    """``values`` (N, ...) with rows ``index`` set to ``rows``: a copy, or ``rows`` itself as a read-only view when
    they replace every row in order (a long program fully compensated: no second copy)."""
    rows = np.asarray(rows, dtype=values.dtype)
    if rows.shape == values.shape and every_row(index, len(values)):
        return read_only(rows)
    out = values.copy()
    out[index] = rows
    return out


def rows_of(values, index):
    """``values[index]``; a read-only view instead of a copy when ``index`` takes every row in order."""
    return read_only(values) if every_row(index, len(values)) else values[index]


def every_row(index, n):
    """Whether ``index`` (K,) takes each of n rows once, in order."""
    return len(index) == n and np.array_equal(index, np.arange(n))


def repeated(value, n):
    """A read-only object array (n,) holding ``value`` n times, in one element's memory (a zero stride)."""
    one = np.empty(1, dtype=object)
    one[0] = value
    return np.broadcast_to(one, (n,))


def read_only(values):
    """A view of an array that cannot be written through (shared data stays as it is)."""
    view = values[:]
    view.flags.writeable = False
    return view


class Rows(Sequence):
    """A sequence whose items are built on access from a table (``build(k)``)."""

    def __init__(self, size, build):
        self._size, self._build = size, build

    def __len__(self):
        return self._size

    def __getitem__(self, k):
        if isinstance(k, slice):
            return tuple(self._build(j) for j in range(*k.indices(self._size)))
        if not -self._size <= k < self._size:
            raise IndexError(k)
        return self._build(k % self._size)


class TargetRows(Rows):
    """The targets of a table-backed program: a `TargetTable` seen as a sequence of `Target`."""

    def __init__(self, table):
        super().__init__(len(table), table.target)
        self.table = table


class StatementTable(Sequence):
    """Statements as columns, each a `Statement` built on access (a long program's declarations).

    Parameters
    ----------
    line : ndarray of int, shape (S,)
    text : Sequence of str, length S
        As written (the whole line).
    source : int or ndarray of int, shape (S,)
    refs : Mapping[int, tuple of int], optional
        ``{row: target indices}`` of the statements naming targets.
    """

    def __init__(self, line, text, source=0, refs=None):
        self.line = np.asarray(line, dtype=int)
        self.text, self.refs = text, refs or {}
        self.source = np.broadcast_to(np.asarray(source, dtype=int), self.line.shape)

    @classmethod
    def of(cls, statements):
        """The table of `Statement` objects (or a `StatementTable` itself)."""
        if isinstance(statements, cls):
            return statements
        return cls([s.line for s in statements], tuple(s.text for s in statements),
                   np.array([s.source for s in statements], dtype=int),
                   {k: s.refs for k, s in enumerate(statements) if s.refs})

    @classmethod
    def merged(cls, parts):
        """One table of several tables' or sequences' statements, in their order (the parts' order)."""
        tables = [cls.of(part) for part in parts]
        sizes = [len(t) for t in tables]
        part, row = np.repeat(np.arange(len(tables)), sizes), np.concatenate([np.arange(n) for n in sizes])
        offsets = np.cumsum([0] + sizes)
        refs = {int(offsets[j] + k): r for j, t in enumerate(tables) for k, r in t.refs.items()}
        return cls(np.concatenate([t.line for t in tables]), Picked([t.text for t in tables], part, row),
                   np.concatenate([t.source for t in tables]), refs)

    def __len__(self):
        return len(self.line)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return tuple(self[j] for j in range(*k.indices(len(self))))
        if not -len(self) <= k < len(self):
            raise IndexError(k)
        k %= len(self)
        return Statement(int(self.line[k]), self.text[k], self.refs.get(k, ()), int(self.source[k]))

    def naming(self):
        """The statements that name targets (`Statement.refs`), in order."""
        return tuple(self[k] for k in sorted(self.refs))


class ItemRows(Rows):
    """The items of a table-backed program: its statements and the motions of a `MotionTable`, in program order
    (by file, then line).

    Parameters
    ----------
    statements : Sequence of Statement
        A `StatementTable` for many.
    motions : MotionTable
    """

    def __init__(self, statements, motions):
        statements = StatementTable.of(statements)
        lines = np.concatenate([statements.line, motions.line]).astype(int)
        sources = np.concatenate([statements.source, motions.source]).astype(int)
        self._order = np.lexsort((lines, sources))
        self.statements, self.table = statements, motions
        super().__init__(len(lines), self._item)
        self.motions = Rows(len(motions), motions.motion)

    def _item(self, k):
        j = self._order[k]
        return self.statements[j] if j < len(self.statements) else self.table.motion(j - len(self.statements))

    def naming(self):
        """The items that name targets (`Statement.refs`, `Motion.refs`), in program order."""
        position = np.empty(len(self._order), dtype=int)
        position[self._order] = np.arange(len(self._order))
        rows = position[np.array([*self.statements.refs, *(len(self.statements) + k for k in self.table.refs)],
                                 dtype=int)]
        return tuple(self[int(k)] for k in np.sort(rows))


class Picked(Sequence):
    """Items picked from several sequences: item k is ``sequences[part[k]][row[k]]`` (merged columns built on access).

    Parameters
    ----------
    sequences : list of Sequence
    part, row : ndarray of int, shape (N,)
    """

    def __init__(self, sequences, part, row):
        self.sequences, self.part, self.row = sequences, part, row

    def __len__(self):
        return len(self.part)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self[j] for j in range(*k.indices(len(self)))]
        return self.sequences[self.part[k]][self.row[k]]


class TextSlices(Sequence):
    """Pieces of a text given by their offsets (N,), each a str built on access (a long program's point names).

    Parameters
    ----------
    text : str
    start, end : ndarray of int, shape (N,)
    """

    def __init__(self, text, start, end):
        self.text, self.start, self.end = text, start, end

    def __len__(self):
        return len(self.start)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self.text[a:b] for a, b in zip(self.start[k].tolist(), self.end[k].tolist())]
        return self.text[self.start[k]:self.end[k]]


class LineLabels(Sequence):
    """Labels ``file:line`` of targets given by their lines (N,), built on access."""

    def __init__(self, source_name, lines):
        self.source_name, self.lines = source_name, np.asarray(lines, dtype=int)

    def __len__(self):
        return len(self.lines)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [f"{self.source_name}:{n}" for n in self.lines[k].tolist()]
        return f"{self.source_name}:{self.lines[k]}"


def value_codes(values):
    """Integer codes (N,) of hashable values (N,) and the distinct values in first-seen order."""
    values = list(values)
    names = list(dict.fromkeys(values))
    if len(names) <= 1:
        return np.zeros(len(values), dtype=int), names
    lookup = {name: k for k, name in enumerate(names)}
    return np.fromiter(map(lookup.__getitem__, values), dtype=int, count=len(values)), names
