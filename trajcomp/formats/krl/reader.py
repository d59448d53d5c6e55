"""The KRL reader: .src statements and .dat declarations into a `Program` (see `trajcomp.formats.krl`)."""

import dataclasses
import functools
import itertools
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError
from trajcomp.formats.krl import at_once, config_dat, line_walk
from trajcomp.formats.krl.grammar import (
    ACC, ACC_AXIS, ACC_CP, ACC_EXTAX, ACC_GROUPS, ACC_ORI, ACT, APO, APPROX, ARRAY_ELEMENT, ASSIGN, AXES,
    AXIS_GROUPS, BAS, BAS_ACC_PTP, BAS_FRAMES, BAS_SPEEDS, BLOCK_CLOSES, BLOCK_OPENS, CLOSING, DATA, DATA_REF, DECL,
    DECL_BARE, DECL_START, DEF, DEF_LINE, DEFDAT, END_SPLINE, ENDDAT, EXTERNAL, EXTERNAL_ACC_GROUPS,
    EXTERNAL_GROUPS, FIRST_WORD, FLOW_WORDS, GLOBAL_POINT, GLOBAL_WORD, HOME, JOINT_GROUPS, JOINT_TYPES, JUMP_TO,
    LIMITS, MEMBER, MOTION, MOTION_SPANS, MOTIONS, NAME, NUMBER_DECL, ORI_GROUPS, OUTSIDE_ROUTINES, POSE,
    PTP_ACC_GROUPS, SPLINE, STATUS_LARGEST, SYSVAR, VEL, VEL_AXIS, VEL_CP, VEL_EXTAX, WITH_BASE, WITH_CALL,
    WITH_EXTAX, WITH_SPEED, WITH_TOOL, WITH_WORD, WORD,
)
from trajcomp.formats.number_fields import NUMBER
from trajcomp.formats.text import (
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
    split_top,
    statement_text,
    unresolved,
    whole_circle,
)
from trajcomp.programs import flow
from trajcomp.programs.flow import Step, Unknown
from trajcomp.programs.program import Program
from trajcomp.programs.tables import ItemRows, MotionTable, StatementTable
from trajcomp.programs.items import (
    CIRCULAR, JOINT, LINEAR, Motion, Span, SpanTable, Statement, Target, replaced,
)
from trajcomp.arm.transforms import pose_to_matrix


@dataclasses.dataclass(frozen=True)
class _Named:
    """A motion argument naming a point, resolved once the whole program is read."""

    name: str
    line: int
    parameter: bool = False  # a parameter of the routine the motion is in


def _members(body, start, source, name, line, text, numeric=True):
    """``{member: Span}`` of a KRL aggregate body at offset ``start``; type prefixes skipped."""
    colon = re.match(r"\s*\w+\s*:", body)
    skip = colon.end() if colon else 0
    out, position = {}, skip
    for piece in body[skip:].split(","):
        m = MEMBER.match(piece)
        if m:
            key = m.group(1).lower()
            out[key] = Span(source, start + position + m.start(2), start + position + m.end(2), m.group(2))
        elif numeric and piece.strip():
            fail(name, line, text, f"malformed member {piece.strip()!r}")
        position += len(piece) + 1
    return out


def _int(text, source_name, line, original, field):
    """An INT member: a whole number or a bit string ``'B0101'``."""
    return int(text[2:-1], 2) if text.startswith("'") else integer(text, source_name, line, original, field)


def _values(members, roles, source_name, line, original):
    return np.array([finite(members[r].text, source_name, line, original, r.upper(), LIMITS[r]) for r in roles])


def _external(members, source_name, line, original):
    """E1..E6 as stated (NaN for the ones not given); None if none is."""
    given = [e for e in EXTERNAL if e in members]
    if not given:
        return None
    values = np.full(int(given[-1][1:]), np.nan)
    for e in given:
        values[int(e[1:]) - 1] = finite(members[e].text, source_name, line, original, e.upper(), LENGTH_LIMIT)
    return values


def _point(members, name, source_name, line, text, typ):
    """A Target from the members of a point aggregate."""
    external = _external(members, source_name, line, text)
    if typ in JOINT_TYPES or (typ is None and "a1" in members):
        missing = [a for a in AXES if a not in members]
        if missing:
            fail(source_name, line, text, f"joint point lacks {', '.join(m.upper() for m in missing)}")
        joints = np.radians(_values(members, AXES, source_name, line, text))
        return Target(name=name, line=line, joints=joints, external=external, spans={a: members[a] for a in AXES})
    return Target(name=name, line=line, pose=_frame(members, source_name, line, text), external=external,
                  config=_status_turn(members, source_name, line, text),
                  spans={k: v for k, v in members.items() if k in POSE or k in ("s", "t")})


def _status_turn(members, source_name, line, text):
    """``(S, T)`` of a point, each within the bits KUKA defines (S: a status byte, T: one bit per axis A1-A6)."""
    if "s" not in members or "t" not in members:
        return ()
    words = []
    for member, largest in STATUS_LARGEST.items():
        field = member.upper()
        value = _int(members[member].text, source_name, line, text, field)
        if not 0 <= value <= largest:
            fail(source_name, line, text, f"{field} {members[field.lower()].text[:40]}: outside 0..{largest} "
                 f"({'the status byte' if field == 'S' else 'one sign bit per axis A1-A6'})")
        words.append(value)
    return tuple(words)


def _frame(members, source_name, line, text):
    missing = [p for p in POSE if p not in members]
    if missing:
        fail(source_name, line, text, f"point lacks {', '.join(m.upper() for m in missing)}")
    vector = _values(members, POSE, source_name, line, text)
    vector[3:] = np.radians(vector[3:])
    return pose_to_matrix(vector)


def _sibling_dat(path):
    for candidate in path.parent.iterdir():
        if candidate.stem.lower() == path.stem.lower() and candidate.suffix.lower() == ".dat":
            return candidate
    return None


class _Reader:
    """Parser state while reading one KRL program."""

    def __init__(self):
        self.sources, self.targets, self.items = [], [], []
        self.points, self.data = {}, {}
        self.unset = {}  # NAME -> why its value is only known at run time
        self.tools, self.frames = {"0": np.eye(4)}, {"0": np.eye(4)}
        self.runtime = {"TOOL": {}, "BASE": {}}  # number -> why TOOL_DATA[n] / BASE_DATA[n] is set at run time
        self.tool = self.base = None
        self.tool_why = self.base_why = ""  # why the active tool / base is only known at run time
        self.params = set()
        self.speed_ptp = self.speed_cp = self.zone = None
        self.speed_spans = {JOINT: None, LINEAR: None}  # the number of the statement that set each speed
        none_set = "no {} before it in this program: the speed in force is set at run time"
        self.speed_why = {JOINT: none_set.format("BAS(#VEL_PTP)"), LINEAR: none_set.format("$VEL.CP")}
        # (value, why, span) of each speed setting in force: the TCP's (mm/s), each axis's and external axis's (%)
        self.initial = {"cp": (None, self.speed_why[LINEAR], None)}
        self.initial |= dict.fromkeys(JOINT_GROUPS, (None, self.speed_why[JOINT], None))
        # the controller's own: (value, why)
        self.initial |= dict.fromkeys(PTP_ACC_GROUPS + ("acc_cp",) + ORI_GROUPS, (None, ""))
        self.axes = [self.initial[JOINT_GROUPS[0]]] * len(JOINT_GROUPS)  # the settings of a PTP's groups in force
        self.steps = []  # what the .src does besides moving, in order (`trajcomp.programs.flow`)
        self.siblings = set()  # upper names of the other .src files beside it: routines the read does not include
        self.outside_spline = None  # the TCP speed setting in force before the spline block being read
        self.block_caps = {}  # what the spline block being read gives its PTPs' external axes (`with_external`)
        self.numbers = {}  # NAME -> (value, why it is only known at run time) of REAL / INT data declared with one
        self.assigned = {}  # NAME -> first line of the .src that assigns it
        self.shared = set()  # NAMEs of GLOBAL points: other programs may assign them
        self.redeclared = False  # a point declared twice: the last declaration counts
        self.in_data_list = {}  # (source index, NAME) -> line: the points each data list declares (once each)
        self.companions = {}  # file -> (source index, Lines, masked text) of other data lists read
        self.motion_spans = SpanTable(MOTION_SPANS)  # the spans of the motions, in order: all in the .src
        # (source, line) -> the shares a PTP's WITH clause gives its external axes for it alone (`with_external`)
        self.external_caps = {}

    def declared_in(self, file, line_no):
        """Read the point another data list (``$config.dat``, a GLOBAL one) declares at ``file``:``line_no``.

        The file is read once, as a companion source (`Source`): its point is
        corrected there, for every program that uses it.
        """
        if file not in self.companions:
            self.companions[file] = self.add_source(read_source(file, companion=True))
        index, lines, masked = self.companions[file]
        start = lines.starts[line_no - 1]
        self.declarations(index, masked, line_no, start, start + len(lines.line(line_no)))

    def scan_assignments(self, masked, lines):
        """Note the names the .src assigns (a declared speed is a constant only if nothing assigns it)."""
        for line_no, start, end in lines:
            text = statement_text(masked, start, end)
            if (m := ASSIGN.match(text)) and not NUMBER_DECL.match(text):
                self.assigned.setdefault(m.group(1).upper(), line_no)

    def number_value(self, text, index, line_no, original, field):
        """``(value, why)`` of a speed's text: a literal or REAL / INT data provably constant in the program.

        Constant: declared with a number in the .dat or .src (CONST, or not
        GLOBAL) and never assigned by the .src; else its value is set at run
        time (value None, and why).
        """
        name = self.sources[index].name
        if re.fullmatch(NUMBER, text):
            return finite(text, name, line_no, original, field), ""
        key = text.upper()
        if key in self.params:
            return None, f"{text}: routine parameter, set at run time (line {line_no})"
        if key in self.assigned:
            return None, f"{text} is assigned at run time (line {self.assigned[key]})"
        if key in self.numbers:
            return self.numbers[key]
        return None, f"{field} = {text}: set at run time (line {line_no})"
    def once_in_data_list(self, index, point, line_no, original):
        """Refuse ``point`` declared at ``line_no`` of a data list (a ``.dat``: one scope) that declares it
        already, whatever the case (``P3``, ``p3``): the controller refuses such a list."""
        if not self.sources[index].name.lower().endswith(".dat"):
            return  # a .src: each routine declares its own points
        first = self.in_data_list.setdefault((index, point.upper()), line_no)
        if first != line_no:
            fail(self.sources[index].name, line_no, original,
                 f"{point} is declared again (first at line {first}): a data list declares a name once")

    def add_source(self, source):
        self.sources.append(source)
        index = len(self.sources) - 1
        return index, Lines(source.text), mask(source.text, ";")

    def declarations(self, index, masked, line_no, start, end):
        """Handle a point, FDAT/PDAT/LDAT or TOOL_DATA/BASE_DATA line; True if it was one."""
        name = self.sources[index].name
        text = statement_text(masked, start, end)
        original = self.sources[index].text[start:end]
        m = DECL.match(text)
        if m:
            typ, point = m.group(1).upper(), m.group(2)
            body_start = start + m.start(3)
            if typ in ("FDAT", "PDAT", "LDAT"):
                self.data[point.upper()] = _members(m.group(3), body_start, index, name, line_no, original, False)
            else:
                members = _members(m.group(3), body_start, index, name, line_no, original)
                if GLOBAL_WORD.search(text, 0, m.start(2)):
                    self.shared.add(point.upper())
                self.redeclared |= point.upper() in self.points
                self.once_in_data_list(index, point, line_no, original)
                self.points[point.upper()] = len(self.targets)
                self.targets.append(_point(members, point, name, line_no, original, typ))
            return True
        if m := NUMBER_DECL.match(text):
            qualifiers = m.group(1).upper().split()
            if "GLOBAL" in qualifiers and "CONST" not in qualifiers:
                why = f"{m.group(2)}: GLOBAL data other programs may change, known at run time (line {line_no})"
                self.numbers[m.group(2).upper()] = (None, why)
            else:
                self.numbers[m.group(2).upper()] = (finite(m.group(3), name, line_no, original, m.group(2)), "")
            return True
        if DECL_START.match(text):
            fail(name, line_no, original, "malformed or cut point declaration")
        if m := DECL_BARE.match(text):
            place = f"{name}:{line_no}" if self.sources[index].companion else f"line {line_no}"
            for point in re.split(r"\s*,\s*", m.group(1)):
                self.unset[point.upper()] = f"{point} is declared without a value (set at run time, {place})"
            return True
        m = DATA.match(text)
        if m:
            which = "TOOL" if m.group(1).upper() == "TOOL_DATA" else "BASE"
            value = m.group(3)
            if value.startswith("{") and value.endswith("}") and value.count("{") == 1:
                members = _members(value[1:-1], start + m.start(3) + 1, index, name, line_no, original)
                (self.tools if which == "TOOL" else self.frames)[m.group(2)] = _frame(members, name, line_no, original)
                self.runtime[which].pop(m.group(2), None)
            else:
                self.runtime[which][m.group(2)] = f"{m.group(1).upper()}[{m.group(2)}] set at run time (line {line_no})"
            return True
        return False

    def statement(self, index, masked, line_no, start, end):
        """Handle one .src line."""
        name = self.sources[index].name
        text = statement_text(masked, start, end)
        original = self.sources[index].text[start:end]
        if m := DEF_LINE.match(text):
            self.params = {p.split(":")[0].strip().upper() for p in m.group(1).split(",") if p.strip()}
            self.steps.append(Step("routine", DEF.match(text).group(1), line=line_no, source=index))
        m = MOTION.match(text)  # first: most lines of a long program are motions, and no declaration is one
        if m:
            self.items.append(self.motion(m, index, start, line_no, original))
            return
        self.flow_step(text, index, line_no)
        if self.declarations(index, masked, line_no, start, end):
            self.items.append(Statement(line_no, original))
            return
        self.state(text, index, start, name, line_no, original)
        self.items.append(Statement(line_no, original))

    def flow_step(self, text, index, line_no):
        """Note a statement that changes the order the program runs in (`trajcomp.programs.flow.Step`)."""
        m = FIRST_WORD.match(text)
        if m is None:
            return
        word = m.group(1).upper()
        kind = FLOW_WORDS.get(word)
        if kind == "jump":
            target = JUMP_TO.match(text)
            self.steps.append(Step("jump", target.group(1) if target else "", False, line_no, index))
        elif kind is not None:
            self.steps.append(Step(kind, line=line_no, source=index))
        elif m.group(2) == "(":  # a routine: this file's is followed, another .src's is not known
            why = f"a routine of {word.lower()}.src, which may move the arm and set speeds" \
                if word in self.siblings else None
            self.steps.append(Step("call", m.group(1), why, line_no, index))
        elif m.group(2):
            self.steps.append(Step("label", m.group(1), line=line_no, source=index))

    def give(self, group, value, why, span, line_no, index, axis=None):
        """Put a speed setting in force: JOINT ``value`` % of the axis of flow group ``axis`` (`JOINT_GROUPS`: an
        arm's or an external axis's; None: all, as ``BAS(#VEL_PTP)`` sets them), LINEAR ``value`` mm/s; ``why`` it is
        known at run time only, ``span`` the number that states it (re-timing writes there)."""
        setting = (value, why, span)
        if group == LINEAR:
            self.speed_cp, self.speed_why[LINEAR], self.speed_spans[LINEAR] = setting
            self.steps.append(Step("set", "cp", setting, line_no, index))
            return
        for n in range(len(JOINT_GROUPS)) if axis is None else [JOINT_GROUPS.index(axis)]:
            self.axes[n] = setting
            self.steps.append(Step("set", JOINT_GROUPS[n], setting, line_no, index))
        self.speed_ptp, self.speed_why[JOINT], self.speed_spans[JOINT] = in_force(self.axes)

    def select(self, which, value, why=""):
        """Make tool or base ``value`` active (``why``: it is only known at run time)."""
        why = why or self.runtime[which].get(value, "")
        if which == "TOOL":
            self.tool, self.tool_why = value, why
        else:
            self.base, self.base_why = value, why

    def state(self, text, index, start, name, line_no, original):
        """Track tool, base, speed and zone statements."""
        if m := SYSVAR.match(text):
            which, value = m.group(1).upper(), m.group(2)
            ref = DATA_REF.match(value)
            if ref and (ref.group(1).upper() == "TOOL_DATA") == (which == "TOOL"):
                self.select(which, ref.group(2))
            elif value.upper() == "$NULLFRAME":
                self.select(which, "0")
            elif value.startswith("{") and value.endswith("}") and value.count("{") == 1:
                members = _members(value[1:-1], start + m.start(2) + 1, index, name, line_no, original)
                table = self.tools if which == "TOOL" else self.frames
                frame = _frame(members, name, line_no, original)
                # the same value set again is the same tool or base
                key = next((k for k, T in table.items() if k.startswith(which) and np.array_equal(T, frame)),
                           f"{which} line {line_no}")
                table[key] = frame
                self.select(which, key)
            else:
                self.select(which, None, f"${which} = {value} set at run time (line {line_no})")
        elif m := BAS.match(text):
            what, value = m.group(1).upper(), m.group(2)
            if what in BAS_FRAMES:
                if not re.fullmatch(NUMBER, value):
                    self.select(what, None, f"BAS(#{what}, {value}) set at run time (line {line_no})")
                else:
                    self.select(what, str(integer(value, name, line_no, original, what)))
                return
            self.set_speed(BAS_SPEEDS[what], m, 2, index, start, line_no, original, f"BAS(#{what})")
        elif m := ACT.match(text):
            self.activate(m.group(1).upper(), m.group(2).upper(), index, line_no, original)
        elif m := SPLINE.match(text):
            own = m.group(1) and self.with_speed(m.group(1), start + m.start(1), index, line_no, original, LINEAR)
            self.block_caps = self.with_external(m.group(1), index, line_no, original) if m.group(1) else {}
            if own:  # SPLINE WITH $VEL.CP = v: the block's motions run at v, the speed before it after ENDSPLINE
                self.outside_spline = (self.speed_cp, self.speed_why[LINEAR], self.speed_spans[LINEAR])
                self.give(LINEAR, *own, line_no, index)
        elif END_SPLINE.match(text):
            self.block_caps = {}
            if self.outside_spline is not None:
                self.give(LINEAR, *self.outside_spline, line_no, index)
                self.outside_spline = None
        elif m := VEL_CP.match(text):
            self.set_speed(LINEAR, m, 1, index, start, line_no, original, "$VEL.CP")
        elif m := VEL_AXIS.match(text):
            self.set_speed(JOINT, m, 2, index, start, line_no, original, f"$VEL_AXIS[{m.group(1)}]",
                           AXIS_GROUPS[int(m.group(1)) - 1])
        elif m := VEL_EXTAX.match(text):  # the external axis's own % of its maximum: a PTP moving it runs no faster
            self.set_speed(JOINT, m, 2, index, start, line_no, original, f"$VEL_EXTAX[{m.group(1)}]",
                           EXTERNAL_GROUPS[int(m.group(1)) - 1])
        elif m := VEL.match(text):
            members = _members(m.group(1), start + m.start(1), index, name, line_no, original, False)
            if "cp" in members:
                span = members["cp"]
                value, why = self.number_value(span.text, index, line_no, original, "$VEL.CP")
                self.give(LINEAR, None if value is None else value * 1000.0, why, span, line_no, index)
        elif m := ACC_CP.match(text):
            self.accelerate("acc_cp", m.group(1), 1000.0, index, line_no, original, "$ACC.CP")
        elif m := ACC.match(text):
            members = _members(m.group(1), start + m.start(1), index, name, line_no, original, False)
            if "cp" in members:
                self.accelerate("acc_cp", members["cp"].text, 1000.0, index, line_no, original, "$ACC.CP")
            for member in sorted(set(members) & {"ori1", "ori2"}):
                self.accelerate(f"acc_{member}", members[member].text, 1.0, index, line_no, original,
                                f"$ACC.{member.upper()}")
        elif m := ACC_ORI.match(text):
            self.accelerate(f"acc_{m.group(1).lower()}", m.group(2), 1.0, index, line_no, original,
                            f"$ACC.{m.group(1).upper()}")
        elif m := ACC_AXIS.match(text):
            self.accelerate(ACC_GROUPS[int(m.group(1)) - 1], m.group(2), 1.0, index, line_no, original,
                            f"$ACC_AXIS[{m.group(1)}]")
        elif m := ACC_EXTAX.match(text):  # the external axis's own % of its maximum acceleration
            self.accelerate(EXTERNAL_ACC_GROUPS[int(m.group(1)) - 1], m.group(2), 1.0, index, line_no, original,
                            f"$ACC_EXTAX[{m.group(1)}]")
        elif m := BAS_ACC_PTP.match(text):
            for group in ACC_GROUPS:
                self.accelerate(group, m.group(1), 1.0, index, line_no, original, "BAS(#ACC_PTP)")
        elif m := APO.match(text):
            self.zone = finite(m.group(1), name, line_no, original, "$APO.CDIS")

    def accelerate(self, group, text, scale, index, line_no, original, field):
        """An acceleration setting of ``group`` (``acc_cp``: the TCP's, m/s^2 read as mm/s^2 by ``scale``;
        ``accN``: axis N's, %) from the value ``text``, for the motions it reaches (`_flow_speeds`)."""
        value, why = self.number_value(text, index, line_no, original, field)
        setting = (None if value is None else value * scale, why)
        self.steps.append(Step("set", group, setting, line_no, index))

    def set_speed(self, group, m, at, index, start, line_no, original, field, axis=None):
        """A statement sets the speed of the motions of ``group`` (JOINT: % of the axis of flow group ``axis`` or
        all, LINEAR: m/s) to match ``m``'s group ``at``."""
        value, why = self.number_value(m.group(at), index, line_no, original, field)
        if group == LINEAR and value is not None:
            value = value * 1000.0
        span = Span(index, start + m.start(at), start + m.end(at), m.group(at))
        self.give(group, value, why, span, line_no, index, axis)

    def with_speed(self, clause, at, index, line_no, original, kind):
        """``(speed, why, span)`` a spline motion's WITH clause sets for it alone; None if it sets none.

        ``$VEL = SVEL_CP(v, ..)`` and ``$VEL.CP = v`` (m/s, returned in
        mm/s), ``$VEL_AXIS[n] = SVEL_JOINT(p)`` (%); any other ``$VEL``
        value is set at run time.
        """
        for piece, position in split_top(clause, at):
            m = WITH_SPEED.search(piece)
            if m is None or m.start() != len(piece) - len(piece.lstrip()):
                continue
            rhs, rhs_at = piece[m.end():], position + m.end()
            call = WITH_CALL.match(rhs)
            if call:
                args = split_top(rhs[call.end():rhs.rindex(")")], rhs_at + call.end())
                rhs, rhs_at = args[0]
            text = rhs.strip()
            span = Span(index, rhs_at + len(rhs) - len(rhs.lstrip()), rhs_at + len(rhs.rstrip()), text)
            field = m.group().rstrip("= \t")
            if not text or (not call and "[" not in m.group() and ".CP" not in m.group().upper()):
                return None, f"{field}: set at run time (line {line_no})", span
            value, why = self.number_value(text, index, line_no, original, field)
            scale = 1000.0 if kind != JOINT else 1.0
            return (None if value is None else value * scale), why, span
        return None

    def with_external(self, clause, index, line_no, original, found=None):
        """The shares a spline motion's (or block's) WITH clause gives its external axes for that motion (the
        block's motions) alone: ``{"VEL": (%, why), "ACC": (%, why)}`` from ``$VEL_EXTAX[n] = p`` and
        ``$ACC_EXTAX[n] = p`` (a literal or a constant, `number_value`; value None where set at run time, with
        why), the slowest of each and of those ``found`` already (a block's); a setting none gives has no key."""
        found = dict(found or {})
        for piece, _ in split_top(clause):
            m = WITH_EXTAX.match(piece.strip())
            if m is None:
                continue
            which, field = m.group(1).upper(), f"${m.group(1).upper()}_EXTAX[{m.group(2)}]"
            value, why = self.number_value(piece.strip()[m.end():].strip(), index, line_no, original, field)
            known = found.get(which, (np.inf, ""))[0]
            if known is not None and (value is None or value < known):
                found[which] = (value, why)
        return found

    def activate(self, kind, data_name, index, line_no, original):
        """FDAT_ACT / PDAT_ACT / LDAT_ACT: tool, base, speed and zone of the next motion."""
        name = self.sources[index].name
        data = self.data.get(data_name)
        if kind == "FDAT":
            if data is None:
                why = f"FDAT {data_name} is not in this program: its tool and base are unknown (line {line_no})"
                self.select("TOOL", None, why)
                self.select("BASE", None, why)
                return
            for which, member in (("TOOL", "tool_no"), ("BASE", "base_no")):
                if member in data:
                    self.select(which, str(integer(data[member].text, name, line_no, original, member.upper())))
        elif data is not None:
            if "vel" in data:
                vel = finite(data["vel"].text, name, line_no, original, "VEL")
                joint = kind == "PDAT"
                self.give(JOINT if joint else LINEAR, vel if joint else vel * 1000.0, "", None, line_no, index)
            if "apo_dist" in data:
                self.zone = finite(data["apo_dist"].text, name, line_no, original, "APO_DIST")

    def motion(self, m, index, start, line_no, original):
        """A Motion from a PTP/LIN/CIRC line; named points are resolved at the end (`_resolve`)."""
        name = self.sources[index].name
        kind = MOTIONS[m.group(1).upper()]
        args, *with_clause = WITH_WORD.split(m.group(3), maxsplit=1)
        own_speed = None
        if with_clause:
            self.spline_frames(with_clause[0], name, line_no, original)
            clause_at = start + m.start(3) + len(m.group(3)) - len(with_clause[0])
            own_speed = self.with_speed(with_clause[0], clause_at, index, line_no, original, kind)
        caps = self.with_external(with_clause[0] if with_clause else "", index, line_no, original,
                                  self.block_caps) if kind == JOINT else {}
        if caps:
            self.external_caps[(index, line_no)] = caps
        offset = start + m.start(3)
        approx = APPROX.search(args)
        zone = self.zone if approx else None
        if approx:
            args = args[: approx.start()]
        parts, position = [], 0
        for piece, _ in split_top(args):
            parts.append((piece, offset + position))
            position += len(piece) + 1
        wanted = 2 if kind == CIRCULAR else 1
        if len(parts) < wanted or not parts[0][0].strip():
            fail(name, line_no, original, f"{m.group(1).upper()} needs {wanted} target(s)")
        reason = ""
        if m.group(2):
            found, reason = [None] * wanted, "relative motion: its position depends on where the arm is"
        else:
            found = [self.target(piece, at, index, name, line_no, original) for piece, at in parts[:wanted]]
            if None in found:
                written = " ".join(parts[found.index(None)][0].split())
                reason = (f"an element of a point array: {written} (trajcomp reads single points, not arrays' "
                          "elements)" if ARRAY_ELEMENT.fullmatch(written) else
                          f"position computed at run time: {written}")
        roles = ("via_name", "target_name")[2 - wanted:]
        spans = {"motion": (start + m.start(1), start + m.end(1))}  # offsets: the spans are columns (`_resolve`)
        spans |= {role: name_offsets(piece, at) for role, (piece, at), point in zip(roles, parts, found)
                  if isinstance(point, _Named)}  # where a per-use copy's name is written (`trajcomp.formats.uses`)
        reason = reason or self.tool_why or self.base_why
        group = JOINT if kind == JOINT else LINEAR
        speed, unit = (self.speed_ptp, "%") if kind == JOINT else (self.speed_cp, "mm/s")
        speed_why = self.speed_why[group]
        if own_speed is not None:  # this motion's own, in its WITH clause: re-timing writes there
            speed, speed_why, with_span = own_speed
            spans["speed_with"] = (with_span.start, with_span.end)
        elif self.speed_spans[group] is not None:  # the statement that set it: re-timing writes there
            spans["speed"] = (self.speed_spans[group].start, self.speed_spans[group].end)
        speed, speed_why = _capped(speed, speed_why, caps.get("VEL"))
        share, share_why = caps.get("ACC", (None, ""))
        speed_why = speed_why or (f"acceleration: {share_why}" if share_why else "")
        self.motion_spans.add(spans)
        return Motion(
            kind=kind,
            target=found[-1],
            via=found[0] if kind == CIRCULAR else None,
            speed=speed,
            speed_unit=unit,
            zone=zone,
            tool=self.tool,
            frame=self.base,
            line=line_no,
            text=original.strip(),
            reason=reason,
            speed_why=speed_why,
            acceleration_share=None if share is None or share >= 100.0 else share / 100.0,
        )

    def spline_frames(self, clause, name, line_no, original):
        """Tool and base of a spline inline form: ``$TOOL=STOOL2(FP1), $BASE=SBASE(FP1.BASE_NO)``."""
        for which, pattern in (("TOOL", WITH_TOOL), ("BASE", WITH_BASE)):
            if m := pattern.search(clause):
                data = self.data.get(m.group(1).upper(), {})
                member = data.get(f"{which.lower()}_no")
                if member is None:
                    self.select(which, None, f"FDAT {m.group(1)} is not in this program: {which.lower()} unknown "
                                             f"(line {line_no})")
                else:
                    self.select(which, str(integer(member.text, name, line_no, original, f"{which}_NO")))
            elif re.search(rf"\${which}\s*=", clause, re.I):
                self.select(which, None, f"${which} set at run time in WITH (line {line_no})")

    def target(self, piece, at, index, name, line_no, original):
        """Target index of an inline aggregate, `_Named` for a point name, None for an expression."""
        stripped = piece.strip()
        if stripped.startswith("{") and stripped.endswith("}") and stripped.count("{") == 1:
            body_at = at + piece.index("{") + 1
            members = _members(stripped[1:-1], body_at, index, name, line_no, original)
            if not set(AXES if "a1" in members else POSE) <= set(members):
                return None  # LIN {Z 500}: the members not given are the arm's current ones, known at run time
            self.targets.append(_point(members, "", name, line_no, original, None))
            return len(self.targets) - 1
        if NAME.match(stripped):
            return _Named(stripped, line_no, stripped.upper() in self.params)
        return None


def read(path):
    """Read a KRL .src and its .dat (same name, beside it, if there is one).

    The lines a CAM post-processor or KUKA's editor writes (points declared
    one a line, `WRITTEN_POINT`; motions to them, `WRITTEN_MOTION`; motions
    to points written inline, `INLINE_MOTION`) are read at once as columns; every other line one by one, in order, its
    tool, base, speed and zone in force for the motions read at once after
    it (`line_walk.Walk`).

    Raises
    ------
    ReadError
        Malformed or cut text, a .dat without DEFDAT or ENDDAT, or motions
        to points the program does not define (all named with their lines).
    """
    path = Path(path)
    reader = _Reader()
    src_index, src_lines, src_masked = reader.add_source(read_source(path))
    if not DEF.search(src_masked):
        raise ReadError(f"{path}: not a KRL program: no DEF line")
    src = reader.sources[src_index]
    written, inline = at_once.written_motions(src_index, src_masked, src_lines)
    # the motion lines read at once open and close no block: the runs of other lines between them
    check_closed(src, src_masked, BLOCK_OPENS, BLOCK_CLOSES, CLOSING,
                 runs_between(written["start"], written["end"], len(src_masked)), OUTSIDE_ROUTINES)
    others = line_walk.other_lines(src_lines, written["line"])
    reader.scan_assignments(src_masked, others)
    dat_path, table = _sibling_dat(path), None
    if dat_path is not None:
        dat_index, dat_lines, dat_masked = reader.add_source(read_source(dat_path))
        if not DEFDAT.search(dat_masked):
            raise ReadError(f"{dat_path}: not a KRL data list: no DEFDAT line")
        tail = max(0, len(dat_masked) - 65536)  # ENDDAT closes a data list: looked for near its end first
        if not (ENDDAT.search(dat_masked, tail) or ENDDAT.search(dat_masked)):
            raise ReadError(f"{dat_path}: no ENDDAT: the data list is cut off")
        point_lines, table, shared = at_once.written_points(dat_index, dat_masked, dat_lines)
        names = table.name if table is not None else ()
        rows = 0

        def declare_rows(before):
            """The table's points declared before line ``before``, in order."""
            nonlocal rows
            stop = int(np.searchsorted(point_lines, before))
            declared = [name.upper() for name in names[rows:stop]]
            for name, line_no in zip(names[rows:stop], point_lines[rows:stop].tolist()):
                reader.once_in_data_list(dat_index, name, line_no, dat_lines.line(line_no))
            known = len(reader.points)
            reader.points.update(zip(declared, range(len(reader.targets), len(reader.targets) + len(declared))))
            reader.redeclared |= len(reader.points) < known + len(declared)  # a name declared before
            reader.targets.extend(range(rows, stop))  # rows of the table
            reader.shared.update(itertools.compress(declared, shared[rows:stop].tolist()))  # others may assign them
            rows = stop

        for line_no, start, end in line_walk.other_lines(dat_lines, point_lines):
            declare_rows(line_no)
            reader.declarations(dat_index, dat_masked, line_no, start, end)
        declare_rows(len(dat_lines.starts) + 1)
    reader.siblings = {p.stem.upper() for p in path.parent.iterdir() if p.suffix.lower() == ".src" and p != path}
    walk = line_walk.Walk(reader, src_index, src_masked, written, 0 if table is None else len(table))
    for line_no, start, end in others:
        walk.motions_before(line_no)
        reader.statement(src_index, src_masked, line_no, start, end)
    walk.motions_before(len(src_lines.starts) + 1)
    items, resolved = _resolve(reader, path, dat_path, walk)
    targets = line_walk.targets(reader.targets, table, inline)
    notes = _controller_tables(reader, path, walk)
    if not len(walk.rows):  # none read at once
        program = Program("krl", path.stem, items, targets, reader.tools, reader.frames, tuple(reader.sources),
                          notes=notes)
    else:
        motions = MotionTable.merged([MotionTable.of([i for i in items if isinstance(i, Motion)]),
                                      walk.table(resolved)])
        statements = StatementTable.of([i for i in items if not isinstance(i, Motion)])
        program = Program("krl", path.stem, ItemRows(statements, motions), targets, reader.tools, reader.frames,
                          tuple(reader.sources), notes=notes)
    # calls, branches, loops, jumps or waits: speeds and starts as the program runs; accelerations, which the
    # reading in file order does not hold, whenever the program sets one
    accelerating = any(step.kind == "set" and step.name.startswith("acc") for step in reader.steps)
    speeds = functools.partial(_flow_speeds, caps=reader.external_caps)
    return flow.program_followed(program, reader.steps, reader.initial, speeds, settings=accelerating)


def in_force(settings):
    """``(value, why, span)`` a motion runs with under every speed setting of ``settings`` that can reach it.

    Each setting is ``(value, why, span)`` (`_Reader.give`) or a
    `trajcomp.programs.flow.Unknown`. One setting reaching it (in every
    group) is that one; several are their slowest, written nowhere (no
    span); one known at run time only makes the motion's speed so, with why.
    """
    settings = set(settings)
    for setting in settings:
        if isinstance(setting, Unknown):
            return None, setting.why, None
    for value, why, _ in settings:
        if value is None:
            return None, why, None
    if len(settings) == 1:
        return next(iter(settings))
    return min(value for value, _, _ in settings), "", None


def _capped(speed, why, cap):
    """A PTP's speed ``(%, why)`` under ``cap``, the ``(%, why)`` its WITH clause gives an external axis for it
    alone (`_Reader.with_external`; None: none): the slower; set at run time where the cap is."""
    if cap is None or why or speed is None:
        return speed, why
    return (None, cap[1]) if cap[0] is None else (min(speed, cap[0]), "")


def _flow_speeds(table, reached, caps):
    """The speed columns of a KRL program's motions from the settings that can reach each
    (`trajcomp.programs.flow.followed`): PTP the slowest of its axes' and external axes', and of those its WITH
    clause gives its external axes (``caps``: `_Reader.external_caps`), LIN and CIRC the TCP's; a spline motion's
    own WITH speed stays. The spans of the motions whose setting moved to another statement change."""
    own = table.span_offsets("speed_with")[1] >= 0
    joint = table.kind == JOINT
    speed, why = np.array(table.speed, dtype=float), np.array(table.speed_why, dtype=object)
    span = np.full(len(table), None, dtype=object)
    for r, settings in enumerate(reached.settings):
        rows = np.arange(len(table))[reached.rows(r)]
        for groups, members in ((JOINT_GROUPS, joint[rows]), (("cp",), ~joint[rows])):
            at = rows[members & ~own[rows]]
            if len(at):
                value, why[at], span[at] = in_force([s for group in groups for s in settings[group]])
                speed[at] = np.nan if value is None else value
    capped = [(k, caps[key]) for k, key in enumerate(zip(table.source.tolist(), table.line.tolist()))
              if key in caps] if caps else []
    for k, cap in capped:
        value, why[k] = _capped(None if np.isnan(speed[k]) else float(speed[k]), why[k], cap.get("VEL"))
        speed[k] = np.nan if value is None else value
    _, start, end = table.span_offsets("speed")
    new = np.array([(-1, -1) if s is None else (s.start, s.end) for s in span.tolist()], dtype=np.int64).reshape(-1, 2)
    moved = np.flatnonzero(~own & ((new[:, 0] != start) | (new[:, 1] != end)))
    spans = [{**{role: value for role, value in table.spans[k].items() if role != "speed"},
              **({} if span[k] is None else {"speed": span[k]})} for k in moved.tolist()]
    columns = {"speed": speed, "speed_why": why} | _flow_accelerations(table, reached, joint, why, capped)
    return columns | ({"spans": (moved, spans)} if len(moved) else {})


def _flow_accelerations(table, reached, joint, why, capped):
    """The acceleration columns of a KRL program's motions from the settings that can reach each: a PTP's share
    of the arm's (the slowest of its axes' ``$ACC_AXIS`` and external axes' ``$ACC_EXTAX``, %, and of those its
    WITH clause gives its external axes, ``capped``: ``[(row, caps)]``), a LIN's or CIRC's TCP acceleration
    (``$ACC.CP``, mm/s^2), the slowest that can reach it; where one is the controller's own (none set) and others are set, the
    TCP's is not known (none is stated), each axis's own is 100 %. One set at run time leaves the motion as
    written (``why``, changed in place); so does an orientation acceleration (``$ACC.ORI1``, ``ORI2``) stated for a
    LIN or CIRC, which the timing does not model (its joint limits may turn the tool faster)."""
    share, tcp = np.full(len(table), np.nan), np.array(table.acceleration, dtype=float)
    for r, settings in enumerate(reached.settings):
        rows = np.arange(len(table))[reached.rows(r)]
        for groups, members in ((PTP_ACC_GROUPS, joint[rows]), (("acc_cp",), ~joint[rows])):
            at = rows[members]
            found = [s for group in groups for s in settings[group]]
            unknown = [s.why if isinstance(s, Unknown) else s[1] for s in found if isinstance(s, Unknown) or s[1]]
            if not len(at):
                continue
            if unknown:
                why[at[why[at] == ""]] = f"acceleration: {unknown[0]}"
            elif groups == PTP_ACC_GROUPS:
                least = min(100.0 if value is None else value for value, _ in found)
                share[at] = least / 100.0 if least < 100.0 else np.nan
            elif all(value is not None for value, _ in found):
                tcp[at] = min(value for value, _ in found)
        at = rows[~joint[rows]]
        stated = [(group[4:].upper(), s) for group in ORI_GROUPS for s in settings[group]
                  if isinstance(s, Unknown) or s[0] is not None or s[1]]
        if len(at) and stated:
            group, s = stated[0]
            value = "set at run time" if isinstance(s, Unknown) or s[1] else f"{s[0]:g} deg/s^2"
            why[at[why[at] == ""]] = (f"$ACC.{group} {value}: an orientation acceleration, which the timing does not "
                                      "model: left as written")
    for k, caps in capped:
        value, cap_why = caps.get("ACC", (100.0, ""))
        if cap_why:
            why[k] = why[k] or f"acceleration: {cap_why}"
        elif value < 100.0:
            share[k] = np.fmin(share[k], value / 100.0)
    return {"acceleration_share": share, "acceleration": tcp}


def _controller_tables(reader, path, walk):
    """Read into ``reader``'s tools and bases those its motions select by number (``TOOL_DATA[2]``,
    ``BAS(#BASE, 8)``) and the program does not define, from its controller's ``$config.dat``
    (`trajcomp.formats.krl.config_dat`); the report's notes on them (tuple of str)."""
    used = {"TOOL": {state[0] for state in walk.states}, "BASE": {state[1] for state in walk.states}}
    for item in reader.items:
        if isinstance(item, Motion):
            used["TOOL"].add(item.tool)
            used["BASE"].add(item.frame)
    defined = {"TOOL": reader.tools, "BASE": reader.frames}
    wanted = {which: {n for n in numbers if n is not None and n.isdigit() and n not in defined[which]}
              for which, numbers in used.items()}

    def frame(aggregate, line, original):
        members = _members(aggregate[1:-1], 0, None, config_dat.FILE_NAME, line, original)
        return _frame(members, config_dat.FILE_NAME, line, original)

    found, notes = config_dat.tables(path, wanted, frame)
    reader.tools.update(found["TOOL"])
    reader.frames.update(found["BASE"])
    return notes


def _visible(file, match):
    """Whether a program sees a point another data list declares: all of ``$config.dat``'s, GLOBAL ones of others."""
    return file.name.lower() == "$config.dat" or GLOBAL_WORD.search(match.group(0)) is not None


def _resolve(reader, path, dat_path, walk):
    """The items with named points resolved, points changed at run time found, and routine arguments noted.

    A point assigned anywhere in the code (``XP1 = ...``, ``XP1.Z = ...``)
    holds a run-time value, so none of its motions is compensated.

    Returns
    -------
    items : tuple
        The items read one by one.
    resolved : tuple
        The motions read at once (`line_walk.Walk`) resolved as the one-by-one
        read resolves its own: target indices (N,), ``{row: reason}`` of
        the rows whose point is changed at run time, their ``refs``
        (tuples) and whether each is a home position (ndarray of bool).
    """
    assigned, items = {}, []
    # other data lists beside it, and $config.dat beside it or in a backup's R1/System (KRC/R1/Program/x.src)
    config = config_dat.find(path)
    folders = [path.parent] + ([config.parent] if config is not None and config.parent != path.parent.resolve() else [])
    elsewhere = DeclaredElsewhere(dat_path or path, folders, (".dat",), GLOBAL_POINT, ";", assignment=ASSIGN,
                                  code=(".src", ".sub"), visible=_visible)
    for item in reader.items:
        if isinstance(item, Statement) and (m := ASSIGN.match(code_of(item.text, ";"))):
            assigned.setdefault(m.group(1).upper(), item.line)
    missing = []

    def lookup(ref):
        """(index or None, why) of a motion argument."""
        if not isinstance(ref, _Named):
            return ref, ""
        key = ref.name.upper()
        if ref.parameter:
            return None, f"{ref.name}: routine parameter, known at run time"
        if key in assigned and key in reader.points:
            return None, f"{ref.name} is changed at run time (line {assigned[key]})"
        if ref.name.startswith("$"):
            return None, f"{ref.name}: system variable, known at run time"
        if HOME.match(ref.name) and key not in reader.points:
            return None, f"{ref.name}: home position of $config.dat, not in this program (left as written)"
        if key not in reader.points and key not in reader.unset and (found := elsewhere.find(key)):
            reader.declared_in(*found)
            reader.shared.add(key)
        if key in reader.points:
            if key in reader.shared and (where := elsewhere.assigned(key)):
                return None, f"{ref.name} is changed at run time ({where})"
            return reader.points[key], ""
        if key in reader.unset:
            return None, reader.unset[key]
        missing.append((ref.name, ref.line))
        return None, ""

    motion_spans = reader.motion_spans.columns(0, reader.sources[0].text)  # the motions' rows, in order
    motion_rows = iter(range(len(motion_spans)))
    for item in reader.items:
        if isinstance(item, Motion):
            (via, via_why), (target, why) = lookup(item.via), lookup(item.target)
            reason = via_why or why or item.reason
            spans = motion_spans.row(next(motion_rows))
            if reason:
                named = {w.upper() for w in WORD.findall(mask(item.text, ";"))}
                known = tuple(reader.points[w] for w in sorted(named) if w in reader.points)
                home = isinstance(item.target, _Named) and bool(HOME.match(item.target.name))
                item = dataclasses.replace(item, target=None, via=None, reason=reason, axis_position=home, spans=spans,
                                           refs=known + tuple(i for i in (via, target) if isinstance(i, int)))
            else:
                item = whole_circle(replaced(item, target=target, via=via, spans=spans))
        else:
            named = {w.upper() for w in WORD.findall(mask(item.text, ";"))}
            refs = tuple(reader.points[w] for w in sorted(named) if w in reader.points)
            if refs and not DECL.match(item.text):
                item = dataclasses.replace(item, refs=refs)
        items.append(item)
    if missing:
        hint = (f"are they declared in {dat_path.name}? (cut or damaged data list; no other data list beside it, "
                "nor $config.dat, declares them)" if dat_path is not None else
                f"no {path.stem}.dat beside {path.name}, nor another data list declaring them")
        unresolved(path.name, missing, hint)
    return tuple(items), _resolved_rows(reader, walk, assigned, elsewhere)


def _resolved_rows(reader, walk, assigned, elsewhere):
    """`_resolve`'s lookup of the motions read at once, all at once (their points are declared: `line_walk.Walk`)."""
    text, written = reader.sources[walk.index].text, walk.written
    rows = np.frombuffer(walk.rows, dtype=np.int64)
    target = np.frombuffer(walk.point, dtype=np.int64).copy()
    reason, refs, home = {}, [], []
    if not (reader.redeclared or assigned or reader.shared):
        return target, reason, refs, np.array(home, dtype=bool)
    named = np.flatnonzero(written["inline"][rows] < 0)  # an inline point is no name: nothing assigns it
    names = [text[a:b] for a, b in zip(written["name_start"][rows[named]].tolist(),
                                       written["name_end"][rows[named]].tolist())]
    for k, name in zip(named.tolist(), names):
        key = name.upper()
        target[k] = reader.points[key]  # a point declared again after the motion: the last declaration
        if key in assigned:
            where = f"line {assigned[key]}"
        elif not (key in reader.shared and (where := elsewhere.assigned(key))):
            continue
        reason[k] = f"{name} is changed at run time ({where})"
        named = {w.upper() for w in WORD.findall(mask(text[written["start"][rows[k]]:written["end"][rows[k]]], ";"))}
        refs.append(tuple(reader.points[w] for w in sorted(named) if w in reader.points))
        home.append(bool(HOME.match(name)))
    return target, reason, refs, np.array(home, dtype=bool)
