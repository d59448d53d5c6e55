"""The edit engine: the numbers of edited targets replaced in a program's source, formatted like the file wrote them.

`target_edits` turns the targets a compensation changed into text edits
(``(start, end, replacement)`` at the spans a reader recorded), in
batches of `TARGETS_AT_ONCE`; `patched` applies them to every source and
yields each file as `Patched` bytes in its own encoding.
"""

import codecs
import dataclasses
import math
from collections.abc import Mapping

import numpy as np

from trajcomp.errors import WriteError
from trajcomp.formats.number_fields import WrittenNumbers, is_bare, text_codes
from trajcomp.formats.number_writing import column_decimals, written_numbers
from trajcomp.programs.items import SpanColumns, SpanRow
from trajcomp.programs.tables import TargetRows

TARGETS_AT_ONCE = 8192  # edited targets encoded and formatted together: bounds the objects a long program's write makes


def target_edits(program, encode, min_places, columns=None):
    """Text edits that write the edited targets' numbers back into the sources.

    The targets are encoded and their numbers formatted `TARGETS_AT_ONCE`
    at a time, each batch's edits kept as columns (`Edits`): a long
    program's write holds a few bytes per changed number, not a tuple and
    a dict per number. Targets held as a table whose spans are columns
    (`SpanColumns`, a long program's) are encoded by ``columns`` where the
    language gives it: no object per target (`_column_edits`).

    Parameters
    ----------
    program : Program
        Read from the sources it carries.
    encode : callable
        ``encode(targets, olds) -> list of {role: float or str}``: the
        numbers of each edited target in the language (`encode_targets`),
        ``olds`` being ``{role: float}`` of each one's numbers in the file
        (for choosing among equivalent angles and signs). A ``str``
        replaces the span's text as is.
    min_places : Mapping[str, int]
        Fewest decimals per role (at least 0.001 mm for positions).
    columns : callable, optional
        ``columns(table, rows, old) -> {role: ndarray (K,)}``: the numbers
        of the edited rows (K,) of a `TargetTable` in the language, float
        (NaN: left as written) or object (str written as is, None: left),
        ``old`` being `OldNumbers` of those rows (see `_column_edits`).

    Returns
    -------
    list of Edits
        Edits per source; numbers equal at the written precision are left
        with their original text. The numbers are formatted together
        (`written_numbers`).
    """
    targets = program.targets
    if columns is not None and isinstance(targets, TargetRows) and isinstance(targets.table.spans, SpanColumns):
        return _column_edits(targets.table, columns, min_places, len(program.sources))
    edited = (np.flatnonzero(targets.table.edited).tolist() if isinstance(targets, TargetRows)  # no object each
              else [i for i, target in enumerate(targets) if target.edited])
    batches = [_batch_edits([targets[i] for i in edited[lo:lo + TARGETS_AT_ONCE]], encode, min_places,
                            len(program.sources)) for lo in range(0, len(edited), TARGETS_AT_ONCE)]
    return [Edits.joined([batch[k] for batch in batches]) for k in range(len(program.sources))]


def _batch_edits(targets, encode, min_places, sources_count):
    """`Edits` per source of some edited targets (`target_edits`)."""
    edits = [[] for _ in range(sources_count)]
    spans_of = [_fields(target.spans) for target in targets]
    olds = [{role: _number_or_text(span[3]) for role, span in spans.items()} for spans in spans_of]
    numbers = []  # (source, start, end, old text, value, old value, fewest decimals) of every number to write
    for target, spans, old, values_ in zip(targets, spans_of, olds, encode(targets, olds)):
        for role, value in values_.items():
            span = spans.get(role)
            if span is None:
                continue
            if isinstance(value, str):
                if value != span[3]:
                    edits[span[0]].append((span[1], span[2], value))
                continue
            if not math.isfinite(value):
                raise WriteError(f"target {where(target)}: {role} is not a finite number, nothing written")
            old_value = old[role]
            numbers.append(span + (value, old_value if isinstance(old_value, float) else math.nan,
                                   min_places.get(role, 0)))
    if numbers:
        sources, starts, ends, old_texts, values, old_values, places = zip(*numbers)
        changed, texts = written_numbers(np.array(values), np.array([is_bare(t) for t in old_texts], dtype=bool),
                                         np.array(old_values), np.maximum(column_decimals(old_texts), places))
        for k in np.flatnonzero(changed).tolist():
            if texts[k] != old_texts[k]:
                edits[sources[k]].append((starts[k], ends[k], texts[k]))
    return [Edits.of(e) for e in edits]


class OldNumbers:
    """The numbers some targets' spans hold in the file, by role (what `target_edits`' ``columns`` chooses near).

    Each role's columns are made when first asked for: most roles are
    only written over, and a number needs no str of its own.

    Attributes
    ----------
    value : Mapping of str to ndarray, shape (K,)
        Each role's number; NaN where the target has no span of that role
        or its text is no number (a bit string ``'B010'``, a name).
    text : Mapping of str to ndarray of object, shape (K,)
        Each role's text as written; None where the target has no span of that role.
    written : Mapping of str to WrittenNumbers
        How each role's numbers are written (places, a bare point); NaN
        and no places where the target has no span of that role.
    """

    def __init__(self, text, start, end, columns):
        """The numbers of spans ``text[start:end]`` (K, R) of the roles ``columns`` ({role: column}; -1: none).

        The makers hold the spans, not this object: no reference cycle, so a
        batch's columns are freed as soon as the batch is done, also while
        the cyclic collector is paused (`trajcomp.support.memory.collection_paused`).
        """
        present = start >= 0
        region = int(start[present].min()) if present.any() else 0  # the part of the text the spans are in
        codes = []  # that part's character codes, made when a number is first asked for

        def texts(role):
            j = columns[role]
            present = start[:, j] >= 0
            out = np.full(len(present), None, dtype=object)
            out[present] = [text[a:b] for a, b in zip(start[present, j].tolist(), end[present, j].tolist())]
            return out

        def numbers(role):
            if not codes:
                codes.append(text_codes(text[region:int(end.max(initial=0))]))
            j = columns[role]
            present = np.flatnonzero(start[:, j] >= 0)
            return WrittenNumbers.of(codes[0], start[present, j] - region, end[present, j] - region).at(present,
                                                                                                         len(start))

        self.text = _ByRole(columns, texts)
        self.written = written = _ByRole(columns, numbers)
        self.value = _ByRole(columns, lambda role: written[role].values)


class _ByRole(Mapping):
    """``{role: make(role)}`` over the roles of a span table, each made when first asked for."""

    def __init__(self, roles, make):
        self._roles, self._make, self._made = roles, make, {}

    def __getitem__(self, role):
        if role not in self._made:
            if role not in self._roles:
                raise KeyError(role)
            self._made[role] = self._make(role)
        return self._made[role]

    def __iter__(self):
        return iter(self._roles)

    def __len__(self):
        return len(self._roles)


def _column_edits(table, encode, min_places, sources_count):
    """`Edits` per source of a table's edited targets, encoded as columns (`target_edits` with ``columns``)."""
    edits = [Edits.of([]) for _ in range(sources_count)]
    batches = list(_column_batches(table, encode, min_places))  # each batch's edits joined: no str per number
    if batches:
        edits[table.spans.source] = Edits.joined(batches)
    return edits


def _column_batches(table, encode, min_places):
    """The `Edits` of a table's edited targets, `TARGETS_AT_ONCE` targets a batch, each made when the iteration
    reaches it (`_column_edits`)."""
    spans = table.spans
    rows = np.flatnonzero(table.edited)
    for lo in range(0, len(rows), TARGETS_AT_ONCE):
        parts = []
        batch = rows[lo:lo + TARGETS_AT_ONCE]
        starts, ends = spans.start[batch], spans.end[batch]
        old = OldNumbers(spans.text, starts, ends, spans.column)
        for role, new in encode(table, batch, old).items():
            j = spans.column.get(role)
            if j is None:
                continue
            new = np.asarray(new)
            if new.dtype == object:
                change = np.flatnonzero(np.not_equal(new, None) & (starts[:, j] >= 0) & (new != old.text[role]))
                parts.append((starts[change, j], ends[change, j], new[change].tolist()))
                continue
            write = np.flatnonzero(~np.isnan(new) & (starts[:, j] >= 0))
            if np.isinf(new[write]).any():
                k = int(batch[write[np.isinf(new[write])][0]])
                raise WriteError(f"target {where(table.target(k))}: {role} is not a finite number, nothing written")
            written = old.written[role]
            changed, texts = written_numbers(new[write], written.bare[write], written.values[write],
                                             np.maximum(written.places[write], min_places.get(role, 0)))
            keep = np.flatnonzero(changed)  # a number read back other than the old one is written otherwise
            parts.append((starts[write[keep], j], ends[write[keep], j], [texts[k] for k in keep.tolist()]))
        if parts:
            yield Edits.of_columns(np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]),
                                   [t for p in parts for t in p[2]])


def _batches_in_order(table):
    """Whether the spans of a table's edited targets, taken `TARGETS_AT_ONCE` targets a batch, lie batch after
    batch in their text (`_column_batches` then gives its edits in text order: they can be written as made)."""
    spans, rows, end = table.spans, np.flatnonzero(table.edited), -1
    for lo in range(0, len(rows), TARGETS_AT_ONCE):
        batch = rows[lo:lo + TARGETS_AT_ONCE]
        given = spans.start[batch] >= 0
        if given.any():
            if spans.start[batch][given].min() < end:
                return False
            end = spans.end[batch][given].max()
    return True


@dataclasses.dataclass(frozen=True, eq=False)
class Edits:
    """Non-overlapping text edits as columns: what a long program's write holds instead of a tuple per edit.

    Attributes
    ----------
    start, end : ndarray of int, shape (E,)
        Offsets of the text each edit replaces (``start == end``: an
        insertion), ascending as `apply_edits` orders them.
    texts : str
        The replacements one after the other: edit ``k`` writes
        ``texts[cut[k]:cut[k + 1]]``.
    cut : ndarray of int, shape (E + 1,)
    """

    start: np.ndarray
    end: np.ndarray
    texts: str
    cut: np.ndarray

    EDITS_AT_ONCE = 2048  # edits joined together (`blocks`): some 0.25 MB of a CAM program's text at a time

    def __len__(self):
        return len(self.start)

    @classmethod
    def of(cls, edits):
        """The columns of ``(start, end, text)`` edits, in any order."""
        edits = sorted(edits)
        start, end = (np.array([e[k] for e in edits], dtype=np.int64) for k in (0, 1))
        return cls(start, end, "".join(e[2] for e in edits),
                   np.concatenate([[0], np.cumsum([len(e[2]) for e in edits], dtype=np.int64)]))

    @classmethod
    def of_columns(cls, start, end, texts):
        """The columns of edits given as columns (E,) each, in any order (``texts``: a list of str)."""
        order = np.lexsort((end, start))
        texts = np.array(texts, dtype=object)[order].tolist()  # picked in order without a Python step each
        lengths = np.fromiter(map(len, texts), dtype=np.int64, count=len(texts))
        return cls(np.asarray(start, dtype=np.int64)[order], np.asarray(end, dtype=np.int64)[order], "".join(texts),
                   np.concatenate([[0], np.cumsum(lengths)]))

    @classmethod
    def joined(cls, parts):
        """The edits of several `Edits` of one text, in order (their edits do not overlap)."""
        start = np.concatenate([np.zeros(0, dtype=np.int64)] + [p.start for p in parts])
        end = np.concatenate([np.zeros(0, dtype=np.int64)] + [p.end for p in parts])
        shifts = np.cumsum([0] + [len(p.texts) for p in parts])
        cut = np.concatenate([[0]] + [p.cut[1:] + shift for p, shift in zip(parts, shifts.tolist())])
        order = np.lexsort((end, start))  # the parts' edits interleave where their targets do
        texts = "".join(p.texts for p in parts)
        if np.array_equal(order, np.arange(len(order))):
            return cls(start, end, texts, cut)
        return cls.of([(start[k], end[k], texts[cut[k]:cut[k + 1]]) for k in order.tolist()])

    def applied(self, text):
        """``text`` with the edits applied (`apply_edits`)."""
        return "".join([*self.blocks(text), text[self.end[-1] if len(self) else 0:]])

    def blocks(self, text, position=0):
        """``text[position:self.end[-1]]`` with the edits applied, in blocks (str) of `EDITS_AT_ONCE` edits
        (a few MB of pieces joined at a time); ``position``: where the text is taken from (no edit before it)."""
        for lo in range(0, len(self), self.EDITS_AT_ONCE):
            hi = min(lo + self.EDITS_AT_ONCE, len(self))
            yield self._block(text, position, lo, hi)
            position = int(self.end[hi - 1])

    def _block(self, text, position, lo, hi):
        """``text[position:self.end[hi - 1]]`` with edits ``lo..hi - 1`` applied.

        ASCII text and replacements are gathered from their codes at once
        (an index per character: no Python step per edit); others are
        joined piece by piece.
        """
        start, end, cut = self.start[lo:hi], self.end[lo:hi], self.cut[lo:hi + 1]
        kept_from = np.r_[position, end[:-1]]  # each piece of text kept runs from the last edit's end to the edit
        source, replacements = text[position:int(end[-1])], self.texts[int(cut[0]):int(cut[-1])]
        if not (source.isascii() and replacements.isascii()):
            return "".join([piece for a, b, c, d in zip(kept_from.tolist(), start.tolist(), cut[:-1].tolist(),
                                                          cut[1:].tolist())
                            for piece in (text[a:b], self.texts[c:d])])
        codes = np.frombuffer((source + replacements).encode("ascii"), dtype=np.uint8)
        index = np.int32 if len(codes) < 2**31 else np.int64  # the per-character index arrays, 4 bytes where they fit
        piece_start, piece_length = np.empty((2, 2 * (hi - lo)), dtype=np.int64)  # kept, replacement, kept, ...
        piece_start[0::2], piece_length[0::2] = kept_from - position, start - kept_from
        piece_start[1::2], piece_length[1::2] = len(source) + cut[:-1] - cut[0], np.diff(cut)
        shift = (piece_start - (np.cumsum(piece_length) - piece_length)).astype(index)  # a piece's place -> its codes
        at = np.repeat(shift, piece_length)
        at += np.arange(len(at), dtype=index)
        return codes[at].tobytes().decode("ascii")


def _fields(spans):
    """``{role: (source, start, end, text)}`` of a target's spans (a `SpanRow`'s without a `Span` object each)."""
    if isinstance(spans, SpanRow):
        return spans.fields()
    return {role: (span.source, span.start, span.end, span.text) for role, span in spans.items()}


def _number_or_text(text):
    """A span's number, or its text where it is none (a name, a bit string)."""
    try:
        return float(text)
    except ValueError:
        return text


def patched(program, encode, min_places, columns=None, extra=None):
    """The program's sources with the edited targets rewritten (see `target_edits`), each a `Patched`: the bytes
    to write, made while they are written.

    The targets of a table whose spans are columns, encoded by ``columns``,
    are encoded a batch at a time as their source is written, when the
    batches lie one after the other in its text (a long program's
    declarations, one a line, in order): the write holds neither the
    output nor all its edits (1,000,000 KRL points: 220 MB of edits).

    Parameters
    ----------
    program, encode, min_places, columns
        As `target_edits`.
    extra : sequence of list of (start, end, text), optional
        More edits per source (a KRL program's new name), none overlapping a target's numbers.

    Returns
    -------
    list of Patched
    """
    extra = extra or [[] for _ in program.sources]
    targets = program.targets
    table = targets.table if isinstance(targets, TargetRows) else None
    streamed = None  # the source whose edits are made while it is written
    if (columns is not None and table is not None and isinstance(table.spans, SpanColumns)
            and not program.sources[table.spans.source].companion and _batches_in_order(table)):
        streamed, edits = table.spans.source, [Edits.of([]) for _ in program.sources]
    else:
        edits = target_edits(program, encode, min_places, columns)
    out = []
    for k, source in enumerate(program.sources):
        if k == streamed:
            out.append(Patched(source, lambda k=k: _placed(_column_batches(table, columns, min_places), extra[k])))
        else:
            out.append(Patched(source, lambda k=k: _placed([edits[k]], extra[k]), bool(len(edits[k]) or extra[k])))
    return out


def _placed(batches, extra):
    """`Edits` in text order, batch after batch, with a few ``extra`` edits ``[(start, end, text)]`` put in place:
    as a batch of their own between two, or joined into the batch among whose edits they fall."""
    extra = sorted(extra)
    for edits in batches:
        if len(edits) and extra:
            before = [e for e in extra if e[1] <= edits.start[0]]
            inside = [e for e in extra[len(before):] if e[0] < edits.end[-1]]
            extra = extra[len(before) + len(inside):]
            if before:
                yield Edits.of(before)
            if inside:
                edits = Edits.joined([edits, Edits.of(inside)])
        yield edits
    if extra:
        yield Edits.of(extra)

TEXT_PIECE = 2**20  # characters of a text's unedited end encoded at a time


class Patched:
    """The bytes of a source's text with edits applied: an iterable of pieces, each made when the iteration reaches
    it (`trajcomp.support.atomic.write_files_atomic` writes them as they come; the whole output is never held).

    Parameters
    ----------
    source : Source
        The text and its encoding.
    batches : callable
        ``batches() -> iterable of Edits``: the edits, in text order batch after batch.
    changed : bool
        Whether any edit is written (a source whose edits are made while it is written counts as changed).
    """

    def __init__(self, source, batches, changed=True):
        self.source, self.batches, self.changed = source, batches, changed

    def __iter__(self):
        encoder = codecs.getincrementalencoder(self.source.encoding)()
        text, position = self.source.text, 0
        yield encode_text(self.source, "", encoder)  # the encoding's mark (a UTF-8 BOM), if it has one
        for edits in self.batches():
            for block in edits.blocks(text, position):
                yield encode_text(self.source, block, encoder)
            if len(edits):
                position = int(edits.end[-1])
        for start in range(position, len(text), TEXT_PIECE):
            yield encode_text(self.source, text[start:start + TEXT_PIECE], encoder)


def where(target):
    """A target named for messages: ``p10 (line 12)``, or ``line 12`` for an inline one."""
    return f"{target.name} (line {target.line})" if target.name else f"line {target.line}"


def apply_edits(text, edits):
    """``text`` with ``(start, end, replacement)`` edits applied (non-overlapping)."""
    out, position = [], 0
    for start, end, replacement in sorted(edits):
        out.append(text[position:start])
        out.append(replacement)
        position = end
    out.append(text[position:])
    return "".join(out)


def encode_text(source, text, encoder=None):
    """Bytes of ``text`` in the source's encoding (``encoder``: an incremental encoder of it, for a text encoded in
    pieces).

    Raises
    ------
    WriteError
        A character the encoding cannot hold (only possible in new text).
    """
    try:
        return text.encode(source.encoding) if encoder is None else encoder.encode(text)
    except UnicodeEncodeError as exc:
        raise WriteError(f"{source.name}: {exc.object[exc.start:exc.end]!r} cannot be written in "
                         f"{source.encoding}") from exc
