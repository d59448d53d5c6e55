"""The items of a robot program: one dataclass per thing a program states.

`Source` (a file's text), `Span` (where a number stands in it), `Target` (a
position), `Motion` and `Statement` (what the program does, in order), and
the motion kinds `JOINT`, `LINEAR`, `CIRCULAR`. How they make up a program
is documented in `trajcomp.programs.program`, which holds `trajcomp.programs.program.Program`.
"""

import array
import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np

JOINT, LINEAR, CIRCULAR = "joint", "linear", "circular"


@dataclasses.dataclass(frozen=True)
class Source:
    """One file of a program: its name, decoded text (line endings kept) and encoding.

    ``path`` is where it was read from (None for a text built in memory).
    A ``companion`` is another file of the controller read for the points
    the program uses from it (another module of a RAPID task, a KUKA data
    list or ``$config.dat``, FANUC position registers): its points are
    corrected where they are declared, and it is written back only when
    they changed (`trajcomp.formats.file_writing.companion_outputs`).
    """

    name: str
    text: str
    encoding: str
    path: str = None
    companion: bool = False


@dataclasses.dataclass(frozen=True)
class Span:
    """Where a number (or other token) stands in a `Source`: ``text[start:end]``."""

    source: int
    start: int
    end: int
    text: str


def replaced(item, **changes):
    """A copy of a program item (`Target`, `Motion`, `Statement`) with some fields changed.

    What `dataclasses.replace` gives, without running ``__init__`` again:
    the items check nothing on construction, and a long program replaces
    one per target (about 6x faster).
    """
    copy = object.__new__(type(item))
    copy.__dict__.update(item.__dict__, **changes)
    return copy


class SpanColumns(Sequence):
    """The spans of many items in one source, as columns: what a reader of long programs keeps.

    Each item's spans are a `SpanRow` (a Mapping like ``{role: Span}``)
    built on access: a long program holds two integer arrays instead of a
    `Span` object per number.

    Parameters
    ----------
    source : int
        Index of the `Source` in the program.
    text : str
        That source's text.
    roles : sequence of str
        The roles, in the order an item's spans list them.
    start, end : ndarray of int, shape (N, R)
        Offsets of each item's span of each role in ``text``; ``start`` -1
        where the item has no span of that role.
    """

    def __init__(self, source, text, roles, start, end):
        self.source, self.text, self.roles = source, text, tuple(roles)
        self.column = {role: j for j, role in enumerate(self.roles)}
        self.start, self.end = start, end

    def __len__(self):
        return len(self.start)

    def row(self, k):
        """The spans of item ``k``."""
        return SpanRow(self, k)

    def __getitem__(self, k):
        """`row` ``k``: the columns are a sequence of the items' spans (`trajcomp.programs.tables.MotionTable.spans`)."""
        if not -len(self) <= k < len(self):
            raise IndexError(k)
        return SpanRow(self, k % len(self))


class SpanTable:
    """The spans of items recorded one item at a time as offsets (no object each), made `SpanColumns` at the end.

    Parameters
    ----------
    roles : sequence of str
        The roles an item's spans may have, in the order they list them.
    """

    def __init__(self, roles):
        self.roles = tuple(roles)
        self.column = {role: j for j, role in enumerate(self.roles)}
        self.offsets = array.array("q")  # start, end of each role, item after item; -1 where none

    def add(self, offsets):
        """Record the spans ``{role: (start, end) or None}`` of the next item (None: no span)."""
        row = [-1] * (2 * len(self.roles))
        for role, where in offsets.items():
            if where is not None:
                j = 2 * self.column[role]
                row[j:j + 2] = where
        self.offsets.extend(row)

    def columns(self, source, text):
        """The `SpanColumns` of the items recorded, in ``text`` (the text of `Source` ``source``)."""
        pairs = np.frombuffer(self.offsets, dtype=np.int64).reshape(-1, len(self.roles), 2)
        return SpanColumns(source, text, self.roles, pairs[:, :, 0].copy(), pairs[:, :, 1].copy())


class SpanRow(Mapping):
    """The spans of one item of `SpanColumns`: ``{role: Span}`` built on access."""

    __slots__ = ("columns", "k")

    def __init__(self, columns, k):
        self.columns, self.k = columns, k

    def __getitem__(self, role):
        columns = self.columns
        j = columns.column.get(role)
        start = -1 if j is None else int(columns.start[self.k, j])
        if start < 0:
            raise KeyError(role)
        end = int(columns.end[self.k, j])
        return Span(columns.source, start, end, columns.text[start:end])

    def __iter__(self):
        return (role for role, start in zip(self.columns.roles, self.columns.start[self.k].tolist()) if start >= 0)

    def __len__(self):
        return int((self.columns.start[self.k] >= 0).sum())

    def __repr__(self):
        return repr(dict(self))

    def fields(self):
        """``{role: (source, start, end, text)}``: the spans' fields, no `Span` object built."""
        columns = self.columns
        return {role: (columns.source, start, end, columns.text[start:end]) for role, start, end in
                zip(columns.roles, columns.start[self.k].tolist(), columns.end[self.k].tolist()) if start >= 0}


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
        In ``speed_unit``; None when the language default applies or the
        speed is set at run time (``speed_why``).
    speed_unit : str
        ``"mm/s"`` (TCP speed), ``"%"`` (of joint maximum), ``"rad/s"``
        (a joint motion's leading axis; a linear one's orientation),
        ``"s"`` (motion time).
    orientation_speed : float or None
        An orientation speed that bounds the motion beside its TCP speed
        (RAPID speeddata's v_ori), rad/s; None where none does.
    external_speed : float or None
        A speed that bounds the linear external axes (a track) beside the
        TCP speed (RAPID speeddata's v_leax), mm/s; None where none does.
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
    speed_why : str
        Why the speed is known only at run time (``"vWeld: PERS speeddata,
        set at run time (line 4)"``), ``""`` when the program states it:
        re-timing leaves such a motion's speed field as written and lists
        it (`trajcomp.timing.writeback`).
    axis_position : bool
        The motion goes to an axis (joint) position stated outside the
        program (KUKA ``XHOME`` of $config.dat, ``$AXIS_ACT``: where the arm
        is, as RoboDK's and KUKA's programs start): joint space, kept as
        written like a joint target, not a motion left uncompensated.
    source : int
        Index into `Program.sources` of the file the motion is written in:
        0 but in a program joined from several files (`trajcomp.formats.task`).
    acceleration : float or None
        The acceleration the program states for the motion, a limit beside
        the arm's: of the leading axis (rad/s^2) for a joint motion, of the
        TCP (mm/s^2) for a linear or circular one (UR ``a=``); None where
        the controller's own applies.
    acceleration_share : float or None
        The share (0, 1] of the arm's acceleration limits the program's
        acceleration override leaves the motion (KRL ``$ACC_AXIS[n]``, the
        slowest axis's; RAPID ``AccSet``; FANUC ``ACC``, above 100 % read
        as 100 %: the timing keeps the arm's limits); None where the
        controller's own applies.
    start_why : str
        Why the position the motion starts from is not unique (it can be
        reached after a call, a loop's back jump, a branch or a jump from
        elsewhere: `trajcomp.programs.flow`), ``""`` when it is the motion
        before it: such a motion is not timed, its fields are left as
        written and listed (`trajcomp.timing.moves`).
    time_why : str
        Why a time written for the motion would not run as timed (RAPID
        ``AccSet`` with a ramp below 100 %: the controller keeps a ``\\T``
        by cruising faster behind softer ramps, which the timing does not
        model), ``""`` where none: re-timing leaves the field of such a
        motion as written where it would write a time, and lists it
        (`trajcomp.timing.writeback`); a speed is still written.
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
    speed_why: str = ""
    source: int = 0
    orientation_speed: float = None
    external_speed: float = None
    start_why: str = ""
    acceleration: float = None
    acceleration_share: float = None
    time_why: str = ""


@dataclasses.dataclass(frozen=True)
class Statement:
    """Anything that is not a motion, kept as written.

    ``refs`` are the targets it names (procedure arguments ``MyProc p10;``,
    ``PR[1]=P[3]``): used by the program, but not by a motion trajcomp sees.
    ``source``: index into `Program.sources` of the file it is written in,
    as `Motion.source`.
    """

    line: int
    text: str
    refs: tuple = ()
    source: int = 0
