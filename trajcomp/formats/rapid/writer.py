"""ABB RAPID modules (.mod, .prg, .modx).

Read:
- declarations ``[LOCAL|TASK] CONST|PERS|VAR robtarget p10 :=
  [[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,...,eax_f]];`` (mm,
  quaternion scalar first; the external axes carried unchanged, 9E9 =
  unused), ``jointtarget`` (deg), ``tooldata`` (its tframe: the tool) and
  ``wobjdata`` (uframe * oframe: the work object), possibly spread over
  several lines; ``tool.tframe := [..]`` / ``wobj.uframe := [..]`` with a
  literal pose (as RoboDK writes them) give the tool or work object a new
  value from that line on;
- MoveJ / MoveL / MoveC / MoveAbsJ (and their DO / AO / GO / Sync variants,
  TriggL/J/C, ArcL/C, CladL/C) to a declared name or an inline literal, with
  speeddata ``vN`` / ``vmax`` / ``\\V:=`` / ``\\T:=``, zonedata ``fine`` /
  ``zN`` / ``\\Z:=``, the tool and ``\\WObj:=``, also after a comma
  (``tool0,\\WObj:=wobj1``). A named speeddata or num is read where the
  module proves it constant (a CONST with a literal or another such CONST,
  its v_tcp); PERS and VAR data, routine parameters and data declared
  elsewhere are set at run time (`Motion.speed_why`).
  Identifiers are case-insensitive; tool0 (the flange) and wobj0 (the
  world frame) need no declaration.
Not compensated, with the reason (`Motion.reason`): expressions (Offs,
RelTool, CRobT, array elements), routine parameters, points declared without
a value or assigned in the code, tools and work objects changed at run time
or not supported (stationary tool, robot-held work object), and motion
instructions trajcomp does not read (SearchL, MoveExtJ ...), points,
tools and work objects another module of the task assigns. A point
another module of the task declares (not LOCAL; a module of the same
folder, or of a backup's TASKn/PROGMOD and SYSMOD) is read from that module
(a companion `Source`): corrected there, which is written back beside the
output (`trajcomp.formats._text.companion_outputs`) when it changed. A
motion to a point no module declares is a ReadError naming the points; so are
numbers out of range and quaternions that are not rotations. Points passed
to routines (``MyProc p10;``) are `Statement.refs`.

Write: the edited targets' numbers, with confdata from their configuration.
"""

import re

import numpy as np

from trajcomp.errors import WriteError
from trajcomp.formats._rapid_reader import CONF, JOINTS, POSITION, QUAT, read
from trajcomp.formats._text import active_axes, encode_targets, format_number, same_rotation, where, write_single_file
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR
from trajcomp.arm.transforms import matrix_to_quat, quat_to_matrix

__all__ = ["read", "write"]

MIN_PLACES = dict.fromkeys(POSITION, 3) | dict.fromkeys(QUAT, 8) | dict.fromkeys(JOINTS, 4)
SPEEDS = (5, 10, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 400, 500, 600, 800, 1000, 1500, 2000, 2500, 3000)
ZONES = (0, 1, 5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200)
UNUSED = "9E+09"
_NAME = re.compile(r"^[A-Za-z]\w*$")


def _encode(targets, olds):
    return encode_targets(targets, olds, lambda target: dict(zip(JOINTS, np.degrees(target.joints))), _cartesian)


def _cartesian(targets, olds):
    """Position, the quaternion where the rotation differs from the file's (the sign of the file's) and the
    configuration data of each target."""
    poses = np.array([target.pose for target in targets])
    old_quat = np.array([[old[q] for q in QUAT] for old in olds], dtype=float)
    turned = ~same_rotation(poses[:, :3, :3], quat_to_matrix(old_quat))
    quat = matrix_to_quat(poses[turned, :3, :3])
    quat = np.where(np.sum(quat * old_quat[turned], axis=1, keepdims=True) < 0, -quat, quat)
    quats = iter(quat.tolist())
    out = []
    for target, position, turn in zip(targets, poses[:, :3, 3].tolist(), turned.tolist()):
        numbers = dict(zip(POSITION, position)) | (dict(zip(QUAT, next(quats))) if turn else {})
        if target.config:
            numbers |= {c: str(v) for c, v in zip(CONF, target.config)}
        out.append(numbers)
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
    axes = active_axes(program, 6, "RAPID")
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
                    decls.append(f"  CONST jointtarget {names[index]} := [[{_numbers(np.degrees(target.joints), 9)}],[{_extax(target, axes)}]];")
                else:
                    if len(target.config) != 4:
                        raise WriteError(f"target {where(target)}: RAPID needs its confdata; convert with a robot")
                    decls.append(
                        f"  CONST robtarget {names[index]} := [[{_numbers(target.pose[:3, 3], 6)}],"
                        f"[{_numbers(matrix_to_quat(target.pose[:3, :3]), 10)}],"
                        f"[{','.join(str(c) for c in target.config)}],[{_extax(target, axes)}]];"
                    )
            refs.append(names[index])
        joint_target = program.targets[motion.target].is_joint
        keyword = "MoveAbsJ" if joint_target else {JOINT: "MoveJ", LINEAR: "MoveL", CIRCULAR: "MoveC"}[motion.kind]
        wobj = "" if motion.frame is None or joint_target else f"\\WObj:={_identifier(motion.frame, 'w', 'wobj0')}"
        tool = _identifier(motion.tool, "t", "tool0")
        body.append(f"    {keyword} {', '.join(refs)}, {_speed(motion)}, {_zone(motion)}, {tool}{wobj};")
    lines = [f"MODULE {module}"] + decls + ["", "  PROC main()"] + body + ["  ENDPROC", "ENDMODULE"]
    return "\n".join(lines) + "\n"


def _extax(target, axes):
    """eax_a..eax_f of a target: its external ``axes`` (indices), 9E+09 for the others."""
    values = [] if target.external is None else list(target.external)
    out = [values[k] if k in axes and k < len(values) else np.nan for k in range(6)]
    return ",".join(UNUSED if np.isnan(v) else format_number(v, 6) for v in out)


def _point_name(target, taken, number):
    name = re.sub(r"\W", "_", target.name)
    if not _NAME.match(name) or name in taken:
        name = f"{'j' if target.is_joint else 'p'}{number}"
    return name
