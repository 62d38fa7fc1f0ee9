"""Small numpy building blocks of the procedural scene textures (:mod:`gendex_envs.assets.surface_textures`,
:mod:`gendex_envs.assets.backgrounds`): seeded generators, tileable value noise, colour ramps and drawing helpers.

Images are float arrays ``[H, W, 3]`` in [0, 1] until :func:`to_rgba` turns them into the ``uint8 [H, W, 4]`` arrays
SAPIEN uploads. Every generator draws from :func:`rng_for` (a numpy Generator seeded by the texture's name), so one
name always gives the same pixels on one machine and numpy build (transcendental ufuncs may differ in the last bit
across CPUs, which can move a pixel by one level; datasets record texture names, not pixels).
"""

from __future__ import annotations

import zlib

import numpy as np

Color = tuple[float, float, float]


def rng_for(name: str) -> np.random.Generator:
    """A Generator seeded by ``name`` alone (crc32 of its UTF-8 bytes): the same texture every time."""
    return np.random.default_rng([zlib.crc32(name.encode("utf-8")), 0x7E47])


def hex_color(code: str) -> Color:
    """``"#a0b1c2"`` -> (r, g, b) in [0, 1]."""
    code = code.lstrip("#")
    return tuple(int(code[i:i + 2], 16) / 255.0 for i in (0, 2, 4))  # type: ignore[return-value]


def value_noise(rng: np.random.Generator, shape: tuple[int, int], cells: tuple[int, int] | int, octaves: int = 4,
                persistence: float = 0.5) -> np.ndarray:
    """[H, W] fractal value noise in [0, 1], tileable (it wraps at the image edges, so a repeated texture shows no
    seam): ``octaves`` layers of random lattices of ``cells`` (rows, cols), doubled per octave, smoothly
    interpolated."""
    h, w = shape
    cy, cx = (cells, cells) if isinstance(cells, int) else cells
    total = np.zeros(shape)
    amp, norm = 1.0, 0.0
    for _ in range(octaves):
        total += amp * _lattice(rng, h, w, cy, cx)
        norm += amp
        amp *= persistence
        cy, cx = cy * 2, cx * 2
    return total / norm


def _lattice(rng: np.random.Generator, h: int, w: int, cy: int, cx: int) -> np.ndarray:
    grid = rng.random((cy, cx))
    y = np.arange(h) * cy / h
    x = np.arange(w) * cx / w
    y0, x0 = np.floor(y).astype(int), np.floor(x).astype(int)
    ty, tx = _smooth(y - y0), _smooth(x - x0)
    y1, x1 = (y0 + 1) % cy, (x0 + 1) % cx
    y0, x0 = y0 % cy, x0 % cx
    a = grid[np.ix_(y0, x0)] * (1 - tx) + grid[np.ix_(y0, x1)] * tx
    b = grid[np.ix_(y1, x0)] * (1 - tx) + grid[np.ix_(y1, x1)] * tx
    return a * (1 - ty[:, None]) + b * ty[:, None]


def _smooth(t: np.ndarray) -> np.ndarray:
    return t * t * (3 - 2 * t)


def mix(a: Color | np.ndarray, b: Color | np.ndarray, t: np.ndarray | float) -> np.ndarray:
    """Per-pixel blend of colours ``a`` and ``b`` by ``t`` ([H, W] or scalar) -> [H, W, 3] (or [3])."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    t = np.asarray(t, dtype=float)
    return a + (b - a) * (t[..., None] if t.ndim else t)


def ramp(t: np.ndarray, stops: list[tuple[float, Color]]) -> np.ndarray:
    """[H, W] in [0, 1] -> [H, W, 3] through colour stops (position, colour), positions increasing."""
    pos = np.array([p for p, _ in stops])
    cols = np.array([c for _, c in stops], dtype=float)
    return np.stack([np.interp(t, pos, cols[:, k]) for k in range(3)], axis=-1)


def flat(shape: tuple[int, int], color: Color) -> np.ndarray:
    return np.broadcast_to(np.asarray(color, dtype=float), (*shape, 3)).copy()


def shade(img: np.ndarray, factor: np.ndarray | float) -> np.ndarray:
    """``img`` scaled by ``factor`` ([H, W] or scalar)."""
    factor = np.asarray(factor, dtype=float)
    return img * (factor[..., None] if factor.ndim else factor)


def rect(img: np.ndarray, y0: float, x0: float, y1: float, x1: float, color: Color | np.ndarray,
         alpha: float = 1.0) -> None:
    """Paint the rectangle of fractional corners (y0, x0)-(y1, x1) (0..1 of the image) in place."""
    h, w = img.shape[:2]
    r0, r1 = int(round(y0 * h)), int(round(y1 * h))
    c0, c1 = int(round(x0 * w)), int(round(x1 * w))
    if r1 > r0 and c1 > c0:
        region = img[r0:r1, c0:c1]
        region[...] = region * (1 - alpha) + np.asarray(color, dtype=float) * alpha


def frame(img: np.ndarray, y0: float, x0: float, y1: float, x1: float, width: float, color: Color) -> None:
    """An outline of fractional ``width`` (of the image height) around a rectangle, in place."""
    wx = width * img.shape[0] / img.shape[1]
    rect(img, y0, x0, y0 + width, x1, color)
    rect(img, y1 - width, x0, y1, x1, color)
    rect(img, y0, x0, y1, x0 + wx, color)
    rect(img, y0, x1 - wx, y1, x1, color)


def grid_lines(shape: tuple[int, int], rows: int, cols: int, width_px: float, offset_rows: bool = False
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(grout mask [H, W] in [0, 1], row index [H, W], column index [H, W]) of a grid of ``rows`` x ``cols`` cells,
    every other row shifted by half a cell when ``offset_rows`` (bricks, subway tiles); lines ``width_px`` wide."""
    h, w = shape
    y = (np.arange(h) + 0.5)[:, None] * rows / h * np.ones((1, w))
    x = (np.arange(w) + 0.5)[None, :] * cols / w * np.ones((h, 1))
    row = np.floor(y).astype(int)
    if offset_rows:
        x = x + 0.5 * (row % 2)
    col = np.floor(x).astype(int) % cols
    fy, fx = y - np.floor(y), x - np.floor(x)
    half_y, half_x = width_px / 2 * rows / h, width_px / 2 * cols / w
    dist = np.minimum(np.minimum(fy, 1 - fy) / half_y, np.minimum(fx, 1 - fx) / half_x)
    return np.clip(1.5 - dist, 0.0, 1.0), row, col


def cell_values(rng: np.random.Generator, row: np.ndarray, col: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """One random value in [0, 1) per grid cell, spread over the cell's pixels."""
    return rng.random((rows + 1, cols + 1))[row % (rows + 1), col % (cols + 1)]


def to_rgba(img: np.ndarray) -> np.ndarray:
    """[H, W, 3] floats in [0, 1] -> contiguous uint8 [H, W, 4], opaque."""
    rgb = np.clip(np.rint(np.asarray(img, dtype=float) * 255.0), 0, 255).astype(np.uint8)
    alpha = np.full((*rgb.shape[:2], 1), 255, dtype=np.uint8)
    return np.ascontiguousarray(np.concatenate([rgb, alpha], axis=-1))
