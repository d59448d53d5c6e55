"""FANUC position registers: ``PR[n]`` of a program resolved from the controller's POSREG.VA.

A motion ``L PR[3] 100mm/sec FINE`` goes to the value position register 3
holds when the line runs. A controller backup lists the registers in
POSREG.VA, an ASCII listing of ``$POSREG`` (``ARRAY[groups, n] OF Position
Reg``)::

    [*POSREG*]$POSREG  Storage: SHADOW  Access: RW  : ARRAY[2,255] OF Position Reg
        [1,1] =   '@Home'   Group: 1
      J1 =   -70.000 deg   J2 =   -25.000 deg   J3 =     0.000 deg
      J4 =     0.000 deg   J5 =   -90.000 deg   J6 =   -20.000 deg

        [1,3] =   'Reserved' Uninitialized
        [1,254] =   'MasterPSN'
      Group: 1   Config: N U T, 0, 0, 0
      X:  1322.445   Y:   924.767   Z:   194.152
      W:    18.349   P:     8.021   R:    91.743
      EXT1:    40.492 mm

An entry ``[g,n]`` is register n of motion group g: joint (``J1 = .. deg``)
or Cartesian (X, Y, Z mm, W, P, R deg and the CONFIG string of an .LS
position), with ``EXTk:`` extended axes; ``Uninitialized`` or ``********``
where it holds no value. A Cartesian register states no user frame or
tool: it is the position in the user frame and tool active when the line
runs (``UFRAME_NUM``, ``UTOOL_NUM``). Numbers may drop their leading zero
(``-.364``).

The registers of group 1 that the program's motions name are its targets,
declared in POSREG.VA (a companion `Source`): corrected there and written
into a POSREG.VA beside the output with the program, all or none. A
register is left as written, its motions listed, when its value is not
the file's at run time: the program or another TP program of the backup
sets it (``PR[n]=LPOS``, ``PR[n,3]=...``, ``PR[R[1]]=...`` any register),
or the file holds none.
"""

import functools
import os
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError
from trajcomp.formats.fanuc.grammar import CONFIG_VALUE, JOINTS, MOTION_REGISTER, XYZWPR, masked
from trajcomp.formats.text import ANGLE_LIMIT, JOINT_LIMIT, LENGTH_LIMIT, Lines, fail, finite, read_source
from trajcomp.formats.number_fields import NUMBER
from trajcomp.programs.items import Span, Target
from trajcomp.arm.transforms import pose_to_matrix

FILE_NAME = "posreg.va"
# An instruction that sets a register: ``PR[3]=``, ``PR[GP1:3,2:x]=``, ``PR[R[1]]=`` (any register), ``TO PR[3]``.
_SETS = re.compile(r"\bPR\[\s*(?:GP\d+\s*:\s*)?(\d+|R\[[^\]]*\])[^\]=]*\]\s*=(?!=)"
                   r"|\bTO\s+PR\[\s*(?:GP\d+\s*:\s*)?(\d+|R\[[^\]]*\])", re.I)
_HEADER = re.compile(r"^\[\*[^\]]*\*\]\s*\$(\w+)", re.M)
_ENTRY = re.compile(r"^[ \t]*\[\s*(\d+)\s*,\s*(\d+)\s*\][ \t]*=[ \t]*'[^'\r\n]*'([^\r\n]*)", re.M)
_CONFIG = re.compile(r"Config:[ \t]*([^\r\n]*?)[ \t]*\r?$", re.M)
_TP_LINE = re.compile(r"^\s*\d+:\s*|\s*;\s*$")  # a listing's line number and the instruction's end
_FIELD = re.compile(r"(?:\b([XYZWPR])\s*:|\b(J\d+)\s*=|\bEXT(\d+)\s*:)\s*(" + NUMBER + r"|\*+)")


def find(program_path, file_name=FILE_NAME):
    """A listing of a program's controller (POSREG.VA; SYSFRAME.VA ..): beside it, else in the folder above (its
    backup), or None.

    Parameters
    ----------
    program_path : Path
        The .LS program.
    file_name : str
        The listing's name, lower case (any case in the folder).
    """
    folder = Path(program_path).resolve().parent
    for place in (folder, folder.parent):
        for name in _listing(place):
            if name.lower() == file_name:
                return place / name
    return None


def _listing(folder):
    try:
        return sorted(os.listdir(folder))
    except OSError:
        return []


def used_registers(masked):
    """Register numbers the motion lines of a program's masked text name (sorted list of int)."""
    if "R[" not in masked and "r[" not in masked:  # no register at all (a CAM path): the text is not scanned
        return []
    return sorted({int(n) for n in MOTION_REGISTER.findall(masked)})


def resolve(program_path, masked, lines, targets, index):
    """The registers a program's motions name, read from its POSREG.VA: targets, and why others are not.

    Parameters
    ----------
    program_path : Path
        The program.
    masked : str
        Its text with comments and strings blanked (`trajcomp.formats.fanuc.grammar.masked`).
    lines : Lines
        Its lines.
    targets : list of Target
        The program's targets so far; the registers' targets are appended.
    index : int
        The index the POSREG.VA source gets among the program's sources.

    Returns
    -------
    source : Source or None
        POSREG.VA as a companion source; None when there is none or none of
        its registers is read (all set at run time, uninitialized ...).
    registers : dict
        ``{"n": target index}`` of the registers whose motions are compensated.
    why : dict
        ``{"n": reason}`` of the others (``" is set at run time (line 12, PR[3]=LPOS)"``), appended to
        ``position register PR[n]``.
    notes : tuple of str
        What the report must say of the registers read (`Program.notes`).

    Raises
    ------
    ReadError
        POSREG.VA malformed (file, line and field named).
    """
    used = used_registers(masked)
    path = find(program_path)
    if path is None:
        hint = f": its value is the controller's; no {FILE_NAME.upper()} beside the program (its backup's)"
        return None, {}, {str(n): hint for n in used}, ()
    sets = _sets_in_folders(program_path, path.parent, masked, lines)
    source = read_source(path, companion=True)
    entries = _entries(source.text)
    va_lines = Lines(source.text)
    registers, why = {}, {}
    for n in used:
        if None in sets or n in sets:
            where, text = sets.get(n) or sets[None]
            why[str(n)] = f" is set at run time ({where}, {text})"
            continue
        entry = entries.get((1, n))
        if entry is None:
            why[str(n)] = f": {source.name} holds no register {n} of group 1"
            continue
        target = _target(source, index, va_lines, n, entry, entries)
        if isinstance(target, str):
            why[str(n)] = target
            continue
        registers[str(n)] = len(targets)
        targets.append(target)
    read = ", ".join(f"PR[{n}]" for n in registers)
    notes = (f"position registers {read} are read from {source.name} (the values the backup saved): a compensated "
             f"run corrects them in the {source.name} written beside the output, which the controller does not read "
             "with the program: set its registers to those values (DATA > Position Reg); a KAREL program or another "
             "task that sets them at run time is beyond what trajcomp reads",) if registers else ()
    # a listing none of whose registers is read is no file of the program: nothing to write, no batch group to join
    return (source if registers else None), registers, why, notes


def _entries(text):
    """``{(group, number): (entry start, body start, body end, status)}`` of the ``$POSREG`` entries of a listing."""
    headers = [(m.start(), m.group(1).upper()) for m in _HEADER.finditer(text)]
    start = next((at for at, name in headers if name == "POSREG"), None)
    if start is None:
        return {}
    end = next((at for at, _ in headers if at > start), len(text))
    found = list(_ENTRY.finditer(text, start, end))
    out = {}
    for k, m in enumerate(found):
        stop = found[k + 1].start() if k + 1 < len(found) else end
        out[(int(m.group(1)), int(m.group(2)))] = (m.start(), m.end(), stop, m.group(3))
    return out


def _target(source, index, lines, n, entry, entries):
    """The Target of register ``n`` of group 1 (spans in the listing), or why it has none (str)."""
    start, body_start, body_end, status = entry
    line = lines.number(start)
    label = f"PR[{n}]"
    if "uninitialized" in status.lower():
        return (f" is uninitialized in {source.name} (line {line}): the controller faults if this line runs "
                "before something sets it")
    text = source.text
    fields = {}
    for f in _FIELD.finditer(text, body_start, body_end):
        role = (f.group(1) or f.group(2) or f"e{f.group(3)}").lower()
        fields[role] = Span(index, f.start(4), f.end(4), f.group(4))
    if any("*" in span.text for span in fields.values()):
        return f" is not taught in {source.name} (********, line {line})"

    def value(role, limit):
        return finite(fields[role].text, source.name, lines.number(fields[role].start),
                      lines.line(lines.number(fields[role].start)), f"{label} {role.upper()}", limit)

    axes = sorted((role for role in fields if role.startswith("e")), key=lambda role: int(role[1:]))  # e1, e2 ...
    external = [value(e, LENGTH_LIMIT) for e in axes]
    for group in sorted({g for g, _ in entries if g > 1}):  # the axes of the other groups (a servo gun): carried
        _, other_start, other_end, other_status = entries.get((group, n), (0, 0, 0, "uninitialized"))
        if "uninitialized" not in other_status.lower():
            external += [finite(f.group(4), source.name, lines.number(f.start(4)), lines.line(lines.number(f.start(4))),
                                f"{label} GP{group}", LENGTH_LIMIT)
                         for f in _FIELD.finditer(text, other_start, other_end) if "*" not in f.group(4)]
    where = {"name": label, "line": line, "external": np.array(external) if external else None}
    if "j1" in fields:
        missing = [j for j in JOINTS if j not in fields]
        if missing:
            fail(source.name, line, lines.line(line), f"{label} lacks {', '.join(j.upper() for j in missing)}")
        joints = np.radians([value(j, JOINT_LIMIT) for j in JOINTS])
        return Target(**where, joints=joints, spans={j: fields[j] for j in JOINTS})
    missing = [c for c in XYZWPR if c not in fields]
    if missing:
        fail(source.name, line, lines.line(line), f"{label} lacks {', '.join(c.upper() for c in missing)}")
    x, y, z, w, p, r = (value(c, LENGTH_LIMIT if c in "xyz" else ANGLE_LIMIT) for c in XYZWPR)
    spans = {c: fields[c] for c in XYZWPR}
    config = ()
    c = _CONFIG.search(text, body_start, body_end)
    if c:
        v = CONFIG_VALUE.match(c.group(1))
        if not v:
            fail(source.name, lines.number(c.start()), lines.line(lines.number(c.start())),
                 f"{label}: malformed Config (a 6-axis arm's is 'N U T, 0, 0, 0')")
        config = (v.group(1).upper(), v.group(2).upper(), v.group(3).upper(), *map(int, v.groups()[3:]))
        spans["config"] = Span(index, c.start(1), c.end(1), c.group(1))
    pose = pose_to_matrix([x, y, z, *np.radians([r, p, w])])
    return Target(**where, pose=pose, config=config, spans=spans)


def _sets_in_folders(program_path, registers_folder, masked, lines):
    """``{number: (where, instruction)}`` of registers set at run time; key None: ``PR[R[k]]=`` (any register).

    The program's own instructions (``line 12``), then those of the other
    TP program listings (.LS) beside it and beside POSREG.VA (``name.ls:12``).
    """
    own = Path(program_path).resolve()
    found = _sets(masked, lines, "line {}")
    for folder in dict.fromkeys((own.parent, Path(registers_folder).resolve())):
        for name in _listing(folder):
            other = folder / name
            if name.lower().endswith(".ls") and other != own and other.is_file():
                stat = other.stat()
                for key, place in _sets_in_file(str(other), stat.st_mtime_ns, stat.st_size).items():
                    found.setdefault(key, place)
    return found


@functools.lru_cache(maxsize=4096)
def _sets_in_file(path, mtime_ns, size):
    """`_sets` of another program listing, read once per version of the file (a backup's programs each read it)."""
    try:
        source = read_source(path)
    except ReadError:  # a binary file named .ls: no listing, nothing trajcomp can read sets a register
        return {}
    return _sets(masked(source.text), Lines(source.text), f"{source.name}:{{}}")


def _sets(masked, lines, place):
    """``{number or None: (place of the line, the instruction)}`` of the register-setting instructions of a text."""
    found = {}
    for m in _SETS.finditer(masked):
        ref = m.group(1) or m.group(2)
        number = lines.number(m.start())
        instruction = " ".join(_TP_LINE.sub("", lines.line(number)).split())
        found.setdefault(int(ref) if ref.isdigit() else None, (place.format(number), instruction[:80]))
    return found
