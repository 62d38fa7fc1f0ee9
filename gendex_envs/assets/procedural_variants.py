"""Colour variants: the same object in the other colours it is sold in, so that a request can tell two of a kind
apart by colour (*the green apple*, *the blue mug*, *the red rubber ball*).

A variant is its base object's geometry, mass and friction exactly (the same seeded shape and the same mesh files,
recorded as ``params["variant_of"]``), painted in a colour of
the task language's palette (:data:`gendex_envs.attributes.COLORS`), so :func:`gendex_envs.attributes.color_name`
names it as the request does. Its id is ``<base>_<colour>`` (read as *<colour> <category>*), its category the base's
unless it is sold as another thing (a black salt shaker is a pepper shaker). A family of soda cans comes in six
colours from the start.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from gendex_envs.assets.procedural import ProceduralShape
from gendex_envs.assets.procedural_household import _revolved
from gendex_envs.assets.procedural_shapes import GENERATORS, _register
from gendex_envs.attributes import COLORS


def _variant(base: str, colour: str, asset_id: str | None = None, category: str | None = None
             ) -> Callable[[], ProceduralShape]:
    make_base = GENERATORS[base]

    def make() -> ProceduralShape:
        shape = make_base()
        return dataclasses.replace(shape, id=asset_id or f"{base}_{colour}", category=category or shape.category,
                                   rgba=COLORS[colour], params={**shape.params, "variant_of": base},
                                   files_of=shape.files_of or base)
    return make


VARIANTS: dict[str, tuple[str, ...]] = {
    "apple": ("green", "yellow"),
    "bell_pepper": ("yellow", "green"),
    "cup": ("blue", "green", "red", "white"),
    "mug": ("red", "green", "white", "yellow"),
    "bowl": ("blue", "red"),
    "plate": ("blue", "green"),
    "rubber_ball": ("red", "blue", "green", "yellow", "orange"),
    "juice_box": ("orange", "purple"),
    "spice_jar": ("yellow", "green"),
    "toy_car": ("blue", "yellow", "green"),
    "candle": ("red", "purple"),
    "soap_bar": ("white", "green"),
    "tape_roll": ("red", "blue"),
    "teddy_bear": ("white",),
    "chess_king": ("black",),
    "chess_rook": ("white",),
    "storage_bin": ("red", "green"),
    "placemat": ("blue", "green"),
}
"""Base object -> the colours it also comes in (each differs from the base's own colour name)."""

for _base, _colours in VARIANTS.items():
    for _colour in _colours:
        _register(f"{_base}_{_colour}", _variant(_base, _colour))
_register("pepper_shaker", _variant("salt_shaker", "black", "pepper_shaker", "pepper_shaker"))

_CAN = [(0, 0.5), (2.3, 0.0), (2.7, 0.0), (3.3, 0.9), (3.3, 11.2), (2.7, 12.1), (2.7, 12.2), (0, 12.2)]
"""A 330 ml drinks can: domed base, straight wall, necked top (radius concave in height throughout)."""
SODA_COLOURS = ("red", "green", "blue", "orange", "grey", "black")
for _colour in SODA_COLOURS:
    _register(f"soda_can_{_colour}", _revolved(f"soda_can_{_colour}", [(_CAN, ())], 0.35, 0.5, COLORS[_colour],
                                               ("graspable", "food"), category="soda_can"))

__all__ = ["SODA_COLOURS", "VARIANTS"]
