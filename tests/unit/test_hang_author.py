"""The hang skill in the generator: the reader (mug and stand in either order, a stand left unsaid), the offline
author's task (grasp the mug, thread it on a peg, let go: hung, released, still), the scene (the stand fixed off the
middle, where the arm reaches round it), the critic's check that the mug starts clear of the stand, the stage goal,
the reward module, and the skill statistics."""

from __future__ import annotations

import dataclasses

import pytest

from gendex_envs.spec import parse_task_spec, spec_to_dict
from generator.backends.dexterous import HANG_LIFT_M
from generator.backends.offline import OfflineBackend
from generator.backends.offline_scene import HANG_RANDOMIZE, STAND_RANDOMIZE, STAND_REGION_M
from generator.catalog_view import asset_dicts
from generator.critic.directives import apply_directives
from generator.critic.physical import check_scene_static
from generator.critic.skill_checks import HANG_APART_M
from generator.instruction import read_instruction
from generator.phrasing import split
from generator.reward_library import compose_stage_module, compose_task_module, roles_of
from generator.stage_goals import stage_goal
from generator.stats import condition_skill
from generator.steps.validate import check_reward_source


@pytest.mark.parametrize("text, stand", [
    ("hang the mug on the mug tree", "mug_tree"),
    ("hang up the coffee mug on the hook", "mug_hook"),
    ("on the mug rack, hang the mug", "mug_rack"),
])
def test_a_hang_reads_with_the_mug_first(text, stand):
    r = read_instruction(text, asset_dicts())
    assert r.skill == "hang"
    assert [m.asset for m in r.objects] == ["mug", stand], r.objects


@pytest.mark.parametrize("text, stand", [("hang the mug on the mug tree", "mug_tree"),
                                         ("hang the mug on the wall rack", "mug_rack"),
                                         ("hang up the mug", "mug_hook")])
def test_a_hang_threads_the_mug_on_the_stand_and_leaves_it_hanging_still(text, stand, guided):
    p, spec = guided(text)
    found = check_scene_static(spec).violations  # a mug drawn against the stand is moved off it, as refinement does
    spec = apply_directives(spec, [d for v in found if v.check == "hang" for d in v.fix])
    assert [o.asset for o in p.objects] == ["mug", stand]
    assert [s.skill for s in p.steps] == ["reach", "grasp", "hang", "release"]
    assert read_instruction(split(p.description)[1], asset_dicts()).skill == "hang"
    mug, st = spec.object("mug"), spec.object("stand")
    assert st.fixed and not mug.fixed
    (x0, x1), (y0, y1) = STAND_REGION_M
    assert x0 <= st.pos_m[0] <= x1 and y0 <= abs(st.pos_m[1]) <= y1
    assert list(st.randomize.xy_m) == STAND_RANDOMIZE["xy_m"] and st.randomize.yaw_deg == STAND_RANDOMIZE["yaw_deg"]
    assert list(mug.randomize.xy_m) == HANG_RANDOMIZE["xy_m"]
    conds = {c.type: c for c in spec.success.conditions}
    assert sorted(conds) == ["at_rest", "hung", "released"]  # the scene step lets it go and waits for it to hang still
    hung = conds["hung"]
    assert (hung.object, hung.target, hung.min_height_m) == ("mug", "stand", HANG_LIFT_M)
    assert spec.stages[2].target == "stand" and spec.stages[2].success is None
    assert check_scene_static(spec).ok
    raw, roles = spec_to_dict(spec), roles_of(dataclasses.asdict(p))
    check_reward_source(compose_task_module(raw, roles))
    check_reward_source(compose_stage_module(raw, spec.stages[2].name, roles))


def test_a_mug_put_away_or_handed_over_keeps_its_skill_and_its_usual_scene(guided):
    assert read_instruction("put the mug in the bowl", asset_dicts()).skill == "put_in"
    _, spec = guided("hand me the mug")
    assert not any(c.type == "hung" for c in spec.success.conditions)
    assert spec.object("mug").randomize.yaw_deg == 45.0  # a hand-over's, not a hang's


def test_the_critic_moves_a_mug_that_starts_against_its_stand_clear_of_it(guided):
    _, spec = guided("hang the mug on the mug hook")
    raw = spec_to_dict(spec)
    st = spec.object("stand")
    for dx in (0.0, -0.09):
        raw["objects"][0]["pos_m"] = [st.pos_m[0] + dx, st.pos_m[1], 0.0]
        near = parse_task_spec(raw)
        found = [v for v in check_scene_static(near).violations if v.check == "hang"]
        assert len(found) == 1 and found[0].object == "mug" and found[0].measured < HANG_APART_M, dx
        after = check_scene_static(apply_directives(near, list(found[0].fix)))
        assert not [v for v in after.violations if v.check == "hang"], (dx, after.summary())


def test_the_grammar_writes_a_hang_on_every_stand_and_stats_and_stage_goals_know_it():
    from generator.steps.propose import propose

    b, existing, out = OfflineBackend(seed=11, kinds=("hang",)), (), []
    for i in range(6):  # mugs of several colours: a stand may come twice before each has come once
        p, _ = propose(b, index=i, existing=existing)
        existing += (p.name,)
        out.append(p)
    assert {p.objects[1].asset for p in out} == {"mug_hook", "mug_rack", "mug_tree"}
    assert condition_skill("hung") == "hang" and condition_skill("hung", negate=True) is None
    assert stage_goal("hang", "stand", [{"type": "hung", "object": "mug", "target": "stand"}], False) is None
