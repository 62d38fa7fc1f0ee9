"""A chest's drawer as a receptacle (issue 45): *put the lemon in the drawer* is an ``inside`` condition with the
drawer's joint, checked against the bin its link carries (gendex_envs.holds); the offline author slides the drawer
out, the solver sets the object on the bin's floor; an object lying in a slid-out drawer starts in its chest."""

from __future__ import annotations

import dataclasses
import json
import math
from types import SimpleNamespace as NS

import pytest
import torch

from gendex_envs.assets.catalog import get_asset
from gendex_envs.placement import Footprint, Item, in_drawer, place, starts_in
from gendex_envs.spec import ConditionSpec
from generator.backends.base import ModelRequest
from generator.backends.offline import OfflineBackend
from generator.backends.roles import DRAWER_OUT_M, RECEIVING_DRAWERS, drawer_spot
from generator.catalog_view import asset_dict, asset_dicts
from generator.errors import ProposalError
from generator.instruction import InstructionError, read_instruction
from generator.steps.propose import parse_proposal
from generator.steps.scene import adjust_sizes, out_of_drawer, parse_scene


def _guided(b: OfflineBackend, text: str) -> str:
    return b.complete(ModelRequest(step="propose_guided", prompt="", context={
        "reading": read_instruction(text, asset_dicts()).to_dict(), "assets": asset_dicts()})).text


def _scene(b: OfflineBackend, p):
    ids = {o.asset for o in p.objects}
    context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
               "candidate_index": 0, "index": 0, "attempt": 0}
    return adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p), p)


def test_every_drawer_of_a_chest_holds_a_bin_in_its_link_frame():
    """The manifest says where each drawer's bin is (its floor's top to its walls' top) and where its link sits."""
    for asset_id in RECEIVING_DRAWERS:
        rec = get_asset(asset_id)
        assert all(j.holds_m is not None and j.link_origin_m is not None for j in rec.joints), asset_id
        for j in rec.joints:
            (x0, y0, z0), (x1, y1, z1) = j.holds_m
            assert 0 < x0 < x1 and y0 < 0 < y1 and 0 < z0 < z1 <= 0.2, (asset_id, j.name)
    for asset_id in ("cabinet_left_hinge", "box_with_lid_small", "microwave_compact"):
        assert all(j.holds_m is None for j in get_asset(asset_id).joints)  # a door or a lid holds nothing


def test_a_put_into_a_drawer_slides_it_out_and_succeeds_in_its_bin_open_or_shut():
    """*Put the lemon in the drawer*: the success is inside the drawer's bin (its joint named); the drawer starts
    28 cm out, the chest's other drawers shut; at reset the lemon is not in it, set on the bin's floor it is, on the
    table in front of the drawer it is not, and pushed shut with the drawer it still is."""
    from gendex_envs.holds import holds_point
    from gendex_envs.success import _holds
    from gendex_envs.task_env import TaskEnv

    b = OfflineBackend(seed=3)
    p = parse_proposal(_guided(b, "put the lemon in the bottom drawer of the two-drawer dresser"))
    assert (p.success["type"], p.success["target"], p.success["joint"]) == ("inside", "drawer_chest", "drawer_1_slide")
    assert "bottom drawer" in p.description
    spec = _scene(b, p)
    chest = next(o for o in spec.objects if o.name == "drawer_chest")
    assert chest.asset == "drawer_chest_2" and chest.joint_state == {"drawer_0_slide": 0.0,
                                                                    "drawer_1_slide": DRAWER_OUT_M}
    cond = next(c for c in spec.success.conditions if c.type == "inside")
    env = TaskEnv(task_spec=spec, obs_mode="none", render_backend="none")
    try:
        env.reset(seed=0)
        assert not bool(_holds(env, cond)[0])
        lemon = env.obj("lemon")

        def put(p_new) -> bool:
            lemon.set_pose(type(lemon.pose).create_from_pq(p_new[None], lemon.pose.q))
            return bool(_holds(env, cond)[0])

        floor = holds_point(env, "drawer_chest", "drawer_1_slide")[0]
        assert put(floor + torch.tensor([0.0, 0.0, 0.005]))
        assert not put(floor + torch.tensor([-0.3, 0.0, 0.0]))  # in front of the drawer
        assert not put(floor + torch.tensor([0.0, 0.0, 0.25]))  # above its walls
        put(floor + torch.tensor([0.0, 0.0, 0.005]))
        env.articulations["drawer_chest"].set_qpos(torch.zeros(1, 2))  # shut, the lemon carried in with it
        inside = floor + torch.tensor([DRAWER_OUT_M, 0.0, 0.005])
        assert put(inside)
    finally:
        env.close()


def test_the_drawer_s_place_chooses_the_chest_and_a_close_step_shuts_it_after():
    """*top drawer*: only a chest whose drawer the author fills is its top one (the one-drawer chest); *and close
    it*: a second part shuts the drawer, which starts as far out as its shutting was measured from."""
    r = read_instruction("put the can in the top drawer", asset_dicts())
    assert [m.asset for m in r.objects] == ["can", "drawer_chest_1"] and not r.notes
    b = OfflineBackend(seed=5)
    raw = json.loads(_guided(b, "put the apple in the drawer and close it").split("```json\n")[1].split("```")[0])
    assert [s["skill"] for s in raw["steps"]] == ["reach", "grasp", "carry", "release", "reach", "grasp", "close"]
    assert [(c["type"], c.get("joint"), c.get("negate")) for c in (raw["success"], *raw["also"])] == [
        ("inside", "drawer_0_slide", None), ("joint_open", None, True)]


def test_taking_out_of_a_drawer_is_read_and_refused_by_the_offline_author_with_the_measurement():
    r = read_instruction("take the can out of the bottom drawer", asset_dicts())
    assert (r.skill, r.objects[1].asset.startswith("drawer_chest")) == ("take_out", True)
    with pytest.raises(InstructionError, match="does not take things out of a drawer yet.*0 of 12"):
        _guided(OfflineBackend(seed=1), "take the can out of the bottom drawer")


def test_a_proposal_s_joint_names_a_drawer_of_an_inside_target_only():
    base = {"name": "PutCanInDrawer", "description": "Put the can in the drawer.", "success_text": "In it.",
            "objects": [{"name": "can", "asset": "can", "role": "graspable"},
                        {"name": "chest", "asset": "drawer_chest_1", "role": "articulated"}],
            "steps": [{"skill": "reach", "target": "can", "control_joint": "arm", "instruction": "Reach."}]}
    ok = parse_proposal(json.dumps(base | {"success": {"type": "inside", "object": "can", "target": "chest",
                                                       "joint": "drawer_0_slide"}}))
    assert ok.success["joint"] == "drawer_0_slide"
    for bad, why in (({"type": "inside", "object": "can", "target": "chest", "joint": "lid_hinge"},
                      "not a drawer of 'chest'.*allowed: \\['drawer_0_slide'\\]"),
                     ({"type": "joint_open", "object": "chest", "min_fraction": 0.8, "joint": "drawer_0_slide"},
                      "only for 'inside'")):
        with pytest.raises(ProposalError, match=why):
            parse_proposal(json.dumps(base | {"success": bad}))


def test_an_object_in_a_slid_out_drawer_starts_in_its_chest_and_turns_with_it():
    """The chest's closed box leaves out its slid-out drawer; the object on the drawer's floor starts in the chest
    (it moves and turns with it at reset), one on the table in front of it does not, nor one over a shut drawer."""
    rec = {"chest": get_asset("drawer_chest_1"), "can": get_asset("can")}
    sx, sy, sz = drawer_spot(asset_dict("drawer_chest_1"), DRAWER_OUT_M)
    half = math.radians(30) / 2
    chest = NS(name="chest", pos_m=(0.6, 0.1, 0.0), quat_wxyz=(math.cos(half), 0.0, 0.0, math.sin(half)),
               scale=1.0, joint_state={"drawer_0_slide": DRAWER_OUT_M})
    at = (0.6 + math.cos(2 * half) * sx - math.sin(2 * half) * sy, 0.1 + math.sin(2 * half) * sx, sz)
    can = NS(name="can", pos_m=at, scale=1.0)
    assert in_drawer(can, chest, rec["chest"]) and starts_in(can, [can, chest], rec) == "chest"
    assert starts_in(NS(name="can", pos_m=(at[0] - 0.25, at[1], sz), scale=1.0), [chest], rec) is None
    shut = NS(**{**vars(chest), "joint_state": {"drawer_0_slide": 0.0}})
    assert starts_in(can, [can, shut], rec) is None
    torch.manual_seed(0)
    items = [Item("can", at[:2], (0.0, 0.0), 0.0, Footprint((0.0, 0.0), (0.03, 0.03)), starts_in="chest"),
             Item("chest", (0.6, 0.1), (0.05, 0.05), math.radians(15), Footprint((0.0, 0.0), (0.2, 0.2)), True)]
    noise = place(items, 200, (0.8, 0.6))
    (dxy, dyaw), (cxy, _) = noise["chest"], noise["can"]
    rel = torch.tensor(at[:2]) - torch.tensor((0.6, 0.1))
    turned = torch.stack([torch.cos(dyaw) * rel[0] - torch.sin(dyaw) * rel[1],
                          torch.sin(dyaw) * rel[0] + torch.cos(dyaw) * rel[1]], dim=-1)
    assert torch.allclose(cxy, dxy + turned - rel, atol=1e-6) and dyaw.abs().max() > 0.1


def test_a_take_out_of_a_drawer_is_not_met_by_the_object_lying_in_it():
    """Beside the chest is a band of distances from its middle that the slid-out drawer lies in too: the scene
    adds the drawer's ``inside`` negated (a model-written take-out; the offline author refuses them)."""
    from gendex_envs.spec import parse_task_spec

    sx, sy, sz = drawer_spot(asset_dict("drawer_chest_1"), DRAWER_OUT_M)
    raw = {"name": "TakeCanOutOfDrawer", "instruction": "Take the can out of the drawer.",
           "objects": [{"name": "can", "asset": "can", "pos_m": [0.6 + sx, 0.15 + sy, sz]},
                       {"name": "chest", "asset": "drawer_chest_1", "pos_m": [0.6, 0.15, 0.0], "fixed": True,
                        "joint_state": {"drawer_0_slide": DRAWER_OUT_M}}],
           "stages": [{"name": "reach_can", "instruction": "Reach.", "skill": "reach", "method": "motion_planning",
                       "control_joint": "arm", "horizon": 60, "target": "can"}],
           "success": {"description": "Out.", "conditions": [
               {"type": "placed", "object": "can", "target": "chest", "relation": "next_to", "min_gap_m": 0.29,
                "max_gap_m": 0.59}]}}
    spec = out_of_drawer(parse_task_spec(raw))
    assert spec.success.conditions[-1] == ConditionSpec(type="inside", object="can", target="chest",
                                                        joint="drawer_0_slide", negate=True)
    raw["objects"][0]["pos_m"] = [0.2, -0.2, 0.0]  # on the table: nothing to add
    assert len(out_of_drawer(parse_task_spec(raw)).success.conditions) == 1


def test_a_drawer_the_author_may_empty_starts_the_object_in_it_and_its_success_is_out_of_it(monkeypatch):
    """What the author writes for a chest it takes things out of (none is measured good enough yet, so the set is
    patched here): the can on the floor of the slid-out drawer, in it at every reset wherever the chest is drawn,
    and the success (beside the chest, not in the drawer) false there."""
    import generator.backends.offline as offline
    from gendex_envs.holds import in_holds
    from gendex_envs.success import conditions_hold
    from gendex_envs.task_env import TaskEnv

    monkeypatch.setattr(offline, "EMPTIED_DRAWERS", frozenset(RECEIVING_DRAWERS))
    b = OfflineBackend(seed=2)
    p = parse_proposal(_guided(b, "take the can out of the bottom drawer of the three-drawer chest"))
    assert p.objects[0].starts_in == "drawer_chest" and "bottom drawer" in p.description
    spec = _scene(b, p)
    assert [(c.type, c.negate) for c in spec.success.conditions] == [("placed", False), ("inside", True),
                                                                     ("released", False)]
    env = TaskEnv(task_spec=spec, obs_mode="none", render_backend="none")
    try:
        for seed in range(3):
            env.reset(seed=seed)
            assert bool(in_holds(env, "drawer_chest", "drawer_2_slide", env.obj_pose("can").p)[0]), seed
            assert not bool(conditions_hold(env, spec.success.conditions)[0]), seed
    finally:
        env.close()


def test_an_object_taller_than_a_drawer_s_walls_is_not_put_in_it():
    """The cracker box (21 cm) slipped on the carry over the chest (1 of 4 in a batch's gate); the bottle (22 cm)
    stands as far above the walls: refused, naming what it can go in instead."""
    with pytest.raises(InstructionError, match="'drawer' .* cannot be the container it fits in.*trash_can_tall"):
        _guided(OfflineBackend(seed=1), "put the bottle in the drawer")
    parse_proposal(_guided(OfflineBackend(seed=1), "put the sugar box in the drawer"))  # 17.5 cm: in chest 1's


def test_an_object_longer_than_12_cm_is_not_put_in_a_drawer():
    """A banana (18 cm) was let go inside the one-drawer chest's drawer 7 of 16 gate attempts: refused, naming
    what it can go in instead; the toy duck (11.3 cm) still goes in."""
    with pytest.raises(InstructionError, match="'drawer' .* cannot be the container it fits in.*box_with_lid_large"):
        _guided(OfflineBackend(seed=1), "put the banana in the drawer")
    parse_proposal(_guided(OfflineBackend(seed=1), "put the rubber duck in the drawer"))


@pytest.mark.parametrize("seed", range(6))
def test_what_goes_into_a_drawer_starts_before_the_chest_clear_of_its_slid_out_drawer(seed):
    """The slid-out drawer reaches x = 0.15: a block at x 0.08 was held 3 of 10 attempts, at x -0.06 9 of 10. The
    object (and any clutter) starts at x -0.14..-0.06, well short of the drawer even at its randomization."""
    from generator.backends.offline_scene import DRAWER_FRONT_REGION_M

    b = OfflineBackend(seed=seed)
    p = parse_proposal(_guided(b, "put the plum in the drawer"))
    spec = _scene(b, p)
    (x0, x1), (y0, y1) = DRAWER_FRONT_REGION_M
    chest = next(o for o in spec.objects if o.name == "drawer_chest")
    for o in spec.objects:
        if o is chest:
            continue
        x, y, _ = o.pos_m
        assert x0 - 1e-9 <= x <= x1 + 1e-9 and y0 - 1e-9 <= y <= y1 + 1e-9, (o.name, o.pos_m)
        front = chest.pos_m[0] - chest.randomize.xy_m[0] - 0.19 - DRAWER_OUT_M  # the drawer's front, nearest draw
        assert x + o.randomize.xy_m[0] < front - 0.05, (o.name, x, front)


def test_an_object_the_solver_lifts_but_does_not_carry_is_lifted_and_never_set_down():
    """The cracker box was carried and set down at 15 of 23 gate attempts (a tray, a drawer, a plate), lifted 10/10:
    the author lifts it, refuses to set it anywhere with the measurement, and never draws it for a carry."""
    from generator.backends.roles import CARRY_FALLS_SHORT

    assert "cracker_box" in CARRY_FALLS_SHORT
    assert parse_proposal(_guided(OfflineBackend(seed=1), "lift the cracker box")).name == "LiftCrackerBox"
    for text in ("set the cracker box on the tray", "put the cracker box in the large bowl",
                 "hand me the cracker box", "put the cracker box to the left of the bowl"):
        with pytest.raises(InstructionError, match=r"cannot be the object .*lifted, not carried: carried and set down"):
            _guided(OfflineBackend(seed=1), text)
    options = OfflineBackend(seed=1).task_options(list(asset_dicts()))
    with_box = {k for k, raw in options if any(o["asset"] == "cracker_box" for o in raw["objects"])}
    assert with_box <= {"lift", "composed"}, with_box
    assert all(raw["steps"][-1]["skill"] != "release" for k, raw in options if k == "composed"
               and any(o["asset"] == "cracker_box" for o in raw["objects"])), "a composed task sets it down"
