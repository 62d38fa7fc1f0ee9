"""The pantry: more produce, bottles and jars, boxes and baked things, at real size and mass.

Built from the same exact convex pieces as the rest of the catalogue (see
:mod:`gendex_envs.assets.procedural_household`, whose helpers it uses) and registered into
:data:`gendex_envs.assets.procedural_shapes.GENERATORS`.
"""

from __future__ import annotations

import numpy as np

from gendex_envs.assets.procedural import SOURCE_PRIMITIVES, Parts, ellipsoid_pts
from gendex_envs.assets.procedural_household import VEGETABLE, _long, _pointed, _produce, _revolved, _ring
from gendex_envs.assets.procedural_shapes import BOX, FRUIT, _box, _done, _register

FOOD = ("graspable", "food")

# ------------------------------------------------------------------------------------------------ produce
_register("zucchini", _long("zucchini", 20.0, 2.2, 0.3, 0.25, (0.15, 0.35, 0.1, 1.0), 0.02, VEGETABLE, taper=0.15))
_register("eggplant", _long("eggplant", 18.0, 3.8, 0.5, 0.3, (0.3, 0.1, 0.3, 1.0), 0.03, VEGETABLE, taper=0.45))
_register("sweet_potato", _long("sweet_potato", 14.0, 2.8, 0.6, 0.25, (0.7, 0.35, 0.25, 1.0), 0.06, VEGETABLE,
                                taper=0.3))
_register("corn", _long("corn", 18.0, 2.6, 0.4, 0.25, (0.95, 0.8, 0.2, 1.0), 0.02, VEGETABLE, taper=0.3))
_register("pumpkin", _produce("pumpkin", 5.0, 8.0, 0.45, (0.95, 0.5, 0.08, 1.0), 0.05, tags=VEGETABLE, stem=2.0,
                              top_dimple=0.8, bottom_dimple=0.4))
_register("beetroot", _produce("beetroot", 3.0, 6.5, 0.15, (0.5, 0.08, 0.2, 1.0), 0.05, tags=VEGETABLE, stem=1.0,
                               flat=0.4, top_dimple=0.3))
_register("pomegranate", _produce("pomegranate", 4.2, 8.0, 0.3, (0.7, 0.1, 0.12, 1.0), 0.04, stem=1.2, flat=0.4,
                                  top_dimple=0.2, bottom_dimple=0.2))
_register("passion_fruit", _produce("passion_fruit", 3.2, 6.6, 0.05, (0.35, 0.12, 0.3, 1.0), 0.03, stem=0.6))
_register("fig", _pointed("fig", 2.6, 5.5, 1.0, 0.05, (0.4, 0.15, 0.3, 1.0), 0.05, 0.8, FRUIT))

# ------------------------------------------------------------------------------------------------ bottles and jars
_register("ketchup_bottle", _revolved("ketchup_bottle", [
    ([(0, 0), (2.9, 0), (3.2, 0.5), (3.3, 13.0), (2.6, 16.0), (1.4, 17.2), (0, 17.2)], ()),
    ([(0, 17.0), (1.5, 17.0), (1.5, 19.0), (1.0, 19.6), (0, 19.6)], ())], 0.45, 0.6, (0.8, 0.1, 0.05, 1.0), FOOD,
    squash_y=0.7))
_register("honey_jar", _revolved("honey_jar", [
    ([(0, 0), (3.3, 0), (3.5, 0.3), (3.5, 7.5), (3.1, 8.3), (3.2, 8.4), (3.2, 10.0), (0, 10.0)], (4,))],
    0.45, 0.5, (0.85, 0.55, 0.1, 1.0), FOOD))
_register("olive_oil_bottle", _revolved("olive_oil_bottle", [
    ([(0, 0), (2.7, 0), (2.9, 0.4), (2.9, 17.0), (2.4, 19.5), (1.3, 21.5), (1.2, 23.5), (0, 23.5)], (5,))],
    0.55, 0.5, (0.25, 0.35, 0.1, 1.0), FOOD))
_register("beer_bottle", _revolved("beer_bottle", [
    ([(0, 0), (2.9, 0), (3.1, 0.4), (3.1, 13.5), (2.5, 16.5), (1.4, 18.5), (1.3, 22.5), (1.45, 22.7), (1.45, 23.2),
      (0, 23.2)], (5, 6))], 0.5, 0.5, (0.45, 0.25, 0.08, 1.0), FOOD))
_register("ice_cream_tub", _revolved("ice_cream_tub", [
    ([(0, 0), (4.6, 0), (4.8, 0.3), (5.4, 9.0), (5.6, 9.1), (5.6, 9.6), (0, 9.6)], (3,))],
    0.5, 0.6, (0.95, 0.9, 0.8, 1.0), FOOD))
_register("muffin", _revolved("muffin", [
    ([(0, 0), (2.6, 0), (3.1, 4.0), (3.6, 4.4), (3.4, 5.6), (2.2, 6.5), (0, 6.8)], (2,))],
    0.09, 0.8, (0.6, 0.35, 0.2, 1.0), FOOD))

# ------------------------------------------------------------------------------------------------ boxes and blocks
_register("tea_tin", _box("tea_tin", (8.0, 8.0, 11.0), 0.15, 0.6, (0.55, 0.55, 0.6, 1.0), FOOD, 0.5))
_register("butter", _box("butter", (12.5, 6.5, 3.5), 0.25, 0.6, (0.98, 0.9, 0.5, 1.0), FOOD, 0.3))
_register("cereal_box", _box("cereal_box", (15.0, 5.5, 21.0), 0.3, 0.6, (0.95, 0.7, 0.15, 1.0), BOX))


def _cheese():
    """A wedge of cheese lying on its side: a triangular prism 10 cm long, 7 cm at the rind, 5 cm high."""
    tri = [(-5.0, 0.0), (5.0, -3.5), (5.0, 3.5)]
    parts = Parts().convex(np.array([[x, y, z] for x, y in tri for z in (0.0, 5.0)]), faceted=True)
    return _done(parts, id="cheese", category="cheese", tags=FOOD, mass_kg=0.2, friction=0.7,
                 rgba=(0.98, 0.82, 0.3, 1.0), source=SOURCE_PRIMITIVES)


def _bread_roll():
    radii, centre, flat = (5.0, 3.5, 2.8), (0, 0, 2.5), -2.3
    parts = Parts().convex(ellipsoid_pts(radii, centre, 3, flat), ellipsoid_pts(radii, centre, flat_z=flat, n=100))
    return _done(parts, id="bread_roll", category="bread_roll", tags=FOOD, mass_kg=0.06, friction=0.9,
                 rgba=(0.8, 0.55, 0.25, 1.0), source=SOURCE_PRIMITIVES)


_register("cheese", _cheese)
_register("bread_roll", _bread_roll)
# a ring doughnut lying flat: 9 cm across, 3.2 cm high, a 2.6 cm hole
_register("donut", _ring("donut", 1.3, 4.5, 3.2, 0.06, 0.9, (0.95, 0.55, 0.7, 1.0), FOOD))

__all__ = ["FOOD"]
