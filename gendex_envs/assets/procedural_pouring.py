"""Loose pieces that are poured (the ``pour`` task skill): small rigid beads that start in a cup, a mug or a pitcher
and are tipped out of it into a bowl. Each bead is its own rigid body, so a pour is real physics: beads slide to the
rim, spill over it, bounce and settle; none is teleported or counted without having moved.

What pours them is a tall open vessel (tag ``pourer``): the hand holds it by its side, fingers round it and the palm
clear of its mouth (the side grasp needs 13 cm or more of height; a 10 cm cup is held from above, over its mouth), and
turns it about the fingers' direction as a person pours.

A bead is a sphere (its collision a hull of :data:`HULL_POINTS` points on it, close enough to roll), small enough
that a dozen sit in a cup in three layers. The generators register into
:data:`gendex_envs.assets.procedural_shapes.GENERATORS` like every other shape.
"""

from __future__ import annotations

from gendex_envs.assets.procedural import SOURCE_PRIMITIVES, SOURCE_REVOLVE, Parts, ellipsoid_pts, hull_mesh
from gendex_envs.assets.procedural_shapes import VESSEL, _done, _register, _vessel_parts

POURER = VESSEL + ("pourer",)
"""A tall open vessel the hand holds by its side and pours from."""
POURABLE = ("pourable", "bead")
"""A loose piece poured out of a vessel (the ``pour`` task skill); not ``graspable``: one is smaller than a
fingertip."""
HULL_POINTS = 64


def _bead(asset_id: str, diameter_cm: float, mass_kg: float, friction: float, rgba, material: str):
    def make():
        r = diameter_cm / 2
        parts = Parts().add(hull_mesh(ellipsoid_pts([r] * 3, subdiv=2)), [ellipsoid_pts([r] * 3, n=HULL_POINTS)])
        return _done(parts, id=asset_id, category="bead", tags=POURABLE, mass_kg=mass_kg, friction=friction,
                     rgba=rgba, source=SOURCE_PRIMITIVES, params={"radius_m": r / 100, "material": material})
    return make


_register("bead", _bead("bead", 1.8, 0.007, 0.5, (0.8, 0.55, 0.3, 1.0), "ceramic"))
"""A glazed ceramic bead, 18 mm, 7 g: a tall glass holds a dozen in three layers."""
_register("marble", _bead("marble", 1.6, 0.0055, 0.5, (0.3, 0.6, 0.9, 1.0), "glass"))
"""A glass marble, 16 mm, 5.5 g."""


def _pourer(asset_id: str, outer, wall_cm: float, floor_cm: float, mass_kg: float, friction: float, rgba,
            capacity_ml: float, material: str):
    def make():
        parts = _vessel_parts(outer, wall_cm, floor_cm)
        return _done(parts, id=asset_id, category=asset_id, tags=POURER, mass_kg=mass_kg, friction=friction, rgba=rgba,
                     source=SOURCE_REVOLVE, params={"capacity_ml": capacity_ml, "material": material})
    return make


_register("tumbler", _pourer("tumbler", [(0, 0), (2.8, 0), (3.0, 0.3), (3.5, 13.5)], 0.35, 0.8, 0.28, 0.5,
                             (0.75, 0.88, 0.95, 1.0), 420.0, "glass"))
"""A tall drinking glass, narrower at the foot."""
_register("beaker", _pourer("beaker", [(0, 0), (3.05, 0), (3.25, 0.3), (3.25, 14.0)], 0.3, 0.5, 0.2, 0.5,
                            (0.85, 0.92, 0.88, 1.0), 650.0, "glass"))
"""A straight-walled laboratory beaker."""
_register("paper_cup", _pourer("paper_cup", [(0, 0), (2.5, 0), (2.6, 0.3), (3.6, 13.5)], 0.3, 0.4, 0.05, 0.8,
                               (0.95, 0.95, 0.9, 1.0), 470.0, "paper"))
"""A tall takeaway coffee cup: light, wide at the mouth."""
