import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from trajcomp.errors import CalibrationError, ModelError
from trajcomp.model.grid import Lattice, ResidualGrid, detect_lattice, node_counts


def lattice_points(origin, step, shape):
    """Nominal node positions (N, 3), x slowest."""
    axes = [o + s * np.arange(n) for o, s, n in zip(origin, step, shape)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


# ---------------------------------------------------------------- idw8, eqs. 2-4


def hand_cell_grid():
    """A 3x3x3 grid whose cell (1, 1, 1) spans (0, 0, 0)..(10, 20, 30) with distinct vertex values."""
    values = np.random.default_rng(7).normal(size=(3, 3, 3, 3)) * 5.0  # other cells: must not matter
    corner_values = {
        (0, 0, 0): (1.0, -2.0, 0.5),
        (1, 0, 0): (2.0, 3.0, -1.0),
        (0, 1, 0): (-4.0, 1.0, 2.0),
        (0, 0, 1): (0.0, 5.0, 1.5),
        (1, 1, 0): (3.0, -1.0, -2.5),
        (1, 0, 1): (-1.0, 0.0, 4.0),
        (0, 1, 1): (6.0, 2.0, 0.0),
        (1, 1, 1): (-2.0, -3.0, 3.0),
    }
    for (i, j, k), v in corner_values.items():
        values[1 + i, 1 + j, 1 + k] = v
    grid = ResidualGrid(Lattice((-10.0, -20.0, -30.0), (10.0, 20.0, 30.0), (3, 3, 3)), values)
    return grid, corner_values


def test_idw8_matches_hand_computed_eqs_2_to_4():
    grid, v = hand_cell_grid()
    # target K = (3, 4, 12); distances to the 8 vertices of the cell (0..10, 0..20, 0..30), eq. 2
    d = {
        (0, 0, 0): math.sqrt(3**2 + 4**2 + 12**2),  # = 13
        (1, 0, 0): math.sqrt(7**2 + 4**2 + 12**2),
        (0, 1, 0): math.sqrt(3**2 + 16**2 + 12**2),
        (0, 0, 1): math.sqrt(3**2 + 4**2 + 18**2),
        (1, 1, 0): math.sqrt(7**2 + 16**2 + 12**2),
        (1, 0, 1): math.sqrt(7**2 + 4**2 + 18**2),
        (0, 1, 1): math.sqrt(3**2 + 16**2 + 18**2),
        (1, 1, 1): math.sqrt(7**2 + 16**2 + 18**2),
    }
    assert d[(0, 0, 0)] == 13.0
    inv_sum = sum(1.0 / di for di in d.values())
    q = {c: (1.0 / d[c]) / inv_sum for c in d}  # eq. 3
    expected = [sum(q[c] * v[c][axis] for c in d) for axis in range(3)]  # eq. 4
    assert grid.evaluate([[3.0, 4.0, 12.0]], method="idw8")[0] == pytest.approx(expected, abs=1e-12)


def test_idw8_on_an_edge_hand_computed():
    grid, v = hand_cell_grid()
    # K = (0, 0, 15) lies on the cell edge x = 0, y = 0; the cell above in x, y is (0..10, 0..20)
    d = {
        (0, 0, 0): 15.0,
        (0, 0, 1): 15.0,
        (1, 0, 0): math.sqrt(10**2 + 15**2),
        (1, 0, 1): math.sqrt(10**2 + 15**2),
        (0, 1, 0): math.sqrt(20**2 + 15**2),  # = 25
        (0, 1, 1): 25.0,
        (1, 1, 0): math.sqrt(10**2 + 20**2 + 15**2),
        (1, 1, 1): math.sqrt(10**2 + 20**2 + 15**2),
    }
    w = {c: 1.0 / d[c] for c in d}
    expected = [sum(w[c] * v[c][axis] for c in d) / sum(w.values()) for axis in range(3)]
    assert grid.evaluate([[0.0, 0.0, 15.0]])[0] == pytest.approx(expected, abs=1e-12)


def test_idw8_vertex_hit_takes_the_vertex_value():
    grid, v = hand_cell_grid()
    got = grid.evaluate([[0.0, 0.0, 0.0], [10.0, 20.0, 30.0], [10.0, 0.0, 30.0 + 1e-9]])
    assert got == pytest.approx(np.array([v[(0, 0, 0)], v[(1, 1, 1)], v[(1, 0, 1)]]), abs=0)


def test_idw8_uses_measured_vertex_coordinates():
    grid, v = hand_cell_grid()
    nodes = grid.lattice.nodes() + np.random.default_rng(3).normal(scale=0.5, size=(3, 3, 3, 3))
    measured = ResidualGrid(grid.lattice, grid.values, nodes)
    # a target at the measured position of vertex (1, 0, 1) of the cell takes its value ...
    target = nodes[2, 1, 2]
    assert measured.evaluate([target])[0] == pytest.approx(v[(1, 0, 1)], abs=0)
    # ... and elsewhere the weights use distances to the measured vertices
    k = np.array([3.0, 4.0, 12.0])
    corners = [(i, j, l) for i in (0, 1) for j in (0, 1) for l in (0, 1)]
    w = np.array([1.0 / np.linalg.norm(k - nodes[1 + i, 1 + j, 1 + l]) for i, j, l in corners])
    expected = sum(wi * np.array(v[c]) for wi, c in zip(w, corners)) / w.sum()
    assert measured.evaluate([k])[0] == pytest.approx(expected, abs=1e-12)


def test_upper_boundary_and_corners_pick_a_valid_cell():
    grid, _ = hand_cell_grid()
    corners = lattice_points((-10, -20, -30), (20, 40, 60), (2, 2, 2))
    for method in ("idw8", "trilinear"):
        got = grid.evaluate(corners, method=method)
        assert got == pytest.approx(grid.values[::2, ::2, ::2].reshape(-1, 3), abs=1e-12)
    face = np.array([[10.0, 5.0, 7.0], [3.0, 20.0, 30.0]])  # on the upper faces x = 10, and y = 20 with z = 30
    assert np.isfinite(grid.evaluate(face)).all()


box = st.tuples(st.floats(0, 100), st.floats(-50, 50), st.floats(200, 260))
coarse = ResidualGrid(Lattice((0.0, -50.0, 200.0), (25.0, 20.0, 30.0), (5, 6, 3)), np.zeros((5, 6, 3, 3)))


@settings(max_examples=60, deadline=None)
@given(st.lists(box, min_size=1, max_size=20))
def test_idw8_reproduces_a_constant_field(points):
    grid = ResidualGrid(coarse.lattice, np.broadcast_to([0.3, -1.2, 2.5], coarse.values.shape))
    assert grid.evaluate(points, "idw8") == pytest.approx(np.tile([0.3, -1.2, 2.5], (len(points), 1)), abs=1e-12)


def trilinear_field(p):
    x, y, z = p[..., 0], p[..., 1] + 50, p[..., 2] - 200
    return np.stack([0.01 * x - 0.02 * y + 0.3, 1e-4 * x * y - 0.003 * z, 2e-6 * x * y * z + 1e-4 * y * z - 1], axis=-1)


@settings(max_examples=60, deadline=None)
@given(st.lists(box, min_size=1, max_size=20))
def test_trilinear_reproduces_trilinear_fields(points):
    grid = ResidualGrid(coarse.lattice, trilinear_field(coarse.lattice.nodes()))
    p = np.array(points)
    assert grid.evaluate(p, "trilinear") == pytest.approx(trilinear_field(p), abs=1e-9)


@settings(max_examples=60, deadline=None)
@given(st.lists(box, min_size=1, max_size=20))
def test_idw8_stays_within_the_vertex_values(points):
    values = np.random.default_rng(0).uniform(-1, 1, coarse.values.shape)
    got = ResidualGrid(coarse.lattice, values).evaluate(points)
    assert (got >= values.min(axis=(0, 1, 2)) - 1e-12).all() and (got <= values.max(axis=(0, 1, 2)) + 1e-12).all()


# ---------------------------------------------------------------- lattice detection

ORIGIN, STEP, SHAPE = np.array([300.0, -100.0, 300.0]), np.array([100.0, 50.0, 25.0]), (6, 4, 3)


def jittered(rng, scale=0.2):
    p = lattice_points(ORIGIN, STEP, SHAPE)
    return p + rng.uniform(-scale, scale, p.shape)


def test_detects_jittered_lattice_with_different_steps():
    rng = np.random.default_rng(1)
    p = jittered(rng)
    order = rng.permutation(len(p))
    lattice, index = detect_lattice(p[order])
    assert lattice.shape == SHAPE
    assert lattice.origin == pytest.approx(ORIGIN, abs=0.1)
    assert lattice.step == pytest.approx(STEP, abs=0.05)
    exact = np.argwhere(np.ones(SHAPE, dtype=bool))  # same x-slowest order as lattice_points
    assert np.array_equal(index, exact[order])


def test_duplicate_measurements_are_averaged():
    p = lattice_points(ORIGIN, STEP, SHAPE)
    e = np.random.default_rng(2).normal(size=p.shape)
    grid = ResidualGrid.from_points(np.vstack([p, p[:1]]), np.vstack([e, e[:1] + 2.0]), measured=np.vstack([p, p[:1] + 0.4]))
    assert grid.values[0, 0, 0] == pytest.approx(e[0] + 1.0)
    assert grid.values[1, 2, 0] == pytest.approx(e[np.ravel_multi_index((1, 2, 0), SHAPE)])
    assert grid.nodes[0, 0, 0] == pytest.approx(p[0] + 0.2)


def test_missing_nodes_are_reported():
    p = np.delete(lattice_points(ORIGIN, STEP, SHAPE), 5, axis=0)
    lattice, index = detect_lattice(p)
    counts = node_counts(lattice, index)
    assert counts.sum() == len(p) and np.argwhere(counts == 0).tolist() == [[0, 1, 2]]
    with pytest.raises(CalibrationError, match=r"1 of 72 nodes have no measurement, first node \(0, 1, 2\) at \(300.000, -50.000, 350.000\)"):
        ResidualGrid.from_points(p, np.zeros_like(p))


def test_missing_inner_plane_shows_as_missing_nodes():
    p = lattice_points(ORIGIN, STEP, SHAPE)
    p = p[p[:, 0] != 500.0]
    lattice, index = detect_lattice(p)
    assert lattice.shape == SHAPE
    assert (node_counts(lattice, index)[2] == 0).all()


@pytest.mark.parametrize(
    "points, message",
    [
        (lattice_points((0, 0, 5), (10, 10, 1), (3, 3, 1)), r"all 9 points have z within 5.000..5.000 mm; a grid needs at least 2 node planes along z"),
        (np.random.default_rng(0).uniform(0, 100, (200, 3)), r"200 points do not lie on a regular grid: their x coordinates spread continuously"),
        (lattice_points((0, 0, 0), (1, 1, 1), (2, 2, 2)) * [[10, 100, 150]], None),
        (np.random.default_rng(0).uniform(0, 100, (50, 3)), r"50 points do not lie on a regular grid: node planes along x are only 0.\d+ mm apart, less than 8x the tolerance 0.5 mm"),
        (np.vstack([lattice_points((0, 0, 0), (10, 10, 10), (2, 2, 2)), [[20, 0, 0]], [[35, 0, 0]]]), r"10 points: node planes along x are not evenly spaced: gaps 10.000, 10.000, 15.000 mm"),
        (np.vstack([lattice_points((0, 0, 0), (10, 10, 10), (2, 3, 2))] * 10 + [[[10.45, 0, 0]], [[10.9, 0, 0]]]), r"point 121 at \(10.900, 0.000, 0.000\) mm is 0.8\d\d mm off the nearest grid node along x"),
    ],
)
def test_degenerate_inputs_raise_clear_errors(points, message):
    if message is None:  # a valid 2x2x2 lattice with steps 10, 100, 150
        lattice, _ = detect_lattice(points)
        assert lattice.step == pytest.approx([10, 100, 150])
        return
    with pytest.raises(CalibrationError, match=message):
        ResidualGrid.from_points(points, np.zeros_like(points))


def test_bad_shapes_and_nans_raise():
    p = lattice_points(ORIGIN, STEP, SHAPE)
    with pytest.raises(CalibrationError, match="72 points but 71 residuals"):
        ResidualGrid.from_points(p, p[1:])
    bad = p.copy()
    bad[3, 1] = np.nan
    with pytest.raises(CalibrationError, match="grid points: row 3 is not finite"):
        ResidualGrid.from_points(bad, p)


# ---------------------------------------------------------------- outside policy, serialization


def test_outside_policies():
    grid, _ = hand_cell_grid()
    q = np.array([[3.0, 4.0, 12.0], [15.0, 4.0, 12.0], [-50.0, 0.0, 100.0]])
    with pytest.raises(ModelError, match=r"point 1 at \(15.000, 4.000, 12.000\) mm lies outside the residual field's box \(-10.000, -20.000, -30.000\)..\(10.000, 20.000, 30.000\) mm \(2 of 3 points outside\)"):
        grid.evaluate(q)
    assert grid.contains(q).tolist() == [True, False, False]
    clamped = grid.evaluate(q, outside="clamp")
    assert clamped == pytest.approx(grid.evaluate([[3, 4, 12], [10, 4, 12], [-10, 0, 30]]))
    nan = grid.evaluate(q, method="trilinear", outside="nan")
    assert np.isnan(nan[1:]).all() and nan[0] == pytest.approx(grid.evaluate(q[:1], "trilinear")[0])
    with pytest.raises(ValueError, match="outside policy 'skip'"):
        grid.evaluate(q, outside="skip")


def test_dict_round_trip_is_plain_and_exact():
    grid, _ = hand_cell_grid()
    grid = ResidualGrid(grid.lattice, grid.values, grid.lattice.nodes() + 0.1, "trilinear")
    data = json.loads(json.dumps(grid.to_dict()))  # plain lists only
    back = ResidualGrid.from_dict(data)
    assert back.method == "trilinear" and back.lattice.shape == (3, 3, 3)
    assert np.array_equal(back.values, grid.values) and np.array_equal(back.nodes, grid.nodes)
    q = np.random.default_rng(4).uniform(-10, 10, (10, 3))
    assert np.array_equal(back.evaluate(q), grid.evaluate(q))


@pytest.mark.parametrize(
    "change, message",
    [
        ({"step": None}, "missing key 'step'"),
        ({"shape": [3, 3, 1]}, r"needs at least 2 nodes"),
        ({"values": [[0, 0, 0]]}, r"values must be finite with shape \(3, 3, 3, 3\)"),
        ({"method": "cubic"}, "unknown method 'cubic'"),
        ({"step": [1, -1, 1]}, "step > 0"),
    ],
)
def test_from_dict_rejects_bad_data(change, message):
    data = hand_cell_grid()[0].to_dict()
    data.update(change)
    data = {k: v for k, v in data.items() if v is not None}
    with pytest.raises(ModelError, match=message):
        ResidualGrid.from_dict(data)


@settings(max_examples=40, deadline=None)
@given(
    origin=st.tuples(*[st.floats(-1000, 1000)] * 3),
    step=st.tuples(*[st.floats(5, 200)] * 3),
    shape=st.tuples(*[st.integers(2, 7)] * 3),
    seed=st.integers(0, 2**32 - 1),
)
def test_detects_random_jittered_lattices(origin, step, shape, seed):
    rng = np.random.default_rng(seed)
    p = lattice_points(origin, step, shape)
    order = rng.permutation(len(p))
    lattice, index = detect_lattice(p[order] + rng.uniform(-0.2, 0.2, p.shape))
    assert lattice.shape == shape
    assert lattice.step == pytest.approx(step, abs=0.4)  # plane centres within 0.2 mm: slopes within 0.4 mm
    assert np.array_equal(index, np.argwhere(np.ones(shape, dtype=bool))[order])
