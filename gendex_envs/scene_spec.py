"""Typed schema of a task's optional ``scene`` section: what the place around the table looks like.

A scene names a style (:mod:`gendex_envs.scene_styles`: ``kitchen``, ``lab``, ...) and may override any of its
sections: the table top's ``surface``, the ``floor``, the ``background`` of the walls, the ``lighting``, the
``camera_jitter`` of the views, and fixed ``structures`` (shelves, counters, a sink...). A section given replaces the
style's section whole. Every randomized field declares its choices (a list of names) or its range (``[lo, hi]``);
each episode draws one appearance from them (:mod:`gendex_envs.appearance`). Only ``structures`` touch physics
(static boxes with collision, placed where the spec says, never randomized); everything else is light and paint.

Without a ``scene`` section a task looks exactly as it always has (a plain table on a grey floor under ManiSkill's
default lights). ``docs/task_spec.md`` and ``docs/scenes.md`` document the fields.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal, get_args

from gendex_envs.assets.backgrounds import BACKGROUNDS
from gendex_envs.assets.structures import PAINTS, STRUCTURES
from gendex_envs.assets.surface_textures import MATERIALS
from gendex_envs.errors import TaskSpecError
from gendex_envs.typed_yaml import MAX_POSITION_M, bounded_field, build, quote, spec_error, suggest_value

MAX_CHOICES = 64
"""Most names in one list of choices (materials, images, paints)."""
MAX_LIGHTS = 4
"""Most directional lights (each light costs render time)."""
MAX_STRUCTURES = 16
"""Most fixed structures in a scene."""
MAX_AMBIENT = 1.0
"""Bound on the ambient light's grey level."""
MAX_LIGHT_INTENSITY = 5.0
"""Bound on a directional light's intensity (1.0: ManiSkill's default light)."""
COLOR_TEMPERATURE_K = (1500.0, 12000.0)
"""Allowed colour temperatures (K): candle light to blue sky; 6500 K is daylight white."""
MAX_DIRECTION_JITTER_DEG = 45.0
"""Bound on the cone (half-angle, degrees) a light's direction is drawn from."""
MAX_CAMERA_JITTER_M = 0.05
"""Bound on a camera's position noise per axis (m): small enough that every view still frames the workspace."""
MAX_CAMERA_JITTER_DEG = 5.0
"""Bound on a camera's rotation noise about each of its axes (degrees)."""
MAX_ANGLE_DEG = 360.0

Anchor = Literal["table", "far_edge", "left_edge", "right_edge"]
ANCHORS: tuple[str, ...] = get_args(Anchor)


@dataclass(frozen=True, kw_only=True)
class SurfaceSpec:
    """The table top's material: one of ``materials`` per episode."""

    materials: tuple[str, ...] = bounded_field(MAX_CHOICES, "materials", "MAX_CHOICES")
    """Names from the material catalog (``gendex scenes``), at least one, no repeats."""


@dataclass(frozen=True, kw_only=True)
class FloorSpec:
    """The floor's material: one of ``materials`` per episode."""

    materials: tuple[str, ...] = bounded_field(MAX_CHOICES, "materials", "MAX_CHOICES")
    """Names from the material catalog, at least one, no repeats."""


@dataclass(frozen=True, kw_only=True)
class BackgroundSpec:
    """The walls around the scene: one of ``images`` per episode, on every wall."""

    images: tuple[str, ...] = bounded_field(MAX_CHOICES, "images", "MAX_CHOICES")
    """Names from the background catalog, at least one, no repeats."""


@dataclass(frozen=True, kw_only=True)
class LightSpec:
    """One directional light."""

    direction: tuple[float, float, float]
    """Where the light shines (world frame; normalised), pointing down: z < 0."""
    direction_jitter_deg: float = 0.0
    """Half-angle of the cone around ``direction`` each episode's direction is drawn from, 0..45."""
    intensity: tuple[float, float] = (1.0, 1.0)
    """Range [lo, hi] of the light's intensity, 0 <= lo <= hi <= 5."""
    color_temperature_k: tuple[float, float] = (6500.0, 6500.0)
    """Range [lo, hi] of its colour temperature (K), within 1500..12000."""


DEFAULT_LIGHTS = (LightSpec(direction=(1.0, 1.0, -1.0)), LightSpec(direction=(0.0, 0.0, -1.0)))
"""ManiSkill's default lights: a slanted and an overhead white light."""


@dataclass(frozen=True, kw_only=True)
class LightingSpec:
    """Ambient light and directional lights."""

    ambient: tuple[float, float] = (0.3, 0.3)
    """Range [lo, hi] of the ambient light's grey level, 0..1."""
    lights: tuple[LightSpec, ...] = bounded_field(MAX_LIGHTS, "lights", "MAX_LIGHTS", default=DEFAULT_LIGHTS)
    """One to MAX_LIGHTS directional lights."""


@dataclass(frozen=True, kw_only=True)
class CameraJitterSpec:
    """Small pose noise of every camera (the three views, their sensor twins and the hand camera) per episode."""

    position_m: float = 0.0
    """Half-range of position noise per axis (m), 0..0.05."""
    rotation_deg: float = 0.0
    """Half-range of rotation noise about each camera axis (degrees), 0..5."""


@dataclass(frozen=True, kw_only=True)
class StructureSpec:
    """A fixed structure: static, collides, placed by the spec (never randomized); its paint is drawn."""

    name: str
    """snake_case identifier, unique among structures and objects."""
    kind: str
    """Structure from the catalog (``gendex scenes``): shelf, counter, sink, wall_cabinet..."""
    pos_m: tuple[float, float, float]
    """x, y of its footprint's centre (from the anchor) and z of its base above the table top (or the floor)."""
    yaw_deg: float = 0.0
    """Rotation about z (degrees); 0: its front faces -x (towards the robot from the far end of the table)."""
    anchor: Anchor = "table"
    """What x, y are measured from: the table's centre, or the middle of its far (+x), left (+y) or right (-y) edge."""
    on_floor: bool = False
    """z is measured from the floor instead of the table top."""
    colors: tuple[str, ...] | None = bounded_field(MAX_CHOICES, "paints", "MAX_CHOICES", default=None)
    """Paints its body may take (``gendex scenes``); None: the structure's own palette."""


@dataclass(frozen=True, kw_only=True)
class SceneSpec:
    """The ``scene`` section of a task. ``style`` (default ``plain``) fills every section not given here."""

    style: str | None = None
    """A scene style (``gendex scenes``: kitchen, lab, office, workshop, dining, studio, plain)."""
    surface: SurfaceSpec | None = None
    floor: FloorSpec | None = None
    background: BackgroundSpec | None = None
    lighting: LightingSpec | None = None
    camera_jitter: CameraJitterSpec | None = None
    structures: tuple[StructureSpec, ...] | None = bounded_field(MAX_STRUCTURES, "structures", "MAX_STRUCTURES",
                                                                  default=None)
    """Fixed structures; None: the style's, ``[]``: none."""


@dataclass(frozen=True, kw_only=True)
class ResolvedScene:
    """A scene with every section filled in from its style: what the env builds and draws from."""

    style: str
    surface: SurfaceSpec
    floor: FloorSpec
    background: BackgroundSpec
    lighting: LightingSpec
    camera_jitter: CameraJitterSpec
    structures: tuple[StructureSpec, ...]


SECTIONS: tuple[str, ...] = ("surface", "floor", "background", "lighting", "camera_jitter", "structures")


def resolve_scene(scene: SceneSpec) -> ResolvedScene:
    """``scene`` with the sections it leaves out taken from its style (``plain`` when it names none)."""
    from gendex_envs.scene_styles import DEFAULT_STYLE, STYLES

    name = scene.style or DEFAULT_STYLE
    style = STYLES[name]
    return ResolvedScene(style=name, **{s: getattr(scene, s) if getattr(scene, s) is not None else getattr(style, s)
                                        for s in SECTIONS})


# ---------------------------------------------------------------------------------------------- checks
def scene_problems(scene: SceneSpec, path: str = "scene", object_names: tuple[str, ...] = ()) -> list[str]:
    """Every problem of ``scene`` as ``"<path>.<field> = <value> is not allowed; <what is>"`` (empty: valid)."""
    from gendex_envs.scene_styles import STYLES
    from gendex_envs.spec import SNAKE_NAME_RE

    p: list[str] = []

    def need(ok: bool, where: str, value: Any, allowed: str) -> None:
        if not ok:
            p.append(f"{where} = {quote(value)} is not allowed; {allowed}")

    def names(values: tuple[str, ...], where: str, catalog: Mapping[str, Any], what: str) -> None:
        need(len(values) >= 1, where, list(values), f"give at least one {what}")
        need(len(set(values)) == len(values), where, list(values), f"each {what} at most once")
        for i, v in enumerate(values):
            if v not in catalog:
                p.append(f"{where}[{i}] = {quote(v)} is not a known {what}.{suggest_value(v, catalog)} "
                         f"`gendex scenes` lists them.")

    def span(value: tuple[float, float], where: str, lo: float, hi: float, unit: str = "") -> None:
        ok = all(math.isfinite(v) for v in value) and lo <= value[0] <= value[1] <= hi
        need(ok, where, list(value), f"a range [lo, hi] with {lo} <= lo <= hi <= {hi}{unit}")

    if scene.style is not None and scene.style not in STYLES:
        p.append(f"{path}.style = {quote(scene.style)} is not a scene style; allowed: "
                 f"{', '.join(map(repr, STYLES))}.{suggest_value(scene.style, STYLES)}")
    if scene.surface is not None:
        names(scene.surface.materials, f"{path}.surface.materials", MATERIALS, "material")
    if scene.floor is not None:
        names(scene.floor.materials, f"{path}.floor.materials", MATERIALS, "material")
    if scene.background is not None:
        names(scene.background.images, f"{path}.background.images", BACKGROUNDS, "background image")
    if scene.lighting is not None:
        at = f"{path}.lighting"
        span(scene.lighting.ambient, f"{at}.ambient", 0.0, MAX_AMBIENT)
        need(len(scene.lighting.lights) >= 1, f"{at}.lights", [], f"give 1 to {MAX_LIGHTS} lights")
        for i, light in enumerate(scene.lighting.lights):
            li = f"{at}.lights[{i}]"
            d = light.direction
            norm = math.sqrt(sum(c * c for c in d)) if all(math.isfinite(c) for c in d) else 0.0
            need(norm > 1e-6 and d[2] < -1e-6 * norm, f"{li}.direction", list(d),
                 "a non-zero direction pointing down (z < 0): where the light shines")
            need(0.0 <= light.direction_jitter_deg <= MAX_DIRECTION_JITTER_DEG, f"{li}.direction_jitter_deg",
                 light.direction_jitter_deg, f"0 <= jitter <= {MAX_DIRECTION_JITTER_DEG} degrees")
            span(light.intensity, f"{li}.intensity", 0.0, MAX_LIGHT_INTENSITY)
            span(light.color_temperature_k, f"{li}.color_temperature_k", *COLOR_TEMPERATURE_K, " K")
    if scene.camera_jitter is not None:
        cj = scene.camera_jitter
        need(0.0 <= cj.position_m <= MAX_CAMERA_JITTER_M, f"{path}.camera_jitter.position_m", cj.position_m,
             f"0 <= position_m <= {MAX_CAMERA_JITTER_M} (MAX_CAMERA_JITTER_M)")
        need(0.0 <= cj.rotation_deg <= MAX_CAMERA_JITTER_DEG, f"{path}.camera_jitter.rotation_deg", cj.rotation_deg,
             f"0 <= rotation_deg <= {MAX_CAMERA_JITTER_DEG} (MAX_CAMERA_JITTER_DEG)")
    seen: set[str] = set()
    for i, s in enumerate(scene.structures or ()):
        at = f"{path}.structures[{i}]"
        need(bool(SNAKE_NAME_RE.fullmatch(s.name)), f"{at}.name", s.name,
             "must be ASCII snake_case, the whole name ([a-z][a-z0-9_]*)")
        need(s.name not in seen, f"{at}.name", s.name, "structure names must be unique (duplicate name)")
        need(s.name not in object_names, f"{at}.name", s.name, "an object has this name; structures need their own")
        seen.add(s.name)
        if s.kind not in STRUCTURES:
            p.append(f"{at}.kind = {quote(s.kind)} is not a known structure; allowed: "
                     f"{', '.join(map(repr, STRUCTURES))}.{suggest_value(s.kind, STRUCTURES)}")
        need(all(math.isfinite(c) and abs(c) <= MAX_POSITION_M for c in s.pos_m), f"{at}.pos_m", list(s.pos_m),
             f"each coordinate must be within +/-{MAX_POSITION_M} m (MAX_POSITION_M)")
        need(math.isfinite(s.yaw_deg) and abs(s.yaw_deg) <= MAX_ANGLE_DEG, f"{at}.yaw_deg", s.yaw_deg,
             f"must be within +/-{MAX_ANGLE_DEG} degrees")
        if s.colors is not None:
            names(s.colors, f"{at}.colors", PAINTS, "paint")
    return p


def parse_scene(value: str | Mapping | SceneSpec, source: str = "scene=") -> SceneSpec:
    """A validated :class:`SceneSpec` from a style name, a mapping (the YAML section) or a SceneSpec;
    TaskSpecError naming ``source`` and every problem otherwise."""
    if isinstance(value, SceneSpec):
        scene = value
    elif isinstance(value, str):
        scene = SceneSpec(style=value)
    elif isinstance(value, Mapping):
        scene = build(SceneSpec, value, "scene", source)
    else:
        raise TaskSpecError(f"{source}: a scene is a style name, a mapping or a SceneSpec; got {quote(value)} "
                            f"({type(value).__name__})")
    problems = scene_problems(scene)
    if problems:
        raise spec_error(source, problems)
    return scene
