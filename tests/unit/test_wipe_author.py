"""The wipe skill in the generator: the reader (sponge and spill in either order, a spill named alone), the offline
author's task (pick up the sponge, carry it over the spill, wipe it: 90 % of its marks), the scene (the spill fixed
where the arm reaches round it), the critic's check that the sponge starts clear of the spill, the stage goal, the
reward module, and the skill statistics."""

from __future__ import annotations

import dataclasses

import pytest

from gendex_envs.spec import parse_task_spec, spec_to_dict
from generator.backends.dexterous import WIPE_FRACTION
from generator.backends.offline import OfflineBackend
from generator.backends.offline_scene import SPILL_RANDOMIZE, SPILL_REGION_M, WIPE_RANDOMIZE
from generator.catalog_view import asset_dicts
from generator.critic.directives import apply_directives
from generator.critic.physical import check_scene_static
from generator.critic.skill_checks import WIPE_APART_M
from generator.instruction import read_instruction
from generator.phrasing import split
from generator.reward_library import compose_stage_module, compose_task_module, roles_of
from generator.stage_goals import stage_goal
from generator.stats import condition_skill
from generator.steps.validate import check_reward_source


@pytest.mark.parametrize("text, spill", [
    ("wipe the spill with the sponge", "spill_long"),
    ("scrub the square stain with the thick sponge", "spill_square"),
    ("use the sponge to wipe up the coffee spill", "spill_round"),
    ("mop up the mess", "spill_long"),
])
def test_a_wipe_reads_with_the_sponge_and_the_spill_in_either_order(text, spill):
    r = read_instruction(text, asset_dicts())
    assert r.skill == "wipe"
    assert sorted(m.asset for m in r.objects) == sorted(["sponge_block", spill]), r.objects


@pytest.mark.parametrize("text, skill", [("pick up the sponge", "lift"), ("put the sponge in the bowl", "put_in")])
def test_a_sponge_picked_up_or_put_away_keeps_its_skill(text, skill):
    assert read_instruction(text, asset_dicts()).skill == skill


@pytest.mark.parametrize("text, spill", [("wipe the coffee spill with the sponge", "spill_round"),
                                         ("wipe the square spill", "spill_square"),
                                         ("clean up the long stain with the sponge", "spill_long")])
def test_a_wipe_carries_the_sponge_over_the_spill_and_wipes_nine_tenths_of_its_marks(text, spill, guided):
    p, spec = guided(text)
    found = check_scene_static(spec).violations  # a sponge drawn on the spill is moved off it, as refinement does
    spec = apply_directives(spec, [d for v in found if v.check == "wipe" for d in v.fix])
    assert [o.asset for o in p.objects] == ["sponge_block", spill]
    assert [s.skill for s in p.steps] == ["reach", "grasp", "carry", "wipe"]
    assert read_instruction(split(p.description)[1], asset_dicts()).skill == "wipe"
    sponge, area = spec.object("sponge"), spec.object("spill")
    assert area.fixed and not sponge.fixed
    (x0, x1), (y0, y1) = SPILL_REGION_M
    assert x0 <= area.pos_m[0] <= x1 and y0 <= area.pos_m[1] <= y1
    assert list(area.randomize.xy_m) == SPILL_RANDOMIZE["xy_m"] and area.randomize.yaw_deg == SPILL_RANDOMIZE["yaw_deg"]
    assert list(sponge.randomize.xy_m) == WIPE_RANDOMIZE["xy_m"]
    [cond] = spec.success.conditions
    assert (cond.type, cond.object, cond.target, cond.min_fraction) == ("wiped", "sponge", "spill", WIPE_FRACTION)
    wipe = spec.stages[-1]
    assert wipe.skill == "wipe" and wipe.target == "spill"
    assert check_scene_static(spec).ok
    raw, roles = spec_to_dict(spec), roles_of(dataclasses.asdict(p))
    check_reward_source(compose_task_module(raw, roles))
    stage_src = compose_stage_module(raw, wipe.name, roles)
    check_reward_source(stage_src)
    assert "wiped_share('sponge', 'spill')" in stage_src


def test_the_critic_moves_a_sponge_that_starts_on_its_spill_clear_of_it(guided):
    """A sponge on the spill is half way there: the ``wipe`` check measures the gap between the footprints widened by
    their randomization, and its fix moves the sponge until the gap is WIPE_APART_M."""
    _, spec = guided("wipe the square spill with the sponge")
    raw = spec_to_dict(spec)
    area = spec.object("spill")
    for dy in (0.0, 0.1, -0.14):
        raw["objects"][0]["pos_m"] = [area.pos_m[0], area.pos_m[1] + dy, 0.0]
        near = parse_task_spec(raw)
        found = [v for v in check_scene_static(near).violations if v.check == "wipe"]
        assert len(found) == 1 and found[0].object == "sponge" and found[0].measured < WIPE_APART_M, dy
        after = check_scene_static(apply_directives(near, list(found[0].fix)))
        assert not [v for v in after.violations if v.check == "wipe"], (dy, after.summary())


def test_the_grammar_writes_a_wipe_of_every_spill_and_stats_and_stage_goals_know_it():
    from generator.steps.propose import propose

    b, existing, out = OfflineBackend(seed=11, kinds=("wipe",)), (), []
    for i in range(3):
        p, _ = propose(b, index=i, existing=existing)
        existing += (p.name,)
        out.append(p)
    assert sorted(p.objects[1].asset for p in out) == ["spill_long", "spill_round", "spill_square"]
    assert condition_skill("wiped") == "wipe" and condition_skill("wiped", negate=True) is None
    task = [{"type": "wiped", "object": "sponge", "target": "spill", "min_fraction": 0.9}]
    assert stage_goal("wipe", "spill", task, articulated=False) == task
    assert stage_goal("wipe", "bowl", task, articulated=False) is None
