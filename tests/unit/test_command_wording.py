"""Other wordings of a command (generator.command_wording): templates, names and verbs swapped, and only what the
instruction reader reads as the very same task kept."""

from __future__ import annotations

import pytest

from generator.catalog_view import asset_dicts
from generator.command_wording import PLACES, STEP_JOINER, clause_wordings, names, places, reading_key, wordings
from generator.instruction import read_instruction

ASSETS = asset_dicts()


def _key(text: str) -> tuple:
    return reading_key(read_instruction(text, ASSETS))


@pytest.mark.parametrize("command", [
    "deposit the plum in the serving bowl",
    "swing the open compact microwave door closed, then lay the toy block on the chopping board",
    "put the tennis ball to the left of the mixing bowl",
    "set the red block on the far right corner of the table",
    "transfer both fruits into the pot",
])
def test_every_wording_reads_as_the_command_and_the_command_comes_first(command):
    out = wordings(command, ASSETS)
    assert out[0] == command and len(out) == len(set(out))
    assert len(out) >= 3, out  # a template, a name or a verb swapped at least
    want = _key(command)
    for text in out:
        assert _key(text) == want, text
        assert text.count(STEP_JOINER) == command.count(STEP_JOINER), text


def test_a_wording_the_reader_reads_otherwise_is_dropped():
    # 'the bowl' may be either of the catalog's bowls, 'the serving bowl' only one of them: another task
    candidates = clause_wordings("drop the apple in the bowl")
    assert "drop the apple in the serving bowl" in candidates
    out = wordings("drop the apple in the bowl", ASSETS)
    assert "drop the apple in the serving bowl" not in out and len(out) < len(candidates)
    assert _key("drop the apple in the serving bowl") != _key("drop the apple in the bowl")
    assert any(t.startswith(("transfer", "deposit", "pop", "stow", "tuck", "store")) for t in out)
    # a verb of setting down is not offered for putting into (the reader would read a place on the bowl)
    assert not any(t.startswith(("lay ", "rest ")) for t in out)


def test_a_place_never_splits_an_objects_name_and_words_before_a_name_are_kept():
    for text in wordings("place the tennis ball on the near left corner of the table", ASSETS):
        assert "tennis ball" in text and "near left corner" in text, text
    assert {"red bowl", "red serving bowl", "red mixing bowl"} <= set(names("red mixing bowl"))
    assert names("left-hinged cupboard")[:2] == ["left-hinged cupboard", "left-hinged cabinet"]
    assert names("spatula") == ["spatula"]  # no other words for it: kept
    possessive = clause_wordings("shut the lid of the large storage box")
    assert "shut the large storage box's lid" in possessive
    assert not any("box with a lid's" in t or "drawers's" in t for t in possessive), possessive


def test_a_command_the_reader_cannot_read_keeps_its_words():
    assert wordings("juggle the three oranges", ASSETS) == ["juggle the three oranges"]


def test_a_long_command_is_sampled_by_seed_within_the_limit():
    command = ("push the compact microwave's door shut, then drop the cube in the saucepan, then set the plum down on "
               "the dish")
    a = wordings(command, ASSETS, limit=30, seed=1)
    assert a == wordings(command, ASSETS, limit=30, seed=1)
    assert 1 < len(a) <= 31 and a[0] == command
    assert a != wordings(command, ASSETS, limit=30, seed=2)


def test_a_place_is_said_the_other_ways_of_its_relation_and_a_region_stays_on_the_table():
    behind = places("behind the serving bowl")
    assert {"just behind the serving bowl", "on the far side of the bowl", "just behind the mixing bowl"} <= set(behind)
    assert all(not p.startswith(("next to", "to the left", "in front")) for p in behind)
    both = places("between the tray and the serving bowl")
    assert "in between the serving tray and the bowl" in both
    # a region of the table is never said as a side of the table ('in front of the table' is off it)
    assert places("on the near side of the table") == ["on the near side of the table"]
    assert places("on the far right corner of the table") == ["on the far right corner of the table",
                                                              "in the far right corner of the table"]
    assert not any(p.startswith("at ") for row in PLACES for p in row)  # 'move the ball at the corner
    out = wordings("set the lemon next to the dinner plate", ASSETS)
    assert {"set the lemon beside the dinner plate", "set the lemon near the dinner plate"} <= set(out)
    assert len({_key(t) for t in out}) == 1
