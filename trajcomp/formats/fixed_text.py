"""Rows of cells as text, vectorized: numbers as ``"%.<d>f"`` writes them, built as bytes for a whole block at once.

Formatting a float with Python's ``%`` costs about 0.2 us, and a long CSV
program writes millions. Here a block's rows are laid out as one byte
matrix, a row of cells per row, each cell in a fixed-width field padded
with NUL bytes that are dropped at the end; the digits of a number column
come from integer arithmetic on its rounded, scaled values, a few
nanoseconds a digit. The text is character for character the one ``%``
writes. The scaled value ``v * 10**d`` is the true product correctly
rounded (``10**d`` is exact), and rounding is monotonic: where the
product is not exactly a half, it rounds to the same whole number as the
true one. A product that is exactly a half (a tie, or a value either side
of one), a non-finite value and one of more than 15 digits are formatted
by Python instead.
"""

import dataclasses

import numpy as np

_SAFE = 2.0**52  # scaled magnitudes below this are whole numbers and halves exactly


def joined_rows(columns):
    """The text of N rows of cells: cells joined by ``,``, rows by ``\\n`` (no final ``\\n``).

    Parameters
    ----------
    columns : list
        Each either ``(values, places)``: floats (N,) written as ``"%.<places>f" % value`` (``places`` 0 to 15;
        0 writes no point), or a sequence of N str cells written as they are (holding no NUL character, which
        a text file read never has: `trajcomp.formats.text.read_source`).

    Returns
    -------
    str
        ``"\\n".join(",".join(row) for row in rows)`` of the formatted cells.
    """
    fields = [_Fixed.of(*column) if isinstance(column, tuple) else _cell_bytes(column) for column in columns]
    if not fields or not fields[0].shape[0]:
        return ""
    widths = [field.shape[1] for field in fields]
    layout = np.zeros((fields[0].shape[0], sum(widths) + len(widths)), dtype=np.uint8)  # a field and a , per cell
    at = 0
    for field, width in zip(fields, widths):
        if isinstance(field, _Fixed):
            field.write(layout[:, at : at + width])
        else:
            layout[:, at : at + width] = field
        layout[:, at + width] = 44  # ,
        at += width + 1
    layout[:, -1] = 10  # \n in place of the row's last ,
    return layout.tobytes().translate(None, b"\0")[:-1].decode("utf-8")


def _cell_bytes(cells):
    """Cells (N,) (str) as their UTF-8 bytes (N, W) uint8, left-aligned, NUL-padded."""
    try:
        array = np.array(cells, dtype="S")
    except UnicodeEncodeError:
        array = np.array([cell.encode("utf-8") for cell in cells], dtype="S")
    return array.view(np.uint8).reshape(len(array), array.itemsize)


@dataclasses.dataclass(frozen=True)
class _Fixed:
    """A column of numbers as ``"%.<places>f"`` text: their rounded, scaled magnitudes and field width.

    Attributes
    ----------
    values : ndarray, shape (N,)
        The floats.
    places : int
        Digits after the point.
    units : ndarray of int64, shape (N,)
        ``|value| * 10**places`` rounded half to even, as the true product
        rounds (0 for the rows formatted by Python).
    doubtful : ndarray of bool, shape (N,)
        Rows formatted by Python (`texts`).
    texts : list of str
        Their texts.
    """

    values: np.ndarray
    places: int
    units: np.ndarray
    doubtful: np.ndarray
    texts: list

    @classmethod
    def of(cls, values, places):
        values = np.asarray(values, dtype=float)
        with np.errstate(over="ignore", invalid="ignore"):  # of huge and non-finite values: formatted by Python
            scaled = np.abs(values * np.power(10.0, places))  # exact: within half an ulp of the true product;
            # inf beyond 308 places (a mutated number's), which Python then formats
            doubtful = (scaled - np.floor(scaled) == 0.5) | ~(scaled < _SAFE)
        units = np.rint(np.where(doubtful, 0.0, scaled)).astype(np.int64)
        texts = [f"{v:.{places}f}" for v in values[doubtful].tolist()]
        return cls(values, places, units, doubtful, texts)

    @property
    def shape(self):
        """``(N, W)``: W the longest text, a sign and a point included."""
        whole = len(str(int(self.units.max(initial=0)) // 10**self.places))
        width = 1 + whole + self.places + (1 if self.places else 0)
        return len(self.values), max(width, *map(len, self.texts)) if self.texts else width

    def write(self, out):
        """Write the texts into ``out`` (N, W) uint8 of NUL bytes, right-aligned."""
        places, units = self.places, self.units
        column = out.shape[1]
        first = np.full(len(units), column - 1 - places - (1 if places else 0))  # the column of a text's first digit
        for k in range(column - 1 - (1 if places else 0)):  # the last place first, every digit a field can hold
            column -= 1
            if k == places and places:
                out[:, column] = 46  # .
                column -= 1
            tens = units // 10
            digit = units - 10 * tens + 48
            if k > places:  # a leading zero of the integer part is no digit
                digit *= units > 0
                first -= units > 0
            out[:, column] = digit
            units = tens
        negative = np.flatnonzero(np.signbit(self.values) & ~self.doubtful)  # -0.0 and what rounds to 0 too, as %
        out[negative, first[negative] - 1] = 45  # -
        if self.texts:
            width = out.shape[1]
            padded = np.array([text.rjust(width, "\0") for text in self.texts], dtype=f"S{width}")
            out[self.doubtful] = padded.view(np.uint8).reshape(len(padded), width)
