"""The column form of a program: its motions and targets as arrays.

`MotionTable` and `TargetTable` hold all motions and targets of a program as
columns (what the pipeline stages read, see `trajcomp.programs.program`), with the
row helpers that keep long columns from being copied (`rows_of`,
`every_row`, `repeated`, `read_only`), `_codes` for object columns, and the
sequences that show a table as `Motion` / `Target` objects built on access
(`TargetRows`, `ItemRows`, `LineLabels`).
"""

import dataclasses
from collections.abc import Sequence

import numpy as np

from trajcomp.programs.items import Motion, SpanColumns, Target

@dataclasses.dataclass(frozen=True, eq=False)
class MotionTable:
    """The motions of a program as arrays over its M motions, in program order.

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

    def __len__(self):
        return len(self.line)

    @classmethod
    def of(cls, motions):
        """The table of `Motion` objects."""
        def column(values, dtype):
            return np.array(values, dtype=dtype).reshape(len(motions))

        def number(value):
            return np.nan if value is None else value

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
        )

    def motion(self, k, text=""):
        """Motion ``k`` as an object (its spans and refs are not kept in the table)."""
        def optional(value, kind):
            return None if (value < 0 if kind is int else np.isnan(value)) else kind(value)

        return Motion(
            kind=self.kind[k], target=optional(self.target[k], int), via=optional(self.via[k], int),
            speed=optional(self.speed[k], float), speed_unit=self.speed_unit[k], zone=optional(self.zone[k], float),
            tool=self.tool[k], frame=self.frame[k], line=int(self.line[k]), text=text,
            axis_position=bool(self.axis_position[k]),
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


class _Rows(Sequence):
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


class TargetRows(_Rows):
    """The targets of a table-backed program: a `TargetTable` seen as a sequence of `Target`."""

    def __init__(self, table):
        super().__init__(len(table), table.target)
        self.table = table


class ItemRows(_Rows):
    """The items of a table-backed program: its statements, and the motions of a `MotionTable`, by line.

    Parameters
    ----------
    statements : sequence of Statement
    motions : MotionTable
    text : callable
        ``text(line) -> str``: the instruction written at a line.
    """

    def __init__(self, statements, motions, text):
        lines = np.concatenate([[s.line for s in statements], motions.line]).astype(int)
        self._order = np.argsort(lines, kind="stable")
        self.statements, self.table, self._text = tuple(statements), motions, text
        super().__init__(len(lines), self._item)
        self.motions = _Rows(len(motions), self._motion)

    def _item(self, k):
        j = self._order[k]
        return self.statements[j] if j < len(self.statements) else self._motion(j - len(self.statements))

    def _motion(self, k):
        return self.table.motion(k, self._text(int(self.table.line[k])))


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


def _codes(values):
    """Integer codes (N,) of hashable values (N,) and the distinct values in first-seen order."""
    values = list(values)
    names = list(dict.fromkeys(values))
    if len(names) <= 1:
        return np.zeros(len(values), dtype=int), names
    lookup = {name: k for k, name in enumerate(names)}
    return np.fromiter(map(lookup.__getitem__, values), dtype=int, count=len(values)), names
