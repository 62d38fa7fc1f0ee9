"""The offline author's tasks for requests of several steps in order (*close the microwave, then set the bottle on
the plate*; *put the lemon and the plum in the bowl*) and for towers: each step written as its own guided task, then
joined into one composed task (every step's success condition, the steps in turn) where the solver measurably does
them in turn, else refused saying what it joins.

What it joins (:data:`WRITES`): first, at most one door or lid the open hand closes (or a lid it opens); then up to
:data:`MAX_RIGID_STEPS` rigid steps, each moving another object (lifted, put in a container, set down on or by
something, stacked), where later steps may put things in or on what earlier ones used; a lift only last (the object
is still held at the end); last, the lid of a box or bin a step put something in, shut by the open hand (*put the
dice in the box and shut the lid*). A lift followed by a step that moves the same object is that step (*pick up the
apple, then put it in the bowl* is the put)."""

from __future__ import annotations

import json
import re
from collections.abc import Callable

from generator.backends.layouts import ARTICULATED_LAYOUTS
from generator.errors import InstructionError
from generator.phrasing import split

RIGID_SUCCESS = ("lifted", "inside", "near", "over", "placed")
"""Success types of a rigid step: an object lifted or set down somewhere."""
MAX_RIGID_STEPS = 3
"""Rigid steps one task joins (each a reach, grasp, carry and release: three fit the episode's time)."""
WRITES = ("a door or lid the open hand closes (or a lid it opens) first, then up to three steps that each lift, put "
          "in, set down or stack another object, then the lid of a box or bin they put something in shut")


def _first_is_composable(first: dict, acts: dict[str, str]) -> bool:
    """Whether ``first`` is an articulated part the open hand leaves free, measured: a close, or a lid pressed open."""
    if len(first["objects"]) != 1 or first["objects"][0]["role"] != "articulated":
        return False
    o = first["objects"][0]
    layout = ARTICULATED_LAYOUTS.get((acts.get(o["name"], ""), o["asset"]))
    return (layout is not None and not layout["grasp"] and bool(layout["measured"])
            and acts.get(o["name"]) in ("close", "open") and layout.get("composed", True))


def _is_rigid(step: dict) -> bool:
    """A step that moves a rigid object (into a box or bin with a lid, too)."""
    roles = {o["name"]: o["role"] for o in step["objects"]}
    return (step["success"]["type"] in RIGID_SUCCESS and not step.get("also")
            and roles.get(step["success"]["object"]) != "articulated")


def _shuts_what_was_filled(step: dict, before: list[dict], acts: dict[str, str]) -> bool:
    """Whether ``step`` shuts the lid of a box or bin a step ``before`` put something into, by the press measured on
    it (*put the dice in the box and shut the lid*)."""
    if len(step["objects"]) != 1 or step["objects"][0]["role"] != "articulated":
        return False
    o = step["objects"][0]
    layout = ARTICULATED_LAYOUTS.get(("close", o["asset"]))
    return (acts.get(o["name"]) == "close" and layout is not None and bool(layout["measured"])
            and any(b["success"].get("target") == o["name"] and b["success"]["type"] == "inside" for b in before))


def _moves(step: dict) -> str:
    """The name of the object a rigid step moves (its success condition's object)."""
    return step["success"]["object"]


def _one_word_each(commands: list[str], steps: list[dict], names_of: Callable[[str], tuple[str, ...]]) -> list[str]:
    """``commands`` with an object that several steps name called by the word the first of them used (each step is
    worded on its own: *the mixing bowl*, then *the serving bowl* would read as two bowls); not where another object
    of the task has the same words."""
    out = list(commands)
    assets = [o["asset"] for s in steps for o in s["objects"]]
    for k, step in enumerate(steps[1:], 1):
        for o in step["objects"]:
            words = sorted(names_of(o["asset"]), key=len, reverse=True)
            others = {a for a in assets if a != o["asset"]}
            if any(set(words) & set(names_of(a)) for a in others):
                continue
            earlier = next((c for c, st in zip(commands[:k], steps[:k], strict=True)
                            if any(x["asset"] == o["asset"] for x in st["objects"])), None)
            said = next((w for w in words if earlier and re.search(rf"\b{re.escape(w)}\b", earlier)), None)
            if said is not None:
                out[k] = re.sub("|".join(rf"\b{re.escape(w)}\b" for w in words), said, out[k])
    return out


def join_steps(steps: list[dict], acts: Callable[[dict], dict[str, str]], existing: set[str],
               names_of: Callable[[str], tuple[str, ...]] = lambda asset: ()) -> dict:
    """One composed proposal of the step proposals ``steps`` (in order), or :class:`InstructionError` when this
    author does not join them (see the module docstring). ``names_of``: the words a command may call an asset by
    (one word for an object several steps name)."""
    kept: list[dict] = []
    for s in steps:  # a lift, then a step that moves the same object: that step alone
        if kept and kept[-1]["success"]["type"] == "lifted" and _is_rigid(s) and _moves(s) == _moves(kept[-1]):
            kept.pop()
        kept.append(s)
    if len(kept) == 1:
        return _unique(kept[0], existing)
    first, rest = (kept[0], kept[1:]) if _first_is_composable(kept[0], acts(kept[0])) else (None, list(kept))
    last = rest.pop() if len(rest) > 1 and _shuts_what_was_filled(rest[-1], rest[:-1], acts(rest[-1])) else None
    if first is not None and last is not None and first["objects"][0]["name"] == last["objects"][0]["name"]:
        raise InstructionError("the offline author opens a lid first or shuts it last, not both (the lid starts shut "
                               "for the one, open for the other)")
    if not all(_is_rigid(s) for s in rest) or len(rest) > MAX_RIGID_STEPS:
        names = ", then ".join(f"'{s['name']}'" for s in kept)
        raise InstructionError(f"the offline author writes steps in order only as {WRITES}; it cannot write {names} "
                               "as one task yet")
    if any(s["success"]["type"] == "lifted" for s in (rest if last is not None else rest[:-1])):
        raise InstructionError("a lifted object must still be held when the task ends, so the offline author writes a "
                               "lift as the last step only (one hand cannot hold it and work on)")
    moved = [_moves(s) for s in rest]
    if len(set(moved)) != len(moved):
        raise InstructionError(f"two steps move the same object ({', '.join(moved)}); the offline author joins steps "
                               "that each move another object")
    objects: dict[str, dict] = {}
    for s in kept:
        for o in s["objects"]:
            seen = objects.setdefault(o["name"], o)
            if seen["asset"] != o["asset"]:
                raise InstructionError(f"two steps name '{o['name']}' for different objects ({seen['asset']}, "
                                       f"{o['asset']}); name them apart")
    if first is not None and first["objects"][0]["name"] in moved:
        raise InstructionError("a step moves the object whose door or lid the first step works; the offline author "
                               "joins steps on different objects only")
    commands = _one_word_each([split(s["description"])[1].rstrip(".") for s in kept], kept, names_of)
    text = ", then ".join(c for c in commands if c)  # a group's later steps are said by its first (_said_as_group)
    texts = [s["success_text"].rstrip(".") for s in kept]
    return _unique({
        "name": "Then".join(s["name"] for s in kept if s["name"]), "description": text[:1].upper() + text[1:] + ".",
        "objects": list(objects.values()), "steps": [st for s in kept for st in s["steps"]],
        "success": kept[0]["success"], "also": [s["success"] for s in kept[1:]],
        "success_text": ", and ".join([texts[0]] + [t[:1].lower() + t[1:] for t in texts[1:]]) + ".",
        "substitutions": {k: v for s in kept for k, v in s.get("substitutions", {}).items()},
    }, existing)


def _unique(proposal: dict, existing: set[str]) -> dict:
    """``proposal`` named apart from the ``existing`` tasks (a number after its name)."""
    base, k = proposal["name"], 2
    while proposal["name"] in existing:
        proposal = proposal | {"name": f"{base}{k}"}
        k += 1
    return proposal


def sequence_task(propose_step: Callable[[dict], dict], reading: dict, acts: Callable[[dict], dict[str, str]],
                  existing: set[str], names_of: Callable[[str], tuple[str, ...]] = lambda asset: ()) -> dict:
    """The proposal for a reading of several steps (its ``then``), from ``propose_step(step_reading)`` (one step's
    guided proposal); :class:`InstructionError` when the steps are not ones this author joins."""
    readings = [reading | {"then": []}, *(reading.get("then") or [])]
    steps: list[dict] = []
    for r in readings:  # an object of an earlier step is the same model later ('open the bin, then drop ... in it')
        used = {o["asset"] for s in steps for o in s["objects"]}
        objects = [m | {"asset": a, "options": [a]} if (a := next((x for x in m.get("options") or () if x in used),
                                                                    None)) else m for m in r["objects"]]
        steps.append(_named_apart(propose_step(r | {"objects": objects}), steps))
    return join_steps(_said_as_group(steps, readings, names_of), acts, existing, names_of)


def _named_apart(step: dict, before: list[dict]) -> dict:
    """``step`` with an object named as an object of a step ``before`` but another model (*the two blocks*: the
    medium and the large block) renamed by its id, everywhere the step names it."""
    seen = {o["name"]: o["asset"] for s in before for o in s["objects"]}
    for o in step["objects"]:
        if seen.get(o["name"], o["asset"]) != o["asset"]:
            old, new = o["name"], o["asset"]
            said = " ".join(reversed(new.split("_", 1)))  # block_large -> 'large block'

            def swap(x, old=old, new=new, said=said):
                if isinstance(x, dict):
                    return {k: (new if k in ("name", "object", "target", "other") and v == old else swap(v))
                            for k, v in x.items()}
                if isinstance(x, list):
                    return [swap(v) for v in x]
                return re.sub(rf"\bthe {re.escape(old)}\b", f"the {said}", x) if isinstance(x, str) else x

            step = swap(step)
    return step


def _said_as_group(steps: list[dict], readings: list[dict], names_of: Callable[[str], tuple[str, ...]]) -> list[dict]:
    """``steps`` with the steps of a group (*put all the fruit in the pot*: one step per fruit) said as the person
    said them: the first step's command with its object called by the group's words, the others said by it."""
    out = list(steps)
    groups = [(r["objects"][0].get("group") or "") if r["objects"] else "" for r in readings]
    for k, group in enumerate(groups):
        if not group or (k and groups[k - 1] == group):
            continue
        members = [j for j in range(k, len(readings)) if groups[j] == group]
        command = split(out[k]["description"])[1].rstrip(".")
        words = sorted(names_of(out[k]["objects"][0]["asset"]) or (out[k]["objects"][0]["name"],), key=len,
                       reverse=True)
        said = re.sub(rf"\b(the|a|an) ({'|'.join(re.escape(w) for w in words)})\b", group, command, count=1)
        if said == command:
            continue  # not said by a word of its object: each step keeps its own command
        if not group.startswith(("every ", "each ")):  # several things: 'let them go', not 'let it go'
            said = re.sub(r"\bit\b", "them", re.sub(r"\bits\b", "their", said))
        camel = "".join(w.capitalize() for w in group.split() if w not in ("the", "of"))  # 'AllFruit'
        names = sorted(({"".join(p.capitalize() for p in re.split(r"[_\s]+", w)) for w in words}
                        | {"".join(p.capitalize() for p in out[k]["objects"][0]["asset"].split("_"))}), key=len,
                       reverse=True)
        name = re.sub("|".join(re.escape(n) for n in names), camel, out[k]["name"], count=1)
        out[k] = out[k] | {"description": said[:1].upper() + said[1:] + ".", "name": name}
        for j in members[1:]:
            out[j] = out[j] | {"description": "", "name": ""}
    return out


def parse_step(text: str) -> dict:
    """The proposal dict of a fenced JSON answer."""
    return json.loads(text.split("```json\n", 1)[1].rsplit("```", 1)[0])


__all__ = ["MAX_RIGID_STEPS", "RIGID_SUCCESS", "WRITES", "join_steps", "parse_step", "sequence_task"]
