"""What the CSV reader and writer share (see `trajcomp.formats.csv`): the column names, the block size, and
the helpers that split a text into lines and a line into cells, give a cell's value, tell a statement line from a
target row and read a column of number cells at once (`_numbers`, `_canonical`)."""

import re

import numpy as np

POSE = ("x", "y", "z", "a", "b", "c")
JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
BLOCK = 16_384  # rows parsed or formatted together: vectorized, with bounded temporary memory
_QUOTED_COMMA = re.compile(r',(?=(?:[^"]*"[^"]*")*[^"]*$)')  # a comma outside double quotes


def _split(text):
    """The lines of a text and the line endings after them: ``text == "".join(interleaved)``.

    Returns
    -------
    lines : list of str
        Without line endings; the empty piece after a final line ending included.
    endings : list of str
        ``\n``, ``\r\n`` or ``\r`` after each line but the last.
    """
    if "\r" not in text:
        lines = text.split("\n")
        return lines, ["\n"] * (len(lines) - 1)
    parts = re.split(r"(\r\n|\r|\n)", text)
    return parts[0::2], parts[1::2]


def _cells(line):
    """The raw cells of a CSV line: ``",".join(cells) == line``; commas inside quotes kept."""
    return _QUOTED_COMMA.split(line) if '"' in line else line.split(",")


def _value(cell):
    """A cell's value: stripped, quotes removed."""
    value = cell.strip()
    if len(value) > 1 and value[0] == value[-1] == '"':
        return value[1:-1].replace('""', '"')
    return value


def _is_statement(line):
    stripped = line.lstrip()
    return not stripped or stripped[0] == "#"


def _numbers(cells):
    """Values (B,) of a column's cells (B,) (NaN where empty) and which are empty; values None if a cell is no number.

    Canonical numbers (`_canonical`, the common case) are read from their
    digits at once; a column with a non-ASCII character or ``_`` is no
    number (as `trajcomp.formats.text.finite` reads one); a column of few distinct cells (speeds, zones) converts
    each distinct one; other plain numbers are converted from the Python
    str at once; cells with quotes or empty ones go through a str array.
    """
    found = _canonical(cells) if len(cells) else None
    if found is not None and found[1] is not None:
        return found[1], np.zeros(len(cells), dtype=bool)
    joined = "".join(cells)
    if not joined.isascii() or "_" in joined:  # float() reads -62_8.0 and full-width digits: no number here
        return None, np.zeros(len(cells), dtype=bool)
    distinct = set(cells) if len(cells) >= 64 else None
    try:
        if distinct is not None and len(distinct) <= len(cells) // 8:
            distinct = list(distinct)
            lookup = dict(zip(distinct, np.array(distinct, dtype=float).tolist()))
            return np.fromiter(map(lookup.__getitem__, cells), dtype=float, count=len(cells)), \
                np.zeros(len(cells), dtype=bool)
        return np.array(cells, dtype=float), np.zeros(len(cells), dtype=bool)
    except ValueError:
        pass
    text = _stripped(cells)
    empty = text == ""
    number = np.full(len(cells), np.nan)
    try:
        number[~empty] = text[~empty].astype(float)
    except ValueError:
        return None, empty
    return number, empty


def _stripped(cells):
    """The values (B,) of cells (B,) as a str array: spaces and surrounding quotes removed."""
    text = np.array(cells, dtype=str)
    if _plain(cells):
        return text
    text = np.strings.strip(text)
    return np.where(np.strings.startswith(text, '"'), np.strings.strip(np.strings.strip(text, '"')), text)


_ASCII_NUMBER = np.zeros(256, dtype=bool)
_ASCII_NUMBER[np.frombuffer(b"0123456789-.,", dtype=np.uint8)] = True


def _canonical(cells, values=True):
    """``(d, values)`` if every cell (str, B > 0) is a number as ``%.<d>f`` writes it, with the same ``d``, else None.

    Canonical: an optional ``-``, an integer part without leading zeros, a
    point and ``d`` digits; no sign ``+``, exponent, space, quote or
    negative zero. Two such texts of at most 15 digits are equal exactly
    when they read as the same float. ``values`` (B,) are the floats the
    cells state (exactly ``float(cell)``: an integer of at most 15 digits
    divided by ``10**d``, both exact, the division correctly rounded), or
    None for a cell of more digits (or when not asked for).
    """
    first = cells[0]
    dot = first.find(".")
    if dot < 0:
        return None
    places = len(first) - dot - 1
    joined = ",".join(cells) + ","
    try:
        data = np.frombuffer(joined.encode("ascii"), dtype=np.uint8)
    except UnicodeEncodeError:
        return None
    if not _ASCII_NUMBER[data].all():
        return None
    ends = np.flatnonzero(data == 44)
    dots = np.flatnonzero(data == 46)
    if len(ends) != len(cells) or len(dots) != len(cells) or np.any(ends - dots != places + 1):
        return None
    starts = np.concatenate([[0], ends[:-1] + 1])
    negative = data[starts] == 45
    digits = starts + negative  # where the integer part begins
    if np.count_nonzero(data == 45) != np.count_nonzero(negative) or np.any(dots <= digits):
        return None  # a - inside a number, or no integer digit (.5, -.5, -)
    if np.any((data[digits] == 48) & (dots != digits + 1)):
        return None  # a leading zero
    if negative.any() and "-0." + "0" * places + "," in joined:  # a - only starts a cell
        return None  # -0.000
    width = int((ends - digits).max())  # digits and the point
    if width - 1 > 15 or not values:
        return places, None
    at = ends[:, None] - width + np.arange(width)  # each cell right-aligned: the point in one column
    digit = np.where(at >= digits[:, None], data[np.maximum(at, 0)].astype(np.int64) - 48, 0)
    mantissa = np.delete(digit, width - 1 - places, axis=1) @ 10 ** np.arange(width - 2, -1, -1, dtype=np.int64)
    return places, np.where(negative, -mantissa, mantissa) / 10.0**places


def _plain(texts):
    """Whether no text (sequence of str) holds a quote, space or tab: cells then are their values."""
    joined = "".join(texts)
    return not ('"' in joined or " " in joined or "\t" in joined)
