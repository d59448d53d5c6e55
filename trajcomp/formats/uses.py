"""A point used with several tools or frames: a corrected copy of it per use.

One set of numbers cannot be right for two tools or work objects (the same
figure drawn in two work objects, a point reached with two grippers:
legal in every language). Where a language declares points by name (RAPID
robtargets, KRL data lists, URScript pose variables:
`trajcomp.formats.capabilities.PointCopies`), each further use gets a copy of the
point's declaration, written right after it under a free name (``p10_2``),
and the motions of that use name the copy: every copy is then compensated
for its own tool and frame, and the report says so (`Program.notes`). A
point that cannot be copied keeps its motions as written, each listed with
its own tool and frame, the other uses and why no copy is written: a
language without declarations by name (a FANUC position register holds one
position; a copy would need a register the controller does not use), a
point whose joints another variable holds (PolyScope's ``Waypoint_n_q``),
a name a motion's line writes more than once.
"""

import dataclasses
import re

from trajcomp.formats.text import Lines
from trajcomp.formats.source_shifts import edit_sources
from trajcomp.programs.items import Motion, Span
from trajcomp.programs.program import place_text

NAME_LENGTH = 24  # KUKA's limit on names; RAPID allows 32
LINKED_JOINTS = "near"  # span roles of joints another variable holds (a URScript qnear list, `Waypoint_n_q`)
NO_DECLARATION = {
    "fanuc_ls": "a position register holds one position (a copy would need a register the controller does not use)",
}


def per_use(program, copies=True):
    """The program with a copy of each point used with several tools or frames, one per further use.

    Parameters
    ----------
    program : Program
        Read from files (its points have spans, its motions the spans
        ``target_name`` / ``via_name`` of the names they move to, or the
        name once in their line).
    copies : bool
        The language declares points by name (`trajcomp.formats.capabilities.PointCopies`);
        otherwise every such point's motions are left as written.

    Returns
    -------
    Program
        The sources with each copy's declaration inserted after its
        original and the motions of its use renamed; the copies appended to
        the targets, and one note per copy; the motions of a point that
        cannot be copied left as written, each with its reason. The program
        itself when no point is shared.
    """
    groups = _further_uses(program)
    if not groups:
        return program
    taken = None
    edits, copies_made, left = [[] for _ in program.sources], [], {}
    for (i, key), uses in groups.items():
        uses = [(k, role, _name_span(program, k, role, program.targets[i].name)) for k, role in uses]
        why = _why_not_copied(program, i, uses, copies)
        if why:
            left.setdefault(i, why)
            continue
        if taken is None:  # every word of the files: a copy's name must be free of any variable or routine
            taken = {word.lower() for source in program.sources for word in re.findall(r"[\w$]+", source.text)}
        source, start, end, occurrence = _declaration(program, i)
        target = program.targets[i]
        name = _free_name(target.name, taken)
        text = program.sources[source].text
        copy = text[start:occurrence] + name + text[occurrence + len(target.name):end]
        edits[source].append((end, end, copy))
        for _, _, span in uses:
            edits[span.source].append((span.start, span.end, name))
        copies_made.append((i, key, [(k, role) for k, role, _ in uses], name, source, copy, occurrence - start))
    program = _left_as_written(program, left)
    if not copies_made:
        return program
    edited = edit_sources(program, edits)
    targets, items, notes = list(edited.targets), list(edited.items), []
    motion_items = [k for k, item in enumerate(items) if isinstance(item, Motion)]
    for i, key, uses, name, source, copy, occurrence in copies_made:
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


def _name_span(program, k, role, name):
    """The span of ``name`` in motion ``k``: its ``role`` span, else the name written once in the motion's line
    (None: neither)."""
    motion = program.motions[k]
    if role in motion.spans:
        return motion.spans[role]
    text = program.sources[motion.source].text
    start = Lines(text).starts[motion.line - 1]
    end = text.find("\n", start)
    found = list(re.finditer(rf"(?<![\w$]){re.escape(name)}(?![\w$])", text[start:len(text) if end < 0 else end]))
    if not name or len(found) != 1:
        return None
    return Span(motion.source, start + found[0].start(), start + found[0].end(), name)


def _why_not_copied(program, i, uses, copies):
    """Why point ``i`` gets no copy for ``uses`` ``[(motion, role, name span)]`` ("" when it can)."""
    target = program.targets[i]
    if not copies:
        return NO_DECLARATION.get(program.format, f"{program.format} programs do not declare points by name")
    linked = [role for role in target.spans if role.startswith(LINKED_JOINTS)]
    if linked:
        span = target.spans[linked[0]]
        return (f"its joints are a list another variable holds ({program.sources[span.source].name} line "
                f"{Lines(program.sources[span.source].text).number(span.start)}), which a copy would share")
    if _declaration(program, i) is None:
        return "it is not declared by name on lines of its own"
    for k, _, span in uses:
        if span is None:
            motion = program.motions[k]
            return f"its name is not written once in {program.place(motion)!s}: {motion.text[:60]}"
    return ""


def _left_as_written(program, left):
    """The program with the motions of the points ``left`` (``{target: why no copy}``) passed through, each listed
    with its own tool and frame and the other uses (`Motion.reason`)."""
    if not left:
        return program
    first_use = {}  # point -> {(tool, frame): place of its first motion}
    keyed = []
    for k, motion in enumerate(program.motions):
        for i in (motion.via, motion.target):
            if i in left:
                target = program.targets[i]
                key = (motion.tool if target.tool is None else target.tool,
                       motion.frame if target.frame is None else target.frame)
                first_use.setdefault(i, {}).setdefault(key, program.place(motion))
                keyed.append((k, i, key))
    reasons = {}
    for k, i, key in keyed:
        others = "; ".join(f"with {other} at {place_text(place)}"
                           for other, place in first_use[i].items() if other != key)
        reasons.setdefault(k, f"point {program.targets[i].label} is used here with tool/frame {key} and {others}: "
                              f"one set of numbers cannot be right for {'both' if len(first_use[i]) == 2 else 'all'}, "
                              f"and no copy is written: {left[i]}; "
                              "left as written")
    motions = iter(range(len(program.motions)))
    items = []
    for item in program.items:
        if isinstance(item, Motion) and (k := next(motions)) in reasons:
            points = tuple(i for i in (item.via, item.target) if i is not None)
            item = dataclasses.replace(item, target=None, via=None, reason=reasons[k],
                                       refs=tuple(dict.fromkeys(item.refs + points)))
        items.append(item)
    return program.replace(items=tuple(items))


def _further_uses(program):
    """``{(target, (tool, frame)): [(motion, role), ...]}`` of every use of a point with another tool or frame
    than its first use (in program order, via point before target; `Program.target_uses`); ``role`` names the
    motion's name span."""
    uses, groups = program.target_uses(), {}
    for j in uses["clash"].tolist():
        key = (uses["tool"][j], uses["frame"][j])
        role = "via_name" if uses["via"][j] else "target_name"
        groups.setdefault((int(uses["index"][j]), key), []).append((int(uses["motion"][j]), role))
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
