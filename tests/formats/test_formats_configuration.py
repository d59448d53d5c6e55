"""Configuration data of each language from joint angles, against hand-worked poses."""

import numpy as np
import pytest

from trajcomp.arm.ik import configuration_of
from trajcomp.formats.configuration import distinct_tuples, flags
from trajcomp.formats.fanuc.configuration import encode as fanuc_config
from trajcomp.formats.krl.configuration import encode as kuka_status_turn
from trajcomp.formats.rapid.configuration import encode as abb_confdata
from trajcomp.arm.robot import load_robot


@pytest.fixture(scope="module")
def robots():
    return {name: load_robot(name) for name in ("kuka_kr6_r900", "abb_irb4600", "fanuc_lrmate200id")}


def test_kuka_status_and_turn(robots):
    kuka = robots["kuka_kr6_r900"]
    q = np.radians([
        [0, -90, 90, 0, 90, 0],      # home, tool down: front of A1, elbow up, A5 > 0 -> S 2; A2 < 0 -> T 2
        [0, -90, 90, 0, -30, 0],     # same arm, A5 < 0 -> S 6; T bits A2, A5 -> 2 + 16
        [10, -90, -30, 0, 20, 0],    # forearm folded back over A1 -> overhead, S 1
        [-20, -45, 100, -10, 45, -5],  # T = A1 + A2 + A4 + A6 = 1 + 2 + 8 + 32
    ])
    assert kuka_status_turn(kuka, q) == [(2, 2), (6, 18), (1, 6), (2, 43)]


def test_abb_confdata(robots):
    abb = robots["abb_irb4600"]
    q = np.radians([[0, 0, 0, 0, 30, 0], [100, 0, 0, -10, -30, 200], [-10, 0, 0, 185, 30, -95]])
    assert abb_confdata(abb, q) == [(0, 0, 0, 0), (1, -1, 2, 1), (-1, 2, -2, 0)]


def test_fanuc_config(robots):
    fanuc = robots["fanuc_lrmate200id"]
    q = np.radians([[0, 0, 0, 0, -90, 0], [200, 0, 0, 0, 90, -200], [-190, 10, 5, 181, -30, 560]])
    assert fanuc_config(fanuc, q) == [
        ("N", "U", "T", 0, 0, 0),
        ("F", "U", "T", 1, 0, -1),
        ("N", "U", "T", -1, 1, 2),
    ]


@pytest.mark.parametrize("encode", [kuka_status_turn, abb_confdata, fanuc_config])
def test_a_path_of_repeated_postures_shares_its_data(robots, encode):
    """A long path encodes as each target alone would, with one tuple per distinct datum (memory, merges)."""
    robot = robots[{kuka_status_turn: "kuka_kr6_r900", abb_confdata: "abb_irb4600",
                    fanuc_config: "fanuc_lrmate200id"}[encode]]
    rng = np.random.default_rng(3)
    postures = rng.uniform(robot.q_min, robot.q_max, (5, 6))
    q = postures[rng.integers(0, 5, 200)]
    data = encode(robot, q)
    assert data == [encode(robot, row[None])[0] for row in q]
    assert len({id(d) for d in data}) == len(set(data)) <= 5


def test_flags_are_the_configuration_of_the_joints(robots):
    for robot in robots.values():
        q = np.random.default_rng(5).uniform(robot.q_min, robot.q_max, (300, 6))
        behind, up, negative = flags(robot, q)
        configs = configuration_of(robot, q)
        assert behind.tolist() == [c.shoulder == "back" for c in configs]
        assert up.tolist() == [c.elbow == "up" for c in configs]
        assert negative.tolist() == [c.wrist == "negative" for c in configs]
        assert 0 < behind.sum() + up.sum() + negative.sum() < 900  # both values of the flags occur


@pytest.mark.parametrize("high", [3, 2**40])  # rows as one number in mixed radices, or (too wide) sorted as rows
def test_distinct_tuples_are_the_rows(high):
    rows = np.random.default_rng(8).integers(-high, high + 1, (500, 4))
    rows[::3] = rows[0]
    made = distinct_tuples(rows, lambda row: ("x", *row))
    assert made == [("x", *row) for row in rows.tolist()]
    assert len({id(t) for t in made}) == len({tuple(row) for row in rows.tolist()})
