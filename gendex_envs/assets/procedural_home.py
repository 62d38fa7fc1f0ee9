"""Around the home: the rest of a chess set, toys and balls, bathroom and desk things, a flower pot and a few
household objects, at real size and mass.

Built from the same exact convex pieces as the rest of the catalogue (see
:mod:`gendex_envs.assets.procedural_household`, whose helpers it uses) and registered into
:data:`gendex_envs.assets.procedural_shapes.GENERATORS`.
"""

from __future__ import annotations

import numpy as np

from gendex_envs.assets.procedural import (
    SOURCE_PRIMITIVES,
    SOURCE_REVOLVE,
    Parts,
    box_pts,
    cyl_between,
    ellipsoid_pts,
    revolved_solid,
    rounded_box_pts,
)
from gendex_envs.assets.procedural_household import CHESS, HOUSEHOLD, TOILETRY, TOY, _revolved, _ring
from gendex_envs.assets.procedural_shapes import _ball, _box, _done, _register, _vessel_parts

DESK = ("graspable", "office")
WOOD = (0.9, 0.85, 0.7, 1.0)
"""Boxwood: the light chess pieces (the catalog's colour name for it is white)."""


def _base(r: float, h: float) -> tuple:
    """A chess piece's foot: a disc ``r`` cm across that bevels in over ``h`` cm."""
    return [(0, 0), (r, 0), (r, 0.4), (r - 0.4, h), (0, h)], ()


def _shapes(asset_id, parts, mass, friction, rgba, tags, source=SOURCE_PRIMITIVES, category=None, **params):
    return _done(parts, id=asset_id, category=category or asset_id, tags=tags, mass_kg=mass, friction=friction,
                 rgba=rgba, source=source, params=params)


# ------------------------------------------------------------------------------------------------ chess
_register("chess_pawn", _revolved("chess_pawn", [
    _base(1.8, 0.9), ([(0, 0.8), (1.05, 0.8), (0.6, 3.3), (0, 3.3)], ()),
    ([(0, 3.2), (1.0, 3.2), (1.0, 3.5), (0, 3.5)], ()),
    ([(0, 3.3), (0.6, 3.4), (0.95, 3.9), (1.0, 4.3), (0.9, 4.8), (0.5, 5.2), (0, 5.3)], ())], 0.03, 0.7, WOOD, CHESS))
_register("chess_bishop", _revolved("chess_bishop", [
    _base(1.9, 1.0), ([(0, 0.9), (1.15, 0.9), (0.65, 4.6), (0, 4.6)], ()),
    ([(0, 4.5), (1.1, 4.5), (1.1, 4.9), (0, 4.9)], ()),
    ([(0, 4.8), (0.7, 4.8), (1.0, 5.8), (0.95, 6.8), (0.5, 7.7), (0, 7.9)], ()),
    ([(0, 7.8), (0.3, 7.9), (0.35, 8.2), (0.2, 8.5), (0, 8.55)], ())], 0.045, 0.7, WOOD, CHESS))
_register("chess_queen", _revolved("chess_queen", [
    _base(2.0, 1.1), ([(0, 1.0), (1.25, 1.0), (0.75, 5.6), (0, 5.6)], ()),
    ([(0, 5.5), (1.25, 5.5), (1.25, 5.9), (0, 5.9)], ()),
    ([(0, 5.8), (0.8, 5.8), (1.35, 8.0), (1.35, 8.4), (0, 8.4)], ()),
    ([(0, 8.3), (0.4, 8.4), (0.45, 8.8), (0, 9.0)], ())],
    0.055, 0.7, WOOD, CHESS))


def _knight():
    """A knight: a revolved foot, the neck and the horse's head two slanted prisms 1.6 cm thick."""
    vis, hulls = revolved_solid(np.array(_base(1.9, 1.0)[0], dtype=np.float64))
    parts = Parts().add(vis, hulls)
    for poly in ([(-1.2, 0.9), (1.2, 0.9), (0.7, 4.2), (-1.2, 4.6)],
                 [(-1.3, 4.0), (0.5, 3.6), (2.0, 4.4), (1.6, 5.4), (-0.6, 6.2), (-1.3, 5.4)]):
        parts.convex(np.array([[x, y, z] for x, z in poly for y in (-0.8, 0.8)]), faceted=True)
    return _shapes("chess_knight", parts, 0.045, 0.7, WOOD, CHESS)


_register("chess_knight", _knight)

# ------------------------------------------------------------------------------------------------ toys and balls
_register("lacrosse_ball", _ball("lacrosse_ball", 3.15, 0.145, (0.93, 0.93, 0.93, 1.0), 0.9))
_register("squash_ball", _ball("squash_ball", 2.0, 0.024, (0.08, 0.08, 0.08, 1.0), 0.9))
_register("yo_yo", _revolved("yo_yo", [([(0, 0), (2.8, 0), (2.8, 1.5), (0, 1.5)], ()),
                                       ([(0, 1.4), (0.5, 1.4), (0.5, 2.1), (0, 2.1)], ()),
                                       ([(0, 2.0), (2.8, 2.0), (2.8, 3.5), (0, 3.5)], ())],
                             0.05, 0.8, (0.85, 0.15, 0.1, 1.0), TOY))
_register("bowling_pin", _revolved("bowling_pin", [
    ([(0, 0), (2.0, 0), (2.6, 3.0), (2.7, 5.0), (2.0, 8.5), (1.2, 10.5), (1.4, 12.5), (1.3, 13.5), (0.8, 14.5),
      (0, 14.8)], (5,))], 0.12, 0.6, (0.95, 0.95, 0.95, 1.0), TOY))
_register("letter_block", _box("letter_block", (4.5, 4.5, 4.5), 0.05, 0.7, (0.9, 0.78, 0.55, 1.0), TOY, 0.25))


def _toy_train():
    parts = Parts()
    parts.convex(rounded_box_pts((11.0, 4.2, 3.6), 0.4, (0, 0, 3.0)))
    parts.convex(box_pts((3.5, 4.2, 3.4), (-3.5, 0, 6.5)), faceted=True)
    parts.convex(cyl_between([3.5, 0, 4.7], [3.5, 0, 6.5], 0.7, n=12))
    for x in (-3.5, 0.0, 3.5):
        parts.convex(cyl_between([x, -2.5, 1.2], [x, 2.5, 1.2], 1.2, n=16))
    return _shapes("toy_train", parts, 0.15, 0.8, (0.15, 0.55, 0.25, 1.0), TOY)


def _toy_boat():
    """A toy boat: a hull narrowing to the keel and to the bow, and a cabin."""
    top = [(-7.0, -3.0), (3.0, -3.0), (7.0, 0.0), (3.0, 3.0), (-7.0, 3.0)]
    keel = [(-6.0, -1.2), (2.5, -1.2), (5.0, 0.0), (2.5, 1.2), (-6.0, 1.2)]
    hull = np.array([[x, y, 3.0] for x, y in top] + [[x, y, 0.0] for x, y in keel])
    parts = Parts().convex(hull, faceted=True)
    parts.convex(box_pts((5.0, 3.6, 2.5), (-2.0, 0, 4.2)), faceted=True)
    return _shapes("toy_boat", parts, 0.1, 0.7, (0.95, 0.95, 0.95, 1.0), TOY)


def _toy_robot():
    parts = Parts()
    for y in (-0.9, 0.9):
        parts.convex(box_pts((1.6, 1.4, 1.2), (0, y, 0.6)), faceted=True)
    parts.convex(rounded_box_pts((5.0, 3.6, 5.5), 0.3, (0, 0, 3.95)))
    parts.convex(rounded_box_pts((3.2, 3.0, 2.6), 0.3, (0, 0, 8.0)))
    parts.convex(cyl_between([0, 0, 9.2], [0, 0, 10.2], 0.15, n=8))
    return _shapes("toy_robot", parts, 0.12, 0.7, (0.55, 0.6, 0.7, 1.0), TOY)


def _piggy_bank():
    parts = Parts()
    for radii, centre, flat in (((6.0, 4.2, 4.2), (0, 0, 5.0), None), ((1.0, 1.0, 1.4), (3.5, 2.2, 1.2), -1.2),
                                ((1.0, 1.0, 1.4), (3.5, -2.2, 1.2), -1.2), ((1.0, 1.0, 1.4), (-3.5, 2.2, 1.2), -1.2),
                                ((1.0, 1.0, 1.4), (-3.5, -2.2, 1.2), -1.2), ((0.8, 1.4, 1.2), (6.0, 0, 5.2), None),
                                ((0.5, 0.9, 1.0), (3.6, 2.0, 8.6), None), ((0.5, 0.9, 1.0), (3.6, -2.0, 8.6), None)):
        parts.convex(ellipsoid_pts(radii, centre, 2, flat), ellipsoid_pts(radii, centre, flat_z=flat, n=100))
    return _shapes("piggy_bank", parts, 0.35, 0.6, (0.95, 0.55, 0.7, 1.0), HOUSEHOLD)


def _snow_globe():
    parts = Parts().add(*revolved_solid(np.array([(0, 0), (4.0, 0), (3.6, 2.5), (0, 2.5)], dtype=np.float64)))
    parts.convex(ellipsoid_pts([3.8] * 3, (0, 0, 5.8), 3), ellipsoid_pts([3.8] * 3, (0, 0, 5.8)))
    return _shapes("snow_globe", parts, 0.45, 0.5, (0.75, 0.85, 0.95, 1.0), HOUSEHOLD)


_register("toy_train", _toy_train)
_register("toy_boat", _toy_boat)
_register("toy_robot", _toy_robot)
_register("piggy_bank", _piggy_bank)
_register("snow_globe", _snow_globe)

# ------------------------------------------------------------------------------------------------ bathroom
_register("lotion_bottle", _revolved("lotion_bottle", [
    ([(0, 0), (3.0, 0), (3.2, 0.4), (3.2, 13.0), (2.6, 14.5), (1.2, 15.0), (0, 15.0)], ()),
    ([(0, 14.9), (1.3, 14.9), (1.3, 16.5), (0, 16.5)], ()), ([(0, 16.4), (0.4, 16.4), (0.4, 18.5), (0, 18.5)], ())],
    0.35, 0.6, (0.93, 0.93, 0.93, 1.0), TOILETRY))
_register("deodorant", _revolved("deodorant", [
    ([(0, 0), (3.0, 0), (3.2, 0.3), (3.2, 12.0), (3.0, 13.5), (0, 13.8)], ())], 0.15, 0.6, (0.2, 0.35, 0.75, 1.0),
    TOILETRY, squash_y=0.6))
_register("tissue_box", _box("tissue_box", (22.0, 11.5, 9.5), 0.15, 0.6, (0.3, 0.55, 0.8, 1.0), TOILETRY, 0.3))


def _perfume_bottle():
    parts = Parts().convex(rounded_box_pts((6.0, 3.6, 8.0), 0.4, (0, 0, 4.0)))
    parts.convex(cyl_between([0, 0, 7.9], [0, 0, 10.5], 1.2, n=16))
    return _shapes("perfume_bottle", parts, 0.25, 0.5, (0.95, 0.55, 0.7, 1.0), TOILETRY)


def _loofah():
    radii, centre, flat = (6.0, 3.6, 3.2), (0, 0, 2.6), -2.6
    parts = Parts().convex(ellipsoid_pts(radii, centre, 3, flat), ellipsoid_pts(radii, centre, flat_z=flat, n=100))
    return _shapes("loofah", parts, 0.04, 1.2, (0.85, 0.75, 0.5, 1.0), TOILETRY)


_register("perfume_bottle", _perfume_bottle)
_register("loofah", _loofah)
_register("toilet_roll", _ring("toilet_roll", 2.2, 5.5, 10.0, 0.1, 0.9, (0.95, 0.95, 0.95, 1.0), TOILETRY))

# ------------------------------------------------------------------------------------------------ desk
_register("paperweight", _revolved("paperweight", [
    ([(0, 0), (3.8, 0), (3.8, 0.3), (3.3, 2.5), (2.2, 4.2), (0, 4.9)], ())], 0.4, 0.5, (0.6, 0.8, 0.9, 1.0), DESK))
_register("glue_bottle", _revolved("glue_bottle", [
    ([(0, 0), (2.2, 0), (2.3, 0.3), (2.3, 10.0), (1.6, 11.0), (0.9, 11.5), (0, 11.6)], ()),
    ([(0, 11.5), (0.9, 11.5), (0.3, 14.0), (0, 14.0)], ())], 0.13, 0.6, (0.95, 0.95, 0.9, 1.0), DESK))
_register("whiteboard_eraser", _box("whiteboard_eraser", (15.0, 5.5, 3.6), 0.1, 0.8, (0.1, 0.1, 0.12, 1.0), DESK,
                                    0.3))


def _hole_punch():
    parts = Parts().convex(rounded_box_pts((13.0, 8.0, 2.5), 0.3, (0, 0, 1.25)))
    parts.convex(rounded_box_pts((11.0, 4.0, 2.0), 0.4, (0.5, 0, 3.4)))
    return _shapes("hole_punch", parts, 0.45, 0.6, (0.5, 0.5, 0.55, 1.0), DESK)


_register("hole_punch", _hole_punch)

# ------------------------------------------------------------------------------------------------ household
_register("light_bulb", _revolved("light_bulb", [
    ([(0, 0), (1.3, 0), (1.35, 2.6), (0, 2.6)], ()),
    ([(0, 2.5), (1.35, 2.5), (2.2, 3.6), (2.75, 4.9), (3.0, 6.5), (2.9, 8.0), (2.3, 9.5), (1.2, 10.5), (0, 10.8)], ())],
    0.035, 0.5, (0.93, 0.93, 0.93, 1.0), HOUSEHOLD))
_register("hourglass", _revolved("hourglass", [
    ([(0, 0), (4.0, 0), (4.0, 1.0), (0, 1.0)], ()),
    ([(0, 1.0), (3.2, 1.0), (3.3, 3.0), (2.5, 5.5), (0.5, 7.5), (0, 7.5)], ()),
    ([(0, 7.5), (0.5, 7.5), (2.5, 9.5), (3.3, 12.0), (3.2, 14.0), (0, 14.0)], ()),
    ([(0, 14.0), (4.0, 14.0), (4.0, 15.0), (0, 15.0)], ())], 0.35, 0.6, (0.6, 0.4, 0.2, 1.0), HOUSEHOLD))
_register("paint_can", _revolved("paint_can", [([(0, 0), (4.25, 0), (4.25, 9.0), (4.1, 9.5), (0, 9.5)], ())],
                                 0.55, 0.6, (0.7, 0.7, 0.72, 1.0), HOUSEHOLD))
_register("alarm_clock", _box("alarm_clock", (12.0, 6.0, 7.0), 0.3, 0.6, (0.08, 0.08, 0.08, 1.0), HOUSEHOLD, 1.0))


def _spray_bottle():
    vis, hulls = revolved_solid(np.array([(0, 0), (3.0, 0), (3.2, 0.4), (3.2, 14.0), (2.2, 16.0), (1.5, 16.5),
                                          (0, 16.5)], dtype=np.float64))
    parts = Parts().add(vis, hulls)
    parts.convex(rounded_box_pts((6.0, 3.0, 4.0), 0.4, (1.2, 0, 18.4)))
    parts.convex(box_pts((1.0, 1.5, 3.0), (3.2, 0, 15.6)), faceted=True)
    return _shapes("spray_bottle", parts, 0.45, 0.6, (0.3, 0.75, 0.55, 1.0), HOUSEHOLD, source=SOURCE_REVOLVE)


def _flower_pot():
    """A terracotta flower pot, empty: a tapered vessel 15 cm across at the rim, 11.5 cm high."""
    parts = _vessel_parts([(0, 0), (5.0, 0), (5.2, 0.3), (7.5, 11.5)], 0.8, 1.0, wedges=20)
    return _shapes("flower_pot", parts, 0.5, 0.7, (0.75, 0.4, 0.25, 1.0), ("container", "household"),
                   source=SOURCE_REVOLVE, material="terracotta")


_register("spray_bottle", _spray_bottle)
_register("flower_pot", _flower_pot)

__all__ = ["DESK", "WOOD"]
