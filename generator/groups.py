"""Groups of objects said by their kind or in the plural, moved to one place: *put all the fruit in the pot*, *put
both balls in the bowl*, *set the two blocks on the tray*, *drop every toy into the large bowl*.

A group is read as one put-in (or set-down) per object, in the order :func:`choose` draws them. Which objects make the
group is the reader's choice, recorded: each of them is a :class:`~generator.instruction.Mention` of ``how="kind"``
whose ``group`` is the person's phrase, and a note names them all. *All* (and *every*, *each*, a bare plural)
means the objects of that kind the scene holds: the reader draws up to :data:`ALL_COUNT` of them
(:data:`ALL_ON_SURFACE` on a plate, tray or board). A number (*the two balls*, *both*) is that many. A definite
group (*all*, *both*, *the two*) is every object of its kind on the table: the scene holds no clutter of it
(:func:`group_kinds`, checked by the scene step); *two balls* is any two.

The objects drawn are ones the solver holds (``generator.backends.roles.graspable``: >= 90 % of recorded grasps)
and carries to a place (``roles.carried``: not the cracker box) and, for a put-in, that fit in the container; of
different categories when the group is a kind (*the fruit*: a lemon, a plum and a peach, not two apples). The draw
is seeded by the request's words, so a request always reads the same and two requests differ."""

from __future__ import annotations

import dataclasses
import hashlib
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from generator.errors import InstructionError
from generator.vocabulary import KINDS

if TYPE_CHECKING:
    from generator.instruction import Reading

ALL_COUNT = 3
"""Objects *all the ...* draws: as many rigid steps as one task joins (``sequence.MAX_RIGID_STEPS``)..."""
ALL_ON_SURFACE = 2
"""...on a plate, tray or board, two: set down round its middle, the third of three toys on the cutting board
missed it in 3 of 6, 3 of 7 and 3 of 8 gate attempts (two blocks, two balls on the tray: 10 of 10 each)."""
COUNTS = {"both": 2, "two": 2, "three": 3, "2": 2, "3": 3}
"""Words that say how many objects a group has."""
_FORM = re.compile(r"^(?:(all|every|each|both)(?: of)?(?: the)?|(?:the )?(two|three|2|3)|(the))\s+([a-z']+)$")
"""An object phrase that is a group: a quantifier (or *the* before a plural) and one noun."""


@dataclass(frozen=True)
class Group:
    """A group as the request says it."""

    phrase: str
    """The words (``all the fruit``, ``both balls``)."""
    noun: str
    """Its noun in the singular (``fruit``, ``ball``)."""
    count: int | None
    """How many; None for *all*."""
    exclusive: bool = True
    """Whether the scene holds no other object of the group's kind: *all*, *both*, *the two* (a bare number, *two
    balls*, is any two)."""


def singular(word: str) -> str:
    """``word`` without its plural ending (*peaches* -> *peach*, *balls* -> *ball*, *fruit* -> *fruit*)."""
    for end, keep in (("ies", "y"), ("ches", "ch"), ("shes", "sh"), ("xes", "x"), ("ses", "s")):
        if word.endswith(end) and len(word) > len(end) + 1:
            return word[: -len(end)] + keep
    return word[:-1] if word.endswith("s") and not word.endswith("ss") else word


def find_group(object_words: str) -> Group | None:
    """The group an object phrase says (``all the fruit``, ``the balls``), or None: one object (*the fruit*, *the
    ball*) or a list (*the lemon and the plum*)."""
    m = _FORM.match(" ".join(object_words.lower().split()))
    if m is None:
        return None
    quantifier, number, the, noun = m.groups()
    plural = singular(noun) != noun
    if the and not plural:  # 'the fruit' is one fruit
        return None
    if number and not plural:
        return None
    count = COUNTS.get(number or quantifier or "")
    if quantifier in ("every", "each") and plural:  # 'every balls' is no English: not read as a group
        return None
    return Group(m.group(0), singular(noun), count, exclusive=not (number and not m.group(0).startswith("the ")))


PACK = 0.75
"""Objects put in one container lie in slots evenly round its middle (``gendex.solve.set_down.free_spot``); a
number of them the person asked for fits side by side when neighbouring slots are at least this share of the
largest one's width apart (they may lean on each other: *put the lemon and the plum in the bowl*, 0.85 of it, went
in 9 times of 10; a peach and a pear in the pot, 0.73, 8 of 10 and 2 of 5 in two gates)..."""
PACK_ALL = 0.85
"""...and when the reader chooses how many (*all the fruit*), this share: fewer objects, each with room (a pear and
a plum in the pot, 0.86: 10 of 10; a lemon and a plum in the bowl, 0.85: 9 of 10)."""


def side_by_side(objects: Sequence[dict], container: dict, slots: int | None = None, pack: float = PACK) -> bool:
    """Whether ``objects``, fitted to the hand, lie side by side in ``container`` in ``slots`` slots (default: one
    each), their slots ``pack`` of the largest one's width apart (:data:`PACK`)."""
    from gendex.solve.grasp import hand_fit_scale
    from gendex_envs.task_env import CONTAINER_INSIDE_SHARE

    slots = len(objects) if slots is None else slots
    if slots < 2 or not objects:
        return True
    widths = [float(max(a["size_m"][:2])) * hand_fit_scale(a["size_m"][:2]) for a in objects]
    room = CONTAINER_INSIDE_SHARE * float(min(container["size_m"][:2])) / 2 - max(widths) / 2
    return room > 0 and 2 * room * np.sin(np.pi / slots) >= pack * max(widths)


def choose(text: str, group: Group, candidates: Sequence[dict], by_kind: bool,
           container: dict | None = None, most: int = ALL_COUNT) -> list[dict]:
    """The objects of ``group``, drawn from ``candidates`` (assets that can play the part) by a generator seeded with
    ``text``: of distinct categories when ``by_kind``, and side by side in ``container`` when one is given (a put
    in: :func:`side_by_side`). :class:`InstructionError` when the catalog has too few."""
    rng = np.random.default_rng(int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "little"))
    pool = [candidates[i] for i in rng.permutation(len(candidates))]
    want = group.count if group.count is not None else most
    if want > ALL_COUNT:
        raise InstructionError(f"'{group.phrase}': a task moves at most {ALL_COUNT} objects one after another")
    picked: list[dict] = []
    for n in range(want, 1, -1) if group.count is None else (want,):  # 'all': as many as fit, three at most
        picked = []
        for a in pool:
            if len(picked) < n and not (by_kind and a["category"] in {p["category"] for p in picked}) and (
                    container is None or side_by_side([*picked, a], container, n,
                                                      PACK if group.count is not None else PACK_ALL)):
                picked.append(a)
        if len(picked) == n:
            return picked
    where = f" and that lie side by side in the {container['id'].replace('_', ' ')}" if container else ""
    raise InstructionError(f"'{group.phrase}' asks for {want if group.count else 'several'} {group.noun}s that the "
                           f"solver holds{where}; the catalog's: {', '.join(sorted(a['id'] for a in candidates))}")


def read_group(text: str, verb: list[str], objects: str, place: list[str], read_one: Callable[[str], Reading],
               assets: Mapping[str, dict]) -> list[Reading] | None:
    """One reading per object of the group ``objects`` names (the words between the ``verb`` and the ``place``),
    or None when they name no group."""
    from generator.backends.roles import carried, fits_in, graspable
    from generator.instruction import Mention

    group = find_group(objects)
    if group is None:
        return None
    probe = read_one(" ".join([*verb, "the", group.noun, *place]))  # 'put the fruit in the pot'
    m, where = probe.objects[0], probe.objects[-1]
    if m.how == "substitute" or probe.then:
        raise InstructionError(f"'{group.phrase}': the catalog has no {group.noun}; a group is said by a kind "
                               f"({', '.join(sorted(KINDS))}) or by the plural of a catalog object")
    into = assets[where.asset]
    able = [assets[i] for i in m.options if graspable(assets[i]) and carried(assets[i])
            and (probe.skill != "put_in" or fits_in(assets[i], into))]
    put = probe.skill == "put_in"
    picked = choose(text, group, able, m.how == "kind", into if put else None, ALL_COUNT if put else ALL_ON_SURFACE)
    n = len(picked)
    out = []
    for k, a in enumerate(picked, 1):
        mention = Mention(f"{group.phrase} ({k} of {n})", a["id"], "kind", None,
                          f"drawn for '{group.phrase}'", (a["id"],), group=group.phrase)
        out.append(dataclasses.replace(probe, instruction=text, objects=(mention, *probe.objects[1:]), notes=()))
    every = f" (the scene holds no other {group.noun})" if group.exclusive else ""
    note = f"'{group.phrase}' is read as {n}: {', '.join(a['id'] for a in picked)}{every}"
    out[0] = dataclasses.replace(out[0], notes=(*probe.notes, note))
    return out


def group_kinds(reading: Mapping | None) -> tuple[frozenset[str], frozenset[str]]:
    """The kind tags and the categories a recorded reading's groups cover (``Reading.to_dict()``): a scene of such
    a reading holds no clutter of them."""
    tags: set[str] = set()
    categories: set[str] = set()

    def walk(r: Mapping) -> None:
        for m in r.get("objects") or ():
            group = find_group(m.get("group") or "")
            if group is not None and group.exclusive:
                tags.add(KINDS[group.noun]) if group.noun in KINDS else categories.add(group.noun)
        for step in r.get("then") or ():
            walk(step)

    if reading:
        walk(reading)
    return frozenset(tags), frozenset(categories)


def covered(asset: dict, kinds: tuple[frozenset[str], frozenset[str]]) -> bool:
    """Whether ``asset`` is of a group :func:`group_kinds` gave (a kind tag, or a category; *all the things* covers
    every graspable object)."""
    tags, categories = kinds
    return bool(set(asset["tags"]) & tags) or asset["category"] in categories


__all__ = ["ALL_COUNT", "ALL_ON_SURFACE", "COUNTS", "PACK", "PACK_ALL", "Group", "choose", "covered", "find_group",
           "group_kinds", "read_group", "side_by_side", "singular"]
