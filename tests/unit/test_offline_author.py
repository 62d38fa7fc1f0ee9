"""The offline author (not a language model): grounded, distinct, deterministic proposals; vetted reward code."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from gendex_envs.spec import parse_task_spec, spec_to_dict
from generator.backends.base import ModelRequest
from generator.backends.offline import TASK_KINDS, OfflineBackend
from generator.catalog_view import asset_dicts
from generator.errors import BackendError
from generator.instruction import InstructionError, read_instruction
from generator.reward_library import compose_stage_module, compose_task_module, roles_of
from generator.steps.propose import propose
from generator.steps.scene import adjust_sizes, parse_scene
from generator.steps.validate import check_reward_source


def _proposals(seed: int, n: int, kinds: tuple[str, ...] | None = None) -> list:
    b, existing, out = OfflineBackend(seed=seed, kinds=kinds), (), []
    for i in range(n):
        p, _ = propose(b, index=i, existing=existing)
        existing += (p.name,)
        out.append(p)
    return out


def test_proposals_are_grounded_distinct_and_reproducible():
    a, b = _proposals(0, 12), _proposals(0, 12)
    assert a == b
    assert len({p.name for p in a}) == 12
    ids = {d["id"] for d in asset_dicts()}
    assert all(o.asset in ids for p in a for o in p.objects)
    assert _proposals(1, 3) != a[:3]  # another seed, other tasks


def test_a_batch_can_be_held_to_some_kinds_of_task():
    kinds = ("place_at", "turn_off")
    got = _proposals(5, 6, kinds)
    assert all(p.success["type"] == "placed" or (p.success["type"] == "joint_open" and p.success.get("negate"))
               for p in got)
    assert {p.success["type"] for p in got} == {"placed", "joint_open"}  # both kinds are drawn
    with pytest.raises(BackendError, match="unknown kind.*'juggle'.*place_at"):
        OfflineBackend(kinds=("juggle",))


def test_guided_proposal_substitutes_the_closest_catalog_object():
    p, _ = propose(OfflineBackend(seed=0), instruction="grab the apricot")
    assert p.substitutions == {"apricot": p.objects[0].asset}
    assert "fruit" in next(d for d in asset_dicts() if d["id"] == p.objects[0].asset)["tags"]
    assert p.success["type"] == "lifted"


def test_composed_reward_modules_pass_the_static_validator_for_every_skill():
    b = OfflineBackend(seed=0)
    kinds = set()
    for i, p in enumerate(_proposals(0, 60)):
        ids = {o.asset for o in p.objects}
        context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
                   "candidate_index": 0, "index": i, "attempt": 0}
        text = b.complete(ModelRequest(step="scene", prompt="", context=context)).text
        spec = spec_to_dict(adjust_sizes(parse_scene(text, p), p))
        roles = roles_of(dataclasses.asdict(p))
        check_reward_source(compose_task_module(spec, roles))
        for st in spec["stages"]:
            if st["method"] == "RL":
                kinds.add(st["skill"])
                check_reward_source(compose_stage_module(spec, st["name"], roles), filename=st["name"])
    assert {"grasp", "lift", "release", "open"} <= kinds


def test_only_objects_the_solver_measurably_holds_are_proposed_for_grasping(tmp_path):
    from gendex.solve.lift_check import measured_graspable, measured_rates, write_record

    held = measured_graspable()
    below = {a for a, rate in measured_rates().items() if rate < 0.9}
    # the record's objects below 90 % (benchmarks/results/grasp.md, sessions 44 and 45), never proposed for grasping
    assert below == {"service_bell", "pool_ball", "beetroot", "paint_can", "paperweight", "teddy_bear_white", "yo_yo"}
    assert "wrench" in held  # 20/20 in the committed record (12/20 and 8/20 in the two before)
    assert {"fork", "hammer", "golf_ball", "knife", "spoon", "scissors"} <= held  # the scissors 19/20 since the hook
    rows = [{"asset": "apple", "held": 19, "attempts": 20, "scale": 1.0},
            {"asset": "fork", "held": 3, "attempts": 20, "scale": 1.0}]
    write_record(rows, [1, 2], tmp_path / "rec.json")
    assert measured_rates(tmp_path / "rec.json") == {"apple": 0.95, "fork": 0.15}
    assert measured_graspable(0.9, tmp_path / "rec.json") == {"apple"}
    write_record([{"asset": "fork", "held": 20, "attempts": 20, "scale": 1.0}], [5], tmp_path / "rec.json", merge=True)
    assert measured_graspable(0.9, tmp_path / "rec.json") == {"apple", "fork"}  # a run over some objects adds theirs
    for p in _proposals(7, 30):
        for o in p.objects:
            if o.role == "graspable":
                assert o.asset in held, (p.name, o.asset)
            assert o.asset not in below
    # the scene step randomizes every object as the solver issue asks
    b = OfflineBackend(seed=7)
    p = _proposals(7, 1)[0]
    ids = {o.asset for o in p.objects}
    context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
               "candidate_index": 0, "index": 0, "attempt": 0}
    spec = spec_to_dict(adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="",
                                                                          context=context)).text, p), p))
    inside = {o.name for o in p.objects if o.starts_in}  # moves with the container it starts in
    for obj in spec["objects"]:
        r = obj["randomize"]
        assert (min(r["xy_m"]) >= (0.05 if obj.get("fixed") else 0.08) or obj["name"] in inside) \
            and r["yaw_deg"] >= 15.0, obj


def test_the_size_step_fits_a_grasped_object_to_the_hand_as_the_grasp_benchmark_measures_it():
    """A grasped object wider than the hand is written at the scale ``benchmarks/grasp.py`` measured it at: one rule
    (:func:`gendex.solve.grasp.hand_fit_scale`) serves both, so the measured rates are those of the tasks' objects."""
    import pytest

    from gendex.solve.grasp import HAND_SPAN_M, hand_fit_scale
    from gendex.solve.lift_check import fitted_scale
    from gendex_envs.spec import parse_task_spec
    from generator.records import Proposal, ProposedObject, ProposedStep

    assert hand_fit_scale((0.05, 0.3)) == 1.0
    assert hand_fit_scale((0.3, 0.22)) == pytest.approx(HAND_SPAN_M / 0.22)
    assert hand_fit_scale((0.3, 0.22), scale=0.3) == 0.3  # already small enough: kept
    assert fitted_scale("apple") == 1.0
    size = next(d for d in asset_dicts() if d["id"] == "plate")["size_m"]
    assert fitted_scale("plate") == round(HAND_SPAN_M / min(size[:2]), 3) < 0.5
    spec = parse_task_spec({
        "name": "LiftPlate", "instruction": "Lift the plate.",
        "objects": [{"name": "plate", "asset": "plate", "pos_m": [0.1, 0.0, 0.0]}],
        "stages": [{"name": "grasp", "instruction": "Grasp the plate.", "skill": "grasp", "control_joint": "both",
                    "method": "motion_planning", "target": "plate"}],
        "success": {"description": "The plate is lifted.",
                    "conditions": [{"type": "lifted", "object": "plate", "min_height_m": 0.1}]}})
    proposal = Proposal("LiftPlate", "Lift the plate.", (ProposedObject("plate", "plate", "graspable"),),
                        (ProposedStep("grasp", "plate", "both", "Grasp the plate."),), {}, "lifted")
    assert adjust_sizes(spec, proposal).objects[0].scale == fitted_scale("plate")


def test_a_tall_appliance_is_scaled_down_but_keeps_a_handle_the_fingers_fit_behind():
    from gendex_envs.spec import parse_task_spec
    from generator.records import Proposal, ProposedObject, ProposedStep
    from generator.steps.scene import MAX_ARTICULATED_HEIGHT_M, MIN_ARTICULATED_SCALE

    def scaled(asset: str) -> float:
        spec = parse_task_spec({
            "name": "OpenIt", "instruction": "Open it.",
            "objects": [{"name": "it", "asset": asset, "pos_m": [0.5, 0.0, 0.0], "fixed": True}],
            "stages": [{"name": "open", "instruction": "Open it.", "skill": "open", "control_joint": "both",
                        "method": "motion_planning", "target": "it"}],
            "success": {"description": "It is open.",
                        "conditions": [{"type": "joint_open", "object": "it", "min_fraction": 0.5}]}})
        proposal = Proposal("OpenIt", "Open it.", (ProposedObject("it", asset, "articulated"),),
                            (ProposedStep("open", "it", "both", "Open it."),), {}, "joint_open")
        return adjust_sizes(spec, proposal).objects[0].scale

    fridge = next(d for d in asset_dicts() if d["id"] == "refrigerator_left_hinge")["size_m"][2]
    assert MAX_ARTICULATED_HEIGHT_M / fridge < MIN_ARTICULATED_SCALE  # the height rule alone would shrink it more
    assert scaled("refrigerator_left_hinge") == MIN_ARTICULATED_SCALE
    assert scaled("cabinet_left_hinge") == 1.0  # short enough: untouched


def test_every_skill_template_gives_a_valid_scene_and_vetted_reward_code():
    """Stack, push and every measured articulated layout (close a door or drawer, open or close a lid, turn a lever,
    unscrew a cap or screw it on):
    the scene parses with the task schema, starts the joint where the reference task measured it, and the composed
    reward modules pass the static validator (a shut joint rewards closing, a push rewards the object's way to the
    goal mark)."""
    from generator.backends.offline import ARTICULATED_LAYOUTS, _acts
    from generator.steps.propose import parse_proposal

    b = OfflineBackend(seed=3)
    options = [o for skill, o in b.task_options(list(asset_dicts())) if skill != "composed"]
    picked = [o for o in options if o["name"].startswith(("Stack", "Push", "Close", "Turn", "Press", "Unscrew",
                                                          "ScrewOn"))
              and not o["name"].endswith(("Half", "Degrees"))
              or (o["name"].startswith("Open") and o["objects"][0]["asset"] in {i for _, i in ARTICULATED_LAYOUTS})]
    kinds = {o["name"][:4] for o in picked}
    assert kinds == {"Stac", "Push", "Clos", "Turn", "Open", "Pres", "Unsc", "Scre"}, kinds
    laid_out = 0
    for i, raw in enumerate(picked):
        p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
        ids = {o.asset for o in p.objects}
        context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
                   "candidate_index": 0, "index": i, "attempt": 0}
        spec = spec_to_dict(adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="",
                                                                              context=context)).text, p), p))
        roles = roles_of(dataclasses.asdict(p))
        src = compose_task_module(spec, roles)
        check_reward_source(src)
        cond = spec["success"]["conditions"][0]
        if cond.get("negate"):
            assert "(1.0 - info[\"open_fraction\"])" in src
        if cond.get("target") == "goal":
            assert "goal" in spec and "env.goal_pos" in src
        acts = _acts(raw)  # a turn whose success is the joint shut is laid out as turn_off (lever starts open)
        for obj in spec["objects"]:
            layout = ARTICULATED_LAYOUTS.get((acts.get(obj["name"], ""), obj["asset"]))
            if layout:
                assert list(obj["joint_state"].values()) == [layout["start"]]
                assert abs(obj["pos_m"][0] - layout["pos_m"][0]) <= 0.02 + 1e-9
                laid_out += 1
    assert laid_out == len(ARTICULATED_LAYOUTS)


def test_a_lid_opened_before_other_steps_is_laid_out_where_it_can_be_pushed_past_its_balance():
    """A lid the hand leaves for other objects must stay open: the press follows it past its balance point, which
    the hand reaches with the large box further out and the tall bin nearer in (``composed_pos_m``)."""
    from gendex_envs.spec import parse_task_spec
    from generator.backends.offline import ARTICULATED_LAYOUTS
    from generator.critic.physical import check_scene_static
    from generator.steps.propose import parse_proposal

    b = OfflineBackend(seed=4)
    options = b.task_options(list(asset_dicts()))
    checked = set()
    for asset in ("box_with_lid_large", "trash_can_tall"):
        layout = ARTICULATED_LAYOUTS["open", asset]
        single = next(o for k, o in options if k != "composed" and o["objects"][0]["asset"] == asset
                      and o["name"].startswith("Open"))
        composed = next((o for k, o in options if k == "composed" and o["objects"][0]["asset"] == asset
                         and o["name"].startswith("Open")), None)
        assert (composed is None) == (layout.get("composed", True) is False)  # the grammar composes only these
        if composed is None:  # what a guided request for it would compose
            apple = next(a for a in asset_dicts() if a["id"] == "apple")
            composed = b._composed_task("open", next(a for a in asset_dicts() if a["id"] == asset), "lift", apple, None)
        for raw, where in ((single, layout["pos_m"]), (composed, layout["composed_pos_m"])):
            p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
            ids = {o.asset for o in p.objects}
            context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
                       "candidate_index": 0, "index": 0, "attempt": 0}
            spec = spec_to_dict(parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p))
            lid = next(o for o in spec["objects"] if o["asset"] == asset)
            assert np.allclose(lid["pos_m"][:2], where, atol=0.02 + 1e-9), (raw["name"], lid["pos_m"])
            checked.add(raw["name"])
            if asset == "box_with_lid_large":  # the physical critic leaves it there, however far out the jitter
                lid["pos_m"] = [where[0] + 0.02, where[1] + 0.02, 0.0]  # puts it (it moves an object in, not out)
                found = check_scene_static(parse_task_spec(spec)).violations
                assert not [v for v in found if v.check == "out_of_reach" and v.object == lid["name"]], found
    assert len(checked) == 4
    assert ARTICULATED_LAYOUTS["open", "box_with_lid_large"]["composed_pos_m"][0] > 0.5  # further out
    assert ARTICULATED_LAYOUTS["open", "trash_can_tall"]["composed_pos_m"][0] < 0.55  # nearer in


def test_scenes_may_carry_clutter_that_no_stage_or_condition_names():
    """About 40 % of the offline author's scenes with movable objects get one distractor: another kind of object
    the solver holds, marked ``distractor: true``; the scene step accepts up to MAX_DISTRACTORS of them and no more."""
    import yaml

    from generator.errors import SceneError
    from generator.steps.propose import parse_proposal
    from generator.steps.scene import MAX_DISTRACTORS

    b = OfflineBackend(seed=5)
    raw = next(o for skill, o in b.task_options(list(asset_dicts())) if skill == "put_in")
    p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
    ids = {o.asset for o in p.objects}
    seen = 0
    for k in range(12):
        context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
                   "candidate_index": k, "index": 0, "attempt": 0}
        text = b.complete(ModelRequest(step="scene", prompt="", context=context)).text
        spec = parse_scene(text, p)
        extra = [o for o in spec.objects if o.distractor]
        if extra:
            seen += 1
            [d] = extra
            assert d.asset not in ids and d.name.startswith("distractor_")
            assert all(s.target != d.name for s in spec.stages)
    assert 2 <= seen <= 10, seen
    raw = yaml.safe_load(text.split("```yaml\n", 1)[1].split("```", 1)[0])
    clutter = {"asset": "dice", "distractor": True, "pos_m": [0.0, 0.2, 0.0]}
    raw["objects"] += [dict(clutter, name=f"d{i}") for i in range(MAX_DISTRACTORS + 1)]
    with pytest.raises(SceneError, match="at most 2"):
        parse_scene("```yaml\n" + yaml.safe_dump(raw) + "```\n", p)


def test_clutter_in_a_composed_task_keeps_out_of_the_way_of_the_door_the_hand_works_first():
    """A distractor lemon laid in front of an open refrigerator was shoved by the closing door against its body, and
    the door stalled at 0.16 rad (goal 0.12; batch 103589, 2 of 12 dev seeds). Clutter now goes where the task's own
    movable objects go: in a composed task whose articulated object stands off the middle, the other half."""
    from generator.backends.offline_scene import _movable_region
    from generator.steps.propose import parse_proposal

    b = OfflineBackend(seed=7)
    composed = [o for skill, o in b.task_options(list(asset_dicts())) if skill == "composed"]
    sided = 0
    for i, raw in enumerate(composed[::max(1, len(composed) // 150)]):  # ~150 spread over the grammar's thousands
        p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
        ids = {o.asset for o in p.objects}
        for k in range(4):
            context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
                       "candidate_index": k, "index": i, "attempt": 0}
            spec = parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p)
            clutter = [o for o in spec.objects if o.distractor]
            if not clutter:
                continue
            [art] = [o for o in spec.objects if o.fixed and o.joint_state]
            acts = {s.target: s.skill for s in p.steps if s.skill in ("open", "close", "turn")}
            proposal = dataclasses.asdict(p)
            (x0, x1), (y0, y1) = _movable_region(proposal, {a["id"]: a for a in asset_dicts()}, acts)
            x, y, _ = clutter[0].pos_m
            assert x0 <= x <= x1 and y0 <= y <= y1, (p.name, clutter[0].pos_m, art.pos_m)
            if y1 <= 0.0 or y0 >= 0.0:
                sided += 1
                assert y * art.pos_m[1] <= 0.0  # the other half from the articulated object
    assert sided >= 3, sided


def test_composed_tasks_do_two_parts_in_turn_and_check_both():
    """A composed task: a part the open hand does on an articulated object (close a door, open a lid, turn a lever),
    then a rigid one (lift, put into, set on). Both conditions are the task's success (``success`` and ``also``),
    the steps are the two parts' in order, the wording says both, and every reward module passes the validator."""
    from generator.novelty import proposal_signature
    from generator.steps.propose import parse_proposal

    b = OfflineBackend(seed=2)
    composed = [o for skill, o in b.task_options(list(asset_dicts())) if skill == "composed"]
    assert len(composed) >= 50
    for i, raw in enumerate(composed[::max(1, len(composed) // 80)]):  # ~80 spread over the grammar's thousands
        p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
        assert len(p.conditions) == 2 and p.conditions[0]["type"] == "joint_open", p.name
        assert [s.skill for s in p.steps][0] == "reach" and len(p.steps) >= 4
        assert ", then " in p.description and "Then" in p.name
        skills, _ = proposal_signature(dataclasses.asdict(p))
        assert len(skills) == 2, skills
        ids = {o.asset for o in p.objects}
        context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
                   "candidate_index": 0, "index": i, "attempt": 0}
        spec = spec_to_dict(adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="",
                                                                              context=context)).text, p), p))
        assert len([c for c in spec["success"]["conditions"] if c["type"] not in ("grasped", "released")]) == 2
        roles = roles_of(dataclasses.asdict(p))
        src = compose_task_module(spec, roles)
        check_reward_source(src)
        assert "open_fraction_0" in src and src.count("gate = gate * done") == 2  # the second part after the first
        for st in spec["stages"]:
            if st["method"] == "RL":
                check_reward_source(compose_stage_module(spec, st["name"], roles), filename=st["name"])
    with pytest.raises(Exception, match="also must be a list of at most 3"):
        raw = dict(composed[0], also=[composed[0]["success"]] * 4)
        parse_proposal("```json\n" + json.dumps(raw) + "\n```")


def test_a_lift_success_is_written_with_a_grasp_so_a_knocked_object_does_not_count():
    """Height alone was met by an object the arm knocked into the air (random actions: 19/50 on PickUpBottle-v1):
    the scene step adds a ``grasped`` condition for each lifted object, once, and leaves other successes alone."""
    from generator.steps.scene import LIFT_HOLD_FINGERS, hold_lifted

    proposals = _proposals(3, 80)  # every skill has its turn among 80 (17 kinds of task drawn evenly)
    p = next(p for p in proposals if p.success.get("type") == "lifted")
    b = OfflineBackend(seed=3)
    ids = {o.asset for o in p.objects}
    context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
               "candidate_index": 0, "index": 0, "attempt": 0}
    spec = parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p)
    conds = [(c.type, c.object, c.min_fingers) for c in spec.success.conditions]
    lifted = p.success["object"]
    assert ("grasped", lifted, LIFT_HOLD_FINGERS) in conds and ("lifted", lifted, None) in conds
    assert hold_lifted(spec) == spec  # already held: nothing added twice
    put = next(p for p in proposals if p.success.get("type") == "inside" and not p.also)
    context["proposal"] = dataclasses.asdict(put)
    context["assets"] = [a for a in asset_dicts() if a["id"] in {o.asset for o in put.objects}]
    other = parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, put)
    assert [c.type for c in other.success.conditions] == ["inside", "released"]  # and no grasp: see below


def test_a_set_down_success_is_written_with_a_release_held_while_it_settles():
    """A ball still in the hand over a cutting board, or one falling past it, met the board's ``near``: the scene
    step adds ``released`` for each object set in, on or by another, and makes the success hold for
    :data:`SETTLED_STEPS`; a push to the goal point and a success that holds its object are left alone."""
    from generator.steps.scene import SETTLED_STEPS, let_go

    proposals = _proposals(3, 80)
    b = OfflineBackend(seed=3)
    for kind in ("inside", "near", "placed"):
        p = next(p for p in proposals if p.success.get("type") == kind and p.success.get("target") != "goal"
                 and not p.also)
        context = {"proposal": dataclasses.asdict(p), "candidate_index": 0, "index": 0, "attempt": 0,
                   "assets": [a for a in asset_dicts() if a["id"] in {o.asset for o in p.objects}]}
        spec = parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p)
        conds = [(c.type, c.object, c.negate) for c in spec.success.conditions]
        assert conds == [(kind, p.success["object"], False), ("released", p.success["object"], False)], conds
        assert spec.success.hold_steps == SETTLED_STEPS
        assert let_go(spec) == spec  # nothing added twice
    raw = spec_to_dict(spec)
    raw["success"] = {"description": "pushed", "conditions": [{"type": "near", "object": p.success["object"],
                                                               "target": "goal", "max_dist_m": 0.04}]}
    raw["goal"] = {"pos_m": [0.1, 0.0, 0.0]}
    pushed = parse_task_spec(raw)
    assert let_go(pushed) == pushed


@pytest.mark.parametrize("text, asset", [("turn the faucet off", "faucet_lever_swivel"),
                                         ("close the valve", "valve_lever")])
def test_turning_off_starts_the_lever_open_and_succeeds_with_it_shut(text, asset):
    """'Off' is a turn back to the shut end: the lever starts at its open angle (the turn_off layout), the task's
    and the stage's conditions are the joint shut, the stage reward rises as it shuts, and the critic asks for
    nothing (the joint starts open, as a close wants it). Before, 'off' built the turn-on task."""
    from generator.backends.offline import ARTICULATED_LAYOUTS
    from generator.critic.physical import static_findings
    from generator.stage_goals import stage_goal
    from generator.steps.propose import parse_proposal

    reading = read_instruction(text, asset_dicts())
    assert reading.direction == "off"
    b = OfflineBackend(seed=4)
    raw = json.loads(b.complete(ModelRequest(step="propose_guided", prompt="", context={
        "reading": reading.to_dict(), "assets": asset_dicts()})).text.split("```json\n")[1].split("```")[0])
    assert raw["objects"][0]["asset"] == asset and raw["name"].endswith("Off")
    assert raw["success"] == {"type": "joint_open", "object": raw["objects"][0]["name"], "min_fraction": 0.1,
                              "negate": True}
    assert " off" in raw["description"]
    p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
    context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] == asset],
               "candidate_index": 0, "index": 0, "attempt": 0}
    spec = adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p), p)
    (joint, start), = spec.objects[0].joint_state.items()
    assert start == ARTICULATED_LAYOUTS["turn_off", asset]["start"] == 1.2  # the lever's open angle
    violations, meas, _, _ = static_findings(spec, overlap=True)
    assert meas["joint_state"][spec.objects[0].name]["intent"] == "close"
    assert not [v for v in violations if v.check == "joint_state"]
    d = spec_to_dict(spec)
    turn = next(s for s in d["stages"] if s["skill"] == "turn")
    goal = stage_goal("turn", turn["target"], d["success"]["conditions"], articulated=True)
    assert goal == [{"type": "joint_open", "object": turn["target"], "min_fraction": 0.1, "negate": True}]
    src = compose_stage_module(d, turn["name"], roles_of(dataclasses.asdict(p)))
    assert '(1.0 - info["open_fraction"])' in src
    check_reward_source(src)


@pytest.mark.parametrize("text, asset, fraction", [
    ("open the drawer halfway", "drawer_chest_1", 0.5),
    ("open the cabinet door half way", "cabinet_left_hinge", 0.5),
    ("turn the valve 45 degrees", "valve_lever", round(np.radians(45) / 1.2, 3)),  # the lever's range is 1.2 rad
])
def test_a_part_way_request_sets_the_joint_there_and_holds_it(text, asset, fraction):
    """'Halfway' and '<n> degrees' become a joint_at condition at that fraction of the range (degrees from the shut
    end), the stage that moves the joint ends there too, and the success must hold 10 steps (a door swung through
    the band is not half open). Before, 'halfway' was refused."""
    from generator.phrasing import split
    from generator.stage_goals import stage_goal
    from generator.steps.propose import parse_proposal
    from generator.steps.scene import SETTLED_STEPS

    reading = read_instruction(text, asset_dicts())
    b = OfflineBackend(seed=5)
    raw = json.loads(b.complete(ModelRequest(step="propose_guided", prompt="", context={
        "reading": reading.to_dict(), "assets": asset_dicts()})).text.split("```json\n")[1].split("```")[0])
    n = raw["objects"][0]["name"]
    assert raw["objects"][0]["asset"] == asset
    assert raw["success"] == {"type": "joint_at", "object": n, "fraction": fraction, "max_error": 0.1}
    command = split(raw["description"])[1]  # without the situation and purpose framing it
    assert read_instruction(command, asset_dicts()).amount == reading.amount  # its wording reads back
    p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
    context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] == asset],
               "candidate_index": 0, "index": 0, "attempt": 0}
    spec = adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p), p)
    assert spec.success.hold_steps == SETTLED_STEPS
    d = spec_to_dict(spec)
    moving = next(s for s in d["stages"] if s["skill"] in ("open", "turn"))
    goal, = stage_goal(moving["skill"], n, d["success"]["conditions"], articulated=True)
    assert {k: v for k, v in goal.items() if v is not None and v is not False} == raw["success"]
    check_reward_source(compose_task_module(d, roles_of(dataclasses.asdict(p))))


@pytest.mark.parametrize("text, why", [
    ("turn the valve 80 degrees", "turns 69 degrees"),  # past the lever's range
    ("open the drawer 30 degrees", "slides"),
    ("open the trash can lid halfway", "part way"),  # a lid let go part way falls
])
def test_a_part_way_request_the_author_cannot_build_is_refused_saying_why(text, why):
    reading = read_instruction(text, asset_dicts())
    with pytest.raises(InstructionError, match=why):
        OfflineBackend(seed=5).complete(ModelRequest(step="propose_guided", prompt="", context={
            "reading": reading.to_dict(), "assets": asset_dicts()}))


@pytest.mark.parametrize("text", [
    "put the apple to the left of the bowl", "set the lemon to the right of the plate",
    "move the banana in front of the bowl", "put the can behind the pot", "place the pear next to the cup",
    "put the peach between the bowl and the mug", "put the orange on the far right corner of the table",
    "move the block to the near side of the table", "put the tennis ball in the middle of the table",
])
def test_a_place_request_becomes_a_placed_task_that_does_not_start_solved(text):
    """Each relation and region: the proposal's success is the reading's ``placed`` condition (gaps from the
    objects' sizes), its command reads back as the same place, the scene starts the object where the condition does
    not hold (also at the corners of the reset's randomization), nothing else stands at the set-down point, and the
    reward module aims the carry at that point."""
    import itertools

    import torch

    from gendex_envs.task_env import TaskEnv
    from generator.phrasing import split
    from generator.steps.propose import parse_proposal

    reading = read_instruction(text, asset_dicts())
    b = OfflineBackend(seed=6)
    raw = json.loads(b.complete(ModelRequest(step="propose_guided", prompt="", context={
        "reading": reading.to_dict(), "assets": asset_dicts()})).text.split("```json\n")[1].split("```")[0])
    cond = raw["success"]
    assert (cond["type"], cond["relation"], cond.get("region")) == ("placed", reading.relation, reading.region)
    back = read_instruction(split(raw["description"])[1], asset_dicts())
    assert (back.skill, back.relation, back.region) == ("place_at", reading.relation, reading.region)
    p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
    ids = {o.asset for o in p.objects}
    context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
               "candidate_index": 0, "index": 0, "attempt": 0}
    spec = adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p), p)
    assert not [o for o in spec.objects if o.distractor]
    src = compose_task_module(spec_to_dict(spec), roles_of(dataclasses.asdict(p)))
    check_reward_source(src)
    if cond["relation"] != "in_region":
        assert "torch.tensor" in src or "/ 2" in src  # a point beside or between, not the target itself
    # the condition is false at reset, at the nominal layout and with every object moved to a corner of its
    # randomization box
    from gendex_envs.success import _holds

    placed = next(c for c in spec.success.conditions if c.type == "placed")
    env = TaskEnv(task_spec=spec, obs_mode="none", render_backend="none")
    try:
        env.reset(seed=0)
        movable = [o for o in spec.objects if not o.fixed]
        for shifts in itertools.product((-0.08, 0.0, 0.08), repeat=2 * len(movable)):
            for k, o in enumerate(movable):
                pose = env.obj(o.name).pose
                p_new = torch.tensor([[o.pos_m[0] + shifts[2 * k], o.pos_m[1] + shifts[2 * k + 1],
                                       float(pose.p[0, 2])]])
                env.obj(o.name).set_pose(type(pose).create_from_pq(p_new, pose.q))
            assert not bool(_holds(env, placed)[0]), (text, shifts)
    finally:
        env.close()


def test_two_steps_in_order_are_one_composed_task_where_the_author_joins_them():
    """'Close X, then Y': each step is written as its own guided task and joined (both conditions, the steps in
    turn, the place laid out so it does not start met); steps it does not join are refused saying what it writes."""
    from generator.steps.propose import parse_proposal

    reading = read_instruction("shut the trash can lid, then put the lemon to the left of the bowl", asset_dicts())
    b = OfflineBackend(seed=7)
    raw = json.loads(b.complete(ModelRequest(step="propose_guided", prompt="", context={
        "reading": reading.to_dict(), "assets": asset_dicts()})).text.split("```json\n")[1].split("```")[0])
    assert raw["name"].startswith("CloseTrashCan") and "ThenSetLemonLeftOf" in raw["name"]
    assert [s["skill"] for s in raw["steps"]] == ["reach", "close", "reach", "grasp", "carry", "release"]
    assert raw["success"]["negate"] and raw["also"][0]["type"] == "placed"
    back = read_instruction(raw["description"].rstrip("."), asset_dicts())  # the command reads back, step by step
    assert [(r.skill, r.relation) for r in (back, *back.then)] == [("close", None), ("place_at", "left_of")]
    p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
    assert len(p.also) == 1
    def guided(text: str) -> dict:
        return json.loads(b.complete(ModelRequest(step="propose_guided", prompt="", context={
            "reading": read_instruction(text, asset_dicts()).to_dict(), "assets": asset_dicts()})).text.split(
                "```json\n")[1].split("```")[0])

    assert guided("pick up the apple, then put it in the bowl")["name"] == "PutAppleInBowl"  # the put lifts it
    two = guided("put the lemon and the plum in the bowl")  # one bowl, named once, worded the same both times
    assert [o["name"] for o in two["objects"]] == ["lemon", "bowl", "plum"]
    assert [c["type"] for c in (two["success"], *two["also"])] == ["inside", "inside"]
    bowl = [w for w in ("mixing bowl", "serving bowl", "bowl") if w in two["description"]][0]
    assert two["description"].count(bowl) == 2
    tower = guided("stack the three blocks into a tower")  # the middle block on the base first
    assert [(c["object"], c["target"]) for c in (tower["success"], *tower["also"])] == [
        ("block_medium", "block_large"), ("block_small", "block_medium")]
    for text, why in (("open the fridge, then close it", "steps in order only as"),
                      ("close the microwave, then lift the apple, then push the block to the goal", "last step only"),
                      ("put the apple in the bowl, then lift it", "move the same object")):
        with pytest.raises(InstructionError, match=why):
            guided(text)


def test_every_task_the_grammar_can_write_is_a_valid_proposal_with_distinct_object_names():
    """All of them, not a sample; and a requested place between two bowls (it once named both 'bowl')."""
    from generator.steps.propose import parse_proposal

    reading = read_instruction("put the apple between the bowl and the large bowl", asset_dicts())
    raw = json.loads(OfflineBackend(seed=3).complete(ModelRequest(step="propose_guided", prompt="", context={
        "reading": reading.to_dict(), "assets": asset_dicts()})).text.split("```json\n")[1].split("```")[0])
    p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
    assert [o.name for o in p.objects] == ["apple", "bowl", "bowl_large"]

    options = OfflineBackend(seed=1).task_options(list(asset_dicts()))
    kinds = {k for k, _ in options}
    from generator.backends.layouts import ARTICULATED_LAYOUTS

    part_turns = any(s == "turn" and lay["measured"] and not lay.get("part_way_failed")
                     for (s, _), lay in ARTICULATED_LAYOUTS.items())
    # the --kind option's list is what the grammar draws (a lever part way only where one is measured doing it)
    assert kinds == set(TASK_KINDS) - (set() if part_turns else {"turn_part"})
    for _, raw in options:
        p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
        assert len({o.name for o in p.objects}) == len(p.objects), raw["name"]
    assert len({raw["name"] for _, raw in options}) == len(options)


def test_a_take_out_starts_the_object_in_its_container_and_succeeds_with_it_beside():
    """*Take the can out of the bowl*: the can on the bowl's floor, moving with the bowl at reset; success is the can
    set down next to the bowl, false at every reset. An object whose top is level with the rim is refused (the
    fingers close on it above the rim: an apple in a bowl held 3 of 9 gate attempts, a can 6 of 6)."""
    import torch

    from gendex_envs.success import _holds
    from gendex_envs.task_env import TaskEnv
    from generator.critic.physical import CONTAINER_FLOOR_M
    from generator.steps.propose import parse_proposal

    b = OfflineBackend(seed=4)

    def guided(text: str) -> str:
        return b.complete(ModelRequest(step="propose_guided", prompt="", context={
            "reading": read_instruction(text, asset_dicts()).to_dict(), "assets": asset_dicts()})).text

    with pytest.raises(InstructionError, match="stand 3 cm above its rim.*takes out: .*candle, .*sugar_box"):
        guided("take the apple out of the bowl")
    # nor anything taller than the tallest taken out at the gate (the bottle slipped, the shampoo was not grasped)
    for tall in ("bottle", "shampoo bottle"):
        with pytest.raises(InstructionError, match="no taller than 19 cm"):
            guided(f"take the {tall} out of the bowl")
    p = parse_proposal(guided("take the can out of the bowl"))
    assert p.name == "TakeCanOutOfBowl" and p.objects[0].starts_in == "bowl"
    assert (p.success["type"], p.success["relation"], p.success["target"]) == ("placed", "next_to", "bowl")
    ids = {o.asset for o in p.objects}
    context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
               "candidate_index": 0, "index": 0, "attempt": 0}
    spec = adjust_sizes(parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p), p)
    can, bowl = (next(o for o in spec.objects if o.name == n) for n in ("can", "bowl"))
    assert can.pos_m[:2] == bowl.pos_m[:2] and can.pos_m[2] == CONTAINER_FLOOR_M and can.randomize.xy_m == (0, 0)
    placed = next(c for c in spec.success.conditions if c.type == "placed")
    env = TaskEnv(task_spec=spec, obs_mode="none", render_backend="none")
    try:
        for seed in range(4):
            env.reset(seed=seed)
            pc, pb = env.obj_pose("can").p[0], env.obj_pose("bowl").p[0]
            assert float(torch.linalg.norm(pc[:2] - pb[:2])) < 0.01  # in the bowl wherever the bowl was drawn
            assert not bool(_holds(env, placed)[0])
    finally:
        env.close()


def test_a_box_or_bin_with_a_lid_is_put_into_with_its_lid_open_and_shut_after_if_asked():
    """*Put the lemon in the box and shut the lid*: the box starts with its lid open (the layout its shutting was
    measured on), the lemon goes in, the open hand shuts the lid; both conditions are the task's success."""
    from generator.steps.propose import parse_proposal

    b = OfflineBackend(seed=5)

    def guided(text: str) -> dict:
        return json.loads(b.complete(ModelRequest(step="propose_guided", prompt="", context={
            "reading": read_instruction(text, asset_dicts()).to_dict(), "assets": asset_dicts()})).text.split(
                "```json\n")[1].split("```")[0])

    raw = guided("put the lemon in the box and shut the lid")
    assert [s["skill"] for s in raw["steps"]] == ["reach", "grasp", "carry", "release", "reach", "close"]
    assert [(c["type"], c.get("negate")) for c in (raw["success"], *raw["also"])] == [("inside", None),
                                                                                       ("joint_open", True)]
    assert raw["description"].count("lidded box") == 2  # one word for the box in both steps
    p = parse_proposal("```json\n" + json.dumps(raw) + "\n```")
    ids = {o.asset for o in p.objects}
    for text in ("put the lemon in the box and shut the lid", "put the apple in the small bin"):
        p = parse_proposal("```json\n" + json.dumps(guided(text)) + "\n```")
        ids = {o.asset for o in p.objects}
        context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
                   "candidate_index": 0, "index": 0, "attempt": 0}
        spec = parse_scene(b.complete(ModelRequest(step="scene", prompt="", context=context)).text, p)
        lidded = next(o for o in spec.objects if o.joint_state)
        assert next(iter(lidded.joint_state.values())) > 1.5, text  # the lid starts open
    with pytest.raises(InstructionError, match="opens a lid first or shuts it last, not both"):
        guided("open the small trash can, then put the apple in it, then close its lid")


@pytest.mark.parametrize("request_text, success, moved", [
    ("stack the rubik's cube on the large block", "over", "rubiks_cube"),
    ("push the rubik's cube to the target", "near", "rubiks_cube"),
])
def test_a_request_for_what_the_grammar_writes_by_itself_is_built(request_text, success, moved):
    """The autonomous grammar stacks a rubik's cube on the large block and pushes it (STACK_PAIRS, PUSHED); asked
    for in words, the same was refused ('it writes them with: block_large, ...')."""
    p, _ = propose(OfflineBackend(seed=3), instruction=request_text)
    assert not p.substitutions
    assert {o.asset for o in p.objects} >= {moved}
    assert p.success["object"] == next(o.name for o in p.objects if o.asset == moved)
    with pytest.raises(InstructionError, match="'dice' .*cannot be the block to stack"):  # never measured on one
        propose(OfflineBackend(seed=3), instruction="stack the dice on the large block")
