"""Attributes people name objects by: colour (a palette of named colours), and the colour a catalog entry shows.

A task names an object's colour with ``objects[i].color`` (a key of :data:`COLORS`); the env paints the object's
visual in it, as it does ``color_rgba``. What colour an object already is comes from its rgba
(:func:`color_name`: the nearest named colour), so "the red apple" and "the blue block" can be read against the
catalog and against the colours a task gives.
"""

from __future__ import annotations

from typing import Literal, get_args

ColorName = Literal["red", "orange", "yellow", "green", "blue", "purple", "pink", "brown", "white", "grey", "black"]
COLOR_NAMES: tuple[str, ...] = get_args(ColorName)
COLORS: dict[str, tuple[float, float, float, float]] = {
    "red": (0.80, 0.10, 0.10, 1.0), "orange": (0.95, 0.50, 0.08, 1.0), "yellow": (0.95, 0.85, 0.15, 1.0),
    "green": (0.15, 0.65, 0.20, 1.0), "blue": (0.12, 0.30, 0.85, 1.0), "purple": (0.50, 0.20, 0.70, 1.0),
    "pink": (0.95, 0.55, 0.70, 1.0), "brown": (0.50, 0.30, 0.15, 1.0), "white": (0.93, 0.93, 0.93, 1.0),
    "grey": (0.50, 0.50, 0.50, 1.0), "black": (0.08, 0.08, 0.08, 1.0),
}
"""Named colour -> linear RGBA the renderer paints. Distinct enough to tell apart in a 128 px camera frame (the
closest pair, orange and yellow, differ by 0.35 in green)."""
assert tuple(COLORS) == COLOR_NAMES
COLOR_WORDS: dict[str, str] = {**{c: c for c in COLOR_NAMES}, "gray": "grey", "violet": "purple",
                               "crimson": "red", "scarlet": "red", "navy": "blue", "lime": "green"}
"""Words for colours -> the palette's name."""


def color_name(rgba: tuple[float, ...]) -> str:
    """The palette colour nearest to ``rgba`` (its RGB; alpha ignored)."""
    r, g, b = (float(c) for c in rgba[:3])
    return min(COLORS, key=lambda n: (COLORS[n][0] - r) ** 2 + (COLORS[n][1] - g) ** 2 + (COLORS[n][2] - b) ** 2)


__all__ = ["COLORS", "COLOR_NAMES", "COLOR_WORDS", "ColorName", "color_name"]
