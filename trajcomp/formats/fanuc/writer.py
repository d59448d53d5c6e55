"""The FANUC LS writer: the edited positions and CONFIG into the .LS as read, or a program generated from another
language (see `trajcomp.formats.fanuc`)."""

import math
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import WriteError

from trajcomp.formats.fanuc.reader import _CONFIG_VALUE, ABC_ORDER, JOINTS, MIN_PLACES, XYZWPR
from trajcomp.formats.fanuc.speeds import time_field
from trajcomp.formats.text import (
    TARGETS_AT_ONCE,
    Edits,
    active_axes,
    column_decimals,
    companion_outputs,
    encode_targets,
    encode_text,
    encode_xyzabc,
    format_number,
    numbered,
    turned_abc,
    where,
    write_single_file,
    written_numbers,
    written_speed,
)
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR, SpanColumns
from trajcomp.programs.tables import TargetRows
from trajcomp.arm.transforms import matrix_to_pose


def _config_text(config):
    return f"{config[0]} {config[1]} {config[2]}, {config[3]}, {config[4]}, {config[5]}"


def _encode(targets, olds):
    return encode_targets(targets, olds, lambda target: dict(zip(JOINTS, np.degrees(target.joints))), _cartesian)


def _cartesian(targets, olds):
    out = encode_xyzabc(np.array([target.pose for target in targets]), olds, ABC_ORDER)
    for target, old, numbers in zip(targets, olds, out):
        if target.config and "config" in old:
            v = _CONFIG_VALUE.match(old["config"])
            was = (v.group(1).upper(), v.group(2).upper(), v.group(3).upper(), *map(int, v.groups()[3:]))
            if tuple(target.config) != was:
                numbers["config"] = _config_text(target.config)
    return out


def write(program, path):
    """``{path: bytes}``: patched in place if read from .LS, else a generated program.

    The positions of a program read as a table (`trajcomp.programs.tables.TargetRows`, spans as
    `SpanColumns`) are written from its columns (`_table_edits`), as `trajcomp.formats.text.target_edits`
    writes targets one by one.
    """
    targets = program.targets
    if (program.format == "fanuc_ls" and program.sources and isinstance(targets, TargetRows)
            and isinstance(targets.table.spans, SpanColumns) and targets.table.spans.source == 0):
        edits = _table_edits(targets.table, len(program.sources))
        texts = [e.applied(source.text) for source, e in zip(program.sources, edits)]
        return {Path(path): encode_text(program.sources[0], texts[0])} | companion_outputs(program, texts, path)
    return write_single_file(program, path, "fanuc_ls", _encode, MIN_PLACES, _emit)


def _table_edits(table, sources_count):
    """`Edits` per source writing the edited positions of a `TargetTable` (spans in source 0), `TARGETS_AT_ONCE`
    at a time: the numbers `_encode` gives, formatted together (`written_numbers`), no object per position.

    Raises
    ------
    WriteError
        A number to write that is not finite (the position named).
    """
    edited = np.flatnonzero(table.edited)
    parts = [_edits_of_rows(table, edited[lo:lo + TARGETS_AT_ONCE]) for lo in range(0, len(edited), TARGETS_AT_ONCE)]
    return [Edits.joined(parts)] + [Edits.of([]) for _ in range(sources_count - 1)]


def _edits_of_rows(table, rows):
    """The `Edits` of the edited positions ``rows`` (R,) of a table (`_table_edits`)."""
    spans, text = table.spans, table.spans.text
    roles = [role for role in XYZWPR + JOINTS if role in spans.column]
    start = np.stack([spans.start[rows, spans.column[role]] for role in roles], axis=1)  # (R, roles)
    end = np.stack([spans.end[rows, spans.column[role]] for role in roles], axis=1)
    old = [[text[a:b] for a, b in zip(s, e)] for s, e in zip(start.tolist(), end.tolist())]
    old_values = np.array([[_number(t) for t in row] for row in old], dtype=float).reshape(len(rows), len(roles))
    values = np.full((len(rows), len(roles)), np.nan)
    written = np.zeros((len(rows), len(roles)), dtype=bool)
    joint = table.is_joint[rows]
    role_at = {role: j for j, role in enumerate(roles)}
    if joint.any():
        at = [role_at[j] for j in JOINTS]
        values[np.ix_(joint, at)] = np.degrees(table.joints[rows[joint]])
        written[np.ix_(joint, at)] = True
    cartesian = ~joint
    if cartesian.any():
        poses = table.pose[rows[cartesian]]
        xyz, abc = [role_at[c] for c in ABC_ORDER[:3]], [role_at[c] for c in ABC_ORDER[3:]]
        values[np.ix_(cartesian, xyz)] = poses[:, :3, 3]
        written[np.ix_(cartesian, xyz)] = True
        turned, angles = turned_abc(poses[:, :3, :3], old_values[np.ix_(cartesian, abc)])
        turned_rows = np.flatnonzero(cartesian)[turned]
        values[np.ix_(turned_rows, abc)] = angles
        written[np.ix_(turned_rows, abc)] = True
    written &= start >= 0
    row, column = np.nonzero(written)
    bad = ~np.isfinite(values[row, column])
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise WriteError(f"target {where(table.target(int(rows[row[k]])))}: {roles[column[k]]} is not a finite "
                         "number, nothing written")
    old_texts = [old[r][c] for r, c in zip(row.tolist(), column.tolist())]
    places = np.maximum(column_decimals(old_texts), np.array([MIN_PLACES.get(roles[c], 0) for c in range(len(roles))],
                                                              dtype=int)[column])
    changed, texts = written_numbers(values[row, column], old_texts, old_values[row, column], places)
    edits = [(a, b, t) for a, b, t, o, change in zip(start[row, column].tolist(), end[row, column].tolist(), texts,
                                                     old_texts, changed.tolist()) if change and t != o]
    return Edits.of(edits + _config_edits(table, rows))


def _number(text):
    """The number a span's text states (NaN where it is none)."""
    try:
        return float(text)
    except ValueError:
        return math.nan


def _config_edits(table, rows):
    """``(start, end, text)`` edits of the CONFIG strings of positions ``rows`` whose configuration changed."""
    spans = table.spans
    if "config" not in spans.column:
        return []
    column, read = spans.column["config"], {}
    edits = []
    for i, a, b in zip(rows.tolist(), spans.start[rows, column].tolist(), spans.end[rows, column].tolist()):
        config = table.config[i]
        if not config or a < 0:
            continue
        old = spans.text[a:b]
        if old not in read:
            v = _CONFIG_VALUE.match(old)
            read[old] = (v.group(1).upper(), v.group(2).upper(), v.group(3).upper(), *map(int, v.groups()[3:]))
        if tuple(config) != read[old]:
            edits.append((a, b, _config_text(config)))
    return edits


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
