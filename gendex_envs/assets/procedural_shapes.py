"""The procedural object catalogue: one generator per asset id, all at real-world size.

Generators model in centimetres (the numbers read like a ruler) and :func:`_done` scales to metres and moves
the result into the asset frame. Shape variation is seeded from the asset id, so every build is identical.
Masses are real-world (YCB where the object is a YCB one); friction ~0.9 fruit and rubber, ~0.6 metal,
cardboard and ceramics, 0.5 glass, 1.2 sponge.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gendex_envs.assets.procedural import (
    SOURCE_PRIMITIVES,
    SOURCE_REVOLVE,
    SOURCE_TUBE,
    Parts,
    ProceduralShape,
    box_pts,
    cyl_between,
    ellipsoid_pts,
    finish,
    hull_mesh,
    prism_pts,
    revolve_mesh,
    revolve_pts,
    revolved_solid,
    ring_hulls,
    rng_for,
    rot,
    rounded_box_pts,
    tube,
    vessel,
    wobble,
)

CM = np.diag([0.01, 0.01, 0.01, 1.0])

FRUIT = ("graspable", "food", "fruit")
BALL = ("graspable", "ball", "toy")
VESSEL = ("graspable", "container", "tableware", "kitchenware")
BOX = ("graspable", "box", "food")
TOOL = ("graspable", "tool")
UTENSIL = ("graspable", "utensil", "tableware")
BLOCK = ("graspable", "block", "toy")
SURFACE = ("surface", "kitchenware")
HANDOVER = ("handover", "marker")
"""A hand-over zone: where the robot leaves things for a person to take (the ``hand_over`` task skill)."""

PEG = ("graspable", "peg", "toy")
HOLDER = ("holder", "insert")
"""Something a peg is inserted into: a fixed block with a hole a few millimetres wider than its peg (the ``insert``
task skill)."""
WIPER = ("graspable", "kitchenware", "wiper")
"""What wipes a spill: a sponge thick enough to be pinched high and pressed flat on it (the ``wipe`` task skill)."""
SPILL = ("spill", "wipe_area")
"""A marked area to wipe: a thin fixed stain on the table with marks a pressed sponge must pass over (the ``wipe``
task skill)."""

GENERATORS: dict[str, Callable[[], ProceduralShape]] = {}


def _register(asset_id: str, fn: Callable[[], ProceduralShape]) -> None:
    if asset_id in GENERATORS:
        raise ValueError(f"duplicate asset id {asset_id}")
    GENERATORS[asset_id] = fn


def _done(parts: Parts, **kw) -> ProceduralShape:
    return finish(parts.transform(CM), **kw)


# ------------------------------------------------------------------------------------------------ fruit
def _fruit_profile(R, H, n=24, top_bulge=0.0, top_dimple=0.0, bottom_dimple=0.0, w=0.3):
    """Polar fruit outline (r, z) from bottom pole to top pole: radius R, height H, wider top for top_bulge > 0,
    stem / blossom dimples of the given depths."""
    t = np.linspace(0, np.pi, n)
    r = R * np.sin(t) * (1 - top_bulge * np.cos(t))
    z = H / 2 * (1 - np.cos(t))
    z += bottom_dimple * np.exp(-((t / w) ** 2)) - top_dimple * np.exp(-(((np.pi - t) / w) ** 2))
    r[[0, -1]] = 0.0
    return np.column_stack([r, z])


def _fruit(asset_id, profile, mass, rgba, amp, splits=(), stem=None, friction=0.9, lying=False, flat=None, tags=FRUIT):
    """A solid of revolution with seeded asymmetry, optional stem (length cm) at the top, optional flat bottom
    (the profile cut at z = ``flat``, so it stands instead of rocking). Hulls: per band, the poles and at most 7
    rings of 16 points (<= 114 vertices), always including the lowest and the widest one."""
    rng = rng_for(asset_id)
    if flat is not None:
        keep = profile[:, 1] >= flat
        k = int(np.argmax(keep))
        a, b = profile[k - 1], profile[k]
        cut = a + (b - a) * (flat - a[1]) / (b[1] - a[1])
        profile = np.vstack([[0.0, flat], cut, profile[k:]])
        splits = tuple(s - k + 2 for s in splits)
    warp = wobble(rng, amp)
    parts = Parts()
    vis = revolve_mesh(profile, 40)
    vis.vertices = warp(vis.vertices)
    cuts = [0, *splits, len(profile) - 1]
    hulls = []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        idx = set(np.linspace(a, b, min(b - a + 1, 7)).round().astype(int))
        z_off_axis = np.where(profile[a:b + 1, 0] > 0, profile[a:b + 1, 1], np.inf)
        idx |= {a + int(np.argmin(z_off_axis)), a + int(np.argmax(profile[a:b + 1, 0]))}  # lowest ring, equator
        idx = sorted(idx)
        band = np.vstack([profile[idx], [[0.0, profile[a, 1]], [0.0, profile[b, 1]]]])
        hulls.append(warp(revolve_pts(band, 2 * np.pi * np.arange(16) / 16)))
    parts.add(vis, hulls)
    if stem:
        top = profile[-1, 1]
        tilt = rng.uniform(8, 20)
        base = np.array([0.0, 0.0, top - 0.3])
        tip = base + stem * np.array([0.0, np.sin(np.radians(tilt)), np.cos(np.radians(tilt))])
        parts.convex(cyl_between(base, tip, 0.17, 0.13, n=8))
    if lying:
        parts.transform(rot("y", 90))
    return _done(parts, id=asset_id, category=asset_id, tags=tags, mass_kg=mass, friction=friction, rgba=rgba,
                 source=SOURCE_REVOLVE, params={"amp": amp})


def _round_fruit(asset_id, R, H, mass, rgba, amp, stem=None, **kw):
    return lambda: _fruit(asset_id, _fruit_profile(R, H, **kw), mass, rgba, amp, stem=stem)


_register("apple", _round_fruit("apple", 3.8, 7.0, 0.15, (0.75, 0.1, 0.08, 1.0), 0.03, stem=1.3,
                                top_bulge=0.08, top_dimple=0.7, bottom_dimple=0.35))
_register("orange", _round_fruit("orange", 3.8, 7.2, 0.16, (1.0, 0.55, 0.05, 1.0), 0.015,
                                 top_dimple=0.15, bottom_dimple=0.1))
_register("peach", _round_fruit("peach", 3.45, 6.7, 0.15, (0.98, 0.62, 0.42, 1.0), 0.04, stem=0.4,
                                top_dimple=0.35, bottom_dimple=0.15))
_register("plum", _round_fruit("plum", 2.4, 5.2, 0.065, (0.42, 0.12, 0.32, 1.0), 0.03, stem=0.6,
                               top_dimple=0.25, bottom_dimple=0.1))


def _pear():
    z = 9.6 * (1 - np.cos(np.linspace(0, np.pi, 30))) / 2
    r1 = 3.2 * np.sqrt(np.clip(1 - ((z - 3.2) / 3.2) ** 2, 0, None))  # bulb
    r2 = 1.8 * np.sqrt(np.clip(1 - ((z - 6.8) / 2.8) ** 2, 0, None))  # elongated neck
    r = (r1**2.5 + r2**2.5) ** 0.4
    r[[0, -1]] = 0.0
    prof = np.column_stack([r, z])
    inner = np.nonzero((z > 3.2) & (z < 7.2))[0]
    waist = int(inner[np.argmin(r[inner])])
    return _fruit("pear", prof, 0.18, (0.72, 0.78, 0.25, 1.0), 0.03, splits=(waist,), stem=1.6, flat=0.5)


def _lemon():
    x = 4.2 * -np.cos(np.linspace(0, np.pi, 28))
    body = 2.9 * np.clip(1 - (x / 3.8) ** 2, 0, None) ** 0.6
    nub = 0.45 * np.sqrt(np.clip(1 - ((np.abs(x) - 3.75) / 0.45) ** 2, 0, None))
    prof = np.column_stack([np.maximum(body, nub), x])
    prof[[0, -1], 0] = 0.0
    return _fruit("lemon", prof, 0.11, (0.98, 0.88, 0.2, 1.0), 0.03, lying=True)


def _strawberry():
    u = np.linspace(0, 1, 22)
    r = 1.65 * np.sqrt(np.sin(np.clip(u / 0.2, 0, 1) * np.pi / 2)) * (1 - u**1.8) ** 0.8
    return _fruit("strawberry", np.column_stack([r, 4.2 * u]), 0.022, (0.85, 0.08, 0.12, 1.0), 0.04, flat=0.25)


def _banana():
    """Curved chain of tapered, slightly ridged tube segments lying on its side (the curve is horizontal)."""
    s = np.linspace(0, 1, 15)
    radius = 0.45 + 1.4 * np.sin(np.pi * s) ** 0.55
    phi = np.radians(-39 + 78 * s)
    path = np.column_stack([14 * np.sin(phi), 14 * np.cos(phi), 0.92 * radius])
    vis, hulls = tube(path, radius, 0.92 * radius, n_around=10, section=lambda a: 1 + 0.05 * np.cos(5 * a))
    return _done(Parts().add(vis, hulls), id="banana", category="banana", tags=FRUIT, mass_kg=0.12,
                 friction=0.8, rgba=(0.95, 0.82, 0.2, 1.0), source=SOURCE_TUBE, params={"arc_radius_m": 0.14})


_register("pear", _pear)
_register("lemon", _lemon)
_register("strawberry", _strawberry)
_register("banana", _banana)


# ------------------------------------------------------------------------------------------------ balls
def _ball(asset_id, r_cm, mass, rgba, friction):
    def make():
        vis = hull_mesh(ellipsoid_pts([r_cm] * 3, subdiv=3))
        parts = Parts().add(vis, [ellipsoid_pts([r_cm] * 3)])
        return _done(parts, id=asset_id, category=asset_id, tags=BALL, mass_kg=mass, friction=friction, rgba=rgba,
                     source=SOURCE_PRIMITIVES, params={"radius_m": r_cm / 100})
    return make


_register("tennis_ball", _ball("tennis_ball", 3.35, 0.058, (0.8, 0.9, 0.2, 1.0), 0.9))
_register("baseball", _ball("baseball", 3.7, 0.145, (0.95, 0.93, 0.88, 1.0), 0.7))
_register("golf_ball", _ball("golf_ball", 2.135, 0.0459, (0.97, 0.97, 0.97, 1.0), 0.5))
_register("softball", _ball("softball", 4.8, 0.18, (0.95, 0.9, 0.3, 1.0), 0.75))
_register("racquetball", _ball("racquetball", 2.85, 0.040, (0.15, 0.35, 0.85, 1.0), 0.9))


# ------------------------------------------------------------------------------------------------ kitchenware
def _vessel_parts(outer, wall, floor, **kw) -> Parts:
    vis, hulls, info = vessel(np.asarray(outer, dtype=np.float64), wall, floor, **kw)
    parts = Parts().add(vis, hulls)
    parts.anchors.update(cavity=np.array([0.0, 0.0, info["floor_z"]]), rim=np.array([0.0, 0.0, info["top_z"]]))
    for k, (r, z) in enumerate(info["seals"]):
        parts.anchors[f"seal{k}"] = np.array([r, 0.0, z])
    return parts


def _flare(r0, r1, h, n, umax=0.45 * np.pi):
    """Bowl-like outer wall: leaves the flat bottom at radius r0 horizontally and rises to (r1, h)."""
    u = np.linspace(0, umax, n)[1:]
    return np.column_stack([r0 + (r1 - r0) * np.sin(u) / np.sin(umax), h * (1 - np.cos(u)) / (1 - np.cos(umax))])


def _handle(parts, x0, z0, x1, z1, reach, half_w, half_h, n=9, wall_r=None):
    """A D-shaped handle in the xz-plane from (x0, z0) to (x1, z1) bulging out by ``reach`` along +x; both ends
    leave horizontally so their caps sit inside the wall. ``wall_r`` (the wall's outer radius there): anchor
    ``handle_hole`` is the middle of the opening between wall and handle (what a peg threads through)."""
    if wall_r is not None:
        parts.anchors["handle_hole"] = np.array([(wall_r + (x0 + x1) / 2 + reach - half_w) / 2, 0.0, (z0 + z1) / 2])
    s = np.linspace(0, 1, n)
    path = np.column_stack([x0 + (x1 - x0) * s + reach * np.sin(np.pi * s) ** 0.6, np.zeros(n), z0 + (z1 - z0) * s])
    vis, hulls = tube(path, half_w, half_h, normal=(0, 1, 0), n_around=10, hull_every=2)
    parts.add(vis, hulls)


def _container(asset_id, parts, mass, friction, rgba, tags=VESSEL, params=None, category=None):
    return _done(parts, id=asset_id, category=category or asset_id, tags=tags, mass_kg=mass, friction=friction,
                 rgba=rgba, source=SOURCE_REVOLVE, params=params or {})


def _mug():
    parts = _vessel_parts([(0, 0), (3.8, 0), (4.1, 0.3), (4.1, 9.5)], 0.5, 0.8)
    _handle(parts, 3.85, 2.0, 3.85, 8.0, 2.6, 0.45, 0.65, wall_r=4.1)
    return _container("mug", parts, 0.3, 0.6, (0.2, 0.45, 0.75, 1.0), tags=VESSEL + ("hangable",),
                      params={"capacity_ml": 350.0})


def _cup():
    parts = _vessel_parts([(0, 0), (2.55, 0), (2.8, 0.25), (4.0, 9.5)], 0.4, 0.6)
    return _container("cup", parts, 0.1, 0.7, (0.95, 0.6, 0.2, 1.0))


def _bowl(asset_id, r_foot, r_top, h, mass, rgba, wedges):
    def make():
        parts = _vessel_parts(np.vstack([[(0, 0), (r_foot, 0)], _flare(r_foot, r_top, h, 10)]), 0.5, 0.6, groups=3,
                              wedges=wedges)
        return _container(asset_id, parts, mass, 0.6, rgba, category="bowl")
    return make


def _plate():
    outer = [(0, 0), (8.0, 0), (8.6, 0.3), (9.6, 1.2), (10.6, 1.9), (11.0, 2.1)]
    parts = _vessel_parts(outer, 0.45, 0.45, groups=2, wedges=24)
    return _container("plate", parts, 0.45, 0.6, (0.96, 0.96, 0.94, 1.0),
                      tags=("graspable", "tableware", "kitchenware"))


def _pitcher():
    outer = [(0, 0), (6.0, 0), (6.3, 0.4), (6.8, 6.0), (6.6, 12.0), (5.6, 17.0), (5.9, 19.0)]
    parts = _vessel_parts(outer, 0.5, 0.8, groups=3, wedges=20)
    _handle(parts, 6.4, 5.5, 5.55, 16.0, 3.4, 0.55, 0.8, n=11)
    return _container("pitcher", parts, 0.7, 0.6, (0.75, 0.85, 0.9, 1.0),
                      tags=("graspable", "container", "kitchenware"))


def _jar():
    outer = [(0, 0), (4.2, 0), (4.5, 0.3), (4.5, 7.2), (4.1, 8.0), (4.0, 9.0)]
    parts = _vessel_parts(outer, 0.5, 0.7, groups=2)
    return _container("jar", parts, 0.3, 0.5, (0.7, 0.85, 0.75, 1.0), tags=("graspable", "container", "kitchenware"))


def _pot():
    """Small cooking pot: straight-walled vessel with two side tab handles below the rim (symmetric, so the
    cavity stays on the asset origin and a hand can grasp either tab)."""
    parts = _vessel_parts([(0, 0), (7.7, 0), (8.0, 0.3), (8.0, 9.0)], 0.5, 0.6, wedges=20)
    for sign in (1, -1):
        root, end = box_pts([0.1, 5.0, 1.0], [sign * 7.7, 0, 7.6]), box_pts([0.1, 3.6, 0.8], [sign * 11.0, 0, 7.9])
        parts.convex(np.vstack([root, end]), faceted=True)
    return _container("pot", parts, 0.8, 0.6, (0.7, 0.7, 0.72, 1.0), tags=("graspable", "container", "kitchenware"))


def _wine_glass():
    outer = [(0, 0), (3.6, 0), (3.6, 0.25), (2.0, 0.45), (0.9, 0.7), (0.45, 1.2), (0.45, 8.0), (1.2, 8.6),
             (2.3, 9.6), (3.2, 11.0), (3.7, 13.0), (3.8, 15.0), (3.5, 18.0)]
    parts = _vessel_parts(outer, 0.4, 9.0, wall_from=7, groups=3, base_splits=(0.25, 0.45, 0.7, 1.2, 8.0))
    return _container("wine_glass", parts, 0.18, 0.5, (0.8, 0.88, 0.92, 1.0),
                      tags=("graspable", "container", "tableware"))


def _solid(asset_id, profile, splits, mass, friction, rgba, tags, category=None):
    def make():
        vis, hulls = revolved_solid(np.asarray(profile, dtype=np.float64), splits)
        return _done(Parts().add(vis, hulls), id=asset_id, category=category or asset_id, tags=tags, mass_kg=mass,
                     friction=friction, rgba=rgba, source=SOURCE_REVOLVE)
    return make


_register("mug", _mug)
_register("cup", _cup)
_register("bowl", _bowl("bowl", 3.2, 7.5, 6.0, 0.25, (0.92, 0.9, 0.85, 1.0), 20))
_register("bowl_large", _bowl("bowl_large", 4.5, 11.0, 8.0, 0.5, (0.55, 0.7, 0.6, 1.0), 24))
_register("plate", _plate)
_register("pitcher", _pitcher)
_register("jar", _jar)
_register("pot", _pot)
_register("wine_glass", _wine_glass)
_register("bottle", _solid(
    "bottle", [(0, 0), (3.1, 0), (3.3, 0.3), (3.3, 14.5), (3.0, 16.5), (2.2, 18.2), (1.4, 19.3), (1.35, 20.0),
               (1.5, 20.0), (1.5, 22.0), (1.45, 22.3), (0, 22.3)], (6, 7), 0.5, 0.6, (0.3, 0.6, 0.9, 1.0),
    ("graspable", "kitchenware")))
_register("can", _solid(
    "can", [(0, 0.7), (2.2, 0.3), (2.5, 0.0), (2.75, 0.0), (3.3, 0.9), (3.3, 10.8), (2.9, 11.9), (2.9, 12.2),
            (2.7, 12.2), (2.65, 11.9), (0, 11.9)], (), 0.35, 0.5, (0.8, 0.1, 0.1, 1.0), ("graspable", "food")))
_register("tuna_can", _solid(
    "tuna_can", [(0, 0), (4.1, 0), (4.2, 0.15), (4.2, 3.15), (4.15, 3.3), (3.95, 3.3), (3.9, 3.15), (0, 3.15)],
    (), 0.171, 0.5, (0.75, 0.75, 0.78, 1.0), ("graspable", "food")))


def _mustard():
    """YCB-like mustard bottle: a revolved body flattened to 8.5 x 5 cm, with a round cap and nozzle."""
    body = np.array([(0, 0), (4.0, 0), (4.25, 0.4), (4.25, 12.5), (3.6, 14.2), (2.2, 15.2), (1.6, 15.4), (0, 15.4)])
    cap = np.array([(0, 15.2), (1.6, 15.2), (1.6, 16.6), (0.9, 17.0), (0.4, 17.5), (0, 17.5)])
    flat = np.diag([1.0, 5.0 / 8.5, 1.0, 1.0])
    parts = Parts().add(*revolved_solid(body, ())).transform(flat)
    parts.add(*revolved_solid(cap, ()))
    return _done(parts, id="mustard_bottle", category="mustard_bottle", tags=("graspable", "food"), mass_kg=0.603,
                 friction=0.6, rgba=(0.95, 0.85, 0.1, 1.0), source=SOURCE_REVOLVE)


_register("mustard_bottle", _mustard)


# ------------------------------------------------------------------------------------------------ boxes and blocks
def _box(asset_id, size, mass, friction, rgba, tags, bevel=0.0, category=None):
    def make():
        parts = Parts()
        if bevel:
            parts.convex(rounded_box_pts(size, bevel))
        else:
            parts.convex(box_pts(size), faceted=True)
        return _done(parts, id=asset_id, category=category or asset_id, tags=tags, mass_kg=mass, friction=friction,
                     rgba=rgba, source=SOURCE_PRIMITIVES, params={"size_x_m": size[0] / 100})
    return make


def _surface(asset_id, size, mass, friction, rgba, rim=None, bevel=0.3, tags=SURFACE):
    """Something flat to set things on: a board (one bevelled slab, ``size`` x, y, thickness in cm) or, with ``rim``
    (height, wall thickness), a tray: a base and four walls, each its own convex part."""
    def make():
        parts = Parts()
        x, y, t = size
        if rim is None:
            parts.convex(rounded_box_pts(size, bevel, centre=(0, 0, t / 2)))
        else:
            h, w = rim
            parts.convex(box_pts((x, y, t), (0, 0, t / 2)), faceted=True)
            for sx in (-1, 1):
                parts.convex(box_pts((w, y, h), (sx * (x - w) / 2, 0, h / 2)), faceted=True)
            for sy in (-1, 1):
                parts.convex(box_pts((x - 2 * w, w, h), (0, sy * (y - w) / 2, h / 2)), faceted=True)
        return _done(parts, id=asset_id, category=asset_id, tags=tags, mass_kg=mass, friction=friction,
                     rgba=rgba, source=SOURCE_PRIMITIVES, params={"top_z_m": t / 100})
    return make


_register("cutting_board", _surface("cutting_board", (30, 20, 1.8), 0.8, 0.8, (0.72, 0.55, 0.35, 1.0)))
_register("tray", _surface("tray", (34, 26, 0.6), 0.5, 0.6, (0.3, 0.35, 0.4, 1.0), rim=(2.5, 0.8)))
# the hand-over zone: a thin bright mat at the person's side of the table (a marker, never a support to stack on)
_register("handover_mat", _surface("handover_mat", (22, 22, 0.6), 0.2, 1.0, (0.95, 0.75, 0.1, 1.0), bevel=0.2,
                                   tags=HANDOVER))


def _peg(asset_id, width, height, square, rgba, color):
    """A wooden peg standing on its end: a round one (``width`` its diameter, cm) or a square one (``width`` its
    side), ``height`` tall, the edge of the end that goes in first (its bottom) chamfered 2 mm."""
    def make():
        parts, w, c = Parts(), width / 2, 0.2
        if square:
            parts.convex(np.vstack([box_pts((width - 2 * c, width - 2 * c, c), (0, 0, c / 2)),
                                    box_pts((width, width, height - c), (0, 0, (height + c) / 2))]), faceted=True)
        else:
            parts.convex(np.vstack([cyl_between([0, 0, 0], [0, 0, c], w - c, w, n=24),
                                    cyl_between([0, 0, c], [0, 0, height], w, n=24)]))
        volume = (width**2 if square else np.pi * w**2) * height * 1e-6
        return _done(parts, id=asset_id, category="peg", tags=PEG, mass_kg=round(650 * volume, 4), friction=0.8,
                     rgba=rgba, source=SOURCE_PRIMITIVES,
                     params={"shape": "square" if square else "round", "width_m": width / 100, "color": color})
    return make


def _peg_holder(asset_id, hole, square, rgba, outer=9.0, height=5.0, floor=1.0):
    """A block ``outer`` cm across and ``height`` tall with a hole ``hole`` cm across (round or square) down to a
    ``floor`` cm thick: the walls round the hole are convex pieces (16 ring sectors, or four slabs), so the hole is
    open for a peg a few millimetres narrower."""
    def make():
        parts, r = Parts(), hole / 2
        parts.convex(box_pts((outer, outer, floor), (0, 0, floor / 2)), faceted=True)
        if square:
            side = (outer - hole) / 2
            for sx in (-1, 1):
                parts.convex(box_pts((side, outer, height - floor), (sx * (hole + side) / 2, 0, (height + floor) / 2)),
                             faceted=True)
            for sy in (-1, 1):
                parts.convex(box_pts((hole, side, height - floor), (0, sy * (hole + side) / 2, (height + floor) / 2)),
                             faceted=True)
        else:
            for pts in ring_hulls(r, outer / 2, floor, height, pieces=16, overlap=0.05):
                parts.convex(pts)
        return _done(parts, id=asset_id, category="peg_holder", tags=HOLDER, mass_kg=0.4, friction=0.6, rgba=rgba,
                     source=SOURCE_PRIMITIVES, params={"shape": "square" if square else "round",
                                                       "hole_m": hole / 100, "hole_floor_m": floor / 100,
                                                       "top_z_m": height / 100})
    return make


def _spill(asset_id, size, round_, rgba, color, pitch=4.0, inset=1.5):
    """A stain on the table, 3 mm thick: a disc (``size`` its diameter, cm) or a rectangle (``size`` x, y). Its
    marks lie on a grid of ``pitch`` cm centred on it, each at least ``inset`` cm inside its edge
    (:func:`gendex_envs.wiping.spill_marks`): the sites a pressed sponge has to pass over."""
    def make():
        parts, t = Parts(), 0.3
        sx, sy = (size, size) if round_ else size
        if round_:
            parts.convex(cyl_between([0, 0, 0], [0, 0, t], sx / 2, n=32))
        else:
            parts.convex(box_pts((sx, sy, t), (0, 0, t / 2)), faceted=True)
        return _done(parts, id=asset_id, category="spill", tags=SPILL, mass_kg=0.05, friction=0.6, rgba=rgba,
                     source=SOURCE_PRIMITIVES, params={"shape": "round" if round_ else "rectangle", "top_z_m": t / 100,
                                                       "size_x_m": sx / 100, "size_y_m": sy / 100,
                                                       "marks_pitch_m": pitch / 100, "marks_inset_m": inset / 100,
                                                       "color": color})
    return make


_register("spill_round", _spill("spill_round", 18.0, True, (0.4, 0.22, 0.1, 1.0), "brown"))
_register("spill_square", _spill("spill_square", (16.0, 16.0), False, (0.9, 0.5, 0.1, 1.0), "orange"))
_register("spill_long", _spill("spill_long", (26.0, 10.0), False, (0.6, 0.1, 0.15, 1.0), "red"))
_register("peg_round", _peg("peg_round", 2.4, 10.0, False, (0.85, 0.2, 0.15, 1.0), "red"))
_register("peg_square", _peg("peg_square", 2.4, 10.0, True, (0.2, 0.35, 0.85, 1.0), "blue"))
_register("peg_thin", _peg("peg_thin", 1.8, 11.0, False, (0.95, 0.8, 0.15, 1.0), "yellow"))
# each hole 5-6 mm wider than its peg: 2.5-3 mm of clearance a side
_register("peg_holder_round", _peg_holder("peg_holder_round", 3.0, False, (0.72, 0.55, 0.35, 1.0)))
_register("peg_holder_square", _peg_holder("peg_holder_square", 3.0, True, (0.72, 0.55, 0.35, 1.0)))
_register("peg_holder_thin", _peg_holder("peg_holder_thin", 2.3, False, (0.6, 0.45, 0.3, 1.0)))
_register("cracker_box", _box("cracker_box", (16, 6, 21), 0.411, 0.6, (0.85, 0.2, 0.15, 1.0), BOX))
_register("sugar_box", _box("sugar_box", (9, 4, 17.5), 0.514, 0.6, (0.95, 0.9, 0.55, 1.0), BOX))
_register("pudding_box", _box("pudding_box", (8.9, 3.5, 11), 0.187, 0.6, (0.55, 0.35, 0.2, 1.0), BOX))
_register("gelatin_box", _box("gelatin_box", (8.5, 2.8, 7.3), 0.097, 0.6, (0.85, 0.2, 0.3, 1.0), BOX))
_register("sponge", _box("sponge", (9, 6, 3), 0.01, 1.2, (0.95, 0.85, 0.2, 1.0), ("graspable", "kitchenware"), 0.3))
# a thick foam block sponge (a car-wash sponge): tall enough for the palm to press on its top, fingers round its sides
_register("sponge_block", _box("sponge_block", (10, 7, 6), 0.025, 1.2, (0.2, 0.55, 0.9, 1.0), WIPER, 0.5, "sponge"))
_register("block_small", _box("block_small", (4, 4, 4), 0.038, 0.7, (0.85, 0.2, 0.2, 1.0), BLOCK, 0.15, "block"))
_register("block_medium", _box("block_medium", (5, 5, 5), 0.075, 0.7, (0.2, 0.6, 0.25, 1.0), BLOCK, 0.15, "block"))
_register("block_large", _box("block_large", (6, 6, 6), 0.13, 0.7, (0.2, 0.35, 0.85, 1.0), BLOCK, 0.15, "block"))
_register("rubiks_cube", _box("rubiks_cube", (5.7, 5.7, 5.7), 0.1, 0.7, (0.1, 0.1, 0.1, 1.0), BLOCK, 0.3))
_register("dice", _box("dice", (1.6, 1.6, 1.6), 0.005, 0.6, (0.95, 0.95, 0.92, 1.0), BLOCK, 0.2))
_register("foam_brick", _box("foam_brick", (5, 7.5, 5), 0.03, 1.0, (0.8, 0.15, 0.1, 1.0), BLOCK, 0.3))


def _toy_duck():
    parts = Parts()
    for radii, centre, flat in (((4.6, 3.4, 2.9), (0, 0, 2.6), -2.2), ((2.1, 2.1, 2.1), (2.6, 0, 5.6), None),
                                ((1.2, 0.9, 0.4), (4.7, 0, 5.2), None), ((1.4, 1.2, 0.9), (-4.0, 0, 3.9), None)):
        parts.convex(ellipsoid_pts(radii, centre, 3, flat), ellipsoid_pts(radii, centre, flat_z=flat, n=100))
    return _done(parts, id="toy_duck", category="toy_duck", tags=("graspable", "toy"), mass_kg=0.03, friction=0.8,
                 rgba=(1.0, 0.85, 0.1, 1.0), source=SOURCE_PRIMITIVES)


_register("toy_duck", _toy_duck)


# ------------------------------------------------------------------------------------------------ tools (lying)
def _tool(asset_id, parts, mass, friction, rgba, tags=TOOL, source=SOURCE_PRIMITIVES):
    return _done(parts, id=asset_id, category=asset_id, tags=tags, mass_kg=mass, friction=friction, rgba=rgba,
                 source=source, params={"rest": "lying"})


def _hammer():
    """Claw hammer on its side: tapered handle along x, head along y (face cylinder, block, curved claw)."""
    parts = Parts()
    vis, hulls = tube([[0, 0, 1.3], [29, 0, 1.3]], [1.7, 1.35], 1.3, n_around=12, hull_every=1)
    parts.add(vis, hulls)
    parts.convex(box_pts([2.8, 3.2, 2.6], [30, 0, 1.3]), faceted=True)
    parts.convex(cyl_between([30, 1.5, 1.3], [30, 4.6, 1.3], 1.3, 1.25, n=16))
    parts.convex(np.vstack([box_pts([2.8, 0.1, 2.6], [30, -1.55, 1.3]), box_pts([1.0, 0.1, 2.6], [28.6, -5.5, 1.3])]),
                 faceted=True)
    return _tool("hammer", parts, 0.6, 0.6, (0.45, 0.45, 0.5, 1.0))


def _screwdriver():
    parts = Parts()
    c = 1.5 * np.cos(np.pi / 8)  # octagonal handle resting on a flat
    ring = [cyl_between([x, 0, c], [x + 1e-3, 0, c], r, n=8, phase=np.pi / 8)[:8] for x, r in
            ((0, 1.2), (0.6, 1.5), (9.0, 1.5), (10.0, 1.1))]
    parts.convex(np.vstack(ring), faceted=True)
    parts.convex(cyl_between([9.5, 0, c], [20, 0, c], 0.3, n=12))
    tip = np.array([[20.8, y, c + z] for y in (-0.3, 0.3) for z in (-0.05, 0.05)])
    parts.convex(np.vstack([cyl_between([19.9, 0, c], [20.0, 0, c], 0.3, n=12), tip]))
    return _tool("screwdriver", parts, 0.08, 0.7, (0.85, 0.15, 0.1, 1.0))


def _spatula():
    parts = Parts()
    parts.convex(box_pts([14, 2.2, 1.2], [7, 0, 0.6]), faceted=True)
    parts.convex(np.vstack([box_pts([0.1, 1.6, 0.8], [13.9, 0, 0.4]), box_pts([0.1, 5.0, 0.25], [17.0, 0, 0.125])]),
                 faceted=True)
    blade = [(17, -2.5), (25.3, -3.5), (25.8, -3.3), (26, -2.8), (26, 2.8), (25.8, 3.3), (25.3, 3.5), (17, 2.5)]
    parts.convex(prism_pts(blade, 0, 0.25), faceted=True)
    return _tool("spatula", parts, 0.06, 0.7, (0.15, 0.15, 0.15, 1.0), tags=("graspable", "tool", "kitchenware"))


def _marker():
    parts = Parts()
    c = 0.95
    parts.convex(np.vstack([cyl_between([0, 0, c], [0.6, 0, c], 0.6, 0.85, n=16),
                            cyl_between([0.6, 0, c], [11, 0, c], 0.85, n=16)]))
    parts.convex(np.vstack([cyl_between([10.2, 0, c], [15.2, 0, c], 0.95, n=16),
                            cyl_between([15.2, 0, c], [15.6, 0, c], 0.95, 0.7, n=16)]))
    parts.convex(box_pts([4.0, 0.3, 0.4], [13.0, 0, 2.0 * c + 0.15]), faceted=True)
    return _tool("marker", parts, 0.015, 0.6, (0.15, 0.3, 0.8, 1.0))


def _scissors():
    """Closed scissors lying flat: two stacked blades, shanks, and two finger rings (8 hulls each)."""
    parts = Parts()
    blade = np.array([(-1.0, -0.7), (1.0, -0.85), (10.0, -0.05), (10.2, 0.1), (1.0, 0.7), (-1.0, 0.7)])
    for sign, (z0, z1) in ((1, (0.0, 0.22)), (-1, (0.22, 0.44))):
        parts.convex(prism_pts(blade * [1, sign], z0, z1), faceted=True)
        shank = np.vstack([box_pts([0.8, 1.0, z1 - z0], [-1.0, 0, (z0 + z1) / 2]),
                           box_pts([0.6, 0.8, z1 - z0], [-3.7, sign * 1.4, (z0 + z1) / 2])])
        parts.convex(shank, faceted=True)
        t = 2 * np.pi * np.arange(16) / 16
        loop = np.column_stack([-5.2 + 1.35 * np.cos(t), sign * 1.9 + 1.35 * np.sin(t), np.full(16, 0.3)])
        vis, hulls = tube(loop, 0.35, 0.3, n_around=8, hull_every=2, closed=True)
        parts.add(vis, hulls)
    return _tool("scissors", parts, 0.08, 0.6, (0.2, 0.4, 0.8, 1.0), source=SOURCE_TUBE)


def _wrench():
    """Combination wrench lying flat: bar, open (C-shaped) end at +x, closed ring end at -x."""
    parts = Parts()
    parts.convex(box_pts([14, 1.8, 0.5], [0, 0, 0.25]), faceted=True)
    for pts in ring_hulls(0.65, 1.7, 0, 0.6, np.radians(50), np.radians(310), pieces=6):
        parts.convex(pts + [8.0, 0, 0], faceted=True)
    for pts in ring_hulls(0.75, 1.5, 0, 0.7, pieces=8):
        parts.convex(pts + [-8.0, 0, 0], faceted=True)
    return _tool("wrench", parts, 0.15, 0.6, (0.7, 0.72, 0.75, 1.0))


_register("hammer", _hammer)
_register("screwdriver", _screwdriver)
_register("spatula", _spatula)
_register("marker", _marker)
_register("scissors", _scissors)
_register("wrench", _wrench)


# ------------------------------------------------------------------------------------------------ utensils (lying)
def _flat_handle(parts, path, half_w, half_h=0.12):
    vis, hulls = tube(path, half_w, half_h, n_around=8, hull_every=1)
    parts.add(vis, hulls)


def _spoon():
    """Shallow elliptic bowl (a thin vessel scaled to 5.4 x 3.8 cm, 12 wedges) and a handle that arches up from
    the rim and comes down to the table at its end."""
    bowl = _vessel_parts(np.vstack([[(0, 0), (0.8, 0)], _flare(0.8, 2.0, 0.9, 6, np.pi / 2)]), 0.18, 0.18,
                         wedges=12)
    bowl.anchors.clear()
    parts = bowl.transform(np.diag([1.35, 0.95, 1.0, 1.0]))
    _flat_handle(parts, [[2.4, 0, 0.8], [4.5, 0, 1.3], [10, 0, 0.9], [17, 0, 0.12]], [0.35, 0.5, 0.9, 1.1])
    return _tool("spoon", parts, 0.045, 0.6, (0.78, 0.78, 0.8, 1.0), tags=UTENSIL, source=SOURCE_REVOLVE)


def _fork():
    parts = Parts()
    for y in (-1.0, -0.33, 0.33, 1.0):
        parts.convex(box_pts([4.0, 0.24, 0.22], [-2.0, y, 0.11]), faceted=True)
    base = [(-0.2, -1.25), (-0.2, 1.25), (1.2, 1.1), (2.2, 0.45), (2.2, -0.45), (1.2, -1.1)]
    parts.convex(prism_pts(base, 0, 0.22), faceted=True)
    _flat_handle(parts, [[2.0, 0, 0.12], [5.0, 0, 0.9], [15.0, 0, 0.12]], [0.4, 0.55, 1.1])
    return _tool("fork", parts, 0.045, 0.6, (0.78, 0.78, 0.8, 1.0), tags=UTENSIL)


def _knife():
    parts = Parts()
    vis, hulls = tube([[0, 0, 0.6], [10.2, 0, 0.6]], 1.0, 0.6, n_around=12, hull_every=1)
    parts.add(vis, hulls)
    blade = [(9.8, -1.0), (19.5, -1.0), (21.5, -0.3), (22.5, 0.9), (22.2, 1.1), (9.8, 1.1)]
    parts.convex(prism_pts(blade, 0, 0.2), faceted=True)
    return _tool("knife", parts, 0.07, 0.6, (0.3, 0.3, 0.32, 1.0), tags=UTENSIL)


_register("spoon", _spoon)
_register("fork", _fork)
_register("knife", _knife)


# registers the hooks a mug hangs on, the beads a vessel pours and the vessels that pour them, the everyday objects
# (household, pantry, home),
# and the colour variants (last: they copy the others)
from gendex_envs.assets import (  # noqa: E402,F401
    procedural_hanging,
    procedural_home,
    procedural_household,
    procedural_pantry,
    procedural_pouring,
    procedural_variants,
)


def build_all() -> list[ProceduralShape]:
    """Every asset, in id order."""
    return [GENERATORS[k]() for k in sorted(GENERATORS)]
