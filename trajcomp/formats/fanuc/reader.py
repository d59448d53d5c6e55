"""The FANUC LS reader: /MN motion lines and /POS positions into a `Program` (see `trajcomp.formats.fanuc`)."""

import dataclasses
import itertools
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError
from trajcomp.formats.text import (
    ANGLE_LIMIT,
    JOINT_LIMIT,
    LENGTH_LIMIT,
    NUMBER,
    Lines,
    fail,
    finite,
    last_line,
    mask,
    read_source,
    whole_circle,
)
from trajcomp.programs.program import Program
from trajcomp.programs.items import (
    CIRCULAR, JOINT, LINEAR, Motion, Span, SpanColumns, SpanTable, Statement, Target, replaced,
)
from trajcomp.arm.transforms import pose_to_matrix

XYZWPR = ("x", "y", "z", "w", "p", "r")
ABC_ORDER = ("x", "y", "z", "r", "p", "w")  # A = R, B = P, C = W
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
MIN_PLACES = dict.fromkeys(XYZWPR[:3], 3) | dict.fromkeys(XYZWPR[3:], 4) | dict.fromkeys(JOINTS, 4)
KINDS = {"J": JOINT, "L": LINEAR, "C": CIRCULAR}
SPEED_UNITS = {"%": (1.0, "%"), "mm/sec": (1.0, "mm/s"), "cm/min": (10.0 / 60.0, "mm/s"),
               "inch/min": (25.4 / 60.0, "mm/s"), "deg/sec": (np.pi / 180.0, "rad/s"),
               "sec": (1.0, "s"), "msec": (1e-3, "s")}
_UNIT = r"%|mm/se[ck]|cm/min|inch/min|deg/se[ck]|mse[ck]|se[ck]"

_SECTION = re.compile(r"^/(PROG|ATTR|APPL|MN|POS|END)\b")
_NUMBERED = re.compile(r"^\s*(\d+):(.*)$")
_CONTINUED = re.compile(r"^\s*:(.*)$")
_INDEX = r"((?:A?R\[[^\]]*\]|[^\]:\[])+?)"  # P[3], or P[R[3]] / P[R[3:idx]]: an index a register holds
_MOTION = re.compile(r"^\s*([JLC])\s+(P|PR)\[\s*" + _INDEX + r"\s*(?::[^\]]*)?\](.*)$", re.I)
_POINT = re.compile(r"^\s*P\[\s*" + _INDEX + r"\s*(?::[^\]]*)?\](.*)$", re.I)
_SPEED_TERM = re.compile(
    r"^\s*(?:(" + NUMBER + r")\s*(" + _UNIT + r")|A?R\[[^\]]*\]\s*(?:" + _UNIT + r")?|\S+)\s+(FINE|FEIN|CNT\s*(" + NUMBER + r")?\S*|C[RD]\s*(" + NUMBER
    + r")?\S*)(?:\s|$)", re.I
)
_SPEED_FIELD = re.compile(r"(?:" + NUMBER + r")\s*(?:" + _UNIT + r")(?=\s+(?:FINE|FEIN|CNT|CR|CD))", re.I)
_RUNTIME = re.compile(r"\b(Offset|Tool_Offset|INC|VOFFSET)\b", re.I)
_STATE = re.compile(r"^\s*(UFRAME_NUM|UTOOL_NUM|BENUTZER_NUM|WKZ_NUM)\s*=\s*(.*?)\s*;", re.I)
_SET_FRAME = re.compile(r"^\s*(UFRAME|UTOOL|BENUTZER|WKZ)\s*\[\s*(\d+)\s*\]\s*=\s*(.*?)\s*;", re.I)
_POINT_REF = re.compile(r"\bP\[\s*(\d+)\s*(?::[^\]]*)?\]", re.I)
_POS = re.compile(r"P\[\s*(\d+)\s*(?::\s*\"[^\"]*\")?\s*\]\s*\{(.*?)\};", re.S)
_GROUP = re.compile(r"GP(\d+)\s*:(.*?)(?=GP\d+\s*:|$)", re.S)
_FIELD = re.compile(r"\b([XYZWPR]|J\d|E\d)\s*=\s*(" + NUMBER + r"|\*+)\s*(mm|deg)", re.I)
_FRAME_NUMBER = re.compile(r"\b(UF|UT)\s*:\s*(\d+)", re.I)
_CONFIG = re.compile(r"(?:CONFIG|KONFIG)\s*:\s*'([^']*)'", re.I)
_CONFIG_VALUE = re.compile(r"^\s*([NF])\s*([UD])\s*([TB])\s*,\s*(-?\d{1,3})\s*,\s*(-?\d{1,3})\s*,\s*(-?\d{1,3})\s*$", re.I)
_OTHER_REPRESENTATION = re.compile(r"\bR[XYZWPR]\s*=", re.I)
# A Cartesian position of group 1 alone as the teach pendant and CAM post-processors write it (any white space):
# P[1]{ GP1: UF : 0, UT : 1, CONFIG : 'N U T, 0, 0, 0', X = .. mm, Y = .. mm, Z = .. mm, W = .. deg, P = .. deg,
# R = .. deg }; -- read a whole /POS section of them at once (`_written_positions`); any other goes one by one.
_WRITTEN_POSITION = re.compile(
    r"P\[\s*(\d+)\s*(?::\s*\"[^\"]*\")?\s*\]\s*\{\s*GP1\s*:\s*UF\s*:\s*(\d+)\s*,\s*UT\s*:\s*(\d+)\s*,\s*"
    r"CONFIG\s*:\s*'([^']*)'\s*,\s*"
    + r"\s*,\s*".join(f"{c}\\s*=\\s*({NUMBER})\\s*{'mm' if c in 'XYZ' else 'deg'}" for c in "XYZWPR")
    + r"\s*\};", re.I)
_SCARA_CONFIG = re.compile(r"^\s*[LR]\s*,(?:\s*-?\d{1,3}\s*,?)*\s*$", re.I)
_TOOL_WORDS = {"UTOOL_NUM": "tool", "WKZ_NUM": "tool", "UFRAME_NUM": "frame", "BENUTZER_NUM": "frame",
               "UTOOL": "tool", "WKZ": "tool", "UFRAME": "frame", "BENUTZER": "frame"}


@dataclasses.dataclass
class _State:
    """Active tool and user frame numbers while reading /MN, and which are set at run time."""

    tool: str = None
    frame: str = None
    why: dict = dataclasses.field(default_factory=lambda: {"tool": "", "frame": ""})  # active one set at run time
    set_at_run_time: dict = dataclasses.field(default_factory=lambda: {"tool": {}, "frame": {}})  # number -> why

    def update(self, content, line):
        """Follow ``UTOOL_NUM=n``, ``UTOOL_NUM=R[1]`` and ``UTOOL[n]=PR[m]`` (and the user frame ones)."""
        if m := _STATE.match(content):
            what, value = _TOOL_WORDS[m.group(1).upper()], m.group(2)
            if value.isdigit():
                setattr(self, what, value)
                self.why[what] = ""
            else:
                setattr(self, what, None)
                self.why[what] = f"{m.group(1).upper()}={value} chosen at run time (line {line})"
        elif m := _SET_FRAME.match(content):
            what = _TOOL_WORDS[m.group(1).upper()]
            self.set_at_run_time[what][m.group(2)] = (
                f"{what} {m.group(2)} set at run time by {m.group(1).upper()}[{m.group(2)}]={m.group(3)} (line {line})")

    def reason(self, what, number):
        """Why the tool or frame a motion uses is only known at run time ("" if it is not)."""
        if number is None:
            return self.why[what]
        return self.set_at_run_time[what].get(number, "")


def read(path):
    """Read a FANUC .LS program.

    Raises
    ------
    ReadError
        Malformed text, numbers out of range, motions to positions
        without a /POS entry or not taught, or no /END line (the file is
        cut off: the controller's loader refuses it too).
    """
    source = read_source(path)
    masked = mask(source.text, "!", quote='"')
    lines = Lines(source.text)
    head = next((source.text[s:e] for _, s, e in lines if source.text[s:e].strip()), "")
    if not head.lstrip().upper().startswith("/PROG"):
        raise ReadError(f"{path}: not a FANUC .LS program: it does not start with /PROG")
    name = head.split()[1] if len(head.split()) > 1 else Path(path).stem
    section, instructions, pos_start, pos_end = None, [], None, len(source.text)
    for number, start, end in lines:
        text = masked[start:end]
        m = _SECTION.match(text.strip())
        if m:
            section = m.group(1)
            if section == "POS":
                pos_start = end
            elif section == "END" and pos_start is not None:
                pos_end = start
            instructions.append((number, start, end, None))
            continue
        if section == "MN" and (c := _CONTINUED.match(text)) and instructions and instructions[-1][3] is not None:
            prev = instructions[-1]
            instructions[-1] = (prev[0], prev[1], end, prev[3] + " " + c.group(1))
        elif section == "MN" and (n := _NUMBERED.match(text)):
            instructions.append((number, start, end, n.group(2)))
        else:
            instructions.append((number, start, end, None))
    if section != "END":
        last = last_line(lines)
        fail(source.name, last, lines.line(last), "no /END after it: the program is cut off")
    targets, points, unread = _positions(source, masked, lines, pos_start, pos_end)
    from trajcomp.formats.fanuc import posreg  # it reads positions as this module does

    sources, registers, register_why, notes = (source,), {}, {}, ()
    if posreg.used_registers(masked):
        registers_source, registers, register_why, notes = posreg.resolve(path, masked, lines, targets, 1)
        sources += (registers_source,) if registers_source is not None else ()
    items, state = [], _State()
    speeds = SpanTable(("speed",))  # the motions' speed fields as offsets (no Span object each)
    for number, start, end, content in instructions:
        original = source.text[start:end]
        if content is None:
            items.append(Statement(number, original))
            continue
        state.update(content, number)
        m = _MOTION.match(content)
        if not m:
            refs = tuple(points[int(n)] for n in _POINT_REF.findall(content) if int(n) in points)
            items.append(Statement(number, original, refs=refs))
            continue
        motion = _motion(m, points, unread, source.name, number, original, registers, register_why)
        speed = _SPEED_FIELD.search(masked, start, end)  # where re-timing writes the motion's speed
        speeds.add({"speed": None if speed is None else speed.span()})
        items.append(_with_frames(motion, targets, state))
    speeds, rows = speeds.columns(0, source.text), itertools.count()  # the motions' rows, in order
    items = tuple(replaced(item, spans=speeds.row(next(rows))) if isinstance(item, Motion) else item for item in items)
    tools, frames = {"0": np.eye(4)}, {"0": np.eye(4)}
    return Program("fanuc_ls", name, items, tuple(targets), tools, frames, sources, notes=notes)


def _with_frames(motion, targets, state):
    """The motion with the tool and frame it runs with; not compensated if one is set at run time."""
    motion = replaced(motion, tool=state.tool, frame=state.frame)
    for index in (motion.via, motion.target):
        if index is None:
            continue
        target = targets[index]
        tool = target.tool if target.tool is not None else state.tool
        frame = target.frame if target.frame is not None else state.frame
        why = ("" if target.is_joint else state.reason("tool", tool)) or state.reason("frame", frame)
        if not why and not target.is_joint and target.name.startswith("PR[") and None in (tool, frame):
            unset = " and ".join(word for word, number in (("UTOOL_NUM", tool), ("UFRAME_NUM", frame))
                                 if number is None)
            why = (f"{target.name} is a position in the tool and user frame active when the line runs: the program "
                   f"sets no {unset} before it")
        if why:
            points = tuple(i for i in (motion.via, motion.target) if i is not None)
            return dataclasses.replace(motion, target=None, via=None, reason=why, refs=motion.refs + points)
    return motion


def _motion(m, points, unread, name, number, original, registers, register_why):
    kind = KINDS[m.group(1).upper()]
    rest = m.group(4)
    refs = [(m.group(2).upper(), m.group(3))]
    if kind == CIRCULAR:
        second = _POINT.search(rest) or re.search(r"\b(PR)\[\s*" + _INDEX + r"\s*(?::[^\]]*)?\](.*)$", rest, re.I)
        if not second:
            fail(name, number, original, "C needs a via point and an end point")
        if second.re is _POINT:
            refs.append(("P", second.group(1)))
            rest = second.group(2)
        else:
            refs.append(("PR", second.group(2)))
            rest = second.group(3)
    spec = _SPEED_TERM.match(rest)
    if not spec:
        fail(name, number, original, "motion needs a speed and FINE, CNT or CR")
    speed, unit, speed_why = None, "%", ""
    if spec.group(1) is not None:
        scale, unit = SPEED_UNITS[re.sub("sek$", "sec", spec.group(2).lower())]
        speed = finite(spec.group(1), name, number, original, "speed") * scale
    elif (term := " ".join(rest[: spec.start(3)].split())).lower() != "max_speed":  # max_speed: the arm's limits
        speed_why = f"speed {term}: a register, set at run time"
    blend = spec.group(4) or spec.group(5)
    zone = finite(blend, name, number, original, "CNT") if blend is not None else None
    runtime = _RUNTIME.search(rest)
    found, reason = [], ""
    for kind_ref, ref in refs:
        if kind_ref == "P" and ref.isdigit() and int(ref) in unread:
            found.append(None)
            reason = reason or f"P[{ref}] {unread[int(ref)]}"
        elif kind_ref == "PR" and not runtime and ref in registers:  # read from POSREG.VA (`posreg`)
            found.append(registers[ref])
        elif runtime or kind_ref == "PR" or not ref.isdigit():
            found.append(None)
            reason = reason or (f"{runtime.group(1)} applied at run time" if runtime
                                else f"position register PR[{ref}]"
                                     + register_why.get(ref, "" if ref.isdigit() else ": its number is set at run time")
                                if kind_ref == "PR"
                                else f"P[{ref}]: position index computed at run time")
        elif int(ref) not in points:
            fail(name, number, original, f"P[{ref}] has no entry in /POS")
        else:
            found.append(points[int(ref)])
    named = tuple(points[int(r)] if k == "P" else registers[r] for k, r in refs
                  if (k == "P" and r.isdigit() and int(r) in points) or (k == "PR" and r in registers))
    motion = Motion(
        kind=kind,
        target=found[-1],
        via=found[0] if kind == CIRCULAR else None,
        speed=speed,
        speed_unit=unit,
        zone=zone or None,
        line=number,
        text=" ".join(original.split()),
        reason=reason,
        refs=named if reason else (),
        speed_why=speed_why,
    )
    if reason:
        return dataclasses.replace(motion, target=None, via=None)
    return whole_circle(motion)


def _written_positions(source, masked, lines, start, end):
    """The positions of the /POS section written as the pendant writes them (`_WRITTEN_POSITION`), read at once.

    A position whose numbers or configuration the one-by-one read would
    refuse is left out: that read then names it.

    Returns
    -------
    dict
        ``{offset of its P[: (end offset, Target)}``; the targets' spans are `SpanColumns` rows.
    """
    found = list(_WRITTEN_POSITION.finditer(masked, start, end))
    configs = [_CONFIG_VALUE.match(m.group(4)) for m in found]
    numbers = np.array([m.groups()[4:] for m in found], dtype=float).reshape(-1, 6)  # x, y, z, w, p, r
    limits = np.array([LENGTH_LIMIT] * 3 + [ANGLE_LIMIT] * 3)
    good = (np.isfinite(numbers) & (np.abs(numbers) <= limits)).all(axis=1) & np.array([c is not None for c in configs],
                                                                                       dtype=bool)
    keep = np.flatnonzero(good)
    vector = np.concatenate([numbers[keep, :3], np.radians(numbers[keep, 5:2:-1])], axis=1)  # A, B, C = R, P, W
    poses = pose_to_matrix(vector.reshape(-1, 6))
    at = np.array([[m.start(k) for k in (5, 6, 7, 8, 9, 10, 4)] + [m.end(k) for k in (5, 6, 7, 8, 9, 10, 4)]
                   for m in found], dtype=int).reshape(-1, 14)
    columns = SpanColumns(0, source.text, XYZWPR + ("config",), at[:, :7], at[:, 7:])
    line = np.searchsorted(lines.starts, [m.start() for m in found], side="right").tolist()
    out = {}
    for row, k in enumerate(keep.tolist()):
        m, v = found[k], configs[k]
        config = (v.group(1).upper(), v.group(2).upper(), v.group(3).upper(), *map(int, v.groups()[3:]))
        out[m.start()] = (m.end(), Target(name=f"P[{m.group(1)}]", line=line[k], tool=m.group(3), frame=m.group(2),
                                          pose=poses[row], config=config, spans=columns.row(k)))
    return out


def _positions(source, masked, lines, start, end):
    """Targets of the /POS section, ``{P number: target index}`` and ``{P number: why}`` of positions not read.

    Not read: untaught positions (``********``) and positions in a
    representation trajcomp does not read (``RX = .. mm, .. RR = .. deg``).
    """
    targets, points, unread = [], {}, {}
    if start is None:
        return targets, points, unread
    written = _written_positions(source, masked, lines, start, end)
    for m in _POS.finditer(masked, start, end):
        if (position := written.get(m.start())) is not None and position[0] == m.end():  # read with the others
            points[int(m.group(1))] = len(targets)
            targets.append(position[1])
            continue
        body_start = m.start(2)
        body = masked[body_start:m.end(2)]
        groups = {int(g.group(1)): (body_start + g.start(2), g.group(2)) for g in _GROUP.finditer(body)}
        if 1 not in groups:
            continue
        gp_start, gp = groups[1]
        line = lines.number(m.start())
        original = source.text[m.start():m.end()]
        label = f"P[{m.group(1)}]"
        if "*" in "".join(f.group(2) for f in _FIELD.finditer(gp)):
            unread[int(m.group(1))] = (f"is not taught (its position is ********, line {line}): the controller faults "
                                       "only if this line runs")
            continue
        fields, units = {}, {}
        for f in _FIELD.finditer(gp):
            fields[f.group(1).lower()] = Span(0, gp_start + f.start(2), gp_start + f.end(2), f.group(2))
            units[f.group(1).lower()] = f.group(3).lower()
        if "x" not in fields and "j1" not in fields and _OTHER_REPRESENTATION.search(gp):
            unread[int(m.group(1))] = (f"is stated as RX, RY, RZ, RW, RP, RR (line {line}), a representation "
                                       "trajcomp does not read: left as written")
            continue

        def value(role):
            limit = (LENGTH_LIMIT if role in "xyz" or units[role] == "mm"  # a track's E1 in mm
                     else ANGLE_LIMIT if role in "wpr" else JOINT_LIMIT)
            return finite(fields[role].text, source.name, line, original, f"{label} {role.upper()}", limit)

        frames = {f.group(1).upper(): f.group(2) for f in _FRAME_NUMBER.finditer(gp)}
        external = [value(e) for e in sorted(f for f in fields if f.startswith("e"))]
        for k in sorted(g for g in groups if g > 1):
            external += [finite(f.group(2), source.name, line, original, f"{label} GP{k} {f.group(1)}", LENGTH_LIMIT)
                         for f in _FIELD.finditer(groups[k][1]) if "*" not in f.group(2)]
        where = {"name": label, "line": line, "tool": frames.get("UT"), "frame": frames.get("UF"),
                 "external": np.array(external) if external else None}
        if "j1" in fields:
            missing = [j for j in JOINTS if j not in fields]
            if missing:
                fail(source.name, line, original, f"{label} lacks {', '.join(j.upper() for j in missing)}")
            joints = np.radians([value(j) for j in JOINTS])
            target = Target(**where, joints=joints, spans={j: fields[j] for j in JOINTS})
        else:
            missing = [c for c in XYZWPR if c not in fields]
            if missing:
                fail(source.name, line, original, f"{label} lacks {', '.join(c.upper() for c in missing)}")
            x, y, z, w, p, r = (value(c) for c in XYZWPR)
            spans = {c: fields[c] for c in XYZWPR}
            config = ()
            c = _CONFIG.search(gp)
            if c:
                v = _CONFIG_VALUE.match(c.group(1))
                if not v and _SCARA_CONFIG.match(c.group(1)):
                    fail(source.name, line, original, f"{label}: CONFIG '{c.group(1)}' is a 4-axis arm's (SCARA, "
                                                      "arm left or right): 4-axis arms are not supported")
                if not v:
                    fail(source.name, line, original, f"{label}: malformed CONFIG")
                config = (v.group(1).upper(), v.group(2).upper(), v.group(3).upper(), *map(int, v.groups()[3:]))
                spans["config"] = Span(0, gp_start + c.start(1), gp_start + c.end(1), c.group(1))
            pose = pose_to_matrix([x, y, z, *np.radians([r, p, w])])
            target = Target(**where, pose=pose, config=config, spans=spans)
        points[int(m.group(1))] = len(targets)
        targets.append(target)
    return targets, points, unread
