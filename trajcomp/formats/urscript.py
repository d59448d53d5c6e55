"""Universal Robots URScript (.script, .urscript).

Read:
- ``movej``, ``movel``, ``movep``, ``movec`` to a pose literal ``p[x, y, z,
  rx, ry, rz]`` (metres, rotation vector in rad), a joint list ``[q1, ...,
  q6]`` (rad), a variable holding one, or ``get_inverse_kin(pose,
  qnear=joints)``; speeds ``v=`` (m/s, rad/s for movej), blend ``r=`` (m);
- variables ``[global|local] name = p[...]`` / ``= [...]``, with PolyScope's
  pairs ``Waypoint_n_p`` / ``Waypoint_n_q``: the ``_q`` list (like a
  ``qnear`` literal or variable) holds the joints of the pose and is
  rewritten with the corrected joints;
- ``set_tcp(p[...])``: the tool of the following motions (before it, the
  installation TCP: the robot description's tool). Poses are in the base
  frame.
Poses built at run time (pose_trans, pose_add, interpreted expressions) are
left as written and reported as not compensated.
"""

import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError, WriteError
from trajcomp.formats._text import (
    NUMBER,
    active_axes,
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
from trajcomp.transforms import matrix_to_rotvec, rotvec_to_matrix

POSE = ("x", "y", "z", "rx", "ry", "rz")
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
NEAR = ("near1", "near2", "near3", "near4", "near5", "near6")
MIN_PLACES = dict.fromkeys(POSE + JOINTS + NEAR, 6)  # 1e-6 m = 0.001 mm; 1e-6 rad
KINDS = {"movej": JOINT, "movel": LINEAR, "movep": LINEAR, "movec": CIRCULAR}
POSITIONAL = {"movej": ("a", "v", "t", "r"), "movel": ("a", "v", "t", "r"), "movep": ("a", "v", "r"),
              "movec": ("a", "v", "r", "mode")}

_N = r"\s*(" + NUMBER + r")\s*"
_SIX = ",".join([_N] * 6)
_POSE = re.compile(r"^\s*p\[" + _SIX + r"\]\s*$")
_LIST = re.compile(r"^\s*\[" + _SIX + r"\]\s*$")
_ASSIGN = re.compile(r"^\s*(?:global\s+|local\s+)?([A-Za-z_]\w*)\s*=\s*(.+?)\s*$")
_CALL = re.compile(r"\b(movej|movel|movep|movec|set_tcp)\s*\(")
_IK = re.compile(r"^\s*get_inverse_kin\s*\((.*)\)\s*$", re.S)
_NAME = re.compile(r"^\s*([A-Za-z_]\w*)\s*$")
_NUMBERS_ONLY = re.compile(r"^\s*p?\[[\s\d.eE+,-]*\]\s*$")
_SIGNS = re.compile(r"(?m)^\s*def\s+\w+\s*\(|\b(?:movej|movel|movep|movec)\s*\(|\bp\[")


def _arguments(text, offset):
    """``[(argument, start)]`` of a call's argument text, split at top-level commas."""
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


def _closing(text, open_at):
    """Index of the parenthesis closing the one at ``open_at``."""
    depth = 0
    for k in range(open_at, len(text)):
        depth += {"(": 1, ")": -1}.get(text[k], 0)
        if depth == 0:
            return k
    return -1


def _pose(values):
    T = np.eye(4)
    T[:3, :3] = rotvec_to_matrix(values[3:])
    T[:3, 3] = np.asarray(values[:3]) * 1000.0
    return T


class _Reader:
    def __init__(self, source):
        self.source = source
        self.targets, self.items = [], []
        self.variables = {}  # name -> target index, latest assignment
        self.joint_lists = {}  # name -> (joints rad, spans as NEAR roles)
        self.joint_variables = {}  # name -> target index of a joint-list variable
        self.tools, self.tool = {}, None
        self.direct = set()  # joint-list variables used as motion targets

    def literal(self, text, offset, line, original, name=""):
        """A Target from a pose or joint-list literal; None if ``text`` is not one."""
        if m := _POSE.match(text):
            values = [float(m.group(k)) for k in range(1, 7)]
            return Target(name=name, line=line, pose=_pose(values), spans=spans(0, m, POSE, offset))
        if m := _LIST.match(text):
            joints = np.array([float(m.group(k)) for k in range(1, 7)])
            return Target(name=name, line=line, joints=joints, spans=spans(0, m, JOINTS, offset))
        if _NUMBERS_ONLY.match(text):
            fail(self.source.name, line, original, "malformed pose or joint list (six numbers expected)")
        return None

    def add(self, target):
        self.targets.append(target)
        return len(self.targets) - 1

    def position(self, text, offset, line, original):
        """Target index of a motion's position argument (None if computed at run time)."""
        if target := self.literal(text, offset, line, original):
            return self.add(target)
        if m := _NAME.match(text):
            return self.variables.get(m.group(1))
        if m := _IK.match(text):
            args = _arguments(m.group(1), offset + m.start(1))
            index = self.position(args[0][0], args[0][1], line, original)
            near = [a for a in args[1:] if a[0].strip().startswith("qnear")] or args[1:2]
            if index is not None and near:
                near_text, near_at = near[0]
                value = near_text.split("=", 1)[-1] if "=" in near_text else near_text
                shift = near_at + (near_text.index("=") + 1 if "=" in near_text else 0)
                self.link(index, value, shift)
            return index
        return None

    def link(self, index, text, offset):
        """Give Cartesian target ``index`` the joints of a qnear list (literal or variable)."""
        target = self.targets[index]
        if target.is_joint:
            return
        if m := _LIST.match(text):
            joints = np.array([float(m.group(k)) for k in range(1, 7)])
            found = spans(0, m, NEAR, offset)
        elif (m := _NAME.match(text)) and m.group(1) in self.joint_lists:
            joints, found = self.joint_lists[m.group(1)]
        else:
            return
        self.targets[index] = Target(
            name=target.name, line=target.line, pose=target.pose, joints=joints, spans={**target.spans, **found}
        )

    def assignment(self, m, start, line, original):
        name, value = m.group(1), m.group(2)
        target = self.literal(value, start + m.start(2), line, original, name)
        if target is None:
            return
        if target.is_joint:
            near = {n: s for n, s in zip(NEAR, (target.spans[j] for j in JOINTS))}
            self.joint_lists[name] = (target.joints, near)
            self.variables.pop(name, None)
            self.joint_variables[name] = self.add(target)
        else:
            self.variables[name] = self.add(target)

    def call(self, function, args, line, original):
        if function == "set_tcp":
            tcp = self.literal(args[0][0], args[0][1], line, original) if args else None
            if tcp is None or tcp.is_joint:
                self.tool = f"set_tcp line {line}"  # computed at run time: undefined, must be supplied
                return None
            self.tool = f"set_tcp line {line}"
            self.tools[self.tool] = tcp.pose
            return None
        kind = KINDS[function]
        count = 2 if kind == CIRCULAR else 1
        if len(args) < count or not args[0][0].strip():
            fail(self.source.name, line, original, f"{function} needs {count} position(s)")
        found = [self.joint_target(a) or self.position(a, s, line, original) for a, s in args[:count]]
        options = dict(zip(POSITIONAL[function], (a.strip() for a, _ in args[count:] if "=" not in a)))
        options |= {k.strip(): v.strip() for k, v in (a.split("=", 1) for a, _ in args[count:] if "=" in a)}
        speed = _number(options.get("v"))
        blend = _number(options.get("r"))
        return Motion(
            kind=kind,
            target=found[-1],
            via=found[0] if kind == CIRCULAR else None,
            speed=None if speed is None else speed * (1.0 if function == "movej" else 1000.0),
            speed_unit="rad/s" if function == "movej" else "mm/s",
            zone=blend * 1000.0 if blend else None,
            tool=self.tool,
            line=line,
            text=original.strip(),
        )

    def joint_target(self, text):
        """Index of a joint-list variable used directly as a position."""
        m = _NAME.match(text)
        if m and m.group(1) in self.joint_variables and m.group(1) not in self.variables:
            self.direct.add(m.group(1))
            return self.joint_variables[m.group(1)]
        return None


def _number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def read(path):
    """Read a URScript program."""
    source = read_source(path)
    masked = mask(source.text, "#")
    if not _SIGNS.search(masked):
        raise ReadError(f"{path}: not a URScript program: no def, move or pose literal")
    reader = _Reader(source)
    for line, start, end in Lines(source.text):
        text, original = masked[start:end], source.text[start:end]
        call = _CALL.search(text)
        if call:
            close = _closing(text, call.end() - 1)
            if close < 0:
                fail(source.name, line, original, "unbalanced parentheses")
            args = _arguments(text[call.end():close], start + call.end())
            motion = reader.call(call.group(1), args, line, original)
            reader.items.append(motion or Statement(line, original))
            continue
        if m := _ASSIGN.match(text):
            reader.assignment(m, start, line, original)
        reader.items.append(Statement(line, original))
    _pair_waypoints(reader)
    name = Path(path).stem
    return Program("urscript", name, tuple(reader.items), tuple(reader.targets), reader.tools, {}, (source,))


def _pair_waypoints(reader):
    """Give each pose variable ``X_p`` the joints of its ``X_q`` list (PolyScope waypoints)."""
    for name, index in reader.variables.items():
        if name.endswith("_p") and name[:-2] + "_q" in reader.joint_lists and name[:-2] + "_q" not in reader.direct:
            if reader.targets[index].joints is None:
                joints, near = reader.joint_lists[name[:-2] + "_q"]
                target = reader.targets[index]
                reader.targets[index] = Target(
                    name=target.name, line=target.line, pose=target.pose, joints=joints, spans={**target.spans, **near}
                )


def _rotvec_near(rot, old):
    """Rotation vector of ``rot`` (3, 3) closest to ``old`` among its equivalents (angle +- 2 pi)."""
    vec = matrix_to_rotvec(rot)
    angle = np.linalg.norm(vec)
    if angle < 1e-12:
        return vec
    other = vec * (1.0 - 2.0 * np.pi / angle)
    return other if np.linalg.norm(other - old) < np.linalg.norm(vec - old) else vec


def _encode(target, old):
    if target.is_joint:
        return dict(zip(JOINTS, target.joints))
    out = dict(zip(POSE[:3], target.pose[:3, 3] / 1000.0))
    old_vec = np.array([old[r] for r in POSE[3:]])
    if not same_rotation(target.pose[:3, :3], rotvec_to_matrix(old_vec)):
        out |= dict(zip(POSE[3:], _rotvec_near(target.pose[:3, :3], old_vec)))
    if target.joints is not None:
        out |= dict(zip(NEAR, target.joints))
    return out


def write(program, path):
    """``{path: bytes}``: patched in place if read from URScript, else a generated script."""
    return write_single_file(program, path, "urscript", _encode, MIN_PLACES, _emit)


def _list(values, places):
    return ", ".join(format_number(v, places) for v in values)


def _pose_text(T):
    return f"p[{_list(T[:3, 3] / 1000.0, 10)}, {_list(matrix_to_rotvec(T[:3, :3]), 12)}]"


def _position(target, kind):
    if target.is_joint:
        return f"[{_list(target.joints, 12)}]"
    if kind == JOINT and target.joints is not None:
        return f"get_inverse_kin({_pose_text(target.pose)}, qnear=[{_list(target.joints, 12)}])"
    return _pose_text(target.pose)


def _emit(program, name):
    """A new URScript program; poses must already be in the base frame (see postprocess.convert)."""
    active_axes(program, 0, "URScript")
    function = re.sub(r"\W", "_", name) or "program"
    if function[0].isdigit():
        function = "p" + function
    lines, tool = [f"def {function}():"], None
    for motion in program.motions:
        if motion.target is None:
            lines.append(f"  # not converted: {motion.text}")
            continue
        if motion.frame is not None:
            raise WriteError(f"line {motion.line}: URScript poses are in the base frame; frame {motion.frame} left")
        if motion.tool != tool:
            tool = motion.tool
            if tool is not None:
                if tool not in program.tools:
                    raise WriteError(
                        f"tool {tool!r} is used but not defined in the program; "
                        f"give its value (e.g. --tool {tool}=x,y,z,a,b,c in mm and deg)"
                    )
                lines.append(f"  set_tcp({_pose_text(program.tools[tool])})")
        positions = [_position(program.targets[i], motion.kind) for i in (motion.via, motion.target) if i is not None]
        function_name = {JOINT: "movej", LINEAR: "movel", CIRCULAR: "movec"}[motion.kind]
        options = []
        if motion.speed is not None and motion.speed_unit == ("rad/s" if motion.kind == JOINT else "mm/s"):
            options.append(f"v={format_number(motion.speed / (1.0 if motion.kind == JOINT else 1000.0), 6)}")
        if motion.zone is not None:
            options.append(f"r={format_number(motion.zone / 1000.0, 6)}")
        lines.append(f"  {function_name}({', '.join(positions + options)})")
    lines += ["end", f"{function}()"]
    return "\n".join(lines) + "\n"
