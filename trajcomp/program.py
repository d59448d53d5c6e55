"""The robot program model every language maps to.

A `Program` is the ordered list of what the program does -- `Motion` items
and opaque `Statement` items kept in place -- plus its targets: every
Cartesian or joint position the program states, named (KRL .dat points,
RAPID robtarget declarations, FANUC /POS entries, URScript variables) or
inline. Motions refer to targets by index; a motion whose position is
computed at run time (Offs, RelTool, PR[] arithmetic, a procedure parameter,
a tool set at run time, ...) has no target, says why (`Motion.reason`) and
is passed through untouched. Readers refuse a motion to a point they cannot
resolve (undefined, untaught, cut off): nothing passes through silently.
Points named elsewhere than in a compensated motion (procedure arguments,
``Offs(p10, ...)``) are listed by `Program.referenced_targets`, not as unused.

Fidelity: a program read from files keeps their text (`Source`) and, for
each number that a compensation may change, its `Span` in that text. Writers
replace only the numbers of targets marked ``edited`` (`Program.with_targets`
marks them), so an unchanged program writes back byte for byte.

Columns: the pipeline stages (posture, compensation, re-timing) read a
program through `Program.motion_table` and `Program.target_table`, arrays
over all motions and targets, never object by object. A program read from
a long CSV holds only these columns (`Program.from_tables`): its ``items``
and ``targets`` stay complete sequences, but each access builds an object.

Units inside the model: mm and rad. Poses are ``T_frame_tcp`` (4, 4): the
TCP of the target's tool in the target's user frame (KUKA base, ABB work
object, FANUC user frame); ``frame=None`` is the robot base and
``tool=None`` the tool of the robot description.
"""

import dataclasses
import functools
from collections.abc import Mapping, Sequence

import numpy as np

from trajcomp.errors import TrajcompError

JOINT, LINEAR, CIRCULAR = "joint", "linear", "circular"


@dataclasses.dataclass(frozen=True)
class Source:
    """One file of a program: its name, decoded text (line endings kept) and encoding."""

    name: str
    text: str
    encoding: str


@dataclasses.dataclass(frozen=True)
class Span:
    """Where a number (or other token) stands in a `Source`: ``text[start:end]``."""

    source: int
    start: int
    end: int
    text: str


@dataclasses.dataclass(frozen=True, eq=False)
class Target:
    """A Cartesian or joint position stated by a program.

    Attributes
    ----------
    name : str
        Point name (``XP1``, ``p10``, ``P[3]``, ``Waypoint_1_p``); ``""`` for
        an inline target.
    line : int
        Line (1-based) where its numbers are written.
    pose : ndarray, shape (4, 4), or None
        T_frame_tcp, mm. None for a joint target.
    joints : ndarray, shape (6,), or None
        Joint angles, rad: the position of a joint target, or for a
        Cartesian target the joints it was taught or computed with (UR
        ``qnear`` / ``Waypoint_q``, CSV ``j1..j6``, compensation output).
    config : tuple
        The language's configuration data: KRL ``(S, T)``, RAPID ``(cf1,
        cf4, cf6, cfx)``, FANUC ``(flip, elbow, front, t1, t4, t6)``; ``()``
        where the language has none or the file gives none.
    tool, frame : str or None
        Tool and frame names the point data itself states (FANUC UT, UF);
        otherwise the motions using the target state them.
    external : ndarray, shape (K,), or None
        External axes as the program states them (KUKA E1..E6, ABB extax
        eax_a..eax_f, FANUC E1.. of group 1 then the axes of groups 2..),
        in the controller's units (mm for linear, deg for rotary axes);
        NaN for an axis the program marks unused (ABB 9E9). Carried
        unchanged by compensation and conversion: the arm's base is assumed
        fixed (see `Program.moving_external_axes`). None: none stated.
    spans : Mapping[str, Span]
        The target's numbers in the source text by role (``x``, ``q1``,
        ``j3``, ``s`` ...), as the format module names them.
    edited : bool
        Set by `Program.with_targets`; writers rewrite edited targets only.
    """

    name: str
    line: int
    pose: np.ndarray = None
    joints: np.ndarray = None
    config: tuple = ()
    tool: str = None
    frame: str = None
    external: np.ndarray = None
    spans: Mapping = dataclasses.field(default_factory=dict)
    edited: bool = False

    @property
    def is_joint(self):
        """True for a joint-space target (no pose)."""
        return self.pose is None

    @property
    def label(self):
        """``name`` or ``line N`` for messages and reports."""
        return self.name or f"line {self.line}"


@dataclasses.dataclass(frozen=True)
class Motion:
    """One motion instruction.

    Attributes
    ----------
    kind : {"joint", "linear", "circular"}
    target : int or None
        Index into `Program.targets`; None when the position is computed at
        run time (the motion is not compensated; ``reason`` says why).
    via : int or None
        Via (auxiliary) point of a circular motion.
    speed : float or None
        In ``speed_unit``; None when the language default applies.
    speed_unit : str
        ``"mm/s"`` (TCP speed), ``"%"`` (of joint maximum), ``"rad/s"``,
        ``"s"`` (motion time).
    zone : float or None
        Blend radius, mm; None for an exact stop (fine).
    tool, frame : str or None
        Tool and user frame active for this motion.
    line : int
    text : str
        The instruction as written (one line, stripped).
    reason : str
        Why ``target`` is None (``"Offs(...) computed at run time"``); ``""``
        for a compensated motion.
    refs : tuple of int
        Targets the motion names without moving to them as stated (the base
        point of ``Offs(p10, ...)``, the points of a motion whose tool is set
        at run time).
    spans : Mapping[str, Span]
        Where the motion's speed and time fields stand in the source, by
        role as the format module names them (``speed``, ``t``, ``end``
        ...): re-timing writes there (`trajcomp.timing.writeback`).
    axis_position : bool
        The motion goes to an axis (joint) position stated outside the
        program (KUKA ``XHOME`` of $config.dat): joint space, kept as written
        like a joint target, not a motion left uncompensated.
    """

    kind: str
    target: int = None
    via: int = None
    speed: float = None
    speed_unit: str = "mm/s"
    zone: float = None
    tool: str = None
    frame: str = None
    line: int = 0
    text: str = ""
    reason: str = ""
    refs: tuple = ()
    spans: Mapping = dataclasses.field(default_factory=dict)
    axis_position: bool = False


@dataclasses.dataclass(frozen=True)
class Statement:
    """Anything that is not a motion, kept as written.

    ``refs`` are the targets it names (procedure arguments ``MyProc p10;``,
    ``PR[1]=P[3]``): used by the program, but not by a motion trajcomp sees.
    """

    line: int
    text: str
    refs: tuple = ()


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
            name="", line=int(self.line[i]),
            pose=None if self.is_joint[i] else self.pose[i],
            joints=None if np.isnan(self.joints[i]).any() else self.joints[i],
            config=self.config[i], tool=self.tool[i], frame=self.frame[i], external=self.external[i],
            edited=bool(self.edited[i]),
        )

    def with_rows(self, index, *, poses=None, joints=None, configs=None):
        """A copy with rows ``index`` replaced and marked edited (see `Program.with_targets`)."""
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


@dataclasses.dataclass(frozen=True, eq=False)
class Usage:
    """Tool and frame of every target some motion uses (`Program.usage_table`).

    Attributes
    ----------
    index : ndarray of int, shape (K,)
        Target indices, ascending.
    tool, frame : ndarray of object, shape (K,)
        Names (None: the robot's tool / the base).
    """

    index: np.ndarray
    tool: np.ndarray
    frame: np.ndarray


def _codes(values):
    """Integer codes (N,) of hashable values (N,) and the distinct values in first-seen order."""
    values = list(values)
    names = list(dict.fromkeys(values))
    if len(names) <= 1:
        return np.zeros(len(values), dtype=int), names
    lookup = {name: k for k, name in enumerate(names)}
    return np.fromiter(map(lookup.__getitem__, values), dtype=int, count=len(values)), names


@dataclasses.dataclass(frozen=True, eq=False)
class PoseStack:
    """The Cartesian targets of a program as one stack.

    Attributes
    ----------
    index : ndarray of int, shape (N,)
        Target indices into `Program.targets`.
    T : ndarray, shape (N, 4, 4)
        T_frame_tcp, mm.
    tool, frame : tuple of (str or None), length N
    names : tuple of str, length N
        Labels for messages.
    """

    index: np.ndarray
    T: np.ndarray
    tool: tuple
    frame: tuple
    names: tuple

    def __len__(self):
        return len(self.index)


@dataclasses.dataclass(frozen=True, eq=False)
class Program:
    """A robot program: items in order, targets, and tools and frames it defines.

    Attributes
    ----------
    format : str
        Registry name of the language the program was read from (or is
        meant for).
    name : str
    items : Sequence of (Motion or Statement)
    targets : Sequence of Target
    tools : Mapping[str, ndarray (4, 4)]
        T_flange_tool of the tools the program defines, mm.
    frames : Mapping[str, ndarray (4, 4)]
        T_world_frame of the user frames / work objects it defines, mm.
    sources : tuple of Source
        The files it was read from; empty for a program built in memory.
    times : ndarray, shape (M,), or None
        Time stamps of its M motions, s, that the writer puts into the
        program's own time column (a CSV's ``t``: `trajcomp.formats.csv_program.with_times`);
        None: none set.
    """

    format: str
    name: str
    items: Sequence
    targets: Sequence
    tools: Mapping = dataclasses.field(default_factory=dict)
    frames: Mapping = dataclasses.field(default_factory=dict)
    sources: tuple = ()
    times: np.ndarray = None

    @classmethod
    def from_tables(cls, format, name, statements, motions, targets, text, sources=()):
        """A program held as columns: for long programs (a CSV of a million rows).

        Parameters
        ----------
        format, name : str
        statements : sequence of Statement
            Everything that is not a motion, with its line.
        motions : MotionTable
        targets : TargetTable
        text : callable
            ``text(line) -> str``: the instruction at a line (built on access).
        sources : tuple of Source
        """
        return cls(format, name, ItemRows(statements, motions, text), TargetRows(targets), sources=sources)

    @functools.cached_property
    def motions(self):
        """The motion items, in program order (built once: code indexes it in loops over motions)."""
        if isinstance(self.items, ItemRows):
            return self.items.motions
        return tuple(item for item in self.items if isinstance(item, Motion))

    def motion_table(self):
        """The motions as a `MotionTable` (built once)."""
        if isinstance(self.items, ItemRows):
            return self.items.table
        return self._motion_table

    @functools.cached_property
    def _motion_table(self):
        return MotionTable.of(self.motions)

    def target_table(self):
        """The targets as a `TargetTable` (built once)."""
        if isinstance(self.targets, TargetRows):
            return self.targets.table
        return self._target_table

    @functools.cached_property
    def _target_table(self):
        return TargetTable.of(self.targets)

    def runtime_motions(self):
        """Motions whose position is computed at run time (not compensable)."""
        return tuple(self.motions[k] for k in np.flatnonzero(self.motion_table().target < 0))

    def not_compensated(self):
        """``((line, text, reason), ...)`` of the motions passed through unchanged, in program order."""
        return tuple((m.line, m.text, m.reason or "position computed at run time")
                     for m in self.runtime_motions() if not m.axis_position)

    def _referencing_items(self):
        """The items that name targets outside compensated motions (``refs``)."""
        items = self.items.statements if isinstance(self.items, ItemRows) else self.items
        return [item for item in items if item.refs]

    def referenced_targets(self):
        """Targets named outside the compensated motions, which no compensated motion uses.

        Procedure arguments (RAPID ``MyProc p10;``, KRL ``MYPROC(XP1)``),
        ``PR[1]=P[3]``, the base point of ``Offs(p10, ...)``: the program
        uses these points, but trajcomp cannot see where to, so they are
        left as written and must be reported as not compensated.

        Returns
        -------
        tuple of (int, int, str)
            ``(target index, line, text)`` of each naming item, in program order.
        """
        used = set(self.usage_table().index.tolist())
        return tuple(
            (i, item.line, item.text.strip())
            for item in self._referencing_items()
            for i in dict.fromkeys(item.refs)
            if i not in used
        )

    def moving_external_axes(self):
        """External axes whose value differs between the targets the motions use.

        Compensation corrects the arm for a fixed base; a program that moves
        a track or positioner between targets needs that stated.

        Returns
        -------
        tuple of str
            Axis labels (``"E1"``, ...) in axis order; empty if none moves.
        """
        external = self.target_table().external
        values = [external[i] for i in self.usage_table().index.tolist() if external[i] is not None]
        if len(values) < 2:
            return ()
        width = max(len(v) for v in values)
        table = np.full((len(values), width), np.nan)
        for row, v in zip(table, values):
            row[: len(v)] = v
        moving = [k for k in range(width) if len(np.unique(table[~np.isnan(table[:, k]), k])) > 1]
        return tuple(f"E{k + 1}" for k in moving)

    def usage_table(self):
        """Tool and frame of every target some motion uses, as arrays (`Usage`, built once).

        A target's own tool or frame (FANUC UT, UF) wins over the motion's.

        Raises
        ------
        TrajcompError
            A target used with two different tools or frames: one set of
            numbers cannot be right for both.
        """
        return self._usage

    @functools.cached_property
    def _usage(self):
        motions, targets = self.motion_table(), self.target_table()
        index = np.stack([motions.via, motions.target], axis=1).ravel()  # via before target, program order
        rows = np.repeat(np.arange(len(motions)), 2)
        keep = index >= 0
        index, rows = index[keep], rows[keep]
        own_tool, own_frame = targets.tool[index], targets.frame[index]
        tool = np.where(np.equal(own_tool, None), motions.tool[rows], own_tool)
        frame = np.where(np.equal(own_frame, None), motions.frame[rows], own_frame)
        tool_code, _ = _codes(tool)
        frame_code, _ = _codes(frame)
        key = tool_code * (frame_code.max(initial=0) + 1) + frame_code
        order = np.argsort(index, kind="stable")
        first = np.ones(len(order), dtype=bool)
        first[1:] = index[order][1:] != index[order][:-1]
        start = order[first]
        first_key = np.repeat(key[start], np.diff(np.append(np.flatnonzero(first), len(order))))
        clash = np.flatnonzero(key[order] != first_key)
        if clash.size:
            j = order[clash[np.argmin(order[clash])]]
            k = start[np.searchsorted(index[start], index[j])]
            raise TrajcompError(
                f"target {self.targets[index[j]].label} is used with tool/frame {(tool[k], frame[k])} and, "
                f"at line {motions.line[rows[j]]}, with {(tool[j], frame[j])}: it cannot be compensated for both"
            )
        return Usage(index[start], tool[start], frame[start])

    def usage(self):
        """Tool and frame of every target, from its own data or the motions using it.

        Returns
        -------
        dict
            ``{target index: (tool, frame)}`` for every target some motion
            uses (as target or via point), by ascending index (see
            `usage_table` for long programs).

        Raises
        ------
        TrajcompError
            As `usage_table`.
        """
        used = self.usage_table()
        return dict(zip(used.index.tolist(), zip(used.tool.tolist(), used.frame.tolist())))

    def cartesian_targets(self):
        """The Cartesian targets used by motions, as one `PoseStack`."""
        used, targets = self.usage_table(), self.target_table()
        cartesian = ~targets.is_joint[used.index]
        index = used.index[cartesian]
        return PoseStack(index=index, T=targets.pose[index], tool=tuple(used.tool[cartesian]),
                         frame=tuple(used.frame[cartesian]), names=self.labels(index))

    def joint_targets(self):
        """Indices (N,) of the joint targets used by motions, and their joints (N, 6), rad."""
        used, targets = self.usage_table(), self.target_table()
        index = used.index[targets.is_joint[used.index]]
        return index, targets.joints[index]

    def unused_targets(self):
        """Targets nothing uses: no motion, statement or run-time expression (left unchanged)."""
        used = np.zeros(len(self.targets), dtype=bool)
        used[self.usage_table().index] = True
        used[[i for item in self._referencing_items() for i in item.refs]] = True
        return tuple(self.targets[i] for i in np.flatnonzero(~used))

    def where(self, index):
        """Target ``index`` named for messages: label, file and line (``P1 (weld.dat:12)``)."""
        if isinstance(self.targets, TargetRows):
            return self.labels([index])[0]
        target = self.targets[index]
        span = next(iter(target.spans.values()), None)
        if span is not None and span.source < len(self.sources):
            place = f"{self.sources[span.source].name}:{target.line}"
        else:
            place = f"line {target.line}"
        return f"{target.name} ({place})" if target.name else place

    def labels(self, index):
        """`where` of many targets (N,): a sequence of str (built on access for a table-backed program)."""
        if isinstance(self.targets, TargetRows):
            lines = self.target_table().line[np.asarray(index, dtype=int)]
            return LineLabels(self.sources[0].name, lines) if self.sources else [f"line {n}" for n in lines]
        return [self.where(i) for i in index]

    def with_targets(self, index, *, poses=None, joints=None, configs=None):
        """A new program with some targets replaced and marked edited.

        Parameters
        ----------
        index : array_like of int, shape (N,)
            Target indices.
        poses : ndarray, shape (N, 4, 4), optional
            New T_frame_tcp, mm (Cartesian targets only).
        joints : ndarray, shape (N, 6), optional
            New joints, rad.
        configs : sequence of tuple, length N, optional
            New configuration data in the program's language.
        """
        index = np.asarray(index, dtype=int)
        if isinstance(self.targets, TargetRows):
            table = self.targets.table.with_rows(index, poses=poses, joints=joints, configs=configs)
            return dataclasses.replace(self, targets=TargetRows(table))
        targets = list(self.targets)
        for k, i in enumerate(index):
            change = {"edited": True}
            if poses is not None:
                change["pose"] = np.asarray(poses[k], dtype=float)
            if joints is not None:
                change["joints"] = np.asarray(joints[k], dtype=float)
            if configs is not None:
                change["config"] = tuple(configs[k])
            targets[i] = dataclasses.replace(targets[i], **change)
        return dataclasses.replace(self, targets=tuple(targets))

    def replace(self, **changes):
        """A copy with some attributes changed."""
        return dataclasses.replace(self, **changes)
