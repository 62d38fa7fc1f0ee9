"""Groups of objects said by a kind or a plural (*put all the fruit in the pot*): read as one step per object drawn
from the catalog, built with every one of them and no other object of the kind on the table."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from generator.backends.offline import OfflineBackend
from generator.backends.offline_scene import scene_spec
from generator.catalog_view import asset_dicts
from generator.errors import InstructionError, SceneError
from generator.groups import ALL_COUNT, covered, find_group, group_kinds, side_by_side
from generator.instruction import read_instruction
from generator.steps.propose import propose
from generator.steps.scene import parse_scene

A = {a["id"]: a for a in asset_dicts()}


@pytest.mark.parametrize("words, noun, count, exclusive", [
    ("all the fruit", "fruit", None, True), ("all of the toys", "toy", None, True), ("every ball", "ball", None, True),
    ("both balls", "ball", 2, True), ("the two blocks", "block", 2, True), ("three balls", "ball", 3, False),
    ("the balls", "ball", None, True), ("the peaches", "peach", None, True),
])
def test_a_group_is_a_quantifier_or_a_plural_and_one_noun(words, noun, count, exclusive):
    g = find_group(words)
    assert (g.noun, g.count, g.exclusive) == (noun, count, exclusive)


@pytest.mark.parametrize("words", ["the fruit", "the ball", "the lemon and the plum", "the glass", "a ball",
                                   "the tennis balls", "every balls"])
def test_one_object_a_list_or_a_longer_name_is_no_group(words):
    assert find_group(words) is None


def _members(text: str) -> list:
    r = read_instruction(text, list(A.values()))
    return [s.objects[0] for s in (r, *r.then)], r


def test_all_the_fruit_is_distinct_fruit_each_marked_and_named_in_a_note():
    members, r = _members("put all the fruit in the large bowl")
    ids = [m.asset for m in members]
    assert len(ids) == ALL_COUNT and len({A[i]["category"] for i in ids}) == ALL_COUNT
    assert all("fruit" in A[i]["tags"] and m.group == "all the fruit" and m.how == "kind"
               for i, m in zip(ids, members, strict=True))
    assert all(s.skill == "put_in" and s.objects[1].asset == "bowl_large" for s in (r, *r.then))
    assert any(", ".join(ids) in n and "no other fruit" in n for n in r.notes)
    assert _members("put all the fruit in the large bowl")[0] == members  # the same request reads the same


def test_a_group_put_in_a_container_holds_only_as_many_as_lie_side_by_side():
    members, _ = _members("put all the fruit in the pot")  # 16 cm across: as many of the fruits drawn as lie in it
    assert 2 <= len(members) <= ALL_COUNT and side_by_side([A[m.asset] for m in members], A["pot"])
    assert not side_by_side([A["apple"], A["orange"], A["pear"]], A["pot"])
    assert side_by_side([A["apple"], A["orange"], A["pear"]], A["bowl_large"])


@pytest.mark.parametrize("text, says", [
    ("put the five balls in the pot", "several objects ('five balls')"),
    ("put all the gadgets in the bowl", "'gadget' is not in the catalog"),
    ("put both apples on the plate", "asks for 2 apples"),
    ("pick up all the balls", "several objects ('all balls')"),
])
def test_a_group_the_author_cannot_build_is_refused_saying_why(text, says):
    with pytest.raises(InstructionError, match=says.replace("(", r"\(").replace(")", r"\)")):
        read_instruction(text, list(A.values()))


def test_the_offline_author_builds_every_member_and_says_the_group():
    p, _ = propose(OfflineBackend(seed=3), instruction="put both balls in the large bowl")
    members = [m["asset"] for s in (p.reading, *p.reading["then"]) for m in s["objects"][:1]]
    assert [o.asset for o in p.objects if o.role == "graspable"] == members
    assert p.description.startswith("Put both balls") or "both balls" in p.description
    two, _ = propose(OfflineBackend(seed=3), instruction="set the two blocks down on the tray")
    blocks = [o for o in two.objects if o.asset.startswith("block_")]
    assert len(blocks) == 2 and len({o.name for o in blocks}) == 2  # two blocks, named apart


def test_a_group_draws_only_objects_the_author_carries():
    """*the two boxes* once drew the cracker box, which the author lifts but does not carry; the author then built the
    first box as an apple (its alphabetical stand-in). The group draws boxes it sets down, and builds them."""
    members, _ = _members("set the two boxes on the tray")
    assert len(members) == 2 and "cracker_box" not in {m.asset for m in members}
    p, _ = propose(OfflineBackend(seed=0), instruction="set the two boxes on the tray")
    assert sorted(o.asset for o in p.objects if o.role == "graspable") == sorted(m.asset for m in members)
    assert all(A[o.asset]["category"].endswith("box") for o in p.objects if o.role == "graspable")


def test_no_clutter_of_the_group_and_a_scene_with_some_is_refused():
    p, _ = propose(OfflineBackend(seed=3), instruction="put all the fruit in the large bowl")
    kinds = group_kinds(p.reading)
    assert kinds[0] == {"fruit"}
    proposal = dataclasses.asdict(p)
    for seed in range(40):  # the offline scene adds one object of clutter to some scenes: never a fruit
        text = scene_spec(proposal, A, np.random.default_rng(seed))
        spec = parse_scene(text, p)
        assert not any(o.distractor and covered(A[o.asset], kinds) for o in spec.objects)
    fruit = next(a for a in A.values() if "fruit" in a["tags"] and a["id"] not in {o.asset for o in p.objects})
    clutter = f"- {{name: distractor_x, asset: {fruit['id']}, distractor: true, pos_m: [0.3, 0.3, 0.0]}}\n"
    text = scene_spec(proposal, A, np.random.default_rng(0)).replace("objects:\n", "objects:\n" + clutter, 1)
    with pytest.raises(SceneError, match="of a group the request moves whole"):
        parse_scene(text, p)


@pytest.mark.parametrize("phrase, kind", [("grapefruit", "fruit"), ("football", "ball"), ("soda bottle", None),
                                          ("toy car", "toy")])
def test_an_object_the_catalog_lacks_stands_in_by_meaning_not_spelling(phrase, kind):
    r = read_instruction(f"pick up the {phrase}", list(A.values()))
    m = r.objects[0]
    assert m.how in ("substitute", "id", "name") and (kind is None or kind in A[m.asset]["tags"])
    assert not (phrase == "grapefruit" and m.asset == "paper_cup")  # the nearest by its letters


def test_nothing_near_in_meaning_is_refused_with_the_nearest_named():
    with pytest.raises(InstructionError, match=r"no graspable object is near it in meaning \(nearest: .* 0\.\d\d"):
        read_instruction("grab the saxophone", list(A.values()))


def test_every_word_is_read_or_said_not_read():
    r = read_instruction("gently put the lemon in the bowl", list(A.values()))
    assert any("not understood" in n and "'gently'" in n for n in r.notes)
    assert not read_instruction("could you please put the lemon in the bowl", list(A.values())).notes
