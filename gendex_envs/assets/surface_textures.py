"""Procedural surface materials for table tops, floors and structures: wood grains, stone, laminates, metal, tile,
cloth and more, each a seeded numpy texture (:mod:`gendex_envs.assets.texture_noise`) plus PBR values.

:data:`MATERIALS` maps a material name (what a task's ``scene.surface.materials`` and ``scene.floor.materials``
list) to its :class:`MaterialDef`; :func:`material_image` renders one (memoised per process). Textures tile
seamlessly and cover :data:`PERIOD_M` of the surface per repeat. All of it is GenDex's own work (Apache-2.0),
generated at run time: no image files, nothing downloaded (``gendex_envs/assets/data/scenery/catalog.json`` records
the catalog and its licence).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gendex_envs.assets.texture_noise import (
    Color,
    cell_values,
    flat,
    grid_lines,
    hex_color,
    mix,
    rng_for,
    shade,
    to_rgba,
    value_noise,
)

SURFACE_PX = 512
"""Edge length (pixels) of every surface texture."""
PERIOD_M = 1.0
"""Metres of surface one copy of a texture covers (it repeats beyond): a tile of ``tile_white`` is 1/8 m."""

Maker = Callable[[np.random.Generator, int], np.ndarray]


@dataclass(frozen=True)
class MaterialDef:
    """A named surface material: how its texture is drawn and how it reflects light."""

    name: str
    description: str
    make: Maker
    """(rng, size) -> [size, size, 3] colours in [0, 1]."""
    roughness: float
    metallic: float = 0.0
    tags: tuple[str, ...] = ()


# ------------------------------------------------------------------------------------------------ generators
def wood(rng: np.random.Generator, n: int, light: Color, dark: Color, rings: int = 14, warp: float = 1.2,
         knots: int = 0) -> np.ndarray:
    """Flat-sawn wood: growth rings across y bent by low-frequency noise, fine streaks along x, optional knots."""
    bend = value_noise(rng, (n, n), (2, 3), octaves=3)
    y = np.arange(n)[:, None] / n
    t = np.sin(2 * np.pi * (rings * y + warp * bend)) * 0.5 + 0.5
    if knots:
        yy, xx = np.mgrid[0:n, 0:n] / n
        for cy, cx in rng.random((knots, 2)):
            d = np.hypot(np.minimum(abs(yy - cy), 1 - abs(yy - cy)) * 3.0, np.minimum(abs(xx - cx), 1 - abs(xx - cx)))
            t = np.maximum(t, np.exp(-(d / 0.03) ** 2))
    streak = value_noise(rng, (n, n), (64, 4), octaves=3)
    img = mix(light, dark, 0.65 * t ** 1.6 + 0.35 * streak)
    return shade(img, 0.92 + 0.16 * value_noise(rng, (n, n), 4, octaves=2))


def planks(rng: np.random.Generator, n: int, light: Color, dark: Color, rows: int = 6, seam: Color = (0.1, 0.07, 0.05),
           stagger: bool = True) -> np.ndarray:
    """Boards along x: wood grain, each board a tone of its own, dark seams between boards and at staggered ends."""
    base = wood(rng, n, light, dark, rings=rows * 5, warp=0.6)
    lines, row, col = grid_lines((n, n), rows, 2 if stagger else 1, 2.0, offset_rows=stagger)
    tone = 0.82 + 0.3 * cell_values(rng, row, col, rows, 2)
    return mix(shade(base, tone), seam, 0.85 * lines)


def stone(rng: np.random.Generator, n: int, base: Color, vein: Color, veins: float = 3.0, sharp: float = 10.0
          ) -> np.ndarray:
    """Marble: a soft cloudy base crossed by thin turbulent veins."""
    turb = value_noise(rng, (n, n), 4, octaves=5, persistence=0.55)
    x = np.arange(n)[None, :] / n
    y = np.arange(n)[:, None] / n
    v = np.abs(np.sin(2 * np.pi * (veins * 0.5 * (x + y) + 1.8 * turb)))
    vein_t = np.exp(-sharp * v)
    cloud = value_noise(rng, (n, n), 3, octaves=4)
    img = shade(flat((n, n), base), 0.92 + 0.12 * cloud)
    return mix(img, vein, 0.8 * vein_t)


def speckle(rng: np.random.Generator, n: int, base: Color, specks: list[Color], density: float = 0.35,
            grain: int = 96) -> np.ndarray:
    """Granite, terrazzo, cork: a base sprinkled with specks of other colours."""
    img = shade(flat((n, n), base), 0.9 + 0.2 * value_noise(rng, (n, n), 6, octaves=3))
    for color in specks:
        spots = value_noise(rng, (n, n), grain, octaves=1)
        img = mix(img, color, np.clip((spots - (1 - density / len(specks))) * 8, 0, 1))
    return img


def laminate(rng: np.random.Generator, n: int, color: Color, grain: float = 0.05) -> np.ndarray:
    """A plain plastic or painted finish with a faint fine grain."""
    return shade(flat((n, n), color), 1 - grain / 2 + grain * value_noise(rng, (n, n), 48, octaves=2))


def brushed(rng: np.random.Generator, n: int, color: Color, streak: float = 0.18) -> np.ndarray:
    """Brushed metal: fine streaks along x."""
    lines = value_noise(rng, (n, n), (256, 2), octaves=2)
    return shade(flat((n, n), color), 1 - streak / 2 + streak * lines)


def diamond_plate(rng: np.random.Generator, n: int, color: Color, count: int = 10) -> np.ndarray:
    """Tread plate: brushed metal with raised diagonal bars in alternating directions."""
    img = brushed(rng, n, color, 0.12)
    y, x = (np.mgrid[0:n, 0:n] + 0.5) * count / n
    iy, ix = np.floor(y), np.floor(x)
    fy, fx = y - iy - 0.5, x - ix - 0.5
    flip = ((iy + ix) % 2) * 2 - 1
    u, v = (fx + flip * fy) / np.sqrt(2), (fx - flip * fy) / np.sqrt(2)
    bar = np.clip(1.0 - np.hypot(u / 0.32, v / 0.07), 0, 1)
    return shade(img, 1.0 + 0.5 * bar - 0.2 * np.clip(1.0 - np.hypot(u / 0.32, (v + 0.05) / 0.07), 0, 1))


def tiles(rng: np.random.Generator, n: int, tile: Color, grout: Color, count: int = 8, rows: int | None = None,
          offset: bool = False, variation: float = 0.08, alt: Color | None = None) -> np.ndarray:
    """Tiles with grout lines; every tile varies a little; ``alt``: a checkerboard of two colours."""
    rows = rows or count
    lines, row, col = grid_lines((n, n), rows, count, max(2.0, n / count / 18), offset_rows=offset)
    img = flat((n, n), tile)
    if alt is not None:
        img = mix(img, alt, ((row + col) % 2).astype(float))
    tone = 1 - variation / 2 + variation * cell_values(rng, row, col, rows, count)
    img = shade(img, tone * (0.97 + 0.06 * value_noise(rng, (n, n), 16, octaves=2)))
    return mix(img, grout, lines)


def weave(rng: np.random.Generator, n: int, color: Color, threads: int = 128, depth: float = 0.25) -> np.ndarray:
    """Woven cloth: over-under threads and a soft uneven dye."""
    y, x = np.mgrid[0:n, 0:n] * threads / n
    warp = np.sin(np.pi * x) ** 2
    weft = np.sin(np.pi * y) ** 2
    over = ((np.floor(x) + np.floor(y)) % 2).astype(float)
    relief = over * warp + (1 - over) * weft
    return shade(flat((n, n), color), (1 - depth) + depth * relief + 0.08 * (value_noise(rng, (n, n), 6) - 0.5))


def gingham(rng: np.random.Generator, n: int, color: Color, light: Color = (0.96, 0.95, 0.92), bands: int = 8
            ) -> np.ndarray:
    """A checked tablecloth: stripes of ``color`` both ways, darker where they cross, on a woven ground."""
    y, x = np.mgrid[0:n, 0:n] * bands / n
    sx = (np.floor(x * 2) % 2 == 0).astype(float)
    sy = (np.floor(y * 2) % 2 == 0).astype(float)
    img = mix(light, color, 0.5 * (sx + sy))
    return shade(img, weave(rng, n, (1.0, 1.0, 1.0), threads=160, depth=0.15)[..., 0])


def concrete(rng: np.random.Generator, n: int, color: Color, pits: float = 0.02) -> np.ndarray:
    """Concrete: blotchy grey with small dark pores."""
    img = shade(flat((n, n), color), 0.8 + 0.35 * value_noise(rng, (n, n), 8, octaves=6, persistence=0.6))
    holes = value_noise(rng, (n, n), 160, octaves=1)
    return shade(img, 1 - 0.5 * (holes > 1 - pits))


def carpet(rng: np.random.Generator, n: int, color: Color) -> np.ndarray:
    """Loop-pile carpet: dense high-frequency fibre noise over a faint mottle."""
    fibre = value_noise(rng, (n, n), 192, octaves=2)
    return shade(flat((n, n), color), 0.75 + 0.35 * fibre + 0.1 * (value_noise(rng, (n, n), 5) - 0.5))


def grid_mat(rng: np.random.Generator, n: int, color: Color, line: Color, count: int = 16) -> np.ndarray:
    """A rubber or cutting mat: dark ground with a printed grid."""
    lines, _, _ = grid_lines((n, n), count, count, 1.5)
    return mix(laminate(rng, n, color, 0.1), line, 0.8 * lines)


def _m(name: str, description: str, make: Maker, roughness: float, metallic: float = 0.0,
       tags: tuple[str, ...] = ()) -> MaterialDef:
    return MaterialDef(name, description, make, roughness, metallic, tags)


P = functools.partial
H = hex_color
MATERIALS: dict[str, MaterialDef] = {m.name: m for m in (
    _m("oak", "light oak, flat-sawn grain", P(wood, light=H("#c89b68"), dark=H("#8a6138")), 0.6,
       tags=("wood",)),
    _m("walnut", "dark walnut grain", P(wood, light=H("#7a5334"), dark=H("#3b2415"), rings=11), 0.55,
       tags=("wood",)),
    _m("maple", "pale maple with a faint grain", P(wood, light=H("#e6cfa4"), dark=H("#c4a274"), rings=18, warp=0.8),
       0.6, tags=("wood",)),
    _m("cherry", "reddish cherry wood", P(wood, light=H("#b66a44"), dark=H("#7a3a22"), rings=12), 0.5,
       tags=("wood",)),
    _m("pine", "knotty yellow pine", P(wood, light=H("#e3c07f"), dark=H("#b58646"), rings=9, warp=1.6, knots=3),
       0.7, tags=("wood",)),
    _m("butcher_block", "end-joined hardwood strips", P(planks, light=H("#d8a66e"), dark=H("#94602f"), rows=10,
       seam=H("#5c3a1c")), 0.6, tags=("wood",)),
    _m("floor_planks", "oak floorboards with seams", P(planks, light=H("#b98a58"), dark=H("#7a532d"), rows=6),
       0.65, tags=("wood", "floor")),
    _m("grey_planks", "weathered grey floorboards", P(planks, light=H("#a9a39a"), dark=H("#6e6860"), rows=5,
       seam=H("#3a3632")), 0.75, tags=("wood", "floor")),
    _m("marble_white", "white Carrara-like marble with grey veins", P(stone, base=H("#eeeeec"), vein=H("#8d9096")),
       0.2, tags=("stone",)),
    _m("marble_black", "black marble with pale veins", P(stone, base=H("#1f1f22"), vein=H("#c9c7c0"), sharp=14),
       0.15, tags=("stone",)),
    _m("marble_green", "green marble", P(stone, base=H("#2f5a45"), vein=H("#c9dccf"), veins=5), 0.2,
       tags=("stone",)),
    _m("granite", "speckled grey granite", P(speckle, base=H("#8e8b88"), specks=[H("#2b2a2a"), H("#e6e2dc"),
       H("#a2705a")], density=0.45), 0.3, tags=("stone",)),
    _m("terrazzo", "terrazzo: coloured chips in cream", P(speckle, base=H("#e9e2d4"), specks=[H("#c76b4f"),
       H("#5b7f8e"), H("#2d2d2d")], density=0.25, grain=48), 0.35, tags=("stone", "floor")),
    _m("concrete", "poured concrete", P(concrete, color=H("#9c9a96")), 0.9, tags=("stone", "floor")),
    _m("laminate_white", "white laminate", P(laminate, color=H("#efefec")), 0.45, tags=("laminate",)),
    _m("laminate_grey", "light grey laminate", P(laminate, color=H("#b8bbbe")), 0.45, tags=("laminate",)),
    _m("laminate_beige", "beige laminate", P(laminate, color=H("#d9cbb0")), 0.45, tags=("laminate",)),
    _m("laminate_blue", "blue-grey laminate", P(laminate, color=H("#7d93a8")), 0.45, tags=("laminate",)),
    _m("laminate_green", "sage green laminate", P(laminate, color=H("#9fb39a")), 0.45, tags=("laminate",)),
    _m("epoxy_black", "black epoxy-resin lab bench top", P(speckle, base=H("#1c1d1f"), specks=[H("#3a3c40")],
       density=0.2, grain=128), 0.25, tags=("laminate", "lab")),
    _m("stainless_steel", "brushed stainless steel", P(brushed, color=H("#b9bcbf")), 0.35, metallic=1.0,
       tags=("metal",)),
    _m("aluminium_tread", "aluminium tread plate", P(diamond_plate, color=H("#a7abb0")), 0.4, metallic=1.0,
       tags=("metal", "floor")),
    _m("zinc_sheet", "dull zinc sheet", P(brushed, color=H("#8c9398"), streak=0.08), 0.55, metallic=0.8,
       tags=("metal",)),
    _m("tile_white", "white square tiles, grey grout", P(tiles, tile=H("#f2f1ec"), grout=H("#9a9890")), 0.3,
       tags=("tile", "floor")),
    _m("tile_terracotta", "terracotta floor tiles", P(tiles, tile=H("#b6623d"), grout=H("#d8ccb6"), count=4,
       variation=0.18), 0.7, tags=("tile", "floor")),
    _m("tile_checker", "black and white checker tiles", P(tiles, tile=H("#efefe9"), grout=H("#8f8f8a"), count=6,
       alt=H("#202022"), variation=0.04), 0.35, tags=("tile", "floor")),
    _m("tile_blue", "small blue mosaic tiles", P(tiles, tile=H("#4f7fa8"), grout=H("#e5e5e0"), count=16,
       variation=0.25), 0.3, tags=("tile",)),
    _m("linen", "natural linen cloth", P(weave, color=H("#d8cfbd")), 0.95, tags=("cloth",)),
    _m("gingham_red", "red checked tablecloth", P(gingham, color=H("#c0392b")), 0.9, tags=("cloth",)),
    _m("gingham_blue", "blue checked tablecloth", P(gingham, color=H("#2e5d9e")), 0.9,
       tags=("cloth",)),
    _m("felt_green", "green baize felt", P(weave, color=H("#2f6b3a"), threads=256, depth=0.1), 1.0,
       tags=("cloth",)),
    _m("cork", "cork board", P(speckle, base=H("#b78a55"), specks=[H("#7c5632"), H("#d9b27c")], density=0.6,
       grain=160), 0.9, tags=("cork",)),
    _m("rubber_mat", "dark rubber mat with a printed grid", P(grid_mat, color=H("#2a2c2e"), line=H("#5d6266")),
       0.85, tags=("workshop",)),
    _m("cutting_mat", "green cutting mat with a grid", P(grid_mat, color=H("#2f6e4e"), line=H("#b8d8c4")), 0.7,
       tags=("workshop",)),
    _m("carpet_grey", "grey office carpet", P(carpet, color=H("#6f7277")), 1.0, tags=("floor",)),
    _m("carpet_blue", "blue office carpet", P(carpet, color=H("#3d4f6b")), 1.0, tags=("floor",)),
    _m("linoleum", "mottled linoleum", P(speckle, base=H("#c9c4b0"), specks=[H("#9f9a86"), H("#e8e4d4")],
       density=0.5, grain=24), 0.6, tags=("floor",)),
    _m("painted_floor", "grey epoxy-painted floor", P(laminate, color=H("#7d8286"), grain=0.12), 0.5,
       tags=("floor", "workshop")),
)}
"""Every surface material by name."""


@functools.cache
def material_image(name: str) -> np.ndarray:
    """uint8 [SURFACE_PX, SURFACE_PX, 4] texture of material ``name`` (memoised; KeyError for an unknown name)."""
    m = MATERIALS[name]
    img = to_rgba(m.make(rng_for(f"material/{name}"), SURFACE_PX))
    img.setflags(write=False)
    return img


def mean_color(name: str) -> tuple[float, float, float]:
    """The average colour of material ``name`` in [0, 1] (the table's edges are painted in it)."""
    return tuple(float(c) for c in material_image(name)[..., :3].reshape(-1, 3).mean(axis=0) / 255.0)  # type: ignore


__all__ = ["MATERIALS", "MaterialDef", "SURFACE_PX", "material_image", "mean_color"]
