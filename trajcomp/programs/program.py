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
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR, Motion, Source, Span, Statement, Target, replaced
from trajcomp.programs.tables import ItemRows, LineLabels, MotionTable, Rows, TargetRows, TargetTable, value_codes

# The program model as format plugins import it (README "Plugins", plugins/trajcomp-points): the item
# classes are defined in trajcomp.programs.items and stay importable from here.
__all__ = ["CIRCULAR", "JOINT", "LINEAR", "Motion", "PoseStack", "Program", "Source", "Span", "Statement",
           "Target", "Usage"]


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
        program's own time column (a CSV's ``t``: `trajcomp.formats.csv.writer.with_times`);
        None: none set.
    notes : tuple of str
        What reading did to the program that its report must say (a point
        written as a copy per use, `trajcomp.formats.uses`).
    kept_axes : bool
        A Cartesian target that does not state an external axis keeps it
        where the motion before left it (its language's, set when it is
        read: `trajcomp.formats.capabilities.KeptExternalAxes`).
    track_key : str or None
        The key naming its language in a robot's track fields
        (`trajcomp.arm.track.Track.index`; set when it is read or converted:
        `trajcomp.formats.capabilities.ExternalAxes`); None: its targets
        state no track position.
    """

    format: str
    name: str
    items: Sequence
    targets: Sequence
    tools: Mapping = dataclasses.field(default_factory=dict)
    frames: Mapping = dataclasses.field(default_factory=dict)
    sources: tuple = ()
    times: np.ndarray = None
    notes: tuple = ()
    kept_axes: bool = False
    track_key: str = None

    @classmethod
    def from_tables(cls, format, name, statements, motions, targets, sources=(), **fields):
        """A program held as columns: for long programs (a CSV of a million rows, a CAM job in a robot language).

        Parameters
        ----------
        format, name : str
        statements : Sequence of Statement
            Everything that is not a motion, with its line (a `StatementTable` for many).
        motions : MotionTable
        targets : TargetTable
        sources : tuple of Source
        **fields
            Other attributes (``tools``, ``frames``, ``notes`` ...).
        """
        return cls(format, name, ItemRows(statements, motions), TargetRows(targets), sources=sources, **fields)

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
        """``((line, text, reason), ...)`` of the motions passed through unchanged, in program order; ``line`` as
        `place` gives it."""
        return tuple((self.place(m), m.text, m.reason or "position computed at run time")
                     for m in self.runtime_motions() if not m.axis_position)

    def place(self, item):
        """Where a motion or statement is written: its line (int), or ``"file:line"`` (str) in a program joined
        from several files whose items lie in more than one (a task, `trajcomp.formats.task.merge`); as text:
        `place_text`."""
        return f"{self.sources[item.source].name}:{item.line}" if self._joined else item.line

    def location(self, item):
        """Where a motion or statement is written, for messages: ``"weld.src:12"`` (the program's name for a
        program built in memory)."""
        name = self.sources[item.source].name if item.source < len(self.sources) else self.name
        return f"{name}:{item.line}"

    @functools.cached_property
    def _joined(self):
        """Items of this program lie in more than one of its files."""
        if isinstance(self.items, ItemRows):
            return bool(self.items.table.source.any() or self.items.statements.source.any())
        return any(item.source for item in self.items)

    def _referencing_items(self):
        """The items that name targets outside compensated motions (``refs``)."""
        if isinstance(self.items, ItemRows):
            return self.items.naming()
        return [item for item in self.items if item.refs]

    def referenced_targets(self):
        """Targets named outside the compensated motions, which no compensated motion uses.

        Procedure arguments (RAPID ``MyProc p10;``, KRL ``MYPROC(XP1)``),
        ``PR[1]=P[3]``, the base point of ``Offs(p10, ...)``: the program
        uses these points, but trajcomp cannot see where to, so they are
        left as written and must be reported as not compensated.

        Returns
        -------
        tuple of (int, int or str, str)
            ``(target index, line, text)`` of each naming item, in program order; ``line`` as `place` gives it.
        """
        used = set(self.usage_table().index.tolist())
        return tuple(
            (i, self.place(item), item.text.strip())
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
        uses = self._uses
        if uses["clash"].size:
            j = uses["clash"][0]
            k, tool, frame = uses["first"][j], uses["tool"], uses["frame"]
            raise TrajcompError(
                f"target {self.targets[uses['index'][j]].label} is used with tool/frame {(tool[k], frame[k])} and, "
                f"at line {uses['line'][j]}, with {(tool[j], frame[j])}: it cannot be compensated for both"
            )
        start = uses["start"]
        return Usage(uses["index"][start], uses["tool"][start], uses["frame"][start])

    def target_uses(self):
        """Every use of a target by a motion: its tool and frame, the first use of the same target, the clashes.

        Returns
        -------
        dict
            ``index``, ``motion``, ``line``, ``tool``, ``frame`` (U,) of each
            use (via before target, program order), ``via`` (U,): whether
            it is a via point; ``first`` (U,): the use that first names the
            same target; ``start``: the first uses, by ascending target;
            ``clash``: uses with another tool or frame than the first, in
            program order.
        """
        return self._uses

    @functools.cached_property
    def _uses(self):
        """`target_uses`, built once."""
        motions, targets = self.motion_table(), self.target_table()
        index = np.stack([motions.via, motions.target], axis=1).ravel()  # via before target, program order
        rows = np.repeat(np.arange(len(motions)), 2)
        via = np.tile([True, False], len(motions))
        keep = index >= 0
        index, rows, via = index[keep], rows[keep], via[keep]
        own_tool, own_frame = targets.tool[index], targets.frame[index]
        tool = np.where(np.equal(own_tool, None), motions.tool[rows], own_tool)
        frame = np.where(np.equal(own_frame, None), motions.frame[rows], own_frame)
        tool_code, _ = value_codes(tool)
        frame_code, _ = value_codes(frame)
        key = tool_code * (frame_code.max(initial=0) + 1) + frame_code
        order = np.argsort(index, kind="stable")
        first = np.ones(len(order), dtype=bool)
        first[1:] = index[order][1:] != index[order][:-1]
        start = order[first]
        first_use = np.empty(len(order), dtype=int)
        first_use[order] = np.repeat(start, np.diff(np.append(np.flatnonzero(first), len(order))))
        clash = np.sort(np.flatnonzero(key != key[first_use]))
        return {"index": index, "motion": rows, "via": via, "line": motions.line[rows], "tool": tool, "frame": frame,
                "first": first_use, "start": start, "clash": clash}

    def with_shared_targets_left(self):
        """The program with every motion to a point used with several tools or frames left as written.

        One set of numbers cannot be right for two tools or work objects (the
        same figure drawn in two wobjs, UR with two TCPs, legal programs):
        each motion using such a point passes through unchanged, listed with
        the reason (`Motion.reason`), instead of the whole program being
        refused. The program itself when there is none.
        """
        uses = self._uses
        why = {}
        for j in uses["clash"].tolist():
            i, k = int(uses["index"][j]), int(uses["first"][j])
            why.setdefault(i, f"point {self.targets[i].label} is used with tool/frame "
                              f"{(uses['tool'][k], uses['frame'][k])} (line {uses['line'][k]}) and "
                              f"{(uses['tool'][j], uses['frame'][j])} (line {uses['line'][j]}): one set of numbers "
                              "cannot be right for both, its motions are left as written")
        return self.with_targets_left(why)

    def with_targets_left(self, why):
        """The program with every motion to or via the targets ``why`` names left as written.

        Each such motion passes through unchanged (its points kept as its
        ``refs``), listed with the reason (`Motion.reason`).

        Parameters
        ----------
        why : Mapping[int, str]
            Target index to the reason its motions are not compensated.

        Returns
        -------
        Program
            The program itself when ``why`` is empty.
        """
        if not why:
            return self
        items = []
        for item in self.items:
            if isinstance(item, Motion) and (points := [i for i in (item.via, item.target) if i in why]):
                item = dataclasses.replace(item, target=None, via=None, reason=why[points[0]],
                                           refs=tuple(dict.fromkeys(item.refs + tuple(points))))
            items.append(item)
        return dataclasses.replace(self, items=tuple(items))

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
        if self._inline_rows():
            return self.labels([index])[0]
        target = self.targets[index]
        span = next(iter(target.spans.values()), None)
        if span is not None and span.source < len(self.sources):
            place = f"{self.sources[span.source].name}:{target.line}"
        else:
            place = f"line {target.line}"
        return f"{target.name} ({place})" if target.name else place

    def _inline_rows(self):
        """Whether the targets are a table's rows without names or spans (a CSV's): labelled by their lines."""
        return isinstance(self.targets, TargetRows) and self.targets.table.spans is None

    def labels(self, index):
        """`where` of many targets (N,): a sequence of str, each built on access (messages name a few)."""
        if self._inline_rows():
            lines = self.target_table().line[np.asarray(index, dtype=int)]
            return LineLabels(self.sources[0].name, lines) if self.sources else [f"line {n}" for n in lines]
        index = np.asarray(index, dtype=int)
        return Rows(len(index), lambda k: self.where(int(index[k])))

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
            return self._kept_uses(dataclasses.replace(self, targets=TargetRows(table)))
        targets = list(self.targets)
        for k, i in enumerate(index):
            change = {"edited": True}
            if poses is not None:
                change["pose"] = np.asarray(poses[k], dtype=float)
            if joints is not None:
                change["joints"] = np.asarray(joints[k], dtype=float)
            if configs is not None:
                change["config"] = tuple(configs[k])
            targets[i] = replaced(targets[i], **change)
        return self._kept_uses(dataclasses.replace(self, targets=tuple(targets)))

    def _kept_uses(self, other):
        """``other``, this program with other target numbers, given what this one built of its items and of its
        targets' tools and frames (`target_uses`, `usage_table`): the same, not built again (a long program's
        uses are some 60 bytes each)."""
        other.__dict__.update({name: self.__dict__[name] for name in ("motions", "_motion_table", "_joined", "_uses", "_usage")
                               if name in self.__dict__})
        return other

    def replace(self, **changes):
        """A copy with some attributes changed."""
        return dataclasses.replace(self, **changes)


def place_text(place):
    """A place `Program.place` gives, for messages: ``line 12``, or ``b.src:12`` as it is."""
    return place if isinstance(place, str) else f"line {place}"
