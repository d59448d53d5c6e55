"""A point used with several tools or frames: a corrected copy of it per use.

One set of numbers cannot be right for two tools or work objects (the same
figure drawn in two work objects, a point reached with two grippers:
legal in every language). Where a language declares points by name (RAPID
robtargets, KRL data lists: `trajcomp.formats.Format.copies`), each
further use gets a copy of the point's declaration, written right after it
under a free name (``p10_2``), and the motions of that use name the copy:
every copy is then compensated for its own tool and frame, and the report
says so (`Program.notes`). A point a language cannot copy (an inline
literal, a motion whose name trajcomp did not place) keeps its motions as
written, listed (`Program.with_shared_targets_left`).
"""

import dataclasses
import re

from trajcomp.formats.text import Lines, edit_sources
from trajcomp.programs.items import Motion, Span

NAME_LENGTH = 24  # KUKA's limit on names; RAPID allows 32


def per_use(program):
    """The program with a copy of each point used with several tools or frames, one per further use.

    Parameters
    ----------
    program : Program
        Read from files (its points have spans, its motions the spans
        ``target_name`` / ``via_name`` of the names they move to).

    Returns
    -------
    Program
        The sources with each copy's declaration inserted after its
        original and the motions of its use renamed; the copies appended to
        the targets, and one note per copy. The program itself when no
        point is shared.
    """
    groups = _further_uses(program)
    if not groups:
        return program
    taken = {target.name.lower() for target in program.targets if target.name}
    edits, copies = [[] for _ in program.sources], []
    for (i, key), uses in groups.items():
        declaration = _declaration(program, i)
        if declaration is None or any(role not in program.motions[k].spans for k, role in uses):
            continue  # left as written and listed by with_shared_targets_left
        source, start, end, occurrence = declaration
        target = program.targets[i]
        name = _free_name(target.name, taken)
        text = program.sources[source].text
        copy = text[start:occurrence] + name + text[occurrence + len(target.name):end]
        edits[source].append((end, end, copy))
        for k, role in uses:
            span = program.motions[k].spans[role]
            edits[span.source].append((span.start, span.end, name))
        copies.append((i, key, uses, name, source, copy, occurrence - start))
    if not copies:
        return program
    edited = edit_sources(program, edits)
    targets, items, notes = list(edited.targets), list(edited.items), []
    motion_items = [k for k, item in enumerate(items) if isinstance(item, Motion)]
    for i, key, uses, name, source, copy, occurrence in copies:
        original = edited.targets[i]
        new_text = edited.sources[source].text
        at = new_text.find(copy)
        declared = program.targets[i]
        start = min(span.start for span in declared.spans.values())
        line_start = program.sources[source].text.rfind("\n", 0, start) + 1
        shift = len(name) - len(declared.name)
        spans = {}
        for role, span in declared.spans.items():
            offset = span.start - line_start
            offset += shift if offset > occurrence else 0
            spans[role] = Span(source, at + offset, at + offset + len(span.text), span.text)
        targets.append(dataclasses.replace(original, name=name, line=Lines(new_text).number(at), spans=spans,
                                           edited=False))
        for k, role in uses:
            item = items[motion_items[k]]
            items[motion_items[k]] = dataclasses.replace(item, **{role.split("_")[0]: len(targets) - 1})
        places = [edited.place(items[motion_items[k]]) for k, _ in uses]  # "b.src:3" in a task of several files
        lines = ", ".join(map(str, places))
        lines = lines if isinstance(places[0], str) else f"line{'s' * (len(uses) > 1)} {lines}"
        notes.append(f"point {original.name} is used with tool/frame {key} ({lines}) "
                     "besides its first use: "
                     f"written as a copy {name} after it ({edited.sources[source].name}:{targets[-1].line}), "
                     "corrected for that use")
    return edited.replace(targets=tuple(targets), items=tuple(items), notes=edited.notes + tuple(notes))


def _further_uses(program):
    """``{(target, (tool, frame)): [(motion, role), ...]}`` of every use of a point with another tool or frame
    than its first use (in program order, via point before target); ``role`` names the motion's name span."""
    first, groups = {}, {}
    for k, motion in enumerate(program.motions):
        for role, i in (("via_name", motion.via), ("target_name", motion.target)):
            if i is None:
                continue
            target = program.targets[i]
            key = (motion.tool if target.tool is None else target.tool,
                   motion.frame if target.frame is None else target.frame)
            if first.setdefault(i, key) != key:
                groups.setdefault((i, key), []).append((k, role))
    return groups


def _declaration(program, i):
    """``(source, start, end, name offset)`` of the whole lines declaring point ``i``, or None (an inline
    literal, or a declaration on the last line of its file)."""
    target = program.targets[i]
    if not target.name or not target.spans:
        return None
    spans = target.spans.values()
    source = next(iter(spans)).source
    text = program.sources[source].text
    start = text.rfind("\n", 0, min(span.start for span in spans)) + 1
    end = text.find("\n", max(span.end for span in spans)) + 1
    m = re.compile(rf"(?<![\w$]){re.escape(target.name)}(?![\w$])", re.I).search(text, start, end)
    return None if end == 0 or m is None else (source, start, end, m.start())


def _free_name(name, taken):
    """``name_2``, ``name_3`` ... : the first not ``taken`` (case-insensitive), within KUKA's 24 characters."""
    number = 2
    while True:
        suffix = f"_{number}"
        candidate = name[: NAME_LENGTH - len(suffix)] + suffix
        if candidate.lower() not in taken:
            taken.add(candidate.lower())
            return candidate
        number += 1
