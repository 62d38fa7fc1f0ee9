"""The pour skill in the generator: the reader (pieces, vessel and bowl in any order, some left unsaid; a glass one
pours from is the tumbler), the proposal's ``fill`` and its checks, the pieces GenDex lays in the vessel (and lays
again where the critic moves, turns or scales it), the offline author's task (grasp the vessel, pour, stand it up:
poured and upright), the scene (the vessel on one side, the bowl on the other), the critic's check that the vessel
starts clear of the bowl, the stage goal, the reward module and the skill statistics."""

from __future__ import annotations

import dataclasses
import json

import pytest

from gendex_envs.pouring import MAX_PIECES, spec_fills
from gendex_envs.spec import spec_to_dict
from generator.backends.dexterous import POUR_FRACTION, POUR_PIECES
from generator.backends.offline import OfflineBackend
from generator.backends.offline_scene import POUR_BOWL_X_M, POUR_RANDOMIZE, POUR_VESSEL_REGION_M
from generator.catalog_view import asset_dicts
from generator.critic.directives import Directive
from generator.critic.physical import check_scene_static
from generator.critic.skill_checks import POUR_APART_M
from generator.errors import InstructionError, ProposalError
from generator.instruction import read_instruction
from generator.phrasing import split
from generator.reward_library import compose_stage_module, compose_task_module, roles_of
from generator.stage_goals import stage_goal
from generator.stats import condition_skill
from generator.steps.propose import parse_proposal
from generator.steps.refine import apply_fixes
from generator.steps.scene import POURED_TILT_DEG
from generator.steps.validate import check_reward_source


@pytest.mark.parametrize("text, objects", [
    ("pour the beads from the glass into the bowl", ["bead", "tumbler", "bowl"]),
    ("tip the glass of marbles into the large bowl", ["marble", "tumbler", "bowl_large"]),
    ("empty the paper cup of beads into the bowl", ["bead", "paper_cup", "bowl"]),
    ("pour the pellets out of the measuring beaker into the bowl", ["bead", "beaker", "bowl"]),
])
def test_a_pour_reads_pieces_vessel_and_bowl_in_that_order(text, objects):
    r = read_instruction(text, asset_dicts())
    assert r.skill == "pour"
    assert [m.asset for m in r.objects] == objects, r.objects


def test_what_a_pour_leaves_unsaid_is_a_recorded_choice_and_pieces_it_lacks_a_substitution():
    r = read_instruction("empty the beaker into the bowl", asset_dicts())
    assert [m.asset for m in r.objects] == ["beaker", "bowl", "bead"]
    assert r.objects[2].how == "kind" and "names no pourable" in r.objects[2].detail
    rice = read_instruction("pour the rice from the cup into the bowl", asset_dicts())
    assert rice.objects[0].how == "substitute" and rice.objects[0].asset in ("bead", "marble")
    assert rice.objects[1].asset == "paper_cup"  # a cup one pours from is the paper cup, not the short teacup
    with pytest.raises(InstructionError, match="pour_into"):
        read_instruction("pour the beads from the glass into the trash can", asset_dicts())


@pytest.mark.parametrize("text, vessel, bowl, piece", [
    ("pour the beads from the glass into the bowl", "tumbler", "bowl", "bead"),
    ("tip the marbles out of the beaker into the large bowl", "beaker", "bowl_large", "marble"),
])
def test_a_pour_fills_the_vessel_and_ends_poured_with_the_vessel_stood_up(text, vessel, bowl, piece, guided):
    p, spec = guided(text)
    assert [(o.asset, o.fill) for o in p.objects] == [(vessel, {"asset": piece, "count": POUR_PIECES}), (bowl, None)]
    assert [s.skill for s in p.steps] == ["reach", "grasp", "pour"]
    assert read_instruction(split(p.description)[1], asset_dicts()).skill == "pour"
    v, b = spec.object(p.objects[0].name), spec.object(p.objects[1].name)
    pieces = spec_fills(spec)[v.name]  # laid in the vessel where it stands, each its own object
    assert len(pieces) == POUR_PIECES and {spec.object(n).asset for n in pieces} == {piece}
    (x0, x1), (y0, y1) = POUR_VESSEL_REGION_M
    assert x0 <= v.pos_m[0] <= x1 and y0 <= abs(v.pos_m[1]) <= y1
    assert POUR_BOWL_X_M[0] <= b.pos_m[0] <= POUR_BOWL_X_M[1]
    assert v.pos_m[1] * b.pos_m[1] < 0  # on either side of the middle
    for k, o in enumerate((v, b)):
        assert list(o.randomize.xy_m) == POUR_RANDOMIZE[k]["xy_m"]
    conds = {c.type: c for c in spec.success.conditions}
    assert sorted(conds) == ["poured", "upright"]
    assert (conds["poured"].object, conds["poured"].target, conds["poured"].min_fraction) == (v.name, b.name,
                                                                                            POUR_FRACTION)
    assert (conds["upright"].object, conds["upright"].max_tilt_deg) == (v.name, POURED_TILT_DEG)
    assert check_scene_static(spec).ok  # the pieces, inside their vessel, are no penetration
    pour = spec.stages[2]
    task_conds = [spec_to_dict(spec)["success"]["conditions"][0]]
    assert pour.target == b.name and stage_goal(pour.skill, pour.target, task_conds, False) == task_conds
    raw, roles = spec_to_dict(spec), roles_of(dataclasses.asdict(p))
    task = compose_task_module(raw, roles)
    check_reward_source(task)
    assert f"poured_share({v.name!r}, {b.name!r})" in task and "bead_0" not in task  # a dropped bead fails nothing
    check_reward_source(compose_stage_module(raw, pour.name, roles))


def test_a_vessel_the_critic_moves_turns_or_scales_carries_its_pieces_and_a_piece_is_never_moved_alone(guided):
    _, spec = guided("pour the beads from the glass into the bowl")
    before = spec_fills(spec)["tumbler"]
    v0 = spec.object("tumbler")
    found = type("Report", (), {"directives": lambda self: [Directive.move("tumbler", "x", 0.04),
                                                           Directive.rotate("tumbler", "z", 40.0),
                                                           Directive.scale("tumbler", 1.1),
                                                           Directive.move(before[0], "z", 0.05)],
                                "joint_fixes": lambda self: []})()
    moved, applied, rejected = apply_fixes(spec, found, [])
    assert len(applied) == 3 and len(rejected) == 1 and "a piece GenDex lays" in rejected[0]
    assert spec_fills(moved) == {"tumbler": before}  # the same pieces, in the vessel where it now stands
    v1 = moved.object("tumbler")
    assert v1.pos_m[0] == pytest.approx(v0.pos_m[0] + 0.04) and v1.scale == pytest.approx(1.1)
    for name in before:
        assert moved.object(name).pos_m != spec.object(name).pos_m
    assert not [v for v in check_scene_static(moved).violations if {v.object, v.other} & set(before)]


def test_the_critic_moves_a_vessel_that_starts_against_its_bowl_clear_of_it(guided):
    _, spec = guided("pour the beads from the glass into the bowl")
    v, bowl, fills = spec.object("tumbler"), spec.object("bowl"), spec_fills(spec)
    to = [Directive.move("tumbler", axis, bowl.pos_m[k] - 0.1 * (k == 1) - v.pos_m[k]) for k, axis in enumerate("xy")]
    near, _, _ = apply_fixes(spec, type("R", (), {"directives": lambda self: to, "joint_fixes": lambda self: []})(), [])
    found = [v for v in check_scene_static(near).violations if v.check == "pour"]
    assert len(found) == 1 and found[0].object == "tumbler" and found[0].measured < POUR_APART_M
    after, applied, _ = apply_fixes(near, type("R", (), {"directives": lambda self: list(found[0].fix),
                                                         "joint_fixes": lambda self: []})(), [])
    assert applied and not [v for v in check_scene_static(after).violations if v.check == "pour"]
    assert spec_fills(after) == fills


def test_a_proposals_fill_is_checked():
    def proposal(fill, vessel="tumbler", target="bowl"):
        return "```json\n" + json.dumps({
            "name": "PourIt", "description": "Pour the beads into the bowl.", "success_text": "Poured.",
            "objects": [{"name": "glass", "asset": vessel, "role": "graspable", "fill": fill},
                        {"name": "bowl", "asset": target, "role": "container"}],
            "steps": [{"skill": "pour", "target": "bowl", "control_joint": "arm", "instruction": "Pour."}],
            "success": {"type": "poured", "object": "glass", "target": "bowl", "min_fraction": 0.75}}) + "\n```"

    assert parse_proposal(proposal({"asset": "marble", "count": 8})).objects[0].fill == {"asset": "marble",
                                                                                         "count": 8}
    for fill, vessel, target, why in [(None, "tumbler", "bowl", "holds nothing to pour"),
                                      ({"asset": "apple", "count": 8}, "tumbler", "bowl", "not a piece"),
                                      ({"asset": "bead", "count": MAX_PIECES + 1}, "tumbler", "bowl", "whole number"),
                                      ({"asset": "bead", "count": MAX_PIECES}, "beaker", "bowl", "do not fit"),
                                      ({"asset": "bead", "count": 8}, "mug", "bowl", "no vessel to pour from"),
                                      ({"asset": "bead", "count": 8}, "tumbler", "plate", "no container")]:
        with pytest.raises(ProposalError, match=why):
            parse_proposal(proposal(fill, vessel, target))


def test_the_grammar_writes_pours_and_stats_and_stage_goals_know_them():
    from generator.steps.propose import propose

    b, existing, out = OfflineBackend(seed=11, kinds=("pour",)), (), []
    for i in range(3):
        p, _ = propose(b, index=i, existing=existing)
        existing += (p.name,)
        out.append(p)
    assert all(p.success["type"] == "poured" and p.objects[0].fill for p in out)
    assert len({(p.objects[0].asset, p.objects[0].fill["asset"], p.objects[1].asset) for p in out}) == 3
    assert condition_skill("poured") == "pour" and condition_skill("poured", negate=True) is None
    cond = {"type": "poured", "object": "glass", "target": "bowl", "min_fraction": 0.75}
    assert stage_goal("pour", "bowl", [cond], False) == [cond]
