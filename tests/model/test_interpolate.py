"""Every residual field kind through the one entry point, plus the scattered kinds' own behaviour."""

import json

import numpy as np
import pytest

from trajcomp.errors import CalibrationError, ModelError
from trajcomp.model.grid import KINDS, ResidualGrid, field_from_dict, fit_field
from trajcomp.model import interpolate
from trajcomp.model.interpolate import KNN, RBF, GaussianField, Kriging


def smooth_field(p):
    """A smooth error field on the box 0..100 mm, mm."""
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    return 0.5 * np.stack([np.sin(x / 30), np.cos(y / 40), np.sin((x + z) / 50)], axis=1)


def cube(n, side=100.0):
    axis = np.linspace(0.0, side, n)
    return np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)


QUERY = np.random.default_rng(1).uniform(0.0, 100.0, (300, 3))


@pytest.mark.parametrize("kind, ratio", [("idw8", 0.6), ("trilinear", 0.35), ("knn", 0.6), ("rbf", 0.35)])
def test_converges_when_the_grid_is_refined(kind, ratio):
    """Halving the step cuts the max error: by ~1/2 for the inverse-distance kinds, ~1/4 for the others."""
    errors = []
    for n in (5, 9):
        p = cube(n)
        field = fit_field(p, smooth_field(p), step=100.0 / (n - 1), interpolation=kind)
        errors.append(np.abs(field.evaluate(QUERY) - smooth_field(QUERY)).max())
    assert errors[1] < ratio * errors[0]


@pytest.mark.parametrize("kind", KINDS)
def test_every_kind_reproduces_data_and_constants_and_round_trips(kind):
    p = cube(4)
    values = np.random.default_rng(2).normal(size=p.shape)
    field = fit_field(p, values, interpolation=kind, **({"smoothing": 0.0} if kind == "rbf" else {}))
    assert field.evaluate(p) == pytest.approx(values, abs=1e-8)  # exact at the data points
    constant = fit_field(p, np.tile([0.2, -0.1, 0.05], (len(p), 1)), interpolation=kind)
    assert constant.evaluate(QUERY) == pytest.approx(np.tile([0.2, -0.1, 0.05], (len(QUERY), 1)), abs=1e-8)
    back = field_from_dict(json.loads(json.dumps(field.to_dict())))
    assert type(back) is type(field)
    assert back.evaluate(QUERY) == pytest.approx(field.evaluate(QUERY), abs=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_every_kind_applies_the_outside_policy(kind):
    p = cube(3)
    field = fit_field(p, smooth_field(p), interpolation=kind)
    q = np.array([[50.0, 50.0, 50.0], [50.0, 120.0, 50.0]])
    assert field.contains(q).tolist() == [True, False]
    with pytest.raises(ModelError, match=r"point 1 at \(50.000, 120.000, 50.000\) mm lies outside"):
        field.evaluate(q)
    assert field.evaluate(q, outside="clamp")[1] == pytest.approx(field.evaluate([[50.0, 100.0, 50.0]])[0])
    assert np.isnan(field.evaluate(q, outside="nan")[1]).all()


def test_lattice_kinds_refuse_scattered_data():
    p = np.random.default_rng(3).uniform(0, 100, (50, 3))
    for kind in ("idw8", "trilinear"):
        with pytest.raises(CalibrationError, match="do not lie on a regular grid"):
            fit_field(p, p, interpolation=kind)
    with pytest.raises(ValueError, match="unknown interpolation 'cubic'"):
        fit_field(p, p, interpolation="cubic")


def test_lattice_kinds_check_the_expected_step():
    p = cube(5)
    with pytest.raises(CalibrationError, match=r"detected grid step \(25.000, 25.000, 25.000\) mm differs from the expected \(20.000, 20.000, 20.000\) mm along x"):
        fit_field(p, p, step=20.0)
    assert isinstance(fit_field(p, p, step=(25.0, 25.0, 25.2)), ResidualGrid)


# ---------------------------------------------------------------- scattered data

SCATTERED = np.random.default_rng(4).uniform(0.0, 100.0, (300, 3))
NOISE = 0.01


def noisy_errors(seed=5):
    return smooth_field(SCATTERED) + np.random.default_rng(seed).normal(0.0, NOISE, SCATTERED.shape)


def test_knn_hand_computed_weights():
    p = np.array([[0.0, 0, 0], [3.0, 0, 0], [0.0, 4.0, 0], [50.0, 50.0, 50.0]])
    v = np.array([[1.0, 0, 0], [0.0, 1.0, 0], [0.0, 0, 1.0], [9.0, 9.0, 9.0]])
    q = np.array([[0.0, 0.0, 1.0]])  # distances 1, sqrt(10), sqrt(17); the far point is not a neighbour
    for power in (1, 2):
        w = np.array([1.0, 10 ** (-power / 2), 17 ** (-power / 2)])
        got = KNN(p, v, k=3, power=power).evaluate(q, outside="clamp")[0]
        assert got == pytest.approx(w / w.sum(), abs=1e-12)
    assert KNN(p, v, k=3).evaluate([[3.0, 0, 0]])[0] == pytest.approx([0, 1, 0], abs=0)  # data hit


def test_knn_rejects_more_neighbours_than_points():
    with pytest.raises(CalibrationError, match="k=8 neighbours requested but 4 data points"):
        KNN(cube(2)[:4], np.zeros((4, 3)))


def test_rbf_smooths_noise_with_a_cross_validated_smoothing():
    rbf = RBF.fit(SCATTERED, noisy_errors())
    inner = QUERY[np.all((QUERY > 15) & (QUERY < 85), axis=1)]
    error = np.sqrt(np.mean(np.sum((rbf.evaluate(inner) - smooth_field(inner)) ** 2, axis=1)))
    assert rbf.smoothing > 0
    assert error < NOISE * np.sqrt(3)  # better than the noise of a single measurement
    exact = RBF(SCATTERED, noisy_errors(), smoothing=0.0)
    assert np.abs(exact.evaluate(SCATTERED) - noisy_errors()).max() < 1e-8  # smoothing 0 interpolates


def test_rbf_kernel_options_and_errors():
    gauss = RBF(SCATTERED, noisy_errors(), smoothing=1e-3, kernel="gaussian", epsilon=2.0)
    assert np.abs(gauss.evaluate(QUERY[:20]) - smooth_field(QUERY[:20])).max() < 0.1
    with pytest.raises(CalibrationError, match="rbf fit of 300 points"):
        RBF(SCATTERED, noisy_errors(), kernel="gaussian")  # needs epsilon
    with pytest.raises(ModelError, match="a rbf residual field cannot be evaluated by 'idw8'"):
        gauss.evaluate(QUERY, method="idw8")


def test_scattered_input_errors():
    with pytest.raises(CalibrationError, match="300 points but 299 residuals"):
        KNN(SCATTERED, noisy_errors()[1:])
    bad = noisy_errors()
    bad[7, 2] = np.inf
    with pytest.raises(CalibrationError, match="scattered residuals: row 7 is not finite"):
        RBF.fit(SCATTERED, bad)


@pytest.mark.parametrize(
    "data, message",
    [
        ({"kind": "spline"}, "unknown kind 'spline'"),
        ({"kind": "knn", "points": [[0, 0, 0]]}, "residual field knn"),
        ({"kind": "knn", "points": [[0, 0, 0]], "values": [[0, 0]], "k": 1}, r"shape \(N, 3\)"),
    ],
)
def test_field_from_dict_rejects_bad_data(data, message):
    with pytest.raises(ModelError, match=message):
        field_from_dict(data)


def test_kriging_hand_computed_one_and_two_points():
    """One point: the value times exp(-d^2 / 2 L^2) / (1 + nugget); two: the 2 x 2 system solved by hand."""
    value = np.array([[0.3, -0.2, 0.1]])
    field = Kriging(np.zeros((1, 3)), value, length=200.0, nugget=0.25)
    query = np.array([[0.0, 0.0, 0.0], [200.0, 0.0, 0.0], [0.0, 0.0, 5000.0]])
    np.testing.assert_allclose(field.evaluate(query), value * (np.exp([0.0, -0.5, -312.5]) / 1.25)[:, None],
                               atol=1e-15)
    points = np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0]])
    values = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    c = np.exp(-100.0**2 / (2 * 200.0**2))  # the correlation of the two points
    weights = np.array([[1.25, -c], [-c, 1.25]]) / (1.25**2 - c**2) @ values  # inverse of [[1.25, c], [c, 1.25]]
    middle = np.array([[50.0, 0.0, 0.0]])
    expected = np.exp(-50.0**2 / (2 * 200.0**2)) * weights.sum(axis=0)
    np.testing.assert_allclose(Kriging(points, values, 200.0, 0.25).evaluate(middle)[0], expected, rtol=1e-12)


def test_kriging_follows_its_points_returns_to_zero_far_away_and_round_trips():
    rng = np.random.default_rng(4)
    points = rng.uniform(0.0, 1000.0, (40, 3))
    values = 0.2 * np.stack([np.sin(points[:, 0] / 300), np.cos(points[:, 1] / 400), np.sin(points[:, 2] / 350)], 1)
    field = Kriging.fit(points, values)
    assert field.contains(np.array([[1e5, -1e5, 0.0]])).all()  # defined everywhere: nothing is flagged outside
    assert np.abs(field.evaluate(points) - values).max() < 0.05  # it follows the points (less the nugget's share)
    np.testing.assert_allclose(field.evaluate(np.array([[20000.0, 500.0, 500.0]])), 0.0, atol=1e-12)
    assert field.variance(np.array([[20000.0, 500.0, 500.0]]))[0] == pytest.approx(field.signal_variance().mean())
    assert field.variance(points).max() < 0.5 * field.signal_variance().mean()
    again = field_from_dict(json.loads(json.dumps(field.to_dict())))
    np.testing.assert_allclose(again.evaluate(QUERY * 10), field.evaluate(QUERY * 10), rtol=1e-12)


def test_kriging_likelihood_finds_the_correlation_length_of_a_sampled_process():
    """Values drawn from a Gaussian process of length 300 mm (noise 10 %): the fit picks it among the candidates."""
    rng = np.random.default_rng(7)
    points = rng.uniform(0.0, 1000.0, (200, 3))
    squared = np.sum((points[:, None] - points[None]) ** 2, axis=2)
    covariance = np.exp(-squared / (2 * 300.0**2)) + 0.1 * np.eye(len(points))
    values = 0.1 * np.linalg.cholesky(covariance) @ rng.standard_normal((len(points), 3))
    field = Kriging.fit(points, values)
    assert field.length == 300.0 and field.nugget in (0.03, 0.1, 0.2)
    np.testing.assert_allclose(np.sqrt(field.signal_variance()), 0.1, rtol=0.5)
    assert Kriging.fit(points, values, lengths=(100.0, 800.0)).log_likelihood() < field.log_likelihood()


def test_gp_field_is_the_kriging_process_under_its_own_kind(monkeypatch):
    """Calibrate's field on top: one point hand-computed as for kriging; ``fit_field`` with a length takes it, without
    one it chooses by likelihood; the model file keeps the kind (a ``kriging`` field is a re-calibration's)."""
    value = np.array([[0.3, -0.2, 0.1]])
    field = fit_field(np.zeros((1, 3)), value, interpolation="gp", length=200.0, nugget=0.25)
    assert isinstance(field, GaussianField) and field.kind == "gp" and (field.length, field.nugget) == (200.0, 0.25)
    np.testing.assert_allclose(field.evaluate(np.array([[200.0, 0.0, 0.0]])), value * np.exp(-0.5) / 1.25, atol=1e-15)
    rng = np.random.default_rng(5)
    points = rng.uniform(0.0, 1000.0, (60, 3))
    values = 0.1 * np.column_stack([np.sin(points[:, 0] / 300), np.cos(points[:, 1] / 300), np.sin(points[:, 2] / 400)])
    chosen = fit_field(points, values, interpolation="gp")
    assert isinstance(chosen, GaussianField) and (chosen.length, chosen.nugget) == (lambda k: (k.length, k.nugget))(
        Kriging.fit(points, values, nuggets=interpolate.GP_NUGGETS))
    again = field_from_dict(json.loads(json.dumps(chosen.to_dict())))
    assert again.kind == "gp" and type(again) is GaussianField
    whole = chosen.evaluate(QUERY * 10)
    np.testing.assert_allclose(again.evaluate(QUERY * 10), whole, rtol=1e-12)
    monkeypatch.setattr(interpolate, "BLOCK_ELEMENTS", 7 * len(points))  # blocks of 7 queries, the last one short
    np.testing.assert_allclose(chosen.evaluate(QUERY * 10), whole, rtol=1e-12)


def test_kriging_refuses_bad_parameters():
    with pytest.raises(CalibrationError, match="length > 0"):
        Kriging(np.zeros((2, 3)), np.zeros((2, 3)), length=0.0)
    with pytest.raises(ModelError, match="cannot be evaluated by"):
        Kriging(np.zeros((1, 3)), np.zeros((1, 3))).evaluate(np.zeros((1, 3)), method="idw8")


def test_gp_field_over_the_wrist_hand_computed_and_round_trips():
    """One point: the correlation of the position and of the wrist angles (joints 4-6) multiply, each over its own
    length; a field over the wrist refuses to be evaluated without the joints and keeps its angles in the file."""
    value = np.array([[0.3, -0.2, 0.1]])
    wrist = np.array([[10.0, 20.0, 30.0]])  # deg
    field = GaussianField(np.zeros((1, 3)), value, length=200.0, nugget=0.25, angles=wrist, angle_length=40.0)
    assert field.needs_joints and not GaussianField(np.zeros((1, 3)), value).needs_joints
    joints = np.radians([[5.0, 6.0, 7.0, 10.0, 20.0, 30.0], [5.0, 6.0, 7.0, 50.0, 20.0, 30.0],
                         [0.0, 0.0, 0.0, 10.0, 60.0, 30.0], [0.0, 0.0, 0.0, 10.0, 20.0, 30.0]])
    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [200.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    expected = value * (np.exp([0.0, -0.5, -1.0, 0.0]) / 1.25)[:, None]  # joints 1-3 do not count
    np.testing.assert_allclose(field.evaluate(points, joints=joints), expected, atol=1e-15)
    with pytest.raises(ModelError, match="commanded joints"):
        field.evaluate(points)
    again = field_from_dict(json.loads(json.dumps(field.to_dict())))
    np.testing.assert_allclose(again.evaluate(points, joints=joints), expected, atol=1e-15)
    with pytest.raises(CalibrationError, match="one finite triple"):
        GaussianField(np.zeros((2, 3)), np.zeros((2, 3)), angles=wrist, angle_length=40.0)


def test_gp_field_likelihood_takes_the_wrist_where_the_residual_turns_with_it():
    """Residuals at 12 positions, each in 8 wrist orientations: where they follow the wrist's joint 5 the fit takes a
    finite wrist length and predicts orientations it did not see far better than a field of the position alone;
    where they follow the position alone it leaves the wrist out."""
    rng = np.random.default_rng(3)
    positions = np.repeat(rng.uniform(0.0, 1000.0, (12, 3)), 8, axis=0)
    joints = np.zeros((len(positions), 6))
    joints[:, 3:] = np.radians(rng.uniform(-90.0, 90.0, (len(positions), 3)))
    wrist_error = 0.1 * np.column_stack([np.sin(joints[:, 4]), np.cos(joints[:, 4]), np.sin(2 * joints[:, 4])])
    train, held = np.arange(len(positions)) % 4 != 0, np.arange(len(positions)) % 4 == 0
    tried = {"lengths": (150.0, 300.0, 600.0), "nuggets": (0.03, 0.3)}
    turned = GaussianField.fit(positions[train], wrist_error[train], joints=joints[train], **tried)
    alone = GaussianField.fit(positions[train], wrist_error[train], **tried)
    assert turned.needs_joints and np.isfinite(turned.angle_length)
    miss = np.abs(turned.evaluate(positions[held], joints=joints[held]) - wrist_error[held]).mean()
    assert miss < 0.3 * np.abs(alone.evaluate(positions[held]) - wrist_error[held]).mean()
    position_error = 0.1 * np.sin(positions / 300.0)
    assert not GaussianField.fit(positions, position_error, joints=joints, **tried).needs_joints
