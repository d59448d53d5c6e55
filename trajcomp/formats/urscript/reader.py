"""The URScript reader: a script's motions, pose variables, frames and TCPs into a `Program` (see `trajcomp.formats.urscript`)."""

import bisect
import dataclasses
import functools
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError
from trajcomp.formats.number_fields import NUMBER, offset_type
from trajcomp.formats.text import (
    INDENT,
    JOINT_LIMIT,
    LENGTH_LIMIT,
    Lines,
    check_closed,
    fail,
    finite,
    mask,
    read_source,
    spans,
    split_top,
    unresolved,
)
from trajcomp.formats.urscript import grammar
from trajcomp.formats.urscript.grammar import JOINTS, NEAR, POSE
from trajcomp.formats.urscript.lines import FUNCTIONS, cam_lines
from trajcomp.formats.urscript.polyscope import notes as polyscope_notes
from trajcomp.programs import flow
from trajcomp.programs.flow import Step
from trajcomp.programs.program import Program
from trajcomp.programs.items import CIRCULAR, JOINT, Motion, SpanColumns, SpanTable, Statement, Target
from trajcomp.programs.tables import MotionTable, StatementTable, TargetTable, TextSlices, repeated
from trajcomp.arm.transforms import rotvec_to_matrix

ROLES = POSE + JOINTS + NEAR  # the roles of a target's spans
TIMING = ("t", "v", "end")  # the roles of a motion's spans: where re-timing writes
KINDS = {function: signature.kind for function, signature in grammar.MOTIONS.items()}
_PARENTHESIS = re.compile(r"[()]")
_KINDS = np.array([KINDS[f] for f in FUNCTIONS], dtype=object)  # the kind of each of `FUNCTIONS`
_DEFAULT_SPEEDS = np.array([float(grammar.MOTIONS[f].default_speed) for f in FUNCTIONS])  # and its v without one
_UNITS = np.array(["mm/s", "rad/s", "s"], dtype=object)  # of a TCP speed, a movej's speed, a time


def _closing(text, open_at):
    """Index of the parenthesis closing the one at ``open_at``."""
    depth = 0
    for m in _PARENTHESIS.finditer(text, open_at):
        depth += 1 if m.group() == "(" else -1
        if depth == 0:
            return m.start()
    return -1


def _literal_poses(masked, ranges):
    """The poses of the pose literals in some parts of a script, computed together: ``{offset of the literal's x:
    T (4, 4)}``, mm.

    ``ranges``: ``(start, end)`` offsets of the parts. Literals with a number out of range are left out (their
    reading refuses them).
    """
    found = [m for start, end in ranges for m in grammar.POSE_LITERAL.finditer(masked, start, end)]
    values = np.array([m.groups() for m in found], dtype=float).reshape(-1, 6)
    keep = np.flatnonzero((np.isfinite(values) & (np.abs(values) <= LENGTH_LIMIT / 1000.0)).all(axis=1))
    T = poses(values[keep])
    return {found[k].start(1): T[row] for row, k in enumerate(keep.tolist())}


def poses(values):
    """T (N, 4, 4), mm, from x, y, z (m) and rotation vectors (rad), (N, 6)."""
    T = np.tile(np.eye(4), (len(values), 1, 1))
    T[:, :3, :3] = rotvec_to_matrix(values[:, 3:])
    T[:, :3, 3] = values[:, :3] * 1000.0
    return T


def pose(values):
    """T (4, 4), mm, from x, y, z (m) and a rotation vector (rad)."""
    T = np.eye(4)
    T[:3, :3] = rotvec_to_matrix(values[3:])
    T[:3, 3] = np.asarray(values[:3]) * 1000.0
    return T


@dataclasses.dataclass(frozen=True)
class _Named:
    """A motion argument naming a variable never assigned in the script (checked at the end)."""

    name: str
    line: int


class _Blocks:
    """The blocks of a script (``def``, ``sec``, ``thread``, ``if``, ``while``, ``for`` .. ``end``): in which a line runs.

    Parameters
    ----------
    masked : str
        The script, comments and strings blanked.
    lines : Lines
    parts : list of (int, int)
        Offsets of the runs of lines read one by one (every block's first
        and last line is one of them).
    """

    def __init__(self, masked, lines, parts):
        found = sorted((m.start(), m.group(1)) for start, end in parts
                       for pattern in (grammar.BLOCK_OPENS, grammar.BLOCK_CLOSES)
                       for m in pattern.finditer(masked, start, end))
        spans, open_blocks = [], []  # (first line, last line, word, depth); the blocks open at a line
        for offset, word in found:
            line = lines.number(offset)
            if word != "end":
                open_blocks.append((line, word, len(open_blocks)))
            elif open_blocks:  # `check_closed` has checked that every block is closed
                first, opened, depth = open_blocks.pop()
                spans.append((first, line, opened, depth))
        first, last, word, depth = zip(*spans) if spans else ((), (), (), ())
        self.first, self.last, self.depth = (np.array(column, dtype=np.int64) for column in (first, last, depth))
        self.word = np.array(word, dtype=object)

    def _around(self, line):
        """The blocks line ``line`` is in (its first and last lines are in theirs), outermost first (indices)."""
        inside = np.flatnonzero((self.first < line) & (line < self.last))
        return inside[np.argsort(self.depth[inside])]

    def in_order(self, line):
        """Whether line ``line`` runs once each time its program does, in text order: outside any block, or in the
        body of an outermost ``def`` and no block within it."""
        around = self._around(line)
        return len(around) == 0 or (len(around) == 1 and self.word[around[0]] == "def")

    def program(self, line):
        """The first line of the outermost ``def`` line ``line`` is in: the program or routine it runs in (0: the
        script's top level)."""
        around = self._around(line)
        return int(self.first[around[0]]) if len(around) and self.word[around[0]] == "def" else 0

    def in_routine(self, line):
        """Whether line ``line`` is in a ``sec`` or ``thread``, or in a ``def`` within another block: run when
        called or beside the program, not where it stands."""
        around = self._around(line)
        word = self.word[around]
        return bool(np.isin(word, ("sec", "thread")).any() or (word[1:] == "def").any())


@dataclasses.dataclass(eq=False)
class _Value:
    """The latest literal a variable holds: a pose or a six-number list, made a target on first use."""

    target: Target
    index: int = None  # in the program's targets, once used


class _Reader:
    """The reader's state while it reads a script's lines in order: the CAM-shaped motion lines (`CamLines`) in
    blocks, the plain statements (`PlainLines`) at once, every other line one by one."""

    def __init__(self, source, masked, lines, cam, plain):
        self.source, self.masked, self.lines, self.cam = source, masked, lines, cam
        self.targets, self.count, self.items = {}, 0, []  # target index -> Target read one by one; targets; items
        self.blocks = []  # the motions of `CamLines` rows read as blocks, columns each (`cam_block`)
        self.offsets = []  # (frame key, target index, why) of the points also used as frames (`_offsets_from_point`)
        self.motion_spans = SpanTable(TIMING)  # each motion's re-timing fields, in order (offsets)
        self.values, self.numbers = {}, {}  # name -> _Value; name -> float
        self.frames, self.frame_names = {}, {}  # frame key -> T; id(_Value) -> frame key
        self.tools, self.tool, self.tool_why = {}, None, ""
        self.frame_uses, self.point_uses = {}, {}  # variable -> first line used as frame / as point
        self.direct = set()  # joint-list variables used as motion targets
        total = len(lines.starts) - (lines.starts[-1] == len(lines.text))  # as `Lines` yields them
        one_by_one = np.ones(total + 1, dtype=bool)
        one_by_one[0] = one_by_one[cam.line] = one_by_one[plain.line] = False
        self.set_at_run_time, self.assigned = {}, {}  # name -> line of a non-literal assignment; of every one
        for line in np.flatnonzero(one_by_one).tolist():  # a CAM-shaped motion line or plain statement assigns nothing
            start, end = self.where(line)
            if m := grammar.ASSIGN.match(masked[start:end]):
                self.assigned.setdefault(m.group(1), []).append(line)
                value = m.group(2)
                if not (grammar.POSE_VALUE.match(value) or grammar.LIST_VALUE.match(value)
                        or re.fullmatch(NUMBER, value)):
                    self.set_at_run_time.setdefault(m.group(1), line)
        # a plain statement naming an assigned variable is read one by one: it may name a target (`references`)
        naming = np.array([not self.assigned.keys().isdisjoint(grammar.WORD.findall(text))
                           for text in plain.layouts], dtype=bool)[plain.layout]
        one_by_one[plain.line[naming]] = True
        self.plain = plain.rows(~naming)
        self.others = np.flatnonzero(one_by_one)  # the lines read one by one
        self.cam_poses = np.full((len(cam), 4, 4), np.nan)
        self.cam_poses[~cam.is_joint] = poses(cam.values[~cam.is_joint])
        self.parts = _parts(lines, self.others)  # the offsets of the runs of lines read one by one
        self.poses = _literal_poses(masked, self.parts)
        self.params = {p.strip().split("=")[0].strip() for start, end in self.parts
                       for m in grammar.DEF.finditer(masked, start, end) for p in m.group(1).split(",") if p.strip()}

    def where(self, line):
        """``(start, end)`` offsets of line ``line`` (1-based), its line ending left out."""
        start = self.lines.starts[line - 1]
        return start, start + len(self.lines.line(line))

    def read_line(self, line):
        """Read line ``line`` (1-based): a statement or a motion (`call`) into the items."""
        start, end = self.where(line)
        text, original = self.masked[start:end], self.source.text[start:end]
        call = grammar.CALL.search(text)
        if call:
            close = _closing(text, call.end() - 1)
            if close < 0:
                fail(self.source.name, line, original, "unbalanced parentheses")
            args = split_top(text[call.end():close], start + call.end())
            self.items.append(self.call(call.group(1), args, line, original) or Statement(line, original))
            return
        assign = grammar.ASSIGN.match(text)
        refs = self.references(assign.group(2) if assign else text)
        if assign:
            self.assignment(assign, start, line, original)
        self.items.append(Statement(line, original, refs=refs))

    def cam_rows(self, lo, hi):
        """Read the CAM-shaped motion lines ``lo .. hi - 1`` (rows of `CamLines`), between which no line is read one
        by one.

        They take the TCP, frames and variables in force: a block of them
        at once (`cam_block`), except after a TCP set at run time and at the
        first use of each frame variable (read one by one: that read
        registers the frame, or says why its motions are not compensated,
        as it would for any line); a frame variable's further motions are
        read in blocks when its first one was compensable, else one by one.
        """
        if lo == hi:
            return
        if self.tool_why:
            for row in range(lo, hi):
                self.cam_line(row)
            return
        frame = self.cam.frame[lo:hi]
        framed = np.flatnonzero(np.not_equal(frame, None))
        firsts = {}  # frame variable -> the first row using it
        for k, name in zip(framed.tolist(), frame[framed].tolist()):
            firsts.setdefault(name, k)
        keys, done = {}, lo  # frame variable -> its frame key, or None where its motions are read one by one
        for name, k in sorted(firsts.items(), key=lambda item: item[1]):
            self.cam_run(done, lo + k, keys)
            motion = self.cam_line(lo + k)
            keys[name] = motion.frame if motion.target is not None else None
            done = lo + k + 1
        self.cam_run(done, hi, keys)

    def cam_run(self, lo, hi, keys):
        """Read CAM-shaped lines ``lo .. hi - 1`` whose frame variables are in ``keys``: those of a frame
        variable mapped to None one by one, the others in blocks."""
        frame = self.cam.frame[lo:hi]
        alone = np.zeros(hi - lo, dtype=bool)
        for name in [name for name, key in keys.items() if key is None]:
            alone |= np.equal(frame, name)
        done = lo
        for k in (lo + np.flatnonzero(alone)).tolist():
            self.cam_block(done, k, keys)
            self.cam_line(k)
            done = k + 1
        self.cam_block(done, hi, keys)

    def cam_line(self, row):
        """Read CAM-shaped line ``row`` one by one; its motion."""
        if not self.cam.is_joint[row]:
            self.poses[int(self.cam.number_start[row, 0])] = self.cam_poses[row]
        self.read_line(int(self.cam.line[row]))
        return self.items[-1]

    def cam_block(self, lo, hi, keys):
        """Read CAM-shaped lines ``lo .. hi - 1`` together (the TCP and variables in force, frames ``keys``): each a
        motion to a new target, the columns of `call` (`blocks`)."""
        if lo == hi:
            return
        cam, n = self.cam, hi - lo
        line, original = int(cam.line[lo]), self.lines.line(int(cam.line[lo]))  # for messages: none can fail
        joint = _KINDS[cam.function[lo:hi]] == JOINT  # movej: rad/s; the others m/s
        scale = np.where(joint, 1.0, 1000.0)
        v, v_why = self.resolved(lo, hi, 0, lambda name: self.speed(name, line, original, "v"))
        given = cam.option_start[lo:hi, 0] >= 0
        v[~given] = _DEFAULT_SPEEDS[cam.function[lo:hi][~given]]
        t, t_why = self.resolved(lo, hi, 1, lambda name: self.speed(name, line, original, "t"))
        timed = (cam.option_start[lo:hi, 1] >= 0) & ~(t == 0.0)  # t=0: no time; a t set at run time is one
        blend, _ = self.resolved(lo, hi, 2, lambda name: (self.option(name, line, original), ""))
        a, a_why = self.resolved(lo, hi, 3, lambda name: self.acceleration(name, line, original))
        a[timed], a_why[timed] = np.nan, ""  # t= overrides a
        frame = np.full(n, None, dtype=object)
        for name, key in keys.items():
            frame[np.equal(cam.frame[lo:hi], name)] = key
        self.blocks.append({
            "rows": np.arange(lo, hi), "target": np.arange(self.count, self.count + n), "frame": frame,
            "speed": np.where(timed, t, v * scale),
            "speed_unit": _UNITS[np.where(timed, 2, joint.astype(int))],
            "speed_why": np.where(timed, t_why, np.where(v_why == "", a_why, v_why)),
            "acceleration": a * scale,
            "zone": np.where(np.isnan(blend) | (blend == 0.0), np.nan, blend * 1000.0),
            "tool": repeated(self.tool, n),
        })
        self.count += n

    def resolved(self, lo, hi, j, resolve):
        """Option ``j`` (v, t, r) of CAM-shaped lines ``lo .. hi - 1``: ``(value (n,), why (n,) of object)``; a
        variable's value from ``resolve(name) -> (value or None, why)`` (NaN where None)."""
        value = self.cam.option[lo:hi, j].copy()
        why = np.full(hi - lo, "", dtype=object)
        names = self.cam.option_name[lo:hi, j]
        for name in dict.fromkeys(names[np.not_equal(names, None)].tolist()):
            number, reason = resolve(name)
            rows = np.equal(names, name)
            value[rows] = np.nan if number is None else number
            why[rows] = reason
        return value, why

    def fail(self, line, original, message):
        fail(self.source.name, line, original, message)

    def literal(self, text, offset, line, original, name=""):
        """A Target from a pose or six-number list literal; None if ``text`` is not one."""
        if m := grammar.POSE_VALUE.match(text):
            values = [finite(m.group(k), self.source.name, line, original, f"{name or 'pose'} {r}", LENGTH_LIMIT / 1000.0)
                      for k, r in enumerate(POSE, start=1)]
            computed = self.poses.get(offset + m.start(1))
            return Target(name=name, line=line, pose=pose(values) if computed is None else computed,
                          spans=spans(0, m, POSE, offset))
        if m := grammar.LIST_VALUE.match(text):
            joints = np.array([finite(m.group(k), self.source.name, line, original, f"{name or 'list'} {r}",
                                      np.radians(JOINT_LIMIT)) for k, r in enumerate(JOINTS, start=1)])
            return Target(name=name, line=line, joints=joints, spans=spans(0, m, JOINTS, offset))
        if grammar.NUMBERS_ONLY.match(text):
            self.fail(line, original, "malformed pose (p[...] needs six numbers)")
        return None

    def add(self, target):
        self.targets[self.count] = target
        self.count += 1
        return self.count - 1

    def use(self, value):
        """The target index of a variable's literal, made a target on first use."""
        if value.index is None:
            value.index = self.add(value.target)
        return value.index

    def runtime(self, name):
        """Why variable ``name`` holds a value known only at run time ("" if it does not)."""
        if name in self.set_at_run_time:
            return f"{name} is set at run time (line {self.set_at_run_time[name]})"
        if name in self.params:
            return f"{name}: function parameter, known at run time"
        if name in self.assigned and name not in self.values and name not in self.numbers:
            return f"{name} is assigned further down: its value depends on the order of calls"
        return ""

    def position(self, text, offset, line, original):
        """``(target index or _Named or None, frame key, why)`` of a motion's position argument."""
        if target := self.literal(text, offset, line, original):
            return self.add(target), None, ""
        if m := grammar.VARIABLE.match(text):
            name = m.group(1)
            if why := self.runtime(name):
                return None, None, why
            if name in self.values:
                self.point_uses.setdefault(name, line)
                if self.values[name].target.is_joint:
                    self.direct.add(name)
                return self.use(self.values[name]), None, ""
            if name in self.numbers:
                return None, None, f"{name} is a number, not a position"
            return _Named(name, line), None, ""
        if m := grammar.INVERSE_KINEMATICS.match(text):
            args = split_top(m.group(1), offset + m.start(1))
            index, frame, why = self.position(args[0][0], args[0][1], line, original)
            near = [a for a in args[1:] if a[0].strip().startswith("qnear")] or args[1:2]
            if isinstance(index, int) and near:
                near_text, near_at = near[0]
                value = near_text.split("=", 1)[-1] if "=" in near_text else near_text
                shift = near_at + (near_text.index("=") + 1 if "=" in near_text else 0)
                self.link(index, value, shift, line, original)
            return index, frame, why
        if m := grammar.POSE_TRANS.match(text):
            args = split_top(m.group(1), offset + m.start(1))
            if len(args) == 2:
                frame, why = self.frame(args[0][0], args[0][1], line, original)
                if why:
                    return None, None, why
                index, inner, why = self.position(args[1][0], args[1][1], line, original)
                if isinstance(index, int) and inner is None and not self.targets[index].is_joint:
                    return index, frame, ""
        return None, None, "position computed at run time: " + " ".join(text.split())

    def frame(self, text, offset, line, original):
        """``(frame key, why)`` of the first argument of ``pose_trans``: a literal or a variable holding one."""
        if target := self.literal(text, offset, line, original):
            if target.is_joint:
                return None, "pose_trans of a joint list"
            key = f"pose_trans line {line}"
            self.frames[key] = target.pose
            return key, ""
        if m := grammar.VARIABLE.match(text):
            name = m.group(1)
            if why := self.runtime(name):
                return None, why
            self.frame_uses.setdefault(name, line)
            value = self.values.get(name)
            if value is None:
                return name, ""  # not assigned in the script (an installation feature): its value must be given
            if value.target.is_joint:
                return None, f"{name} is a joint list, not a frame"
            if id(value) not in self.frame_names:
                key = name if name not in self.frames else f"{name} line {value.target.line}"
                self.frame_names[id(value)] = key
                self.frames[key] = value.target.pose
            return self.frame_names[id(value)], ""
        return None, "frame computed at run time: " + " ".join(text.split())

    def link(self, index, text, offset, line, original):
        """Give Cartesian target ``index`` the joints of a qnear list (literal or variable)."""
        target = self.targets[index]
        if target.is_joint:
            return
        if m := grammar.LIST_VALUE.match(text):
            joints = np.array([finite(m.group(k), self.source.name, line, original, f"qnear {k}", np.radians(JOINT_LIMIT))
                               for k in range(1, 7)])
            found = spans(0, m, NEAR, offset)
        elif (m := grammar.VARIABLE.match(text)) and m.group(1) in self.values and self.values[m.group(1)].target.is_joint:
            listed = self.values[m.group(1)].target
            joints, found = listed.joints, dict(zip(NEAR, (listed.spans[j] for j in JOINTS)))
        else:
            return
        self.targets[index] = dataclasses.replace(target, joints=joints, spans={**target.spans, **found})

    def assignment(self, m, start, line, original):
        name, text = m.group(1), m.group(2)
        if re.fullmatch(NUMBER, text):
            self.numbers[name] = finite(text, self.source.name, line, original, name)
            self.values.pop(name, None)
            return
        self.numbers.pop(name, None)
        if (listed := grammar.LIST_VALUE.match(text)) and any(abs(float(v)) > np.radians(JOINT_LIMIT) for v in listed.groups()):
            self.values.pop(name, None)  # six numbers no joint can hold (gains, limits): data, not a position
            return
        target = self.literal(text, start + m.start(2), line, original, name)
        if target is None:
            self.values.pop(name, None)
        else:
            self.values[name] = _Value(target)

    def call(self, function, args, line, original):
        if function == "set_tcp":
            self.set_tcp(args, line, original)
            return None
        text = original.strip()
        if function in grammar.STREAMED + grammar.DRIVEN:
            self.motion_spans.add({})
            what = "streamed set point" if function in grammar.STREAMED else (
                "the arm moves by the velocity or torque given at run time")
            return Motion(kind=JOINT, line=line, text=text, reason=f"{function}: {what}, not compensated by trajcomp")
        kind = KINDS[function]
        count = 2 if kind == CIRCULAR else 1
        if len(args) < count or not args[0][0].strip():
            self.fail(line, original, f"{function} needs {count} position(s)")
        found = [self.position(a, s, line, original) for a, s in args[:count]]
        options = dict(zip(grammar.MOTIONS[function].positional, (a.strip() for a, _ in args[count:] if "=" not in a)))
        options |= {k.strip(): v.strip() for k, v in (a.split("=", 1) for a, _ in args[count:] if "=" in a)}
        blend = self.option(options.get("r"), line, original)
        speed, speed_why = self.speed(options.get("v", grammar.MOTIONS[function].default_speed), line, original, "v")
        speed = None if speed is None else speed * (1.0 if kind == JOINT else 1000.0)
        unit = "rad/s" if kind == JOINT else "mm/s"
        acceleration, acceleration_why = self.acceleration(options.get("a"), line, original)
        if "t" in options:  # t= the motion's time: v and a are ignored (t=0: no time)
            time, time_why = self.speed(options["t"], line, original, "t")
            if time != 0.0:
                speed, unit, speed_why = time, "s", time_why
                acceleration, acceleration_why = None, ""
        speed_why = speed_why or acceleration_why
        if acceleration is not None:
            acceleration *= 1.0 if kind == JOINT else 1000.0
        self.motion_spans.add(_timing_offsets(function, args, count))
        frames = {frame for _, frame, _ in found}
        why = next((w for _, _, w in found if w), "") or self.tool_why
        if not why and len(frames) > 1:
            why = "via and end point in different frames"
        return Motion(
            kind=kind,
            target=None if why else found[-1][0],
            via=None if why or kind != CIRCULAR else found[0][0],
            speed=speed,
            speed_unit=unit,
            zone=blend * 1000.0 if blend else None,
            tool=self.tool,
            frame=found[-1][1] if not why else None,
            line=line,
            text=text,
            reason=why,
            refs=tuple(dict.fromkeys([*(i for i, _, _ in found if isinstance(i, int)),
                                      *self.references(" ".join(a for a, _ in args[:count]))])) if why else (),
            speed_why=speed_why,
            acceleration=acceleration,
        )

    def acceleration(self, text, line, original):
        """``(value, why)`` of an ``a=`` argument as `speed` reads it; None without one, or one no bound (``1e999``:
        the arm's own limit)."""
        if text is None:
            return None, ""
        try:
            return self.speed(text, line, original, "a")
        except ReadError:
            return None, ""

    def speed(self, text, line, original, field):
        """``(value, why)`` of a ``v=`` or ``t=`` argument: a literal or a variable the script assigns once, a literal.

        Any other value (a register read, a variable assigned twice or by
        an expression, a function parameter) is set at run time: None, and why.
        """
        if re.fullmatch(NUMBER, text):
            return finite(text, self.source.name, line, original, field), ""
        if not (m := grammar.VARIABLE.match(text)):
            return None, f"{field}={text}: computed at run time"
        name = m.group(1)
        if why := self.runtime(name):
            return None, why
        if name in self.numbers and (len(self.assigned[name]) == 1 or self.in_order(name, line)):
            return self.numbers[name], ""
        if name in self.assigned:
            lines = ", ".join(map(str, self.assigned[name][:3]))
            return None, f"{name} is assigned more than once (lines {lines}): its value is known at run time"
        return None, f"{name} is not assigned in the script: its value is set at run time"

    @functools.cached_property
    def blocks_of_lines(self):
        """The script's blocks (`_Blocks`), found when first needed: a variable assigned several times."""
        return _Blocks(self.masked, self.lines, self.parts)

    def in_order(self, name, line):
        """Whether number variable ``name`` holds at line ``line`` the literal last assigned above it.

        So when every assignment of it runs once, in text order, in one
        program (outside any block, or in the body of one outermost ``def``,
        as RoboDK's posts set ``speed_ms`` where the feed changes:
        `assigned_in_order`), and ``line`` runs in the same
        program as the last one above it (the top level or the same
        outermost ``def``), not in a routine called from elsewhere
        (`_Blocks`). Otherwise its value depends on the calls and loops:
        known at run time.
        """
        blocks, assigned = self.blocks_of_lines, self.assigned[name]
        above = assigned[bisect.bisect_left(assigned, line) - 1]  # `numbers` holds it: one is above
        return (name in self.assigned_in_order and blocks.program(above) == blocks.program(line)
                and not blocks.in_routine(line))

    @functools.cached_property
    def assigned_in_order(self):
        """The variables assigned more than once, all in one program and each where it runs once, in text order
        (`_Blocks.in_order`): no call of another routine can change them between two of their assignments."""
        blocks = self.blocks_of_lines
        return {name for name, lines in self.assigned.items() if len(lines) > 1 and all(map(blocks.in_order, lines))
                and len(set(map(blocks.program, lines))) == 1}

    def option(self, text, line, original):
        """A number given as a literal or a variable holding one; None otherwise."""
        if text is None:
            return None
        if re.fullmatch(NUMBER, text):
            return finite(text, self.source.name, line, original, "v or r")
        return self.numbers.get(text)

    def set_tcp(self, args, line, original):
        """The TCP of the following motions: a literal pose or a variable holding one, else known at run time."""
        text = args[0][0] if args else ""
        tcp = self.literal(text, args[0][1], line, original) if args else None
        m = grammar.VARIABLE.match(text)
        if tcp is None and m and m.group(1) in self.values and not self.runtime(m.group(1)):
            tcp = self.values[m.group(1)].target
            self.frame_uses.setdefault(m.group(1), line)  # a TCP, like a frame: not a point
        if tcp is None or tcp.is_joint:
            self.tool, self.tool_why = None, f"TCP set at run time: set_tcp({text.strip()}) (line {line})"
            return
        # PolyScope sets the TCP again at every Set node: the same pose is the same tool
        same = next((key for key, T in self.tools.items() if np.array_equal(T, tcp.pose)), None)
        self.tool = same or f"set_tcp line {line}"
        self.tools[self.tool], self.tool_why = tcp.pose, ""

    def references(self, text, assigned=None):
        """Targets of the pose variables a statement names (made targets: used, but not by a motion)."""
        names = [w for w in dict.fromkeys(grammar.WORD.findall(text)) if w != assigned and w in self.values
                 and not self.values[w].target.is_joint and w not in self.frame_uses]
        return tuple(self.use(self.values[w]) for w in names)



def _timing_offsets(function, args, count):
    """Where re-timing writes, ``{role: (start, end)}``: the values of ``t`` and ``v`` (named or positional) and the
    call's end."""
    spans = {}
    positional = iter(grammar.MOTIONS[function].positional)
    for text, at in args[count:]:
        key, _, value = text.partition("=") if "=" in text else (next(positional, ""), "", text)
        shift = at + (len(text) - len(value) if "=" in text else 0)
        start = shift + len(value) - len(value.lstrip())
        if key.strip() in ("t", "v"):
            spans[key.strip()] = (start, start + len(value.strip()))
    last, at = args[-1]
    spans["end"] = (at + len(last.rstrip()), at + len(last.rstrip()))
    return spans


def read(path):
    """Read a URScript program, as its grammar declares it (`trajcomp.formats.urscript.grammar`).

    The motion lines a CAM post-processor writes (`grammar.CAM_LINE`, executed by
    `trajcomp.formats.urscript.lines`) are read together, in
    blocks that take the TCP, frames and variables in force at their lines, and the plain statements between them
    at once; every other line is read one by one, in order.

    Raises
    ------
    ReadError
        Malformed text, numbers out of range, a motion to a variable the
        script never assigns, or a variable used both as a frame and as a
        target (compensating it would move the frame).
    """
    source = read_source(path)
    masked = mask(source.text, "#")
    if not grammar.SIGNS.search(masked):
        raise ReadError(f"{path}: not a URScript program: no def, move, pose literal or URScript statement")
    lines = Lines(source.text)
    reader = _Reader(source, masked, lines, *cam_lines(masked, np.array(lines.starts)))
    check_closed(source, masked, grammar.BLOCK_OPENS, grammar.BLOCK_CLOSES,
                 dict.fromkeys(map(str.upper, grammar.BLOCK_WORDS), "END"), reader.parts)
    done = 0  # CAM-shaped lines read
    for line in reader.others.tolist():
        upto = int(np.searchsorted(reader.cam.line, line))
        reader.cam_rows(done, upto)
        done = upto
        reader.read_line(line)
    reader.cam_rows(done, len(reader.cam))
    _finish(reader)
    # def calls, if, while, sleep: starts and stops as the script runs
    return flow.program_followed(_program(reader, path), _flow_steps(reader), {})


def _flow_steps(reader):
    """The `trajcomp.programs.flow.Step` s of a script: ``def`` (``thread``, ``sec``) and their calls, ``if`` ..
    ``elif`` .. ``else``, ``while``, ``break``, ``return``, ``halt``; ``sleep``, ``sync``, ``stopj`` and ``stopl``
    stop the arm (a wait). Looked for in the lines read one by one and the plain statements (a CAM motion line is
    none)."""
    masked, lines, plain = reader.masked, reader.lines, reader.plain
    calling = [j for j, layout in enumerate(plain.layouts) if re.match(r"\s*\w+\s*\(", layout)]
    rows = np.flatnonzero(np.isin(plain.layout, calling)).tolist()
    offsets = [start for start, _ in reader.parts] + [int(plain.start[k]) for k in rows]
    texts = [masked[start:end] for start, end in reader.parts] + [masked[plain.start[k]:plain.stop[k]] for k in rows]
    found = [(at + m.start(), next(g for g in m.group(1, 3, 4, 5, 6) if g), m.group(2))
             for at, text in zip(offsets, texts) for m in grammar.FLOW_LINE.finditer(text)]
    names = {name for _, word, name in found if word == "def" and name}
    if names:
        calls = re.compile(INDENT + r"(" + "|".join(map(re.escape, sorted(names))) + r")[ \t]*\(", re.M)
        found += [(at + m.start(), "call", m.group(1)) for at, text in zip(offsets, texts)
                  for m in calls.finditer(text)]
    found.sort()
    steps, opened = [], []
    for offset, word, name in found:
        line = lines.number(offset)
        if word == "end":
            steps.append(Step(opened.pop() if opened else "end", line=line))
            continue
        if word in grammar.OPENED:
            opened.append(grammar.OPENED[word])
        kind = grammar.FLOW_KINDS.get(word, "wait" if word != "call" else "call")
        steps.append(Step(kind, name or "", line=line))
    return steps


def _parts(lines, numbers):
    """``[(start, end)]`` offsets of the runs of consecutive lines among ``numbers`` (ascending, 1-based)."""
    runs = np.split(numbers, np.flatnonzero(np.diff(numbers) != 1) + 1) if len(numbers) else []
    ends = np.append(lines.starts[1:], len(lines.text))
    return [(lines.starts[run[0] - 1], int(ends[run[-1] - 1])) for run in runs]


def _finish(reader):
    """Check names, pair PolyScope waypoints, and list the pose variables nothing uses."""
    missing = [(m.target.name, m.target.line) for m in reader.items
               if isinstance(m, Motion) and isinstance(m.target, _Named)]
    missing += [(m.via.name, m.via.line) for m in reader.items if isinstance(m, Motion) and isinstance(m.via, _Named)]
    if missing:
        unresolved(reader.source.name, sorted(missing, key=lambda x: x[1]),
                   "they are never assigned a pose in the script")
    for name in sorted(set(reader.frame_uses) & set(reader.point_uses)):
        _offsets_from_point(reader, name)
    _pair_waypoints(reader)
    for name, value in reader.values.items():
        if value.index is None and not value.target.is_joint and name not in reader.frame_uses:
            reader.use(value)


def _offsets_from_point(reader, name):
    """A point also used as the frame of ``pose_trans`` (``movel(pose_trans(pick_p, p[0,0,-0.1,0,0,0]))``
    then ``movel(pick_p)``: the approach idiom) stays a point; the motions to offsets from it are computed
    at run time, built on it (`_offsets_made`)."""
    value = reader.values[name]
    key = reader.frame_names.pop(id(value), None)
    reader.frames.pop(key, None)
    index = reader.use(value)
    reader.offsets.append((name, key, index, f"an offset from the point {name} (pose_trans({name}, ...)), "
                                             "computed at run time"))


def _offsets_made(motions, offsets):
    """The motions with those to offsets from points (`_offsets_from_point`) computed at run time, naming the
    point, and the motions computed at run time that name such a point otherwise (``pose_add(pick_p, ...)``)
    naming it too."""
    for name, key, index, why in offsets:
        offset = np.flatnonzero(motions.frame == key) if key is not None else np.zeros(0, dtype=int)
        naming = [k for k in np.flatnonzero(motions.reason != "").tolist() if k not in set(offset.tolist())
                  and index not in motions.refs.get(k, ()) and name in grammar.WORD.findall(motions.text[k])]
        motions = motions.with_rows(offset, target=np.full(len(offset), -1), via=np.full(len(offset), -1),
                                    frame=np.full(len(offset), None), reason=np.full(len(offset), why, dtype=object),
                                    refs=[(index,)] * len(offset))
        motions = motions.with_rows(naming, refs=[motions.refs.get(k, ()) + (index,) for k in naming])
    return motions


def _pair_waypoints(reader):
    """Give each pose variable ``X_p`` the joints of its ``X_q`` list (PolyScope waypoints)."""
    for name, value in reader.values.items():
        pair = reader.values.get(name[:-2] + "_q") if name.endswith("_p") else None
        if value.index is None or pair is None or not pair.target.is_joint or name[:-2] + "_q" in reader.direct:
            continue
        target = reader.targets[value.index]
        if target.joints is None:
            near = dict(zip(NEAR, (pair.target.spans[j] for j in JOINTS)))
            reader.targets[value.index] = dataclasses.replace(target, joints=pair.target.joints,
                                                              spans={**target.spans, **near})


def _program(reader, path):
    """The program of what ``reader`` read: its targets, motions and statements as columns
    (`Program.from_tables`)."""
    source, cam = reader.source, reader.cam
    rows = _blocks_column(reader, "rows", int)
    motions = [item for item in reader.items if isinstance(item, Motion)]
    statements = [item for item in reader.items if not isinstance(item, Motion)]
    blocks = MotionTable(
        kind=_KINDS[cam.function[rows]], target=_blocks_column(reader, "target", int), via=np.full(len(rows), -1),
        line=cam.line[rows], axis_position=np.zeros(len(rows), dtype=bool), text=cam.texts(source.text, rows),
        **{name: _blocks_column(reader, name, float) for name in ("speed", "zone", "acceleration")},
        **{name: _blocks_column(reader, name, object) for name in ("speed_unit", "tool", "frame", "speed_why")})
    table = MotionTable.merged([MotionTable.of(motions), blocks])
    # the re-timing fields (t, v, the call's end) of every motion, in program order
    offsets = np.frombuffer(reader.motion_spans.offsets, dtype=np.int64).reshape(-1, len(TIMING), 2)
    start = np.concatenate([offsets[:, :, 0], np.c_[cam.option_start[rows][:, [1, 0]], cam.end[rows]]])
    end = np.concatenate([offsets[:, :, 1], np.c_[cam.option_end[rows][:, [1, 0]], cam.end[rows]]])
    order = np.argsort(np.concatenate([[m.line for m in motions], cam.line[rows]]), kind="stable")
    table = dataclasses.replace(table, spans=SpanColumns(0, source.text, TIMING, start[order], end[order]))
    plain, offset = reader.plain, offset_type(source.text)
    statements = StatementTable.merged([statements, StatementTable(plain.line, TextSlices(
        source.text, plain.start.astype(offset), plain.stop.astype(offset)))])
    return Program.from_tables("urscript", Path(path).stem, statements,
                               _offsets_made(table, reader.offsets), _targets(reader, rows), sources=(source,),
                               tools=reader.tools, frames=reader.frames, notes=polyscope_notes(path))


def _blocks_column(reader, name, dtype):
    """One column of the motions read in blocks (`_Reader.cam_block`), the blocks one after the other."""
    return np.concatenate([np.zeros(0, dtype=dtype)] + [block[name] for block in reader.blocks])


def _targets(reader, rows):
    """The `TargetTable` of the targets read one by one and of the CAM-shaped lines ``rows`` read in blocks."""
    cam, n = reader.cam, reader.count
    any_joints = cam.is_joint[rows].any() or any(t.joints is not None for t in reader.targets.values())
    pose = np.full((n, 4, 4), np.nan)
    joints = np.full((n, 6), np.nan) if any_joints else np.broadcast_to(np.nan, (n, 6))  # none: one NaN row shared
    is_joint, line = np.zeros(n, dtype=bool), np.zeros(n, dtype=int)
    offset = offset_type(reader.source.text)  # 18 roles a target: half the bytes
    start, end = np.full((n, len(ROLES)), -1, dtype=offset), np.full((n, len(ROLES)), -1, dtype=offset)
    name = np.full(n, "", dtype=object)
    index = _blocks_column(reader, "target", int)
    joint = cam.is_joint[rows]
    pose[index] = reader.cam_poses[rows]
    if any_joints:
        joints[index[joint]] = cam.values[rows[joint]]
    is_joint[index], line[index] = joint, cam.line[rows]
    for columns, at in ((slice(0, 6), ~joint), (slice(6, 12), joint)):
        start[index[at], columns] = cam.number_start[rows[at]]
        end[index[at], columns] = cam.number_end[rows[at]]
    column = {role: j for j, role in enumerate(ROLES)}
    for i, target in reader.targets.items():
        name[i], line[i], is_joint[i] = target.name, target.line, target.is_joint
        if target.pose is not None:
            pose[i] = target.pose
        if target.joints is not None:
            joints[i] = target.joints
        for role, span in target.spans.items():
            start[i, column[role]], end[i, column[role]] = span.start, span.end
    none = repeated(None, n)
    return TargetTable(pose, is_joint, joints, line, ((),) * n, none, none, (None,) * n, np.zeros(n, dtype=bool),
                       name, SpanColumns(0, reader.source.text, ROLES, start, end))
