"""Procedural background images: the walls of the room around the table (kitchens, labs, offices, workshops,
dining rooms, studios), drawn with numpy from simple shapes: tiles, panels, cabinets, windows, shelves, boards.

:data:`BACKGROUNDS` maps a name (what ``scene.background.images`` lists) to its :class:`BackgroundDef`;
:func:`background_image` renders one (memoised per process). An image spans one wall, floor (bottom row) to
:data:`WALL_HEIGHT_M` above it (top row); the side views see about its lower half, so every design puts something
there. GenDex's own work (Apache-2.0), generated at run time; nothing downloaded.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gendex_envs.assets.surface_textures import brushed, tiles, wood
from gendex_envs.assets.texture_noise import (
    Color,
    cell_values,
    flat,
    frame,
    grid_lines,
    hex_color,
    mix,
    ramp,
    rect,
    rng_for,
    shade,
    to_rgba,
    value_noise,
)

BACKGROUND_SIZE = (512, 1024)
"""(rows, columns) of every background image."""
WALL_HEIGHT_M = 2.4
"""Metres of wall one image spans from bottom row (the floor) to top row."""

Maker = Callable[[np.random.Generator, tuple[int, int]], np.ndarray]


@dataclass(frozen=True)
class BackgroundDef:
    """A named wall image and the kind of place it suggests."""

    name: str
    description: str
    make: Maker
    """(rng, (rows, cols)) -> [rows, cols, 3] colours in [0, 1]."""
    place: str
    """kitchen, lab, office, workshop, dining, studio or other."""


def at(height_m: float) -> float:
    """Fractional image row (0 top, 1 bottom) of ``height_m`` above the floor."""
    return 1.0 - height_m / WALL_HEIGHT_M


# ---------------------------------------------------------------------------------------------- wall parts
def paint(rng: np.random.Generator, shape: tuple[int, int], color: Color, mottle: float = 0.06) -> np.ndarray:
    """A painted wall: flat colour, a little uneven."""
    return shade(flat(shape, color), 1 - mottle / 2 + mottle * value_noise(rng, shape, (4, 8), octaves=4))


def band(img: np.ndarray, texture: np.ndarray, top_m: float, bottom_m: float) -> None:
    """Paste ``texture`` (tiled) into the rows between heights ``bottom_m`` and ``top_m`` above the floor."""
    h, w = img.shape[:2]
    r0, r1 = int(round(at(top_m) * h)), int(round(at(bottom_m) * h))
    th, tw = texture.shape[:2]
    reps = (-(-(r1 - r0) // th), -(-w // tw), 1)
    img[r0:r1] = np.tile(texture, reps)[: r1 - r0, :w]


def cabinets(img: np.ndarray, rng: np.random.Generator, top_m: float, bottom_m: float, doors: int, body: Color,
             handle: Color = (0.75, 0.76, 0.78), glass: bool = False) -> None:
    """A row of cabinet doors between two heights: door panels with gaps, shading and handles."""
    y0, y1 = at(top_m), at(bottom_m)
    rect(img, y0, 0.0, y1, 1.0, shade(np.asarray(body), 0.55))
    for k in range(doors):
        x0, x1 = k / doors + 0.004, (k + 1) / doors - 0.004
        tone = 0.95 + 0.08 * rng.random()
        rect(img, y0 + 0.008, x0, y1 - 0.008, x1, shade(np.asarray(body), tone))
        if glass:
            rect(img, y0 + 0.04, x0 + 0.015, y1 - 0.04, x1 - 0.015, (0.55, 0.62, 0.66), alpha=0.8)
        hx = x1 - 0.02 if k % 2 == 0 else x0 + 0.012
        hy = y1 - 0.05 if top_m > 1.2 else y0 + 0.03
        rect(img, hy, hx, hy + 0.05, hx + 0.008, handle)


def window(img: np.ndarray, rng: np.random.Generator, y0: float, x0: float, y1: float, x1: float, view: str,
           frame_color: Color = (0.95, 0.95, 0.93), panes: int = 2) -> None:
    """A window between fractional corners: a view (sky, garden, city, night, blinds), a frame and mullions."""
    h, w = img.shape[:2]
    r0, r1, c0, c1 = int(y0 * h), int(y1 * h), int(x0 * w), int(x1 * w)
    rows, cols = r1 - r0, c1 - c0
    t = np.linspace(0, 1, rows)[:, None] * np.ones((1, cols))
    if view == "night":
        out = ramp(t, [(0, hex_color("#0b1330")), (1, hex_color("#23305a"))])
        lights = value_noise(rng, (rows, cols), (48, 96), octaves=1) > 0.82
        out = mix(out, hex_color("#ffd27a"), (lights & (t > 0.55)).astype(float))
    else:
        out = ramp(t, [(0, hex_color("#7fb2e5")), (1, hex_color("#d8e9f5"))])
        clouds = value_noise(rng, (rows, cols), (3, 6), octaves=4)
        out = mix(out, (1.0, 1.0, 1.0), np.clip((clouds - 0.55) * 3, 0, 0.8))
        if view in ("garden", "city"):
            skyline = 0.55 + 0.25 * value_noise(rng, (1, cols), (1, 12 if view == "garden" else 40), octaves=2)
            below = t > skyline
            ground = (value_noise(rng, (rows, cols), (8, 16), octaves=3) if view == "garden"
                      else 0.4 + 0.3 * np.floor(value_noise(rng, (rows, cols), (1, 30), octaves=1) * 4) / 4)
            color = ramp(ground, [(0, hex_color("#2f5d2a")), (1, hex_color("#8fbf5a"))]) if view == "garden" else \
                ramp(ground, [(0, hex_color("#5f6673")), (1, hex_color("#b7bcc6"))])
            out = np.where(below[..., None], color, out)
        if view == "blinds":
            slat = (np.sin(np.linspace(0, rows / 6 * np.pi, rows)) * 0.5 + 0.5)[:, None] * np.ones((1, cols))
            out = mix(out, hex_color("#ecebe6"), np.clip(slat * 1.4, 0, 0.92))
    img[r0:r1, c0:c1] = out
    frame(img, y0, x0, y1, x1, 0.02, frame_color)
    for k in range(1, panes):
        xm = x0 + (x1 - x0) * k / panes
        rect(img, y0, xm - 0.004, y1, xm + 0.004, frame_color)
    rect(img, y1, x0 - 0.01, y1 + 0.025, x1 + 0.01, shade(np.asarray(frame_color), 0.9))  # the sill


def shelves_with_books(img: np.ndarray, rng: np.random.Generator, boards_m: list[float], x0: float, x1: float,
                       board: Color, book_colors: list[Color]) -> None:
    """Shelf boards at the given heights with rows of book spines (or jars) standing on them."""
    h, w = img.shape[:2]
    for k, height in enumerate(boards_m):
        y = at(height)
        top = at(boards_m[k + 1]) + 0.02 if k + 1 < len(boards_m) else y - 0.16
        c = int(x0 * w)
        while c < int(x1 * w) - 8:
            width = int(rng.integers(6, 16))
            tall = rng.uniform(0.55, 0.95) * (y - top)
            color = np.asarray(book_colors[int(rng.integers(len(book_colors)))]) * rng.uniform(0.75, 1.05)
            rect(img, y - tall, c / w, y, (c + width) / w, color)
            c += width + int(rng.integers(0, 3))
        rect(img, y, x0, y + 0.018, x1, board)


def radiator(img: np.ndarray, x0: float, x1: float, color: Color = (0.93, 0.93, 0.91)) -> None:
    """A panel radiator under a window: a row of vertical fins between 0.2 and 0.75 m above the floor."""
    rect(img, at(0.75), x0, at(0.2), x1, shade(np.asarray(color), 0.8))
    fins = int((x1 - x0) * 120)
    for k in range(fins):
        fx = x0 + (x1 - x0) * (k + 0.15) / fins
        rect(img, at(0.74), fx, at(0.21), fx + 0.7 * (x1 - x0) / fins, color)


def skirting(img: np.ndarray, color: Color, height_m: float = 0.1) -> None:
    rect(img, at(height_m), 0.0, 1.0, 1.0, color)


def picture(img: np.ndarray, rng: np.random.Generator, y0: float, x0: float, y1: float, x1: float) -> None:
    """A framed abstract picture: soft colour fields."""
    h, w = img.shape[:2]
    r0, r1, c0, c1 = int(y0 * h), int(y1 * h), int(x0 * w), int(x1 * w)
    palette = [tuple(rng.uniform(0.2, 0.95, 3)) for _ in range(3)]
    t = value_noise(rng, (r1 - r0, c1 - c0), (2, 3), octaves=3)
    img[r0:r1, c0:c1] = ramp(t, [(0.0, palette[0]), (0.5, palette[1]), (1.0, palette[2])])
    frame(img, y0, x0, y1, x1, 0.015, (0.15, 0.12, 0.1))


# ------------------------------------------------------------------------------------------------ designs
def kitchen(rng, shape, wall: Color, tile: Color, grout: Color, body: Color, view: str | None = None,
            square: bool = False, uppers: bool = True) -> np.ndarray:
    img = paint(rng, shape, wall)
    n = shape[0]
    tile_tex = tiles(rng, n // 4, tile, grout, count=4 if square else 2, rows=4, offset=not square, variation=0.06)
    band(img, tile_tex, 1.55, 0.9)
    cabinets(img, rng, 0.9, 0.1, 8, body)
    skirting(img, shade(np.asarray(body), 0.4))
    rect(img, at(0.93), 0, at(0.88), 1, hex_color("#3b3b3d"))  # the worktop's edge
    if view:
        window(img, rng, at(2.05), 0.38, at(1.12), 0.62, view)
    elif uppers:
        cabinets(img, rng, 2.25, 1.6, 6, body, glass=True)
    return img


def open_shelves(rng, shape) -> np.ndarray:
    img = kitchen(rng, shape, hex_color("#f1ece2"), hex_color("#ffffff"), hex_color("#c9c6bf"), hex_color("#5d7f73"),
                  uppers=False)
    jars = [hex_color(c) for c in ("#d9c8a0", "#b55d3c", "#e9e4d8", "#6f8a63", "#c9a227")]
    shelves_with_books(img, rng, [1.3, 1.75], 0.1, 0.9, hex_color("#8a6138"), jars)
    return img


def lab(rng, shape, wall: Color, body: Color, board: bool = False, hoods: bool = False) -> np.ndarray:
    img = paint(rng, shape, wall, 0.03)
    seams, _, _ = grid_lines(shape, 1, 8, 2.0)
    img = mix(img, shade(np.asarray(wall), 0.8), 0.6 * seams)
    cabinets(img, rng, 0.9, 0.1, 10, body, handle=(0.3, 0.3, 0.32))
    rect(img, at(0.95), 0, at(0.88), 1, hex_color("#1c1d1f"))
    rect(img, at(1.12), 0.0, at(1.08), 1.0, (0.7, 0.72, 0.74))  # service rail
    for k in range(6):
        rect(img, at(1.2), 0.08 + 0.16 * k, at(1.12), 0.11 + 0.16 * k, (0.92, 0.92, 0.9))  # sockets
    if board:
        rect(img, at(2.0), 0.3, at(1.3), 0.7, (0.97, 0.97, 0.97))
        frame(img, at(2.0), 0.3, at(1.3), 0.7, 0.012, (0.7, 0.7, 0.72))
        for _ in range(14):
            y, x = rng.uniform(at(1.95), at(1.4)), rng.uniform(0.32, 0.6)
            rect(img, y, x, y + 0.006, x + rng.uniform(0.02, 0.08), tuple(rng.choice([0.1, 0.2, 0.7], 3)))
    if hoods:
        for x0 in (0.08, 0.56):
            rect(img, at(2.3), x0, at(0.95), x0 + 0.36, (0.85, 0.86, 0.87))
            rect(img, at(1.8), x0 + 0.03, at(1.0), x0 + 0.33, (0.18, 0.2, 0.22))
            rect(img, at(1.8), x0 + 0.03, at(1.4), x0 + 0.33, (0.55, 0.65, 0.7), alpha=0.5)
    elif not board:
        cabinets(img, rng, 2.25, 1.6, 8, shade(np.asarray(body), 1.1), handle=(0.3, 0.3, 0.32), glass=True)
    return img


def office(rng, shape, wall: Color, kind: str) -> np.ndarray:
    img = paint(rng, shape, wall, 0.04)
    skirting(img, hex_color("#e8e6e0"), 0.12)
    if kind == "picture":
        picture(img, rng, at(1.9), 0.36, at(1.2), 0.64)
        rect(img, at(0.75), 0.05, at(0.12), 0.3, hex_color("#7b8086"))  # a low cabinet
        rect(img, at(0.75), 0.7, at(0.12), 0.95, hex_color("#7b8086"))
    elif kind == "blinds":
        window(img, rng, at(2.1), 0.12, at(0.95), 0.88, "blinds", frame_color=(0.85, 0.85, 0.85), panes=3)
        radiator(img, 0.2, 0.8)
    elif kind == "books":
        rect(img, at(2.3), 0.04, at(0.1), 0.96, hex_color("#6b4a2e"))
        books = [hex_color(c) for c in ("#7b2d26", "#264653", "#2a9d8f", "#e9c46a", "#f4a261", "#e76f51",
                                        "#3d405b", "#d8d5cc")]
        shelves_with_books(img, rng, [0.12, 0.55, 0.98, 1.41, 1.84], 0.05, 0.95, hex_color("#4f3520"), books)
    elif kind == "fabric":
        fabric = shade(flat(shape, hex_color("#6f7f94")), 0.85 + 0.3 * value_noise(rng, shape, 128, octaves=2))
        r0 = int(at(1.5) * shape[0])
        img[r0:] = fabric[r0:]
        for x in np.linspace(0, 1, 6):
            rect(img, at(1.5), max(0.0, x - 0.004), 1.0, min(1.0, x + 0.004), (0.75, 0.76, 0.78))
        rect(img, at(1.52), 0, at(1.47), 1, (0.75, 0.76, 0.78))
    elif kind == "glass":
        behind = ramp(value_noise(rng, shape, (2, 6), octaves=3),
                      [(0, hex_color("#9aa7ad")), (1, hex_color("#dfe6e8"))])
        img = mix(img, behind, 0.9)
        for k in range(5):
            rect(img, at(0.9), 0.05 + 0.19 * k, at(0.55), 0.16 + 0.19 * k, (0.45, 0.5, 0.55), alpha=0.5)
        for x in np.linspace(0, 1, 5):
            rect(img, 0.0, max(0.0, x - 0.005), 1.0, min(1.0, x + 0.005), (0.3, 0.32, 0.34))
        rect(img, at(1.0), 0, at(0.97), 1, (0.3, 0.32, 0.34))
    return img


def workshop(rng, shape, kind: str) -> np.ndarray:
    n, w = shape
    if kind == "pegboard":
        img = shade(flat(shape, hex_color("#b08a5a")), 0.9 + 0.15 * value_noise(rng, shape, (8, 16)))
        y, x = np.mgrid[0:n, 0:w]
        dots = ((y % (n // 40)) < 3) & ((x % (w // 80)) < 3)
        img = shade(img, 1 - 0.6 * dots)
        tools = [hex_color(c) for c in ("#c0392b", "#2c3e50", "#f39c12", "#7f8c8d", "#27ae60")]
        for _ in range(14):
            yy, xx = rng.uniform(at(2.0), at(1.1)), rng.uniform(0.05, 0.92)
            rect(img, yy, xx, yy + rng.uniform(0.08, 0.25), xx + rng.uniform(0.008, 0.03),
                 tools[int(rng.integers(len(tools)))])
        rect(img, at(0.95), 0, 1, 1, hex_color("#5b6066"))  # a bench front
        return img
    if kind in ("brick", "block"):
        rows = 30 if kind == "brick" else 12
        cols = 16 if kind == "brick" else 10
        lines, row, col = grid_lines(shape, rows, cols, 3.0 if kind == "brick" else 4.0, offset_rows=True)
        base = hex_color("#9c4a32") if kind == "brick" else hex_color("#a3a19b")
        tone = 0.8 + 0.35 * cell_values(rng, row, col, rows, cols)
        img = shade(flat(shape, base), tone * (0.9 + 0.2 * value_noise(rng, shape, 32, octaves=3)))
        return mix(img, hex_color("#cfc8bb") if kind == "brick" else hex_color("#7b7a76"), lines)
    # corrugated metal
    x = np.linspace(0, 60 * np.pi, w)[None, :] * np.ones((n, 1))
    img = shade(brushed(rng, max(shape), hex_color("#9ea4a8"))[:n, :w], 0.8 + 0.25 * np.sin(x))
    rust = value_noise(rng, shape, (6, 12), octaves=5)
    return mix(img, hex_color("#8a4b2a"), np.clip((rust - 0.62) * 3, 0, 0.7))


def dining(rng, shape, kind: str) -> np.ndarray:
    n, w = shape
    if kind == "stripes":
        x = np.arange(w)[None, :] * np.ones((n, 1))
        stripes = ((x // 24) % 2).astype(float)
        img = mix(paint(rng, shape, hex_color("#e9dcc3")), hex_color("#c9b48e"), 0.6 * stripes)
        skirting(img, hex_color("#f3efe6"), 0.15)
        picture(img, rng, at(1.9), 0.15, at(1.3), 0.35)
        picture(img, rng, at(1.9), 0.65, at(1.3), 0.85)
        return img
    if kind == "wainscot":
        y, x = np.mgrid[0:n, 0:w]
        dots = (((y % 32) - 16) ** 2 + ((x % 32) - 16) ** 2 < 16).astype(float)
        img = mix(paint(rng, shape, hex_color("#2f4858")), hex_color("#d6b56d"), 0.8 * dots)
        panel = wood(rng, n, hex_color("#9c6b3f"), hex_color("#5e3a1e"), rings=40)
        band(img, np.transpose(panel, (1, 0, 2))[: n // 2], 0.95, 0.0)
        for k in range(9):
            frame(img, at(0.85), 0.02 + 0.109 * k, at(0.12), 0.1 + 0.109 * k, 0.01, hex_color("#4a2c14"))
        rect(img, at(0.98), 0, at(0.93), 1, hex_color("#4a2c14"))
        return img
    img = paint(rng, shape, hex_color("#efe6d8"))  # garden window
    window(img, rng, at(2.1), 0.2, at(0.8), 0.8, "garden", panes=3)
    skirting(img, hex_color("#ffffff"), 0.12)
    return img


def backdrop(rng, shape, top: Color, bottom: Color) -> np.ndarray:
    """A photo-studio sweep: a smooth vertical gradient with a soft vignette."""
    n, w = shape
    t = np.linspace(0, 1, n)[:, None] * np.ones((1, w))
    img = ramp(t, [(0, top), (1, bottom)])
    x = np.linspace(-1, 1, w)[None, :]
    return shade(img, (1 - 0.25 * x ** 2) * (0.98 + 0.04 * value_noise(rng, shape, (2, 4))))


def chalkboard(rng, shape) -> np.ndarray:
    img = paint(rng, shape, hex_color("#d9d2c0"))
    board = shade(flat(shape, hex_color("#2e4a3b")), 0.9 + 0.2 * value_noise(rng, shape, (6, 12), octaves=4))
    r0, r1 = int(at(2.1) * shape[0]), int(at(0.9) * shape[0])
    c0, c1 = int(0.1 * shape[1]), int(0.9 * shape[1])
    img[r0:r1, c0:c1] = board[r0:r1, c0:c1]
    for _ in range(24):
        y, x = rng.uniform(at(2.0), at(1.0)), rng.uniform(0.12, 0.8)
        rect(img, y, x, y + 0.007, x + rng.uniform(0.02, 0.09), (0.85, 0.87, 0.84), alpha=0.7)
    frame(img, at(2.1), 0.1, at(0.9), 0.9, 0.015, hex_color("#8a6138"))
    skirting(img, hex_color("#5a4632"), 0.12)
    return img


def plaster(rng, shape) -> np.ndarray:
    img = paint(rng, shape, hex_color("#e4e0d8"), 0.1)
    trowel = value_noise(rng, shape, (6, 12), octaves=5, persistence=0.65)
    img = mix(img, hex_color("#cfc7b8"), np.clip((trowel - 0.5) * 2.5, 0, 1) * 0.6)
    skirting(img, hex_color("#f6f4ef"), 0.12)
    radiator(img, 0.3, 0.7)
    return img


def night_window(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    img = paint(rng, shape, hex_color("#c8c2b8"))
    window(img, rng, at(2.2), 0.1, at(0.85), 0.9, "night", frame_color=(0.25, 0.25, 0.27), panes=4)
    return img


P = functools.partial
H = hex_color
BACKGROUNDS: dict[str, BackgroundDef] = {b.name: b for b in (
    BackgroundDef("kitchen_subway_white", "white subway-tile splashback, white cabinets, glass-front uppers",
                  P(kitchen, wall=H("#f4f1ea"), tile=H("#fbfbf8"), grout=H("#b9b6ae"), body=H("#f0efe9")), "kitchen"),
    BackgroundDef("kitchen_subway_sage", "sage-green subway tiles over sage cabinets",
                  P(kitchen, wall=H("#eef0e8"), tile=H("#a9c2a5"), grout=H("#e7e9e2"), body=H("#7d9b86")), "kitchen"),
    BackgroundDef("kitchen_window", "a kitchen window over navy cabinets and square tiles",
                  P(kitchen, wall=H("#f3eee4"), tile=H("#f6f6f2"), grout=H("#c2beb4"), body=H("#2f3e5c"),
                    view="sky", square=True), "kitchen"),
    BackgroundDef("kitchen_garden_window", "a kitchen window onto a garden, oak cabinets",
                  P(kitchen, wall=H("#f6efe2"), tile=H("#e8dcc4"), grout=H("#b8ab92"), body=H("#b98a58"),
                    view="garden"), "kitchen"),
    BackgroundDef("kitchen_open_shelves", "open shelves with jars over green cabinets", open_shelves, "kitchen"),
    BackgroundDef("lab_panels", "grey lab wall panels, a service rail with sockets, grey cabinets",
                  P(lab, wall=H("#e3e6e8"), body=H("#9aa3ab")), "lab"),
    BackgroundDef("lab_whiteboard", "a lab wall with a whiteboard over white cabinets",
                  P(lab, wall=H("#eceae4"), body=H("#e2e2de"), board=True), "lab"),
    BackgroundDef("lab_fume_hoods", "two fume hoods set in a lab wall",
                  P(lab, wall=H("#dfe5e6"), body=H("#c9ced2"), hoods=True), "lab"),
    BackgroundDef("lab_blue_cabinets", "blue lab cabinets under glass-front uppers",
                  P(lab, wall=H("#f1f3f4"), body=H("#4f77a8")), "lab"),
    BackgroundDef("office_picture", "a beige office wall with a framed picture and low cabinets",
                  P(office, wall=H("#e8dcc8"), kind="picture"), "office"),
    BackgroundDef("office_blinds", "a wide office window with blinds",
                  P(office, wall=H("#e6e6e2"), kind="blinds"), "office"),
    BackgroundDef("office_bookshelf", "a wall of bookshelves", P(office, wall=H("#ddd6c8"), kind="books"), "office"),
    BackgroundDef("office_partition", "fabric cubicle partitions", P(office, wall=H("#eef0f2"), kind="fabric"),
                  "office"),
    BackgroundDef("office_glass", "glass partitions onto an open office", P(office, wall=H("#e9eef0"), kind="glass"),
                  "office"),
    BackgroundDef("workshop_pegboard", "a pegboard with hanging tools over a bench",
                  P(workshop, kind="pegboard"), "workshop"),
    BackgroundDef("workshop_brick", "red brick", P(workshop, kind="brick"), "workshop"),
    BackgroundDef("workshop_block", "grey cinder blocks", P(workshop, kind="block"), "workshop"),
    BackgroundDef("workshop_corrugated", "corrugated metal with rust", P(workshop, kind="corrugated"), "workshop"),
    BackgroundDef("dining_stripes", "striped wallpaper with two pictures", P(dining, kind="stripes"), "dining"),
    BackgroundDef("dining_wainscot", "wood wainscoting under dotted wallpaper", P(dining, kind="wainscot"),
                  "dining"),
    BackgroundDef("dining_garden_window", "a wide window onto a garden", P(dining, kind="garden"), "dining"),
    BackgroundDef("studio_warm", "a warm grey photo backdrop", P(backdrop, top=H("#d9d1c7"), bottom=H("#8c8379")),
                  "studio"),
    BackgroundDef("studio_cool", "a cool blue-grey photo backdrop", P(backdrop, top=H("#c9d3dc"), bottom=H("#5f6b77")),
                  "studio"),
    BackgroundDef("classroom_chalkboard", "a chalkboard with chalk marks", chalkboard, "other"),
    BackgroundDef("plaster_white", "plain white plaster", plaster, "other"),
    BackgroundDef("city_night_window", "a window onto a city at night", night_window, "other"),
)}
"""Every background image by name."""


@functools.cache
def background_image(name: str) -> np.ndarray:
    """uint8 [rows, cols, 4] image of background ``name`` (memoised; KeyError for an unknown name)."""
    img = to_rgba(BACKGROUNDS[name].make(rng_for(f"background/{name}"), BACKGROUND_SIZE))
    img.setflags(write=False)
    return img
