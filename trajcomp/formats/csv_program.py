"""Program CSV (conventions.md): one target per row, TCP poses in the robot base frame.

Columns ``x,y,z,a,b,c`` (mm, deg; A, B, C intrinsic Z-Y'-X''), optional
``motion`` (PTP | LIN), ``speed`` (mm/s), ``zone`` (mm), ``j1..j6`` (deg)
and ``t`` (s, written by re-timing). A row with empty pose fields and
joints is a joint target. ``#`` lines are comments. Any other column (an
id, a comment) is kept as it is, except a name close to a known one (``xx``,
``speeed``: a typo would silently drop data) and a column given twice.
A pose or joint group given in part, and a file without target rows, are
refused too.

Writing a program read from CSV keeps every column, row and byte; the
edited rows get their new pose and, where the program knows their joints,
``j1..j6`` (added as columns when the file has none).
"""

import dataclasses
import difflib
import math
import re

import numpy as np

from trajcomp.formats._text import (
    ANGLE_LIMIT,
    JOINT_LIMIT,
    LENGTH_LIMIT,
    Lines,
    active_axes,
    apply_edits,
    encode_text,
    encode_xyzabc,
    fail,
    finite,
    format_number,
    read_source,
    target_edits,
)
from trajcomp.program import JOINT, LINEAR, Motion, Program, Span, Statement, Target
from trajcomp.transforms import matrix_to_pose, pose_to_matrix

POSE = ("x", "y", "z", "a", "b", "c")
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
MIN_PLACES = dict.fromkeys(POSE[:3], 3) | dict.fromkeys(POSE[3:], 4) | dict.fromkeys(JOINTS, 4)
KINDS = {"PTP": JOINT, "LIN": LINEAR}
KNOWN = POSE + JOINTS + ("motion", "speed", "zone", "t")
_FIELD = re.compile(r'(?:^|,)[ \t]*("(?:[^"]|"")*"|[^,]*)')


def _fields(text, start):
    """``[(value, start, end)]`` of a CSV line at offset ``start``."""
    out = []
    for m in _FIELD.finditer(text):
        value = m.group(1).rstrip()
        s = m.start(1)
        e = s + len(value)
        if value.startswith('"'):
            value = value[1:-1].replace('""', '"')
        out.append((value.strip(), start + s, start + e))
    return out


def read(path):
    """Read a program CSV. Raises ReadError with file:line, field and text."""
    source = read_source(path)
    lines = Lines(source.text)
    header, items, targets = None, [], []
    for number, start, end in lines:
        line = source.text[start:end]
        if not line.strip() or line.lstrip().startswith("#"):
            items.append(Statement(number, line))
            continue
        fields = _fields(line, start)
        if header is None:
            header = _header([f[0].lower() for f in fields], source.name, number, line)
            has_pose, has_joints = POSE[0] in header, JOINTS[0] in header
            items.append(Statement(number, line))
            continue
        if len(fields) != len(header):
            fail(source.name, number, line, f"expected {len(header)} fields, got {len(fields)}")
        row = dict(zip(header, fields))
        motion, target = _row(source.name, number, line, row, has_pose, has_joints, len(targets))
        targets.append(target)
        items.append(dataclasses.replace(motion, spans=_timing_spans(row, end)))
    targets = _with_poses(targets)
    if header is None:
        fail(source.name, 1, source.text[:80], "not a program CSV: no header row")
    if not targets:
        fail(source.name, lines.number(len(source.text)), source.text[-80:], "no target rows after the header")
    return Program("csv", source.name.rsplit(".", 1)[0], tuple(items), targets, sources=(source,))


def _header(names, source_name, number, line):
    """The column names, checked: a whole pose or joint group, no column twice, no near-miss of a known name."""
    groups = [group for group in (POSE, JOINTS) if any(c in names for c in group)]
    if not groups:
        fail(source_name, number, line, "not a program CSV: the header needs x,y,z,a,b,c or j1..j6")
    twice = sorted({c for c in names if names.count(c) > 1})
    if twice:
        fail(source_name, number, line, f"column {', '.join(twice)} given twice")
    for group in groups:
        missing = [c for c in group if c not in names]
        if missing:
            fail(source_name, number, line, f"column {', '.join(missing)} missing: {','.join(group)} go together")
    for name in names:
        close = difflib.get_close_matches(name, KNOWN, n=1, cutoff=0.6) if name not in KNOWN else []
        if close:
            fail(source_name, number, line, f"unknown column {name!r}: did you mean {close[0]!r}?")
    return names


def _number(name, number, line, field, column):
    limit = LENGTH_LIMIT if column in POSE[:3] else ANGLE_LIMIT if column in POSE else (
        JOINT_LIMIT if column in JOINTS else math.inf)
    return finite(field[0], name, number, line, f"field {column}", limit)


def _row(name, number, line, row, has_pose, has_joints, index):
    def numbers(columns):
        return np.array([_number(name, number, line, row[c], c) for c in columns])

    def spans(columns):
        return {c: Span(0, row[c][1], row[c][2], row[c][0]) for c in columns}

    pose_given = has_pose and any(row[c][0] for c in POSE)
    joints_given = has_joints and any(row[c][0] for c in JOINTS)
    if not (pose_given or joints_given):
        fail(name, number, line, "a row needs x,y,z,a,b,c or j1..j6")
    pose = joints = None
    found = {}
    if pose_given:
        pose = numbers(POSE)  # x, y, z, a, b, c (mm, deg): matrices for all rows at once in _with_poses
        found |= spans(POSE)
    if joints_given:
        joints = np.radians(numbers(JOINTS))
        found |= spans(JOINTS)
    kind_text = row.get("motion", ("", 0, 0))[0].upper()
    if kind_text and kind_text not in KINDS:
        fail(name, number, line, f"field motion: expected PTP or LIN, got {kind_text!r}")
    speed = _number(name, number, line, row["speed"], "speed") if row.get("speed", ("",))[0] else None
    zone = _number(name, number, line, row["zone"], "zone") if row.get("zone", ("",))[0] else None
    target = Target(name="", line=number, pose=pose, joints=joints, spans=found)
    motion = Motion(
        kind=KINDS.get(kind_text, LINEAR),
        target=index,
        speed=speed,
        zone=zone or None,
        line=number,
        text=line.strip(),
    )
    return motion, target


def _timing_spans(row, end):
    """Where re-timing writes: the ``t`` cell (if the file has the column) and the row's end."""
    spans = {"end": Span(0, end, end, "")}
    if "t" in row:
        spans["t"] = Span(0, row["t"][1], row["t"][2], row["t"][0])
    return spans


def _with_poses(targets):
    """The targets (tuple) with their pose rows x, y, z, a, b, c (mm, deg) turned into matrices in one call."""
    rows = [k for k, t in enumerate(targets) if t.pose is not None]
    out = list(targets)
    if rows:
        vectors = np.array([targets[k].pose for k in rows])
        vectors[:, 3:] = np.radians(vectors[:, 3:])
        for k, matrix in zip(rows, pose_to_matrix(vectors)):
            out[k] = Target(name="", line=targets[k].line, pose=matrix, joints=targets[k].joints,
                            spans=targets[k].spans)
    return tuple(out)


def _encode(target, old):
    out = {}
    if target.pose is not None:
        out |= encode_xyzabc(target.pose, old, POSE)
    if target.joints is not None:
        out |= dict(zip(JOINTS, np.degrees(target.joints)))
    return out


def write(program, path):
    """The CSV text of a program: patched in place if read from CSV, else generated."""
    if program.format == "csv" and program.sources:
        source = program.sources[0]
        edits = target_edits(program, _encode, MIN_PLACES)[0] + _added_joints(program, source)
        return {path: encode_text(source, apply_edits(source.text, edits))}
    return {path: _emit(program).encode("utf-8")}


def _added_joints(program, source):
    """Edits appending j1..j6 to the header and rows when the file has no joint columns."""
    lines = Lines(source.text)
    header = next(((n, s, e) for n, s, e in lines if source.text[s:e].strip()
                   and not source.text[s:e].lstrip().startswith("#")), None)
    names = [f[0].lower() for f in _fields(source.text[header[1]:header[2]], header[1])]
    if any(c in names for c in JOINTS) or not any(t.edited and t.joints is not None for t in program.targets):
        return []
    edits = [(header[2], header[2], "," + ",".join(JOINTS))]
    for target in program.targets:
        end = lines.starts[target.line - 1] + len(lines.line(target.line))
        cells = [""] * 6 if target.joints is None else [format_number(v, 4) for v in np.degrees(target.joints)]
        edits.append((end, end, "," + ",".join(cells)))
    return edits


def _emit(program):
    """A new program CSV; poses must already be in the base frame (see postprocess.convert)."""
    active_axes(program, 0, "program CSV")
    targets = program.targets
    used = [i for m in program.motions if m.target is not None for i in (m.via, m.target) if i is not None]
    with_joints = all(targets[i].joints is not None for i in used)
    columns = list(POSE) + ["motion", "speed", "zone"] + (list(JOINTS) if with_joints else [])
    rows = [",".join(columns)]
    for motion in program.motions:
        if motion.target is None:
            rows.append(f"# not converted: {motion.text}")
            continue
        if motion.via is not None:
            rows.append(_row_text(targets[motion.via], motion, LINEAR, with_joints))
        rows.append(_row_text(targets[motion.target], motion, motion.kind, with_joints))
    return "\n".join(rows) + "\n"


def _row_text(target, motion, kind, with_joints):
    if target.pose is None:
        cells = [""] * 6
    else:
        pose = matrix_to_pose(target.pose)
        cells = [format_number(v, 6) for v in pose[:3]] + [format_number(v, 9) for v in np.degrees(pose[3:])]
    speed = format_number(motion.speed, 3) if motion.speed is not None and motion.speed_unit == "mm/s" else ""
    zone = format_number(motion.zone, 3) if motion.zone is not None else ""
    cells += ["PTP" if kind == JOINT else "LIN", speed, zone]
    if with_joints:
        cells += [format_number(v, 9) for v in np.degrees(target.joints)]
    return ",".join(cells)
