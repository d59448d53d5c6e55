"""The RAPID writer: the edited robtargets into the module as read, or a module generated from another language (see `trajcomp.formats.rapid`)."""

import re

import numpy as np

from trajcomp.errors import WriteError
from trajcomp.formats.rapid.reader import CONF, JOINTS, POSITION, PREDEFINED_V_LEAX, PREDEFINED_V_ORI, QUAT, read
from trajcomp.formats.file_writing import active_axes, write_single_file, written_speed
from trajcomp.formats.number_writing import ceil_places, floor_places, format_number
from trajcomp.formats.pose_encoding import encode_targets, same_rotation
from trajcomp.formats.text_edits import where
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


def _encode_columns(table, rows, old):
    """The numbers of a `TargetTable`'s rows (K,) in RAPID, as columns (`trajcomp.formats.text_edits.target_edits`):
    `_encode` without an object per target."""
    joint = table.is_joint[rows]
    out = dict(zip(JOINTS, np.where(joint[:, None], np.degrees(table.joints[rows]), np.nan).T))
    cartesian = np.flatnonzero(~joint)
    poses = table.pose[rows[cartesian]]
    position = np.full((len(rows), 3), np.nan)
    position[cartesian] = poses[:, :3, 3]
    out |= dict(zip(POSITION, position.T))
    old_quat = np.stack([old.value[q] for q in QUAT], axis=1)[cartesian]
    turned = ~same_rotation(poses[:, :3, :3], quat_to_matrix(old_quat))
    quat = matrix_to_quat(poses[turned, :3, :3])
    quats = np.full((len(rows), 4), np.nan)
    quats[cartesian[turned]] = np.where(np.sum(quat * old_quat[turned], axis=1, keepdims=True) < 0, -quat, quat)
    out |= dict(zip(QUAT, quats.T))
    distinct = {}  # code of each distinct configuration: a path's points mostly share theirs
    code = np.array([distinct.setdefault(config, len(distinct)) for config in map(table.config.__getitem__,
                                                                                      rows.tolist())], dtype=int)
    code[joint] = len(distinct)  # a joint target writes no confdata: the row of None below
    for k, role in enumerate(CONF):
        texts = [str(c[k]) if c and k < len(c) else None for c in distinct] + [None]
        out[role] = np.array(texts, dtype=object)[code]
    return out


def write(program, path):
    """``{path: bytes}``: patched in place if read from RAPID, else a generated module."""
    return write_single_file(program, path, "rapid", _encode, MIN_PLACES, _emit, _encode_columns)


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
    """The speed data of a generated motion: ``vN``, ``vmax``, a literal with its v_ori and v_leax, ``\\V`` or
    ``\\T``."""
    value, unit = written_speed(motion, "rapid")
    if value is None:
        return "vmax"  # the arm's limits
    if unit == "s":
        return f"vmax\\T:={format_number(ceil_places(value, 3), 3)}"
    v_tcp = floor_places(value, 3)
    v_ori = PREDEFINED_V_ORI if motion.orientation_speed is None else np.degrees(motion.orientation_speed)
    v_leax = PREDEFINED_V_LEAX if motion.external_speed is None else motion.external_speed
    if v_ori < PREDEFINED_V_ORI or v_leax < PREDEFINED_V_LEAX:
        return (f"[{format_number(v_tcp, 3)},{format_number(floor_places(min(v_ori, PREDEFINED_V_ORI), 3), 3)},"
                f"{format_number(floor_places(min(v_leax, PREDEFINED_V_LEAX), 3), 3)},1000]")
    if v_tcp in SPEEDS:
        return f"v{v_tcp:g}"
    return f"v1000\\V:={format_number(v_tcp, 3)}"


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
    decls, body, names, taken = [], [], {}, set()  # taken: the point names given so far
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
    used = program.cartesian_targets()
    quaternion = dict(zip(used.index.tolist(), matrix_to_quat(used.T[:, :3, :3])))  # every target's at once
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
                names[index] = _point_name(target, taken, len(names) + 1)
                taken.add(names[index])
                if target.is_joint:
                    decls.append(f"  CONST jointtarget {names[index]} := [[{_numbers(np.degrees(target.joints), 9)}],[{_extax(target, axes)}]];")
                else:
                    if len(target.config) != 4:
                        raise WriteError(f"target {where(target)}: RAPID needs its confdata; convert with a robot")
                    decls.append(
                        f"  CONST robtarget {names[index]} := [[{_numbers(target.pose[:3, 3], 6)}],"
                        f"[{_numbers(quaternion[index], 10)}],"
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
