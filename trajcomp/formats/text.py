"""Source-preserving text helpers shared by the format modules.

Readers decode a file once (keeping its line endings and encoding), find
statements with regular expressions on a *masked* copy of the text (comments
and string contents blanked, same length, so offsets stay valid) and record
the span of every number a compensation may change. Writers replace only
the numbers of edited targets, formatted like the file wrote them.
"""

import array
import bisect
import codecs
import dataclasses
import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError, WriteError
from trajcomp.formats.fixed_text import joined_rows
from trajcomp.formats.number_fields import NUMBER, WrittenNumbers, decimals, is_bare, read_numbers, text_codes
from trajcomp.programs.items import CIRCULAR, Source, Span, SpanColumns, SpanRow, replaced
from trajcomp.programs.tables import ItemRows, Picked, StatementTable, TargetRows
from trajcomp.arm.transforms import abc_to_matrix, matrix_to_abc
from trajcomp.support.memory import collection_paused

# Magnitudes no robot program states: beyond them a number is a typo or damage, not a position.
LENGTH_LIMIT = 1e6  # mm (a kilometre)
ANGLE_LIMIT = 1e4  # deg
JOINT_LIMIT = 3600.0  # deg (ten turns)
_BRACKET_OR_COMMA = re.compile(r"[{}\[\](),]")  # what `split_top` looks at


def read_source(path, name=None, companion=False):
    """Decode a text file exactly: UTF-8 (with or without BOM), else Latin-1.

    ``companion``: the file is read for the points a program uses from it (`Source`).

    Raises
    ------
    ReadError
        Unreadable, or binary (NUL bytes).
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ReadError(f"{path}: cannot read: {exc.strerror}") from exc
    if b"\0" in data:
        raise ReadError(f"{path}: not a text file")
    encoding = "utf-8-sig" if data.startswith(b"\xef\xbb\xbf") else "utf-8"
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError:
        encoding = "latin-1"
        text = data.decode(encoding)
    return Source(name or path.name, text, encoding, str(path), companion)


def mask(text, comment, quote='"'):
    """``text`` with comments (from ``comment`` to the line end) and string contents blanked.

    The result has the same length and line breaks, so offsets and line
    numbers found in it hold for ``text``. Scanned left to right: a comment
    mark inside a string and a quote inside a comment are plain text. The
    marks are looked for with ``str.find`` (each mark's next one found once
    for the stretch up to it), not a pattern tried at every character: a
    long program with few comments is scanned at memory speed.
    """
    if quote not in text and comment not in text:  # a statement's line, mostly
        return text
    end = len(text)
    found = {}  # mark -> its first offset at or after where the scan stands (end: none)

    def next_at(mark, start):
        at = found.get(mark, -1)
        if at < start:
            at = text.find(mark, start)
            found[mark] = at = end if at < 0 else at
        return at

    pieces, position = [], 0
    while (start := min(next_at(quote, position), next_at(comment, position))) < end:
        pieces.append(text[position:start])
        if next_at(quote, position) == start:  # a string: its contents to the closing quote (or the end) blanked
            close = next_at(quote, start + 1)
            pieces += (quote, _NOT_LINE_BREAK.sub(" ", text[start + 1:close]), text[close:close + 1])
            position = close + 1
        else:  # a comment, to its line's end
            position = min(next_at("\r", start), next_at("\n", start))
            pieces.append(" " * (position - start))
    pieces.append(text[position:])
    return "".join(pieces)


_NOT_LINE_BREAK = re.compile(r"[^\r\n]")


class Lines:
    """Line numbers (1-based) of offsets in a text, and its lines without line endings.

    ``starts``: the lines' start offsets, an ``array.array`` of int64 (8 bytes a
    line, not a Python int each; `numpy.asarray` views it).
    """

    PIECE = 1 << 22  # characters looked at together for line endings

    def __init__(self, text):
        self.text = text
        self.starts = array.array("q", [0])
        if text.isascii():  # a long program's line endings found at once: "\r\n", a "\r" alone, "\n"
            for at in range(0, len(text), self.PIECE):  # a piece at a time: a few MB of codes, not the text's size
                codes = text_codes(text[at:at + self.PIECE + 1])  # and the next character: "\r" ends a line alone
                line_feed = codes == ord("\n")
                ends = line_feed | ((codes == ord("\r")) & ~np.append(line_feed[1:], False))
                self.starts.frombytes((np.flatnonzero(ends[:self.PIECE]) + at + 1).astype(np.int64).tobytes())
        else:
            self.starts.extend(m.end() for m in re.finditer(r"\r\n|\r|\n", text))

    def number(self, offset):
        """Line number of a character offset."""
        return bisect.bisect_right(self.starts, offset)

    def __iter__(self):
        """``(number, start, end)`` of every line; ``end`` excludes the line ending."""
        for k, start in enumerate(self.starts):
            stop = self.starts[k + 1] if k + 1 < len(self.starts) else len(self.text)
            line = self.text[start:stop].rstrip("\r\n")
            if k + 1 == len(self.starts) and not line:
                return
            yield k + 1, start, start + len(line)

    def line(self, number):
        """The text of line ``number`` without its line ending."""
        start = self.starts[number - 1]
        end = self.starts[number] if number < len(self.starts) else len(self.text)
        return self.text[start:end].rstrip("\r\n")


def split_top(text, offset=0):
    """``[(piece, start)]`` of ``text`` split at commas outside braces, brackets and parentheses.

    ``start`` is the piece's offset in the source (``offset`` is where ``text`` begins).
    """
    parts, depth, start = [], 0, 0
    for m in _BRACKET_OR_COMMA.finditer(text):  # the other characters count for nothing: skipped by the regex
        ch = m.group()
        if ch in "{[(":
            depth += 1
        elif ch in "}])":
            depth -= 1
        elif depth == 0:
            k = m.start()
            parts.append((text[start:k], offset + start))
            start = k + 1
    parts.append((text[start:], offset + start))
    return parts


def fail(source_name, line, text, message):
    """Raise a ReadError naming file, line, the problem and the offending text."""
    raise ReadError(f"{source_name}:{line}: {message}: {text.strip()[:200]!r}")


def runs_between(start, end, length):
    """``(start, end)`` offsets of the runs of text between N lines read at once, the parts `check_closed` scans.

    Parameters
    ----------
    start, end : ndarray of int, shape (N,)
        Offsets of the lines read at once (each to its line break), ascending.
    length : int
        Length of the text.

    Returns
    -------
    list of (int, int)
        The runs longer than the line break between two such lines.
    """
    part_start, part_end = np.append(0, end), np.append(start, length)
    between = np.flatnonzero(part_end - part_start > 1)
    return list(zip(part_start[between].tolist(), part_end[between].tolist()))


def check_closed(source, masked, opener, closer, closing, parts=None):
    """Refuse a text whose last block is never closed: a file cut off in transfer.

    Every controller refuses such a file (a syntax error on loading, or
    when the program is selected); a reader that took it would compensate
    and write the part that arrived as if it were the whole program.

    Parameters
    ----------
    source : Source
        The text read (its name is used in the message).
    masked : str
        ``source.text`` with comments and strings blanked (`mask`).
    opener, closer : re.Pattern
        Line patterns (``re.M``) of the statements that open and close a
        block, group 1 their keyword (``DEF``, ``PROC``; ``END``, ``ENDPROC``).
    closing : Mapping[str, str]
        The closing keyword of each opening keyword (upper case).
    parts : list of (int, int), optional
        ``(start, end)`` offsets of whole lines of ``masked`` where a block
        may open or close, the others known to do neither (a reader's
        motion lines: not scanned); default the whole text.

    Raises
    ------
    ReadError
        A block open at the end of the text, naming its line and the
        keyword that should close it.
    """
    parts = [(0, len(masked))] if parts is None else parts
    marks = sorted([(m.start(), m.group(1).upper(), opens) for start, end in parts
                    for pattern, opens in ((opener, True), (closer, False))
                    for m in pattern.finditer(masked, start, end)])
    open_blocks = []
    for at, keyword, opens in marks:
        if opens:
            open_blocks.append((at, keyword))
        elif open_blocks and closing[open_blocks[-1][1]] == keyword:
            open_blocks.pop()
    if open_blocks:
        at, keyword = open_blocks[-1]
        lines = Lines(source.text)
        line = lines.number(at)
        fail(source.name, line, lines.line(line),
             f"{keyword} has no {closing[keyword]} (the text ends at line {last_line(lines)}): the program is cut off")


def last_line(lines):
    """The number of the last line of `Lines` that holds more than white space (1 for an empty text)."""
    return lines.number(max(len(lines.text.rstrip()) - 1, 0))


def finite(text, source_name, line, original, field, limit=math.inf):
    """The float a number's text states; ReadError naming the field if it is not a number within ``limit``.

    A number is written in ASCII digits without ``_`` (Python's float reads
    ``-62_8.0`` and full-width digits; no controller does).
    """
    try:
        if not text.isascii() or "_" in text:
            raise ValueError(text)
        value = float(text)
    except ValueError:
        fail(source_name, line, original, f"{field}: not a number {text[:40]!r}")
    if not math.isfinite(value) or abs(value) > limit:
        fail(source_name, line, original, f"{field}: {text[:40]!r} is out of range" +
             (f" (beyond +-{limit:g})" if math.isfinite(limit) else ""))
    return value


def integer(text, source_name, line, original, field):
    """The integer a number's text states (``2``, ``2.0``); ReadError if it is not a whole number."""
    value = finite(text, source_name, line, original, field)
    if value != int(value):
        fail(source_name, line, original, f"{field}: {text[:40]!r} is not a whole number")
    return int(value)


def unresolved(source_name, missing, hint):
    """ReadError listing motions whose point cannot be resolved: ``missing`` is ``[(name, line)]``."""
    shown = ", ".join(f"{name} (line {line})" for name, line in missing[:10])
    more = f" and {len(missing) - 10} more" if len(missing) > 10 else ""
    raise ReadError(f"{source_name}: motions to points the program does not define: {shown}{more}; {hint}")


class DeclaredElsewhere:
    """Where the other files of a program's controller declare and assign a point: RAPID modules of the same
    task, KUKA data lists beside the program and ``$config.dat``. Read only when a program names a point it
    does not declare itself, or one that other files may change.

    Parameters
    ----------
    path : Path
        The program's file (not searched).
    folders : sequence of Path
        Folders whose files are searched (missing ones are skipped).
    extensions : sequence of str
        Extensions of the files that declare points, lower case with the dot.
    pattern : re.Pattern
        Group 1: the declared point's name, in the file's masked text.
    comment : str
        The language's comment mark (`mask`).
    assignment : re.Pattern, optional
        Group 1: the name of a point a statement gives a value (``p10 :=``, ``XP1 =``), per line.
    code : sequence of str, optional
        Extensions of the files whose statements may assign points (default: ``extensions``).
    visible : callable, optional
        ``visible(file, match) -> bool``: whether a declaration ``pattern`` matched is seen by the program
        (a KUKA point of another data list only if GLOBAL); default all.
    """

    def __init__(self, path, folders, extensions, pattern, comment, assignment=None, code=None, visible=None):
        self.path, self.folders, self.extensions = Path(path), list(folders), set(extensions)
        self.pattern, self.comment, self.assignment = pattern, comment, assignment
        self.code, self.visible = set(code or extensions), visible or (lambda file, match: True)
        self.found, self.assignments = None, None

    def _files(self, extensions):
        for folder in self.folders:
            if folder.is_dir():
                for file in sorted(folder.iterdir()):
                    if file != self.path and file.suffix.lower() in extensions and file.is_file():
                        yield file

    def _masked(self, file):
        """The masked text of a file and its `Lines`, or None for a binary or unreadable one (it declares nothing)."""
        try:
            text = mask(read_source(file).text, self.comment)
        except ReadError:
            return None
        return text, Lines(text)

    def find(self, name):
        """``(file, line)`` of another file's declaration of point ``name`` (matched without case), or None."""
        if self.found is None:
            self.found = {}
            for file in self._files(self.extensions):
                if (masked := self._masked(file)) is not None:
                    for m in self.pattern.finditer(masked[0]):
                        if self.visible(file, m):
                            self.found.setdefault(m.group(1).lower(), (file, masked[1].number(m.start())))
        return self.found.get(name.lower())

    def where(self, name):
        """``"file:line"`` of another file's declaration of point ``name``, or ``""``."""
        found = self.find(name)
        return f"{found[0].name}:{found[1]}" if found else ""

    def assigned(self, name):
        """``"file:line"`` of another file's statement giving point ``name`` a value at run time, or ``""``."""
        if self.assignment is None:
            return ""
        if self.assignments is None:
            self.assignments = {}
            for file in self._files(self.code):
                if (masked := self._masked(file)) is not None:
                    text, lines = masked
                    for number, start, end in lines:
                        if m := self.assignment.match(text[start:end]):
                            self.assignments.setdefault(m.group(1).lower(), f"{file.name}:{number}")
        return self.assignments.get(name.lower(), "")


def whole_circle(motion):
    """A circular motion with both its via and end point, or none of them (run time).

    A circle whose via or end point is computed at run time cannot be
    compensated half: both then pass through, named in ``refs``.
    """
    if motion.kind != CIRCULAR or (motion.via is None) == (motion.target is None):
        return motion
    known = tuple(i for i in (motion.via, motion.target) if i is not None)
    return dataclasses.replace(motion, target=None, via=None, refs=motion.refs + known,
                               reason=motion.reason or "circle point computed at run time")


def spans(source, match, roles, offset=0):
    """``{role: Span}`` of the groups of a regex match; ``roles`` names groups 1, 2, ...

    ``offset`` is added to the match positions (when the regex ran on a slice).
    """
    out = {}
    for k, role in enumerate(roles, start=1):
        if role is None or match.group(k) is None:
            continue
        start, end = match.span(k)
        out[role] = Span(source, start + offset, end + offset, match.group(k))
    return out


def name_span(piece, at, source):
    """Where the point name a motion argument ``piece`` (at offset ``at``) starts with stands (`Span`), or None.

    Per-use copies of a point (`trajcomp.formats.uses`) rename it there.
    """
    offsets = name_offsets(piece, at)
    return None if offsets is None else Span(source, *offsets, piece[offsets[0] - at:offsets[1] - at])


def name_offsets(piece, at):
    """``(start, end)`` in the source of the point name a motion argument ``piece`` (at offset ``at``) starts
    with, or None: `name_span` without its object (a reader that keeps its spans as `SpanColumns`)."""
    m = _LEADING_NAME.match(piece)
    return None if m is None else (at + m.start(1), at + m.end(1))


_LEADING_NAME = re.compile(r"\s*([A-Za-z_$][\w$]*)")


def values(spans_, roles):
    """The numbers of some roles as floats."""
    return [float(spans_[role].text) for role in roles]


def ceil_places(value, places):
    """``value`` rounded up at ``places`` decimals (a time written never shorter than timed)."""
    return math.ceil(value * 10**places - 1e-9) / 10**places


def floor_places(value, places):
    """``value`` rounded down at ``places`` decimals, at least one unit of the last (a speed written never faster
    than timed, never 0)."""
    return max(math.floor(value * 10**places + 1e-9), 1) / 10**places


def written_speed(motion, language):
    """``(speed, unit)`` a generated program of ``language`` (a registered name) writes for ``motion``.

    Raises
    ------
    WriteError
        A speed in a unit the language does not state (its format's
        ``speed_units``): the program must be converted into it first
        (`trajcomp.compensation.program_rewrite.convert_program`), never written faster.
    """
    from trajcomp.formats import find_format

    units = find_format(format=language).speed_units[motion.kind]
    if motion.speed is not None and motion.speed_unit not in units:
        raise WriteError(f"line {motion.line}: a {motion.kind} motion's speed in {motion.speed_unit} cannot be written "
                         f"in {language} (convert the program into it first: its speeds are converted no faster)")
    return motion.speed, motion.speed_unit


def format_number(value, places):
    """``value`` with ``places`` decimals, never ``-0``."""
    text = f"{value:.{places}f}"
    return text[1:] if float(text) == 0.0 and text.startswith("-") else text


def same_rotation(rot, old_rot):
    """Whether rotations (..., 3, 3) equal the ones the file states (...): their numbers then stay as written."""
    return np.abs(np.subtract(rot, old_rot)).max(axis=(-2, -1), initial=0.0) <= 1e-12


def turned_abc(rotation, old_abc):
    """The rows whose rotation differs from the file's, and their A, B, C nearest the file's.

    Parameters
    ----------
    rotation : ndarray, shape (N, 3, 3)
    old_abc : ndarray, shape (N, 3)
        A, B, C the file states, deg (R = Rz(A) Ry(B) Rx(C)).

    Returns
    -------
    turned : ndarray of bool, shape (N,)
    abc : ndarray, shape (T, 3)
        A, B, C of the T turned rows, deg, each shifted by whole turns nearest the old one.
    """
    turned = ~same_rotation(rotation, abc_to_matrix(np.radians(old_abc)))
    return turned, near_angle(np.degrees(matrix_to_abc(rotation[turned])), old_abc[turned])


def encode_xyzabc(poses, olds, roles):
    """Numbers of poses (N, 4, 4) as x, y, z (mm) and A, B, C (deg, R = Rz(A) Ry(B) Rx(C)): a dict each.

    ``roles`` names the six numbers in that order (FANUC: x, y, z, r, p, w).
    The angles are chosen nearest the file's ``olds`` (N dicts), and left
    out where the rotation is the one the file states.
    """
    old_abc = np.array([[old[role] for role in roles[3:]] for old in olds], dtype=float).reshape(-1, 3)
    turned, abc = turned_abc(poses[:, :3, :3], old_abc)
    angles = iter(abc.tolist())
    return [dict(zip(roles[:3], position)) | (dict(zip(roles[3:], next(angles))) if turn else {})
            for position, turn in zip(poses[:, :3, 3].tolist(), turned.tolist())]


def encode_targets(targets, olds, joints, cartesian):
    """The numbers of targets in a language (`target_edits`), the Cartesian ones computed together.

    Parameters
    ----------
    targets : list of Target
    olds : list of dict
        Each target's numbers in the file, ``{role: float or str}``.
    joints : callable
        ``joints(target) -> {role: value}`` of a joint target.
    cartesian : callable
        ``cartesian(targets, olds) -> list of {role: value}`` of the
        Cartesian targets (vectorized over them).
    """
    out = [joints(target) if target.is_joint else None for target in targets]
    rows = [k for k, numbers in enumerate(out) if numbers is None]
    for k, numbers in zip(rows, cartesian([targets[k] for k in rows], [olds[k] for k in rows]) if rows else ()):
        out[k] = numbers
    return out


def near_angle(angle, reference, period=360.0):
    """``angle`` (scalar or array) shifted by whole periods to be closest to ``reference``."""
    return angle - period * np.round((np.asarray(angle) - reference) / period)


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

    EDITS_AT_ONCE = 8192  # edits whose pieces are joined together (`applied`): a few MB of pieces at a time

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
        piece_start, piece_length = np.empty((2, 2 * (hi - lo)), dtype=np.int64)  # kept, replacement, kept, ...
        piece_start[0::2], piece_length[0::2] = kept_from - position, start - kept_from
        piece_start[1::2], piece_length[1::2] = len(source) + cut[:-1] - cut[0], np.diff(cut)
        shift = piece_start - (np.cumsum(piece_length) - piece_length)  # from a piece's place out to its codes
        return codes[np.repeat(shift, piece_length) + np.arange(int(piece_length.sum()))].tobytes().decode("ascii")


def _fields(spans):
    """``{role: (source, start, end, text)}`` of a target's spans (a `SpanRow`'s without a `Span` object each)."""
    if isinstance(spans, SpanRow):
        return spans.fields()
    return {role: (span.source, span.start, span.end, span.text) for role, span in spans.items()}


def column_decimals(texts):
    """Digits after the decimal point of number texts (N,) (`decimals`), ndarray of int."""
    texts = np.asarray(texts, dtype=str)
    dot = np.strings.find(texts, ".")
    places = np.where(dot >= 0, np.strings.str_len(texts) - dot - 1, 0)
    exponent = (np.strings.find(texts, "e") >= 0) | (np.strings.find(texts, "E") >= 0)
    places[exponent] = [decimals(t) for t in texts[exponent]]
    return places


def written_numbers(values, bare, old_values, places):
    """How a file writes new numbers over old ones, all at once: what `format_number` writes each.

    Parameters
    ----------
    values : ndarray, shape (N,)
        The new numbers (finite).
    bare : ndarray of bool, shape (N,)
        Whether the old text writes a bare point (`trajcomp.formats.number_fields.is_bare`).
    old_values : ndarray, shape (N,)
        The old numbers (NaN where the old text is none).
    places : ndarray of int, shape (N,)
        Decimals to write each with.

    Returns
    -------
    changed : ndarray of bool, shape (N,)
        False where the new text reads back equal to the old number (the
        old text then stays).
    texts : list of str
        ``"%.<places>f"`` of each value, never ``-0``; ``.5`` without its
        0 where the old text wrote a bare point.
    """
    texts, read_back = np.empty(len(values), dtype=object), np.empty(len(values))
    for p in np.unique(places).tolist():
        pick = np.flatnonzero(places == p)
        block = joined_rows([(values[pick], p)])
        codes = text_codes(block)
        ends = np.append(np.flatnonzero(codes == 10), len(codes))
        read_back[pick] = read_numbers(codes, np.append(0, ends[:-1] + 1), ends)[0]
        texts[pick] = block.split("\n")
    for k in np.flatnonzero(np.signbit(values) & (values > -(10.0 ** -places))).tolist():  # what may write -0
        if float(texts[k]) == 0.0:
            texts[k] = texts[k][1:]
    texts = texts.tolist()
    changed = read_back != old_values
    for k in np.flatnonzero(changed & bare).tolist():  # the file writes .5, not 0.5
        texts[k] = BARE_ZERO.sub(r"\1.", texts[k], count=1)
    return changed, texts


BARE_ZERO = re.compile(r"^(-?)0\.")  # the 0 of 0.5 and -0.5, for a file that writes .5


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


def check_writable(program):
    """WriteError naming the first target, tool, frame or motion that cannot become robot code.

    Robot code must never receive ``nan`` or ``inf``, nor a circle without
    its via point; every writer is fed through this check
    (`trajcomp.formats.write`).
    """
    motions, targets = program.motion_table(), program.target_table()
    used = np.zeros(len(targets), dtype=bool)
    used[motions.target[motions.target >= 0]] = used[motions.via[motions.via >= 0]] = True
    used = np.flatnonzero(used)  # the targets used, ascending (as np.unique, without its sort or hash of every index)
    pose, joints = targets.pose, targets.joints  # judged whole, then the used picked: no copy of the arrays
    bad_pose = (np.isinf(pose).any(axis=(1, 2)) | (~targets.is_joint & np.isnan(pose).any(axis=(1, 2))))[used]
    stated = ~np.isnan(joints).all(axis=1)  # NaN: no joints
    bad_joints = (stated & ~np.isfinite(joints).all(axis=1))[used]
    for what, bad in (("pose", bad_pose), ("joints", bad_joints)):
        if bad.any():
            raise WriteError(f"target {program.where(used[np.argmax(bad)])}: {what} not finite, nothing written")
    for i in used.tolist():
        external = targets.external[i]
        if external is not None and np.isinf(external).any():  # NaN: an unused axis
            raise WriteError(f"target {program.where(i)}: external axes not finite, nothing written")
    for kind, table in (("tool", program.tools), ("frame", program.frames)):
        for name, T in table.items():
            if not np.isfinite(T).all():
                raise WriteError(f"{kind} {name}: value not finite, nothing written")
    circle_without_via = (motions.kind == CIRCULAR) & (motions.target >= 0) & (motions.via < 0)
    bad_speed = ~np.isnan(motions.speed) & ~np.isfinite(motions.speed)
    bad_zone = ~np.isnan(motions.zone) & ~np.isfinite(motions.zone)
    for bad, problem in ((circle_without_via, "a circle needs its via point"), (bad_speed, "speed not finite"),
                         (bad_zone, "zone not finite")):
        if bad.any():
            m = program.motions[int(np.argmax(bad))]
            raise WriteError(f"motion at line {m.line} ({m.text[:60]}): {problem}, nothing written")


def active_axes(program, capacity, language):
    """External axes a generated program writes: those a used target gives a value other than 0.

    A program without external axes may still state them as 0 (KUKA E1..E6):
    those are left out of languages that do not need them.

    Parameters
    ----------
    capacity : int
        How many external axes a point of the language holds.
    language : str
        For the message.

    Returns
    -------
    list of int
        Axis indices (0 = E1), ascending.

    Raises
    ------
    WriteError
        An axis with a value beyond what the language holds: dropping it
        would move the program elsewhere.
    """
    used = sorted({i for m in program.motions for i in (m.target, m.via) if i is not None})
    first = {}  # axis -> the index of the first target giving it a value
    for i in used:
        external = program.targets[i].external
        if external is not None:
            for k, v in enumerate(external):
                if not np.isnan(v) and v != 0.0:
                    first.setdefault(k, i)
    beyond = sorted(k for k in first if k >= capacity)
    if beyond:
        raise WriteError(f"{language} points hold {capacity} external axes; target {program.where(first[beyond[0]])} gives "
                         f"E{beyond[0] + 1} a value: it cannot be written without changing what the program does")
    active = set(first)
    return sorted(active)


def write_single_file(program, path, format_name, encode, min_places, emit, columns=None):
    """``{path: bytes or Patched}`` of a one-file language.

    The program's source patched in place (see `patched`, ``encode`` and
    ``columns`` as `target_edits` takes them) when it was read from
    ``format_name``; otherwise ``emit(program, path.stem)`` generated as
    UTF-8 text.
    """
    path = Path(path)
    if program.format == format_name and program.sources:
        written = patched(program, encode, min_places, columns)
        return {path: written[0]} | companion_outputs(program, written, path)
    return {path: emit(program, path.stem).encode("utf-8")}


def companion_outputs(program, written, path, own=1):
    """``{file: Patched}`` of a program's sources beyond the ``own`` first ones (those written as ``path``).

    Each lies where it lay relative to the program's first file (another
    module of its task beside it, ``../System/$config.dat`` of a KUKA
    backup); a companion (`Source`) is written only when its points changed.
    `trajcomp.formats.write` refuses a file that would land outside the
    output's folder.

    Parameters
    ----------
    program : Program
    written : sequence of Patched
        Every source as written (`patched`).
    path : Path
        Where the program's first file is written.
    own : int
        How many first sources the language's writer places itself.
    """
    home = Path(program.sources[0].path).parent
    return {Path(path).parent / os.path.relpath(source.path, home): patch
            for source, patch in zip(program.sources[own:], written[own:])
            if not (source.companion and not patch.changed)}


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


def numbered(names):
    """Map tool or frame names to controller numbers: numeric names keep theirs, others get free ones."""
    taken = {int(n) for n in names if n is not None and str(n).isdigit()}
    out, free = {None: 0}, 1
    for name in names:
        if name in out:
            continue
        if str(name).isdigit():
            out[name] = int(name)
            continue
        while free in taken:
            free += 1
        out[name] = free
        taken.add(free)
    return out


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


TEXT_BLOCK = 65536  # texts made at a time when `Texts` are iterated


class Texts(Sequence):
    """Non-empty texts of waypoints lo .. hi - 1 made on demand (a long program's settings without a str each).

    Parameters
    ----------
    make : callable
        ``make(lo, hi) -> list of str``: the texts of waypoints lo .. hi - 1,
        none empty.
    lo, hi : int
    """

    def __init__(self, make, lo, hi):
        self.make, self.lo, self.hi = make, lo, max(hi, lo)

    def __len__(self):
        return self.hi - self.lo

    def __getitem__(self, i):
        if isinstance(i, slice):
            start, stop, step = i.indices(len(self))
            if step != 1:
                return tuple(self)[i]
            return Texts(self.make, self.lo + start, self.lo + stop)
        i = i + len(self) if i < 0 else i
        if not 0 <= i < len(self):
            raise IndexError("text index out of range")
        return self.make(self.lo + i, self.lo + i + 1)[0]

    def __iter__(self):
        for lo in range(self.lo, self.hi, TEXT_BLOCK):
            yield from self.make(lo, min(lo + TEXT_BLOCK, self.hi))

    def __eq__(self, other):
        if not isinstance(other, (tuple, list, Texts)):
            return NotImplemented
        return len(self) == len(other) and all(a == b for a, b in zip(self, other))

    def __hash__(self):
        return hash(tuple(self))

    def __repr__(self):
        shown = "" if not len(self) else f": {self[0]!r}" if len(self) == 1 else f": {self[0]!r} .. {self[-1]!r}"
        return f"Texts({len(self)} texts{shown})"
