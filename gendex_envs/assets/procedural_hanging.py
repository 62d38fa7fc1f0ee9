"""Things a mug hangs on by its handle (the ``hang`` task skill): fixed stands with round pegs that rise a little
towards their tips, so a mug hung on one slides down to the peg's root rather than off its end.

Each peg ``k`` is recorded as anchors ``peg<k>_root`` (where it leaves the post or rail) and ``peg<k>_tip`` (its end,
on its axis), in the asset frame: :mod:`gendex.solve.hang` threads a handle onto the peg along that axis. The
generators register into :data:`gendex_envs.assets.procedural_shapes.GENERATORS` like every other shape.
"""

from __future__ import annotations

import numpy as np

from gendex_envs.assets.procedural import SOURCE_PRIMITIVES, Parts, box_pts, cyl_between
from gendex_envs.assets.procedural_shapes import _done, _register

HOOK = ("hook", "hang_on")
"""A stand with pegs a mug hangs on by its handle (the ``hang`` task skill)."""
PEG_RISE_DEG = 12.0
"""How much a peg rises towards its tip (a mug tree's pegs slope up: a hung mug slides to the root)."""
PEG_RADIUS_CM = 0.4
"""Pegs are 8 mm thick: a mug's handle leaves 5 mm a side round one."""
BASE_CM = 1.5
"""Thickness of a stand's base plate."""


def _peg(parts: Parts, k: int, root, azimuth_deg: float, length_cm: float, start_cm: float) -> None:
    """Peg ``k`` leaving ``root`` (cm, on the post's axis or the rail's) towards ``azimuth_deg`` (about the vertical,
    0 = +x), ``start_cm`` out of it (the post's surface) and ``length_cm`` long from there."""
    a, rise = np.radians(azimuth_deg), np.radians(PEG_RISE_DEG)
    d = np.array([np.cos(rise) * np.cos(a), np.cos(rise) * np.sin(a), np.sin(rise)])
    root = np.asarray(root, dtype=np.float64)
    tip = root + (start_cm + length_cm) * d
    parts.convex(cyl_between(root, tip, PEG_RADIUS_CM, n=12))
    parts.anchors[f"peg{k}_root"] = root + start_cm * d
    parts.anchors[f"peg{k}_tip"] = tip


def _finish(asset_id: str, parts: Parts, category: str, rgba, pegs: int, **params) -> object:
    return _done(parts, id=asset_id, category=category, tags=HOOK, mass_kg=1.5, friction=0.5, rgba=rgba,
                 source=SOURCE_PRIMITIVES, params={"pegs": pegs, "peg_radius_m": PEG_RADIUS_CM / 100, **params})


def _mug_stand(asset_id: str, category: str, pegs, post_cm: float, base, rgba, round_base: bool = False):
    """A post ``post_cm`` tall on a base plate (``base``: side lengths, or a diameter) with ``pegs``: (height cm,
    azimuth deg, length cm) each, leaving the post all round (a mug tree) or to one side (a hook)."""
    def make():
        parts, r = Parts(), 1.2
        if round_base:
            parts.convex(cyl_between([0, 0, 0], [0, 0, BASE_CM], base / 2, n=32))
        else:
            parts.convex(box_pts((base[0], base[1], BASE_CM), (0, 0, BASE_CM / 2)), faceted=True)
        parts.convex(cyl_between([0, 0, BASE_CM], [0, 0, post_cm], r, n=20))
        parts.convex(cyl_between([0, 0, post_cm], [0, 0, post_cm + 0.8], r, 0.6, n=20))  # a rounded top
        for k, (z, az, length) in enumerate(pegs):
            _peg(parts, k, [0.0, 0.0, z], az, length, r)
        return _finish(asset_id, parts, category, rgba, len(pegs), post_height_m=post_cm / 100)
    return make


def _mug_rack(asset_id: str, rgba, width_cm: float = 34.0, bar_cm: float = 28.0, hooks=(-9.0, 9.0)):
    """Two posts and a rail ``bar_cm`` up between them, pegs leaving the rail towards -x at ``hooks`` (y, cm)."""
    def make():
        parts, half = Parts(), width_cm / 2
        parts.convex(box_pts((10.0, width_cm + 4.0, BASE_CM), (0, 0, BASE_CM / 2)), faceted=True)
        for y in (-half, half):
            parts.convex(box_pts((2.0, 2.0, bar_cm + 1.0 - BASE_CM), (0, y, (bar_cm + 1.0 + BASE_CM) / 2)),
                         faceted=True)
        parts.convex(box_pts((2.0, width_cm + 2.0, 2.0), (0, 0, bar_cm)), faceted=True)
        for k, y in enumerate(hooks):
            _peg(parts, k, [0.0, y, bar_cm], 180.0, 8.0, 1.0)
        return _finish(asset_id, parts, "mug_rack", rgba, len(hooks), post_height_m=(bar_cm + 1.0) / 100)
    return make


_register("mug_hook", _mug_stand("mug_hook", "mug_hook", [(22.0, 180.0, 9.0)], 27.0, (12.0, 12.0),
                                 (0.55, 0.4, 0.28, 1.0)))
_register("mug_tree", _mug_stand("mug_tree", "mug_tree", [(20.0, 180.0, 8.0), (25.0, 60.0, 8.0), (30.0, -60.0, 8.0)],
                                 34.0, 16.0, (0.75, 0.6, 0.4, 1.0), round_base=True))
_register("mug_rack", _mug_rack("mug_rack", (0.35, 0.35, 0.38, 1.0)))

__all__ = ["HOOK", "PEG_RADIUS_CM", "PEG_RISE_DEG"]
