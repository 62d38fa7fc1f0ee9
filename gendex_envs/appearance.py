"""What one episode looks like: the draw of a scene's choices and ranges (:mod:`gendex_envs.scene_spec`) from the
episode's seed.

Every draw goes through its own numpy Generator, seeded by ``(seed, APPEARANCE_TAG, crc32(field))``: it never touches
Gymnasium's ``np_random``, ManiSkill's episode RNG or torch's RNG, so a task's object placement, physics and the actions
a solver takes are the same with appearance randomization on or off; and each field has its own stream, so adding a
camera or a structure leaves the other fields' draws as they were. With randomization off every field takes its
nominal value (the first choice, the middle of each range, no jitter), whatever the seed.

An :class:`Appearance` is plain data; :meth:`Appearance.to_dict` is the JSON-able record datasets keep per episode
(``env.unwrapped.appearance``).
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gendex_envs.assets.structures import STRUCTURES
from gendex_envs.scene_spec import LightSpec, ResolvedScene

APPEARANCE_TAG = 0x5CE7E49
"""Constant mixed into every appearance seed: appearance streams never coincide with other uses of the seed."""


def appearance_rng(seed: int, field: str) -> np.random.Generator:
    """The Generator of ``field``'s draw in the episode of ``seed``."""
    return np.random.default_rng([int(seed) % 2**63, APPEARANCE_TAG, zlib.crc32(field.encode("utf-8"))])


def kelvin_to_rgb(kelvin: float) -> tuple[float, float, float]:
    """Colour of a black body at ``kelvin`` (Tanner Helland's fit, 1000..40000 K), scaled so its largest channel is
    1: 6500 K is about white, lower is warmer (orange), higher cooler (blue)."""
    t = kelvin / 100.0
    r = 255.0 if t <= 66 else 329.698727446 * (t - 60) ** -0.1332047592
    g = 99.4708025861 * math.log(t) - 161.1195681661 if t <= 66 else 288.1221695283 * (t - 60) ** -0.0755148492
    b = 255.0 if t >= 66 else (0.0 if t <= 19 else 138.5177312231 * math.log(t - 10) - 305.0447927307)
    rgb = [min(max(c, 0.0), 255.0) for c in (r, g, b)]
    top = max(rgb)
    return tuple(round(c / top, 6) for c in rgb)  # type: ignore[return-value]


@dataclass(frozen=True)
class LightDraw:
    """One directional light as drawn: unit direction, colour temperature, intensity, and the resulting RGB."""

    direction: tuple[float, float, float]
    color_temperature_k: float
    intensity: float

    @property
    def rgb(self) -> tuple[float, float, float]:
        """Colour times intensity: what the renderer's light gets."""
        return tuple(c * self.intensity for c in kelvin_to_rgb(self.color_temperature_k))  # type: ignore


@dataclass(frozen=True)
class CameraDraw:
    """A camera's pose noise: a position offset (m, in its parent frame) and rotations about its own x (roll),
    y (pitch) and z (yaw) axes (degrees)."""

    offset_m: tuple[float, float, float]
    rotation_deg: tuple[float, float, float]


@dataclass(frozen=True)
class Appearance:
    """What one episode looks like."""

    style: str
    seed: int
    randomized: bool
    surface: str
    floor: str
    background: str
    ambient: float
    lights: tuple[LightDraw, ...]
    structures: dict[str, str]
    """Structure name -> the paint of its body."""
    cameras: dict[str, CameraDraw]

    def to_dict(self) -> dict:
        """JSON-able record of the draw (what a dataset stores per episode)."""
        return {
            "style": self.style, "seed": self.seed, "randomized": self.randomized, "surface": self.surface,
            "floor": self.floor, "background": self.background, "ambient": round(self.ambient, 6),
            "lights": [{"direction": [round(c, 6) for c in li.direction],
                        "color_temperature_k": round(li.color_temperature_k, 3),
                        "intensity": round(li.intensity, 6)} for li in self.lights],
            "structures": dict(self.structures),
            "cameras": {n: {"offset_m": [round(c, 6) for c in c_.offset_m],
                            "rotation_deg": [round(c, 6) for c in c_.rotation_deg]} for n, c_ in self.cameras.items()},
        }


def _uniform(rng: np.random.Generator, span: tuple[float, float], randomize: bool) -> float:
    lo, hi = span
    return float(rng.uniform(lo, hi)) if randomize and hi > lo else (lo + hi) / 2


def _choice(rng: np.random.Generator, names: Sequence[str], randomize: bool) -> str:
    return names[int(rng.integers(len(names)))] if randomize else names[0]


def _direction(rng: np.random.Generator, light: LightSpec, randomize: bool) -> tuple[float, float, float]:
    """The light's direction, drawn uniformly (by solid angle) within its jitter cone."""
    d = np.asarray(light.direction, dtype=float)
    d /= np.linalg.norm(d)
    if not randomize or light.direction_jitter_deg <= 0:
        return tuple(float(c) for c in d)  # type: ignore[return-value]
    cos_max = math.cos(math.radians(light.direction_jitter_deg))
    cos_t = rng.uniform(cos_max, 1.0)
    phi = rng.uniform(0.0, 2 * math.pi)
    helper = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    sin_t = math.sqrt(max(0.0, 1 - cos_t * cos_t))
    out = cos_t * d + sin_t * (math.cos(phi) * u + math.sin(phi) * v)
    if out[2] > -0.05:  # a wide cone around a low light may reach the horizon: keep it shining down
        out[2] = -0.05
    out /= np.linalg.norm(out)
    return tuple(float(c) for c in out)  # type: ignore[return-value]


def draw_appearance(scene: ResolvedScene, seed: int, cameras: Sequence[str] = (), randomize: bool = True
                    ) -> Appearance:
    """The appearance of the episode of ``seed`` (``cameras``: the names of the cameras to jitter)."""
    lights = []
    for k, light in enumerate(scene.lighting.lights):
        rng = appearance_rng(seed, f"light/{k}")
        lights.append(LightDraw(direction=_direction(rng, light, randomize),
                                color_temperature_k=_uniform(rng, light.color_temperature_k, randomize),
                                intensity=_uniform(rng, light.intensity, randomize)))
    structures = {}
    for s in scene.structures:
        palette = s.colors if s.colors is not None else STRUCTURES[s.kind].palette
        structures[s.name] = _choice(appearance_rng(seed, f"structure/{s.name}"), palette, randomize)
    jitter = scene.camera_jitter
    views = {}
    for name in sorted(cameras):
        rng = appearance_rng(seed, f"camera/{name}")
        on = randomize and (jitter.position_m > 0 or jitter.rotation_deg > 0)
        offset = rng.uniform(-jitter.position_m, jitter.position_m, 3) if on else np.zeros(3)
        turn = rng.uniform(-jitter.rotation_deg, jitter.rotation_deg, 3) if on else np.zeros(3)
        views[name] = CameraDraw(tuple(float(c) for c in offset), tuple(float(c) for c in turn))  # type: ignore
    return Appearance(
        style=scene.style, seed=int(seed), randomized=randomize,
        surface=_choice(appearance_rng(seed, "surface"), scene.surface.materials, randomize),
        floor=_choice(appearance_rng(seed, "floor"), scene.floor.materials, randomize),
        background=_choice(appearance_rng(seed, "background"), scene.background.images, randomize),
        ambient=_uniform(appearance_rng(seed, "ambient"), scene.lighting.ambient, randomize),
        lights=tuple(lights), structures=structures, cameras=views)
