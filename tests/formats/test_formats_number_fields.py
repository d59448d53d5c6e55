"""Numbers read from a text's characters at once (`trajcomp.formats.number_fields`) against Python's own reading."""

import re

import numpy as np
import pytest

from trajcomp.formats.number_fields import (FIELDS_AT_ONCE, NUMBER, WrittenNumbers, decimals, is_bare, read_numbers,
                                            text_codes)


def _python(field):
    """What the one-by-one readers take: ``float`` of a field that matches NUMBER, else no number."""
    return float(field) if re.fullmatch(NUMBER, field) else None


def _check(fields, prefix=""):
    text, start, end = prefix, [], []
    for field in fields:
        start.append(len(text))
        text += field
        end.append(len(text))
        text += ";"
    values, is_number = read_numbers(text_codes(text), start, end)
    written = WrittenNumbers.of(text_codes(text), start, end)
    assert np.array_equal(written.values, values, equal_nan=True)
    for field, value, number, places, bare in zip(fields, values, is_number, written.places, written.bare):
        expected = _python(field)
        assert number == (expected is not None), field
        if number:  # how it is written, for a writer formatting a new number like it
            assert places == decimals(field) and bare == is_bare(field), field
        if expected is None:
            assert np.isnan(value), field
        else:  # the same float, sign of zero included
            assert value == expected and np.signbit(value) == np.signbit(expected), field


EDGES = ["0", "-0", "-0.000", "+0.5", ".5", "-.5", "5.", "-5.", "007.250", "123456789012345", "1234567890123456",
         "0.000000000000001", "12345678.9012345", "-1234567890.12345678901", "9E+09", "9e9", "-1.5e-3", "1e",
         "", "-", "+", ".", "-.", "1.2.3", "--1", "+-1", "1-", " 1", "1 ", "inf", "nan", "1_000", "0x10", "١٢",
         "1" * 30, "0." + "1" * 30, "1,5"]


def test_edge_fields_read_as_python_reads_them():
    _check(EDGES)


def test_non_ascii_text_offsets_are_str_offsets():
    _check(EDGES, prefix="Grüße, Ωmega: ")


def test_random_decimals_read_exactly_across_blocks():
    rng = np.random.default_rng(7)
    n = FIELDS_AT_ONCE + 5000  # more than one block
    magnitude = 10.0 ** rng.integers(-4, 8, n)
    numbers = rng.uniform(-1, 1, n) * magnitude
    places = rng.integers(0, 12, n)
    fields = [f"{v:.{p}f}" for v, p in zip(numbers, places)]
    fields[::97] = [f"{v:+.3f}" for v in numbers[::97]]  # signed
    fields[::101] = [f"{v:.6e}" for v in numbers[::101]]  # exponents: read by float
    _check(fields)


@pytest.mark.parametrize("field", ["9E+09", "0.0000000000", "-1", "1 ", "1e400", ""])
def test_a_repeated_field_reads_as_each_alone(field):
    """A block of one text repeated (a path's unused external axes) is read once: the same values."""
    _check([field] * (FIELDS_AT_ONCE + 3) + ["2.5", field])


def test_empty():
    values, is_number = read_numbers(text_codes(""), [], [])
    assert values.shape == is_number.shape == (0,)


@pytest.mark.parametrize("text", ["abc", "añb"])
def test_codes_index_by_str_offset(text):
    codes = text_codes(text)
    assert [chr(c) for c in codes.tolist()] == list(text)


def test_numbers_placed_among_fields_without_one():
    text = "1.50;-.25"
    found = WrittenNumbers.of(text_codes(text), [0, 5], [4, 9]).at(np.array([1, 3]), 4)
    assert np.array_equal(found.values, [np.nan, 1.5, np.nan, -0.25], equal_nan=True)
    assert found.places.tolist() == [0, 2, 0, 2] and found.bare.tolist() == [False, False, False, True]
    assert found.is_number.tolist() == [False, True, False, True]
