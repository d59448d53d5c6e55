import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from trajcomp.errors import CalibrationError
from trajcomp.model.stats import ErrorStats, as_vectors, format_table, kfold_indices


def test_hand_computed_two_vectors():
    s = ErrorStats.from_errors([[3.0, 4.0, 0.0], [0.0, 0.0, 0.0]])
    # norms 5 and 0
    assert s.n == 2
    assert s.mean == pytest.approx(2.5)
    assert s.rms == pytest.approx(math.sqrt((25 + 0) / 2))
    # numpy's default percentile: 0 + 0.95 * (5 - 0)
    assert s.p95 == pytest.approx(4.75)
    assert s.max == pytest.approx(5.0)
    assert s.signed_mean == pytest.approx((1.5, 2.0, 0.0))
    assert s.std == pytest.approx((1.5, 2.0, 0.0))


def test_signed_means_cancel_but_norms_do_not():
    s = ErrorStats.from_errors([[1.0, 0, 0], [-1.0, 0, 0]])
    assert s.signed_mean == pytest.approx((0, 0, 0))
    assert s.mean == pytest.approx(1.0)


def test_summary_and_dict():
    s = ErrorStats.from_errors([[0.123, 0, 0]])
    assert s.summary() == "mean 0.123  rms 0.123  p95 0.123  max 0.123 mm"
    d = s.as_dict()
    assert d["n"] == 1 and d["signed_mean"] == pytest.approx([0.123, 0, 0])
    assert ErrorStats(**{**d, "signed_mean": tuple(d["signed_mean"]), "std": tuple(d["std"])}) == s


def test_format_table_has_a_row_per_mode():
    s = ErrorStats.from_errors([[3.0, 4.0, 0.0], [0.0, 0.0, 0.0]])
    text = format_table({"none": s, "composite": s})
    lines = text.splitlines()
    assert len(lines) == 3
    assert lines[0].split()[:6] == ["mode", "n", "mean", "rms", "p95", "max"]
    assert lines[2].split() == ["composite", "2", "2.5000", "3.5355", "4.7500", "5.0000", "1.5000", "2.0000", "0.0000"]


@pytest.mark.parametrize("bad", [np.zeros((0, 3)), np.zeros((4, 2)), [[0, np.nan, 0]], [[np.inf, 0, 0]]])
def test_bad_errors_raise(bad):
    with pytest.raises(CalibrationError, match="error vectors"):
        ErrorStats.from_errors(bad)


def test_as_vectors_names_the_row():
    with pytest.raises(ValueError, match="points: row 2 is not finite"):
        as_vectors([[0, 0, 0], [1, 1, 1], [0, np.nan, 0]], "points", error=ValueError)


@given(arrays(float, st.tuples(st.integers(1, 30), st.just(3)), elements=st.floats(-1e3, 1e3)))
def test_norm_order(e):
    s = ErrorStats.from_errors(e)
    tol = 1e-9 * (1 + s.max)
    assert 0 <= s.mean <= s.rms + tol
    assert s.rms <= s.max + tol
    assert s.p95 <= s.max + tol


@given(st.integers(2, 200), st.integers(2, 12), st.integers(0, 2**32 - 1))
def test_kfold_partitions(n, k, seed):
    k = min(k, n)
    folds = kfold_indices(n, k, seed)
    assert len(folds) == k
    tests = np.concatenate([test for _, test in folds])
    assert np.array_equal(np.sort(tests), np.arange(n))  # every index exactly once
    sizes = [len(test) for _, test in folds]
    assert max(sizes) - min(sizes) <= 1
    for train, test in folds:
        assert np.array_equal(np.union1d(train, test), np.arange(n))
        assert len(np.intersect1d(train, test)) == 0


def test_kfold_is_deterministic_and_shuffled():
    a = kfold_indices(20, 4, seed=3)
    b = kfold_indices(20, 4, seed=3)
    assert all(np.array_equal(x[1], y[1]) for x, y in zip(a, b))
    assert not np.array_equal(a[0][1], np.arange(5))  # not the unshuffled split


@pytest.mark.parametrize("n, k", [(5, 1), (3, 4)])
def test_kfold_bad_k(n, k):
    with pytest.raises(CalibrationError, match="cross-validation"):
        kfold_indices(n, k, 0)
