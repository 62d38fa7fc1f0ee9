"""The offline author sets every scene it lays out in a place (generator.backends.offline_style): a batch spans the
styles, never one whose structures the critic rejects, and the style draws nothing from the layout's generator."""

from __future__ import annotations

import dataclasses

import numpy as np
import yaml

from generator.backends.base import ModelRequest
from generator.backends.offline import OfflineBackend
from generator.backends.offline_scene import scene_spec
from generator.backends.offline_style import FALLBACK_STYLE, STYLE_ROTATION, style_for
from generator.catalog_view import asset_dicts
from generator.critic.physical import check_scene_static
from generator.steps.propose import propose
from generator.steps.scene import adjust_sizes, parse_scene


def _batch(seed: int, n: int):
    b = OfflineBackend(seed=seed)
    existing: tuple[str, ...] = ()
    for i in range(n):
        p, _ = propose(b, index=i, existing=existing)
        existing += (p.name,)
        ids = {o.asset for o in p.objects}
        context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
                   "candidate_index": 0, "index": i, "attempt": 0}
        yield p, context, b.complete(ModelRequest(step="scene", prompt="", context=context)).text


def test_a_batch_of_twenty_spans_at_least_five_styles_each_leaving_the_arm_room():
    styles = []
    for p, _, text in _batch(3, 20):
        spec = adjust_sizes(parse_scene(text, p), p)
        assert spec.scene is not None and spec.scene.structures is None  # the style's own structures
        assert not check_scene_static(spec).by_check("structure_room"), spec.name
        styles.append(spec.scene.style)
    assert len(set(styles)) >= 5 and set(styles) <= set(STYLE_ROTATION)
    assert text.rstrip("`\n").endswith(f"scene: {{style: {styles[-1]}}}")  # the last line of the file


def test_the_style_leaves_the_layout_as_it_was():
    """Two styles of one proposal drawn with the same generator: the same file but for the scene line; the style is
    the same for every candidate of a task and moves on with the task index."""
    p, context, _ = next(_batch(0, 1))
    assets = {a["id"]: a for a in context["assets"]}
    a = yaml.safe_load(scene_spec(context["proposal"], assets, np.random.default_rng(5), (0, 0)).strip("`yaml\n"))
    b = yaml.safe_load(scene_spec(context["proposal"], assets, np.random.default_rng(5), (0, 1)).strip("`yaml\n"))
    assert a.pop("scene") == {"style": STYLE_ROTATION[0]} and b.pop("scene") == {"style": STYLE_ROTATION[1]}
    assert a == b
    again = scene_spec(context["proposal"], assets, np.random.default_rng(9), (0, 0))
    assert f"style: {STYLE_ROTATION[0]}" in again


def test_a_style_whose_structures_block_the_layout_is_passed_over():
    """An apple laid out off the table's left edge, against the kitchen's counter: the kitchen is passed over for the
    next style of the rotation, whose structures leave the apple room."""
    spec = {"name": "LiftApple", "instruction": "Lift the apple.",
            "objects": [{"name": "apple", "asset": "apple", "pos_m": [0.2, 0.9, 0.0],
                         "randomize": {"xy_m": [0.0, 0.0], "yaw_deg": 0.0}}],
            "stages": [{"name": "grasp_apple", "instruction": "Grasp it.", "skill": "grasp", "method": "RL",
                        "control_joint": "hand", "target": "apple"}],
            "success": {"description": "Lifted.", "conditions": [{"type": "lifted", "object": "apple",
                                                                 "min_height_m": 0.1}]}}
    kitchen = STYLE_ROTATION.index("kitchen")
    assert style_for(spec, 0, kitchen) == STYLE_ROTATION[kitchen + 1]
    assert style_for({**spec, "objects": [{**spec["objects"][0], "pos_m": [0.2, 0.3, 0.0]}]}, 0, kitchen) == "kitchen"
    assert style_for({**spec, "objects": [{"name": "apple", "asset": "no_such_asset", "pos_m": [0, 0, 0]}]},
                     0, kitchen) == FALLBACK_STYLE  # a layout that does not parse gets a style without structures
