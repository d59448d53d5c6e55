"""The KRL writer: the edited points into the .src and .dat as read, or a program generated from another language (see `trajcomp.formats.krl`)."""

import functools
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import WriteError
from trajcomp.formats.krl.grammar import AXES, DEF, DEFDAT, MIN_PLACES, NAME, POSE, PROGRAM_NAME
from trajcomp.formats.krl.reader import read
from trajcomp.formats.text import mask
from trajcomp.formats.file_writing import active_axes, companion_outputs, numbered, written_speed
from trajcomp.formats.number_writing import floor_places, format_number
from trajcomp.formats.pose_encoding import encode_targets, encode_xyzabc, turned_abc
from trajcomp.formats.text_edits import patched
from trajcomp.programs.items import CIRCULAR, JOINT, LINEAR
from trajcomp.arm.transforms import matrix_to_pose

__all__ = ["read", "write"]


@functools.lru_cache(maxsize=1024)  # a path's points mostly share their S and T, and how the file writes them
def _status_text(value, old):
    if isinstance(old, str) and old.startswith("'B"):
        return f"'B{value:0{len(old) - 3}b}'"
    return str(value)


def _encode(targets, olds):
    return encode_targets(targets, olds, lambda target: dict(zip(AXES, np.degrees(target.joints))), _cartesian)


def _cartesian(targets, olds):
    out = encode_xyzabc(np.array([target.pose for target in targets]), olds, POSE)
    for target, old, numbers in zip(targets, olds, out):
        if target.config:
            numbers["s"] = _status_text(target.config[0], old.get("s"))
            numbers["t"] = _status_text(target.config[1], old.get("t"))
    return out


def _encode_columns(table, rows, old):
    """The numbers of a `TargetTable`'s rows (K,) in KRL, as columns (`trajcomp.formats.text_edits.target_edits`)."""
    joint = table.is_joint[rows]
    pose = table.pose[rows]
    out = dict(zip(AXES, np.where(joint[:, None], np.degrees(table.joints[rows]), np.nan).T))
    out |= dict(zip(POSE[:3], np.where(joint[:, None], np.nan, pose[:, :3, 3]).T))
    cartesian = np.flatnonzero(~joint)
    old_abc = np.stack([old.value[role] for role in POSE[3:]], axis=1)[cartesian]
    turned, abc = turned_abc(pose[cartesian, :3, :3], old_abc)
    angles = np.full((len(rows), 3), np.nan)
    angles[cartesian[turned]] = abc
    out |= dict(zip(POSE[3:], angles.T))
    for k, role in enumerate(("s", "t")):
        out[role] = np.array([_status_text(config[k], was) if config else None for config, was in
                              zip((table.config[i] for i in rows.tolist()), old.text[role])], dtype=object)
    return out


def write(program, path):
    """``{path.src: bytes, path.dat: bytes}``: patched in place if read from KRL, else generated.

    The DEF and DEFDAT names become the output file's name when it differs
    (KUKA loads a program only under its own name); a program written under
    the name it was read from keeps them as they were, valid KRL or not.

    Raises
    ------
    WriteError
        A new name that is not a valid KRL name.
    """
    path = Path(path)
    patch = program.format == "krl" and program.sources
    same_name = patch and path.stem.lower() == Path(program.sources[0].name).stem.lower()
    if not same_name and not PROGRAM_NAME.match(path.stem):
        raise WriteError(
            f"{path}: {path.stem!r} cannot name a KRL program (letters, digits and _, "
            "not starting with a digit, at most 24 characters): KUKA needs DEF name = file name"
        )
    dat = path.with_suffix(".dat" if path.suffix.islower() else ".DAT")
    if patch:
        own = 2 if len(program.sources) > 1 and not program.sources[1].companion else 1  # the .src and its .dat
        renames = [[] if same_name else _renamed(source.text, pattern, path.stem)
                   for source, pattern in zip(program.sources[:own], (DEF, DEFDAT))]
        written = patched(program, _encode, MIN_PLACES, _encode_columns, renames + [[]] * (len(program.sources) - own))
        return dict(zip([path, dat][:own], written)) | companion_outputs(program, written, path, own)
    src_text, dat_text = _emit(program, path.stem)
    return {path: src_text.encode("latin-1"), dat: dat_text.encode("latin-1")}


def _renamed(text, pattern, name):
    """The edit ``[(start, end, name)]`` that gives the first DEF (or DEFDAT) of ``text`` the name ``name`` if it
    has another (KRL ignores case), else ``[]``.

    Searched in the masked text's first 64 KB, then in longer beginnings
    (masking a beginning masks it as the whole text does): the DEF line
    opens the file, and a long data list is never masked whole.
    """
    size = 65536
    while (m := pattern.search(mask(text[:size], ";"))) is None or m.end() >= size:  # a name cut at the end: longer
        if size >= len(text):
            break
        size *= 4
    if m is None or m.group(1).lower() == name.lower():
        return []
    return [(m.start(1), m.end(1), name)]


def _aggregate(target, axes):
    """Type and members of a point declaration; its external ``axes`` (indices) as E1..E6."""
    values = target.external if target.external is not None else []
    external = [f"E{k + 1} {format_number(values[k], 6)}" for k in axes if k < len(values) and not np.isnan(values[k])]
    if target.is_joint:
        axes = [f"A{k + 1} {format_number(v, 9)}" for k, v in enumerate(np.degrees(target.joints))]
        return "E6AXIS", ",".join(axes + external)
    pose = matrix_to_pose(target.pose)
    fields = [f"{p.upper()} {format_number(v, 6)}" for p, v in zip(POSE[:3], pose[:3])]
    fields += [f"{p.upper()} {format_number(v, 9)}" for p, v in zip(POSE[3:], np.degrees(pose[3:]))]
    if target.config:
        fields += [f"S {target.config[0]}", f"T {target.config[1]}"]
    return ("E6POS" if target.config or external else "POS"), ",".join(fields + external)


def _emit(program, name):
    """New .src and .dat texts (CRLF, as KUKA's editors write them)."""
    tools = numbered([m.tool for m in program.motions])
    bases = numbered([m.frame for m in program.motions])
    axes = active_axes(program, 6, "KRL")
    names, decls = {}, []
    src = [f"DEF {name}( )"]
    tool = base = zone = None
    speeds = {}  # the value each modal speed statement was last given: BAS(#VEL_PTP) %, $VEL.CP mm/s
    for motion in program.motions:
        if motion.target is None:
            src.append(f"  ; not converted: {motion.text}")
            continue
        if motion.tool != tool:
            tool = motion.tool
            src.append(f"  $TOOL={_selected(tool, program.tools, tools, 'TOOL_DATA')}")
        if motion.frame != base:
            base = motion.frame
            src.append(f"  $BASE={_selected(base, program.frames, bases, 'BASE_DATA')}")
        value, _ = written_speed(motion, "krl")
        if motion.kind == JOINT:  # a PTP runs at BAS(#VEL_PTP): stated for every one (the arm's limits: 100 %)
            statement = f"BAS(#VEL_PTP,{format_number(floor_places(100.0 if value is None else value, 3), 3)})"
        else:  # $VEL.CP, m/s; none stated: the arm's limits, any speed in force is no faster
            statement = None if value is None else f"$VEL.CP={format_number(floor_places(value / 1000.0, 6), 6)}"
        if statement is not None and speeds.get(motion.kind == JOINT) != statement:
            speeds[motion.kind == JOINT] = statement
            src.append(f"  {statement}")
        if motion.zone is not None and motion.zone != zone:
            zone = motion.zone
            src.append(f"  $APO.CDIS={format_number(zone, 3)}")
        refs = []
        for index in (motion.via, motion.target):
            if index is None:
                continue
            if index not in names:
                names[index] = _point_name(program.targets[index], names.values(), len(names) + 1)
                typ, body = _aggregate(program.targets[index], axes)
                decls.append(f"DECL {typ} {names[index]}={{{body}}}")
            refs.append(names[index])
        keyword = {JOINT: "PTP", LINEAR: "LIN", CIRCULAR: "CIRC"}[motion.kind]
        approx = " C_DIS" if motion.zone is not None else ""
        src.append(f"  {keyword} {', '.join(refs)}{approx}")
    src.append("END")
    dat = [f"DEFDAT {name}"] + decls + ["ENDDAT"]
    return "\r\n".join(src) + "\r\n", "\r\n".join(dat) + "\r\n"


def _selected(key, values, numbers, data):
    """What ``$TOOL`` / ``$BASE`` is set to: the known value inline (the controller's TOOL_DATA / BASE_DATA
    tables are never written), else the table entry of its number, ``$NULLFRAME`` for none."""
    if key is None:
        return "$NULLFRAME"
    if key in values:
        pose = matrix_to_pose(values[key])
        numbers_text = [format_number(v, 6) for v in pose[:3]] + [format_number(v, 9) for v in np.degrees(pose[3:])]
        return "{" + ",".join(f"{p.upper()} {v}" for p, v in zip(POSE, numbers_text)) + "}"
    return f"{data}[{numbers[key]}]"


def _point_name(target, taken, number):
    name = re.sub(r"\W", "_", target.name)[:24]
    if not name or not NAME.match(name) or name.upper() in {t.upper() for t in taken}:
        name = f"XP{number}"
    return name
