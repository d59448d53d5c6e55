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

Units inside the model: mm and rad. Poses are ``T_frame_tcp`` (4, 4): the
TCP of the target's tool in the target's user frame (KUKA base, ABB work
object, FANUC user frame); ``frame=None`` is the robot base and
``tool=None`` the tool of the robot description.
"""

import dataclasses
from collections.abc import Mapping

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
    items : tuple of (Motion or Statement)
    targets : tuple of Target
    tools : Mapping[str, ndarray (4, 4)]
        T_flange_tool of the tools the program defines, mm.
    frames : Mapping[str, ndarray (4, 4)]
        T_world_frame of the user frames / work objects it defines, mm.
    sources : tuple of Source
        The files it was read from; empty for a program built in memory.
    """

    format: str
    name: str
    items: tuple
    targets: tuple
    tools: Mapping = dataclasses.field(default_factory=dict)
    frames: Mapping = dataclasses.field(default_factory=dict)
    sources: tuple = ()

    @property
    def motions(self):
        """The motion items, in program order."""
        return tuple(item for item in self.items if isinstance(item, Motion))

    def runtime_motions(self):
        """Motions whose position is computed at run time (not compensable)."""
        return tuple(m for m in self.motions if m.target is None)

    def not_compensated(self):
        """``((line, text, reason), ...)`` of the motions passed through unchanged, in program order."""
        return tuple((m.line, m.text, m.reason or "position computed at run time")
                     for m in self.runtime_motions() if not m.axis_position)

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
        used = self.usage()
        return tuple(
            (i, item.line, item.text.strip())
            for item in self.items
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
        values = [self.targets[i].external for i in sorted(self.usage()) if self.targets[i].external is not None]
        if len(values) < 2:
            return ()
        width = max(len(v) for v in values)
        table = np.full((len(values), width), np.nan)
        for row, v in zip(table, values):
            row[: len(v)] = v
        moving = [k for k in range(width) if len(np.unique(table[~np.isnan(table[:, k]), k])) > 1]
        return tuple(f"E{k + 1}" for k in moving)

    def usage(self):
        """Tool and frame of every target, from its own data or the motions using it.

        Returns
        -------
        dict
            ``{target index: (tool, frame)}`` for every target some motion
            uses (as target or via point).

        Raises
        ------
        TrajcompError
            A target used with two different tools or frames: one set of
            numbers cannot be right for both.
        """
        used = {}
        for motion in self.motions:
            for index in (motion.target, motion.via):
                if index is None:
                    continue
                target = self.targets[index]
                tool = target.tool if target.tool is not None else motion.tool
                frame = target.frame if target.frame is not None else motion.frame
                if used.setdefault(index, (tool, frame)) != (tool, frame):
                    raise TrajcompError(
                        f"target {target.label} is used with tool/frame {used[index]} and, "
                        f"at line {motion.line}, with {(tool, frame)}: it cannot be compensated for both"
                    )
        return used

    def cartesian_targets(self):
        """The Cartesian targets used by motions, as one `PoseStack`."""
        used = self.usage()
        index = [i for i in sorted(used) if not self.targets[i].is_joint]
        return PoseStack(
            index=np.array(index, dtype=int),
            T=np.array([self.targets[i].pose for i in index]).reshape(-1, 4, 4),
            tool=tuple(used[i][0] for i in index),
            frame=tuple(used[i][1] for i in index),
            names=tuple(self.targets[i].label for i in index),
        )

    def joint_targets(self):
        """Indices (N,) of the joint targets used by motions, and their joints (N, 6), rad."""
        index = np.array([i for i in sorted(self.usage()) if self.targets[i].is_joint], dtype=int)
        return index, np.array([self.targets[i].joints for i in index]).reshape(-1, 6)

    def unused_targets(self):
        """Targets nothing uses: no motion, statement or run-time expression (left unchanged)."""
        used = set(self.usage()) | {i for item in self.items for i in item.refs}
        return tuple(t for i, t in enumerate(self.targets) if i not in used)

    def where(self, index):
        """Target ``index`` named for messages: label, file and line (``P1 (weld.dat:12)``)."""
        target = self.targets[index]
        span = next(iter(target.spans.values()), None)
        if span is not None and span.source < len(self.sources):
            place = f"{self.sources[span.source].name}:{target.line}"
        else:
            place = f"line {target.line}"
        return f"{target.name} ({place})" if target.name else place

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
        targets = list(self.targets)
        for k, i in enumerate(np.asarray(index, dtype=int)):
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
