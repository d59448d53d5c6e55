"""Numbers written as a robot program writes them: decimals, rounding that never speeds up, no ``-0``."""

import math
import re

import numpy as np

from trajcomp.formats.fixed_text import joined_rows
from trajcomp.formats.number_fields import decimals, read_numbers, text_codes


def ceil_places(value, places):
    """``value`` rounded up at ``places`` decimals (a time written never shorter than timed)."""
    return math.ceil(value * 10**places - 1e-9) / 10**places


def floor_places(value, places):
    """``value`` rounded down at ``places`` decimals, at least one unit of the last (a speed written never faster
    than timed, never 0)."""
    return max(math.floor(value * 10**places + 1e-9), 1) / 10**places


def format_number(value, places):
    """``value`` with ``places`` decimals, never ``-0``."""
    text = f"{value:.{places}f}"
    return text[1:] if float(text) == 0.0 and text.startswith("-") else text


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
