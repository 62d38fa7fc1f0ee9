"""Building the place around a task: the table and floor every task has, and for a task with a ``scene`` section
(:mod:`gendex_envs.scene_spec`) the room, its lights, its fixed structures and each episode's appearance.

:func:`build_table_and_ground` builds the table (a box with collision, its top the plane z = 0) and the floor (a
collision plane at the table's foot), with today's plain visuals when the task has no scene. :class:`Scenery`
does the rest for a task with one, in three steps the env calls:

* :meth:`Scenery.build` (at scene load): one static actor per structure with its collision boxes (the same in every
  parallel env), then per parallel env one visual-only actor holding the textured table top, the table's edges and
  legs, the floor, four walls and the structures' painted boxes; each env has its own materials, so each can look
  different.
* :meth:`Scenery.load_lighting` (instead of ManiSkill's default lights): the scene's directional lights in every
  parallel env.
* :meth:`Scenery.apply` (at every reset, for the envs being reset): draws each env's :class:`Appearance` from its
  episode seed (:func:`~gendex_envs.appearance.draw_appearance`: its own random streams) and sets textures, paints,
  lights and camera poses. Nothing here touches physics state or any random generator physics uses.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import sapien
import torch
from mani_skill.utils.structs import Actor, Pose

from gendex_envs.appearance import Appearance, draw_appearance
from gendex_envs.assets.backgrounds import WALL_HEIGHT_M, background_image
from gendex_envs.assets.catalog import DYNAMIC_FRICTION_RATIO
from gendex_envs.assets.structures import PAINTS, ROLE_COLORS, STRUCTURES, StructureDef
from gendex_envs.assets.surface_textures import MATERIALS, PERIOD_M, material_image, mean_color
from gendex_envs.errors import TaskSpecError
from gendex_envs.placement import Item
from gendex_envs.scene_geometry import ROBOT_BASE_HALF_M, STRUCTURE_GAP_M, structure_pose
from gendex_envs.scene_spec import ResolvedScene, SceneSpec, StructureSpec, parse_scene, resolve_scene

log = logging.getLogger(__name__)

TABLE_TOP_RGBA = [0.72, 0.62, 0.5, 1.0]
TABLE_LEG_RGBA = [0.35, 0.3, 0.25, 1.0]
GROUND_RGBA = [0.55, 0.57, 0.6, 1.0]
TABLE_THICKNESS_M = 0.05
ROOM_MIN_M = (-2.0, 2.0, 1.6)
"""Least room: walls at x = -2 and +2 m and y = +-1.6 m (the side views, at y = +-1 m, look at the far walls)."""
ROOM_MARGIN_M = 1.0
"""Least distance from the table's edges to the walls; structures push walls further out when they need room."""


def build_table_and_ground(scene, table, visual: bool = True) -> tuple[Actor, Actor]:
    """The table (top at z = 0, collision box TABLE_THICKNESS_M thick) and the ground (a collision plane at the table's
    foot); with ``visual`` today's plain look (a wooden-brown top and legs, a grey floor), else collision only (a
    :class:`Scenery` paints them)."""
    sx, sy = table.size_m
    b = scene.create_actor_builder()
    top = sapien.Pose(p=[0.0, 0.0, -TABLE_THICKNESS_M / 2])
    mat = sapien.physx.PhysxMaterial(table.friction, DYNAMIC_FRICTION_RATIO * table.friction, 0.0)
    b.add_box_collision(top, [sx / 2, sy / 2, TABLE_THICKNESS_M / 2], material=mat)
    if visual:
        b.add_box_visual(top, [sx / 2, sy / 2, TABLE_THICKNESS_M / 2],
                         material=sapien.render.RenderMaterial(base_color=TABLE_TOP_RGBA, roughness=0.8))
        for pose in _leg_poses(table):  # legs: visual only, they never touch anything
            b.add_box_visual(pose, [0.03, 0.03, table.height_m / 2],
                             material=sapien.render.RenderMaterial(base_color=TABLE_LEG_RGBA))
    b.initial_pose = sapien.Pose()
    built_table = b.build_static("table")
    z = -table.height_m
    g = scene.create_actor_builder()
    g.add_plane_collision(sapien.Pose(p=[0, 0, z], q=[0.7071068, 0, -0.7071068, 0]))
    if visual:
        g.add_box_visual(sapien.Pose(p=[0, 0, z - 0.005]), [4.0, 4.0, 0.005],
                         material=sapien.render.RenderMaterial(base_color=GROUND_RGBA))
    g.initial_pose = sapien.Pose()
    return built_table, g.build_static("ground")


def _leg_poses(table) -> list[sapien.Pose]:
    sx, sy = table.size_m
    return [sapien.Pose(p=[lx * (sx / 2 - 0.05), ly * (sy / 2 - 0.05), -table.height_m / 2])
            for lx in (-1, 1) for ly in (-1, 1)]


def _yaw_pose(p, yaw_deg: float) -> sapien.Pose:
    a = math.radians(yaw_deg)
    return sapien.Pose(p=[float(c) for c in p], q=[math.cos(a / 2), 0.0, 0.0, math.sin(a / 2)])


@dataclass(frozen=True)
class PlacedStructure:
    """A structure of the spec at its world pose."""

    index: int
    spec: StructureSpec
    definition: StructureDef
    pose: sapien.Pose

    def part_poses(self) -> list[sapien.Pose]:
        return [self.pose * sapien.Pose(p=list(part.center_m)) for part in self.definition.parts]

    def world_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(min, max) corners of its axis-aligned world box."""
        lo, hi = self.definition.bounds_m
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        world = corners @ self.pose.to_transformation_matrix()[:3, :3].T + self.pose.p
        return world.min(axis=0), world.max(axis=0)


def place_structures(structures: tuple[StructureSpec, ...], table) -> list[PlacedStructure]:
    """Each structure's world pose: its anchor on the table, its offset, its base on the table top or the floor
    (:func:`~gendex_envs.scene_geometry.structure_pose`, which the planner and the critic use too)."""
    return [PlacedStructure(i, s, STRUCTURES[s.kind], _yaw_pose(structure_pose(s, table)[:3, 3], s.yaw_deg))
            for i, s in enumerate(structures)]


def _quad(center, u, v, repeat: tuple[float, float], material) -> sapien.render.RenderShapeTriangleMesh:
    """A textured rectangle: corners center +- u +- v, facing u x v; the texture repeats ``repeat`` times along u
    and v, its top row towards +v."""
    c, u, v = (np.asarray(a, dtype=np.float32) for a in (center, u, v))
    n = np.cross(u, v)
    n /= np.linalg.norm(n)
    vertices = np.stack([c - u - v, c + u - v, c + u + v, c - u + v]).astype(np.float32)
    ru, rv = repeat
    uvs = np.array([[0, rv], [ru, rv], [ru, 0], [0, 0]], dtype=np.float32)
    triangles = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)
    return sapien.render.RenderShapeTriangleMesh(vertices, triangles, np.tile(n, (4, 1)).astype(np.float32), uvs,
                                                 material)


class Scenery:
    """The room, lights, structures and per-episode appearance of a task with a scene (see the module docstring).

    Args:
        scene: the resolved scene (its style's sections filled in).
        randomize: draw each episode's appearance from its seed; False: every episode takes the nominal
            appearance (first choices, mid ranges, no jitter). Physics is the same either way.
    """

    def __init__(self, scene: ResolvedScene, randomize: bool = True):
        self.scene = scene
        self.randomize = randomize
        self.drawn: dict[int, Appearance] = {}
        """The appearance of each parallel env's current episode, by env index."""
        self.structures: dict[str, Actor] = {}
        """Each structure's static collision actor, by structure name."""
        self.room: tuple[float, float, float] = ROOM_MIN_M
        self._materials: list[dict[str, sapien.render.RenderMaterial]] = []
        self._lights: list[list[sapien.render.RenderDirectionalLightComponent]] = []
        self._textures: dict[tuple[str, str], sapien.render.RenderTexture2D] = {}
        self._fixed: dict[str, sapien.render.RenderMaterial] = {}

    @classmethod
    def of_task(cls, spec_scene: SceneSpec | None, override: str | Mapping | SceneSpec | None,
                randomize: bool = True) -> Scenery | None:
        """The scenery of a task whose spec has ``spec_scene``, or of ``override`` (the env's ``scene=``) when
        given; None: neither (the task's plain look)."""
        chosen = parse_scene(override) if override is not None else spec_scene
        return None if chosen is None else cls(resolve_scene(chosen), randomize)

    # ------------------------------------------------------------------------------------------ building
    def build(self, env, layout: list[Item]) -> None:
        """Structures (collision) and every parallel env's visual actor; called once per scene load, after the
        objects (``layout``: their placement items; a structure may not overlap their start regions)."""
        spec = env.task_spec
        placed = place_structures(self.scene.structures, spec.table)
        self._check_room(placed, spec.robot, layout)
        self.room = self._room_bounds(placed, spec)
        self.structures = {}
        for ps in placed:
            b = env.scene.create_actor_builder()
            for part, pose in zip(ps.definition.parts, ps.part_poses(), strict=True):
                if part.collision:
                    b.add_box_collision(pose, [s / 2 for s in part.size_m])
            b.initial_pose = sapien.Pose()
            self.structures[ps.spec.name] = b.build_static(f"structure_{ps.spec.name}")
        self._materials = []
        if not env.scene.can_render():
            return
        self._fixed = {role: sapien.render.RenderMaterial(base_color=[*rgb, 1.0], roughness=rough, metallic=metal)
                       for role, (rgb, rough, metal) in ROLE_COLORS.items()}
        self._fixed["leg"] = sapien.render.RenderMaterial(base_color=TABLE_LEG_RGBA)
        nominal = draw_appearance(self.scene, 0, randomize=False)
        for i in range(env.num_envs):
            self._materials.append(self._env_materials(nominal))
            self._build_look(env, i, placed)

    def _env_materials(self, a: Appearance) -> dict[str, sapien.render.RenderMaterial]:
        """One env's own materials, starting at the nominal appearance (a textured slot keeps a texture always:
        SAPIEN does not show a texture set again after it was removed)."""
        mats = {"surface": self._textured("material", a.surface), "floor": self._textured("material", a.floor),
                "walls": self._textured("background", a.background),
                "edge": sapien.render.RenderMaterial(base_color=[*mean_color(a.surface), 1.0], roughness=0.6)}
        for name, paint in a.structures.items():
            mats[f"structure/{name}"] = sapien.render.RenderMaterial(base_color=[*PAINTS[paint], 1.0], roughness=0.5)
        return mats

    def _textured(self, kind: str, name: str) -> sapien.render.RenderMaterial:
        mat = sapien.render.RenderMaterial(base_color=[1.0, 1.0, 1.0, 1.0], roughness=0.8)
        mat.base_color_texture = self._texture(kind, name)
        return mat

    def _texture(self, kind: str, name: str) -> sapien.render.RenderTexture2D:
        """The GPU texture of a material or background (uploaded once per Scenery)."""
        key = (kind, name)
        if key not in self._textures:
            img = material_image(name) if kind == "material" else background_image(name)
            levels = int(math.log2(max(img.shape[:2]))) + 1  # a full mip chain: fine patterns stay free of moire
            self._textures[key] = sapien.render.RenderTexture2D(img, "R8G8B8A8Unorm", mipmap_levels=levels, srgb=True)
        return self._textures[key]

    def _build_look(self, env, i: int, placed: list[PlacedStructure]) -> None:
        mats = self._materials[i]
        table = env.task_spec.table
        sx, sy = table.size_m
        floor_z = -table.height_m
        x0, x1, yh = self.room
        b = env.scene.create_actor_builder()
        b.set_scene_idxs([i])
        # ManiSkill's hook for procedural visual meshes (its add_plane_repeated_visual fills the same list)
        shapes = b._procedural_shapes  # noqa: SLF001 (no public way to add a mesh built from arrays)
        shapes.append(_quad((0, 0, 0), (sx / 2, 0, 0), (0, sy / 2, 0), (sx / PERIOD_M, sy / PERIOD_M),
                            mats["surface"]))
        thick = TABLE_THICKNESS_M / 2 - 0.0005  # the textured top sits 1 mm above the box's visual top
        b.add_box_visual(sapien.Pose(p=[0, 0, -0.001 - thick]), [sx / 2, sy / 2, thick], material=mats["edge"])
        for pose in _leg_poses(table):
            b.add_box_visual(pose, [0.03, 0.03, table.height_m / 2], material=self._fixed["leg"])
        shapes.append(_quad(((x0 + x1) / 2, 0, floor_z), ((x1 - x0) / 2, 0, 0), (0, yh, 0),
                            ((x1 - x0) / PERIOD_M, 2 * yh / PERIOD_M), mats["floor"]))
        up = (0, 0, WALL_HEIGHT_M / 2)
        zc = floor_z + WALL_HEIGHT_M / 2
        for center, u in (((x1, 0, zc), (0, -yh, 0)), ((x0, 0, zc), (0, yh, 0)),
                          (((x0 + x1) / 2, yh, zc), ((x1 - x0) / 2, 0, 0)),
                          (((x0 + x1) / 2, -yh, zc), (-(x1 - x0) / 2, 0, 0))):
            shapes.append(_quad(center, u, up, (1.0, 1.0), mats["walls"]))
        for ps in placed:
            for part, pose in zip(ps.definition.parts, ps.part_poses(), strict=True):
                mat = mats[f"structure/{ps.spec.name}"] if part.role == "body" else self._fixed[part.role]
                b.add_box_visual(pose, [s / 2 for s in part.size_m], material=mat)
        b.initial_pose = sapien.Pose()
        b.build_static(f"scenery_{i}")

    def _room_bounds(self, placed: list[PlacedStructure], spec) -> tuple[float, float, float]:
        """(x of the back wall, x of the far wall, half width): around the table, the robot and every structure."""
        sx, sy = spec.table.size_m
        lo = [spec.robot.base_pos_m[0] - ROOM_MARGIN_M, -sx / 2 - ROOM_MARGIN_M]
        hi = [sx / 2 + ROOM_MARGIN_M]
        half = [sy / 2 + ROOM_MARGIN_M, abs(spec.robot.base_pos_m[1]) + ROOM_MARGIN_M]
        for ps in placed:
            a, b = ps.world_bounds()
            lo.append(float(a[0]) - 0.01)
            hi.append(float(b[0]) + 0.01)
            half.append(max(abs(float(a[1])), abs(float(b[1]))) + 0.01)
        return min(ROOM_MIN_M[0], *lo), max(ROOM_MIN_M[1], *hi), max(ROOM_MIN_M[2], *half)

    def _check_room(self, placed: list[PlacedStructure], robot_spec, layout: list[Item]) -> None:
        """TaskSpecError when a structure overlaps the robot's base or an object's start region (its footprint
        grown by its position noise, turned any way when its yaw is randomized)."""
        robot = robot_spec.base_pos_m
        keep_out = [("the robot's base", (robot[0], robot[1]), (ROBOT_BASE_HALF_M, ROBOT_BASE_HALF_M))]
        for item in layout:
            cx, cy = item.pos[0] + item.footprint.offset[0], item.pos[1] + item.footprint.offset[1]
            hx, hy = item.footprint.half
            if item.noise_yaw_rad > 0:
                hx = hy = math.hypot(hx, hy) + math.hypot(*item.footprint.offset)
            keep_out.append((f"object {item.name!r}'s start region", (cx, cy),
                             (hx + item.noise_xy[0], hy + item.noise_xy[1])))
        for ps in placed:
            a, b = ps.world_bounds()
            if b[2] <= 0.0 and ps.spec.on_floor:
                continue  # wholly below the table top
            for what, (cx, cy), (hx, hy) in keep_out:
                if (a[0] < cx + hx + STRUCTURE_GAP_M and b[0] > cx - hx - STRUCTURE_GAP_M
                        and a[1] < cy + hy + STRUCTURE_GAP_M and b[1] > cy - hy - STRUCTURE_GAP_M):
                    raise TaskSpecError(
                        f"scene.structures[{ps.index}] ({ps.spec.kind} {ps.spec.name!r}) covers x "
                        f"{a[0]:.2f}..{b[0]:.2f} m, y {a[1]:.2f}..{b[1]:.2f} m and overlaps {what} (x "
                        f"{cx - hx:.2f}..{cx + hx:.2f}, y {cy - hy:.2f}..{cy + hy:.2f}); move it (pos_m, anchor) or "
                        "leave it out (structures: [] or another style)")

    # ------------------------------------------------------------------------------------------ lights
    def load_lighting(self, env) -> None:
        """The scene's directional lights in every parallel env (ManiSkill's default lights are not added)."""
        nominal = draw_appearance(self.scene, 0, randomize=False)
        ms = env.scene
        subs = ms.sub_scenes[:1] if ms.parallel_in_single_scene else ms.sub_scenes
        self._lights = []
        for sub in subs:
            lights = []
            for k, drawn in enumerate(nominal.lights):
                entity = sapien.Entity()
                entity.name = f"scenery_light_{k}"
                light = sapien.render.RenderDirectionalLightComponent()
                entity.add_component(light)
                light.color = list(drawn.rgb)
                light.shadow = bool(env.enable_shadow and k == 0)  # as ManiSkill's default: the first light only
                light.shadow_near, light.shadow_far = -10.0, 10.0
                light.shadow_half_size, light.shadow_map_size = 5.0, 2048
                light.pose = sapien.Pose([0, 0, 0], sapien.math.shortest_rotation([1, 0, 0], list(drawn.direction)))
                sub.add_entity(entity)
                lights.append(light)
            self._lights.append(lights)
            sub.render_system.ambient_light = [nominal.ambient] * 3

    # ------------------------------------------------------------------------------------------ episodes
    def apply(self, env, env_idx: torch.Tensor, episode_seeds) -> None:
        """Draw and show the appearance of each env in ``env_idx`` from its episode seed (``episode_seeds`` [num_envs],
        ManiSkill's ``_episode_seed``)."""
        seeds = np.asarray(episode_seeds).reshape(-1)
        render = env.scene.can_render()
        cameras = self._cameras(env) if render else {}
        # one draw per env being reset: SAPIEN materials, lights and cameras have no batched setters
        for i in env_idx.tolist():
            a = draw_appearance(self.scene, int(seeds[i] if len(seeds) > i else seeds[0]), tuple(cameras),
                                self.randomize)
            self.drawn[i] = a
            if render:
                self._paint(i, a)
                self._light(env, i, a)
                self._aim(cameras, i, a)

    def appearance(self, num_envs: int) -> list[dict]:
        """Each env's current appearance as a JSON-able dict (empty before the first reset)."""
        return [self.drawn[i].to_dict() if i in self.drawn else {} for i in range(num_envs)]

    def _paint(self, i: int, a: Appearance) -> None:
        if i >= len(self._materials):
            return
        mats = self._materials[i]
        for slot, kind, name in (("surface", "material", a.surface), ("floor", "material", a.floor),
                                 ("walls", "background", a.background)):
            mats[slot].base_color_texture = self._texture(kind, name)
            if kind == "material":
                mats[slot].roughness, mats[slot].metallic = MATERIALS[name].roughness, MATERIALS[name].metallic
        mats["edge"].base_color = [*mean_color(a.surface), 1.0]
        for name, paint in a.structures.items():
            mats[f"structure/{name}"].base_color = [*PAINTS[paint], 1.0]

    def _light(self, env, i: int, a: Appearance) -> None:
        if i >= len(self._lights):
            return
        for light, drawn in zip(self._lights[i], a.lights, strict=True):
            light.color = list(drawn.rgb)
            light.pose = sapien.Pose([0, 0, 0], sapien.math.shortest_rotation([1, 0, 0], list(drawn.direction)))
        env.scene.sub_scenes[i].render_system.ambient_light = [a.ambient] * 3

    @staticmethod
    def _cameras(env) -> dict[str, list]:
        """Camera name -> the ManiSkill cameras of that name (a view's sensor and its human-render twin)."""
        out: dict[str, list] = {}
        for group in (env.scene.sensors, env.scene.human_render_cameras):
            for name, cam in group.items():
                if hasattr(cam, "camera") and hasattr(cam.config, "pose"):
                    out.setdefault(name, []).append(cam)
        return out

    @staticmethod
    def _aim(cameras: dict[str, list], i: int, a: Appearance) -> None:
        for name, cams in cameras.items():
            jitter = a.cameras[name]
            for cam in cams:
                nominal = Pose.create(cam.config.pose).sp
                turn = sapien.Pose()
                turn.set_rpy(np.radians(jitter.rotation_deg))
                pose = sapien.Pose(p=nominal.p + np.asarray(jitter.offset_m, dtype=np.float32), q=nominal.q) * turn
                rc = cam.camera
                # ManiSkill's RenderCamera wraps one SAPIEN camera per env and sets them all at once only
                per_env = rc._render_cameras  # noqa: SLF001 (no public per-env pose setter)
                if i < len(per_env):
                    per_env[i].set_local_pose(pose)
                # its cached poses and matrices are stale now (ManiSkill clears them only in set_local_pose)
                rc._cached_local_pose = None  # noqa: SLF001
                rc._cached_model_matrix = None  # noqa: SLF001
                rc._cached_extrinsic_matrix = None  # noqa: SLF001
