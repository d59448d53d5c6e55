"""Numbers written in a text, read from their characters at once: the bulk readers' parser.

A CAM program states millions of numbers. Taking each as a Python str
(a regular expression's groups) and converting it costs about 1 us a
number; here the readers give the offsets of the fields and the digits
are read with integer arithmetic on the text's character codes, a block
of fields at a time (`_from_characters`). A number of at most 15 digits
is read exactly as ``float`` reads it: its digits make a whole number
below 2**53 and the power of ten between it and its value (places and
exponent) is exact up to 10**22, so their product or quotient, correctly
rounded, is the decimal correctly rounded. The other fields (more digits,
a larger power) are read by ``float`` once per distinct text where they
match `NUMBER`; anything else is no number.
"""

import dataclasses
import re

import numpy as np

NUMBER = r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?"  # a number as the robot languages write one (ASCII digits)
FIELDS_AT_ONCE = 65536  # fields laid out as a (width, fields) matrix together: bounds the matrices' memory
_WIDEST = 24  # characters of the widest field read from its digits (more: read by `float`)
_DIGITS = 15  # at most this many digits make a whole number below 2**53
_EXACT_POWER = 22  # 10.0**k is exact for |k| <= 22
_NUMBER = re.compile(NUMBER)
_PLUS, _MINUS, _POINT, _ZERO, _NINE, _E, _LOWER_E = map(ord, "+-.09Ee")


def decimals(text):
    """Number of digits after the decimal point in a number's text."""
    mantissa = re.split(r"[eE]", text)[0]
    return len(mantissa.split(".")[1]) if "." in mantissa else 0


def is_bare(text):
    """Whether a number's text starts with its point, after a sign (``.5``, ``-.5``): a file that writes no 0."""
    return text.startswith((".", "-.", "+."))


def text_codes(text):
    """The character codes (L,) of a text, indexed by its str offsets: uint8 for ASCII text, else uint32.

    Parameters
    ----------
    text : str
        A program's text (`trajcomp.programs.items.Source.text`).

    Returns
    -------
    ndarray, shape (L,)
        ``codes[k] == ord(text[k])``.
    """
    if text.isascii():
        return np.frombuffer(text.encode("ascii"), dtype=np.uint8)
    return np.frombuffer(text.encode("utf-32-le"), dtype=np.uint32)


def offset_type(text):
    """The integer type of offsets into ``text`` a table keeps: int32 where they fit (half the bytes of int64)."""
    return np.int32 if len(text) < 2**31 else np.int64


@dataclasses.dataclass(frozen=True)
class WrittenNumbers:
    """N fields of a text read as numbers, and how each is written (what a writer formats new numbers like).

    Attributes
    ----------
    values : ndarray of float, shape (N,)
        ``float(field)``; NaN where the field is no number.
    is_number : ndarray of bool, shape (N,)
        Whether the field is a number as `NUMBER` states one (no blank, no ``inf``).
    places : ndarray of int, shape (N,)
        Digits after its point, before an exponent (`decimals`).
    bare : ndarray of bool, shape (N,)
        Whether the field starts with its point (`is_bare`).
    """

    values: np.ndarray
    is_number: np.ndarray
    places: np.ndarray
    bare: np.ndarray

    @classmethod
    def of(cls, codes, start, end):
        """The fields ``text[start:end]`` (N,) of a text's character codes (`text_codes`), read at once."""
        start, end = np.asarray(start, dtype=np.int64), np.asarray(end, dtype=np.int64)
        blocks = [_from_characters(codes, start[k:k + FIELDS_AT_ONCE], end[k:k + FIELDS_AT_ONCE])
                  for k in range(0, len(start), FIELDS_AT_ONCE)]
        values, read, places, bare = (np.concatenate(column) for column in zip(*blocks)) if blocks else \
            dataclasses.astuple(cls.none(0))
        is_number = read.copy()
        other = np.flatnonzero(~read)
        if len(other):  # by float, once per distinct text
            texts = ["".join(map(chr, codes[a:b].tolist())) for a, b in zip(start[other].tolist(), end[other].tolist())]
            number = {text: float(text) if _NUMBER.fullmatch(text) else None for text in set(texts)}
            is_number[other] = [number[text] is not None for text in texts]
            values[other] = [np.nan if number[text] is None else number[text] for text in texts]
            places[other] = [decimals(text) for text in texts]
            bare[other] = [is_bare(text) for text in texts]
        return cls(values, is_number, places, bare)

    @classmethod
    def none(cls, n):
        """N fields that are no number (NaN, no places, not bare)."""
        return cls(np.full(n, np.nan), np.zeros(n, dtype=bool), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=bool))

    def at(self, rows, n):
        """These M numbers as rows (M,) of N fields, the others no number (`none`)."""
        out = WrittenNumbers.none(n)
        for column, values in zip((out.values, out.is_number, out.places, out.bare),
                                  (self.values, self.is_number, self.places, self.bare)):
            column[rows] = values
        return out


def read_numbers(codes, start, end):
    """Values of N numbers written at ``text[start:end]``, read at once (`WrittenNumbers`).

    Parameters
    ----------
    codes : ndarray, shape (L,)
        The text's character codes (`text_codes`).
    start, end : array_like of int, shape (N,)
        Offsets of each field (``end`` excluded), as a regular expression gives them on the text.

    Returns
    -------
    values : ndarray of float, shape (N,)
        ``float(text[start:end])``; NaN where the field is no number.
    is_number : ndarray of bool, shape (N,)
        Whether the field is a number as `NUMBER` states one (no blank, no ``inf``).
    """
    numbers = WrittenNumbers.of(codes, start, end)
    return numbers.values, numbers.is_number


def _from_characters(codes, start, end):
    """Values (B,) of B fields read from their characters, whether each was read so, its places and whether it
    starts with its point (`WrittenNumbers`).

    Read so: a number as `NUMBER` states one (an
    optional sign, digits with at most one point, an optional exponent
    ``e[+-]digits``) of at most 15 digits before the exponent and at most
    22 powers of ten between its digits and its value (``10**22`` is the
    largest exact power); the others are left to ``float`` (`read_numbers`).
    The characters are laid out one row per column of the fields (W, B)
    and read a column at a time, left to right, as a whole number
    ``mantissa``, the digits after the point ``places`` and the exponent;
    B fields that repeat one text are read once.
    """
    width = end - start
    widest = int(min(width.max(initial=0), _WIDEST))
    column = np.arange(widest)[:, None]
    inside = column < width
    char = codes[np.minimum(start + column, len(codes) - 1)].astype(np.int64)
    char[~inside] = 0
    n = len(start)
    if n > 1 and (width == width[0]).all() and (char == char[:, :1]).all():  # one text (an unused axis' 9E+09)
        return tuple(np.repeat(column, n) for column in _from_characters(codes, start[:1], end[:1]))
    mantissa, places, count, points, exponent, exponent_digits = (np.zeros(n, dtype=np.int64) for _ in range(6))
    bad, in_exponent, after_e, exponent_negative = (np.zeros(n, dtype=bool) for _ in range(4))
    for j in range(widest):
        c = char[j]
        digit = (c >= _ZERO) & (c <= _NINE)
        point, e = c == _POINT, (c == _E) | (c == _LOWER_E)
        sign = (c == _PLUS) | (c == _MINUS)
        whole = digit & ~in_exponent
        mantissa = np.where(whole, mantissa * 10 + c - _ZERO, mantissa)
        places += whole & (points > 0)
        count += whole
        points += point
        power = digit & in_exponent
        exponent = np.where(power, exponent * 10 + c - _ZERO, exponent)
        exponent_digits += power
        exponent_negative |= after_e & (c == _MINUS)
        bad |= inside[j] & ~(digit | point | e | sign)
        bad |= (point & in_exponent) | (e & (in_exponent | (count == 0))) | (sign & ~after_e & (j > 0))
        in_exponent |= e
        after_e = e
    shift = np.where(exponent_negative, -exponent, exponent) - places  # value = mantissa * 10**shift
    read = ~bad & (points <= 1) & (count >= 1) & (count <= _DIGITS) & (width <= _WIDEST)
    read &= ~in_exponent | ((exponent_digits >= 1) & (exponent_digits <= 3) & (np.abs(shift) <= _EXACT_POWER))
    shift = np.where(read, shift, 0)
    whole = mantissa.astype(float)
    magnitude = np.where(shift >= 0, whole * 10.0 ** np.maximum(shift, 0), whole / 10.0 ** np.maximum(-shift, 0))
    first, second = (char[k] if k < widest else np.zeros(n, dtype=np.int64) for k in (0, 1))
    bare = np.where((first == _PLUS) | (first == _MINUS), second, first) == _POINT
    return np.where(read, np.where(first == _MINUS, -magnitude, magnitude), np.nan), read, places, bare


# The characters around the numbers: how the bulk readers find the lines and fields they read at once.

def character_table(characters):
    """Whether each code (256,) is one of ``characters`` (ASCII; `spelt` makes a code beyond ASCII 127)."""
    table = np.zeros(256, dtype=bool)
    table[np.frombuffer(characters.encode("ascii"), dtype=np.uint8)] = True
    return table


WORD_CHARACTER = character_table("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_")
DIGIT = character_table("0123456789")
BLANK = character_table(" \t")
_UPPER = np.arange(256, dtype=np.uint8)  # an ASCII text's codes in upper case (its bytes: uint8)
_UPPER[ord("a"):ord("z") + 1] -= 32
_UPPER[128:] = 127


def spelt(codes, at, width):
    """The upper-case ASCII codes (K, width) of the ``width`` characters from offsets ``at`` (K,) (127 beyond ASCII;
    the text's last character repeated beyond its end)."""
    spelt_codes = codes.take(at[:, None] + np.arange(width), mode="clip")
    return _UPPER[spelt_codes if codes.dtype == np.uint8 else np.minimum(spelt_codes, 127)]


def spells(codes, at, word):
    """Whether the text spells ``word`` (upper case ASCII) from each offset ``at`` (K,), in any case."""
    return starts_with(spelt(codes, at, len(word)), word)


def starts_with(spelt_codes, word):
    """Whether each row of characters (..., W) `spelt` gives starts with ``word`` (upper case ASCII, at most W)."""
    return (spelt_codes[..., :len(word)] == np.frombuffer(word.encode("ascii"), dtype=np.uint8)).all(axis=-1)


def line_bounds(codes):
    """Offsets (L+1,) of the lines' starts (the text's start and each ``\\n``'s next) and of their ``\\n`` (the
    text's end for the last): where a `re.M` pattern's ``^`` and ``$`` match."""
    newline = np.flatnonzero(codes == ord("\n"))
    return np.concatenate([[0], newline + 1]), np.append(newline, len(codes))
