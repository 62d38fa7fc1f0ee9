"""Words of the task language beyond a skill and its objects, as a request writes them: a direction (*turn the tap
off*), an amount (*halfway*, *45 degrees*), and the phrases of constructs the author and solver do not build yet
(:data:`NOT_BUILT`); with what an amount means for an asset's joint (:func:`joint_fraction`).
:mod:`generator.instruction` reads requests with them."""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from generator.errors import InstructionError
from generator.phrasing import SURFACES


def find(words: Sequence[str], phrase: str, start: int = 0) -> int:
    """Index of ``phrase`` (words) in ``words`` at or after ``start``, else -1."""
    p = phrase.split()
    for i in range(start, len(words) - len(p) + 1):
        if list(words[i:i + len(p)]) == p:
            return i
    return -1


DETERMINERS = frozenset("a an the its my your our their his her some this these those".split())
"""Words that start a noun phrase: an unknown word names an object (the catalog lacks) only in such a phrase
(*grab the mango*), never elsewhere in the sentence (*keep hold of it*, *without lifting it*)."""
_NOT_BUILT_GROUPS: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    ("steps out of order ('{}')", "steps said after the step they come before",
     ("afterwards", "after that", "before", "after you")),
    ("a side of something held ('{}')", "places relative to the hand", ("to its left", "to its right")),
    ("a direction ('{}')", "pushes in a direction", ("forward", "backward", "away from")),
)
NOT_BUILT: tuple[tuple[str, str, str], ...] = tuple((phrase, what.format(phrase), construct)
                                                   for what, construct, phrases in _NOT_BUILT_GROUPS
                                                   for phrase in phrases)
"""Phrases of constructs the task language has (``docs/task_spec.md``) but the author and solver do not build yet:
(phrase, what the request asks for, the construct). A request with one is refused, never built without it; so is
one ending in ``left``, ``right`` (*push the block left*) or ``off`` (*turn the tap off*), but not one where they name
a model (*the left fridge*), are a verb (*the door that was left open*) or say where from (*lift it off the
table*)."""
HALF_WORDS = ("half", "halfway", "partly", "partially", "partway")
"""Words asking to open or turn something part way: read as half its range (*partly* with a note saying so)."""
_UNITS = {w: i for i, w in enumerate("zero one two three four five six seven eight nine ten eleven twelve thirteen "
                                      "fourteen fifteen sixteen seventeen eighteen nineteen".split())}
_TENS = {w: 10 * i for i, w in enumerate("_ _ twenty thirty forty fifty sixty seventy eighty ninety".split()) if i > 1}


def _number_before(words: list[str], k: int) -> float | None:
    """The number written just before ``words[k]`` (``45``, ``forty five``, ``ninety``), else None."""
    if k > 0 and re.fullmatch(r"\d+(\.\d+)?", words[k - 1]):
        return float(words[k - 1])
    if k > 1 and words[k - 2] in _TENS and words[k - 1] in _UNITS and _UNITS[words[k - 1]] < 10:
        return float(_TENS[words[k - 2]] + _UNITS[words[k - 1]])
    if k > 0 and (words[k - 1] in _TENS or words[k - 1] in _UNITS):
        return float(_TENS.get(words[k - 1], _UNITS.get(words[k - 1], 0)))
    return None


def amount_words(words: list[str]) -> set[int]:
    """Where the words of an amount are (*halfway*, *part way*, *forty five degrees*): they name no object."""
    at = {k for k, w in enumerate(words) if w in HALF_WORDS}
    for k in range(len(words) - 1):
        if words[k] in ("half", "part") and words[k + 1] == "way":
            at |= {k, k + 1}
    for k, w in enumerate(words):
        if w in ("degrees", "degree", "deg"):
            at.add(k)
            at |= {j for j in (k - 1, k - 2) if j >= 0 and (words[j] in _UNITS or words[j] in _TENS
                                                             or words[j].replace(".", "").isdigit())}
    return at


def read_amount(words: list[str]) -> tuple[str | None, str | None]:
    """How far the request asks a joint to go (:attr:`Reading.amount`) and a note when a word was read loosely;
    :class:`InstructionError` for ``degrees`` without a number."""
    for k, w in enumerate(words):
        if w in ("degrees", "degree", "deg"):
            n = _number_before(words, k)
            if n is None:
                raise InstructionError(f"'{w}' without a number before it: say how far, e.g. 'turn the valve 45 "
                                       f"degrees'")
            return f"{n:g} degrees", None
    if find(words, "half way") >= 0 or find(words, "part way") >= 0:
        return "half", None
    loose = next((w for w in words if w in HALF_WORDS), None)
    if loose is None:
        return None, None
    return "half", (f"'{loose}' read as half of the way" if loose not in ("half", "halfway") else None)


def is_off(words: list[str]) -> bool:
    """Whether the request asks to turn something off: an ``off`` right after a verb (*turn off the tap*) or not
    followed by what it comes off (*switch it off*, *turn the valve off please*; not *lift it off the table*)."""
    for i, w in enumerate(words):
        if w != "off":
            continue
        nxt = words[i + 1] if i + 1 < len(words) else ""
        if (i > 0 and words[i - 1] in ("turn", "turned", "switch", "switched", "shut")) or (
                nxt not in DETERMINERS and nxt not in ("of", "from")):
            return True
    return False


GROUP_WORDS = frozenset("two three four five six several all both every".split())
"""Words that ask for several objects at once when a plural follows (*three blocks*; not *three-drawer chest*)."""


MIN_PART_FRACTION = 0.2
"""A part-way joint goal is at least this fraction of the range from closed (nearer, holding still is within the
condition's 10 %)."""


def joint_fraction(amount: str, a: dict) -> float:
    """The fraction of ``a``'s main joint range (closed to open) that a reading's ``amount`` asks for: ``half`` is
    0.5; ``<n> degrees`` turns a revolute joint that far from closed. :class:`InstructionError` for degrees of a
    slide, or more than the joint's range."""
    if amount == "half":
        return 0.5
    deg = float(amount.split()[0])
    j = a["joints"][0]
    span = abs(j["open_qpos"] - j["closed_qpos"])
    what = f"the {a['category'].replace('_', ' ')}'s {j['handle_link'].split('_')[0]}"
    if j["type"] != "revolute":
        raise InstructionError(f"'{amount}': {what} slides, it does not turn; ask for it half open instead")
    most = float(np.degrees(span))
    if not MIN_PART_FRACTION * most <= deg <= most:
        raise InstructionError(f"'{amount}': {what} turns {most:.0f} degrees from closed to open; ask for "
                               f"{MIN_PART_FRACTION * most:.0f} to {most:.0f} degrees")
    return round(float(np.radians(deg)) / span, 3)


def amount_word(fraction: float, a: dict) -> str:
    """Task-name words for a part-way joint: ``half``, ``45 degrees`` (a revolute joint) or ``to 65 pct``."""
    text = amount_text(fraction, a)
    return "half" if fraction == 0.5 else text if text.endswith("degrees") else f"to {round(100 * fraction)} pct"


def amount_text(fraction: float, a: dict | None = None) -> str:
    """``halfway``, or how far in degrees (a revolute joint) or per cent of the range."""
    if fraction == 0.5:
        return "halfway"
    if a is not None and a["joints"][0]["type"] == "revolute":
        span = abs(a["joints"][0]["open_qpos"] - a["joints"][0]["closed_qpos"])
        return f"{np.degrees(fraction * span):.0f} degrees"
    return f"{100 * fraction:.0f} % of the way"


REGION_PHRASES: tuple[tuple[str, str], ...] = (
    ("far left corner", "far_left"), ("far right corner", "far_right"), ("near left corner", "near_left"),
    ("near right corner", "near_right"), ("back left corner", "far_left"), ("back right corner", "far_right"),
    ("front left corner", "near_left"), ("front right corner", "near_right"), ("far left", "far_left"),
    ("far right", "far_right"), ("near left", "near_left"), ("near right", "near_right"), ("far side", "far"),
    ("far end", "far"), ("back of the table", "far"), ("near side", "near"), ("front of the table", "near"),
    ("left side", "left"), ("right side", "right"), ("middle of the table", "centre"),
    ("centre of the table", "centre"), ("center of the table", "centre"), ("left of the table", "left"),
    ("right of the table", "right"), ("near edge", "near"), ("front edge", "near"), ("far edge", "far"),
    ("back edge", "far"), ("left edge", "left"), ("right edge", "right"), ("to the left", "left"),
    ("to the right", "right"), ("on the left", "left"), ("on the right", "right"), ("leftward", "left"),
    ("rightward", "right"))
"""Phrases naming a region of the table (``placed`` with ``in_region``), longest first; one followed by *of* and an
object names a side of that object (*on the left side of the bowl*: :data:`RELATION_PHRASES`)."""
RELATION_PHRASES: tuple[tuple[str, str], ...] = (
    ("to the left of", "left_of"), ("to the right of", "right_of"), ("left side of", "left_of"),
    ("right side of", "right_of"), ("left of", "left_of"), ("right of", "right_of"), ("in front of", "in_front_of"),
    ("near side of", "in_front_of"), ("front side of", "in_front_of"), ("far side of", "behind"),
    ("back side of", "behind"), ("at the back of", "behind"), ("behind", "behind"), ("next to", "next_to"),
    ("beside", "next_to"), ("alongside", "next_to"), ("between", "between"))
"""Phrases naming a place relative to other objects (``placed``), longest first where one holds another."""
NEAR_PHRASES = ("close to", "near to", "near")
"""Phrases that name a place beside an object only where something is set down there (*set the lemon near the plate*
is not *on* it); elsewhere they say which object (*lift the apple near the bowl*)."""
_IN_OR_ON = frozenset({"in", "into", "inside", "on", "onto", "upon"})


def read_place(words: list[str], setting_down: bool = False) -> tuple[str | None, str | None, set[int]]:
    """``(relation, region, where its words are)``: where the request sets something down, seen from the robot
    (*to the left of the bowl*: ``left_of``; *on the far right corner of the table*: ``in_region``, ``far_right``;
    *push the block left*: ``in_region``, ``left``), or ``(None, None, set())``. With ``setting_down`` (a put, set
    or push), *near the plate* (:data:`NEAR_PHRASES`) is beside it, and so is *by the plate* where nothing is put in
    or on (*lift the mug by its handle* is no place)."""
    for phrase, region in REGION_PHRASES:
        k = find(words, phrase)
        if k < 0:
            continue
        n = len(phrase.split())
        after = words[k + n:k + n + 3]
        beyond = words[k + n + (after[:1] == ["side"]):][:3]  # 'on the left' of 'on the left side of the bowl'
        if beyond[:1] == ["of"] and not set(beyond[1:3]) & set(SURFACES):  # the left side of the bowl
            continue
        extra = 1 + (after[1:2] == ["the"]) + 1 if after[:1] == ["of"] else 0
        return "in_region", region, set(range(k, k + n + extra))
    near = tuple((p, "next_to") for p in NEAR_PHRASES) if setting_down else ()
    for phrase, relation in RELATION_PHRASES + near:
        k = find(words, phrase)
        if k >= 0:
            return relation, None, set(range(k, k + len(phrase.split())))
    k = find(words, "by")
    if setting_down and k >= 0 and words[k + 1:k + 2] in (["the"], ["a"], ["an"]) and not set(words) & _IN_OR_ON:
        return "next_to", None, {k}
    if words and words[-1] in ("left", "right"):  # 'push the block left' (a model's qualifier is checked later)
        return "in_region", words[-1], {len(words) - 1}
    return None, None, set()


def split_steps(text: str) -> list[str]:
    """The steps of a request said in order (*A, then B, then C*; *first A and then B*), each without its joiner;
    one step for a request without ``then``."""
    parts = re.split(r"\s*,?\s*(?:\band\s+)?\bthen\b[\s,]*", text, flags=re.IGNORECASE)
    parts = [re.sub(r"^(first|firstly)\s+", "", p.strip(" ,.;"), flags=re.IGNORECASE) for p in parts]
    return [p for p in parts if p]


_WHY = re.compile(r",? so (?:that )?(?:it|they|the|there|we|i|you|nothing|no) .*$")
_THROWN = re.compile(r"(throw|toss|chuck)\b(?=.*\b(?:in|into|inside)\b)", re.IGNORECASE)
_ONE = re.compile(r"\bthe\s+([a-z]+)\s+one\b", re.IGNORECASE)
_PLACE_TAIL = re.compile(r"\s*\b(on top of|next to|in front of|to the left of|to the right of|onto|on|into|in|inside|"
                         r"beside|behind|by|and|from|than)\s*$", re.IGNORECASE)


def restated(text: str) -> tuple[str, str | None]:
    """What to read of ``text`` when it says more or less than its task, and the note saying so (None: read it as
    it is): a reason after the request (*flip the cup over so it can dry*: not something to do, unless a step follows
    it); *throw the apple in the bin* (a drop into it); *the green one* after *the blue cube* (the green cube)."""
    why = _WHY.search(text)
    if why is not None and why.start() > 0 and not re.search(r"\bthen\b|;", why.group(0)):
        return text[:why.start()], f"'{why.group(0).lstrip(', ')}' is read as the reason, not as something to do"
    thrown = _THROWN.match(text)
    if thrown is not None:  # not 'throw the ball' (across the room): that is no task
        return "drop" + text[thrown.end():], f"'{thrown.group(1)}' is read as 'drop' (into the place it names)"
    one = _ONE.search(text)
    if one is not None and one.group(1).lower() not in ("other", "same", "first", "last", "next", "right", "left"):
        noun = re.search(r"([a-z']+)$", _PLACE_TAIL.sub("", text[:one.start()]).rstrip(), re.IGNORECASE)
        if noun is not None and noun.group(1).lower() not in DETERMINERS | {"it", "them", "one"}:
            said = f"the {one.group(1)} {noun.group(1)}"
            return text[:one.start()] + said + text[one.end():], f"'{one.group(0)}' is read as '{said}'"
    return text, None
