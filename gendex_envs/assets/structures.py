"""Fixed structures of a scene: shelves, counters, a sink, cabinets, a window, a pegboard... built from boxes.

A structure is static and collides (every part with ``collision=True``; a glass pane or a door seam is visual only).
Its frame: origin at the centre of its footprint on the surface it stands on (or the bottom of a wall-mounted one),
z up, its front facing -x (towards the robot when it stands at the far end of the table; ``yaw_deg`` turns it).
Each part is painted by its role: ``body`` in a colour drawn per episode from the structure's palette (or the
task's), the other roles in fixed colours. GenDex's own work (Apache-2.0).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

from gendex_envs.assets.texture_noise import Color, hex_color

Role = Literal["body", "top", "metal", "dark", "glass", "wood", "white"]
ROLES: tuple[str, ...] = get_args(Role)

PAINTS: dict[str, Color] = {name: hex_color(code) for name, code in (
    ("white", "#f1f0eb"), ("cream", "#e9dfc8"), ("light_grey", "#c3c6c9"), ("mid_grey", "#8d9297"),
    ("charcoal", "#3b3e42"), ("black", "#1d1e20"), ("navy", "#2d3c5a"), ("steel_blue", "#4f77a8"),
    ("sage", "#8aa38f"), ("teal", "#2f7f7a"), ("butter", "#e9d48a"), ("terracotta", "#b8643f"),
    ("red", "#a8322b"), ("oak_tone", "#b98a58"), ("walnut_tone", "#5e3d24"), ("pegboard_brown", "#b08a5a"),
)}
"""Paint colours a structure's body may take, by name."""

ROLE_COLORS: dict[str, tuple[Color, float, float]] = {
    "top": (hex_color("#2f3033"), 0.3, 0.0),
    "metal": (hex_color("#b9bcbf"), 0.3, 1.0),
    "dark": (hex_color("#202124"), 0.6, 0.0),
    "glass": (hex_color("#b4cdd9"), 0.05, 0.3),  # drawn opaque: a pale pane (SAPIEN's rasteriser shows alpha dark)
    "wood": (hex_color("#c8955f"), 0.6, 0.0),
    "white": (hex_color("#f4f4f2"), 0.3, 0.0),
}
"""(colour, roughness, metallic) of every fixed role (``body`` is drawn per episode)."""


@dataclass(frozen=True)
class Part:
    """One box of a structure: full size and centre in the structure's frame (m)."""

    size_m: tuple[float, float, float]
    center_m: tuple[float, float, float]
    role: Role = "body"
    collision: bool = True


@dataclass(frozen=True)
class StructureDef:
    """A named fixed structure."""

    name: str
    description: str
    parts: tuple[Part, ...]
    palette: tuple[str, ...]
    """Paints (:data:`PAINTS`) its body may take."""
    mount: Literal["stands", "wall"] = "stands"
    """``stands`` on the surface below it; ``wall``: hangs (its base is where the spec puts it)."""

    @property
    def bounds_m(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """(min corner, max corner) of all parts in the structure's frame."""
        lo = tuple(min(p.center_m[k] - p.size_m[k] / 2 for p in self.parts) for k in range(3))
        hi = tuple(max(p.center_m[k] + p.size_m[k] / 2 for p in self.parts) for k in range(3))
        return lo, hi  # type: ignore[return-value]


def _box(size: tuple[float, float, float], center: tuple[float, float, float], role: Role = "body",
         collision: bool = True) -> Part:
    return Part(size, center, role, collision)


def _handles(x: float, ys: list[float], z: float, vertical: bool = True) -> list[Part]:
    size = (0.02, 0.012, 0.1) if vertical else (0.02, 0.1, 0.012)
    return [_box(size, (x, y, z), "metal", collision=False) for y in ys]


def _seams(x: float, ys: list[float], z0: float, z1: float) -> list[Part]:
    """Dark door gaps on a front at x: vertical lines at ys."""
    return [_box((0.004, 0.006, z1 - z0), (x, y, (z0 + z1) / 2), "dark", collision=False) for y in ys]


def _counter(sink: bool) -> tuple[Part, ...]:
    depth, width, height = 0.6, 1.0, 0.9
    parts = [_box((depth - 0.04, width, height - 0.04), (0.02, 0.0, (height - 0.04) / 2)),
             _box((0.01, width, 0.08), (-depth / 2 + 0.045, 0.0, 0.04), "dark", collision=False)]
    parts += _seams(-depth / 2 + 0.038, [-0.25, 0.0, 0.25], 0.1, height - 0.06)
    parts += _handles(-depth / 2 + 0.03, [-0.04, 0.04, -0.29, 0.29], height - 0.16)
    top_z = height - 0.02
    if not sink:
        return (*parts, _box((depth + 0.02, width + 0.02, 0.04), (0.0, 0.0, top_z), "top"))
    hole_x, hole_y = 0.36, 0.46  # the basin opening, centred at x = -0.03
    cx = -0.03
    front = (cx - hole_x / 2) - (-depth / 2 - 0.01)
    back = (depth / 2 + 0.01) - (cx + hole_x / 2)
    side = (width + 0.02 - hole_y) / 2
    parts += [
        _box((front, width + 0.02, 0.04), (-depth / 2 - 0.01 + front / 2, 0.0, top_z), "top"),
        _box((back, width + 0.02, 0.04), (depth / 2 + 0.01 - back / 2, 0.0, top_z), "top"),
        _box((hole_x, side, 0.04), (cx, hole_y / 2 + side / 2, top_z), "top"),
        _box((hole_x, side, 0.04), (cx, -hole_y / 2 - side / 2, top_z), "top"),
        _box((hole_x, hole_y, 0.01), (cx, 0.0, height - 0.2), "metal"),  # basin floor
        _box((0.01, hole_y, 0.18), (cx - hole_x / 2 + 0.005, 0.0, height - 0.11), "metal"),
        _box((0.01, hole_y, 0.18), (cx + hole_x / 2 - 0.005, 0.0, height - 0.11), "metal"),
        _box((hole_x, 0.01, 0.18), (cx, hole_y / 2 - 0.005, height - 0.11), "metal"),
        _box((hole_x, 0.01, 0.18), (cx, -hole_y / 2 + 0.005, height - 0.11), "metal"),
        _box((0.04, 0.04, 0.3), (0.24, 0.0, height + 0.15), "metal"),  # faucet column
        _box((0.2, 0.03, 0.03), (0.15, 0.0, height + 0.285), "metal"),  # spout
    ]
    return tuple(parts)


def _shelf() -> tuple[Part, ...]:
    d, w, h = 0.35, 0.9, 1.2
    parts = [_box((d, 0.02, h), (0.0, s * (w / 2 - 0.01), h / 2)) for s in (-1, 1)]
    parts += [_box((d, w - 0.04, 0.02), (0.0, 0.0, z)) for z in (0.06, 0.42, 0.8, h - 0.01)]
    parts.append(_box((0.01, w, h), (d / 2 - 0.005, 0.0, h / 2)))
    return tuple(parts)


def _wall_cabinet() -> tuple[Part, ...]:
    d, w, h = 0.34, 0.8, 0.7
    return (_box((d, w, h), (0.0, 0.0, h / 2)), *_seams(-d / 2 - 0.001, [0.0], 0.02, h - 0.02),
            *_handles(-d / 2 - 0.01, [-0.04, 0.04], 0.1))


def _window() -> tuple[Part, ...]:
    d, w, h, bar = 0.06, 1.0, 0.8, 0.06
    return (_box((d, w, bar), (0.0, 0.0, bar / 2), "white"), _box((d, w, bar), (0.0, 0.0, h - bar / 2), "white"),
            _box((d, bar, h), (0.0, -w / 2 + bar / 2, h / 2), "white"),
            _box((d, bar, h), (0.0, w / 2 - bar / 2, h / 2), "white"),
            _box((d, 0.03, h), (0.0, 0.0, h / 2), "white"), _box((d, w, 0.03), (0.0, 0.0, h / 2), "white"),
            _box((0.005, w - 2 * bar, h - 2 * bar), (0.0, 0.0, h / 2), "glass", collision=False),
            _box((0.12, w + 0.06, 0.025), (-0.04, 0.0, -0.0125), "body"))  # sill


def _pegboard() -> tuple[Part, ...]:
    w, h = 0.9, 0.6
    parts = [_box((0.02, w, h), (0.0, 0.0, h / 2))]
    for i, y in enumerate((-0.33, -0.2, -0.07, 0.07, 0.2, 0.33)):
        for z in (0.2, 0.42):
            parts.append(_box((0.08, 0.01, 0.01), (-0.05, y, z), "metal"))
        if i % 2 == 0:
            parts.append(_box((0.015, 0.04, 0.16), (-0.03, y + 0.03, 0.3 if i % 4 else 0.12), "dark"))
    return tuple(parts)


def _dish_rack() -> tuple[Part, ...]:
    parts = [_box((0.32, 0.45, 0.02), (0.0, 0.0, 0.01))]
    for k in range(8):
        y = -0.19 + 0.054 * k
        parts.append(_box((0.006, 0.006, 0.12), (-0.1, y, 0.08), "metal"))
        parts.append(_box((0.006, 0.006, 0.12), (0.1, y, 0.08), "metal"))
    parts += [_box((0.2, 0.008, 0.2), (0.0, -0.165 + 0.11 * k, 0.12), "white") for k in range(3)]
    return tuple(parts)


def _monitor() -> tuple[Part, ...]:
    return (_box((0.2, 0.24, 0.02), (0.03, 0.0, 0.01), "dark"), _box((0.04, 0.06, 0.26), (0.05, 0.0, 0.15), "dark"),
            _box((0.03, 0.62, 0.37), (0.02, 0.0, 0.36)), _box((0.002, 0.58, 0.33), (0.004, 0.0, 0.36), "dark",
                                                             collision=False))


def _fume_hood() -> tuple[Part, ...]:
    d, w, h = 0.7, 1.2, 1.1
    return (_box((d, 0.05, h), (0.0, -w / 2 + 0.025, h / 2)), _box((d, 0.05, h), (0.0, w / 2 - 0.025, h / 2)),
            _box((0.04, w, h), (d / 2 - 0.02, 0.0, h / 2), "white"), _box((d, w, 0.22), (0.0, 0.0, h + 0.11)),
            _box((0.01, w - 0.1, 0.35), (-d / 2 + 0.01, 0.0, h - 0.18), "glass", collision=False),
            _box((0.03, w - 0.1, 0.03), (-d / 2 + 0.01, 0.0, h - 0.37), "metal"))


def _drawers(d: float, w: float, h: float, rows: int) -> tuple[Part, ...]:
    parts = [_box((d, w, h), (0.0, 0.0, h / 2))]
    for k in range(1, rows):
        parts.append(_box((0.004, w - 0.02, 0.006), (-d / 2 - 0.001, 0.0, h * k / rows), "dark", collision=False))
    for k in range(rows):
        parts.append(_box((0.02, 0.12, 0.015), (-d / 2 - 0.01, 0.0, h * (k + 0.75) / rows), "metal",
                          collision=False))
    return tuple(parts)


STRUCTURES: dict[str, StructureDef] = {s.name: s for s in (
    StructureDef("shelf", "free-standing shelf unit, 4 boards (0.35 x 0.9 x 1.2 m)", _shelf(),
                 ("white", "oak_tone", "walnut_tone", "light_grey", "charcoal")),
    StructureDef("counter", "kitchen base cabinet with a worktop (0.62 x 1.02 x 0.9 m)", _counter(False),
                 ("white", "cream", "sage", "navy", "oak_tone", "light_grey")),
    StructureDef("sink", "base cabinet with a steel sink basin and a faucet (0.62 x 1.02 x 1.2 m)", _counter(True),
                 ("white", "cream", "sage", "navy", "light_grey")),
    StructureDef("wall_cabinet", "wall-hung cabinet with two doors (0.34 x 0.8 x 0.7 m)", _wall_cabinet(),
                 ("white", "cream", "sage", "navy", "oak_tone"), mount="wall"),
    StructureDef("backsplash", "upright splashback panel (0.02 x 1.6 x 0.6 m)",
                 (_box((0.02, 1.6, 0.6), (0.0, 0.0, 0.3)),), ("white", "cream", "sage", "light_grey", "terracotta")),
    StructureDef("window_frame", "window frame with mullions, a glass pane and a sill (0.14 x 1.06 x 0.8 m)",
                 _window(), ("white", "cream", "light_grey"), mount="wall"),
    StructureDef("pegboard", "wall pegboard with pegs and hanging tools (0.13 x 0.9 x 0.6 m)", _pegboard(),
                 ("pegboard_brown", "white", "mid_grey"), mount="wall"),
    StructureDef("cutting_station", "butcher-block board with a knife block (0.32 x 0.46 x 0.2 m)",
                 (_box((0.3, 0.45, 0.03), (0.0, 0.0, 0.015), "wood"),
                  _box((0.1, 0.09, 0.18), (0.09, 0.17, 0.12))), ("black", "charcoal", "red", "oak_tone")),
    StructureDef("dish_rack", "plate rack on a drip tray with three plates (0.32 x 0.45 x 0.22 m)", _dish_rack(),
                 ("white", "light_grey", "charcoal", "sage")),
    StructureDef("upper_shelf", "wall shelf board on two brackets (0.25 x 1.0 x 0.18 m)",
                 (_box((0.25, 1.0, 0.03), (0.0, 0.0, 0.165)),
                  *(_box((0.2, 0.02, 0.15), (0.02, y, 0.075), "dark") for y in (-0.35, 0.35))),
                 ("white", "oak_tone", "walnut_tone", "charcoal"), mount="wall"),
    StructureDef("monitor", "desk monitor on a stand (0.2 x 0.62 x 0.55 m)", _monitor(), ("black", "charcoal",
                                                                                          "white")),
    StructureDef("fume_hood", "lab fume hood with a glass sash (0.7 x 1.2 x 1.32 m)", _fume_hood(),
                 ("light_grey", "white", "steel_blue")),
    StructureDef("filing_cabinet", "three-drawer filing cabinet (0.5 x 0.45 x 1.0 m)", _drawers(0.5, 0.45, 1.0, 3),
                 ("light_grey", "mid_grey", "charcoal", "steel_blue")),
    StructureDef("tool_chest", "six-drawer tool chest (0.45 x 0.7 x 0.9 m)", _drawers(0.45, 0.7, 0.9, 6),
                 ("red", "steel_blue", "charcoal", "teal")),
)}
"""Every fixed structure by name."""
