"""The URScript reader: a script's motions, pose variables, frames and TCPs into a `Program` (see `trajcomp.formats.urscript`)."""

import dataclasses
import itertools
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError
from trajcomp.formats.text import (
    JOINT_LIMIT,
    LENGTH_LIMIT,
    NUMBER,
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
from trajcomp.formats.urscript.polyscope import notes as polyscope_notes
from trajcomp.programs.program import Program
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR, Motion, SpanTable, Statement, Target, replaced
from trajcomp.arm.transforms import rotvec_to_matrix

POSE = ("x", "y", "z", "rx", "ry", "rz")
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
NEAR = ("near1", "near2", "near3", "near4", "near5", "near6")
KINDS = {"movej": JOINT, "movel": LINEAR, "movep": LINEAR, "movec": CIRCULAR}
NOT_READ = ("servoj", "servoc")  # motions with a target trajcomp does not compensate (streamed set points)
DEFAULT_SPEED = {"movej": "1.05", "movel": "0.25", "movep": "0.25", "movec": "0.25"}  # v when not given: rad/s, m/s
POSITIONAL = {"movej": ("a", "v", "t", "r"), "movel": ("a", "v", "t", "r"), "movep": ("a", "v", "r"),
              "movec": ("a", "v", "r", "mode")}

_N = r"\s*(" + NUMBER + r")\s*"
_SIX = ",".join([_N] * 6)
_POSE = re.compile(r"^\s*p\[" + _SIX + r"\]\s*$")
_LIST = re.compile(r"^\s*\[" + _SIX + r"\]\s*$")
_ASSIGN = re.compile(r"^\s*(?:global\s+|local\s+)?([A-Za-z_]\w*)\s*=(?!=)\s*(.+?)\s*$")
_DEF = re.compile(r"^\s*def\s+\w+\s*\((.*?)\)\s*:", re.M)
_BLOCKS = ("DEF", "SEC", "THREAD", "IF", "WHILE", "FOR")  # statements whose body ends with ``end``
_BLOCK_OPENS = re.compile(r"^[ \t]*(def|sec|thread|if|while|for)\b[^\n]*:\s*$", re.M)
_BLOCK_CLOSES = re.compile(r"^[ \t]*(end)\s*$", re.M)
_CALL = re.compile(r"\b(movej|movel|movep|movec|set_tcp|servoj|servoc)\s*\(")
_IK = re.compile(r"^\s*get_inverse_kin\s*\((.*)\)\s*$", re.S)
_POSE_TRANS = re.compile(r"^\s*pose_trans\s*\((.*)\)\s*$", re.S)
_NAME = re.compile(r"^\s*([A-Za-z_]\w*)\s*$")
_WORD = re.compile(r"[A-Za-z_]\w*")
_NUMBERS_ONLY = re.compile(r"^\s*p\[[\s\d.eE+,-]*\]\s*$")
_SIGNS = re.compile(r"(?m)^\s*def\s+\w+\s*\(|\b(?:movej|movel|movep|movec)\s*\(|\bp\[")
_PARENTHESIS = re.compile(r"[()]")
# every pose literal of the script, whose rotations are computed together (`_literal_poses`)
_POSE_LITERAL = re.compile(r"\bp\[" + _SIX + r"\]")


def _closing(text, open_at):
    """Index of the parenthesis closing the one at ``open_at``."""
    depth = 0
    for m in _PARENTHESIS.finditer(text, open_at):
        depth += 1 if m.group() == "(" else -1
        if depth == 0:
            return m.start()
    return -1


def _literal_poses(masked):
    """The poses of the script's pose literals, computed together: ``{offset of the literal's x: T (4, 4)}``, mm.

    Literals with a number out of range are left out (their reading refuses them).
    """
    found = list(_POSE_LITERAL.finditer(masked))
    values = np.array([m.groups() for m in found], dtype=float).reshape(-1, 6)
    keep = np.flatnonzero((np.isfinite(values) & (np.abs(values) <= LENGTH_LIMIT / 1000.0)).all(axis=1))
    T = np.tile(np.eye(4), (len(keep), 1, 1))
    T[:, :3, :3] = rotvec_to_matrix(values[keep, 3:])
    T[:, :3, 3] = values[keep, :3] * 1000.0
    return {found[k].start(1): T[row] for row, k in enumerate(keep.tolist())}


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


@dataclasses.dataclass(eq=False)
class _Value:
    """The latest literal a variable holds: a pose or a six-number list, made a target on first use."""

    target: Target
    index: int = None  # in the program's targets, once used


class _Reader:
    def __init__(self, source, masked):
        self.source = source
        self.targets, self.items = [], []
        self.motion_spans = SpanTable(("t", "v", "end"))  # each motion's re-timing fields, in order (offsets)
        self.values, self.numbers = {}, {}  # name -> _Value; name -> float
        self.frames, self.frame_names = {}, {}  # frame key -> T; id(_Value) -> frame key
        self.tools, self.tool, self.tool_why = {}, None, ""
        self.frame_uses, self.point_uses = {}, {}  # variable -> first line used as frame / as point
        self.direct = set()  # joint-list variables used as motion targets
        self.poses = _literal_poses(masked)
        self.params = {p.strip().split("=")[0].strip() for m in _DEF.finditer(masked)
                       for p in m.group(1).split(",") if p.strip()}
        self.set_at_run_time, self.assigned = {}, {}  # name -> line of a non-literal assignment; of every one
        for line, start, end in Lines(masked):
            if m := _ASSIGN.match(masked[start:end]):
                self.assigned.setdefault(m.group(1), []).append(line)
                if not (_POSE.match(m.group(2)) or _LIST.match(m.group(2)) or re.fullmatch(NUMBER, m.group(2))):
                    self.set_at_run_time.setdefault(m.group(1), line)

    def fail(self, line, original, message):
        fail(self.source.name, line, original, message)

    def literal(self, text, offset, line, original, name=""):
        """A Target from a pose or six-number list literal; None if ``text`` is not one."""
        if m := _POSE.match(text):
            values = [finite(m.group(k), self.source.name, line, original, f"{name or 'pose'} {r}", LENGTH_LIMIT / 1000.0)
                      for k, r in enumerate(POSE, start=1)]
            computed = self.poses.get(offset + m.start(1))
            return Target(name=name, line=line, pose=pose(values) if computed is None else computed,
                          spans=spans(0, m, POSE, offset))
        if m := _LIST.match(text):
            joints = np.array([finite(m.group(k), self.source.name, line, original, f"{name or 'list'} {r}",
                                      np.radians(JOINT_LIMIT)) for k, r in enumerate(JOINTS, start=1)])
            return Target(name=name, line=line, joints=joints, spans=spans(0, m, JOINTS, offset))
        if _NUMBERS_ONLY.match(text):
            self.fail(line, original, "malformed pose (p[...] needs six numbers)")
        return None

    def add(self, target):
        self.targets.append(target)
        return len(self.targets) - 1

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
        if m := _NAME.match(text):
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
        if m := _IK.match(text):
            args = split_top(m.group(1), offset + m.start(1))
            index, frame, why = self.position(args[0][0], args[0][1], line, original)
            near = [a for a in args[1:] if a[0].strip().startswith("qnear")] or args[1:2]
            if isinstance(index, int) and near:
                near_text, near_at = near[0]
                value = near_text.split("=", 1)[-1] if "=" in near_text else near_text
                shift = near_at + (near_text.index("=") + 1 if "=" in near_text else 0)
                self.link(index, value, shift, line, original)
            return index, frame, why
        if m := _POSE_TRANS.match(text):
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
        if m := _NAME.match(text):
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
        if m := _LIST.match(text):
            joints = np.array([finite(m.group(k), self.source.name, line, original, f"qnear {k}", np.radians(JOINT_LIMIT))
                               for k in range(1, 7)])
            found = spans(0, m, NEAR, offset)
        elif (m := _NAME.match(text)) and m.group(1) in self.values and self.values[m.group(1)].target.is_joint:
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
        if (listed := _LIST.match(text)) and any(abs(float(v)) > np.radians(JOINT_LIMIT) for v in listed.groups()):
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
        if function in NOT_READ:
            self.motion_spans.add({})
            return Motion(kind=JOINT, line=line, text=text,
                          reason=f"{function}: streamed set point, not compensated by trajcomp")
        kind = KINDS[function]
        count = 2 if kind == CIRCULAR else 1
        if len(args) < count or not args[0][0].strip():
            self.fail(line, original, f"{function} needs {count} position(s)")
        found = [self.position(a, s, line, original) for a, s in args[:count]]
        options = dict(zip(POSITIONAL[function], (a.strip() for a, _ in args[count:] if "=" not in a)))
        options |= {k.strip(): v.strip() for k, v in (a.split("=", 1) for a, _ in args[count:] if "=" in a)}
        blend = self.option(options.get("r"), line, original)
        speed, speed_why = self.speed(options.get("v", DEFAULT_SPEED[function]), line, original, "v")
        speed = None if speed is None else speed * (1.0 if function == "movej" else 1000.0)
        unit = "rad/s" if function == "movej" else "mm/s"
        if "t" in options:  # t= the motion's time: v and a are ignored (t=0: no time)
            time, time_why = self.speed(options["t"], line, original, "t")
            if time != 0.0:
                speed, unit, speed_why = time, "s", time_why
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
        )

    def speed(self, text, line, original, field):
        """``(value, why)`` of a ``v=`` or ``t=`` argument: a literal or a variable the script assigns once, a literal.

        Any other value (a register read, a variable assigned twice or by
        an expression, a function parameter) is set at run time: None, and why.
        """
        if re.fullmatch(NUMBER, text):
            return finite(text, self.source.name, line, original, field), ""
        if not (m := _NAME.match(text)):
            return None, f"{field}={text}: computed at run time"
        name = m.group(1)
        if why := self.runtime(name):
            return None, why
        if name in self.numbers and len(self.assigned[name]) == 1:
            return self.numbers[name], ""
        if name in self.assigned:
            lines = ", ".join(map(str, self.assigned[name][:3]))
            return None, f"{name} is assigned more than once (lines {lines}): its value is known at run time"
        return None, f"{name} is not assigned in the script: its value is set at run time"

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
        m = _NAME.match(text)
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
        names = [w for w in dict.fromkeys(_WORD.findall(text)) if w != assigned and w in self.values
                 and not self.values[w].target.is_joint and w not in self.frame_uses]
        return tuple(self.use(self.values[w]) for w in names)



def _timing_offsets(function, args, count):
    """Where re-timing writes, ``{role: (start, end)}``: the values of ``t`` and ``v`` (named or positional) and the
    call's end."""
    spans = {}
    positional = iter(POSITIONAL[function])
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
    """Read a URScript program.

    Raises
    ------
    ReadError
        Malformed text, numbers out of range, a motion to a variable the
        script never assigns, or a variable used both as a frame and as a
        target (compensating it would move the frame).
    """
    source = read_source(path)
    masked = mask(source.text, "#")
    if not _SIGNS.search(masked):
        raise ReadError(f"{path}: not a URScript program: no def, move or pose literal")
    check_closed(source, masked, _BLOCK_OPENS, _BLOCK_CLOSES, dict.fromkeys(_BLOCKS, "END"))
    reader = _Reader(source, masked)
    for line, start, end in Lines(source.text):
        text, original = masked[start:end], source.text[start:end]
        call = _CALL.search(text)
        if call:
            close = _closing(text, call.end() - 1)
            if close < 0:
                fail(source.name, line, original, "unbalanced parentheses")
            args = split_top(text[call.end():close], start + call.end())
            motion = reader.call(call.group(1), args, line, original)
            reader.items.append(motion or Statement(line, original))
            continue
        assign = _ASSIGN.match(text)
        refs = reader.references(assign.group(2) if assign else text)
        if assign:
            reader.assignment(assign, start, line, original)
        reader.items.append(Statement(line, original, refs=refs))
    _finish(reader)
    motion_spans, rows = reader.motion_spans.columns(0, source.text), itertools.count()  # the motions' rows, in order
    items = tuple(replaced(item, spans=motion_spans.row(next(rows))) if isinstance(item, Motion) else item
                  for item in reader.items)
    return Program("urscript", Path(path).stem, items, tuple(reader.targets), reader.tools,
                   reader.frames, (source,), notes=polyscope_notes(path))


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
    at run time, built on it."""
    value = reader.values[name]
    key = reader.frame_names.pop(id(value), None)
    reader.frames.pop(key, None)
    index = reader.use(value)
    why = f"an offset from the point {name} (pose_trans({name}, ...)), computed at run time"
    for k, item in enumerate(reader.items):
        if not isinstance(item, Motion):
            continue
        if key is not None and item.frame == key:
            reader.items[k] = dataclasses.replace(item, target=None, via=None, frame=None, reason=why, refs=(index,))
        elif item.reason and index not in item.refs and name in _WORD.findall(item.text):
            reader.items[k] = dataclasses.replace(item, refs=item.refs + (index,))  # pose_add(pick_p, ...)


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
