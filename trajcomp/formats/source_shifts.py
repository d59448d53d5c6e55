"""Source shifting: a program's sources edited in memory, every span and line number moved along (`edit_sources`)."""

import dataclasses

import numpy as np

from trajcomp.formats.text import Lines
from trajcomp.formats.text_edits import apply_edits
from trajcomp.programs.items import Span, SpanColumns, SpanRow, replaced
from trajcomp.programs.tables import ItemRows, Picked, StatementTable, TargetRows
from trajcomp.support.memory import collection_paused


def edit_sources(program, edits):
    """The program with text edits applied to its sources and every span and line number moved along.

    Parameters
    ----------
    program : Program
    edits : sequence of list of (start, end, text)
        Per source; non-overlapping; an insertion (start == end) goes before
        a span starting there and after a span ending there.

    Returns
    -------
    Program
    """
    if not any(edits):  # nothing written (every speed kept): the program as it is
        return program
    with collection_paused():  # a span and an item object each (`trajcomp.support.memory`)
        return _edited(program, [_Shift(source.text, sorted(e)) for source, e in zip(program.sources, edits)],
                       {k for k, e in enumerate(edits) if e})


def _edited(program, shifts, changed):
    """`edit_sources` of the edits ``shifts`` (one `_Shift` per source); ``changed``: the sources edited.

    A target stated in a source without edits (a KRL .dat when speed lines
    go into the .src) keeps its spans and line as they are. Spans kept as
    `SpanColumns` move as columns, each table at once (no `Span` object made).
    """
    sources = tuple(s.source_like(source) for s, source in zip(shifts, program.sources))
    if isinstance(program.targets, TargetRows):  # a table's targets move as columns
        edited = _edited(program.replace(targets=()), shifts, changed)
        return edited.replace(targets=_moved_rows(program.targets, shifts, changed))
    if isinstance(program.items, ItemRows) and isinstance(program.items.table.spans, (SpanColumns, Picked, type(None))):
        edited = _edited(program.replace(items=()), shifts, changed)  # a table's items move as columns
        return edited.replace(items=_moved_items(program.items, shifts, changed))
    every_target = list(program.targets)
    moving = [bool(t.spans) and _source_of(t.spans) in changed for t in every_target]
    targets = [t for t, move in zip(every_target, moving) if move]  # a target without spans keeps its line
    things = targets + list(program.items)  # statements and motions are lines of the first file
    spans = [getattr(thing, "spans", {}) for thing in things]
    tables = {}  # id -> the SpanColumns of some things' spans, moved
    for of in spans:
        if isinstance(of, SpanRow) and id(of.columns) not in tables:
            tables[id(of.columns)] = _moved_columns(shifts[of.columns.source], of.columns)
    moved = iter(_moved_spans(shifts, [span for of in spans if not isinstance(of, SpanRow) for span in of.values()]))
    first_file = [0] * (len(things) - len(targets))
    lines = _moved_lines(shifts, [_source_of(t.spans) for t in targets] + first_file,
                         [thing.line for thing in things])

    def moved_spans(of):
        if isinstance(of, SpanRow):
            return {"spans": tables[id(of.columns)].row(of.k)}
        return {"spans": {role: next(moved) for role in of}} if of else {}

    edited = iter([replaced(thing, line=line, **moved_spans(of)) for thing, of, line in zip(things, spans, lines)])
    return program.replace(sources=sources, targets=tuple(next(edited) if move else t
                                                          for t, move in zip(every_target, moving)),
                           items=tuple(edited))


def _moved_rows(targets, shifts, changed):
    """`TargetRows` with their spans and lines in the edited texts (as they are if their source is not edited)."""
    table = targets.table
    if table.spans is None or table.spans.source not in changed:  # a target without spans keeps its line
        return targets
    shift = shifts[table.spans.source]
    moved = dataclasses.replace(table, spans=_moved_columns(shift, table.spans), line=shift.lines(table.line))
    return TargetRows(moved)


def _moved_items(items, shifts, changed):
    """`ItemRows` whose motions' spans (`SpanColumns`) and statements' and motions' lines are in the edited texts.

    Texts stay as they are (as `replaced` keeps an item's text).
    """
    statements, motions = items.statements, items.table
    spans = motions.spans
    if isinstance(spans, Picked):  # a merged table's: each part's spans moved
        spans = Picked([_moved_span_maps(shifts, part) for part in spans.sequences], spans.part, spans.row)
    elif spans is not None and spans.source in changed:
        spans = _moved_columns(shifts[spans.source], spans)
    motions = dataclasses.replace(motions, spans=spans, line=np.array(_moved_lines(shifts, motions.source,
                                                                                   motions.line), dtype=int))
    statements = StatementTable(_moved_lines(shifts, statements.source, statements.line), statements.text,
                                statements.source, statements.refs)
    return ItemRows(statements, motions)


def _moved_span_maps(shifts, maps):
    """Items' spans (a sequence of Mapping: a part of a merged `MotionTable.spans`) in the edited texts, as
    `_edited` moves them: `SpanColumns` as columns, other spans each."""
    if isinstance(maps, SpanColumns):
        return _moved_columns(shifts[maps.source], maps)
    tables = {}  # id -> the SpanColumns of some items' spans, moved
    moved = iter(_moved_spans(shifts, [span for of in maps if not isinstance(of, SpanRow) for span in of.values()]))
    out = []
    for of in maps:
        if isinstance(of, SpanRow):
            if id(of.columns) not in tables:
                tables[id(of.columns)] = _moved_columns(shifts[of.columns.source], of.columns)
            out.append(tables[id(of.columns)].row(of.k))
        else:
            out.append({role: next(moved) for role in of} if of else of)
    return tuple(out)


def _source_of(spans):
    """The source of a thing's spans (its first span's)."""
    return spans.columns.source if isinstance(spans, SpanRow) else next(iter(spans.values())).source


def _moved_columns(shift, columns):
    """`SpanColumns` in the edited text of its source (`_Shift` ``shift``), as `_moved_spans` moves each span."""
    given = columns.start >= 0
    start = np.where(given, shift.starts(columns.start), -1)
    end = np.where(given, np.maximum(shift.ends(columns.end), start), -1)
    return SpanColumns(columns.source, shift.new, columns.roles, start, end)


def _moved_spans(shifts, spans):
    """The spans (list of Span) in the edited texts, each source's positions moved at once."""
    source = np.array([span.source for span in spans], dtype=int)
    start = np.array([span.start for span in spans], dtype=int)
    end = np.array([span.end for span in spans], dtype=int)
    for k, shift in enumerate(shifts):
        rows = np.flatnonzero(source == k)
        start[rows] = shift.starts(start[rows])
        end[rows] = np.maximum(shift.ends(end[rows]), start[rows])
    texts = [shift.new for shift in shifts]
    return [Span(k, a, b, texts[k][a:b]) for k, a, b in zip(source.tolist(), start.tolist(), end.tolist())]


def _moved_lines(shifts, sources, numbers):
    """Line numbers (list of int) in the edited texts of lines ``numbers`` of ``sources``."""
    source, number = np.array(sources, dtype=int), np.array(numbers, dtype=int)
    for k, shift in enumerate(shifts):
        rows = np.flatnonzero(source == k)
        number[rows] = shift.lines(number[rows])
    return number.tolist()


class _Shift:
    """Offsets and line numbers of a text before edits mapped to the edited text, for arrays of them."""

    def __init__(self, text, edits):
        self.old, self.new = text, apply_edits(text, edits)
        self.edit_ends = np.array([e[1] for e in edits], dtype=int)
        self.insertions = np.array([e[0] for e in edits if e[0] == e[1]], dtype=int)  # ascending, as the edits
        self.delta = np.cumsum([0] + [len(e[2]) - (e[1] - e[0]) for e in edits])
        self.old_starts = np.array(Lines(self.old).starts)
        self.new_starts = np.array(Lines(self.new).starts)

    def starts(self, positions):
        """New offsets of span starts (n,): after every edit ending at or before them."""
        return positions + self.delta[np.searchsorted(self.edit_ends, positions, side="right")]

    def ends(self, positions):
        """New offsets of span ends (n,): after every edit ending at or before them, except insertions at them."""
        at = np.searchsorted(self.insertions, positions, side="right") - np.searchsorted(self.insertions, positions)
        return positions + self.delta[np.searchsorted(self.edit_ends, positions, side="right") - at]

    def lines(self, numbers):
        """New numbers of lines (n,) (by their starts); numbers outside the text as they are."""
        inside = (numbers >= 1) & (numbers <= len(self.old_starts))
        moved = self.starts(self.old_starts[np.clip(numbers, 1, len(self.old_starts)) - 1])
        return np.where(inside, np.searchsorted(self.new_starts, moved, side="right"), numbers)

    def source_like(self, source):
        return dataclasses.replace(source, text=self.new)  # its file and role (`Source.companion`) kept
