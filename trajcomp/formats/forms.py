"""Statement forms: a line of a language declared once as a sequence of elements, run two ways.

A `Form` compiles to a regular expression matched on one line at a time
(`Form.regex`, what the statement-by-statement read and any line the other
strategy leaves use), and runs over many lines at once on their
characters' codes (`Form.find`, a `Cursor` moved element by element: no
Python object per line). Both give the same groups, as ``Match.regs``
gives them. Run at once, each element takes the first way the pattern
tries (an `Optional` or a `Repeat` as many times as it is there, the
first alternative of an `Either` that is there) and a line that then
fails is dropped, never tried another way; an element that has no
vectorised run (a `Number` that states no ``ends_before``) is taken as
absent: a line that holds it fails there (or leaves the `Optional`
around it) and is left to the pattern. So the lines found at once are a
subset of those the pattern matches, with the same groups (the pattern
being greedy, its first match is the one found at once); but for what
lies inside a `Value` or a `Number` run at once, which the one reading
its fields checks.

`written_lines` runs a language's forms over a text both ways: the lines
found at once, the others matched by the forms' patterns one by one.
"""

import re

import numpy as np

from trajcomp.formats.number_fields import (
    BLANK, NUMBER, WORD_CHARACTER, character_table, line_bounds, offset_type, spelt, starts_with,
)


class Cursor:
    """Offsets into a text, one in each of K lines, moved over its characters at once.

    Parameters
    ----------
    codes : ndarray, shape (L,)
        The text's character codes (`trajcomp.formats.number_fields.text_codes`).
    line_end : ndarray of int, shape (K,)
        Offset of each line's end (its line ending excluded): no character is read there or after.
    span : (int, int), optional
        The part of the text `find` looks in (offsets ``[lo, hi)``): the whole text if not given.
    """

    def __init__(self, codes, line_end, span=None, _found=None):
        self.codes, self.line_end = codes, line_end
        self.span = (0, len(codes)) if span is None else span
        self._found = {} if _found is None else _found  # characters -> their offsets in `span`, shared by `of`
        self._word = None  # the last `word` asked: (at, its end), reused while the same array is asked again

    def of(self, rows):
        """The cursor of lines ``rows`` (K',) of these."""
        return Cursor(self.codes, self.line_end[rows], self.span, self._found)

    def _code(self, at):
        code = self.codes[np.minimum(at, len(self.codes) - 1)]
        return np.where(at < self.line_end, np.minimum(code, 127), 0)  # 0: past the line's end, 127: not ASCII

    def char(self, at, character):
        """Whether each line has ``character`` at ``at`` (K,)."""
        return self._code(at) == ord(character)

    def spells(self, at, lower, letter):
        """Whether each line has a text (ASCII) from ``at`` (K,): ``lower`` (W,) its codes in lower case, ``letter``
        (W,) bool where it has a letter (either case there)."""
        offsets = at[:, None] + np.arange(len(lower))
        code = self.codes[np.minimum(offsets, len(self.codes) - 1)]
        code = np.where(offsets < self.line_end[:, None], np.minimum(code, 127), 0)
        return (np.where(letter, code | 0x20, code) == lower).all(axis=1)

    def among(self, at, table):
        """Whether each line has a character of ``table`` (`character_table`) at ``at`` (K,)."""
        return table[self._code(at)]

    WINDOW = 8  # characters first looked at together on each line; doubled for the lines still in a run
    LOOKED_AT = 1 << 22  # characters looked at together at most (over all lines in a run)

    def skip(self, at, table):
        """The first offset at or after ``at`` (K,) whose character is not in ``table`` (`character_table`).

        The characters are looked at a window at a time, over the lines
        still in a run, the window doubled each time (up to `LOOKED_AT`
        characters in all): a run of n characters takes about log2(n)
        steps and 2n characters looked at, a megabyte of blanked comment
        milliseconds (a column at a time, it took 13 s).
        """
        at = np.array(at, dtype=np.int64)
        last = len(self.codes) - 1
        moving = np.flatnonzero((at < self.line_end) & table[np.minimum(self.codes[np.minimum(at, last)], 127)])
        width = self.WINDOW  # the lines whose first character is out of the run (most: no blank) are done
        while len(moving):
            window = at[moving, None] + np.arange(width)
            inside = window < self.line_end[moving, None]
            in_run = inside & table[np.minimum(self.codes[np.minimum(window, last)], 127)]
            run = np.argmin(in_run, axis=1)  # the first character out of the run: 0 where all are in it
            ended = ~in_run[np.arange(len(moving)), run]
            at[moving] += np.where(ended, run, width)
            moving = moving[~ended]
            width = max(self.WINDOW, min(2 * width, self.LOOKED_AT // max(len(moving), 1)))
        return at

    def blanks(self, at):
        """The first offset at or after ``at`` (K,) not blank."""
        return self.skip(at, BLANK)

    def word(self, at):
        """The end of the word (ASCII ``\\w+``) at ``at`` (K,): ``at`` itself where none starts."""
        if self._word is None or self._word[0] is not at:  # each form's first word is the same (`find_lines`)
            self._word = at, self.skip(at, WORD_CHARACTER)
        return self._word[1]

    def keyword(self, at, words, word_end=None):
        """The end of the one of ``words`` (upper case ASCII, whole words, any case) at ``at`` (K,); -1 where none.
        ``word_end``: `word` of ``at`` if known."""
        end = np.full(len(at), -1)
        length = (self.word(at) if word_end is None else word_end) - at
        for word in words:
            rows = np.flatnonzero(length == len(word))
            whole = rows[starts_with(spelt(self.codes, at[rows], len(word)), word)]
            end[whole] = at[whole] + len(word)
        return end

    def find(self, at, characters, count=1):
        """The offset of the ``count``-th of ``characters`` (any of them) at or after ``at`` (K,) in `span`; -1 where
        it holds fewer."""
        if characters not in self._found:
            lo, hi = self.span
            block = self.codes[lo:hi]
            self._found[characters] = np.flatnonzero(np.logical_or.reduce([block == ord(c) for c in characters])) + lo
        offsets = self._found[characters]
        if not len(offsets):
            return np.full(len(at), -1)
        k = np.searchsorted(offsets, at) + count - 1
        found = k < len(offsets)
        return np.where(found, offsets[np.where(found, k, 0)], -1)


class Element:
    """A part of a form: its pattern (`pattern`) and its run over K lines at once (`run`)."""

    groups = 0  # the groups it holds

    def pattern(self):
        """Its regular expression (flags ``re.I | re.M``)."""
        raise NotImplementedError

    def run(self, cursor, at, found):
        """The offsets (K,) after the element on each line from ``at`` (K,) and whether it is there (K,) bool;
        its groups' ``(start, end)`` (each (K, 2)) appended to ``found``."""
        raise NotImplementedError


class Blank(Element):
    """Blanks (spaces, tabs): any number, or at least one (``required``)."""

    def __init__(self, required=False):
        self.required = required

    def pattern(self):
        return r"[ \t]+" if self.required else r"[ \t]*"

    def run(self, cursor, at, found):
        end = cursor.blanks(at)
        return end, (end > at) if self.required else np.ones(len(at), dtype=bool)


class Literal(Element):
    """These characters (``:=``, ``,``, ``X ``; letters in any case, as the form's pattern reads them)."""

    def __init__(self, text):
        self.text = text
        self.lower, self.letter = np.array([ord(c) for c in text.lower()]), np.array([c.isalpha() for c in text])

    def pattern(self):
        return re.escape(self.text)

    def run(self, cursor, at, found):
        return at + len(self.text), cursor.spells(at, self.lower, self.letter)


class Words(Element):
    """One of these words (ASCII, any case), ended where the next element starts."""

    def __init__(self, *words):
        self.words = words

    def pattern(self):
        return "(?:" + "|".join(map(re.escape, self.words)) + ")"

    def run(self, cursor, at, found):
        end = cursor.keyword(at, [w.upper() for w in self.words])
        return end, end >= 0


class Name(Element):
    """A word (``\\w+``).

    Parameters
    ----------
    first : str, optional
        The characters its first may be (a character class's inside, ASCII: ``A-Za-z`` for a letter).
    ascii : bool
        Its characters ASCII word characters only (``[A-Za-z0-9_]``).
    excluding : tuple of str
        Words it is not (whole words, any case).
    """

    def __init__(self, first=None, ascii=False, excluding=()):
        self.first, self.ascii, self.excluding = first, ascii, tuple(w.upper() for w in excluding)
        self.starts = first and character_table("".join(
            chr(c) for c in range(128) if re.fullmatch(f"[{first}]", chr(c), re.I)))

    def pattern(self):
        rest = "[A-Za-z0-9_]" if self.ascii else r"\w"
        not_word = "(?!(?:" + "|".join(map(re.escape, self.excluding)) + r")\b)" if self.excluding else ""
        return not_word + (f"[{self.first}]{rest}*" if self.first else rest + "+")

    def run(self, cursor, at, found):
        end = cursor.word(at)
        there = end > at
        if self.first:
            there &= cursor.among(at, self.starts)
        if self.excluding:
            there &= cursor.keyword(at, self.excluding, end) < 0
        return end, there


class Number(Element):
    """A number as the robot languages write one (`trajcomp.formats.number_fields.NUMBER`), or as ``pattern`` states.

    Run at once where ``ends_before`` is given: the characters up to the
    first of those (at least one), what they hold checked by the one
    reading them (`trajcomp.formats.number_fields.read_numbers`); else
    not run at once (the line is left to the pattern).
    """

    def __init__(self, pattern=NUMBER, ends_before=None):
        self.number, self.ends_before = pattern, ends_before

    def pattern(self):
        return self.number

    def run(self, cursor, at, found):
        if self.ends_before is None:
            return at, np.zeros(len(at), dtype=bool)
        end = cursor.find(at, self.ends_before)
        return end, (end > at) & (end < cursor.line_end)


class Value(Element):
    """A bracketed value laid out as ``layout`` (its delimiters, e.g. ``[[,,],[,,,]]``: each innermost list any
    characters but ``]``, a line break and ``;``). Run at once, its opening brackets are checked and its end
    found (after as many ``]`` as it has); what lies between is not: the one reading its fields checks it (a
    value not laid out so is left to the statement-by-statement read)."""

    def __init__(self, layout):
        self.layout = layout

    def pattern(self):
        return "".join(r"\[[^]\r\n;]*\]" if len(token) > 1 else re.escape(token)
                       for token in re.findall(r"\[[^][]*\]|.", self.layout))  # an innermost list: any such text

    def run(self, cursor, at, found):
        opening = len(self.layout) - len(self.layout.lstrip("["))
        there = np.ones(len(at), dtype=bool)
        for k in range(opening):
            there &= cursor.char(at + k, "[")
        end = cursor.find(at, "]", self.layout.count("]")) + 1
        return end, there & (end > 0)


class _Several(Element):
    """Elements together: their patterns joined by `joining` in a group that captures nothing, then `after`."""

    joining, after = "", ""

    def __init__(self, *elements):
        self.elements = elements
        self.groups = sum(e.groups for e in elements)

    def pattern(self):
        return "(?:" + self.joining.join(e.pattern() for e in self.elements) + ")" + self.after


class Optional(_Several):
    """Its elements, or nothing (a group inside: ``(-1, -1)`` where not taken). Run at once, taken where all its
    elements are there."""

    after = "?"

    def run(self, cursor, at, found):
        inner = []
        end, there = _run_all(self.elements, cursor, at, inner)
        for span in inner:
            span[~there] = -1
        found.extend(inner)
        return np.where(there, end, at), np.ones(len(at), dtype=bool)


class Repeat(_Several):
    """Its elements (no group among them: a pattern's repeated group holds its last repeat only), any number of
    times; run at once, as many times as they are there."""

    after = "*"

    def __init__(self, *elements):
        super().__init__(*elements)
        if self.groups:
            raise ValueError("a Repeat holds no group")

    def run(self, cursor, at, found):
        at, rows, moving = np.array(at), np.arange(len(at)), cursor
        while len(rows):
            end, there = _run_all(self.elements, moving, at[rows], [])
            there &= end > at[rows]  # an empty repeat ends them, as in the pattern
            rows = rows[there]
            at[rows] = end[there]
            moving = cursor.of(rows)
        return at, np.ones(len(at), dtype=bool)


class Either(_Several):
    """One of its elements (``a|b``): run at once, the first that is there; the groups of the others ``(-1, -1)``."""

    joining = "|"

    def run(self, cursor, at, found):
        end, there = np.full(len(at), -1, dtype=np.int64), np.zeros(len(at), dtype=bool)
        for alternative in self.elements:
            inner = []
            after, here = _run_all((alternative,), cursor, at, inner)
            taken = here & ~there
            for span in inner:
                span[~taken] = -1
            found.extend(inner)
            end[taken], there = after[taken], there | taken
        return end, there


class Group(Element):
    """Its elements, their text a group (``Match.group``); ``name``: the group's name (`Form.group`)."""

    def __init__(self, *elements, name=None):
        self.elements, self.name = elements, name
        self.groups = 1 + sum(e.groups for e in elements)

    def pattern(self):
        return ("(" if self.name is None else f"(?P<{self.name}>") + "".join(e.pattern() for e in self.elements) + ")"

    def run(self, cursor, at, found):
        inner = []
        end, there = _run_all(self.elements, cursor, at, inner)
        found.append(np.stack((at, end), axis=1))
        found.extend(inner)
        return end, there


class LineEnd(Element):
    """The end of the line (a ``\\r`` before its ``\\n`` allowed)."""

    def pattern(self):
        return r"\r?$"

    def run(self, cursor, at, found):
        return at, at == cursor.line_end


def _run_all(elements, cursor, at, found):
    """Run ``elements`` in order from ``at`` (K,), each on the lines where those before it are there (the others
    dropped: no work on them). The offsets after them (K,; -1 where not there), whether they are there (K,); their
    groups appended to ``found`` (each (K, 2); -1 on the lines an element before the group is not on)."""
    count, alive, spans = len(at), np.arange(len(at)), []
    for element in elements:
        inner = []
        at, here = element.run(cursor, at, inner)
        spans.extend((alive, span) for span in inner)
        if not here.all():
            kept = np.flatnonzero(here)
            alive, at, cursor = alive[kept], at[kept], cursor.of(kept)
    if len(alive) == count:  # every line there: no line's offsets to fill with -1
        found.extend(span for _, span in spans)
        return at, np.ones(count, dtype=bool)
    end, there = np.full(count, -1, dtype=np.int64), np.zeros(count, dtype=bool)
    end[alive], there[alive] = at, True
    for rows, span in spans:
        full = np.full((count, 2), -1, dtype=np.int64)
        full[rows] = span
        found.append(full)
    return end, there


class Form:
    """A statement written on one line: its elements, after any blanks at the line's start.

    Parameters
    ----------
    *elements : Element
        In order; the form's groups are those of its `Group` elements, numbered as in a regular expression.

    Attributes
    ----------
    regex : re.Pattern
        Its pattern (``re.I | re.M``), matched from a line's start to its end (``match(text, start, end)``).
    """

    def __init__(self, *elements):
        self.elements = (Blank(), *elements)
        self.regex = re.compile("".join(e.pattern() for e in self.elements), re.I | re.M)
        self.groups, self._named = self.regex.groups, dict(self.regex.groupindex)

    def group(self, *names):
        """The numbers of the groups named ``names`` (`Group`), as ``Match.regs`` indexes them (list of int)."""
        return [self._named[name] for name in names]

    def find(self, codes, starts, ends):
        """The lines written in this form, found at once from their characters.

        Parameters
        ----------
        codes : ndarray, shape (L,)
            The masked text's character codes (`trajcomp.formats.number_fields.text_codes`).
        starts, ends : ndarray of int, shape (B,)
            Offsets of the lines' starts and of their ``\\n`` (or the text's end), ascending.

        Returns
        -------
        rows : ndarray of int, shape (K,)
            The lines written so (indices into ``starts``): a subset of
            those `regex` matches (module docstring).
        regs : ndarray of int, shape (K, groups + 1, 2)
            Their matches' offsets as ``Match.regs`` gives them.
        """
        return find_lines([self], codes, starts, ends)[0]


def find_lines(forms, codes, starts, ends):
    """`Form.find` of each of ``forms`` over the same lines, the blanks at their starts skipped once: list of
    ``(rows, regs)``."""
    if not len(starts) or not len(codes):
        return [(np.zeros(0, dtype=np.int64), np.zeros((0, form.groups + 1, 2), dtype=np.int64)) for form in forms]
    carriage = (ends > starts) & (codes[np.maximum(ends - 1, 0)] == ord("\r"))
    cursor = Cursor(codes, ends - carriage, (int(starts[0]), int(ends[-1])))
    first = cursor.blanks(starts)  # every form starts with the blanks (`Form`)
    out = []
    for form in forms:
        found = []
        _, there = _run_all(form.elements[1:], cursor, first, found)
        rows = np.flatnonzero(there)
        spans = [np.stack((starts, ends), axis=1), *found]
        if len(rows) < len(starts):
            spans = [span[rows] for span in spans]
        out.append((rows, np.stack(spans, axis=1)))
    return out


LINES_AT_ONCE = 65536  # lines whose forms are found together (`written_lines`): bounds the arrays held


def written_lines(forms, masked, codes):
    """The lines written in each of ``forms``: found at once from their characters (`find_lines`), `LINES_AT_ONCE`
    lines at a time, the others matched by each form's pattern (`Form.regex`) one by one.

    Parameters
    ----------
    forms : sequence of Form
    masked : str
        The text, comments and strings blanked (`trajcomp.formats.text.mask`).
    codes : ndarray, shape (L,)
        Its character codes (`trajcomp.formats.number_fields.text_codes`).

    Returns
    -------
    list of ndarray, shape (N_k, groups_k + 1, 2)
        Per form, the offsets ``(start, end)`` of each line's match (from
        the line's start) and of each of its groups, as ``Match.regs``
        gives them (`offset_type`: int32 where they fit), ascending.
    """
    offset = offset_type(masked)
    starts, ends = line_bounds(codes)
    found = [[] for _ in forms]
    taken = np.zeros(len(starts), dtype=bool)
    for lo in range(0, len(starts), LINES_AT_ONCE):
        for k, (at, groups) in enumerate(find_lines(forms, codes, starts[lo:lo + LINES_AT_ONCE],
                                                    ends[lo:lo + LINES_AT_ONCE])):
            taken[lo + at] = True
            found[k].append(groups.astype(offset))
    others = np.flatnonzero(~taken).tolist()
    for k, form in enumerate(forms):
        matched = [m.regs for line in others if not masked[starts[line]:ends[line]].isspace()  # not a comment's line
                   and (m := form.regex.match(masked, int(starts[line]), int(ends[line])))]
        found[k].append(np.array(matched, dtype=offset).reshape(-1, form.groups + 1, 2))
    out = []
    for blocks in found:
        rows = np.concatenate([block for block in blocks if len(block)] or blocks[-1:])
        out.append(rows[np.argsort(rows[:, 0, 0], kind="stable")] if len(blocks[-1]) else rows)  # matched among them
    return out
