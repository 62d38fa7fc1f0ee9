"""The offline author's tasks of dexterous skills that need an exact fit, a press or a tip of the wrist: a peg put
into the hole it fits (``insert``), a spill wiped with a sponge pressed down on it (``wipe``), a mug hung by its
handle on a peg (``hang``), the beads in a glass poured into a bowl (``pour``) and a glass turned upside down on the
table (``flip``); and what a task that moves an articulated object asks (:func:`joint_goal`). Each ``*_task``
returns a proposal (a dict, as :mod:`generator.backends.offline` writes them); ``words(name)`` is the author's
generator that words a task."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from generator.backends.wording import camel, carry_steps, step, word
from generator.phrasing import MODEL_WORDS, painted, phrase, qualifiers

INSERT_XY_M = 0.005
"""An inserted peg's bottom is this close to its hole's axis (the hole leaves 2.5-3 mm a side; a peg standing beside
the holder is 4 cm or more off it)."""
INSERT_DZ_M = (-0.005, 0.01)
"""... and this far above the hole's floor (a peg resting on the holder's top, or on its rim, is 2 cm or more up)."""
HANG_LIFT_M = 0.05
"""A hung mug has risen at least this far since reset (one leant on a stand's 1.5 cm base plate has not)."""
WIPE_FRACTION = 0.9
"""A wiped spill has had this share of its marks passed over by the pressed sponge (the solver goes back over what
it missed; 12-16 marks: one may be left)."""

POUR_FRACTION = 0.75
"""A pour has put at least this share of the vessel's pieces in the container (9 of 12; holding still and random
actions met it on none of 150 episodes each: benchmarks/results/skills.md)."""
POUR_PIECES = 12
"""Pieces the offline author fills a vessel with: three layers of four in a tumbler or a paper cup (8 cm of their
13.5), beads four layers of three in the narrower beaker (10 cm of its 14; :func:`gendex_envs.pouring.fill_layout`)."""

FLIP_TILT_DEG = 150.0
"""A flipped object's axis is at least this far from where it pointed at reset (upside down on its rim: 175-180; on
its side: 90)."""

Words = Callable[[str], np.random.Generator]


def insert_task(a: dict, b: dict, words: Words, colors: tuple[str | None, ...] = ()) -> dict:
    """Insert peg ``a`` into holder ``b``'s hole and let go; the scene step adds that it stands upright
    (:func:`generator.steps.scene.inserted_upright`)."""
    from gendex_envs.assets.catalog import get_asset

    n, t = "peg", "holder"
    shape = MODEL_WORDS.get(a["id"], "")
    floor = float(get_asset(b["id"]).entry.params["hole_floor_m"])
    return {
        "name": camel("insert", *painted(a, colors, 0)),
        "description": phrase("insert", a, words(camel("insert", a["id"])), other=b, other_qualifier=shape,
                              **qualifiers(a, None, colors)),
        "objects": [{"name": n, "asset": a["id"], "role": "graspable"},
                    {"name": t, "asset": b["id"], "role": "support"}],
        "steps": [*carry_steps(n, t, "over")[:3],
                  step("release", n, "hand", f"Lower the {word(n)} into the {word(t)}'s hole and let go of it.")],
        "success": {"type": "over", "object": n, "target": t, "max_xy_m": INSERT_XY_M,
                    "min_dz_m": round(floor + INSERT_DZ_M[0], 4), "max_dz_m": round(floor + INSERT_DZ_M[1], 4)},
        "success_text": f"The {shape} peg stands in the {word(t)}'s hole, down on its floor, let go.",
    }


def wipe_task(a: dict, b: dict, words: Words, colors: tuple[str | None, ...] = ()) -> dict:
    """Wipe spill ``b`` with sponge ``a``: pick it up, carry it over the spill, press it down on it and slide it
    over the spill's marks (:mod:`gendex.solve.wipe`)."""
    n, t = "sponge", "spill"
    kind = MODEL_WORDS.get(b["id"], "")
    return {
        "name": camel("wipe", *painted(b, colors, 1)),
        "description": phrase("wipe", a, words(camel("wipe", b["id"], a["id"])), other=b, other_qualifier=kind,
                              **qualifiers(a, None, colors)),
        "objects": [{"name": n, "asset": a["id"], "role": "graspable"},
                    {"name": t, "asset": b["id"], "role": "support"}],
        "steps": [*carry_steps(n, t, "over")[:3],
                  step("wipe", t, "arm", f"Press the {word(n)} down on the {word(t)} and wipe it all over.")],
        "success": {"type": "wiped", "object": n, "target": t, "min_fraction": WIPE_FRACTION},
        "success_text": f"The {word(n)} has been pressed down and passed over the {kind + ' ' if kind else ''}"
                        f"{word(t)}'s marks.",
    }


def hang_task(a: dict, b: dict, words: Words, colors: tuple[str | None, ...] = ()) -> dict:
    """Hang mug ``a`` by its handle on a peg of stand ``b`` and let go (:mod:`gendex.solve.hang`); the scene step adds
    that it is let go and still (:func:`generator.steps.scene.hung_lets_go`)."""
    n, t = "mug", "stand"
    kind = MODEL_WORDS.get(b["id"], "")
    return {
        "name": camel("hang", *painted(a, colors, 0), "on", b["id"].rsplit("_", 1)[-1]),
        "description": phrase("hang", a, words(camel("hang", a["id"], b["id"])), other=b,
                              **qualifiers(a, None, colors)),
        "objects": [{"name": n, "asset": a["id"], "role": "graspable"},
                    {"name": t, "asset": b["id"], "role": "support"}],
        "steps": [*carry_steps(n, t, "over")[:2],
                  step("hang", t, "arm", f"Slide the {word(n)}'s handle onto a peg of the {word(t)} and lower it."),
                  step("release", n, "hand", f"Let go of the {word(n)}: it hangs on the peg.")],
        "success": {"type": "hung", "object": n, "target": t, "min_height_m": HANG_LIFT_M},
        "success_text": f"The {word(n)} hangs by its handle on the {kind + ' ' if kind else ''}{word(t)}, let go and "
                        "still.",
    }


def pour_task(piece: dict, vessel: dict, target: dict, words: Words, colors: tuple[str | None, ...] = ()) -> dict:
    """Pour the :data:`POUR_PIECES` pieces (catalog ``piece``) that fill ``vessel`` into container ``target``: grasp
    the vessel by its side, tip it over the container, stand it up again (:mod:`gendex.solve.pour`); the scene step
    lays the pieces in it and adds that it stands up again (:func:`generator.steps.scene.poured_stands_up`)."""
    n, t = vessel["category"], target["category"]
    size = target["id"].rsplit("_", 1)[-1] if target["id"] != target["category"] else ""
    name = camel("pour", f"{piece['id']}s", "from", *painted(vessel, colors, 1), "into", target["id"])
    words_of = qualifiers(vessel, target, colors[1:])
    if size:  # the large bowl
        words_of["other_qualifier"] = " ".join(w for w in (words_of.get("other_qualifier"), size) if w)
    return {
        "name": name,
        "description": phrase("pour", vessel, words(name), other=target, pieces=piece["id"], **words_of),
        "objects": [{"name": n, "asset": vessel["id"], "role": "graspable",
                     "fill": {"asset": piece["id"], "count": POUR_PIECES}},
                    {"name": t, "asset": target["id"], "role": "container"}],
        "steps": [*carry_steps(n, t, "over")[:2],
                  step("pour", t, "arm", f"Tip the {word(n)} over the {word(t)} until the {piece['id']}s fall in, "
                                         f"then stand it up again.")],
        "success": {"type": "poured", "object": n, "target": t, "min_fraction": POUR_FRACTION},
        "success_text": f"At least {POUR_FRACTION:.0%} of the {piece['id']}s that filled the {word(n)} lie in the "
                        f"{word(t)}, and the {word(n)} stands up again.",
    }


def flip_task(a: dict, words: Words, colors: tuple[str | None, ...] = ()) -> dict:
    """Turn vessel ``a`` upside down on the table: grasp it by its side, turn it over and let it go on its rim
    (:mod:`gendex.solve.flip`); the scene step adds that it is let go and still
    (:func:`generator.steps.scene.hung_lets_go`)."""
    n = a["category"]
    name = camel("flip", *painted(a, colors, 0))
    flipped = {"type": "flipped", "object": n, "min_tilt_deg": FLIP_TILT_DEG}
    return {
        "name": name,
        "description": phrase("flip", a, words(name), **qualifiers(a, None, colors)),
        "objects": [{"name": n, "asset": a["id"], "role": "graspable"}],
        "steps": [*carry_steps(n, n, "over")[:2],
                  step("flip", n, "arm", f"Turn the {word(n)} upside down and lower it to the table."),
                  step("release", n, "hand", f"Let go of the {word(n)}: it stands on its rim.")],
        "success": flipped,
        "success_text": f"The {word(n)} stands upside down on the table, let go and still.",
    }


def joint_goal(skill: str, a: dict, n: str, part: str) -> tuple[str, str, dict, str]:
    """What a task that moves articulated ``a`` (spec name ``n``, its moving ``part``) by ``skill`` asks: the stage
    skill, what the stage does, the success condition and its sentence. ``skill``: close, turn, press (past the
    detent: a latching button or a switch then stays there), twist (a full turn counter-clockwise, a turn of the hand
    at a time), twist_on (the cap screwed back down from a full turn off), turn_off (the lever pushed back shut), or
    open (a lid lifted along its arc; a bottom-hinged door pulled down by its bar to half its opening: the hook
    follows its arc that far from where the arm reaches it; at 80 % the arm reached no pose for the standard oven and
    the plain dishwasher in 9 of 20 attempts)."""
    shut = {"type": "joint_open", "object": n, "min_fraction": 0.1, "negate": True}
    if skill == "close":
        return ("close", f"Push the {part} along its path until it is shut.", shut,
                f"The {part} is shut to less than 10 % of its opening.")
    if skill == "turn":
        return ("turn", f"Push the {part} round until it is fully turned.",
                {"type": "joint_open", "object": n, "min_fraction": 0.8},
                f"The {part} is turned to at least 80 % of its range.")
    if skill == "press":
        button = a["category"] == "button"
        what = "button all the way down" if button else "switch's lever down past its click"
        return ("press", f"Press the {what}.", {"type": "joint_open", "object": n, "min_fraction": 0.9},
                f"The {word(n)} is pressed in to at least 90 % of its travel." if button
                else f"The {word(n)} is on: its lever is pressed down to at least 90 % of its swing.")
    if skill == "twist":
        return ("twist", f"Unscrew the {word(n)}'s cap, regrasping it between turns.",
                {"type": "joint_open", "object": n, "min_fraction": 0.9},
                f"The {word(n)}'s cap is unscrewed: turned at least 90 % of a full turn.")
    if skill == "twist_on":
        return ("twist", f"Screw the {word(n)}'s cap down clockwise, regrasping it between turns.", shut,
                f"The {word(n)}'s cap is screwed on: less than 10 % of a full turn from shut.")
    if skill == "turn_off":
        return ("turn", f"Push the {part} back until the {word(n)} is off.", shut,
                f"The {part} is back to less than 10 % of its range: the {word(n)} is off.")
    doing = ("Pull the door down by its bar until it is half open." if part == "door"  # an oven's, a dishwasher's
             else f"Lift the {part} along its arc until it is open.")
    return ("open", doing, {"type": "joint_open", "object": n, "min_fraction": 0.5},
            f"The {part} is open to at least half of its opening.")


__all__ = ["FLIP_TILT_DEG", "HANG_LIFT_M", "INSERT_DZ_M", "INSERT_XY_M", "POUR_FRACTION", "POUR_PIECES",
           "WIPE_FRACTION", "flip_task", "hang_task", "insert_task", "joint_goal", "pour_task", "wipe_task"]
