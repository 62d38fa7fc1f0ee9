"""The twist skill in the generator: the reader (unscrew, open the jar, take the lid off), the offline author's
unscrew tasks and their scenes, and the skill statistics."""

from __future__ import annotations

import dataclasses

import pytest

from gendex_envs.spec import spec_to_dict
from generator.backends.base import ModelRequest
from generator.backends.layouts import ARTICULATED_LAYOUTS, TWIST_RANDOMIZE
from generator.backends.offline import OfflineBackend
from generator.backends.offline_scene import STAGE_HORIZONS
from generator.catalog_view import asset_dicts
from generator.instruction import read_instruction
from generator.phrasing import split
from generator.reward_library import compose_stage_module, compose_task_module, roles_of
from generator.stats import condition_skill, part_of
from generator.steps.propose import parse_proposal
from generator.steps.scene import adjust_sizes, parse_scene
from generator.steps.validate import check_reward_source


@pytest.mark.parametrize("text, asset", [
    ("unscrew the jar lid", "screw_jar"), ("open the jar", "screw_jar"), ("take the lid off the jar", "screw_jar"),
    ("twist the cap off the bottle", "screw_bottle"), ("loosen the bottle cap", "screw_bottle"),
    ("unscrew the kitchen canister", "screw_canister"), ("turn the jar lid", "screw_jar"),
    ("twist open the jam jar", "screw_jar"), ("unscrew the water bottle", "screw_bottle"),
])
def test_an_unscrew_request_reads_as_a_twist_of_the_screw_top_model(text, asset):
    r = read_instruction(text, asset_dicts())
    assert r.skill == "twist" and [m.asset for m in r.objects] == [asset], (r.skill, r.objects)


@pytest.mark.parametrize("text, skill, asset", [("pick up the jar", "lift", "jar"),
                                                ("pick up the bottle", "lift", "bottle"),
                                                ("take the can out of the bowl", "take_out", "can"),
                                                ("open the box lid", "open", "box_with_lid_large")])
def test_the_same_words_keep_their_other_skills(text, skill, asset):
    r = read_instruction(text, asset_dicts())
    assert (r.skill, r.objects[0].asset) == (skill, asset)


@pytest.mark.parametrize("text, asset", [
    ("screw the lid on the jar", "screw_jar"), ("tighten the jar lid", "screw_jar"), ("close the jar", "screw_jar"),
    ("put the cap back on the bottle", "screw_bottle"), ("screw the canister's lid back on", "screw_canister")])
def test_screwing_on_reads_as_a_twist_on(text, asset):
    r = read_instruction(text, asset_dicts())
    assert (r.skill, r.direction, [m.asset for m in r.objects]) == ("twist", "on", [asset]), r.lines()
    assert read_instruction("unscrew the jar lid", asset_dicts()).direction is None


def test_putting_something_on_top_of_a_jar_is_no_twist():
    """'on top of the jar' is a place (refused: a jar is no surface), not the cap screwed on."""
    from generator.instruction import InstructionError

    with pytest.raises(InstructionError, match="place_on"):
        read_instruction("put the lemon on top of the jar", asset_dicts())


@pytest.mark.parametrize("text, asset", [("screw the lid back on the jar", "screw_jar"),
                                         ("close the bottle", "screw_bottle")])
def test_a_screw_on_task_starts_a_full_turn_off_and_ends_shut(text, asset):
    """The cap starts at its open end (FULL_TURN) and the task ends with it screwed shut (under 10 % of a turn):
    another task than unscrewing (its signature says ``on``), worded so the reader reads it back as screwing on."""
    from generator.backends.layouts import FULL_TURN
    from generator.novelty import proposal_signature

    b = OfflineBackend(seed=5)
    reading = read_instruction(text, asset_dicts())
    p = parse_proposal(b.complete(ModelRequest(step="propose_guided", prompt="", context={
        "reading": reading.to_dict(), "assets": asset_dicts()})).text)
    assert [o.asset for o in p.objects] == [asset] and [s.skill for s in p.steps] == ["reach", "twist"]
    assert p.name.startswith("ScrewOn") and p.success["negate"] and p.success["min_fraction"] == 0.1
    back = read_instruction(split(p.description)[1], asset_dicts())
    assert (back.skill, back.direction) == ("twist", "on"), (p.description, back.lines())
    assert proposal_signature(dataclasses.asdict(p))[0] == ("twist", "on")
    context = {"proposal": dataclasses.asdict(p), "candidate_index": 0, "index": 0, "attempt": 0,
               "assets": [a for a in asset_dicts() if a["id"] == asset]}
    spec = adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p), p)
    assert spec.objects[0].joint_state == {"cap_screw": FULL_TURN}
    # shut is the whole success: no cap in the hand at the end
    assert [(c.type, c.negate) for c in spec.success.conditions] == [("joint_open", True)]
    raw, roles = spec_to_dict(spec), roles_of(dataclasses.asdict(p))
    check_reward_source(compose_task_module(raw, roles))


@pytest.mark.parametrize("text, asset", [("unscrew the jar lid", "screw_jar"),
                                         ("twist the cap off the bottle", "screw_bottle"),
                                         ("unscrew the canister", "screw_canister")])
def test_an_unscrew_task_is_a_reach_and_a_long_twist_to_a_full_turn(text, asset):
    """The proposal reaches for the cap and twists it until it is 90 % of a full turn open; its command reads back as
    a twist; the scene lays the container where the twist was measured (fixed, the cap shut, randomized
    TWIST_RANDOMIZE) with a stage horizon for the regrasps; the reward modules pass the validator."""
    b = OfflineBackend(seed=4)
    reading = read_instruction(text, asset_dicts())
    p = parse_proposal(b.complete(ModelRequest(step="propose_guided", prompt="", context={
        "reading": reading.to_dict(), "assets": asset_dicts()})).text)
    assert [o.asset for o in p.objects] == [asset] and [s.skill for s in p.steps] == ["reach", "twist"]
    assert p.success == {**p.success, "type": "joint_open", "min_fraction": 0.9}
    assert read_instruction(split(p.description)[1], asset_dicts()).skill == "twist"
    context = {"proposal": dataclasses.asdict(p), "candidate_index": 0, "index": 0, "attempt": 0,
               "assets": [a for a in asset_dicts() if a["id"] == asset]}
    spec = adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p), p)
    o = spec.objects[0]
    nominal = ARTICULATED_LAYOUTS["twist", asset]["pos_m"]
    assert o.fixed and all(abs(a - n) <= 0.021 for a, n in zip(o.pos_m[:2], nominal, strict=True))
    assert list(o.randomize.xy_m) == TWIST_RANDOMIZE["xy_m"] and o.joint_state == {"cap_screw": 0.0}
    twist = spec.stages[1]
    assert twist.skill == "twist" and twist.horizon == STAGE_HORIZONS["twist"]
    # unscrewed means the cap ends in the hand: a forearm brushing past a cap turns it too
    assert [(c.type, c.object, c.part) for c in spec.success.conditions] == [
        ("joint_open", o.name, None), ("grasped", o.name, "handle")]
    assert spec.success.description.endswith("The cap ends in the hand.")
    assert spec.max_episode_steps >= 2 * twist.horizon
    raw, roles = spec_to_dict(spec), roles_of(dataclasses.asdict(p))
    check_reward_source(compose_task_module(raw, roles))
    check_reward_source(compose_stage_module(raw, twist.name, roles))


def test_stats_count_a_cap_opened_as_a_twist():
    jar = next(a for a in asset_dicts() if a["id"] == "screw_jar")
    assert part_of(jar) == "cap"
    assert condition_skill("joint_open", part="cap") == "twist"


def test_the_critic_flags_a_cap_that_starts_unscrewed():
    """The joint_state check reads the twist's joint_open success: a cap that starts 95 % of a turn open is already
    done, and the fix starts it shut."""
    from gendex_envs.spec import parse_task_spec
    from generator.critic.joints import apply_joint_fix
    from generator.critic.physical import check_scene_static

    cond = {"type": "joint_open", "object": "jar", "min_fraction": 0.9}
    raw = {"name": "UnscrewJarTry", "instruction": "Unscrew the jar.",
           "objects": [{"name": "jar", "asset": "screw_jar", "pos_m": [0.12, 0.0, 0.0], "fixed": True,
                        "joint_state": {"cap_screw": 6.0}}],
           "stages": [{"name": "twist_jar", "instruction": "Unscrew.", "skill": "twist", "method": "RL",
                       "control_joint": "both", "horizon": 700, "target": "jar"}],
           "success": {"description": "Unscrewed.", "conditions": [cond]}}
    spec = parse_task_spec(raw)
    found = [v for v in check_scene_static(spec).violations if v.check == "joint_state"]
    assert len(found) == 1 and found[0].object == "jar"
    fixed = apply_joint_fix(spec, found[0].joint_fix)
    assert fixed.objects[0].joint_state["cap_screw"] == 0.0
    assert not [v for v in check_scene_static(fixed).violations if v.check == "joint_state"]
