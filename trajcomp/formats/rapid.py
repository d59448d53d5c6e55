"""ABB RAPID modules (.mod, .prg, .modx).

Read:
- declarations ``[LOCAL|TASK] CONST|PERS|VAR robtarget p10 :=
  [[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,...,eax_f]];`` (mm,
  quaternion scalar first), ``jointtarget`` (deg), ``tooldata`` (its tframe:
  the tool) and ``wobjdata`` (uframe * oframe: the work object), possibly
  spread over several lines;
- MoveJ / MoveL / MoveC / MoveAbsJ to a declared name or an inline literal,
  with speeddata ``vN`` / ``\\V:=``, zonedata ``fine`` / ``zN`` / ``\\Z:=``,
  the tool and ``\\WObj:=``. tool0 is the flange, wobj0 the world frame.
Targets computed at run time (Offs, RelTool, CRobT, ...) or not declared in
the module are left as written and reported as not compensated. Unused
external axes (9E+09) are never touched.

Write: the edited targets' numbers, with confdata from their configuration.
"""

import re

import numpy as np

from trajcomp.errors import ReadError, WriteError
from trajcomp.formats._text import (
    NUMBER,
    Lines,
    fail,
    format_number,
    mask,
    write_single_file,
    read_source,
    same_rotation,
    spans,
)
from trajcomp.program import CIRCULAR, JOINT, LINEAR, Motion, Program, Statement, Target
from trajcomp.transforms import matrix_to_quat, quat_to_matrix

POSITION = ("x", "y", "z")
QUAT = ("q1", "q2", "q3", "q4")
CONF = ("cf1", "cf4", "cf6", "cfx")
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
MIN_PLACES = dict.fromkeys(POSITION, 3) | dict.fromkeys(QUAT, 8) | dict.fromkeys(JOINTS, 4)
KINDS = {"MOVEJ": JOINT, "MOVEL": LINEAR, "MOVEC": CIRCULAR, "MOVEABSJ": JOINT}
SPEEDS = (5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800, 1000, 1500, 2000, 2500, 3000)
ZONES = (0, 1, 5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200)
UNUSED = "9E+09"

_N = r"\s*(" + NUMBER + r")\s*"
_POSE = r"\[\s*\[" + ",".join([_N] * 3) + r"\]\s*,\s*\[" + ",".join([_N] * 4) + r"\]\s*\]"
_ROBTARGET = re.compile(
    r"^\s*\[\s*\[" + ",".join([_N] * 3) + r"\]\s*,\s*\[" + ",".join([_N] * 4) + r"\]\s*,\s*\["
    + ",".join([_N] * 4) + r"\]\s*,\s*\[" + ",".join([_N] * 6) + r"\]\s*\]\s*$"
)
_JOINTTARGET = re.compile(r"^\s*\[\s*\[" + ",".join([_N] * 6) + r"\]\s*,\s*\[" + ",".join([_N] * 6) + r"\]\s*\]\s*$")
_TOOLDATA = re.compile(r"^\s*\[\s*(TRUE|FALSE)\s*,\s*" + _POSE + r"\s*,", re.I)
_WOBJDATA = re.compile(
    r"^\s*\[\s*(TRUE|FALSE)\s*,\s*(?:TRUE|FALSE)\s*,\s*\"(\s*)\"\s*,\s*" + _POSE + r"\s*,\s*" + _POSE + r"\s*\]\s*$", re.I
)
_DECL = re.compile(
    r"^\s*(?:(?:LOCAL|TASK)\s+)*(?:CONST|PERS|VAR)\s+(robtarget|jointtarget|tooldata|wobjdata)\s+(\w+)\s*:=(.*);\s*$",
    re.I | re.S,
)
_STARTS_DECL = re.compile(r"^\s*(?:(?:LOCAL|TASK)\s+)*(?:CONST|PERS|VAR)\b", re.I)
_MOVE = re.compile(r"^\s*(MoveJ|MoveL|MoveC|MoveAbsJ)\b(.*);\s*$", re.I | re.S)
_STARTS_MOVE = re.compile(r"^\s*Move(?:J|L|C|AbsJ)\b", re.I)
_MODULE = re.compile(r"^\s*MODULE\s+(\w+)", re.I | re.M)
_NAME = re.compile(r"^[A-Za-z]\w*$")
_OPTION = re.compile(r"\\(\w+)(?:\s*:=\s*([^\\]+))?")


def _pose(values):
    """T (4, 4) from x, y, z (mm) and a quaternion [w, x, y, z]."""
    T = np.eye(4)
    T[:3, :3] = quat_to_matrix(values[3:7])
    T[:3, 3] = values[:3]
    return T


def _statements(source, masked):
    """``(line, start, end)`` of each statement: declarations and moves up to their ``;``, else one line."""
    lines = Lines(source.text)
    out, pending = [], None
    for number, start, end in lines:
        if pending is not None:
            if ";" in masked[start:end]:
                out.append((pending[0], pending[1], start + masked[start:end].index(";") + 1))
                pending = None
            continue
        text = masked[start:end]
        if (_STARTS_DECL.match(text) or _STARTS_MOVE.match(text)) and ";" not in text:
            pending = (number, start)
        elif _STARTS_DECL.match(text) or _STARTS_MOVE.match(text):
            out.append((number, start, start + text.index(";") + 1))
        else:
            out.append((number, start, end))
    if pending is not None:
        fail(source.name, pending[0], source.text[pending[1]:pending[1] + 80], "statement without ';'")
    return out


def _split_top(text, offset):
    """``[(piece, start)]`` of ``text`` split at top-level commas."""
    parts, depth, start = [], 0, 0
    for k, ch in enumerate(text):
        if ch in "[(":
            depth += 1
        elif ch in "])":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append((text[start:k], offset + start))
            start = k + 1
    parts.append((text[start:], offset + start))
    return parts


class _Reader:
    def __init__(self, source):
        self.source = source
        self.targets, self.items, self.points = [], [], {}
        self.tools = {"tool0": np.eye(4)}
        self.frames = {"wobj0": np.eye(4)}

    def literal(self, kind, text, offset, name, line, original):
        """A Target from a robtarget or jointtarget literal starting at ``offset``."""
        if kind == "jointtarget":
            m = _JOINTTARGET.match(text)
            if not m:
                fail(self.source.name, line, original, "malformed jointtarget")
            found = spans(0, m, JOINTS, offset)
            return Target(name=name, line=line, joints=np.radians([float(m.group(k)) for k in range(1, 7)]), spans=found)
        m = _ROBTARGET.match(text)
        if not m:
            fail(self.source.name, line, original, "malformed robtarget")
        found = spans(0, m, POSITION + QUAT + CONF, offset)
        values = np.array([float(m.group(k)) for k in range(1, 8)])
        config = tuple(int(float(m.group(k))) for k in range(8, 12))
        return Target(name=name, line=line, pose=_pose(values), config=config, spans=found)

    def declaration(self, m, start, line, original):
        kind, name, value = m.group(1).lower(), m.group(2), m.group(3)
        offset = start + m.start(3)
        if kind in ("robtarget", "jointtarget"):
            self.points[name.lower()] = len(self.targets)
            self.targets.append(self.literal(kind, value, offset, name, line, original))
            return
        pattern = _TOOLDATA if kind == "tooldata" else _WOBJDATA
        d = pattern.match(value)
        if not d:
            fail(self.source.name, line, original, f"malformed {kind}")
        robot_held = d.group(1).upper() == "TRUE"
        if robot_held != (kind == "tooldata"):
            return  # a stationary tool or a robot-held work object is not supported: the name stays undefined
        numbers = [float(g) for g in d.groups()[1 if kind == "tooldata" else 2:]]
        if kind == "tooldata":
            self.tools[name] = _pose(numbers)
        else:
            self.frames[name] = _pose(numbers[:7]) @ _pose(numbers[7:])

    def target(self, piece, start, kind, line, original):
        text = piece.strip()
        if text.startswith("["):
            shift = start + len(piece) - len(piece.lstrip())
            literal_kind = "jointtarget" if kind == "MOVEABSJ" else "robtarget"
            self.targets.append(self.literal(literal_kind, text, shift, "", line, original))
            return len(self.targets) - 1
        if _NAME.match(text):
            return self.points.get(text.lower())
        return None

    def motion(self, m, start, line, original):
        keyword = m.group(1).upper()
        kind = KINDS[keyword]
        pieces = [(p, s) for p, s in _split_top(m.group(2), start + m.start(2)) if not p.strip().startswith("\\")]
        wanted = 5 if kind == CIRCULAR else 4
        if len(pieces) != wanted:
            fail(self.source.name, line, original, f"{m.group(1)} needs {wanted} arguments")
        points = [self.target(_bare(p), s, keyword, line, original) for p, s in pieces[: wanted - 3]]
        speed_text, zone_text, tool_text = (p for p, _ in pieces[wanted - 3:])
        options = {k.lower(): (v or "").strip() for p, _ in pieces for k, v in _OPTION.findall(p)}
        speed = _number(options.get("v")) or _number(_bare(speed_text).strip()[1:])
        zone_name = _bare(zone_text).strip().lower()
        zone = _number(options.get("z")) if "z" in options else _number(zone_name[1:]) if zone_name != "fine" else None
        return Motion(
            kind=kind,
            target=points[-1],
            via=points[0] if kind == CIRCULAR else None,
            speed=speed,
            zone=zone or None,
            tool=_bare(tool_text).strip(),
            frame=options.get("wobj", "wobj0"),
            line=line,
            text=" ".join(original.split()),
        )


def _bare(argument):
    """An argument without its optional parts (``\\V:=...``, ``\\WObj:=...``, ``\\NoEOffs``)."""
    return re.sub(r"\\.*", "", argument, flags=re.S)


def _number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def read(path):
    """Read a RAPID module."""
    source = read_source(path)
    masked = mask(source.text, "!")
    module = _MODULE.search(masked)
    if not module:
        raise ReadError(f"{path}: not a RAPID module: no MODULE line")
    reader = _Reader(source)
    for line, start, end in _statements(source, masked):
        text, original = masked[start:end], source.text[start:end]
        if m := _DECL.match(text):
            reader.declaration(m, start, line, original)
        elif m := _MOVE.match(text):
            reader.items.append(reader.motion(m, start, line, original))
            continue
        reader.items.append(Statement(line, original))
    return Program(
        "rapid", module.group(1), tuple(reader.items), tuple(reader.targets), reader.tools, reader.frames, (source,)
    )


def _encode(target, old):
    if target.is_joint:
        return dict(zip(JOINTS, np.degrees(target.joints)))
    out = dict(zip(POSITION, target.pose[:3, 3]))
    old_quat = [old[q] for q in QUAT]
    if not same_rotation(target.pose[:3, :3], quat_to_matrix(old_quat)):
        quat = matrix_to_quat(target.pose[:3, :3])
        out |= dict(zip(QUAT, -quat if np.dot(quat, old_quat) < 0 else quat))
    if target.config:
        out |= {c: str(v) for c, v in zip(CONF, target.config)}
    return out


def write(program, path):
    """``{path: bytes}``: patched in place if read from RAPID, else a generated module."""
    return write_single_file(program, path, "rapid", _encode, MIN_PLACES, _emit)


def _numbers(values, places):
    return ",".join(format_number(v, places) for v in values)


def _pose_text(T):
    return f"[[{_numbers(T[:3, 3], 6)}],[{_numbers(matrix_to_quat(T[:3, :3]), 10)}]]"


def _identifier(name, prefix, default):
    if name is None:
        return default
    text = re.sub(r"\W", "_", str(name))
    return text if _NAME.match(text) else f"{prefix}{text}"


def _speed(motion):
    if motion.speed is None or motion.speed_unit != "mm/s":
        return "v1000"
    if motion.speed in SPEEDS:
        return f"v{motion.speed:g}"
    return f"v1000\\V:={format_number(motion.speed, 3)}"


def _zone(motion):
    if motion.zone is None:
        return "fine"
    if motion.zone in ZONES:
        return f"z{motion.zone:g}"
    return f"z10\\Z:={format_number(motion.zone, 3)}"


def _emit(program, name):
    """A new RAPID module; Cartesian targets need their confdata (see postprocess.convert)."""
    module = _identifier(name, "M", "Module")
    decls, body, names = [], [], {}
    for tool in dict.fromkeys(m.tool for m in program.motions):
        if tool is not None and tool in program.tools and _identifier(tool, "t", "tool0") != "tool0":
            decls.append(
                f"  PERS tooldata {_identifier(tool, 't', 'tool0')} := [TRUE,{_pose_text(program.tools[tool])},"
                "[1,[0,0,1],[1,0,0,0],0,0,0]];  ! load data not converted: check mass and centre of gravity"
            )
    for frame in dict.fromkeys(m.frame for m in program.motions):
        if frame is not None and frame in program.frames and _identifier(frame, "w", "wobj0") != "wobj0":
            decls.append(
                f"  PERS wobjdata {_identifier(frame, 'w', 'wobj0')} := [FALSE,TRUE,\"\","
                f"{_pose_text(program.frames[frame])},[[0,0,0],[1,0,0,0]]];"
            )
    unused = ",".join([UNUSED] * 6)
    for motion in program.motions:
        if motion.target is None:
            body.append(f"    ! not converted: {motion.text}")
            continue
        refs = []
        for index in (motion.via, motion.target):
            if index is None:
                continue
            target = program.targets[index]
            if index not in names:
                names[index] = _point_name(target, set(names.values()), len(names) + 1)
                if target.is_joint:
                    decls.append(f"  CONST jointtarget {names[index]} := [[{_numbers(np.degrees(target.joints), 9)}],[{unused}]];")
                else:
                    if len(target.config) != 4:
                        raise WriteError(f"target {target.label}: RAPID needs its confdata; convert with a robot")
                    decls.append(
                        f"  CONST robtarget {names[index]} := [[{_numbers(target.pose[:3, 3], 6)}],"
                        f"[{_numbers(matrix_to_quat(target.pose[:3, :3]), 10)}],"
                        f"[{','.join(str(c) for c in target.config)}],[{unused}]];"
                    )
            refs.append(names[index])
        joint_target = program.targets[motion.target].is_joint
        keyword = "MoveAbsJ" if joint_target else {JOINT: "MoveJ", LINEAR: "MoveL", CIRCULAR: "MoveC"}[motion.kind]
        wobj = "" if motion.frame is None or joint_target else f"\\WObj:={_identifier(motion.frame, 'w', 'wobj0')}"
        tool = _identifier(motion.tool, "t", "tool0")
        body.append(f"    {keyword} {', '.join(refs)}, {_speed(motion)}, {_zone(motion)}, {tool}{wobj};")
    lines = [f"MODULE {module}"] + decls + ["", "  PROC main()"] + body + ["  ENDPROC", "ENDMODULE"]
    return "\n".join(lines) + "\n"


def _point_name(target, taken, number):
    name = re.sub(r"\W", "_", target.name)
    if not _NAME.match(name) or name in taken:
        name = f"{'j' if target.is_joint else 'p'}{number}"
    return name
