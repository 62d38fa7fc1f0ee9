"""The insert skill in the generator: the pegs and holders (a hole 5-6 mm wider than its peg), the reader, the offline
author, the scene step's upright condition, the critic's check that the peg starts clear of its holder, and the skill
statistics."""

from __future__ import annotations

import dataclasses

import pytest

from gendex_envs.assets.catalog import get_asset
from gendex_envs.spec import parse_task_spec, spec_to_dict
from generator.backends.dexterous import INSERT_DZ_M, INSERT_XY_M
from generator.backends.offline import OfflineBackend
from generator.backends.offline_scene import HOLDER_YAW_DEG, INSERT_RANDOMIZE
from generator.backends.roles import HOLE_CLEARANCE_M, fits_hole
from generator.catalog_view import asset_dicts
from generator.critic.directives import apply_directives
from generator.critic.physical import check_scene_static
from generator.critic.skill_checks import INSERT_APART_M
from generator.errors import InstructionError
from generator.instruction import read_instruction
from generator.phrasing import split
from generator.reward_library import compose_task_module, roles_of
from generator.stats import condition_skill
from generator.steps.scene import INSERTED_TILT_DEG
from generator.steps.validate import check_reward_source

PAIRS = {"peg_round": "peg_holder_round", "peg_square": "peg_holder_square", "peg_thin": "peg_holder_thin"}


def test_each_peg_fits_its_own_holder_only_with_millimetres_to_spare():
    """A hole is 5-6 mm wider than its peg (2.5-3 mm a side), of the peg's shape; no other holder takes it."""
    assets = {a["id"]: a for a in asset_dicts()}
    for peg, holder in PAIRS.items():
        width = get_asset(peg).entry.params["width_m"]
        hole = get_asset(holder).entry.params["hole_m"]
        assert 0.005 - 1e-9 <= hole - width <= 0.006 + 1e-9, (peg, hole - width)
        assert HOLE_CLEARANCE_M[0] <= hole - width <= HOLE_CLEARANCE_M[1]
        assert [h for h in PAIRS.values() if fits_hole(assets[peg], assets[h])] == [holder]
        lo, hi = get_asset(peg).entry.bbox_min_m, get_asset(peg).entry.bbox_max_m
        assert hi[0] - lo[0] == pytest.approx(width, abs=1e-4)  # the box is the peg: nothing sticks out


@pytest.mark.parametrize("text, peg, holder", [
    ("insert the square peg into the square hole", "peg_square", "peg_holder_square"),
    ("put the round peg into the round hole", "peg_round", "peg_holder_round"),
    ("fit the dowel into the narrow hole", "peg_thin", "peg_holder_thin"),
    ("put the peg in the holder", "peg_round", "peg_holder_round"),
])
def test_an_insert_request_reads_as_one_with_its_peg_and_holder(text, peg, holder):
    r = read_instruction(text, asset_dicts())
    assert r.skill == "insert" and [m.asset for m in r.objects] == [peg, holder], (r.skill, r.objects)


@pytest.mark.parametrize("text, skill", [("pick up the peg", "lift"), ("insert the apple into the bowl", "put_in"),
                                         ("put the lemon in the bowl", "put_in")])
def test_pegs_picked_up_and_other_insertions_keep_their_skills(text, skill):
    assert read_instruction(text, asset_dicts()).skill == skill


@pytest.mark.parametrize("text, peg", [("insert the square peg into the square hole", "peg_square"),
                                       ("plug the thin peg into its hole", "peg_thin"),
                                       ("insert the peg", "peg_round")])
def test_an_insert_carries_the_peg_over_its_fitting_holder_and_sets_it_down_in_the_hole(text, peg, guided):
    """The proposal takes the peg to the holder its hole fits (fixed, both moved at reset), its command reads back as
    an insert, and the success asks the peg's bottom within INSERT_XY_M of the hole's axis, on the hole's floor,
    upright, let go; the critic finds the scene sound and the reward module passes the validator."""
    p, spec = guided(text)
    assert [o.asset for o in p.objects] == [peg, PAIRS[peg]]
    assert [s.skill for s in p.steps] == ["reach", "grasp", "carry", "release"]
    assert read_instruction(split(p.description)[1], asset_dicts()).skill == "insert"
    holder, moved = spec.object("holder"), spec.object("peg")
    assert holder.fixed and not moved.fixed
    assert list(holder.randomize.xy_m) == INSERT_RANDOMIZE["xy_m"] == list(moved.randomize.xy_m)
    assert holder.randomize.yaw_deg == HOLDER_YAW_DEG
    floor = get_asset(PAIRS[peg]).entry.params["hole_floor_m"]
    kinds = [(c.type, c.object) for c in spec.success.conditions]
    assert kinds == [("over", "peg"), ("released", "peg"), ("upright", "peg")]
    over, _, upright = spec.success.conditions
    assert (over.target, over.max_xy_m) == ("holder", INSERT_XY_M)
    assert (over.min_dz_m, over.max_dz_m) == pytest.approx((floor + INSERT_DZ_M[0], floor + INSERT_DZ_M[1]))
    assert upright.max_tilt_deg == INSERTED_TILT_DEG
    assert spec.success.hold_steps >= 10
    assert check_scene_static(spec).ok
    check_reward_source(compose_task_module(spec_to_dict(spec), roles_of(dataclasses.asdict(p))))


def test_a_peg_that_does_not_fit_the_named_hole_is_refused_naming_the_one_it_fits(guided):
    with pytest.raises(InstructionError, match="peg_holder_square"):
        guided("put the square peg in the round hole")


def test_the_critic_moves_a_peg_that_starts_by_its_holder_clear_of_it(guided):
    """A peg next to its hole is half inserted by a nudge: the ``insert`` check measures the gap between the footprints
    widened by their randomization and its fix moves the peg until the gap is INSERT_APART_M."""
    _, spec = guided("insert the square peg into the square hole")
    raw = spec_to_dict(spec)
    holder = spec.object("holder")
    for dy in (0.0, 0.08, -0.12):
        raw["objects"][0]["pos_m"] = [holder.pos_m[0], holder.pos_m[1] + dy, 0.0]
        near = parse_task_spec(raw)
        found = [v for v in check_scene_static(near).violations if v.check == "insert"]
        assert len(found) == 1 and found[0].object == "peg" and found[0].measured < INSERT_APART_M, dy
        after = check_scene_static(apply_directives(near, list(found[0].fix)))
        assert not [v for v in after.violations if v.check == "insert"], (dy, after.summary())
        assert INSERT_APART_M <= after.measurements["insert"]["peg"]["gap_m"] < INSERT_APART_M + 0.01


def test_the_grammar_writes_an_insert_for_every_peg_and_stats_count_it():
    from generator.steps.propose import propose

    b, existing, out = OfflineBackend(seed=11, kinds=("insert",)), (), []
    for i in range(3):
        p, _ = propose(b, index=i, existing=existing)
        existing += (p.name,)
        out.append(p)
    assert sorted((p.objects[0].asset, p.objects[1].asset) for p in out) == sorted(PAIRS.items())
    assert condition_skill("over", target_category="peg_holder") == "insert"
    assert condition_skill("over", target_category="plate") == "place_on"
