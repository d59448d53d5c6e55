import json

import numpy as np
import pytest

from trajcomp.errors import CalibrationError, ModelError
from trajcomp.model.linear import LinearCorrection, fit_linear

RNG = np.random.default_rng(11)
# the paper's large cube: corner (300, -100, 300), side 500, step 100
AXIS = np.arange(6) * 100.0
P = np.stack(np.meshgrid(AXIS + 300, AXIS - 100, AXIS + 300, indexing="ij"), axis=-1).reshape(-1, 3)


def planted(p, noise, rng=RNG):
    """The paper's pattern: dx ~ y, dy ~ x, dz ~ x and z."""
    x, y, z = p.T
    e = np.stack([0.002 * y + 0.1, -0.003 * x + 1.5, 0.004 * x - 0.001 * z - 2.0], axis=1)
    return e + rng.normal(0.0, noise, p.shape)


def test_recovers_planted_relation_and_selects_the_regressors():
    model = fit_linear(P, planted(P, noise=0.01))
    assert model.regressors == (("y",), ("x",), ("x", "z"))
    expected = [[0.1, 0, 0.002, 0], [1.5, -0.003, 0, 0], [-2.0, 0.004, 0, -0.001]]
    assert model.coefficients[:, 1:] == pytest.approx(np.array(expected)[:, 1:], abs=2e-5)
    assert model.coefficients[:, 0] == pytest.approx(np.array(expected)[:, 0], abs=0.02)
    assert min(model.r2) > 0.99
    residual = planted(P, 0.0) - model.predict_error(P)
    assert np.abs(residual).max() < 0.01


def test_exact_data_picks_the_smallest_true_model():
    model = fit_linear(P, planted(P, noise=0.0))
    assert model.regressors == (("y",), ("x",), ("x", "z"))
    assert model.r2 == pytest.approx((1.0, 1.0, 1.0))


def test_irrelevant_regressors_are_rarely_chosen():
    """Pure noise on 50 fixed seeds: BIC keeps the intercept alone on at least 90 % of the axes."""
    chosen = [len(r) for seed in range(50) for r in fit_linear(P, np.random.default_rng(seed).normal(0.0, 0.05, P.shape)).regressors]
    assert np.mean(np.array(chosen) == 0) >= 0.9


def test_pure_noise_keeps_only_the_intercept():
    model = fit_linear(P, np.random.default_rng(0).normal(0.3, 0.05, P.shape))
    assert model.regressors == ((), (), ())
    assert model.coefficients[:, 0] == pytest.approx([0.3] * 3, abs=0.02)
    assert np.all(model.coefficients[:, 1:] == 0)


def test_aic_is_available():
    model = fit_linear(P, planted(P, noise=0.01), criterion="aic")
    assert all(set(want) <= set(got) for want, got in zip((("y",), ("x",), ("x", "z")), model.regressors))
    with pytest.raises(ValueError, match="unknown selection criterion 'r2'"):
        fit_linear(P, planted(P, 0.0), criterion="r2")


def test_planar_data_skips_the_constant_coordinate():
    flat = P[P[:, 2] == 300.0]
    model = fit_linear(flat, planted(flat, noise=0.0))
    assert model.regressors[:2] == (("y",), ("x",))
    assert "z" not in model.regressors[2]


def test_describe_reads_like_the_paper():
    model = LinearCorrection([[-0.35, 0, 0.0021, 0], [0.2, -0.001, 0, 0], [0.5, 0, 0, 0]], (("y",), ("x",), ()), (0.93, 0.5, 1.0))
    assert model.describe().splitlines() == [
        "dx = 0.0021*y - 0.35 (R^2 0.930)",
        "dy = -0.001*x + 0.2 (R^2 0.500)",
        "dz = 0.5 (R^2 1.000)",
    ]


def test_dict_round_trip():
    model = fit_linear(P, planted(P, noise=0.01))
    data = json.loads(json.dumps(model.to_dict()))
    assert data["dx"]["slopes"].keys() == {"y"}
    back = LinearCorrection.from_dict(data)
    assert back.regressors == model.regressors and back.r2 == model.r2
    assert np.array_equal(back.coefficients, model.coefficients)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda d: d.pop("dy"), "missing key 'dy'"),
        (lambda d: d["dx"]["slopes"].update(w=1.0), r"unknown regressor\(s\) \['w'\]"),
        (lambda d: d["dz"].update(intercept="a lot"), "malformed entry"),
    ],
)
def test_from_dict_rejects_bad_data(change, message):
    data = fit_linear(P, planted(P, noise=0.01)).to_dict()
    change(data)
    with pytest.raises(ModelError, match=message):
        LinearCorrection.from_dict(data)


def test_too_few_points_and_bad_input():
    with pytest.raises(CalibrationError, match="4 points, need at least 5"):
        fit_linear(P[:4], planted(P[:4], 0.0))
    e = planted(P, 0.0)
    e[9, 0] = np.nan
    with pytest.raises(CalibrationError, match="errors: row 9 is not finite"):
        fit_linear(P, e)
    with pytest.raises(CalibrationError, match="216 positions but 215 errors"):
        fit_linear(P, planted(P, 0.0)[1:])
