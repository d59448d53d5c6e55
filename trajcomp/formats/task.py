"""Programs as controllers hold them: several files of one controller read as one program.

A program file is read with the points it uses from the other files of
its controller (another module of a RAPID task, a KUKA data list or
``$config.dat``): those files are its companion sources (`Source`), and
their points are corrected where they are declared. Files that share
points (a RAPID task's modules, KUKA programs using one ``$config.dat``)
are compensated together: `merge` joins their programs so that a point
declared once is one target, corrected once and consistently for every
file that uses it, and `groups` finds which files of a batch belong
together. The writer then writes every changed file where it lies
(`trajcomp.formats.file_writing.companion_outputs`), all of them in one atomic
commit (`trajcomp.formats.write`).
"""

import dataclasses
import os

import numpy as np

from trajcomp.errors import TrajcompError
from trajcomp.programs.program import Program
from trajcomp.programs.items import Motion


def file_key(path):
    """A file's identity for joining (absolute, case-folded where the file system ignores case)."""
    return os.path.normcase(os.path.abspath(path))


def merge(programs):
    """One program of several read from the files of one controller.

    Sources are joined by path (a file read as one program's companion and
    as another program is that program's, written whatever changed); a
    target declared at the same place of the same file is one target;
    items follow in the order of the programs. A tool or frame two files
    define differently under one name is kept apart as ``name (file)``.

    Parameters
    ----------
    programs : sequence of Program
        Of one language, read from files (their sources have paths).

    Returns
    -------
    Program
        Named after the first that has motions, else the first (a point the files use with several tools or
        frames is resolved by `trajcomp.formats.read_task`); each item names
        the file it is written in (`Motion.source`), so that its place is
        ``file:line`` (`Program.place`).
    """
    languages = {program.format for program in programs}
    if len(languages) > 1:
        raise TrajcompError(f"programs of one task must be of one language, got {', '.join(sorted(languages))}")
    sources, slot = [], {}
    for program in programs:
        for source in program.sources:
            key = file_key(source.path)
            if key not in slot:
                slot[key] = len(sources)
                sources.append(source)
            elif not source.companion:
                sources[slot[key]] = source
    targets, places, items, tools, frames = [], {}, [], {}, {}
    for program in programs:
        moved = [slot[file_key(source.path)] for source in program.sources]
        index = [_joined(target, moved, targets, places) for target in program.targets]
        names = {kind: _named(getattr(program, kind), table, program.sources[0].name)
                 for kind, table in (("tools", tools), ("frames", frames))}
        items += [_moved_item(item, index, moved, names) for item in program.items]
    first = programs[0]
    # named after the first file that moves the arm (messages name the program): not a module of data before it
    name = next((program.name for program in programs if len(program.motion_table())), first.name)
    notes = tuple(note for program in programs for note in program.notes)
    return Program(first.format, name, tuple(items), tuple(targets), tools, frames, tuple(sources), notes=notes)


def _joined(target, moved, targets, places):
    """Index of ``target`` among the joined ``targets``: the one declared at the same place, else appended."""
    spans = {role: dataclasses.replace(span, source=moved[span.source]) for role, span in target.spans.items()}
    first = next(iter(spans.values()), None)
    place = None if first is None else (first.source, first.start)
    if place in places:
        return places[place]
    if place is not None:
        places[place] = len(targets)
    targets.append(dataclasses.replace(target, spans=spans))
    return len(targets) - 1


def _named(values, table, file):
    """Add a program's tools (or frames) to the joined ``table``: ``{name: joined name}``."""
    names = {}
    for name, T in values.items():
        joined = name if name not in table or np.array_equal(table[name], T) else f"{name} ({file})"
        table[joined] = T
        names[name] = joined
    return names


def _moved_item(item, index, moved, names):
    """An item of one program with its targets, spans, tools and frames in the joined program."""
    change = {"refs": tuple(index[i] for i in item.refs), "source": moved[item.source]}
    if isinstance(item, Motion):
        change |= {
            "target": None if item.target is None else index[item.target],
            "via": None if item.via is None else index[item.via],
            "spans": {role: dataclasses.replace(span, source=moved[span.source]) for role, span in item.spans.items()},
            "tool": names["tools"].get(item.tool, item.tool),
            "frame": names["frames"].get(item.frame, item.frame),
        }
    return dataclasses.replace(item, **change)


def groups(paths):
    """Which files of a batch are compensated together: lists of indices into ``paths``, each in input order.

    Files that read points of each other or of one shared file (a RAPID
    task's modules, KUKA programs using one ``$config.dat``) form one
    group, so that a shared point is corrected once and every file is
    written by one run. Only files of languages whose programs use other
    files' points (their `trajcomp.formats.capabilities.Tasks`) are read for this; a
    file that cannot be read is a group of its own (its run says why, a
    crash included).

    Parameters
    ----------
    paths : sequence of Path

    Returns
    -------
    list of list of int
        Ordered by their first file.
    """
    from trajcomp import formats  # the registry imports this module lazily
    from trajcomp.formats.capabilities import Tasks

    parent = list(range(len(paths)))

    def root(k):
        while parent[k] != k:
            k = parent[k]
        return k

    owner = {}  # file -> the first input reading it
    for k, path in enumerate(paths):
        try:
            if formats.find_format(path).capability(Tasks) is None:
                continue
            program = formats.read(path)
        except Exception:  # refused or a bug: the file's own run reports it, as the batch reports any file's
            continue
        for file in formats.input_paths(path, program):
            key = file_key(file)
            if key in owner:
                parent[root(k)] = root(owner[key])
            else:
                owner[key] = k
    joined = {}
    for k in range(len(paths)):
        joined.setdefault(root(k), []).append(k)
    return sorted(joined.values())
