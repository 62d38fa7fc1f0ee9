"""Named scene styles: bundles of surface, floor, background, lighting, camera jitter and structures, so a task
writes ``scene: {style: kitchen}`` and overrides only what it wants (:mod:`gendex_envs.scene_spec`).

Structures stand beside the table (anchored to its left or right edge, on the floor, against the side walls), where
the two side views see them behind the table and the arm, reaching over the table, does not; none stands on the
table top. An env refuses a structure that overlaps an object's start region or the robot's base
(:mod:`gendex_envs.scene`).
"""

from __future__ import annotations

from gendex_envs.scene_spec import (
    BackgroundSpec,
    CameraJitterSpec,
    FloorSpec,
    LightingSpec,
    LightSpec,
    SceneSpec,
    StructureSpec,
    SurfaceSpec,
)

DEFAULT_STYLE = "plain"
"""The style of a scene that names none: fills the sections it leaves out."""

_JITTER = CameraJitterSpec(position_m=0.01, rotation_deg=1.5)


def _light(direction: tuple[float, float, float], jitter: float, intensity: tuple[float, float],
           kelvin: tuple[float, float]) -> LightSpec:
    return LightSpec(direction=direction, direction_jitter_deg=jitter, intensity=intensity,
                     color_temperature_k=kelvin)


def _side(name: str, kind: str, side: str, along_m: float, out_m: float, z_m: float = 0.0, on_floor: bool = True,
          colors: tuple[str, ...] | None = None) -> StructureSpec:
    """A structure beside the table: ``along_m`` along x, ``out_m`` out from the left (+y) or right (-y) edge, facing
    the table."""
    left = side == "left"
    return StructureSpec(name=name, kind=kind, pos_m=(along_m, out_m if left else -out_m, z_m),
                         yaw_deg=90.0 if left else -90.0, anchor="left_edge" if left else "right_edge",
                         on_floor=on_floor, colors=colors)


STYLES: dict[str, SceneSpec] = {
    "plain": SceneSpec(
        surface=SurfaceSpec(materials=("laminate_beige",)), floor=FloorSpec(materials=("concrete",)),
        background=BackgroundSpec(images=("studio_cool",)), lighting=LightingSpec(),
        camera_jitter=CameraJitterSpec(), structures=()),
    "kitchen": SceneSpec(
        surface=SurfaceSpec(materials=("butcher_block", "oak", "maple", "marble_white", "marble_black", "granite",
                                       "laminate_white", "tile_white")),
        floor=FloorSpec(materials=("tile_checker", "tile_terracotta", "floor_planks", "linoleum", "terrazzo")),
        background=BackgroundSpec(images=("kitchen_subway_white", "kitchen_subway_sage", "kitchen_window",
                                          "kitchen_garden_window", "kitchen_open_shelves")),
        lighting=LightingSpec(ambient=(0.25, 0.4), lights=(_light((0.5, -1.0, -1.0), 20.0, (0.8, 1.3), (3500, 6000)),
                                                            _light((0.0, 0.0, -1.0), 10.0, (0.5, 0.9), (4000, 6500)))),
        camera_jitter=_JITTER,
        structures=(_side("sink", "sink", "right", 0.2, 0.66), _side("counter", "counter", "left", 0.2, 0.66),
                    _side("dish_rack", "dish_rack", "left", 0.35, 0.62, z_m=0.9),
                    _side("wall_cabinet", "wall_cabinet", "right", 0.2, 0.83, z_m=0.55, on_floor=False))),
    "lab": SceneSpec(
        surface=SurfaceSpec(materials=("epoxy_black", "laminate_white", "laminate_grey", "stainless_steel",
                                       "laminate_blue")),
        floor=FloorSpec(materials=("linoleum", "painted_floor", "tile_white", "terrazzo")),
        background=BackgroundSpec(images=("lab_panels", "lab_whiteboard", "lab_fume_hoods", "lab_blue_cabinets")),
        lighting=LightingSpec(ambient=(0.3, 0.45), lights=(_light((0.2, 0.1, -1.0), 10.0, (0.9, 1.3), (5000, 7500)),
                                                            _light((-0.5, 0.8, -1.0), 15.0, (0.3, 0.6), (5500, 7000)))),
        camera_jitter=_JITTER,
        structures=(_side("fume_hood", "fume_hood", "right", 0.35, 0.8), _side("shelf", "shelf", "left", 0.3, 0.55),
                    _side("filing_cabinet", "filing_cabinet", "left", -0.45, 0.6))),
    "office": SceneSpec(
        surface=SurfaceSpec(materials=("laminate_white", "laminate_grey", "laminate_beige", "oak", "walnut", "maple",
                                       "cork")),
        floor=FloorSpec(materials=("carpet_grey", "carpet_blue", "floor_planks", "linoleum")),
        background=BackgroundSpec(images=("office_picture", "office_blinds", "office_bookshelf", "office_partition",
                                          "office_glass")),
        lighting=LightingSpec(ambient=(0.3, 0.45), lights=(_light((0.3, -0.6, -1.0), 15.0, (0.7, 1.1), (4000, 6000)),
                                                            _light((0.0, 0.0, -1.0), 5.0, (0.5, 0.8), (3500, 5000)))),
        camera_jitter=_JITTER,
        structures=(_side("filing_cabinet", "filing_cabinet", "right", 0.4, 0.55),
                    _side("shelf", "shelf", "left", 0.3, 0.55),
                    _side("upper_shelf", "upper_shelf", "left", 0.3, 0.86, z_m=0.25, on_floor=False))),
    "workshop": SceneSpec(
        surface=SurfaceSpec(materials=("butcher_block", "rubber_mat", "cutting_mat", "zinc_sheet", "pine",
                                       "aluminium_tread")),
        floor=FloorSpec(materials=("concrete", "painted_floor", "aluminium_tread", "grey_planks")),
        background=BackgroundSpec(images=("workshop_pegboard", "workshop_brick", "workshop_block",
                                          "workshop_corrugated")),
        lighting=LightingSpec(ambient=(0.2, 0.35), lights=(_light((0.4, 0.8, -1.0), 25.0, (0.9, 1.5), (3000, 5500)),
                                                            _light((0.0, 0.0, -1.0), 10.0, (0.4, 0.8), (4000, 6500)))),
        camera_jitter=_JITTER,
        structures=(_side("tool_chest", "tool_chest", "right", 0.4, 0.6),
                    _side("pegboard", "pegboard", "left", 0.3, 0.99, z_m=0.05, on_floor=False),
                    _side("cutting_station", "cutting_station", "right", 0.4, 0.6, z_m=0.9))),
    "dining": SceneSpec(
        surface=SurfaceSpec(materials=("linen", "gingham_red", "gingham_blue", "walnut", "cherry", "oak",
                                       "marble_white")),
        floor=FloorSpec(materials=("floor_planks", "terrazzo", "tile_terracotta", "carpet_grey")),
        background=BackgroundSpec(images=("dining_stripes", "dining_wainscot", "dining_garden_window",
                                          "plaster_white")),
        lighting=LightingSpec(ambient=(0.25, 0.4), lights=(_light((0.6, -0.8, -1.0), 20.0, (0.8, 1.3), (2700, 4500)),
                                                            _light((0.0, 0.0, -1.0), 10.0, (0.4, 0.8), (2700, 4000)))),
        camera_jitter=_JITTER,
        structures=(_side("sideboard", "counter", "left", 0.3, 0.66, colors=("walnut_tone", "oak_tone", "white")),
                    _side("window", "window_frame", "right", 0.2, 0.97, z_m=0.05, on_floor=False))),
    "studio": SceneSpec(
        surface=SurfaceSpec(materials=("laminate_white", "laminate_grey", "laminate_green", "laminate_blue",
                                       "felt_green", "concrete", "marble_green")),
        floor=FloorSpec(materials=("concrete", "painted_floor", "grey_planks")),
        background=BackgroundSpec(images=("studio_warm", "studio_cool", "plaster_white", "classroom_chalkboard",
                                          "city_night_window")),
        lighting=LightingSpec(ambient=(0.2, 0.5), lights=(_light((1.0, 1.0, -1.0), 30.0, (0.7, 1.4), (3000, 8000)),
                                                           _light((-0.6, -0.8, -1.0), 30.0, (0.2, 0.7), (4000, 9000)))),
        camera_jitter=_JITTER, structures=()),
}
"""Every scene style by name; each fills every section."""
