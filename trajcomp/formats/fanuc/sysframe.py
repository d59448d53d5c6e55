"""FANUC user frames and tools of a program read from the controller's SYSFRAME.VA.

A /POS position states its user frame and tool by number (``UF : 2, UT :
1``); their values are the controller's, set up on the teach pendant
(SETUP > Frames) and saved in a backup's SYSFRAME.VA, an ASCII listing of
``$MNUFRAME`` and ``$MNUTOOL`` (``ARRAY[groups, n] OF POSITION``)::

    [*SYSTEM*]$MNUFRAME  Storage: SHADOW  Access: RW  : ARRAY[1,9] OF POSITION
        [1,1] =
      Group: 1   Config: N D B, 0, 0, 0
      X:  1250.000   Y:  -430.500   Z:   120.000
      W:     0.000   P:     0.000   R:    90.000
    [*SYSTEM*]$MNUTOOL  Storage: SHADOW  Access: RW  : ARRAY[1,10] OF POSITION
        [1,1] =   'TORCH'   Group: 1
      X:     5.000   Y:     0.000   Z:   412.000
      W:     0.000   P:   -30.000   R:     0.000

Entry ``[1,n]`` is user frame (tool) n of motion group 1, in the world
(the faceplate), W, P, R as in a position (R = Rz(R) Ry(P) Rx(W));
``Uninitialized`` or ``********`` where it holds none. UF 0 and UT 0 are
the world and the faceplate. The frames and tools a program uses and does
not define are read from the SYSFRAME.VA beside it or in the folder above
(its backup, as POSREG.VA: `trajcomp.formats.fanuc.posreg.find`); the
report names them. A program that sets one at run time (``UFRAME[2]=PR[1]``)
keeps its motions after that line as written (`trajcomp.formats.fanuc.reader`).
"""

import functools
import os
import re
from pathlib import Path

import numpy as np

from trajcomp.formats.text import ANGLE_LIMIT, LENGTH_LIMIT, Lines, finite, read_source
from trajcomp.formats.number_fields import NUMBER
from trajcomp.arm.transforms import pose_to_matrix

FILE_NAME = "sysframe.va"
VARIABLES = {"MNUFRAME": "frame", "MNUTOOL": "tool"}
_HEADER = re.compile(r"^\[\*[^\]]*\*\]\s*\$(\w+)", re.M)
_ENTRY = re.compile(r"^[ \t]*\[\s*(\d+)\s*,\s*(\d+)\s*\][ \t]*=([^\r\n]*)", re.M)
_FIELD = re.compile(r"\b([XYZWPR])\s*:\s*(" + NUMBER + r"|\*+)")
XYZWPR = "XYZWPR"


def entries(path):
    """``{("frame" or "tool", number): (line, T or why it has none)}`` of group 1's entries of a SYSFRAME.VA.

    Read once per version of the file (a backup's programs all read it).
    ``T`` (4, 4) is T_world_uframe or T_faceplate_tool, mm; an entry
    without a value gives the reason as a str.
    """
    stat = os.stat(path)
    return _entries(str(path), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=64)
def _entries(path, mtime_ns, size):
    source = read_source(path)
    text, lines = source.text, Lines(source.text)
    headers = [(m.start(), m.group(1).upper()) for m in _HEADER.finditer(text)] + [(len(text), None)]
    found = {}
    for (start, variable), (end, _) in zip(headers, headers[1:]):
        if variable not in VARIABLES:
            continue
        matches = list(_ENTRY.finditer(text, start, end))
        for k, m in enumerate(matches):
            if int(m.group(1)) != 1:
                continue
            stop = matches[k + 1].start() if k + 1 < len(matches) else end
            line = lines.number(m.start())
            found[(VARIABLES[variable], str(int(m.group(2))))] = (line, _value(source.name, lines, text, m, stop))
    return source.name, found


def _value(name, lines, text, entry, stop):
    """T (4, 4) of one entry, or why it holds none (str)."""
    if "uninitialized" in entry.group(3).lower():
        return "uninitialized"
    fields = {f.group(1).upper(): f for f in _FIELD.finditer(text, entry.end(), stop)}
    if any("*" in f.group(2) for f in fields.values()):
        return "not set (********)"
    if set(fields) != set(XYZWPR):
        return f"lacks {', '.join(c for c in XYZWPR if c not in fields)}"

    def value(c):
        line = lines.number(fields[c].start(2))
        return finite(fields[c].group(2), name, line, lines.line(line), f"${c}", LENGTH_LIMIT if c in "XYZ"
                      else ANGLE_LIMIT)

    x, y, z, w, p, r = (value(c) for c in XYZWPR)
    return pose_to_matrix([x, y, z, *np.radians([r, p, w])])


def find(program_path):
    """The SYSFRAME.VA of a program's controller (beside it or in the folder above), or None."""
    from trajcomp.formats.fanuc.posreg import find as find_listing

    return find_listing(program_path, FILE_NAME)


def tables(program_path, wanted):
    """The user frames and tools a program uses and does not define, as its controller's SYSFRAME.VA holds them.

    Parameters
    ----------
    program_path : Path
        The .LS program.
    wanted : dict
        ``{"tool": names, "frame": names}``: the UT and UF numbers used and not defined (str of digits).

    Returns
    -------
    found : dict
        ``{"tool": {name: T_faceplate_tool}, "frame": {name: T_world_uframe}}`` (mm).
    notes : tuple of str
        What the report must say: where the values come from, and the entries the file holds none for.
    """
    path = find(program_path) if any(wanted.values()) else None
    found = {"tool": {}, "frame": {}}
    if path is None:
        return found, ()
    name, table = entries(path)
    read, empty = [], []
    for what, label in (("frame", "UFRAME"), ("tool", "UTOOL")):
        for number in sorted(wanted[what], key=int):
            line, value = table.get((what, str(int(number))), (None, "not listed"))
            if isinstance(value, str):
                empty.append(f"{label} {number} ({value}{'' if line is None else f', line {line}'})")
            else:
                found[what][number] = value
                read.append(f"{label} {number} (line {line})")
    notes = ()
    if read:
        shown = os.path.relpath(path, Path(program_path).resolve().parent)
        notes += (f"user frames and tools read from the controller's {shown} (the values its backup holds): "
                  + ", ".join(read) + ". A controller whose frames changed since runs other values: compensate "
                  "with its current SYSFRAME.VA",)
    if empty:
        notes += (f"{name} holds no value for " + ", ".join(empty) + ": give it with --frame / --tool",)
    return found, notes
