"""Near-duplicate proposals are skipped: same skills on the same kinds of object, or an instruction that reads the
same (MiniLM cosine >= NEAR_DUPLICATE_COSINE)."""

from __future__ import annotations

import dataclasses

import pytest

from gendex_envs.registry import REPO_TASKS_DIR, resolve_task
from generator.backends.offline import OfflineBackend
from generator.novelty import Novelty, existing_tasks, proposal_signature, spec_signature
from generator.steps.propose import propose


@pytest.fixture(scope="module")
def novelty() -> Novelty:
    return Novelty(existing_tasks([REPO_TASKS_DIR]))


def _put(obj: str, into: str, text: str) -> dict:
    return {"name": "X", "description": text,
            "objects": [{"name": "a", "asset": obj, "role": "graspable"},
                        {"name": "b", "asset": into, "role": "container"}],
            "steps": [{"skill": "reach", "target": "a"}, {"skill": "grasp", "target": "a"},
                      {"skill": "carry", "target": "b"}, {"skill": "release", "target": "a"}],
            "success": {"type": "inside", "object": "a", "target": "b"}}


def test_signatures_of_a_proposal_and_of_its_committed_spec_agree():
    spec = resolve_task("GenDex/PutAppleBowl-v1").spec
    assert spec_signature(spec) == (("put_in",), ("apple", "bowl"))
    assert proposal_signature(_put("apple", "bowl", "")) == spec_signature(spec)
    # a rigid object is its category (the scanned apple is an apple); an articulated one is its model
    assert proposal_signature(_put("apple_scan", "bowl", ""))[1] == ("apple", "bowl")
    assert spec_signature(resolve_task("GenDex/CloseCabinet-v0").spec) == (("close_door",), ("cabinet_left_hinge",))


def test_near_duplicates_are_named_with_the_task_they_duplicate(novelty):
    same = _put("apple_scan", "bowl", "Drop the scanned apple in the bowl, for a healthy snack.")
    why = novelty.near_duplicate(proposal_signature(same), same["description"])
    assert why is not None and "GenDex/PutAppleBowl-v" in why and "same skills" in why  # one of its versions
    other = _put("peach", "pot", "Drop the peach in the pot, for a healthy snack.")  # no library task does
    assert novelty.near_duplicate(proposal_signature(other), other["description"]) is None


def test_an_instruction_that_reads_like_an_existing_one_is_a_near_duplicate(novelty):
    if novelty._emb is None:
        pytest.skip(f"MiniLM not installed ({novelty.embedding}): only the signature test runs")
    text = resolve_task("GenDex/PutAppleBowl-v1").spec.instruction
    why = novelty.near_duplicate((("lift",), ("peach",)), text)  # another task, worded exactly like one that exists
    assert why is not None and "reads like GenDex/PutAppleBowl-v" in why  # v1 or a later version worded alike


def test_the_offline_author_proposes_no_duplicate_of_the_library_or_of_its_own_batch():
    from generator.novelty import ExistingTask

    novelty = Novelty(existing_tasks([REPO_TASKS_DIR]))
    taken = {t.signature for t in novelty.existing}
    b, names = OfflineBackend(seed=11), ()
    for i in range(12):
        p, rejected = propose(b, index=i, existing=names, novelty=novelty)
        sig = proposal_signature(dataclasses.asdict(p))
        # the author steers clear of the library's signatures; a wording MiniLM finds too close to an existing
        # instruction (sibling models: left- and right-hinged fridges) is refused and proposed again
        assert sig not in taken, (p.name, rejected)
        assert all("reads like GenDex/" in r for r in rejected), rejected
        names += (p.name,)
        taken.add(sig)
        novelty.add(ExistingTask(f"GenDex/{p.name}-v0", sig, p.description))


def test_the_offline_author_widens_the_set_of_objects_the_library_uses():
    """Of a drawn skill's tasks the author proposes one that puts in its scene an object no existing task uses
    (``ctx["existing_assets"]``, handed over by the propose step from the library's specs); ``fresh_first`` keeps
    every proposal when none brings a new object."""
    import json

    from generator.backends.base import ModelRequest
    from generator.catalog_view import asset_dicts
    from generator.novelty import fresh_first, proposal_assets

    novelty = Novelty(existing_tasks([REPO_TASKS_DIR]))
    used = {a for t in novelty.existing for a in t.assets}
    assert "apple" in used and len(used) >= 100  # the committed library's assets are read from the specs
    everything = {a["id"] for a in asset_dicts()}
    for fresh in ("pear", "lime", "hourglass"):  # every lift but one is of a used object: that one is proposed
        ctx = {"assets": list(asset_dicts()), "existing_assets": sorted(everything - {fresh})}
        for seed in range(3):
            text = OfflineBackend(seed=seed, kinds=("lift",)).complete(
                ModelRequest(step="propose", prompt="", context=ctx)).text
            p = json.loads(text.split("```json")[1].split("```")[0])
            assert proposal_assets(p) == (fresh,), (fresh, p["name"])
    old = [_put("apple", "bowl", ""), _put("peach", "bowl", "")]
    assert fresh_first(old, {"apple", "bowl", "peach"}) == old
    assert fresh_first(old, {"apple", "bowl"}) == old[1:]


def test_an_extension_equals_adding_one_by_one_leaves_the_original_and_is_made_once(novelty):
    import numpy as np

    from generator.novelty import ExistingTask

    added = [ExistingTask(f"GenDex/Extra{i}-v0", (("lift",), (f"kind{i}",)), text) for i, text in
             enumerate(["Lift the purple teapot off the counter.", "Slide the sponge under the tap."])]
    by_add = Novelty(novelty.existing)
    for task in added:
        by_add.add(task)
    before = list(novelty.existing)
    one, two = novelty.extended(added[:1]), novelty.extended(added)
    assert two.existing == by_add.existing and np.array_equal(two._emb, by_add._emb)
    assert one.existing == by_add.existing[:-1] and novelty.existing == before
    assert novelty.extended(added) is two and novelty.extended(()) is novelty
    assert two.near_duplicate(("x",), added[1].instruction) is not None  # the added instruction is known


def test_a_part_way_or_turned_off_joint_is_another_task_than_all_the_way():
    """A half-open door and a lever turned off are new beside the open door and the lever turned on (before, the
    grammar's turn-offs and half-open doors were all skipped as duplicates of TurnFaucet and the open tasks)."""
    from generator.backends.offline import OfflineBackend
    from generator.catalog_view import asset_dicts
    from generator.novelty import proposal_signature

    by_kind: dict[str, set] = {}
    for k, p in OfflineBackend(seed=0).task_options(list(asset_dicts())):
        by_kind.setdefault(k, set()).add(proposal_signature(p))
    part_turns = by_kind.get("turn_part", set())  # none while no lever is measured turning part way
    assert by_kind["open_part"] and all(("part_way" in s[0]) for s in by_kind["open_part"] | part_turns)
    assert all(("off" in s[0]) for s in by_kind["turn_off"])
    assert not (by_kind["turn"] & (by_kind["turn_off"] | part_turns))
    assert not ((by_kind["open_door"] | by_kind["open_drawer"]) & by_kind["open_part"])
