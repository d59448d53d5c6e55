"""Rows laid out as bytes (`trajcomp.formats.fixed_text`) against Python's own ``'%.<d>f' % v`` and str.join."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from trajcomp.formats.fixed_text import joined_rows

TIES_AND_EDGES = [0.0, -0.0, 0.5, -0.5, 1.5, 2.5, -2.5, 0.125, -0.375, 0.0625, 2.675, 1.0005, 1.0015, 0.0005,
                  -0.0005, 9.9995, -9.9995, 999.9999, 0.1 + 0.2, 1 / 3, 1e-300, -1e-300, 5e-324, 1e15, -1e15,
                  4503599627370495.5, 2.0**52, 2.0**53 + 2, 1e20, -1e20, 1.7976931348623157e308, float("nan"),
                  float("inf"), float("-inf"), 99.5, 9.5, 0.95, 0.995, 100.0, 1e6, 123456789012.3456]


def python(values, places):
    return [f"{v:.{places}f}" for v in np.asarray(values, dtype=float).tolist()]


@pytest.mark.parametrize("places", range(16))
def test_numbers_are_what_python_writes(places):
    rng = np.random.default_rng(places)
    step = 10.0**-places
    values = np.concatenate([
        TIES_AND_EDGES,
        rng.uniform(-2000, 2000, 3000),
        rng.normal(0, 10.0 ** rng.integers(-8, 12, 3000)),
        (np.round(rng.uniform(-100, 100, 3000) / step) + 0.5) * step,  # halves of the last place, as near as binary
        np.round(rng.uniform(-100, 100, 3000), places),  # values a file at these places states
        (np.round(rng.uniform(-1, 1, 1000) / step) + 0.5) * step * (1 + rng.choice([-1, 1], 1000) * 2.0**-52),
    ])
    assert joined_rows([(values, places)]).split("\n") == python(values, places)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=1, max_size=40), st.integers(0, 15))
def test_any_floats_are_what_python_writes(values, places):
    assert joined_rows([(np.array(values), places)]).split("\n") == python(values, places)


def test_rows_of_number_and_text_cells_are_joined_as_str_join_does():
    rng = np.random.default_rng(7)
    x, y = rng.uniform(-1e3, 1e3, 50), rng.normal(0, 1e-4, 50)
    words = (["LIN", "", "a b", '"quoted, cell"', "é", "PTP  "] * 9)[:50]
    expected = "\n".join(",".join(row) for row in zip(python(x, 3), words, python(y, 9), python(x, 0)))
    assert joined_rows([(x, 3), words, (y, 9), (x, 0)]) == expected


def test_no_rows_are_no_text():
    assert joined_rows([(np.empty(0), 3), []]) == ""
