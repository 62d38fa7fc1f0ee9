"""An episode's appearance is a function of its seed alone, drawn from the scene's choices and ranges through its own
random streams; with randomization off it is the nominal one whatever the seed."""

import json
import math

import numpy as np
import pytest
import torch

from gendex_envs.appearance import draw_appearance, kelvin_to_rgb
from gendex_envs.scene_spec import SceneSpec, parse_scene, resolve_scene

KITCHEN = resolve_scene(SceneSpec(style="kitchen"))
CAMERAS = ("left_overhead", "right_overhead", "top_down", "hand_camera")


def test_the_same_seed_draws_the_same_appearance_and_seeds_vary_it():
    draws = [draw_appearance(KITCHEN, s, CAMERAS) for s in range(40)]
    assert draws[7] == draw_appearance(KITCHEN, 7, CAMERAS)
    assert len({d.surface for d in draws}) == len(KITCHEN.surface.materials)  # 40 draws reach all 8 surfaces
    assert len({d.background for d in draws}) == len(KITCHEN.background.images)
    assert len({round(d.ambient, 6) for d in draws}) == 40


def test_every_draw_lies_within_its_declared_choices_and_ranges():
    for s in range(50):
        a = draw_appearance(KITCHEN, s, CAMERAS)
        assert a.surface in KITCHEN.surface.materials and a.floor in KITCHEN.floor.materials
        assert a.background in KITCHEN.background.images
        assert KITCHEN.lighting.ambient[0] <= a.ambient <= KITCHEN.lighting.ambient[1]
        for light, spec in zip(a.lights, KITCHEN.lighting.lights, strict=True):
            lo, hi = spec.intensity
            assert lo <= light.intensity <= hi
            assert spec.color_temperature_k[0] <= light.color_temperature_k <= spec.color_temperature_k[1]
            nominal = np.asarray(spec.direction) / np.linalg.norm(spec.direction)
            angle = math.degrees(math.acos(min(1.0, float(np.dot(nominal, light.direction)))))
            assert angle <= spec.direction_jitter_deg + 1e-6 and light.direction[2] < 0
        for cam in a.cameras.values():
            assert max(map(abs, cam.offset_m)) <= KITCHEN.camera_jitter.position_m
            assert max(map(abs, cam.rotation_deg)) <= KITCHEN.camera_jitter.rotation_deg
        for s_spec in KITCHEN.structures:
            assert a.structures[s_spec.name]  # every structure gets a paint


def test_randomization_off_is_the_nominal_look_whatever_the_seed():
    nominal = [draw_appearance(KITCHEN, s, CAMERAS, randomize=False) for s in (0, 1, 12345)]
    first = nominal[0]
    assert all(n.surface == first.surface and n.lights == first.lights and n.cameras == first.cameras
               for n in nominal)
    assert first.surface == KITCHEN.surface.materials[0] and first.background == KITCHEN.background.images[0]
    assert first.ambient == pytest.approx(sum(KITCHEN.lighting.ambient) / 2)
    assert all(c.offset_m == (0.0, 0.0, 0.0) and c.rotation_deg == (0.0, 0.0, 0.0) for c in first.cameras.values())


def test_each_field_has_its_own_stream():
    """Another camera, or a structure more, leaves every other field's draw as it was."""
    a = draw_appearance(KITCHEN, 3, CAMERAS[:3])
    b = draw_appearance(KITCHEN, 3, CAMERAS)
    assert (a.surface, a.floor, a.background, a.ambient, a.lights) == (b.surface, b.floor, b.background, b.ambient,
                                                                        b.lights)
    assert a.cameras["top_down"] == b.cameras["top_down"]
    fewer = resolve_scene(parse_scene({"style": "kitchen", "structures": []}))
    c = draw_appearance(fewer, 3, CAMERAS)
    assert (c.surface, c.lights, c.cameras) == (b.surface, b.lights, b.cameras) and c.structures == {}


def test_drawing_touches_no_other_random_generator():
    np.random.seed(5)
    torch.manual_seed(5)
    np_state, torch_state = np.random.get_state()[1].copy(), torch.get_rng_state().clone()
    for s in range(20):
        draw_appearance(KITCHEN, s, CAMERAS)
    assert np.array_equal(np.random.get_state()[1], np_state) and torch.equal(torch.get_rng_state(), torch_state)


def test_the_record_is_json_and_names_what_was_drawn():
    a = draw_appearance(KITCHEN, 11, CAMERAS)
    record = json.loads(json.dumps(a.to_dict()))
    assert record["style"] == "kitchen" and record["seed"] == 11 and record["randomized"] is True
    assert record["surface"] == a.surface and set(record["cameras"]) == set(CAMERAS)
    assert len(record["lights"]) == 2 and set(record["structures"]) == {s.name for s in KITCHEN.structures}


def test_colour_temperature_runs_from_warm_to_cool():
    warm, white, cool = kelvin_to_rgb(2700), kelvin_to_rgb(6500), kelvin_to_rgb(11000)
    assert warm[0] == 1.0 and warm[2] < 0.6  # candle-ish: red full, blue low
    assert min(white) > 0.95
    assert cool[2] == 1.0 and cool[0] < 0.85
