"""The offline author's tasks for requests of several steps in order (*close the microwave, then set the bottle on
the plate*): each step written as its own guided task, then joined into one composed task (both success conditions,
the steps in turn) where the solver measurably does the two in turn, else refused saying what it writes."""

from __future__ import annotations

import json
from collections.abc import Callable

from generator.backends.layouts import ARTICULATED_LAYOUTS
from generator.errors import InstructionError
from generator.phrasing import split

SECOND_SUCCESS = ("lifted", "inside", "near", "over", "placed")
"""Success types a second step may have: a rigid object lifted or set down somewhere."""
WRITES = ("a door or lid the open hand closes (or a lid it opens), then lifting an object, putting it in a "
          "container or setting it down on or by something")


def _first_is_composable(first: dict, acts: dict[str, str]) -> bool:
    """Whether ``first`` is an articulated part the open hand leaves free, measured: a close, or a lid pressed open."""
    if len(first["objects"]) != 1 or first["objects"][0]["role"] != "articulated":
        return False
    o = first["objects"][0]
    layout = ARTICULATED_LAYOUTS.get((acts.get(o["name"], ""), o["asset"]))
    return (layout is not None and not layout["grasp"] and bool(layout["measured"])
            and acts.get(o["name"]) in ("close", "open") and layout.get("composed", True))


def sequence_task(propose_step: Callable[[dict], dict], reading: dict, acts: Callable[[dict], dict[str, str]],
                  existing: set[str]) -> dict:
    """The proposal for a two-step ``reading`` (its ``then``), from ``propose_step(step_reading)`` (one step's
    guided proposal); :class:`InstructionError` when the steps are not ones this author joins."""
    then = reading.get("then") or []
    if len(then) != 1:
        raise InstructionError(f"the offline author writes at most two steps in order ({WRITES}); the request has "
                               f"{len(then) + 1}")
    first = propose_step(reading | {"then": []})
    second = propose_step(then[0])
    if not _first_is_composable(first, acts(first)) or any(o["role"] == "articulated" for o in second["objects"]) \
            or second["success"]["type"] not in SECOND_SUCCESS:
        raise InstructionError(f"the offline author writes two steps in order only as {WRITES}; it cannot write "
                               f"'{first['name']}' then '{second['name']}' as one task yet")
    if {o["name"] for o in first["objects"]} & {o["name"] for o in second["objects"]}:
        raise InstructionError("the two steps name the same object; the offline author joins steps on different "
                               "objects only")
    name, k = f"{first['name']}Then{second['name']}", 2
    base = name
    while name in existing:
        name, k = f"{base}{k}", k + 1
    commands = [split(p["description"])[1].rstrip(".") for p in (first, second)]
    text = ", then ".join(commands)
    rest = second["success_text"]
    return {
        "name": name, "description": text[:1].upper() + text[1:] + ".",
        "objects": first["objects"] + second["objects"], "steps": first["steps"] + second["steps"],
        "success": first["success"], "also": [second["success"]],
        "success_text": f"{first['success_text'][:-1]}, and {rest[:1].lower()}{rest[1:]}",
        "substitutions": {**first.get("substitutions", {}), **second.get("substitutions", {})},
    }


def parse_step(text: str) -> dict:
    """The proposal dict of a fenced JSON answer."""
    return json.loads(text.split("```json\n", 1)[1].rsplit("```", 1)[0])


__all__ = ["SECOND_SUCCESS", "WRITES", "parse_step", "sequence_task"]
