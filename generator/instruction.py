"""Reading a person's request: which task skill it asks for, and which catalog objects it names.

``gendex generate --instruction "..."`` starts here, before any backend is asked anything. :func:`read_instruction`
finds the skill from the verb (and its preposition: *put X in Y* is not *put X on Y*) and resolves every object
phrase against the catalog — multi-word names (*tuna can*), plurals, synonyms (*fridge*, *tap*), parts (*the top
drawer*), kinds (*a fruit*), colours; steps, lists, towers and groups go through :mod:`generator.compound`. Nothing
is silent: each object is recorded with how it was resolved (:class:`Mention`); one the catalog lacks stands in by
the object nearest in meaning (:mod:`generator.nearest`), a *substitution* the CLI prints and the proposal keeps; a
word no part of the reading takes is said in a note; a verb with no skill, an object that cannot play its part or
a construct not built yet (:data:`NOT_BUILT`) raises :class:`InstructionError` listing what is possible, and
``gendex generate`` exits 2. The skills are :data:`TASK_SKILLS`; the same vocabulary goes into the language-model
backend's proposal prompt (:func:`skill_vocabulary`)."""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from gendex_envs.attributes import COLOR_WORDS
from generator.compound import read_compound
from generator.constructs import (
    DETERMINERS,
    GROUP_WORDS,
    NOT_BUILT,
    amount_words,
    find,
    is_off,
    read_amount,
    read_place,
    restated,
)
from generator.errors import InstructionError
from generator.nearest import stand_in
from generator.phrasing import MODEL_WORDS
from generator.vocabulary import COURTESY_WORDS, KINDS, ORDINALS, PARTS, SYNONYMS, TASK_SKILLS, TaskSkill
from generator.vocabulary import FILLER_WORDS as _FILLER
from generator.vocabulary import STOP_WORDS as _STOP

_VERB_WORDS = frozenset(w for s in TASK_SKILLS.values() for v in s.verbs for w in v.split())


_INTO = ("into", "in", "inside")
_ONTO = ("onto", "on", "on top of", "upon")


@dataclass(frozen=True)
class Mention:
    """An object phrase of the request and the catalog asset it stands for."""

    phrase: str
    """The words as the person wrote them (lower case, articles dropped)."""
    asset: str
    how: str
    """``id`` (a catalog id), ``name`` (a catalog name: multi-word, plural), ``synonym``, ``kind`` (a kind of object:
    the asset is a choice) or ``substitute`` (the catalog lacks it: the closest object that can play the part)."""
    part: str | None = None
    """The part named with it (``door``, ``drawer``, ``lid``; ``top drawer`` -> ``drawer``), if any."""
    detail: str = ""
    options: tuple[str, ...] = ()
    """Every asset the phrase names that can play its part (``fridge``: both refrigerators); :attr:`asset` is the
    first. A task using another of them keeps the person's meaning; any other asset is a substitution."""
    qualifier: str = ""
    """Words the person put next to a catalog name that are not catalog words themselves (``left fridge``,
    ``three drawer chest``): they choose among the name's models where they match a model's id."""
    color: str | None = None
    """The colour the person named it by (a key of :data:`gendex_envs.attributes.COLORS`): the task paints it so."""
    group: str = ""
    """The group it was drawn for (*all the fruit*: :mod:`generator.groups`), if any."""

    @property
    def substituted(self) -> bool:
        return self.how in ("substitute", "kind")


@dataclass(frozen=True)
class Reading:
    """What a request asks for."""

    instruction: str
    skill: str
    """A key of :data:`TASK_SKILLS`."""
    objects: tuple[Mention, ...]
    """In the order of their roles (the thing acted on first, then the container, surface or base)."""
    notes: tuple[str, ...] = field(default=())
    """Parts of the request that shape nothing (``the top drawer``: the drawer the solver opens is the first)."""
    direction: str | None = None
    """For a turn: ``"on"`` (towards the open end, the default) or ``"off"`` (*turn the tap off*, *close the
    valve*: back to the shut end); for a twist: ``"on"`` screws the cap on (*close the jar*), None unscrews it."""
    relation: str | None = None
    """For ``place_at``: where the object goes relative to the others (a relation of the ``placed`` condition:
    ``left_of``, ``between``, ..., or ``in_region``)."""
    region: str | None = None
    """For ``place_at`` with ``in_region``: the region of the table (``far_left``, ``near``, ``centre``, ...)."""
    then: tuple[Reading, ...] = ()
    """The steps the request asks for after this one, in order (*close the microwave, then set the bottle on the
    plate*); each its own reading."""
    amount: str | None = None
    """How far an open or a turn goes when the request says: ``"half"`` (*open the drawer halfway*) or ``"<n>
    degrees"`` (*turn the valve 45 degrees*, from the shut end); None: all the way."""

    @property
    def all_objects(self) -> tuple[Mention, ...]:
        """The objects of this step and of every later one."""
        return self.objects + tuple(m for r in self.then for m in r.all_objects)

    @property
    def substitutions(self) -> dict[str, str]:
        """Phrase -> asset for every object the catalog lacked (or a kind that was chosen from), in every step."""
        return {m.phrase: m.asset for m in self.all_objects if m.substituted}

    def lines(self) -> list[str]:
        """Human-readable account of the reading (what the CLI prints)."""
        where = (self.region if self.relation == "in_region" else self.relation or "").replace("_", " ")
        out = [f'"{self.instruction}" -> skill {self.skill!r}'
               + "".join(f", {x}" for x in (self.direction, where, self.amount) if x)]
        for m in self.objects:
            verb = {"id": "is", "name": "is", "synonym": "means", "kind": "chose", "substitute": "SUBSTITUTED"}[m.how]
            what = m.asset
            if m.how in ("id", "name", "synonym") and len(m.options) > 1:  # which one is the author's choice
                what, detail = f"one of {', '.join(m.options)}", ""
            else:
                detail = m.detail
            out.append(f"  {m.phrase!r} {verb} {what}" + (f", painted {m.color}" if m.color else "")
                       + (f" ({detail})" if detail else ""))
        out += [f"  note: {n}" for n in self.notes]
        for r in self.then:
            out += ["  then " + r.lines()[0], *r.lines()[1:]]
        return out

    def to_dict(self) -> dict:
        return dataclasses.asdict(self) | {"substitutions": self.substitutions}


def skill_vocabulary() -> str:
    """The task skills with their verbs, objects and an example (one per line, for prompts and messages)."""
    return "\n".join(f"  - {s.name}: {', '.join(s.verbs[:5])} — {s.objects} (e.g. \"{s.example}\")"
                     for s in TASK_SKILLS.values())


# ---------------------------------------------------------------------------------------------- roles
def is_graspable(a: dict) -> bool:
    return "graspable" in a["tags"] and not a.get("joints")


def is_container(a: dict) -> bool:
    return "container" in a["tags"] and not a.get("joints") and a["category"] not in ("cup", "wine_glass", "jar")


def drawers(a: dict) -> tuple[str, ...]:
    """The joints of ``a`` whose link holds things (catalog ``holds_m``: a chest's drawers)."""
    return tuple(j["name"] for j in a.get("joints") or () if j.get("holds_m"))


def is_surface(a: dict) -> bool:
    """Something flat to set an object on: a plate, or an asset tagged ``surface`` (tray, cutting board)."""
    return a["category"] == "plate" or ("surface" in a["tags"] and not a.get("joints"))


def is_block(a: dict) -> bool:
    return "block" in a["tags"] and not a.get("joints")


PRESSED = ("button", "switch")
"""Categories of articulated objects whose one part is pressed past a detent (the ``press`` skill)."""


def part_kinds(a: dict) -> tuple[str, ...]:
    """The kinds of movable part an articulated asset has (``door``, ``drawer``, ``lid``, ``lever``, ``knob``; a
    button's or a switch's one part is ``button`` or ``switch``)."""
    if a.get("category") in PRESSED:
        return tuple(a["category"] for _ in a.get("joints") or [])
    kinds = []
    for j in a.get("joints") or []:
        link = j.get("handle_link") or j["name"]
        kinds.append(next((p for p in ("door", "drawer", "lid", "lever", "knob", "rack", "cap") if p in link), "part"))
    return tuple(kinds)


ROLE_TESTS = {
    "graspable": is_graspable, "container": is_container, "surface": is_surface, "block": is_block,
    "receptacle": lambda a: is_container(a) or ("container" in a["tags"] and "lid" in part_kinds(a))
    or bool(drawers(a)),
    "holder": lambda a: is_container(a) or bool(drawers(a)),
    "pushable": lambda a: not a.get("joints") and max(a["size_m"][:2]) <= 0.25,
    "openable": lambda a: any(k in ("door", "drawer", "lid") for k in part_kinds(a)),
    "turnable": lambda a: any(k in ("lever", "knob") for k in part_kinds(a)),
    "pressable": lambda a: any(k in PRESSED for k in part_kinds(a)),
    "ball": lambda a: "ball" in a["tags"] and not a.get("joints"),
    "landmark": lambda a: not a.get("joints"),
    "handover": lambda a: "handover" in a["tags"],
    "screwable": lambda a: "cap" in part_kinds(a),
    "insertable": lambda a: "peg" in a["tags"] and not a.get("joints"),
    "socket": lambda a: "insert" in a["tags"] and not a.get("joints"),
    "wiper": lambda a: "wiper" in a["tags"] and not a.get("joints"),
    "wipe_area": lambda a: "wipe_area" in a["tags"] and not a.get("joints"),
    "hangable": lambda a: "hangable" in a["tags"] and not a.get("joints"),
    "hang_on": lambda a: "hang_on" in a["tags"] and not a.get("joints"),
    "pourable": lambda a: "pourable" in a["tags"] and not a.get("joints"),
    "pourer": lambda a: "pourer" in a["tags"] and not a.get("joints"),
    "pour_into": lambda a: is_container(a) and "pourer" not in a["tags"] and min(a["size_m"][:2]) >= 0.14,
    "flippable": lambda a: "pourer" in a["tags"] and not a.get("joints"),
}
"""What an object must be to play each role."""

SKILL_ROLES: dict[str, tuple[str, ...]] = {
    "lift": ("graspable",), "put_in": ("graspable", "receptacle"), "place_on": ("graspable", "surface"),
    "stack": ("block", "block"), "push": ("pushable",), "open": ("openable",), "close": ("openable",),
    "turn": ("turnable",), "reorient": ("ball",), "place_at": ("graspable", "landmark"),
    "take_out": ("graspable", "holder"), "press": ("pressable",), "hand_over": ("graspable",),
    "twist": ("screwable",), "insert": ("insertable", "socket"), "wipe": ("wiper", "wipe_area"),
    "hang": ("hangable", "hang_on"), "pour": ("pourable", "pourer", "pour_into"), "flip": ("flippable",),
}
"""The roles of a skill's objects, in order (what :attr:`Reading.objects` holds)."""


# ---------------------------------------------------------------------------------------------- reading
def _words(text: str) -> list[str]:
    """Lower-case words; a possessive is its noun (*the cabinet's door* -> *the cabinet door*)."""
    words = re.findall(r"[a-z0-9']+", text.lower().replace("-", " "))
    return [w for w in (re.sub(r"'s?$", "", w) for w in words) if w]


def _names(assets: Iterable[dict]) -> dict[str, tuple[str, list[dict]]]:
    """Phrase -> (how, assets it names): ids and categories with their words spaced, plurals, synonyms."""
    assets = sorted(assets, key=lambda a: (a["id"] != a["category"], a["id"]))
    out: dict[str, tuple[str, list[dict]]] = {}

    def add(phrase: str, how: str, match: list[dict]) -> None:
        if match and phrase not in out:
            out[phrase] = (how, match)

    for a in assets:
        add(a["id"].replace("_", " "), "id", [a])
        cat, aid = a["category"], a["id"]
        if aid.startswith(cat + "_"):  # block_small -> 'small block', trash_can_tall -> 'tall trash can'
            suffix = aid[len(cat) + 1:].replace("_", " ")
            add(f"{suffix} {cat.replace('_', ' ')}", "id", [a])
            for phrase, target in SYNONYMS.items():  # ... 'tall bin', 'compact microwave oven'
                if target == cat:
                    add(f"{suffix} {phrase}", "id", [a])
        model = MODEL_WORDS.get(aid, "").replace("-", " ")  # the author's: 'right hinged cabinet', '13 inch laptop'
        for phrase in [cat.replace("_", " "), *(p for p, t in SYNONYMS.items() if t == cat)] if model else ():
            add(f"{model} {phrase}", "id", [a])
    for a in assets:
        cat = a["category"]
        same = [b for b in assets if b["category"] == cat]
        for phrase in (cat.replace("_", " "), cat.replace("_", "")):
            add(phrase, "name", same)
            add(phrase + ("es" if phrase.endswith(("s", "x", "ch")) else "s"), "name", same)
    categories = {b["category"] for b in assets}
    for phrase, target in SYNONYMS.items():
        match = [b for b in assets if target in (b["category"], b["id"])]
        # a word for one model ('emergency stop' -> button_estop) names it as its id does, not any of its kind
        add(phrase, "synonym" if target in categories else "id", match)
    return out


def _spans(words: list[str], names: dict[str, tuple[str, list[dict]]]) -> list[tuple[int, int, str]]:
    """Non-overlapping (start, end, phrase) of catalog phrases in ``words``, longest first, then the earliest
    (*ball valve lever*: the synonym *ball valve* and its part, not *ball* and the id *valve lever*)."""
    hits = []
    for phrase in names:
        n = len(phrase.split())
        i = find(words, phrase)
        while i >= 0:
            hits.append((-n, i, phrase))
            i = find(words, phrase, i + 1)
    taken = [False] * len(words)
    found = []
    for neg, i, phrase in sorted(hits):
        if not any(taken[i:i - neg]):
            found.append((i, i - neg, phrase))
            taken[i:i - neg] = [True] * -neg
    return sorted(found)


def _starts_with_verb(text: str) -> bool:
    words = _words(text)
    return any(words[:len(v.split())] == v.split() for s in TASK_SKILLS.values() for v in s.verbs)


def _skill(words: list[str]) -> tuple[str, int] | None:
    """The skill the request's verb asks for and where the verb ends; None when no verb of any skill is there."""
    hits = []
    for s in TASK_SKILLS.values():
        for v in s.verbs:
            i = find(words, v)
            if i >= 0:
                hits.append((i, -len(v.split()), s.name, i + len(v.split())))
    if words[:1] == ["hand"]:  # 'hand the bottle to me'; 'hand' elsewhere is the robot's ('with the open hand')
        hits.append((0, -1, "hand_over", 1))
    if not hits:
        return None
    hits.sort()
    first = hits[0][0]
    names = [h[2] for h in hits if h[0] == first]
    end = hits[0][3]
    rest = " " + " ".join(words[end:]) + " "
    if ("close" in names or re.search(r" (shut|shuts|closed) ", rest)
            or (" back in " in rest and "push" in names)):
        return "close", end
    if "put_in" in names or "place_on" in names:
        into = any(f" {p} " in rest for p in _INTO)
        onto = any(f" {p} " in rest for p in _ONTO)
        if "on top of" in rest or (onto and not into):
            return "place_on", end
        if into:
            return "put_in", end
        return ("place_on" if "place_on" in names else "put_in"), end
    moved = next((w for w in words[end:] if w not in DETERMINERS), "")
    if " out of " in rest and names[0] in ("lift", "put_in", "place_on", "open", "take_out") and moved not in PARTS:
        return "take_out", end  # take the apple out of the bowl; not 'pull the drawer out of the chest' (an open)
    if "take_out" in names and " lid " in rest:
        return "open", end  # remove the lid
    opened = re.search(r" open (?!hand |palm |fingers )", rest)  # not 'with the open hand'
    if names[0] in ("lift", "push", "turn") and (opened or " lid off " in rest):
        return "open", end  # lift the lid open, swing the door open, take the lid off
    if " upside down " in rest or (names[0] in ("turn", "press", "flip") and rest.endswith(" over ")):
        return "flip", end  # turn the glass upside down, turn the cup over
    if "turn" in names and "reorient" in names:
        return "turn", end
    return names[0], end


def read_instruction(instruction: str, assets: Sequence[dict]) -> Reading:
    """Read ``instruction`` against the catalog ``assets`` (see the module docstring); :class:`InstructionError`
    when it asks for something outside the skills or names objects that cannot play their parts."""
    text = " ".join(instruction.split())
    if not text:
        raise InstructionError("the instruction is empty; say what the hand should do, e.g. "
                               + "; ".join(f'"{s.example}"' for s in TASK_SKILLS.values()))
    said, note = restated(text)  # a reason after the request; 'the green one' after 'the blue cube'
    if note is not None:
        reading = read_instruction(said, assets)
        return dataclasses.replace(reading, instruction=text, notes=(*reading.notes, note))
    compound = read_compound(text, assets, lambda step: read_instruction(step, assets), _starts_with_verb,
                             lambda step: _skill(_words(step)))
    if compound is not None:  # steps in order, 'and' and a verb, several objects to one place
        return compound
    words = _words(text)
    _refuse_unbuilt(text, words)
    found = _skill(words)
    if found is None:
        raise InstructionError(f'"{text}" names no skill GenDex can perform. Possible requests:\n'
                               + skill_vocabulary())
    skill, verb_end = found
    in_hand = find(words, "in the hand") >= 0 or find(words, "in hand") >= 0 or find(words, "in its hand") >= 0
    names = _names(assets)
    # a name inside the verb is the verb: 'switch on the tap' (the verb), 'turn on the switch' (the object)
    spans = [sp for sp in _spans(words, names) if sp[0] >= verb_end or sp[2] not in _VERB_WORDS]
    # a colour that is also a name ('orange') right before another name is its colour: 'the orange block'
    spans = [sp for k, sp in enumerate(spans) if not (sp[2] in COLOR_WORDS and k + 1 < len(spans)
                                                      and spans[k + 1][0] == sp[1])]
    notes: list[str] = []
    mentions: list[Mention] = []
    at: list[int] = []  # where each mention starts in the words
    used = [False] * len(words)
    for i, j, phrase in spans:
        used[i:j] = [True] * (j - i)
        how, match = names[phrase]
        part = next((w for w in [*words[j:j + 2], *words[max(0, i - 1):i]] if w in PARTS), None) or next(
            (w for w in words[max(0, i - 3):i - 2] if w in PARTS and words[i - 2:i] == ["of", "the"]), None)
        if phrase in ("drawer", "drawers"):
            part = "drawer"
        ordinal = next((ORDINALS[w] for w in words[max(0, i - 2):i] if w in ORDINALS), None)
        if ordinal in ("top", "bottom") and part == "drawer" and skill in ("put_in", "take_out"):
            # things go in (and come out of) a chest's lowest drawer: its bottom one, the top one of a chest of one
            match = [a for a in match if ordinal == "bottom" or len(a.get("joints") or ()) == 1] or match
        elif ordinal:
            notes.append(f"'{ordinal} {phrase}': the solver acts on the {part or 'part'} the task's first joint "
                         "moves; which one is not chosen by its place")
        mentions.append(Mention(phrase, match[0]["id"], how, part, options=tuple(a["id"] for a in match)))
        at.append(i)
    # kind words ('a fruit') and unknown nouns, outside the catalog phrases and the verb
    relation, region, at_place = read_place(words, setting_down=skill in ("put_in", "place_on", "push"))
    no_object = amount_words(words) | at_place  # the words of an amount or a place
    unknown = []
    unread = []  # words no part of the reading takes: said in a note
    for k, w in enumerate(words):
        if (used[k] or k < verb_end or w in _STOP or w in PARTS or w in ORDINALS or k in no_object
                or (len(w) < 3 and not w.isdigit())):
            if k < verb_end and not (used[k] or w in _VERB_WORDS or w in _STOP or w in COURTESY_WORDS or w in PARTS
                                     or w in _FILLER or k in no_object or w in ORDINALS):
                unread.append(w)  # 'gently put ...'
            continue
        named_next = k > 0 and words[k - 1] in DETERMINERS and any(i == k + 1 for i, _, _ in spans)
        if (w in _VERB_WORDS and not named_next) or w in _FILLER:  # 'the empty bowl': a word about the bowl
            continue
        if mentions and at[-1] == k - 1 and mentions[-1].how == "kind" and w not in KINDS:
            mentions.pop()  # a kind word before an unknown one: one object the catalog lacks ('toy car': a toy)
            unknown.append((at.pop(), words[k - 1]))
        in_phrase = k > 0 and (words[k - 1] in DETERMINERS or (unknown and unknown[-1][0] == k - 1)
                               or used[k - 1] or (k + 1 < len(words) and used[k + 1]))
        if not in_phrase:  # not in a noun phrase: 'keep hold of it', 'without lifting it'
            unread += [w] if w not in COURTESY_WORDS else []
            continue
        after = next((mentions[n] for n, (i, _, _) in enumerate(spans) if i == k + 1), None)
        if w in KINDS and after is not None and (KINDS[w] in _by_id(assets, after.asset)["tags"]
                                                 or KINDS[w] == "graspable"):
            used[k] = True  # a kind word that says what the next name is: "the toy block" (its qualifier may
            continue        # come before it: "the large toy block")
        if w in KINDS and not (unknown and unknown[-1][0] == k - 1):
            mentions.append(Mention(w, "", "kind", None, f"any {KINDS[w]}"))
            at.append(k)
        else:  # an unknown word, or a kind word after one ('dragon fruit': a fruit the catalog lacks)
            unknown.append((k, w))
    roles = SKILL_ROLES[skill]
    if relation is not None and skill in ("put_in", "place_on", "push", "lift", "stack"):
        # 'put the apple to the left of the bowl', 'push the block left': set down there, seen from the robot
        skill = "place_at"
        roles = {"in_region": ("graspable",), "between": ("graspable", "landmark", "landmark")}.get(
            relation, SKILL_ROLES["place_at"])
    elif relation is not None and not (relation == "in_region" and at_place == {len(words) - 1}):
        raise InstructionError(f'"{text}" asks for a place ({relation.replace("_", " ")}'
                               + (f", {region}" if region else "") + f") with the '{skill}' skill: places are for "
                               "setting an object down (put, set, place, move, push)")
    if skill == "reorient" and not in_hand and not any(ROLE_TESTS["ball"](_by_id(assets, m.asset))
                                                       for m in mentions if m.asset):
        # 'rotate the faucet' is a turn; 'rotate the ball' (or anything 'in the hand') is a reorientation
        skill, roles = "turn", SKILL_ROLES["turn"]
    if skill == "place_on" and len(mentions) >= 2 and all(m.asset and is_block(_by_id(assets, m.asset))
                                                          for m in mentions[:2]):
        skill, roles = "stack", SKILL_ROLES["stack"]
    runs: list[list[tuple[int, str]]] = []
    for k, w in unknown:  # unknown words next to each other are one phrase ('dragon fruit')
        if runs and runs[-1][-1][0] == k - 1:
            runs[-1].append((k, w))
        else:
            runs.append([(k, w)])
    starts = {i: n for n, (i, _, _) in enumerate(spans)}
    for n, (i, _, _) in enumerate(spans):  # a name led by a kind word starts at the kind word
        while i > 0 and used[i - 1] and words[i - 1] in KINDS and i - 1 not in starts:
            i -= 1
            starts[i] = n
    ends = {j: n for n, (_, j, _) in enumerate(spans)}
    free = []
    for run in runs:  # a word right before or after a catalog name qualifies it ('left fridge'), it is no object
        n = starts.get(run[-1][0] + 1, ends.get(run[0][0]))
        if n is None or mentions[n].how not in ("id", "name", "synonym"):
            free.append(run)
            continue
        mentions[n], note = _qualified(mentions[n], [w for _, w in run], run[0][0] < spans[n][0], assets)
        at[n] = min(at[n], run[0][0])
        if note:
            notes.append(note)
    if unread:  # every word is read, or said to be not read
        notes.append(f"not understood, so it shapes nothing: {', '.join(repr(w) for w in unread)}")
    for run in free:  # a colour word in it is the colour to paint the stand-in ('the red toy car')
        colours = sorted({COLOR_WORDS[w] for _, w in run[:-1] if w in COLOR_WORDS})
        if len(colours) > 1:
            raise InstructionError(f"'{' '.join(w for _, w in run)}' names {len(colours)} colours "
                                   f"({', '.join(colours)}); an object is painted one colour")
        phrase = " ".join(w for _, w in run if w not in COLOR_WORDS or (_, w) == run[-1])
        kind = KINDS.get(run[-1][1])
        mentions.append(Mention(phrase, "", "substitute", None, f"a {kind}" if kind else "", (),
                                color=colours[0] if len(colours) == 1 else None))
        at.append(run[0][0])
    mentions = _one_per_object([m for _, m in sorted(zip(at, mentions, strict=True), key=lambda p: p[0])])
    amount, loose = read_amount(words)
    if loose:
        notes.append(loose)
    off = is_off(words)
    from generator.remaps import Read, object_skill  # the dexterous skills a verb means by its objects

    r = object_skill(Read(skill, roles, relation, region, mentions), words, text, assets)
    skill, roles, relation, region, mentions = r.skill, r.roles, r.relation, r.region, r.mentions
    direction = r.direction  # 'on': a cap screwed on
    if skill in ("push", "turn", "flip") and mentions and mentions[0].asset and ROLE_TESTS["pressable"](
            _by_id(assets, mentions[0].asset)):
        skill, roles = "press", SKILL_ROLES["press"]  # 'push the button', 'turn on the switch'
    if skill == "close" and mentions and mentions[0].asset and ROLE_TESTS["turnable"](
            _by_id(assets, mentions[0].asset)) and not ROLE_TESTS["openable"](_by_id(assets, mentions[0].asset)):
        skill, roles, direction = "turn", SKILL_ROLES["turn"], "off"  # 'close the valve', 'shut the tap'
        notes.append(f"closing the {mentions[0].phrase} is turning it off")
    elif skill == "turn":
        direction = "off" if off else "on"
    _refuse_unbuilt(text, words, skill, [m for m in mentions if m.qualifier and m.how in ("id", "name", "synonym")
                                         and not any(f"'{m.qualifier}' in" in n for n in notes)])
    resolved = [_own_color(m, assets) for m in _assign(skill, roles, mentions, assets, text)]
    for m in resolved:
        if m.color is not None and _by_id(assets, m.asset).get("joints"):
            raise InstructionError(f"'{m.phrase}': painting an articulated object ({m.asset}) is not built yet; ask "
                                   f"for it without a colour")
    return Reading(text, skill, tuple(resolved), tuple(notes), direction=direction, relation=relation,
                   region=region, amount=amount)


def _own_color(m: Mention, assets: Sequence[dict]) -> Mention:
    """``m`` with its colour dropped when it names the model of its options that has that colour as its own look
    (an articulated model's ``color``: 'the red button' is the emergency stop, not a button painted red)."""
    if m.color is None:
        return m
    own = [i for i in m.options or (m.asset,) if _by_id(assets, i).get("color") == m.color]
    return dataclasses.replace(m, asset=own[0], options=tuple(own), color=None) if own else m


def _refuse_unbuilt(text: str, words: list[str], skill: str | None = None,
                    qualified: Sequence[Mention] = ()) -> None:
    """:class:`InstructionError` when the request asks for a construct in :data:`NOT_BUILT` (a sequence, a
    direction, an amount, a place relative to something): built without it, the task would not be what was asked.
    Called before the verb is read (the phrases), and with the ``skill`` and the ``qualified`` mentions after (a
    last word ``left``/``right``/``off``: a direction unless it names a model or the skill opens a lid)."""
    if skill is None:
        found = [(what, c) for p, what, c in NOT_BUILT if find(words, p) >= 0]
        for i, w in enumerate(words):  # 'three blocks', 'all the fruit', 'both mugs'; not 'all the way'
            rest = words[i + 1:i + 3]
            nxt = rest[1] if rest[:1] == ["the"] and len(rest) > 1 else (rest[0] if rest else "")
            plural = nxt.endswith("s") and not nxt.endswith("ss") and nxt != "drawers"
            if w in GROUP_WORDS and nxt and nxt not in ("way", "time", "degrees") and (
                    plural or w in ("all", "both", "every")):
                found.append((f"several objects ('{w} {nxt}')", "groups of objects other than two or three put "
                              "in or set on one place ('put all the fruit in the pot'), or towers of anything but "
                              "blocks,"))
    else:
        chose = {w for m in qualified for w in m.qualifier.split()}  # 'left fridge': a model, not a side
        last = words[-1]
        found = []
        if last in ("left", "right") and last not in chose and skill != "place_at":  # 'close the door left'
            found.append((f"a direction ('{last}')", f"a direction with the '{skill}' skill"))
        amount = read_amount(words)[0]
        if amount is not None and (skill not in ("open", "turn") or (skill == "turn" and is_off(words))):
            found.append((f"an amount ('{amount}')", f"part-way moves with the '{skill}' skill"))
        if skill not in ("open", "turn") and is_off(words):
            found.append(("a direction ('off')", f"turning off with the '{skill}' skill"))  # 'switch off the oven'

    if found:
        what, construct = found[0]
        raise InstructionError(
            f'"{text}" asks for {what}: the author and the solver do not build {construct} yet, and a task '
            f"without it would not be what you asked. Ask for one of these instead:\n{skill_vocabulary()}")


QUALIFIER_WORDS = {"one": "1", "two": "2", "three": "3", "four": "4", "single": "1", "double": "2", "triple": "3",
                   "big": "large", "huge": "large", "little": "small", "tiny": "small", "tallest": "tall"}
"""Qualifier words as catalog ids spell them (`drawer_chest_3`, `bowl_large`)."""


def _qualified(m: Mention, words: list[str], before: bool, assets: Sequence[dict]) -> tuple[Mention, str]:
    """``m`` with the qualifying ``words`` a person put next to it: a colour word is the colour the task paints it
    (:data:`gendex_envs.attributes.COLOR_WORDS`); the others choose the models of its name whose id has one of them
    (``left`` -> ``refrigerator_left_hinge``; ``three`` -> ``drawer_chest_3``), or, when none has, keep the same
    models with a note saying the words chose nothing."""
    qualifier = " ".join(words)
    phrase = f"{qualifier} {m.phrase}" if before else f"{m.phrase} {qualifier}"
    category = _by_id(assets, m.asset)["category"]
    models = [a for a in assets if a["id"] == m.asset or ((m.how != "id" or m.asset == category)
                                                            and a["category"] == category)]
    colours = sorted({COLOR_WORDS[w] for w in words if w in COLOR_WORDS})
    if len(colours) > 1:
        raise InstructionError(f"'{phrase}' names {len(colours)} colours ({', '.join(colours)}); an object is "
                               "painted one colour")
    if colours:
        m = dataclasses.replace(m, color=colours[0])
    keys = {QUALIFIER_WORDS.get(w, w) for w in words if w not in COLOR_WORDS}
    chosen = [a for a in models if any(p.startswith(k) for k in keys for p in a["id"].split("_"))]
    if not chosen:
        note = (f"'{qualifier}' in '{phrase}' matches none of the catalog's {category.replace('_', ' ')} models "
                f"({', '.join(a['id'] for a in models)}); read as '{m.phrase}'") if keys else ""
        return dataclasses.replace(m, phrase=phrase, qualifier=qualifier), note
    ids = tuple(a["id"] for a in chosen)
    return dataclasses.replace(m, phrase=phrase, asset=ids[0], options=ids, qualifier=qualifier), ""


def _one_per_object(mentions: list[Mention]) -> list[Mention]:
    """One mention per object named twice (*the drawer of the dresser*: both words name the drawer chests; *the
    two-drawer dresser*: one of them); the narrower reading is kept, then the more specific wording (an id before a
    name before a synonym)."""
    rank = {"id": 0, "name": 1, "synonym": 2}
    out: list[Mention] = []
    for m in mentions:
        same = next((k for k, o in enumerate(out) if m.how in rank and o.how in rank and o.options and m.options
                     and o.color == m.color  # the red block and the blue block are two blocks
                     and (set(o.options) <= set(m.options) or set(m.options) <= set(o.options))), None)
        if same is None:
            out.append(m)
            continue
        o = out[same]
        if (len(m.options), rank[m.how]) < (len(o.options), rank[o.how]):
            out[same] = m
    return out


def _by_id(assets: Sequence[dict], asset_id: str) -> dict:
    return next(a for a in assets if a["id"] == asset_id)


def _assign(skill: str, roles: tuple[str, ...], mentions: list[Mention], assets: Sequence[dict],
            text: str) -> list[Mention]:
    """Give each role of ``skill`` an object: the named ones in order when they can play it, else the closest
    catalog object that can (a substitution); :class:`InstructionError` when a named object cannot play its part."""
    out: list[Mention] = []
    pending = list(mentions)
    for role in roles:
        test = ROLE_TESTS[role]
        able = [a for a in assets if test(a)]
        m = pending.pop(0) if pending else None
        if m is None:
            choice = sorted(able, key=lambda a: a["id"])[0]
            out.append(Mention(f"(a {role} object)", choice["id"], "kind", None,
                               f"the request names no {role} object; chose {choice['id']}",
                               tuple(sorted(a["id"] for a in able))))
            continue
        if m.how == "kind":
            tag = KINDS[m.phrase]
            kind = [a for a in able if tag in a["tags"] or tag == "graspable"]
            if not kind:
                raise InstructionError(f"no {m.phrase} in the catalog can be the {role} object of '{skill}' "
                                       f"({TASK_SKILLS[skill].objects}); {role} objects: "
                                       + ", ".join(a["id"] for a in able))
            ids = tuple(sorted(a["id"] for a in kind))
            out.append(dataclasses.replace(m, asset=ids[0], options=ids, detail=f"a {m.phrase}: chose from "
                                                                                 f"{len(ids)}"))
            continue
        if m.how == "substitute":  # the kind a word says ('toy car': a toy), then the nearest in meaning
            into = mentions[1].asset if skill == "put_in" and len(mentions) > 1 and mentions[1].asset else None
            out.append(stand_in(m, able, role, skill, None if into is None else _by_id(assets, into)))
            continue
        kind = _by_id(assets, m.asset)["category"]
        named = [a for a in assets if a["id"] == m.asset or (m.how != "id" and a["category"] == kind)]
        if m.asset == kind and not test(_by_id(assets, m.asset)):  # a name that is its kind's too names its kind
            named = [a for a in assets if a["category"] == kind]  # where it cannot play the role ('the sponge')
        if m.options and (m.qualifier or m.part == "drawer"):  # 'the right fridge', 'the top drawer': only the
            # models the qualifier or the drawer's place chose
            named = [a for a in named if a["id"] in m.options]
        fit = [a for a in named if test(a)]
        if m.part is not None and role in ("openable",):
            fit = [a for a in fit if m.part in part_kinds(a)] or fit
        if not fit:
            raise InstructionError(
                f"'{skill}' needs {TASK_SKILLS[skill].objects}, and '{m.phrase}' ({m.asset}) cannot be its {role} "
                f"object. Objects that can: {', '.join(sorted(a['id'] for a in able)) or 'none'}.\n"
                f"Possible requests:\n{skill_vocabulary()}")
        chosen = fit[0] if m.asset not in {a["id"] for a in fit} else _by_id(assets, m.asset)
        ids = tuple(a["id"] for a in fit)
        out.append(dataclasses.replace(m, asset=chosen["id"], options=ids,
                                       detail=f"one of {', '.join(ids)}" if len(ids) > 1 else ""))
    for m in pending:
        if m.how == "substitute":
            raise InstructionError(f"'{m.phrase}' in \"{text}\" is not an object of the catalog and has no part in "
                                   f"'{skill}' ({TASK_SKILLS[skill].objects})")
        raise InstructionError(f"'{m.phrase}' ({m.asset}) in \"{text}\" has no part in a '{skill}' task, which acts "
                               f"on {TASK_SKILLS[skill].objects}; ask for one task at a time")
    return out


__all__ = ["KINDS", "SKILL_ROLES", "SYNONYMS", "TASK_SKILLS", "InstructionError", "Mention", "Reading", "TaskSkill",
           "drawers", "read_instruction", "skill_vocabulary"]
