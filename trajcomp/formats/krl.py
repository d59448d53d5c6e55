"""KUKA KRL: a .src program with its .dat data list.

Read:
- points declared in the .dat or .src: ``DECL E6POS XP1={X ..,Y ..,Z ..,A ..,B
  ..,C ..,S ..,T ..,E1 ..}``, POS and FRAME (Cartesian), E6AXIS and AXIS
  (joint targets); A, B, C are intrinsic Z-Y'-X'' angles in degrees;
- PTP / LIN / CIRC (and SPTP / SLIN / SCIRC) to a point name or an inline
  aggregate ``{X ..}`` / ``{A1 ..}``, with C_PTP / C_DIS / C_VEL / C_ORI;
  the relative motions PTP_REL / LIN_REL / CIRC_REL are run-time positions;
- inline forms (``;FOLD PTP P1 ...;%{PE}`` with ``FDAT_ACT`` / ``PDAT_ACT`` /
  ``LDAT_ACT`` and the FDAT / PDAT / LDAT of the .dat): they name the
  point, so changing the point's numbers keeps the fold consistent;
- tool and base: ``$TOOL = TOOL_DATA[n]``, ``$BASE = BASE_DATA[n]``,
  ``BAS(#TOOL, n)``, ``BAS(#BASE, n)``, FDAT TOOL_NO / BASE_NO, inline
  ``$TOOL = {X ..}`` and ``TOOL_DATA[n] = {X ..}`` definitions (tool and
  base 0 are the flange and the world); speeds ``$VEL.CP`` (m/s),
  ``BAS(#VEL_PTP, %)``, ``BAS(#VEL_CP, m/s)``, PDAT / LDAT VEL; zone
  ``$APO.CDIS`` or the PDAT / LDAT APO_DIST.
Other statements pass through. A motion to an expression (geometric
operator ``P:{X 10}``, function calls) or to a point the program does not
define is left as written and reported as not compensated.

Write: the edited points' numbers, with S and T from their configuration.
KUKA requires the DEF name of the .src and the DEFDAT name of the .dat to be
the file name: a program written under another name gets both renamed (and
its .dat written beside it under the same name); otherwise the files are
written back byte for byte.
"""

import dataclasses
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError, WriteError
from trajcomp.formats._text import (
    NUMBER,
    Lines,
    encode_text,
    encode_xyzabc,
    fail,
    format_number,
    mask,
    numbered,
    patched,
    read_source,
)
from trajcomp.program import CIRCULAR, JOINT, LINEAR, Motion, Program, Span, Statement, Target
from trajcomp.transforms import matrix_to_pose, pose_to_matrix

POSE = ("x", "y", "z", "a", "b", "c")
AXES = ("a1", "a2", "a3", "a4", "a5", "a6")
MIN_PLACES = dict.fromkeys(POSE[:3], 3) | dict.fromkeys(POSE[3:], 4) | dict.fromkeys(AXES, 4)
CARTESIAN_TYPES = {"E6POS", "POS", "FRAME"}
JOINT_TYPES = {"E6AXIS", "AXIS"}
KINDS = {"PTP": JOINT, "SPTP": JOINT, "LIN": LINEAR, "SLIN": LINEAR, "CIRC": CIRCULAR, "SCIRC": CIRCULAR}

_DECL = re.compile(
    r"^\s*(?:DECL\s+)?(?:GLOBAL\s+)?(E6POS|POS|FRAME|E6AXIS|AXIS|FDAT|PDAT|LDAT)\s+(\w+)\s*=\s*\{(.*)\}\s*$", re.I
)
_DATA = re.compile(r"^\s*(TOOL_DATA|BASE_DATA)\s*\[\s*(\d+)\s*\]\s*=\s*\{(.*)\}\s*$", re.I)
_SYSVAR = re.compile(r"^\s*\$(TOOL|BASE)\s*=\s*(?:(TOOL_DATA|BASE_DATA)\s*\[\s*(\d+)\s*\]|(\$NULLFRAME)|\{(.*)\})\s*$", re.I)
_BAS = re.compile(r"^\s*BAS\s*\(\s*#(TOOL|BASE|VEL_PTP|VEL_CP)\s*,\s*(" + NUMBER + r")\s*\)\s*$", re.I)
_ACT = re.compile(r"^\s*(FDAT|PDAT|LDAT)_ACT\s*=\s*(\w+)\s*$", re.I)
_VEL_CP = re.compile(r"^\s*\$VEL\.CP\s*=\s*(" + NUMBER + r")\s*$", re.I)
_APO = re.compile(r"^\s*\$APO\.CDIS\s*=\s*(" + NUMBER + r")\s*$", re.I)
_MOTION = re.compile(r"^\s*(PTP|LIN|CIRC|SPTP|SLIN|SCIRC)(_REL)?\b\s*(.*?)\s*$", re.I)
_MEMBER = re.compile(r"\s*([A-Za-z_]\w*)\s+(" + NUMBER + r"|'B[01]+')\s*$")
_APPROX = re.compile(r"\s*((?:\bC_(?:PTP|DIS|VEL|ORI)\b\s*)+)$", re.I)
_NAME = re.compile(r"^[A-Za-z_$][\w$]*$")
_DEF = re.compile(r"^\s*(?:GLOBAL\s+)?DEF(?:FCT\s+\w+)?\s+(\w+)\s*\(", re.I | re.M)
_DEFDAT = re.compile(r"^\s*DEFDAT\s+(\w+)", re.I | re.M)
_PROGRAM_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]{0,23}$")  # KRL names: 24 characters at most


def _members(body, start, source, name, line, text, numeric=True):
    """``{member: Span}`` of a KRL aggregate body at offset ``start``; type prefixes skipped."""
    colon = re.match(r"\s*\w+\s*:", body)
    skip = colon.end() if colon else 0
    out, position = {}, skip
    for piece in body[skip:].split(","):
        m = _MEMBER.match(piece)
        if m:
            key = m.group(1).lower()
            out[key] = Span(source, start + position + m.start(2), start + position + m.end(2), m.group(2))
        elif numeric and piece.strip():
            fail(name, line, text, f"malformed member {piece.strip()!r}")
        position += len(piece) + 1
    return out


def _int(text):
    return int(text[2:-1], 2) if text.startswith("'") else int(float(text))


def _point(members, name, source_name, line, text, typ):
    """A Target from the members of a point aggregate."""
    if typ in JOINT_TYPES or (typ is None and "a1" in members):
        missing = [a for a in AXES if a not in members]
        if missing:
            fail(source_name, line, text, f"joint point lacks {', '.join(m.upper() for m in missing)}")
        joints = np.radians([float(members[a].text) for a in AXES])
        return Target(name=name, line=line, joints=joints, spans={a: members[a] for a in AXES})
    missing = [p for p in POSE if p not in members]
    if missing:
        fail(source_name, line, text, f"point lacks {', '.join(m.upper() for m in missing)}")
    vector = np.array([float(members[p].text) for p in POSE])
    vector[3:] = np.radians(vector[3:])
    config = (_int(members["s"].text), _int(members["t"].text)) if "s" in members and "t" in members else ()
    keep = {k: v for k, v in members.items() if k in POSE or k in ("s", "t")}
    return Target(name=name, line=line, pose=pose_to_matrix(vector), config=config, spans=keep)


def _frame(members, source_name, line, text):
    missing = [p for p in POSE if p not in members]
    if missing:
        fail(source_name, line, text, f"frame lacks {', '.join(m.upper() for m in missing)}")
    vector = np.array([float(members[p].text) for p in POSE])
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
        self.tools, self.frames = {"0": np.eye(4)}, {"0": np.eye(4)}
        self.tool = self.base = None
        self.speed_ptp = self.speed_cp = self.zone = None

    def add_source(self, source):
        self.sources.append(source)
        index = len(self.sources) - 1
        return index, Lines(source.text), mask(source.text, ";")

    def declarations(self, index, masked, line_no, start, end):
        """Handle a point, FDAT/PDAT/LDAT or TOOL_DATA/BASE_DATA line; True if it was one."""
        name = self.sources[index].name
        text = masked[start:end]
        original = self.sources[index].text[start:end]
        m = _DECL.match(text)
        if m:
            typ, point = m.group(1).upper(), m.group(2)
            body_start = start + m.start(3)
            if typ in ("FDAT", "PDAT", "LDAT"):
                self.data[point.upper()] = _members(m.group(3), body_start, index, name, line_no, original, False)
            else:
                members = _members(m.group(3), body_start, index, name, line_no, original)
                self.points[point.upper()] = len(self.targets)
                self.targets.append(_point(members, point, name, line_no, original, typ))
            return True
        m = _DATA.match(text)
        if m:
            members = _members(m.group(3), start + m.start(3), index, name, line_no, original)
            table = self.tools if m.group(1).upper() == "TOOL_DATA" else self.frames
            table[m.group(2)] = _frame(members, name, line_no, original)
            return True
        return False

    def statement(self, index, masked, line_no, start, end):
        """Handle one .src line."""
        name = self.sources[index].name
        text = masked[start:end]
        original = self.sources[index].text[start:end]
        if self.declarations(index, masked, line_no, start, end):
            self.items.append(Statement(line_no, original))
            return
        m = _MOTION.match(text)
        if m:
            self.items.append(self.motion(m, index, start, line_no, original))
            return
        self.state(text, index, start, name, line_no, original)
        self.items.append(Statement(line_no, original))

    def state(self, text, index, start, name, line_no, original):
        """Track tool, base, speed and zone statements."""
        if m := _SYSVAR.match(text):
            which = m.group(1).upper()
            if m.group(3) is not None:
                value = m.group(3)
            elif m.group(4) is not None:
                value = "0"
            else:
                members = _members(m.group(5), start + m.start(5), index, name, line_no, original)
                value = f"{which} line {line_no}"
                (self.tools if which == "TOOL" else self.frames)[value] = _frame(members, name, line_no, original)
            if which == "TOOL":
                self.tool = value
            else:
                self.base = value
        elif m := _BAS.match(text):
            what, value = m.group(1).upper(), m.group(2)
            if what == "TOOL":
                self.tool = str(int(float(value)))
            elif what == "BASE":
                self.base = str(int(float(value)))
            elif what == "VEL_PTP":
                self.speed_ptp = float(value)
            else:
                self.speed_cp = float(value) * 1000.0
        elif m := _ACT.match(text):
            kind, data_name = m.group(1).upper(), m.group(2).upper()
            data = self.data.get(data_name)
            if data is None:
                return
            if kind == "FDAT":
                if "tool_no" in data:
                    self.tool = str(int(float(data["tool_no"].text)))
                if "base_no" in data:
                    self.base = str(int(float(data["base_no"].text)))
            else:
                if "vel" in data:
                    vel = float(data["vel"].text)
                    if kind == "PDAT":
                        self.speed_ptp = vel
                    else:
                        self.speed_cp = vel * 1000.0
                if "apo_dist" in data:
                    self.zone = float(data["apo_dist"].text)
        elif m := _VEL_CP.match(text):
            self.speed_cp = float(m.group(1)) * 1000.0
        elif m := _APO.match(text):
            self.zone = float(m.group(1))

    def motion(self, m, index, start, line_no, original):
        """A Motion from a PTP/LIN/CIRC line."""
        name = self.sources[index].name
        kind = KINDS[m.group(1).upper()]
        args = re.split(r"\bWITH\b", m.group(3), flags=re.I)[0]
        offset = start + m.start(3)
        approx = _APPROX.search(args)
        zone = self.zone if approx else None
        if approx:
            args = args[: approx.start()]
        parts, position = [], 0
        for piece in _split_top(args):
            parts.append((piece, offset + position))
            position += len(piece) + 1
        wanted = 2 if kind == CIRCULAR else 1
        if len(parts) < wanted or not parts[0][0].strip():
            fail(name, line_no, original, f"{m.group(1).upper()} needs {wanted} target(s)")
        if m.group(2):  # relative motion: the position depends on where the robot is
            found = [None] * wanted
        else:
            found = [self.target(piece, at, index, name, line_no, original) for piece, at in parts[:wanted]]
        speed, unit = (self.speed_ptp, "%") if kind == JOINT else (self.speed_cp, "mm/s")
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
        )

    def target(self, piece, at, index, name, line_no, original):
        """Target index of a motion argument; None for an expression or an undefined point."""
        stripped = piece.strip()
        if stripped.startswith("{") and stripped.endswith("}") and stripped.count("{") == 1:
            body_at = at + piece.index("{") + 1
            members = _members(stripped[1:-1], body_at, index, name, line_no, original)
            self.targets.append(_point(members, "", name, line_no, original, None))
            return len(self.targets) - 1
        if _NAME.match(stripped):
            return self.points.get(stripped.upper(), ("pending", stripped))
        return None


def _split_top(text):
    """Split at commas outside braces, brackets and parentheses."""
    parts, depth, current = [], 0, []
    for ch in text:
        if ch in "{[(":
            depth += 1
        elif ch in "}])":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append("".join(current))
            current = []
        else:
            current.append(ch)
    parts.append("".join(current))
    return parts


def read(path):
    """Read a KRL .src and its .dat (same name, beside it, if there is one)."""
    path = Path(path)
    reader = _Reader()
    src = read_source(path)
    if not _DEF.search(mask(src.text, ";")):
        raise ReadError(f"{path}: not a KRL program: no DEF line")
    src_index, src_lines, src_masked = reader.add_source(src)
    dat_path = _sibling_dat(path)
    if dat_path is not None:
        dat_index, dat_lines, dat_masked = reader.add_source(read_source(dat_path))
        for line_no, start, end in dat_lines:
            reader.declarations(dat_index, dat_masked, line_no, start, end)
    for line_no, start, end in src_lines:
        reader.statement(src_index, src_masked, line_no, start, end)
    items = []
    for item in reader.items:
        if isinstance(item, Motion):
            item = dataclasses.replace(
                item, target=_resolve(item.target, reader.points), via=_resolve(item.via, reader.points)
            )
        items.append(item)
    return Program(
        "krl", path.stem, tuple(items), tuple(reader.targets), reader.tools, reader.frames, tuple(reader.sources)
    )


def _resolve(ref, points):
    """Point references made before their declaration (names declared later in the .src)."""
    if isinstance(ref, tuple):
        return points.get(ref[1].upper())
    return ref


def _status_text(value, old):
    if isinstance(old, str) and old.startswith("'B"):
        return f"'B{value:0{len(old) - 3}b}'"
    return str(value)


def _encode(target, old):
    if target.is_joint:
        return dict(zip(AXES, np.degrees(target.joints)))
    out = encode_xyzabc(target.pose, old, POSE)
    if target.config:
        out["s"] = _status_text(target.config[0], old.get("s"))
        out["t"] = _status_text(target.config[1], old.get("t"))
    return out


def write(program, path):
    """``{path.src: bytes, path.dat: bytes}``: patched in place if read from KRL, else generated.

    The DEF and DEFDAT names become the output file's name when it differs
    (KUKA loads a program only under its own name).

    Raises
    ------
    WriteError
        The output file name is not a valid KRL name.
    """
    path = Path(path)
    if not _PROGRAM_NAME.match(path.stem):
        raise WriteError(
            f"{path}: {path.stem!r} cannot name a KRL program (letters, digits and _, "
            "not starting with a digit, at most 24 characters): KUKA needs DEF name = file name"
        )
    dat = path.with_suffix(".dat" if path.suffix.islower() else ".DAT")
    if program.format == "krl" and program.sources:
        texts = patched(program, _encode, MIN_PLACES)
        texts = [_renamed(text, pattern, path.stem) for text, pattern in zip(texts, (_DEF, _DEFDAT))]
        outs = [path, dat][: len(texts)]
        return {out: encode_text(source, text) for out, source, text in zip(outs, program.sources, texts)}
    src_text, dat_text = _emit(program, path.stem)
    return {path: src_text.encode("latin-1"), dat: dat_text.encode("latin-1")}


def _renamed(text, pattern, name):
    """``text`` with the name of its first DEF (or DEFDAT) replaced by ``name`` if it differs (KRL ignores case)."""
    m = pattern.search(mask(text, ";"))
    if m is None or m.group(1).lower() == name.lower():
        return text
    return text[: m.start(1)] + name + text[m.end(1):]


def _aggregate(target):
    if target.is_joint:
        return "E6AXIS", ",".join(f"A{k + 1} {format_number(v, 9)}" for k, v in enumerate(np.degrees(target.joints)))
    pose = matrix_to_pose(target.pose)
    fields = [f"{p.upper()} {format_number(v, 6)}" for p, v in zip(POSE[:3], pose[:3])]
    fields += [f"{p.upper()} {format_number(v, 9)}" for p, v in zip(POSE[3:], np.degrees(pose[3:]))]
    if target.config:
        fields += [f"S {target.config[0]}", f"T {target.config[1]}"]
    return ("E6POS" if target.config else "POS"), ",".join(fields)


def _emit(program, name):
    """New .src and .dat texts (CRLF, as KUKA's editors write them)."""
    tools = numbered([m.tool for m in program.motions])
    bases = numbered([m.frame for m in program.motions])
    names, decls = {}, []
    src = [f"DEF {name}( )"]
    for table, numbers, data in ((program.tools, tools, "TOOL_DATA"), (program.frames, bases, "BASE_DATA")):
        for key, number in numbers.items():
            if key is not None and number and key in table:
                pose = matrix_to_pose(table[key])
                values = [format_number(v, 6) for v in pose[:3]] + [format_number(v, 9) for v in np.degrees(pose[3:])]
                src.append(f"  {data}[{number}]={{" + ",".join(f"{p.upper()} {v}" for p, v in zip(POSE, values)) + "}")
    tool = base = speed = zone = None
    for motion in program.motions:
        if motion.target is None:
            src.append(f"  ; not converted: {motion.text}")
            continue
        if motion.tool != tool:
            tool = motion.tool
            src.append(f"  $TOOL=TOOL_DATA[{tools[tool]}]" if tool is not None else "  $TOOL=$NULLFRAME")
        if motion.frame != base:
            base = motion.frame
            src.append(f"  $BASE=BASE_DATA[{bases[base]}]" if base is not None else "  $BASE=$NULLFRAME")
        if motion.speed is not None and (motion.speed, motion.speed_unit) != speed:
            speed = (motion.speed, motion.speed_unit)
            if motion.speed_unit == "mm/s":
                src.append(f"  $VEL.CP={format_number(motion.speed / 1000.0, 6)}")
            elif motion.speed_unit == "%":
                src.append(f"  BAS(#VEL_PTP,{format_number(motion.speed, 3)})")
        if motion.zone is not None and motion.zone != zone:
            zone = motion.zone
            src.append(f"  $APO.CDIS={format_number(zone, 3)}")
        refs = []
        for index in (motion.via, motion.target):
            if index is None:
                continue
            if index not in names:
                names[index] = _point_name(program.targets[index], names.values(), len(names) + 1)
                typ, body = _aggregate(program.targets[index])
                decls.append(f"DECL {typ} {names[index]}={{{body}}}")
            refs.append(names[index])
        keyword = {JOINT: "PTP", LINEAR: "LIN", CIRCULAR: "CIRC"}[motion.kind]
        approx = " C_DIS" if motion.zone is not None else ""
        src.append(f"  {keyword} {', '.join(refs)}{approx}")
    src.append("END")
    dat = [f"DEFDAT {name}"] + decls + ["ENDDAT"]
    return "\r\n".join(src) + "\r\n", "\r\n".join(dat) + "\r\n"


def _point_name(target, taken, number):
    name = re.sub(r"\W", "_", target.name)[:24]
    if not name or not _NAME.match(name) or name.upper() in {t.upper() for t in taken}:
        name = f"XP{number}"
    return name
