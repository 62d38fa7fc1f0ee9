"""The ``scene`` section of a task spec: styles fill what a task leaves out, every field is bounded, and a bad value
is a TaskSpecError naming the field and what is allowed."""

import copy
import re
from pathlib import Path

import pytest
import yaml

from gendex_envs.errors import TaskSpecError
from gendex_envs.scene_spec import (
    MAX_CHOICES,
    SECTIONS,
    SceneSpec,
    SurfaceSpec,
    parse_scene,
    resolve_scene,
    scene_problems,
)
from gendex_envs.scene_styles import DEFAULT_STYLE, STYLES
from gendex_envs.spec import dump_task_spec, parse_task_spec, spec_to_dict

TASK = yaml.safe_load("""
name: PickApple
instruction: Pick up the apple.
objects:
  - {name: apple, asset: apple, pos_m: [0.1, 0.0, 0.0]}
stages:
  - {name: grasp, instruction: Grasp it., skill: grasp, method: RL, control_joint: hand, target: apple}
success:
  description: Lifted.
  conditions: [{type: lifted, object: apple, min_height_m: 0.1}]
""")


def _with_scene(scene) -> dict:
    raw = copy.deepcopy(TASK)
    raw["scene"] = scene
    return raw


def test_a_task_without_a_scene_keeps_its_yaml_as_it_was():
    spec = parse_task_spec(TASK)
    assert spec.scene is None and "scene" not in dump_task_spec(spec)


def test_every_style_is_valid_and_fills_every_section():
    assert DEFAULT_STYLE in STYLES and len(set(STYLES) - {"plain"}) >= 5
    for name, style in STYLES.items():
        assert scene_problems(style, f"STYLES[{name}]") == []
        assert all(getattr(style, s) is not None for s in SECTIONS), name
        resolved = resolve_scene(SceneSpec(style=name))
        assert resolved.style == name and resolved.surface == style.surface


def test_a_section_given_replaces_the_styles_and_the_rest_comes_from_it():
    spec = parse_task_spec(_with_scene({"style": "kitchen", "surface": {"materials": ["walnut", "oak"]},
                                        "structures": []}))
    resolved = resolve_scene(spec.scene)
    assert resolved.surface.materials == ("walnut", "oak") and resolved.structures == ()
    assert resolved.background == STYLES["kitchen"].background
    plain = resolve_scene(SceneSpec(floor=STYLES["lab"].floor))  # no style: the plain one fills the rest
    assert plain.style == DEFAULT_STYLE and plain.floor == STYLES["lab"].floor
    assert plain.surface == STYLES[DEFAULT_STYLE].surface


def test_a_scene_round_trips_through_yaml():
    raw = _with_scene({"style": "office", "lighting": {"ambient": [0.2, 0.4], "lights": [
        {"direction": [0.0, 1.0, -1.0], "direction_jitter_deg": 10, "intensity": [0.5, 1.5],
         "color_temperature_k": [3000, 6000]}]},
        "structures": [{"name": "cab", "kind": "counter", "pos_m": [0.3, 0.66, 0.0], "yaw_deg": 90,
                        "anchor": "left_edge", "on_floor": True, "colors": ["sage"]}]})
    spec = parse_task_spec(raw)
    assert parse_task_spec(yaml.safe_load(dump_task_spec(spec))) == spec
    assert spec_to_dict(spec)["scene"]["structures"][0]["kind"] == "counter"


@pytest.mark.parametrize("scene, message", [
    ({"style": "kitchn"}, r"scene.style = 'kitchn' is not a scene style; allowed: .*Did you mean: 'kitchen'"),
    ({"surface": {"materials": ["marbel_white"]}},
     r"scene.surface.materials\[0\] = 'marbel_white' is not a known material. Did you mean: 'marble_white'"),
    ({"surface": {"materials": []}}, r"scene.surface.materials = \[\] is not allowed; give at least one material"),
    ({"floor": {"materials": ["oak", "oak"]}}, r"scene.floor.materials = \['oak', 'oak'\].*each material at most"),
    ({"background": {"images": ["kitchen"]}}, r"scene.background.images\[0\] = 'kitchen' is not a known background"),
    ({"lighting": {"ambient": [0.6, 0.2]}},
     r"scene.lighting.ambient = \[0.6, 0.2\] is not allowed; a range \[lo, hi\] with 0.0 <= lo <= hi <= 1.0"),
    ({"lighting": {"lights": [{"direction": [0, 0, 1]}]}},
     r"scene.lighting.lights\[0\].direction = \[0.0, 0.0, 1.0\] is not allowed; .*pointing down"),
    ({"lighting": {"lights": [{"direction": [0, 0, -1], "intensity": [1, 9]}]}},
     r"lights\[0\].intensity = \[1.0, 9.0\] is not allowed; a range \[lo, hi\] with 0.0 <= lo <= hi <= 5.0"),
    ({"lighting": {"lights": [{"direction": [0, 0, -1], "color_temperature_k": [500, 6500]}]}},
     r"color_temperature_k = \[500.0, 6500.0\] is not allowed; .*1500.0 <= lo <= hi <= 12000.0 K"),
    ({"lighting": {"lights": [{"direction": [0, 0, -1], "direction_jitter_deg": 90}]}},
     r"direction_jitter_deg = 90.0 is not allowed; 0 <= jitter <= 45.0 degrees"),
    ({"lighting": {"lights": []}}, r"scene.lighting.lights = \[\] is not allowed; give 1 to 4 lights"),
    ({"lighting": {"lights": [{"direction": [0, 0, -1]}] * 5}}, r"scene.lighting.lights: 5 lights; at most 4"),
    ({"camera_jitter": {"position_m": 0.5}}, r"scene.camera_jitter.position_m = 0.5 is not allowed; 0 <= position_m"),
    ({"camera_jitter": {"rotation_deg": -1}}, r"scene.camera_jitter.rotation_deg = -1.0 is not allowed"),
    ({"structures": [{"name": "s", "kind": "shelve", "pos_m": [0, 0, 0]}]},
     r"scene.structures\[0\].kind = 'shelve' is not a known structure; .*Did you mean: 'shelf'"),
    ({"structures": [{"name": "apple", "kind": "shelf", "pos_m": [0, 0, 0]}]},
     r"scene.structures\[0\].name = 'apple' is not allowed; an object has this name"),
    ({"structures": [{"name": "a", "kind": "shelf", "pos_m": [0, 0, 0]},
                     {"name": "a", "kind": "sink", "pos_m": [1, 0, 0]}]}, r"structures\[1\].name = 'a'.*duplicate"),
    ({"structures": [{"name": "a", "kind": "shelf", "pos_m": [0, 99, 0]}]},
     r"structures\[0\].pos_m = \[0.0, 99.0, 0.0\] is not allowed; each coordinate must be within \+/-20.0 m"),
    ({"structures": [{"name": "a", "kind": "shelf", "pos_m": [0, 0, 0], "anchor": "ceiling"}]},
     r"anchor = 'ceiling' is not allowed; allowed values: 'table', 'far_edge', 'left_edge', 'right_edge'"),
    ({"structures": [{"name": "a", "kind": "shelf", "pos_m": [0, 0, 0], "colors": ["mauve"]}]},
     r"structures\[0\].colors\[0\] = 'mauve' is not a known paint"),
    ({"lighting": {"ambient": [0.1, float("nan")]}}, r"scene.lighting.ambient\[1\] = nan is not allowed; must be a"),
    ({"surface": {"materials": ["oak"] * (MAX_CHOICES + 1)}}, rf"{MAX_CHOICES + 1} materials; at most {MAX_CHOICES}"),
    ({"surfaces": {"materials": ["oak"]}}, r"scene: unknown key 'surfaces'. Did you mean: 'surface'"),
    ({"surface": {"materials": "oak"}}, r"scene.surface.materials = 'oak' has the wrong type \(str\); expected a list"),
])
def test_bad_scenes_are_refused_naming_the_field(scene, message):
    with pytest.raises(TaskSpecError, match=message):
        parse_task_spec(_with_scene(scene))


def test_the_env_argument_takes_a_style_a_mapping_or_a_spec():
    assert parse_scene("lab") == SceneSpec(style="lab")
    assert parse_scene({"style": "lab", "structures": []}).structures == ()
    spec = SceneSpec(surface=SurfaceSpec(materials=("oak",)))
    assert parse_scene(spec) is spec
    with pytest.raises(TaskSpecError, match=r"scene=: scene.style = 'garage' is not a scene style"):
        parse_scene("garage")
    with pytest.raises(TaskSpecError, match=r"a scene is a style name, a mapping or a SceneSpec; got 3 \(int\)"):
        parse_scene(3)


def test_the_docs_scene_example_is_valid():
    doc = (Path(__file__).parents[2] / "docs" / "scenes.md").read_text()
    block = re.search(r"```yaml\n(.*?)```", doc, re.S)
    assert block is not None
    resolved = resolve_scene(parse_scene(yaml.safe_load(block.group(1))["scene"], source="docs/scenes.md"))
    assert resolved.style == "kitchen" and resolved.structures == ()
    assert resolved.surface.materials == ("marble_white", "butcher_block")
