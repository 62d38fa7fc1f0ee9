"""The hand-over skill in the generator: the reader, the offline author, the scene step's settling conditions, the
critic's check that the object starts clear of the hand-over mat, and the skill statistics."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gendex_envs.spec import parse_task_spec, spec_to_dict
from generator.backends.offline import HANDOVER_DZ_M, HANDOVER_XY_M, OfflineBackend
from generator.backends.offline_scene import HANDOVER_REGION_M
from generator.catalog_view import asset_dicts
from generator.critic.directives import apply_directives
from generator.critic.physical import check_scene_static
from generator.critic.skill_checks import HANDOVER_APART_M
from generator.instruction import read_instruction
from generator.phrasing import split
from generator.reward_library import compose_task_module, roles_of
from generator.stats import condition_skill
from generator.steps.validate import check_reward_source


@pytest.mark.parametrize("text, asset", [
    ("hand me the bottle", "bottle"), ("Hand the mug to the person", "mug"), ("pass me the apple please", "apple"),
    ("put the can on the hand-over mat", "can"), ("bring me the mustard bottle", "mustard_bottle"),
    ("hand over the banana", "banana"), ("deliver the sugar box to the hand-over area", "sugar_box"),
    ("give me the cup", "cup"),
])
def test_a_hand_over_request_reads_as_one_with_its_object_and_no_other(text, asset):
    r = read_instruction(text, asset_dicts())
    assert r.skill == "hand_over" and [m.asset for m in r.objects] == [asset], (r.skill, r.objects)


@pytest.mark.parametrize("text, skill", [
    ("lift the apple with the open hand", "lift"), ("give the emergency stop a push", "press"),
    ("rotate the tennis ball in the hand", "reorient"), ("set the bottle on the plate", "place_on"),
])
def test_hand_words_elsewhere_leave_other_skills_alone(text, skill):
    assert read_instruction(text, asset_dicts()).skill == skill


@pytest.mark.parametrize("text, obj, upright", [("hand me the bottle", "bottle", True),
                                                ("pass me the apple", "apple", False),
                                                ("give me the mug", "mug", True),
                                                ("hand me the small block", "block_small", False),
                                                ("pass me the foam brick", "foam_brick", True)])
def test_a_hand_over_is_carried_to_the_mat_and_left_there_still_and_standing(text, obj, upright, guided):
    """The proposal carries the object onto the hand-over mat (the task's own object, fixed on the far side of the
    table), its command reads back as a hand-over, and the success asks the object let go, at rest and, unless it
    rolls or is a cube (it stands on any face; a brick does not), standing as it stood; the critic finds the scene
    sound and the reward module passes the validator."""
    p, spec = guided(text)
    assert [o.asset for o in p.objects] == [obj, "handover_mat"]
    assert read_instruction(split(p.description)[1], asset_dicts()).skill == "hand_over"
    mat = spec.object("mat")
    (x0, x1), (y0, y1) = HANDOVER_REGION_M
    assert mat.fixed and x0 <= mat.pos_m[0] <= x1 and y0 <= mat.pos_m[1] <= y1
    kinds = [(c.type, c.object) for c in spec.success.conditions]
    name = spec.success.conditions[0].object
    want = [("over", name), ("released", name), ("at_rest", name)] + ([("upright", name)] if upright else [])
    assert kinds == want
    over = spec.success.conditions[0]
    assert (over.target, over.max_xy_m, over.min_dz_m, over.max_dz_m) == ("mat", HANDOVER_XY_M, *HANDOVER_DZ_M)
    assert spec.success.hold_steps >= 10
    assert check_scene_static(spec).ok
    check_reward_source(compose_task_module(spec_to_dict(spec), roles_of(dataclasses.asdict(p))))


def test_the_critic_moves_an_object_that_starts_on_or_by_the_mat_clear_of_it(guided):
    """Held still, a bottle that starts on the mat is handed over: the critic's ``handover`` check measures the gap
    between the two footprints widened by their randomization and its fix moves the bottle until the gap is
    HANDOVER_APART_M."""
    _, spec = guided("hand me the bottle")
    raw = spec_to_dict(spec)
    mat = spec.object("mat")
    for dx in (0.0, -0.12, -0.2):
        raw["objects"][0]["pos_m"] = [mat.pos_m[0] + dx, mat.pos_m[1], 0.0]
        near = parse_task_spec(raw)
        report = check_scene_static(near)
        found = [v for v in report.violations if v.check == "handover"]
        assert len(found) == 1 and found[0].object == "bottle" and found[0].measured < HANDOVER_APART_M, dx
        fixed = apply_directives(near, list(found[0].fix))
        after = check_scene_static(fixed)
        assert not [v for v in after.violations if v.check == "handover"], (dx, after.summary())
        gap = after.measurements["handover"]["bottle"]["gap_m"]
        assert HANDOVER_APART_M <= gap < HANDOVER_APART_M + 0.01


def test_the_grammar_writes_hand_overs_of_objects_the_solver_holds():
    from generator.steps.propose import propose

    b, existing, out = OfflineBackend(seed=11, kinds=("hand_over",)), (), []
    for i in range(4):
        p, _ = propose(b, index=i, existing=existing)
        existing += (p.name,)
        out.append(p)
    assert all(p.name.startswith("HandOver") and p.objects[1].asset == "handover_mat" for p in out)
    assert len({p.objects[0].asset for p in out}) == 4


def test_stats_count_a_set_down_on_the_mat_as_a_hand_over():
    assert condition_skill("over", target_category="handover_mat") == "hand_over"
    assert condition_skill("over", target_category="plate") == "place_on"
    assert condition_skill("inside", target_category="handover_mat", negate=True) is None
    assert np.isclose(HANDOVER_XY_M, 0.08)
