"""Requests of several steps: steps said in order (*A, then B*; *A and then B*), a step joined by *and* and a verb
(*put the dice in the box and shut the lid*), towers of blocks (*stack the three blocks into a tower*: one stack
reading, its objects top first) and several objects moved to one place (*put the lemon and the plum in
the bowl*: one put-in per object, in the order named). Each step is read on its own by the one-step reader; a
pronoun (*it*, *them*) or a bare part (*the lid*) in a step stands for an object of the step before it, the first that
can play its part in the step (*put the orange in the fridge and close it*: the fridge).

:mod:`generator.instruction` calls :func:`read_compound` before reading a request as one step."""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from generator.constructs import split_steps
from generator.errors import InstructionError
from generator.groups import read_group

if TYPE_CHECKING:
    from generator.instruction import Reading

GROUP_SKILLS = ("put_in", "place_on")
"""Skills whose request may name several objects for one place (*put the lemon and the plum in the bowl*)."""
PLACE_WORDS = ("into", "in", "inside", "onto", "on", "on top of")
"""Words that start the place of a put or a set-down (where a list of objects ends)."""
PARTICLES = ("down", "away", "back", "over", "up")
"""Words between the objects and the place that belong to the verb (*set the blocks down on the tray*)."""
TOWER_OF = {"blocks": "block", "cubes": "block"}
"""Plurals a tower is built of, and the catalog category they name."""
GROUP_WORD = re.compile(r"\b(\w+)\s+(\w+\s+)?(blocks|cubes)\b")
"""Blocks in the plural after a word (*stack the blocks*, *stack the three wooden cubes*): a tower without the word."""
NUMBERS = {**{w: i for i, w in enumerate("zero one two three four five six seven eight nine ten".split())},
           **{str(i): i for i in range(11)}}
"""How many blocks a tower request asks for (*the three blocks*, *4 cubes*)."""
GOES_ON = ("hold", "keep", "leave", "stay")
"""Verbs that go on with the step before rather than start one (*open the door halfway and hold it there*)."""
_PRONOUN = re.compile(r"\b(it|them)\b", re.IGNORECASE)
_BARE_PART = re.compile(r"\b(the|its)\s+(lid|door|drawer)\b", re.IGNORECASE)
_BARE_PLACE = re.compile(r"\b(in|inside|into|on|onto)$", re.IGNORECASE)
"""A step that ends at its place word (*open the bin, then drop the apple in*): the place is the step before's."""


def and_steps(text: str, starts_with_verb: Callable[[str], bool]) -> list[str]:
    """``text`` split where *and* or a comma is followed by a verb of a skill (*pick up the apple and put it in the
    bowl*, *open the drawer, put the ball inside*); one part when none is."""
    pieces = re.split(r"(\s*,?\s+and\s+|\s*,\s*)", text)
    out = [pieces[0]]
    for joiner, p in zip(pieces[1::2], pieces[2::2], strict=True):
        if p and starts_with_verb(p) and p.split()[0].lower() not in GOES_ON:
            out.append(p)
        else:
            out[-1] += joiner + p
    return out


def split_at_place(text: str, verb_end: int) -> tuple[list[str], list[str], list[str]] | None:
    """The words of ``text`` as (verb, objects, place): the place starts at the first of :data:`PLACE_WORDS` after
    an object; None when there is none. ``verb_end``: where the verb's words end."""
    words = text.split()
    verb, rest = words[:verb_end], words[verb_end:]
    at = next((i for i, w in enumerate(rest) if w.lower() in PLACE_WORDS and i > 0), None)
    return None if at is None else (verb, rest[:at], rest[at:])


def group_steps(text: str, verb_end: int) -> list[str]:
    """One step per object of a list before the place (*put the apple, the lemon and the plum in the bowl* -> three
    puts into the bowl); ``[text]`` when the request names one object. ``verb_end``: where the verb's words end."""
    parts = split_at_place(text, verb_end)
    if parts is None or "and" not in (w.lower() for w in parts[1]):
        return [text]
    verb, rest, after = parts
    at = len(rest)
    rest = rest + after
    items = [i.strip() for i in re.split(r"\s*,\s*(?:and\s+)?|\s+and\s+", " ".join(rest[:at])) if i.strip()]
    place = " ".join(rest[at:])
    return [" ".join([*verb, item, place]) for item in items] if len(items) > 1 else [text]


def _with_previous(step: str, previous: Reading, read_one: Callable[[str], Reading]) -> Reading:
    """``step`` read with its pronoun, bare part or bare place word standing for an object of ``previous``: the
    first of them that reads (the error of the first try when none does)."""
    pronoun, part, place = _PRONOUN.search(step), _BARE_PART.search(step), _BARE_PLACE.search(step)
    if pronoun is None and part is None and place is None:
        return read_one(step)
    if pronoun is not None:  # 'raise the pear clear of the table and keep hold of it': the step's own object
        try:
            own = read_one(step)
        except InstructionError:
            own = None
        before = step[:pronoun.start()].lower()
        if (own is not None and any(m.phrase in before for m in own.objects)
                and all(m.phrase in step.lower() for m in own.objects)):  # not 'put the apple in it' (a choice)
            return own
    first_error: InstructionError | None = None
    for m in previous.objects:
        name = f"the {m.color + ' ' if m.color else ''}{m.phrase}"
        said = part is not None and m.part == part.group(2) and name.endswith(" " + part.group(2))  # 'the drawer'
        whole = name if part is None or said else f"{name} {part.group(2)}"
        tried = (_PRONOUN.sub(name, step) if pronoun else _BARE_PART.sub(whole, step) if part
                 else f"{step} {name}")  # 'put the ball inside': inside the step before's object
        # ('close the drawer' after 'the drawer' stays that, not 'the drawer drawer')
        try:
            return read_one(tried)
        except InstructionError as exc:
            first_error = first_error or exc
    if part is not None and pronoun is None:
        return read_one(step)  # 'the lid' may name its object by itself
    assert first_error is not None
    raise first_error


def _same_step(a: Reading, b: Reading) -> bool:
    return (a.skill, [m.asset for m in a.objects], a.direction, a.amount, a.relation, a.region) == (
        b.skill, [m.asset for m in b.objects], b.direction, b.amount, b.relation, b.region)


def read_tower(text: str, assets: Sequence[dict]) -> Reading | None:
    """A tower of blocks (*stack the three blocks into a tower*, *build a tower of the small, medium and large
    blocks*): one ``stack`` reading whose objects go top first, the smallest on top; None when ``text`` asks for no
    tower; :class:`InstructionError` for a tower the catalog's blocks cannot make."""
    from generator.instruction import Mention, Reading

    words = re.findall(r"[a-z0-9]+", text.lower())
    plural = next((w for w in words if w in TOWER_OF), None)
    if plural is None or not ("tower" in words or (words[:1] == ["stack"] and GROUP_WORD.search(text.lower()))):
        return None
    blocks = sorted((a for a in assets if a["category"] == TOWER_OF[plural]), key=lambda a: a["size_m"][2])
    sizes = [w for w in words if w in ("small", "medium", "large")]
    count = next((NUMBERS[w] for w in words if w in NUMBERS), None)
    chosen = [a for a in blocks if any(a["id"].endswith("_" + z) for z in sizes)] if sizes else blocks
    from gendex_envs.attributes import COLOR_WORDS

    if any(w in COLOR_WORDS for w in words):
        raise InstructionError(f'"{text}": a tower of blocks named by colour is not built yet; name them by size '
                               "(small, medium, large) or by number")
    if count is not None and count != len(chosen):
        raise InstructionError(f'"{text}" asks for a tower of {count} {plural}: the catalog has {len(chosen)} '
                               f"({', '.join(a['id'] for a in chosen)}), each of another size")
    if len(chosen) < 2:
        raise InstructionError(f'"{text}": a tower needs two or more {plural}; the catalog has '
                               f"{', '.join(a['id'] for a in blocks)}")
    mentions = tuple(Mention(plural, a["id"], "name", options=(a["id"],)) for a in chosen)
    return Reading(text, "stack", mentions)


def read_compound(text: str, assets: Sequence[dict], read_one: Callable[[str], Reading],
                  starts_with_verb: Callable[[str], bool],
                  group_of: Callable[[str], tuple[str, int] | None]) -> Reading | None:
    """The reading of a request of several steps or objects (see the module docstring), or None when ``text`` is
    one step of one object. ``read_one`` reads one step, ``starts_with_verb`` tells whether a part begins with a
    skill's verb, and ``group_of`` gives the skill and verb end of a step (None: no verb)."""
    tower = read_tower(text, assets)
    if tower is not None:
        return tower
    ordered = split_steps(text)
    steps = [s for part in ordered for s in and_steps(part, starts_with_verb)]
    if len(steps) > len(ordered):  # split at 'and' + verb; where a part does not read ('grip the handle and pull
        try:                       # the door open'), the words around 'and' are one step
            return _read_steps(text, steps, read_one, group_of, assets)
        except InstructionError:
            if len(ordered) == 1:
                return None
    if len(ordered) == 1:
        readings = _group(text, read_one, group_of, assets)
        return None if readings is None else dataclasses.replace(readings[0], instruction=text,
                                                                 then=tuple(readings[1:]))
    return _read_steps(text, ordered, read_one, group_of, assets)


def _read_steps(text: str, steps: list[str], read_one: Callable[[str], Reading],
                group_of: Callable[[str], tuple[str, int] | None], assets: Sequence[dict]) -> Reading:
    """The reading of ``steps`` in order: a step of several objects is one step per object, each with its own
    words; a step said again in other words is one step."""
    readings: list[Reading] = []
    for step in steps:
        parts = _group(step, read_one, group_of, assets) or [
            _with_previous(step, readings[-1], read_one) if readings else read_one(step)]
        for part in parts:
            if readings and _same_step(readings[-1], part):
                continue  # 'take hold of the cube and raise it'
            readings.append(part)
    return dataclasses.replace(readings[0], instruction=text, then=tuple(readings[1:]))


def _group(text: str, read_one: Callable[[str], Reading], group_of: Callable[[str], tuple[str, int] | None],
           assets: Sequence[dict]) -> list[Reading] | None:
    """One reading per object of a step that moves several objects to one place (a list of them, or a group:
    :mod:`generator.groups`), or None (not such a step)."""
    found = group_of(text)
    if found is None or found[0] not in GROUP_SKILLS:
        return None
    parts = split_at_place(text, found[1])
    if parts is not None:
        verb, objects, place = parts
        while objects and objects[-1].lower() in PARTICLES:  # 'set the two blocks down on the tray'
            place = [objects.pop(), *place]
        grouped = read_group(text, verb, " ".join(objects), place, read_one, {a["id"]: a for a in assets})
        if grouped is not None:
            return grouped
    steps = group_steps(text, found[1])
    if len(steps) == 1:
        return None
    readings = [read_one(s) for s in steps]
    if len({(r.skill, r.objects[-1].asset) for r in readings}) != 1:
        return None  # not one place for all of them: read as one step (and refused there, saying why)
    return readings


__all__ = ["GROUP_SKILLS", "PARTICLES", "PLACE_WORDS", "TOWER_OF", "and_steps", "group_steps", "read_compound",
           "read_tower", "split_at_place"]
