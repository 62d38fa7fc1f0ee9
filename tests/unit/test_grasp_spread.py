"""How far a held object swung over in the hand, seen from above (grasp_trial.spread)."""

import itertools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gendex.solve.grasp_trial import UPRIGHT_SPREAD, spread
from gendex.solve.shape import ConvexPart, ObjectShape


def box(x: float, y: float, z: float) -> ObjectShape:
    corners = np.array(list(itertools.product((-x / 2, x / 2), (-y / 2, y / 2), (-z / 2, z / 2))))
    return ObjectShape([ConvexPart.of_points(corners)])


def rot(seq: str, deg) -> np.ndarray:
    return Rotation.from_euler(seq, deg, degrees=True).as_matrix()


def test_a_tall_box_swung_45_degrees_spreads_about_twice_and_a_turn_about_the_vertical_nothing():
    sugar = box(0.04, 0.09, 0.175)
    upright = np.eye(3)
    assert spread(sugar, upright, rot("z", 70)) == pytest.approx(1.0, abs=1e-6)
    swung = spread(sugar, upright, rot("x", 45))
    # upright: 9 x 4 cm (diagonal 9.8 cm); swung about its thin side: 4 x (9 + 17.5) / sqrt 2 cm
    assert swung == pytest.approx(np.hypot(0.04, (0.09 + 0.175) / np.sqrt(2)) / np.hypot(0.09, 0.04), rel=1e-6)
    assert swung > 1.9 > UPRIGHT_SPREAD
    # a slight sway is still upright; measured from a start that was already yawed
    assert spread(sugar, rot("z", 30), rot("zx", [30, 8])) <= UPRIGHT_SPREAD


def test_a_ball_does_not_spread_however_it_turns_and_a_cube_only_when_tipped_far():
    k = np.arange(400) + 0.5  # points spread evenly over a 6.8 cm sphere
    polar, azimuth = np.arccos(1 - 2 * k / 400), np.pi * (1 + 5**0.5) * k
    ball = ObjectShape([ConvexPart.of_points(0.034 * np.stack(
        [np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)], axis=1))])
    for turn in (rot("x", 60), rot("xy", [20, 35]), rot("zyx", [10, 80, 45])):
        assert spread(ball, np.eye(3), turn) == pytest.approx(1.0, abs=0.03)
    cube = box(0.05, 0.05, 0.05)
    assert spread(cube, np.eye(3), rot("x", 12)) <= UPRIGHT_SPREAD < spread(cube, np.eye(3), rot("xy", [35, 35]))
