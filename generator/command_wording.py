"""Every wording of a command that asks for the same task: its templates swapped, its objects and the table called by
their other names, each kept only where the instruction reader reads it exactly as it reads the command.

A library worded from one template per sentence shape reads alike however its situations and purposes vary (206
tasks measured a mean pairwise all-MiniLM-L6-v2 cosine of 0.333 on their commands alone). People ask for one thing in
many ways; :func:`wordings` lists the ways the offline author knows for a written command:

- each clause (the author joins steps with *, then*) is matched against the author's templates
  (:data:`generator.phrasing.COMMANDS`); a clause that matches one is written with every template of that kind;
- each object phrase in it is also said with the category's other words (:data:`generator.phrasing.NAMES`: *pot*,
  *saucepan*, *cooking pot*), keeping its colour, size or model word (*red*, *small*, *left-hinged*);
- the word for the table is any of :data:`generator.phrasing.SURFACES`;
- a step no template matches (a group of objects) starts with another verb of putting in or on (:data:`VERBS`).

**What keeps a wording faithful is the reader, not the templates**: a candidate survives only when
:func:`generator.instruction.read_instruction` reads it as the same skill, the same objects (the same catalog
choices, colours and parts), direction, relation, region, amount and steps as the command itself, with no word it
does not understand that neither the command nor the author's templates have, and no object called two things in two
steps. A command the reader cannot read keeps its words.
"""

from __future__ import annotations

import functools
import itertools
import re
from collections.abc import Sequence

import numpy as np

from generator.command_templates import COMMANDS, PLACE_AT
from generator.errors import InstructionError
from generator.instruction import Reading, read_instruction
from generator.phrasing import NAMES, SURFACES, awkward

STEP_JOINER = ", then "
"""How the offline author joins the steps of a composed command (:func:`generator.phrasing.phrase_parts`)."""
MAX_WORDINGS = 240
"""Most candidate wordings tried for one command (a three-step command has thousands): a seeded sample of them,
the command itself always first."""
TEMPLATES: dict[str, tuple[str, ...]] = {**COMMANDS, "place_at": PLACE_AT}
"""Every template the author words a command from, by kind."""
SLOTS = "odsapw"
"""Template slots: the object acted on, the destination or articulated object, the table, an amount, the pieces,
where a placed object goes."""
PLACES: tuple[tuple[str, ...], ...] = (
    ("to the left of", "on the left side of", "left of"),
    ("to the right of", "on the right side of", "right of"),
    ("in front of", "just in front of", "on the near side of"),
    ("behind", "just behind", "on the far side of"),
    ("next to", "beside", "alongside", "close to", "near"),
    ("between", "in between", "midway between"),
    ("on the", "in the"),
)
"""Ways of saying where a placed object goes that mean the same (each row), by how the place phrase starts; the
reader decides which of them, with what follows (*in the far right corner*, not *in the near side*), read alike.
None starts with *at*: *move the ball at the corner* is what *move* makes of it."""
PATTERNS = {
    "w": "(?:" + "|".join(sorted({p for row in PLACES for p in row}, key=len, reverse=True)) + ") .+",
    "a": r"(?:halfway|half|partly|partway|\d+ degrees|top |middle |bottom |)",
    "s": "|".join(SURFACES),
}
"""What a slot matches where not any words: where a placed object goes (a relation and what follows, so *the tennis
ball on the far side* never splits inside the object's name), how far (or which drawer), the table."""
PLACE_WORDS = re.compile(r"\b((side|corner|middle|left|right|front|back) of|behind|between|next to|beside|"
                         r"alongside|near|close to)\b")
"""Words no object phrase of a template other than a place's has: a place read as an object (*lay the brick on
the near right corner of the table*) is not a plate."""


@functools.cache
def _templates() -> tuple[tuple[str, re.Pattern], ...]:
    """(kind, pattern) for every command template: a slot matches the words it stood for, and a slot that appears
    twice must match the same words both times."""
    out = []
    for kind, templates in TEMPLATES.items():
        for t in templates:
            seen: set[str] = set()
            pattern = ""
            for piece in re.split(r"(\{[a-z]\})", t):
                if re.fullmatch(r"\{[a-z]\}", piece):
                    k = piece[1]
                    pattern += f"(?P={k})" if k in seen else f"(?P<{k}>{PATTERNS.get(k, '.+?')})"
                    seen.add(k)
                else:
                    pattern += re.escape(piece)
            out.append((kind, re.compile(f"^{pattern}$")))
    return tuple(out)


VERBS = (
    ("put", "place", "drop", "transfer", "deposit", "pop", "stow", "store", "move"),  # into
    ("put", "place", "set", "lay", "move"),  # onto
)
"""Verbs a step no template matches (a group: *put all the fruit into the pot*) may start with instead of one
another, by whether it puts into or onto; the reader still decides which of them ask for the same task."""


def _verb_swaps(clause: str) -> list[str]:
    verbs = VERBS[0] if re.search(r"\b(into|inside|in)\b", clause) else VERBS[1]
    v = next((v for v in verbs if clause.startswith(v + " ")), None)
    return [] if v is None else [w + clause[len(v):] for w in verbs if w != v]


@functools.cache
def _name_words() -> tuple[tuple[str, tuple[str, ...]], ...]:
    """(word, its category's words) for every word of :data:`NAMES`, longest first (so *serving bowl* is found
    before *bowl*)."""
    pairs = {w: words for words in NAMES.values() for w in words}
    return tuple(sorted(pairs.items(), key=lambda kv: -len(kv[0])))


def names(phrase: str) -> list[str]:
    """``phrase`` (an object phrase of a command) with the category word at its end said every way the author
    says it, the words before it (colour, size, model) kept: ``red mixing bowl`` -> ``red bowl``, ``red serving
    bowl``, ...; ``[phrase]`` when it ends in no known word."""
    for word, words in _name_words():
        if phrase == word or phrase.endswith(" " + word):
            head = phrase[: len(phrase) - len(word)]
            return list(dict.fromkeys([phrase, *(head + w for w in words)]))
    return [phrase]


def places(where: str) -> list[str]:
    """``where`` (a placed object's place phrase) and the same place said the other ways of its row of
    :data:`PLACES` (the longest start that matches), its objects by their other names (:func:`names`); a region of
    the table only with *on* or *in* (not *in front of the table*; *in* only for a corner or the middle)."""
    if where.split()[-1] in SURFACES:  # a region: 'on the far right corner of the table'
        start = next((p for p in PLACES[-1] if where.startswith(p + " ")), None)
        if start is None:
            return [where]
        rest = where[len(start) + 1:]
        row = PLACES[-1] if re.search(r"\b(corner|middle|centre)\b", rest) else ("on the",)
        return list(dict.fromkeys([where, *(f"{p} {rest}" for p in row)]))
    start = next((p for p in sorted((p for row in PLACES for p in row), key=len, reverse=True)
                  if where.startswith(p + " the ")), None)
    if start is None:
        return [where]
    rest = where[len(start) + 5:]
    row = next(r for r in PLACES if start in r)
    objects = [names(o) for o in rest.split(" and the ")]
    said = [" and the ".join(combo) for combo in itertools.product(*objects)]
    return list(dict.fromkeys([where, *(f"{p} the {o}" for p in row for o in said)]))


def _fill(template: str, slots: dict[str, str]) -> str | None:
    needed = set(re.findall(r"\{([a-z])\}", template))
    if not needed <= set(slots):
        return None
    if awkward(template, slots):
        return None  # not 'the chest of drawers's drawer', 'the box with a lid's lid'
    return template.format(**{k: slots.get(k, "") for k in SLOTS})


def clause_wordings(clause: str) -> list[str]:
    """Every wording of one step of a command the templates and names give (``clause`` itself first); not yet
    checked by the reader."""
    out = [clause]
    for kind, pattern in _templates():
        m = pattern.match(clause)
        if m is None:
            continue
        found = m.groupdict()
        if kind != "place_at" and any(PLACE_WORDS.search(found.get(k) or "") for k in "od"):
            continue
        choices = {k: (names(v) if k in "od" else list(SURFACES) if k == "s" else places(v) if k == "w" else [v])
                   for k, v in found.items()}
        keys = sorted(choices)
        for values in itertools.product(*(choices[k] for k in keys)):
            slots = dict(zip(keys, values, strict=True))
            for other in TEMPLATES[kind]:
                text = _fill(other, slots)
                if text is not None:
                    out.append(text)
    if len(out) == 1:  # no template (a group: 'put all the fruit in the pot'): other names, other verbs
        for word, words in _name_words():
            if re.search(rf"\b{re.escape(word)}\b", clause):
                out += [re.sub(rf"\b{re.escape(word)}\b", w, clause, count=1) for w in words]
                break
        out += [x for text in out for x in _verb_swaps(text)]
    return list(dict.fromkeys(out))


@functools.cache
def _variant_of(asset_id: str) -> str | None:
    """The object a colour variant copies (``params["variant_of"]``), else None."""
    from gendex_envs.assets.catalog import catalog

    record = catalog().get(asset_id)
    return None if record is None else record.entry.params.get("variant_of")


def _mention_key(m) -> tuple:
    """The catalog choices of mention ``m`` with its colour, part and group (for one of a group, the group alone).
    Colour variants whose base is among the choices are left out: *the dinner plate* and *the plate* choose the same
    plate, whatever colours the catalog also has it in (*the blue plate* is the variant itself)."""
    if m.group:  # one of a group (*all the fruit*): which members is the reader's choice from the catalog, not words
        return ((), m.color, m.part, m.group)
    options = m.options or (m.asset,)
    kept = tuple(sorted(o for o in options if _variant_of(o) not in options))
    return (kept, m.color, m.part, m.group)


def reading_key(r: Reading) -> tuple:
    """What a reading asks for, whatever the words: skill, objects (the catalog choices, colour, part, group),
    direction, relation, region, amount and the steps after it."""
    return (r.skill, tuple(_mention_key(m) for m in r.objects), r.direction, r.relation, r.region, r.amount,
            tuple(reading_key(x) for x in r.then))


def _names_per_object(r: Reading) -> int:
    """How many names the steps of ``r`` give its objects beyond one each: *drop the ball in the mixing bowl, then
    the peach in the serving bowl* reads as two bowls to a person, whatever the reader makes of it."""
    said: dict[tuple, set[str]] = {}
    for m in r.all_objects:
        said.setdefault(_mention_key(m), set()).add(m.phrase)
    return sum(len(v) - 1 for v in said.values())


def _not_understood(r: Reading) -> set[str]:
    """The words the reader reports it did not understand, in every step."""
    out = {w for n in r.notes if "not understood" in n for w in re.findall(r"'([^']+)'", n)}
    return out.union(*(_not_understood(x) for x in r.then))


@functools.cache
def _template_words() -> frozenset[str]:
    """Every word of the author's templates: each template reads back as its task (a test holds them to it), so a
    word of them the reader passes over (*no further*, *and stop*) shapes nothing there."""
    texts = [t for ts in TEMPLATES.values() for t in ts]
    return frozenset(w for t in texts for w in re.findall(r"[a-z]+", re.sub(r"\{[a-z]\}", " ", t)))


def wordings(command: str, assets: Sequence[dict], limit: int = MAX_WORDINGS, seed: int = 0) -> list[str]:
    """Every wording of ``command`` (a bare command: no situation, no purpose) that the reader reads as it reads
    ``command`` (see the module docstring), ``command`` first; at most ``limit`` candidates are read (a sample
    drawn by ``seed`` when there are more). ``[command]`` when the reader cannot read it."""
    try:
        reference = read_instruction(command, assets)
    except InstructionError:
        return [command]
    key, vague, named = reading_key(reference), _not_understood(reference), _names_per_object(reference)
    steps = [clause_wordings(c) for c in command.split(STEP_JOINER)]
    total = int(np.prod([len(s) for s in steps]))
    if total <= limit:
        combos = list(itertools.product(*steps))
    else:
        rng = np.random.default_rng(seed)
        combos = {tuple(s[int(rng.integers(len(s)))] for s in steps) for _ in range(limit)}
        combos = sorted(combos)
    out = [command]
    for combo in combos:
        text = STEP_JOINER.join(combo)
        if text in out:
            continue
        try:
            r = read_instruction(text, assets)
        except InstructionError:
            continue
        if (reading_key(r) == key and _not_understood(r) - vague <= _template_words()
                and _names_per_object(r) <= named):
            out.append(text)
    return out


__all__ = ["MAX_WORDINGS", "PLACES", "STEP_JOINER", "TEMPLATES", "VERBS", "clause_wordings", "names", "places",
           "reading_key", "wordings"]
