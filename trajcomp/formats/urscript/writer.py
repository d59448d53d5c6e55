"""The URScript writer: the edited poses into the script as read, or a script generated from another language (see `trajcomp.formats.urscript`)."""

import re

import numpy as np

from trajcomp.errors import WriteError
from trajcomp.formats.file_writing import active_axes, write_single_file, written_speed
from trajcomp.formats.number_writing import ceil_places, floor_places, format_number
from trajcomp.formats.pose_encoding import encode_targets, same_rotation
from trajcomp.formats.urscript.grammar import JOINTS, NEAR, POSE
from trajcomp.formats.urscript.reader import read
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR
from trajcomp.arm.transforms import matrix_to_rotvec, rotvec_to_matrix

__all__ = ["read", "write"]

MIN_PLACES = dict.fromkeys(POSE + JOINTS + NEAR, 6)  # 1e-6 m = 0.001 mm; 1e-6 rad


def _rotvec_near(rot, old):
    """Rotation vectors (N, 3) of ``rot`` (N, 3, 3), each the closest to ``old`` (N, 3) among its equivalents
    (angle +- 2 pi)."""
    vec = matrix_to_rotvec(rot)
    angle = np.linalg.norm(vec, axis=1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):  # no rotation: no other equivalent
        other = vec * (1.0 - 2.0 * np.pi / angle)
    closer = np.linalg.norm(other - old, axis=1) < np.linalg.norm(vec - old, axis=1)
    return np.where(closer[:, None] & (angle >= 1e-12), other, vec)


def _encode(targets, olds):
    return encode_targets(targets, olds, lambda target: dict(zip(JOINTS, target.joints)), _cartesian)


def _cartesian(targets, olds):
    """Position (m), the rotation vector where the rotation differs from the file's, and qnear of each target."""
    poses = np.array([target.pose for target in targets])
    old_vec = np.array([[old[r] for r in POSE[3:]] for old in olds], dtype=float)
    turned = ~same_rotation(poses[:, :3, :3], rotvec_to_matrix(old_vec))
    vectors = iter(_rotvec_near(poses[turned, :3, :3], old_vec[turned]).tolist())
    out = []
    for target, position, turn in zip(targets, (poses[:, :3, 3] / 1000.0).tolist(), turned.tolist()):
        numbers = dict(zip(POSE[:3], position)) | (dict(zip(POSE[3:], next(vectors))) if turn else {})
        if target.joints is not None:
            numbers |= dict(zip(NEAR, target.joints))
        out.append(numbers)
    return out


def _encode_columns(table, rows, old):
    """The numbers of a `TargetTable`'s rows (K,) in URScript, as columns (`trajcomp.formats.text_edits.target_edits`):
    what `_encode` gives each, NaN where it gives none."""
    joint = table.is_joint[rows]
    pose, joints = table.pose[rows], table.joints[rows]
    out = dict(zip(JOINTS, np.where(joint[:, None], joints, np.nan).T))
    out |= dict(zip(POSE[:3], np.where(joint[:, None], np.nan, pose[:, :3, 3] / 1000.0).T))
    cartesian = np.flatnonzero(~joint)
    old_vec = np.stack([old.value[role] for role in POSE[3:]], axis=1)[cartesian]
    turned = ~same_rotation(pose[cartesian, :3, :3], rotvec_to_matrix(old_vec))
    vectors = np.full((len(rows), 3), np.nan)
    vectors[cartesian[turned]] = _rotvec_near(pose[cartesian[turned], :3, :3], old_vec[turned])
    out |= dict(zip(POSE[3:], vectors.T))
    return out | dict(zip(NEAR, np.where(joint[:, None], np.nan, joints).T))


def write(program, path):
    """``{path: bytes}``: patched in place if read from URScript, else a generated script."""
    return write_single_file(program, path, "urscript", _encode, MIN_PLACES, _emit, _encode_columns)


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
        value, unit = written_speed(motion, "urscript")  # none: UR's default speed, no faster than the arm's limits
        if unit == "s" and value is not None:
            options.append(f"t={format_number(ceil_places(value, 4), 4)}")
        elif value is not None:  # movej: the leading axis, rad/s; else the TCP, m/s
            options.append(f"v={format_number(floor_places(value / (1.0 if unit == 'rad/s' else 1000.0), 6), 6)}")
        if motion.zone is not None:
            options.append(f"r={format_number(motion.zone / 1000.0, 6)}")
        lines.append(f"  {function_name}({', '.join(positions + options)})")
    lines += ["end", f"{function}()"]
    return "\n".join(lines) + "\n"
