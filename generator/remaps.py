"""Which dexterous skill a request means once its objects are known: the instruction reader reads a verb first
(*put*, *open*, *insert*), and these rules look at what the verb acts on.

- a hand-over mat among the objects: ``hand_over`` (*set the bottle on the hand-over mat*); the mat is the task's own;
- a screw-top model opened, turned, taken off or pressed: ``twist`` (*open the jar*, *take the lid off the bottle*);
  screwed on, tightened or closed: ``twist`` with direction ``on`` (*screw the lid on the jar*, *close the jar*);
- a peg put, placed, inserted or fitted into a holder (or a peg inserted): ``insert`` (*put the square peg in the
  square hole*, *push the peg into the hole*, *insert the peg*); a peg picked up, or pushed to the goal, stays a
  lift or a push;
- a wipe names its sponge and its spill in either order (*wipe the spill with the sponge*, *use the sponge to wipe
  the spill*): the sponge is put first; a spill named alone gets the catalog's sponge after it;
- a pour names its pieces, its vessel and the container in any order, or leaves some out (*pour the beads from the
  glass into the bowl*, *empty the beaker into the bowl*, *tip the glass of marbles into the large bowl*): the pieces
  first, then the vessel, then the container, and what is left unsaid is the catalog's first that can be it; a
  glass or a cup one pours from is the vessel of :data:`~generator.vocabulary.POUR_VESSELS` (a wine glass or a
  teacup is none), and pieces the catalog lacks (*the rice*) are its closest pieces, a recorded substitution; a lid
  tipped back (*tip the bin's lid back to open it*) is an ``open``;
- a glass or a cup turned over (*turn the glass upside down*) is the same vessel a pour would use.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from generator.instruction import Mention

PUT_SKILLS = ("put_in", "place_on", "place_at", "lift", "push")
"""Skills whose verb (*put*, *set*, *place*, *take*, *move*) may mean a hand-over or an insertion by its objects."""


@dataclasses.dataclass
class Read:
    """What the reader has so far: the skill, its roles, a relation or region, and the objects mentioned."""

    skill: str | None
    roles: tuple[str, ...]
    relation: str | None
    region: str | None
    mentions: list[Mention]
    direction: str | None = None
    """``"on"``: a cap screwed on (a twist that shuts)."""


def object_skill(r: Read, words: list[str], text: str, assets: Sequence[dict]) -> Read:
    """``r`` with its skill replaced where its objects say which dexterous skill is meant (module docstring)."""
    from generator.instruction import ROLE_TESTS, SKILL_ROLES, _by_id

    def plays(m: Mention, role: str) -> bool:
        return bool(m.asset) and ROLE_TESTS[role](_by_id(assets, m.asset))

    zone = [m for m in r.mentions if plays(m, "handover")]
    if zone and r.skill in (*PUT_SKILLS, "hand_over"):
        # the mat is the task's own, not an object to assign
        r = Read("hand_over", SKILL_ROLES["hand_over"], None, None, [m for m in r.mentions if m not in zone])
    screws = [m for m in (_screw_model(m, assets) for m in r.mentions) if m is not None]
    tighten = r.skill in ("close", "place_on") or words[-1:] == ["on"] or any(w in ("screw", "tighten") for w in words)
    # not 'take the apple out of the jar', 'put the apple on (top of) the jar'; but 'put the cap back on the bottle'
    cap_words = ("lid", "cap") if r.skill == "place_on" else ("lid", "cap", "top")
    capped = r.skill not in ("take_out", "place_on") or any(w in cap_words for w in words)
    if screws and capped and r.skill in ("open", "turn", "take_out", "press", "close", "twist", "place_on"):
        r = dataclasses.replace(r, skill="twist", roles=SKILL_ROLES["twist"], mentions=screws[:1],
                                direction="on" if tighten else None)  # 'screw the lid on the jar', 'close the jar'
    socket = any(plays(m, "socket") for m in r.mentions)
    peg_only = r.skill == "put_in" and all(plays(m, "insertable") for m in r.mentions)  # 'insert the peg'
    if r.mentions and (r.skill == "insert" or peg_only or (socket and r.skill in ("put_in", "place_on", "place_at",
                                                                                  "push"))):
        r = Read("insert", SKILL_ROLES["insert"], None, None, r.mentions)
    if r.skill == "wipe":  # a sponge: a wiper, or named by a kind that has one ('the sponge')
        kinds = {a["category"] for a in assets if ROLE_TESTS["wiper"](a)}
        wipers = [m for m in r.mentions
                  if plays(m, "wiper") or (m.asset and _by_id(assets, m.asset)["category"] in kinds)]
        rest = [m for m in r.mentions if m not in wipers]
        roles = SKILL_ROLES["wipe"] if wipers or not rest else ("wipe_area", "wiper")
        r = dataclasses.replace(r, roles=roles, mentions=wipers + rest)
    if r.skill == "hang":  # 'hang the mug on the tree', 'onto the rack, hang the mug': the mug first
        hung = [m for m in r.mentions if plays(m, "hangable")]
        r = dataclasses.replace(r, mentions=hung + [m for m in r.mentions if m not in hung])
    if r.skill == "pour" and r.mentions and all(plays(m, "openable") for m in r.mentions):
        r = Read("open", SKILL_ROLES["open"], None, None, r.mentions)  # 'tip the bin's lid back to open it'
    if r.skill == "pour":
        r = _pour_order(r, plays, assets)
    if r.skill == "flip":  # 'turn the glass upside down': a drinking glass, as in a pour
        r = dataclasses.replace(r, mentions=[_vessel(m, plays) for m in r.mentions])
    return r


def _vessel(m: Mention, plays) -> Mention:
    """``m`` as the vessel of :data:`~generator.vocabulary.POUR_VESSELS` its last word names, where it names an
    object that is none (*the glass*: the tumbler, not the wine glass; *the cup*: the paper cup, not the teacup); a
    phrase that says more (*the wine glass*) names what it says, and a colour stays the vessel's."""
    from generator.vocabulary import POUR_VESSELS

    words = m.phrase.split() if m.phrase else []
    plain = len(words) == 1 or (len(words) == 2 and m.color is not None)  # 'the glass', 'the red glass'
    if m.asset and plain and not plays(m, "pourer") and words[-1] in POUR_VESSELS and not plays(m, "pour_into"):
        vessel = POUR_VESSELS[words[-1]]
        return dataclasses.replace(m, asset=vessel, options=(vessel,), how="synonym")
    return m


def _pour_order(r: Read, plays, assets: Sequence[dict]) -> Read:
    """A pour's mentions as pieces, vessel, container, with its roles in that order and the unsaid ones last (module
    docstring)."""
    from generator.instruction import SKILL_ROLES

    mentions = [_vessel(m, plays) for m in r.mentions]
    pieces = [m for m in mentions if plays(m, "pourable")]
    vessels = [m for m in mentions if plays(m, "pourer") and m not in pieces]
    rest = [m for m in mentions if m not in pieces and m not in vessels]
    if not pieces and rest and rest[0].how == "substitute":  # 'pour the rice ...': pieces the catalog lacks
        pieces, rest = rest[:1], rest[1:]
    named = ["pourable"] * bool(pieces) + ["pourer"] * bool(vessels) + ["pour_into"] * bool(rest)
    roles = tuple(named) + tuple(x for x in SKILL_ROLES["pour"] if x not in named)
    return dataclasses.replace(r, roles=roles, mentions=pieces + vessels + rest)


def _screw_model(m: Mention, assets: Sequence[dict]) -> Mention | None:
    """``m`` as the model with a screw cap it may name (*the jar*: the rigid jar's name, and the screw-top jar's
    kind), None when it names none."""
    from generator.instruction import ROLE_TESTS, _by_id

    if not m.asset:
        return None
    kind = _by_id(assets, m.asset)["category"]
    ids = [*(m.options or (m.asset,)), *(a["id"] for a in assets if a["category"] == kind)]
    screw = next((i for i in ids if ROLE_TESTS["screwable"](_by_id(assets, i))), None)
    return None if screw is None else dataclasses.replace(m, asset=screw, options=(screw,))


__all__ = ["PUT_SKILLS", "Read", "object_skill"]
