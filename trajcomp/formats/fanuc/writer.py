"""The FANUC LS writer: the edited positions and CONFIG into the .LS as read, or a program generated from another
language (see `trajcomp.formats.fanuc`)."""

import functools
import math
import re

import numpy as np

from trajcomp.errors import WriteError

from trajcomp.formats.fanuc.grammar import JOINTS, config as _config
from trajcomp.formats.fanuc.reader import ABC_ORDER, MIN_PLACES
from trajcomp.formats.fanuc.speeds import time_field
from trajcomp.formats.file_writing import active_axes, numbered, write_single_file, written_speed
from trajcomp.formats.number_writing import format_number
from trajcomp.formats.pose_encoding import encode_targets, encode_xyzabc, turned_abc
from trajcomp.formats.text_edits import where
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR
from trajcomp.arm.transforms import matrix_to_pose


def _config_text(config):
    return f"{config[0]} {config[1]} {config[2]}, {config[3]}, {config[4]}, {config[5]}"


def _encode(targets, olds):
    return encode_targets(targets, olds, lambda target: dict(zip(JOINTS, np.degrees(target.joints))), _cartesian)


def _cartesian(targets, olds):
    out = encode_xyzabc(np.array([target.pose for target in targets]), olds, ABC_ORDER)
    for target, old, numbers in zip(targets, olds, out):
        if target.config and "config" in old and (text := _config_change(tuple(target.config), old["config"])):
            numbers["config"] = text
    return out


def _encode_columns(table, rows, old):
    """The numbers of a `TargetTable`'s rows (K,) in FANUC LS, as columns (`trajcomp.formats.text_edits.target_edits`):
    what `_encode` gives each, a number that is not finite as ``inf`` (refused)."""
    joint = table.is_joint[rows]
    pose = table.pose[rows]

    def refused(values, rows_of):  # NaN means "left as written" to target_edits: a NaN to write is refused
        return np.where(rows_of[:, None] & ~np.isfinite(values), np.inf, values)

    out = dict(zip(JOINTS, refused(np.where(joint[:, None], np.degrees(table.joints[rows]), np.nan), joint).T))
    out |= dict(zip(ABC_ORDER[:3], refused(np.where(joint[:, None], np.nan, pose[:, :3, 3]), ~joint).T))
    cartesian = np.flatnonzero(~joint)
    old_abc = np.stack([old.value[role] for role in ABC_ORDER[3:]], axis=1)[cartesian]
    turned, abc = turned_abc(pose[cartesian, :3, :3], old_abc)
    angles = np.full((len(rows), 3), np.nan)
    angles[cartesian[turned]] = abc
    out |= dict(zip(ABC_ORDER[3:], refused(angles, np.isin(np.arange(len(rows)), cartesian[turned])).T))
    if "config" in old.text:
        out["config"] = _config_changes(table.config, rows, old.text["config"], joint)
    return out


def _config_changes(configs, rows, olds, joint):
    """The CONFIG texts (object array (K,)) to write for the rows (K,) of a table's ``configs``, over the file's
    ``olds`` (K,): None where the row states none, is a joint position, or states the file's (`_config_change`).

    A path's positions share a few configurations: each distinct text is
    read once and the rows compared at once.
    """
    wanted = np.empty(len(rows), dtype=object)
    wanted[:] = [configs[i] for i in rows.tolist()]
    read = {text: _config(text) for text in set(olds.tolist()) - {None}}  # the file's, each distinct once
    stated = np.empty(len(rows), dtype=object)
    stated[:] = [read.get(text) if text is not None else None for text in olds.tolist()]
    out = np.full(len(rows), None, dtype=object)
    for k in np.flatnonzero(~joint & np.not_equal(olds, None) & (wanted != stated)).tolist():
        if wanted[k] and tuple(wanted[k]) != stated[k]:
            out[k] = _config_text(wanted[k])
    return out


@functools.lru_cache(maxsize=1024)  # a path's positions mostly share their configuration and how it is written
def _config_change(config, old):
    """The CONFIG text to write for ``config`` over the file's ``old`` one; None where they state the same."""
    return None if tuple(config) == _config(old) else _config_text(config)


def write(program, path):
    """``{path: bytes}``: patched in place if read from .LS, else a generated program."""
    return write_single_file(program, path, "fanuc_ls", _encode, MIN_PLACES, _emit, _encode_columns)


ATTR = """/ATTR
OWNER\t\t= MNEDITOR;
COMMENT\t\t= "trajcomp";
PROG_SIZE\t= 0;
CREATE\t\t= DATE 00-01-01  TIME 00:00:00;
MODIFIED\t= DATE 00-01-01  TIME 00:00:00;
FILE_NAME\t= ;
VERSION\t\t= 0;
LINE_COUNT\t= {count};
MEMORY_SIZE\t= 0;
PROTECT\t\t= READ_WRITE;
TCD:  STACK_SIZE\t= 0,
      TASK_PRIORITY\t= 50,
      TIME_SLICE\t= 0,
      BUSY_LAMP_OFF\t= 0,
      ABORT_REQUEST\t= 0,
      PAUSE_REQUEST\t= 0;
DEFAULT_GROUP\t= 1,*,*,*,*;
CONTROL_CODE\t= 00000000 00000000;"""


WRITTEN_UNITS = {"%": "%", "mm/s": "mm/sec", "rad/s": "deg/sec"}  # a generated program's speed units


def _speed(motion):
    """The speed of a generated motion: ``p%``, ``v mm/sec``, ``w deg/sec`` (whole numbers, rounded down), a time
    (`time_field`, rounded up) or ``max_speed`` / ``100%`` (the arm's limits)."""
    value, unit = written_speed(motion, "fanuc_ls")
    if value is None:
        return "100%" if motion.kind == JOINT else "max_speed"
    if unit == "s":
        return time_field(value)
    whole = max(math.floor((np.degrees(value) if unit == "rad/s" else value) + 1e-9), 1)
    return f"{whole}{WRITTEN_UNITS[unit]}"


def _emit(program, name):
    """A new .LS program; Cartesian targets need their CONFIG (see postprocess.convert)."""
    used = program.usage()
    tools = numbered([used[i][0] for i in sorted(used)])
    frames = numbered([used[i][1] for i in sorted(used)])
    axes = active_axes(program, 3, "FANUC .LS (group 1)")
    mn, pos, numbers = [], [], {}
    for table, numbering, label in ((program.tools, tools, "UTOOL"), (program.frames, frames, "UFRAME")):
        for key, number in numbering.items():
            if key is not None and number and key in table:
                x, y, z, a, b, c = matrix_to_pose(table[key])
                values = [x, y, z, *np.degrees([c, b, a])]
                mn.append(f"  ! {label} {number} = " + ",".join(format_number(v, 3) for v in values) + " ;")
    for motion in program.motions:
        if motion.target is None:
            mn.append(f"  ! not converted: {motion.text[:60]} ;")
            continue
        refs = []
        for index in (motion.via, motion.target):
            if index is None:
                continue
            if index not in numbers:
                numbers[index] = len(numbers) + 1
                tool, frame = used[index]
                pos.append(_position(program.targets[index], numbers[index], tools[tool], frames[frame], axes))
            refs.append(f"P[{numbers[index]}]")
        zone = "FINE" if motion.zone is None else f"CNT{int(round(min(motion.zone, 100)))}"
        keyword = {JOINT: "J", LINEAR: "L", CIRCULAR: "C"}[motion.kind]
        if motion.kind == CIRCULAR:
            mn.append(f"C {refs[0]}    \n    :  {refs[1]} {_speed(motion)} {zone}    ;")
        else:
            mn.append(f"{keyword} {refs[0]} {_speed(motion)} {zone}    ;")
    numbered_mn = [f"{k:4d}:{line}" for k, line in enumerate(mn, start=1)]
    text = [f"/PROG  {_program_name(name)}", ATTR.format(count=len(mn)), "/MN"] + numbered_mn
    return "\n".join(text + ["/POS"] + pos + ["/END"]) + "\n"


def _program_name(name):
    return (re.sub(r"[^A-Z0-9_]", "_", name.upper()) or "PROG")[:36]


def _position(target, number, tool, frame, axes):
    head = f"P[{number}]{{\n   GP1:\n\tUF : {frame}, UT : {tool},"
    if target.is_joint:
        j = [format_number(v, 6) for v in np.degrees(target.joints)]
        body = (f"\n\tJ1= {j[0]} deg,\tJ2= {j[1]} deg,\tJ3= {j[2]} deg,"
                f"\n\tJ4= {j[3]} deg,\tJ5= {j[4]} deg,\tJ6= {j[5]} deg")
        return head + body + _extended(target, axes) + "\n};"
    if len(target.config) != 6:
        raise WriteError(f"target {where(target)}: FANUC needs its CONFIG; convert with a robot")
    x, y, z, a, b, c = matrix_to_pose(target.pose)
    p = [format_number(v, 6) for v in (x, y, z)] + [format_number(v, 9) for v in np.degrees([c, b, a])]
    return (head + f"\t\tCONFIG : '{_config_text(target.config)}',"
            f"\n\tX = {p[0]}  mm,\tY = {p[1]}  mm,\tZ = {p[2]}  mm,"
            f"\n\tW = {p[3]} deg,\tP = {p[4]} deg,\tR = {p[5]} deg" + _extended(target, axes) + "\n};")


def _extended(target, axes):
    """``,\\n\\tE1= ..`` of a target's external ``axes`` (indices) as extended axes of group 1.

    Written in mm: a rotary extended axis needs its unit changed to deg.
    """
    values = [] if target.external is None else target.external
    fields = [f"E{k + 1}= {format_number(values[k], 6)}  mm" for k in axes if k < len(values) and not np.isnan(values[k])]
    return ",\n\t" + ",\t".join(fields) if fields else ""
