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


def test_a_swung_object_fits_what_it_is_set_on_when_its_footprint_does():
    """fits_on: a bottle caged 25 degrees over still fits a 22 cm bowl (the side grasp that holds it is taken, where
    the upright rule alone passed it over for pinches that slipped in the carry); a sugar box swung 45 degrees fits
    neither a 16 cm bowl nor a 20 cm board."""
    from gendex.solve.grasp_trial import FIT_FRACTION, fits_on

    def posed(shape: ObjectShape, r: np.ndarray | None = None):
        m = np.eye(4)
        m[:3, :3] = np.eye(3) if r is None else r
        return shape.posed(m)

    cylinder = ObjectShape([ConvexPart.of_points(np.array(
        [[0.033 * np.cos(a), 0.033 * np.sin(a), z] for a in np.linspace(0, 2 * np.pi, 24, endpoint=False)
         for z in (-0.1, 0.1)]))])
    bottle_swung = spread(cylinder, np.eye(3), rot("x", 25))
    assert bottle_swung > UPRIGHT_SPREAD  # the upright rule alone would pass the cage over
    large_bowl, bowl, board = box(0.22, 0.22, 0.07), box(0.16, 0.16, 0.06), box(0.3, 0.2, 0.02)
    assert fits_on(posed(cylinder), posed(large_bowl))(bottle_swung)
    assert not fits_on(posed(cylinder), posed(bowl))(bottle_swung)  # 0.8 x 16 cm = 12.8 cm < its 15.9 cm
    sugar = box(0.04, 0.09, 0.175)
    swung = spread(sugar, np.eye(3), rot("x", 45))
    for target in (bowl, board):
        assert not fits_on(posed(sugar), posed(target))(swung)
        assert fits_on(posed(sugar), posed(target))(1.0)  # upright, it fits both
    # the room is the target's narrower side, whatever its yaw
    assert fits_on(posed(sugar), posed(board, rot("z", 40)))(1.5) == (1.5 * np.hypot(0.09, 0.04)
                                                                       <= FIT_FRACTION * 0.2 + 1e-9)
