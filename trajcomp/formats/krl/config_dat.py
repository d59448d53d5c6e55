"""KUKA ``$config.dat``: the controller's tool, base and load tables a program selects by number.

A KRC backup lays out a robot's files as ``KRC/R1/Program/..`` (the
programs, in folders of any depth) and ``KRC/R1/System/$config.dat``,
which holds, among the cell's GLOBAL data, the tables the teach pendant's
tool and base calibration fills::

    TOOL_DATA[2]={X 12.5,Y 0.0,Z 185.2,A 0.0,B 90.0,C 0.0}
    TOOL_NAME[2,]="TORCH"
    BASE_DATA[8]={X 1450.0,Y -620.0,Z 310.5,A 90.0,B 0.0,C 0.0}
    LOAD_DATA[2]={M 5.5,CM {X 1.0,Y 2.0,Z 3.0,A 0.0,B 0.0,C 0.0},J {X 0.1,Y 0.2,Z 0.3}}

A program selects them by number (``$TOOL = TOOL_DATA[2]``, ``BAS(#TOOL,
2)``, an inline form's FDAT ``TOOL_NO 2``): the controller then moves
with the values of this file, unless the program itself assigns the
entry (``TOOL_DATA[2] = {..}``), which the reader reads first.
``BAS(#TOOL, n)`` and the inline forms load ``LOAD_DATA[n]`` with tool n;
trajcomp compensates geometry and reads the load only to report it (the
arm deflects with its load: calibrate with the one the program runs).
``M -1`` is KUKA's "default load of the machine data".
"""

import functools
import os
import re
from pathlib import Path

from trajcomp.formats.text import Lines, finite, mask, read_source

FILE_NAME = "$config.dat"
ANCESTORS = 4  # folders above a program's looked in for ``System/$config.dat`` (KRC/R1/Program/a/b/x.src)
# TOOL_DATA[2]={..}, also as `DECL FRAME TOOL_DATA[2]={..}`; LOAD_DATA's aggregate holds two others (CM, J)
_ENTRY = re.compile(r"^[ \t]*(?:DECL[ \t]+(?:GLOBAL[ \t]+)?(?:FRAME|LOAD)[ \t]+)?(TOOL|BASE|LOAD)_DATA[ \t]*\[[ \t]*(\d+)"
                    r"[ \t]*\][ \t]*=[ \t]*(\{.*\})[ \t]*\r?$", re.I | re.M)
_MASS = re.compile(r"^\{\s*M\s+([^,}]+)", re.I)
_CENTRE = re.compile(r"\bCM\s*\{([^}]*)\}", re.I)
TABLES = {"TOOL": "TOOL_DATA", "BASE": "BASE_DATA"}


def find(program_path):
    """The ``$config.dat`` of a program's controller, or None.

    Beside the program, else ``System/$config.dat`` in one of the
    `ANCESTORS` folders above it (a KRC backup's ``R1/System`` for a program
    in ``R1/Program`` or a folder of it); the name in any case.

    Parameters
    ----------
    program_path : Path
        The .src program.
    """
    folder = Path(program_path).resolve().parent
    places = [folder] + [ancestor / system for ancestor in folder.parents[:ANCESTORS]
                         for system in _named(ancestor, "system")]
    for place in places:
        for name in _named(place, FILE_NAME):
            if (place / name).is_file():
                return place / name
    return None


def _named(folder, name):
    """The entries of ``folder`` named ``name`` in any case (none for a folder that cannot be listed)."""
    try:
        return sorted(entry for entry in os.listdir(folder) if entry.lower() == name)
    except OSError:
        return []


def entries(path):
    """``{(table, number): (line, aggregate)}`` of the TOOL, BASE and LOAD entries a ``$config.dat`` assigns.

    Read once per version of the file (a backup's programs all read it).
    ``table`` is ``"TOOL"``, ``"BASE"`` or ``"LOAD"``, ``number`` a str
    (``"2"``), the aggregate its text ``{X ..}``.
    """
    stat = os.stat(path)
    return _entries(str(path), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=64)
def _entries(path, mtime_ns, size):
    source = read_source(path, name=FILE_NAME)
    masked, lines = mask(source.text, ";"), Lines(source.text)
    found = {}
    for m in _ENTRY.finditer(masked):
        found[(m.group(1).upper(), str(int(m.group(2))))] = (
            lines.number(m.start()), source.text[m.start(3):m.end(3)])
    return source.name, found


def tables(program_path, wanted, frame):
    """The tools and bases a program selects by number and does not define, as its controller's file holds them.

    Parameters
    ----------
    program_path : Path
        The .src program.
    wanted : dict
        ``{"TOOL": numbers, "BASE": numbers}``: the numbers used and not defined (str of digits, ``"2"``).
    frame : callable
        ``frame(members_text, line, original) -> ndarray (4, 4)``: the pose of an aggregate ``{X ..}``
        (refusing a malformed one with file, line and field).

    Returns
    -------
    found : dict
        ``{"TOOL": {number: T_flange_tool}, "BASE": {number: T_world_base}}`` (mm).
    notes : tuple of str
        What the report must say: where each value comes from, and the load with each tool.
    """
    path = find(program_path) if any(wanted.values()) else None
    found = {"TOOL": {}, "BASE": {}}
    if path is None:
        return found, ()
    name, table = entries(path)
    read = []
    for which in ("TOOL", "BASE"):
        for number in sorted(wanted[which], key=int):
            if (which, number) not in table:
                continue
            line, aggregate = table[(which, number)]
            found[which][number] = frame(aggregate, line, f"{TABLES[which]}[{number}]={aggregate}")
            what = f"{TABLES[which]}[{number}] (line {line})"
            if which == "TOOL":
                what += _load(table.get(("LOAD", number)), number, name)
            read.append(what)
    if not read:
        return found, ()
    shown = os.path.relpath(path, Path(program_path).resolve().parent)
    return found, (f"tools and bases read from the controller's {shown}, the values its backup holds: "
                   + "; ".join(read) + ". A controller whose tables changed since runs other values: compensate "
                   "with its current $config.dat",)


def _load(entry, number, name):
    """What the report says of the load that goes with tool ``number`` (LOAD_DATA[n] of the file, if any)."""
    if entry is None:
        return ""
    line, aggregate = entry
    mass = _MASS.match(aggregate)
    if mass is None:
        return f", with LOAD_DATA[{number}] (line {line}) as written"
    value = finite(mass.group(1).strip(), name, line, aggregate, f"LOAD_DATA[{number}] M")
    if value < 0:
        return f", with LOAD_DATA[{number}] M {mass.group(1).strip()}: the default load of the machine data"
    centre = _CENTRE.search(aggregate)
    at = "" if centre is None else f" at {{{' '.join(centre.group(1).split())}}}"
    return (f", with LOAD_DATA[{number}] {value:g} kg{at} (line {line}): the arm deflects with its load, "
            "calibrate with this one")
