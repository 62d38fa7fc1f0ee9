"""Named colours: the palette, reading a colour off an rgba, and ``objects[i].color`` in the spec."""

from __future__ import annotations

import copy
import itertools

import pytest

from gendex_envs.attributes import COLOR_NAMES, COLOR_WORDS, COLORS, color_name
from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import parse_task_spec


def test_the_palette_colours_are_far_apart_and_read_back_as_themselves():
    for a, b in itertools.combinations(COLOR_NAMES, 2):
        gap = max(abs(x - y) for x, y in zip(COLORS[a][:3], COLORS[b][:3], strict=True))
        assert gap >= 0.3, (a, b, gap)
    assert all(color_name(COLORS[c]) == c for c in COLOR_NAMES)
    assert all(w in COLOR_WORDS and COLOR_WORDS[w] == w for w in COLOR_NAMES)
    assert COLOR_WORDS["gray"] == "grey"


@pytest.mark.parametrize("rgba, name", [((0.9, 0.2, 0.15, 1.0), "red"), ((0.2, 0.2, 0.75, 1.0), "blue"),
                                        ((0.95, 0.95, 0.9, 1.0), "white"), ((0.6, 0.4, 0.2, 1.0), "brown")])
def test_an_rgba_reads_as_its_nearest_named_colour(rgba, name):
    assert color_name(rgba) == name


RAW = {"name": "LiftRedBlock", "instruction": "pick up the red block",
       "objects": [{"name": "block", "asset": "block_small", "pos_m": [0.1, 0.0, 0.0], "color": "red"}],
       "stages": [{"name": "reach", "instruction": "reach", "skill": "reach", "method": "motion_planning",
                   "control_joint": "arm", "target": "block"}],
       "success": {"description": "lifted", "conditions": [{"type": "lifted", "object": "block",
                                                            "min_height_m": 0.1}]}}


def test_a_named_colour_is_the_objects_paint():
    spec = parse_task_spec(RAW)
    assert spec.objects[0].color == "red" and spec.objects[0].rgba == COLORS["red"]
    plain = copy.deepcopy(RAW)
    del plain["objects"][0]["color"]
    assert parse_task_spec(plain).objects[0].rgba is None  # the asset's own colour


def test_a_colour_outside_the_palette_or_two_colours_are_refused():
    raw = copy.deepcopy(RAW)
    raw["objects"][0]["color"] = "rde"
    with pytest.raises(TaskSpecError, match=r"objects\[0\].color.*'red'"):
        parse_task_spec(raw)
    raw["objects"][0].update(color="red", color_rgba=[0.1, 0.2, 0.3, 1.0])
    with pytest.raises(TaskSpecError, match=r"give color \('red'\) or color_rgba, not both"):
        parse_task_spec(raw)
