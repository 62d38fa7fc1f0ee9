"""The flip skill in the generator: the reader (turn upside down, turn over, flip, upend; a glass or cup is the
vessel a pour would use, a wine glass or a box is refused; flipping a switch stays a press), the offline author's
task (grasp the vessel by its side, flip, let go: flipped, released, at rest), its layout, the critic's room check,
the stage goal, the reward module and the skill statistics."""

from __future__ import annotations

import dataclasses

import pytest

from gendex_envs.spec import spec_to_dict
from generator.backends.dexterous import FLIP_TILT_DEG
from generator.backends.offline import OfflineBackend
from generator.backends.offline_scene import FLIP_RANDOMIZE, FLIP_REGION_M
from generator.backends.roles import FLIPPABLE
from generator.catalog_view import asset_dicts
from generator.critic.directives import Directive
from generator.critic.physical import check_scene_static
from generator.critic.skill_checks import FLIP_ROOM_M
from generator.errors import InstructionError
from generator.instruction import read_instruction
from generator.phrasing import split
from generator.reward_library import compose_stage_module, compose_task_module, roles_of
from generator.stage_goals import stage_goal
from generator.stats import condition_skill
from generator.steps.refine import apply_fixes
from generator.steps.scene import SETTLED_STEPS
from generator.steps.validate import check_reward_source


@pytest.mark.parametrize("text, asset", [
    ("turn the glass upside down", "tumbler"),
    ("flip the paper cup over", "paper_cup"),
    ("turn the beaker over", "beaker"),
    ("turn over the coffee cup", "paper_cup"),
    ("upend the drinking glass", "tumbler"),
    ("invert the cup", "paper_cup"),
])
def test_a_flip_reads_the_vessel_to_turn_over(text, asset):
    r = read_instruction(text, asset_dicts())
    assert r.skill == "flip" and [m.asset for m in r.objects] == [asset]


def test_a_colour_stays_a_wine_glass_is_refused_and_flipping_a_switch_is_a_press():
    red = read_instruction("turn the red glass upside down", asset_dicts())
    assert [(m.asset, m.color) for m in red.objects] == [("tumbler", "red")]
    for text in ("turn the wine glass upside down", "flip the box over", "turn the mug upside down"):
        with pytest.raises(InstructionError, match="flippable"):
            read_instruction(text, asset_dicts())
    assert read_instruction("flip the switch", asset_dicts()).skill == "press"
    assert read_instruction("flip up the lid of the trash can", asset_dicts()).skill == "open"
    # a pour's glass is the tumbler; 'the wine glass' says more, and is no vessel to pour from
    assert read_instruction("pour the beads from the glass into the bowl", asset_dicts()).objects[1].asset == "tumbler"
    with pytest.raises(InstructionError):
        read_instruction("pour the beads from the wine glass into the bowl", asset_dicts())


@pytest.mark.parametrize("text, asset", [("turn the glass upside down", "tumbler"),
                                         ("flip the paper cup over", "paper_cup")])
def test_a_flip_grasps_turns_over_and_lets_go_and_ends_flipped_let_go_and_still(text, asset, guided):
    p, spec = guided(text)
    assert [o.asset for o in p.objects] == [asset]
    assert [s.skill for s in p.steps] == ["reach", "grasp", "flip", "release"]
    assert read_instruction(split(p.description)[1], asset_dicts()).skill == "flip"
    o = spec.object(p.objects[0].name)
    (x0, x1), (y0, y1) = FLIP_REGION_M
    assert x0 <= o.pos_m[0] <= x1 and y0 <= o.pos_m[1] <= y1
    assert list(o.randomize.xy_m) == FLIP_RANDOMIZE["xy_m"] and len(spec.objects) == 1  # no clutter beside it
    conds = {c.type: c for c in spec.success.conditions}
    assert sorted(conds) == ["at_rest", "flipped", "released"]
    assert conds["flipped"].min_tilt_deg == FLIP_TILT_DEG and spec.success.hold_steps == SETTLED_STEPS
    flip = spec.stages[2]
    task_conds = spec_to_dict(spec)["success"]["conditions"]
    assert stage_goal(flip.skill, flip.target, task_conds, False) == [task_conds[0]]
    raw, roles = spec_to_dict(spec), roles_of(dataclasses.asdict(p))
    task = compose_task_module(raw, roles)
    check_reward_source(task)
    assert "turned" in task and "init_obj_quat" in task
    check_reward_source(compose_stage_module(raw, flip.name, roles))
    assert check_scene_static(spec).ok


def test_the_author_refuses_a_beaker_it_cannot_stand_on_its_rim(guided):
    assert read_instruction("turn the beaker over", asset_dicts()).skill == "flip"  # read, then refused saying why
    with pytest.raises(InstructionError, match="glass or paper cup to turn upside down"):
        guided("turn the beaker over")


def test_the_critic_keeps_other_objects_clear_of_a_glass_to_turn_over():
    from gendex_envs.spec import parse_task_spec

    spec = parse_task_spec({
        "name": "FlipNear", "instruction": "Turn the glass upside down.",
        "objects": [{"name": "glass", "asset": "tumbler", "pos_m": [0.02, 0.0, 0.0],
                     "randomize": {"xy_m": [0.08, 0.08], "yaw_deg": 180.0}},
                    {"name": "apple", "asset": "apple", "pos_m": [0.02, 0.2, 0.0],
                     "randomize": {"xy_m": [0.02, 0.02], "yaw_deg": 0.0}}],
        "stages": [{"name": "flip_glass", "instruction": "Flip it.", "skill": "flip", "method": "RL",
                    "control_joint": "arm", "target": "glass"}],
        "success": {"description": "Upside down.", "conditions": [{"type": "flipped", "object": "glass"}]}})
    found = [v for v in check_scene_static(spec).violations if v.check == "flip"]
    assert len(found) == 1 and found[0].object == "apple" and found[0].measured < FLIP_ROOM_M
    fixed, applied, _ = apply_fixes(spec, type("R", (), {"directives": lambda self: list(found[0].fix),
                                                         "joint_fixes": lambda self: []})(), [])
    assert applied and not [v for v in check_scene_static(fixed).violations if v.check == "flip"]
    assert fixed.object("apple").pos_m[1] > 0.2 and fixed.object("glass").pos_m == spec.object("glass").pos_m
    assert isinstance(found[0].fix[0], Directive)


def test_the_grammar_writes_a_flip_of_each_vessel_and_stats_know_them():
    from generator.steps.propose import propose

    b, existing, out = OfflineBackend(seed=11, kinds=("flip",)), (), []
    for i in range(len(FLIPPABLE)):
        p, _ = propose(b, index=i, existing=existing)
        existing += (p.name,)
        out.append(p)
    assert all(p.success["type"] == "flipped" for p in out)
    assert {p.objects[0].asset for p in out} == set(FLIPPABLE)  # then it has no more flips to write
    assert condition_skill("flipped") == "flip" and condition_skill("flipped", negate=True) is None


def test_a_reason_after_the_command_is_noted_and_never_swallows_a_step():
    r = read_instruction("flip the paper cup over so it can dry", asset_dicts())
    assert [m.asset for m in r.objects] == ["paper_cup"] and any("reason" in n for n in r.notes)
    two = read_instruction("open the drawer so the apple fits, then put the apple in the drawer", asset_dicts())
    assert two.skill == "open" and [t.skill for t in two.then] == ["put_in"]
