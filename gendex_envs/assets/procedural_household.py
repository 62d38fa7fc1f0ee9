"""Everyday things of a kitchen, a desk, a bathroom and a toy box, at real size: produce, kitchen and bathroom items,
toys and games, a few household tools, open containers to put things in and flat things to set them on.

Each is built from the same exact convex pieces as the rest of the catalogue (bands of a solid of revolution whose
radius is concave in height, boxes, ellipsoids, lofts of two convex sections) and registers into
:data:`gendex_envs.assets.procedural_shapes.GENERATORS`. Sizes and masses are those of the common real object
(a kiwi 6.6 cm and 75 g, a pool ball 57 mm and 170 g, a roll of duct tape 10 cm across); friction follows the
material (rubber and fur 1.0, fruit 0.9, wood 0.7, plastic, glass, wax and metal 0.6).
"""

from __future__ import annotations

import numpy as np
import trimesh

from gendex_envs.assets.procedural import (
    SOURCE_PRIMITIVES,
    SOURCE_REVOLVE,
    Parts,
    box_pts,
    cyl_between,
    ellipsoid_pts,
    revolved_solid,
    ring_hulls,
    rounded_box_pts,
)
from gendex_envs.assets.procedural_shapes import (
    BOX,
    FRUIT,
    _ball,
    _box,
    _done,
    _fruit,
    _fruit_profile,
    _register,
    _surface,
    _tool,
)

VEGETABLE = ("graspable", "food", "vegetable")
KITCHEN = ("graspable", "kitchenware")
TOY = ("graspable", "toy")
CHESS = ("graspable", "toy", "chess")
HOUSEHOLD = ("graspable", "household")
OFFICE = ("graspable", "office", "tool")
TOILETRY = ("graspable", "toiletry")
OPEN_BOX = ("container", "kitchenware")
"""An open box or basket things are put in: not grasped itself (it is wider than the hand)."""


# ------------------------------------------------------------------------------------------------ produce
def _produce(asset_id, R, H, mass, rgba, amp, tags=FRUIT, stem=None, lying=False, flat=None, **profile):
    return lambda: _fruit(asset_id, _fruit_profile(R, H, **profile), mass, rgba, amp, stem=stem, lying=lying,
                          flat=flat, tags=tags)


def _pointed(asset_id, R, H, point, mass, rgba, amp, stem, tags):
    """A bulb that narrows to a point at the top (an onion, a head of garlic): the radius falls off faster the
    higher it is (``point`` how much faster)."""
    t = np.linspace(0, np.pi, 26)
    r = R * np.sin(t) ** (1 + point * (t / np.pi) ** 3)
    r[[0, -1]] = 0.0
    prof = np.column_stack([r, H / 2 * (1 - np.cos(t))])
    return lambda: _fruit(asset_id, prof, mass, rgba, amp, stem=stem, flat=0.3, tags=tags)


def _long(asset_id, length, R, bluntness, mass, rgba, amp, tags, taper=0.0):
    """Produce lying on its side, ``length`` cm long and ``R`` cm round (a cucumber, a potato, a carrot):
    ``bluntness`` < 1 squares the ends off; ``taper`` > 0 narrows one end (a carrot's tip)."""
    x = length / 2 * -np.cos(np.linspace(0, np.pi, 30))
    u = (x + length / 2) / length
    r = R * np.clip(1 - (2 * x / length) ** 2, 0, None) ** bluntness * (1 - taper * (1 - u) ** 1.5)
    r[[0, -1]] = 0.0
    return lambda: _fruit(asset_id, np.column_stack([r, x]), mass, rgba, amp, lying=True, tags=tags)


def _egg():
    t = np.linspace(0, np.pi, 26)
    r = 2.2 * np.sin(t) * (1 + 0.1 * np.cos(t))
    r[[0, -1]] = 0.0
    return _fruit("egg", np.column_stack([r, 2.9 * (1 - np.cos(t))]), 0.06, (0.96, 0.9, 0.78, 1.0), 0.0,
                  friction=0.6, lying=True, tags=("graspable", "food"))


def _avocado():
    """Pear-shaped: a round bulb and a narrower neck, joined smoothly; it stands on a flattened bottom."""
    z = 10.0 * (1 - np.cos(np.linspace(0, np.pi, 30))) / 2
    r1 = 3.4 * np.sqrt(np.clip(1 - ((z - 3.5) / 3.5) ** 2, 0, None))
    r2 = 2.4 * np.sqrt(np.clip(1 - ((z - 6.6) / 3.4) ** 2, 0, None))
    r = (r1**2.5 + r2**2.5) ** 0.4
    r[[0, -1]] = 0.0
    return _fruit("avocado", np.column_stack([r, z]), 0.2, (0.2, 0.3, 0.1, 1.0), 0.03, stem=0.5, flat=0.5)


_register("kiwi", _produce("kiwi", 2.6, 6.6, 0.075, (0.5, 0.36, 0.2, 1.0), 0.04, lying=True))
_register("lime", _produce("lime", 2.8, 5.8, 0.067, (0.4, 0.72, 0.2, 1.0), 0.02, lying=True, top_dimple=0.15,
                           bottom_dimple=0.1))
_register("tomato", _produce("tomato", 3.6, 5.4, 0.12, (0.85, 0.12, 0.08, 1.0), 0.05, tags=VEGETABLE, stem=0.6,
                             top_dimple=0.5, bottom_dimple=0.15))
_register("bell_pepper", _produce("bell_pepper", 3.9, 8.0, 0.17, (0.9, 0.15, 0.05, 1.0), 0.06, tags=VEGETABLE,
                                  stem=1.8, flat=0.4, top_bulge=0.12, top_dimple=0.8, bottom_dimple=0.5))
_register("mango", _produce("mango", 3.6, 10.5, 0.3, (0.95, 0.62, 0.15, 1.0), 0.05, lying=True))
_register("grapefruit", _produce("grapefruit", 4.9, 9.4, 0.35, (0.98, 0.72, 0.35, 1.0), 0.015, top_dimple=0.2,
                                 bottom_dimple=0.15))
_register("onion", _pointed("onion", 3.7, 7.4, 1.5, 0.17, (0.8, 0.6, 0.3, 1.0), 0.04, 1.0, VEGETABLE))
_register("garlic", _pointed("garlic", 3.0, 5.4, 2.5, 0.05, (0.93, 0.9, 0.84, 1.0), 0.06, 0.8, VEGETABLE))
_register("potato", _long("potato", 9.2, 3.0, 0.5, 0.2, (0.72, 0.56, 0.36, 1.0), 0.06, VEGETABLE))
_register("cucumber", _long("cucumber", 20.0, 2.2, 0.3, 0.3, (0.18, 0.42, 0.12, 1.0), 0.02, VEGETABLE))
_register("carrot", _long("carrot", 17.0, 2.1, 0.25, 0.07, (0.95, 0.45, 0.08, 1.0), 0.02, VEGETABLE, taper=0.55))
_register("egg", _egg)
_register("avocado", _avocado)


# ------------------------------------------------------------------------------------------------ kitchen and bathroom
def _revolved(asset_id, pieces, mass, friction, rgba, tags, squash_y=1.0, category=None):
    """A stack of solids of revolution, each given as (profile, splits) with a radius concave in height on every
    band; ``squash_y`` flattens the whole (a shampoo bottle is oval)."""
    def make():
        parts = Parts()
        for profile, splits in pieces:
            parts.add(*revolved_solid(np.asarray(profile, dtype=np.float64), splits))
        if squash_y != 1.0:
            parts.transform(np.diag([1.0, squash_y, 1.0, 1.0]))
        return _done(parts, id=asset_id, category=category or asset_id, tags=tags, mass_kg=mass, friction=friction,
                     rgba=rgba, source=SOURCE_REVOLVE)
    return make


_register("salt_shaker", _revolved("salt_shaker", [([(0, 0), (2.0, 0), (2.1, 0.2), (2.1, 7.0), (1.9, 8.2),
                                                     (1.3, 8.9), (0, 9.1)], ())], 0.12, 0.6,
                                   (0.95, 0.95, 0.95, 1.0), KITCHEN))
_register("pepper_mill", _revolved("pepper_mill", [([(0, 0), (2.6, 0), (2.75, 0.4), (2.75, 3.5), (2.2, 7.5),
                                                     (2.2, 10.5), (2.75, 12.5), (2.6, 14.2), (1.6, 15.2), (1.0, 15.8),
                                                     (0, 16.4)], (4, 5))], 0.3, 0.7, (0.4, 0.24, 0.12, 1.0), KITCHEN))
_register("spice_jar", _revolved("spice_jar", [([(0, 0), (2.2, 0), (2.3, 0.2), (2.3, 9.8), (2.15, 10.0), (0, 10.0)],
                                                 ())], 0.12, 0.6, (0.65, 0.3, 0.15, 1.0), KITCHEN))
_register("yogurt_cup", _revolved("yogurt_cup", [([(0, 0), (2.7, 0), (2.8, 0.2), (3.6, 8.0), (3.75, 8.1),
                                                   (3.75, 8.3), (0, 8.3)], (3,))], 0.13, 0.6,
                                  (0.95, 0.95, 0.9, 1.0), ("graspable", "food")))
_register("candle", _revolved("candle", [([(0, 0), (2.5, 0), (2.5, 9.8), (2.4, 10.0), (0, 10.0)], ()),
                                         ([(0, 9.9), (0.1, 9.9), (0.1, 11.0), (0, 11.0)], ())], 0.17, 0.6,
                              (0.95, 0.9, 0.75, 1.0), HOUSEHOLD))
_register("shampoo_bottle", _revolved("shampoo_bottle", [([(0, 0), (3.5, 0), (3.7, 0.4), (3.7, 15.5), (3.2, 17.0),
                                                           (1.4, 17.8), (0, 17.8)], ()),
                                                          ([(0, 17.6), (1.4, 17.6), (1.4, 20.0), (0, 20.0)], ())],
                                      0.45, 0.6, (0.2, 0.65, 0.7, 1.0), TOILETRY, squash_y=0.6))
_register("service_bell", _revolved("service_bell", [([(0, 0), (4.2, 0), (4.2, 0.6), (0, 0.6)], ()),
                                                     ([(0, 0.6), (3.8, 0.6), (3.6, 2.0), (3.0, 3.4), (2.0, 4.4),
                                                       (0, 4.9)], ()),
                                                     ([(0, 4.8), (0.4, 4.8), (0.4, 6.0), (0, 6.0)], ()),
                                                     ([(0, 5.9), (0.6, 6.1), (0.7, 6.5), (0.5, 6.9), (0, 7.0)], ())],
                                    0.25, 0.6, (0.85, 0.72, 0.3, 1.0), HOUSEHOLD))
_register("juice_box", _box("juice_box", (6.3, 4.0, 10.5), 0.22, 0.6, (0.3, 0.7, 0.2, 1.0), BOX, 0.2))
_register("soap_bar", _box("soap_bar", (9.0, 6.0, 3.2), 0.13, 0.6, (0.95, 0.7, 0.8, 1.0), TOILETRY, 0.9))


def _milk_carton():
    """A half-pint school milk carton: a 6.4 cm square box, its gable top and the sealed fin along the ridge."""
    parts = Parts()
    parts.convex(box_pts((6.4, 6.4, 7.6), (0, 0, 3.8)), faceted=True)
    gable = np.array([[x, y, z] for y in (-3.2, 3.2) for x, z in ((-3.2, 7.6), (3.2, 7.6), (0.0, 9.6))])
    parts.convex(gable, faceted=True)
    parts.convex(box_pts((0.5, 6.4, 1.0), (0, 0, 9.9)), faceted=True)
    return _done(parts, id="milk_carton", category="milk_carton", tags=BOX, mass_kg=0.25, friction=0.6,
                 rgba=(0.95, 0.95, 0.97, 1.0), source=SOURCE_PRIMITIVES)


def _toothpaste_tube():
    """A tube lying on the table: round at the cap end, pressed flat into a seam at the other (one convex loft),
    and its cap."""
    t = 2 * np.pi * np.arange(20) / 20
    cap_end = np.column_stack([np.zeros(20), 1.8 * np.cos(t), 1.8 + 1.8 * np.sin(t)])
    seam = np.column_stack([np.full(20, 16.0), 2.5 * np.cos(t), 1.8 + 0.15 * np.sin(t)])
    parts = Parts()
    parts.convex(np.vstack([cap_end, seam]))
    parts.convex(cyl_between([-1.6, 0, 1.8], [0.1, 0, 1.8], 1.0, n=16))
    return _done(parts, id="toothpaste_tube", category="toothpaste_tube", tags=TOILETRY, mass_kg=0.12, friction=0.7,
                 rgba=(0.95, 0.95, 0.97, 1.0), source=SOURCE_PRIMITIVES, params={"rest": "lying"})


def _rolling_pin():
    """A wooden rolling pin lying on its barrel (16 cm, 4.8 cm across), a narrower handle at each end."""
    parts = Parts()
    parts.convex(cyl_between([4.0, 0, 2.4], [20.0, 0, 2.4], 2.4, n=24))
    for x0, x1 in ((0.0, 4.2), (19.8, 24.0)):
        parts.convex(cyl_between([x0, 0, 2.4], [x1, 0, 2.4], 1.3, n=16))
    return _tool("rolling_pin", parts, 0.3, 0.7, (0.85, 0.68, 0.45, 1.0), tags=("graspable", "tool", "kitchenware"))


def _flashlight():
    """A torch lying on its side: a tube 3.8 cm across, a wider head and its lens."""
    parts = Parts()
    parts.convex(cyl_between([0.0, 0, 2.6], [14.5, 0, 2.6], 1.9, n=20))
    parts.convex(np.vstack([cyl_between([14.0, 0, 2.6], [15.0, 0, 2.6], 1.9, n=20),
                            cyl_between([18.5, 0, 2.6], [19.0, 0, 2.6], 2.6, n=20)]))
    return _tool("flashlight", parts, 0.25, 0.7, (0.95, 0.75, 0.1, 1.0), tags=("graspable", "tool", "household"))


_register("milk_carton", _milk_carton)
_register("toothpaste_tube", _toothpaste_tube)
_register("rolling_pin", _rolling_pin)
_register("flashlight", _flashlight)


# ------------------------------------------------------------------------------------------------ toys and games
_register("pool_ball", _ball("pool_ball", 2.86, 0.17, (0.95, 0.8, 0.1, 1.0), 0.6))
_register("cricket_ball", _ball("cricket_ball", 3.6, 0.16, (0.65, 0.1, 0.08, 1.0), 0.7))
_register("rubber_ball", _ball("rubber_ball", 3.2, 0.06, (0.55, 0.2, 0.75, 1.0), 1.0))
_register("chess_king", _revolved("chess_king", [([(0, 0), (2.0, 0), (2.0, 0.5), (1.6, 1.1), (0, 1.1)], ()),
                                                 ([(0, 1.0), (1.25, 1.0), (0.85, 6.0), (0, 6.0)], ()),
                                                 ([(0, 5.8), (1.35, 5.8), (1.35, 6.3), (0, 6.3)], ()),
                                                 ([(0, 6.2), (0.9, 6.2), (1.25, 7.6), (1.1, 8.4), (0, 8.6)], ()),
                                                 ([(0, 8.5), (0.25, 8.5), (0.25, 9.9), (0, 9.9)], ())],
                                  0.06, 0.7, (0.9, 0.85, 0.7, 1.0), CHESS))
_register("chess_rook", _revolved("chess_rook", [([(0, 0), (1.9, 0), (1.9, 0.5), (1.5, 1.0), (0, 1.0)], ()),
                                                 ([(0, 0.9), (1.3, 0.9), (1.05, 4.2), (0, 4.2)], ()),
                                                 ([(0, 4.1), (1.4, 4.1), (1.4, 5.6), (0, 5.6)], ())],
                                  0.04, 0.7, (0.12, 0.12, 0.12, 1.0), CHESS))


def _toy_car():
    """A toy car: a rounded body on four wheels and a cabin on top."""
    parts = Parts()
    parts.convex(rounded_box_pts((10.0, 4.6, 2.2), 0.5, (0, 0, 2.2)))
    parts.convex(rounded_box_pts((5.0, 4.0, 1.8), 0.5, (-0.6, 0, 3.9)))
    for x in (-3.2, 3.2):
        for y in (-2.3, 2.3):
            parts.convex(cyl_between([x, y - 0.4, 1.1], [x, y + 0.4, 1.1], 1.1, n=16))
    return _done(parts, id="toy_car", category="toy_car", tags=TOY, mass_kg=0.12, friction=0.8,
                 rgba=(0.85, 0.15, 0.1, 1.0), source=SOURCE_PRIMITIVES)


def _teddy_bear():
    """A sitting teddy bear: body, legs, arms, head, ears and muzzle, each an ellipsoid; it sits on the flat of its
    body and its legs."""
    parts = Parts()
    for radii, centre, flat in (((3.6, 3.2, 4.4), (0, 0, 3.8), -3.8), ((2.0, 1.4, 1.2), (1.6, 1.8, 1.2), -1.2),
                                ((2.0, 1.4, 1.2), (1.6, -1.8, 1.2), -1.2), ((1.0, 1.0, 2.2), (0.8, 3.3, 5.6), None),
                                ((1.0, 1.0, 2.2), (0.8, -3.3, 5.6), None), ((2.8, 2.8, 2.8), (0, 0, 9.8), None),
                                ((1.0, 0.5, 1.0), (0, 2.2, 12.0), None), ((1.0, 0.5, 1.0), (0, -2.2, 12.0), None),
                                ((1.2, 1.2, 0.9), (2.5, 0, 9.4), None)):
        parts.convex(ellipsoid_pts(radii, centre, 2, flat), ellipsoid_pts(radii, centre, flat_z=flat, n=100))
    return _done(parts, id="teddy_bear", category="teddy_bear", tags=TOY, mass_kg=0.12, friction=1.0,
                 rgba=(0.6, 0.4, 0.22, 1.0), source=SOURCE_PRIMITIVES)


_register("toy_car", _toy_car)
_register("teddy_bear", _teddy_bear)


# ------------------------------------------------------------------------------------------------ desk
def _ring(asset_id, r_in, r_out, h, mass, friction, rgba, tags):
    """A hollow cylinder standing on its end, ``r_in`` to ``r_out`` cm round and ``h`` cm high (a roll of tape, a
    toilet roll, a doughnut): 16 overlapping ring sectors."""
    def make():
        visual = trimesh.creation.annulus(r_in, r_out, h, sections=48)
        visual.apply_translation([0, 0, h / 2])
        parts = Parts().add(visual, ring_hulls(r_in, r_out, 0.0, h, pieces=16, overlap=0.05))
        return _done(parts, id=asset_id, category=asset_id, tags=tags, mass_kg=mass, friction=friction, rgba=rgba,
                     source=SOURCE_PRIMITIVES)
    return make


def _stapler():
    """A desk stapler: a base plate, the arm above it and the hinge block joining them at the back."""
    parts = Parts()
    parts.convex(rounded_box_pts((15.0, 4.0, 1.2), 0.3, (0, 0, 0.6)))
    parts.convex(rounded_box_pts((14.0, 3.2, 2.6), 0.6, (0.4, 0, 3.2)))
    parts.convex(box_pts((2.4, 3.2, 1.2), (-6.2, 0, 1.6)), faceted=True)
    return _done(parts, id="stapler", category="stapler", tags=OFFICE, mass_kg=0.25, friction=0.7,
                 rgba=(0.15, 0.15, 0.18, 1.0), source=SOURCE_PRIMITIVES)


# a roll of duct tape lying flat: 10 cm across, 5 cm high, its core 7.6 cm across
_register("tape_roll", _ring("tape_roll", 3.8, 5.0, 5.0, 0.15, 0.8, (0.6, 0.6, 0.62, 1.0), HOUSEHOLD))
_register("stapler", _stapler)


# ------------------------------------------------------------------------------------------------ open containers
def _open_box(asset_id, size, wall, floor, mass, friction, rgba, material):
    """An open box ``size`` (x, y, height) cm: a floor and four walls ``wall`` thick, each its own convex part; its
    ``cavity`` and ``rim`` anchors are on the axis, like a vessel's."""
    def make():
        x, y, h = size
        parts = Parts()
        parts.convex(box_pts((x, y, floor), (0, 0, floor / 2)), faceted=True)
        for sx in (-1, 1):
            parts.convex(box_pts((wall, y, h - floor), (sx * (x - wall) / 2, 0, (h + floor) / 2)), faceted=True)
        for sy in (-1, 1):
            parts.convex(box_pts((x - 2 * wall, wall, h - floor), (0, sy * (y - wall) / 2, (h + floor) / 2)),
                         faceted=True)
        parts.anchors.update(cavity=np.array([0.0, 0.0, floor]), rim=np.array([0.0, 0.0, h]))
        return _done(parts, id=asset_id, category=asset_id, tags=OPEN_BOX, mass_kg=mass, friction=friction, rgba=rgba,
                     source=SOURCE_PRIMITIVES, params={"material": material})
    return make


_register("basket", _open_box("basket", (28.0, 20.0, 10.0), 0.8, 0.8, 0.4, 0.8, (0.72, 0.55, 0.3, 1.0), "wicker"))
_register("baking_dish", _open_box("baking_dish", (26.0, 18.0, 6.0), 1.0, 1.0, 1.0, 0.6, (0.9, 0.88, 0.85, 1.0),
                                   "ceramic"))
_register("storage_bin", _open_box("storage_bin", (30.0, 20.0, 11.5), 0.6, 0.6, 0.4, 0.6, (0.3, 0.5, 0.8, 1.0),
                                   "plastic"))


# ------------------------------------------------------------------------------------------------ flat things to set on
_register("placemat", _surface("placemat", (38.0, 28.0, 0.4), 0.1, 0.9, (0.55, 0.35, 0.6, 1.0), bevel=0.15))
_register("baking_sheet", _surface("baking_sheet", (33.0, 23.0, 0.5), 0.35, 0.5, (0.7, 0.7, 0.72, 1.0),
                                   rim=(1.5, 0.5)))

__all__ = ["CHESS", "HOUSEHOLD", "KITCHEN", "OFFICE", "OPEN_BOX", "TOILETRY", "TOY", "VEGETABLE"]
