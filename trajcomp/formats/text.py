"""Reading a program's source: decoding, masking, lines, statements and checked fields, shared by the readers.

Readers decode a file once (keeping its line endings and encoding), find
statements with regular expressions on a *masked* copy of the text (comments
and string contents blanked, same length, so offsets stay valid) and record
the span of every number a compensation may change. Writers replace only
the numbers of edited targets, formatted like the file wrote them
(`trajcomp.formats.text_edits`).
"""

import array
import bisect
import dataclasses
import math
import re
from pathlib import Path

import numpy as np

from trajcomp.errors import ReadError
from trajcomp.formats.number_fields import text_codes
from trajcomp.programs.items import CIRCULAR, Source, Span

# Magnitudes no robot program states: beyond them a number is a typo or damage, not a position.
LENGTH_LIMIT = 1e6  # mm (a kilometre)
ANGLE_LIMIT = 1e4  # deg
JOINT_LIMIT = 3600.0  # deg (ten turns)
_BRACKET_OR_COMMA = re.compile(r"[{}\[\](),]")  # what `split_top` looks at


LINE_LIMIT = 1 << 20  # bytes in one line (1 MiB): thousands of times the longest line a robot program writes
# A line's start and its indent, taken whole: a pattern failing after it does not give the blanks back one at a time
# (a blanked comment line of LINE_LIMIT blanks cost 0.15 s per pattern that way; with this, 0.02 s)
INDENT = r"^[ \t]*(?![ \t])"


def read_source(path, name=None, companion=False):
    """Decode a text file exactly: UTF-8 (with or without BOM), else Latin-1.

    ``companion``: the file is read for the points a program uses from it (`Source`).

    Raises
    ------
    ReadError
        Unreadable, binary (NUL bytes), or a line longer than `LINE_LIMIT`
        (damage or not a program: parsing it would take memory and time
        out of proportion to the file).
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ReadError(f"{path}: cannot read: {exc.strerror}") from exc
    if b"\0" in data:
        raise ReadError(f"{path}: not a text file")
    if (start := _long_line_start(data)) >= 0:
        line = data.count(b"\n", 0, start) + data.count(b"\r", 0, start) - data.count(b"\r\n", 0, start) + 1
        raise ReadError(f"{name or path.name}:{line}: a line longer than {LINE_LIMIT:,} bytes, beyond any robot "
                        f"program's (damaged, or not a program): {data[start:start + 40].decode('latin-1')!r}...")
    encoding = "utf-8-sig" if data.startswith(b"\xef\xbb\xbf") else "utf-8"
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError:
        encoding = "latin-1"
        text = data.decode(encoding)
    return Source(name or path.name, text, encoding, str(path), companion)


def _long_line_start(data, piece=1 << 22):
    """Offset of the first line of ``data`` (bytes) longer than `LINE_LIMIT`, -1 if none; looked at ``piece``
    bytes at a time."""
    if len(data) <= LINE_LIMIT:
        return -1
    start = 0  # of the line running into the piece
    for at in range(0, len(data), piece):
        codes = np.frombuffer(data, np.uint8, count=min(piece, len(data) - at), offset=at)
        ends = np.flatnonzero((codes == ord("\n")) | (codes == ord("\r"))) + at
        starts = np.append(start, ends + 1)
        long = np.flatnonzero(np.append(ends, at + len(codes)) - starts > LINE_LIMIT)
        if len(long):
            return int(starts[long[0]])
        start = int(starts[-1])
    return -1


def mask(text, comment, quote='"'):
    """``text`` with comments (from ``comment`` to the line end) and string contents blanked.

    The result has the same length and line breaks, so offsets and line
    numbers found in it hold for ``text``. Scanned left to right: a comment
    mark inside a string and a quote inside a comment are plain text. The
    marks are looked for with ``str.find`` (each mark's next one found once
    for the stretch up to it), not a pattern tried at every character: a
    long program with few comments is scanned at memory speed.

    A line ending that is a carriage return alone (old Mac text, some
    controllers' exports) becomes a line feed here, so that the readers'
    patterns (``^``, ``$``, ``\n``) see its lines; the source text, and so
    what is written, keeps it.
    """
    if "\r" in text:
        text = _LONE_CARRIAGE_RETURN.sub("\n", text)
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


def statement_text(masked, start, end):
    """``masked[start:end]`` without the blanks a comment left at its end (`mask`): a statement's patterns are not
    run over a blanked comment's length (each pattern that fails on a line would look at every blank again)."""
    return masked[start:end].rstrip(" \t")


def code_of(text, comment):
    """A statement's ``text`` without its comments and strings (`mask`) nor the blanks they leave at its end."""
    return statement_text(mask(text, comment), 0, len(text))


_NOT_LINE_BREAK = re.compile(r"[^\r\n]")
_LONE_CARRIAGE_RETURN = re.compile(r"\r(?!\n)")


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


def check_closed(source, masked, opener, closer, closing, parts=None, outside=None):
    """Refuse a text whose blocks are not closed in order: a file cut off in transfer, or one its controller
    refuses to load.

    Every controller refuses such a file (a syntax error on loading, or
    when the program is selected); a reader that took it would compensate
    and write the part that arrived as if it were the whole program. A
    block closed by the keyword of a block around it (``END`` while an
    ``IF`` is open), a closing keyword with no block to close, and (with
    ``outside``) a statement outside every block are refused the same way.

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
    outside : re.Pattern, optional
        The lines that may stand outside every block (a KRL ``&ACCESS``
        line, RAPID's ``%%%`` header); blank and comment lines may too.
        None: any line may (URScript's top-level statements).

    Raises
    ------
    ReadError
        Naming the line and the keyword of the block left open, or the
        line out of place.
    """
    parts = [(0, len(masked))] if parts is None else parts
    marks = sorted([(m.start(), m.group(1).upper(), opens) for start, end in parts
                    for pattern, opens in ((opener, True), (closer, False))
                    for m in pattern.finditer(masked, start, end)])
    lines = Lines(source.text)

    def refuse(at, message):
        line = lines.number(at)
        fail(source.name, line, lines.line(line), message)

    open_blocks, outermost = [], []  # the blocks open, and the (start, end) offsets of those closed around no other
    for at, keyword, opens in marks:
        if opens:
            open_blocks.append((at, keyword))
        elif open_blocks and closing[open_blocks[-1][1]] == keyword:
            start, _ = open_blocks.pop()
            if not open_blocks:
                outermost.append((start, at))
        elif open_blocks and keyword in (closing[k] for _, k in open_blocks):
            inner_at, inner = open_blocks[-1]
            refuse(inner_at, f"{inner} has no {closing[inner]} before the {keyword} of line {lines.number(at)}")
        else:
            refuse(at, f"{keyword} closes no block")
    if open_blocks:
        at, keyword = open_blocks[-1]
        refuse(at, f"{keyword} has no {closing[keyword]} (the text ends at line {last_line(lines)}): "
                   "the program is cut off")
    if outside is not None:
        gaps = zip([0] + [masked.find("\n", end) % (len(masked) + 1) for _, end in outermost],
                   [start for start, _ in outermost] + [len(masked)])
        for start, end in gaps:
            for m in _STATEMENT_LINE.finditer(masked, start, end):
                if not outside.match(m.group()):
                    first = next(iter(closing))
                    refuse(m.start(), f"a statement outside every {first} ... {closing[first]} block")


_STATEMENT_LINE = re.compile(r'^[ \t"]*[^\s"].*$', re.M)  # a masked line with more than blanks and quotes


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
