"""Configuration data of each language from joint angles, against hand-worked poses."""

import numpy as np
import pytest

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
