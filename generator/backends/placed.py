"""The offline author's ``placed`` tasks: set a graspable object down beside, in front of, behind or between other
objects, or in a region of the table, as the robot sees it (*put the apple to the left of the bowl*).

:func:`placed_task` writes the proposal (the gaps of the condition from the objects' sizes); :func:`placed_layout`
lays the scene out so the object starts where the condition does not hold, on the far side of where it goes, and the
set-down point is clear of the other objects and inside the region where the solver measurably grasps and places.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gendex_envs.spec import RobotSpec
from gendex_envs.success import REGION_AHEAD_M, REGION_DEPTH_M, REGION_PARTS
from generator.backends.roles import drawer_joint, drawer_spot, drawer_words
from generator.backends.wording import camel, step, word
from generator.phrasing import PLACE_AT, names_for, painted, phrase, qualifiers

HAND_ROOM_M = 0.06
"""Centre distance beyond touching that a side relation's band starts at: room for the fingers round the held object
(at 2 cm the hand setting a lemon down in front of a cutting board pushed the board out of the band, dev seeds)."""
BAND_M = 0.15
"""Width of a side or ``next_to`` relation's band of centre distances."""
TAKE_OUT_ROOM_M = 0.03
"""A taken-out object lies at least this far beyond touching its container (out of it, not leaning on its rim)."""
TAKE_OUT_BAND_M = 0.12
"""Width of a take-out's ``next_to`` band."""
DRAWER_TAKE_OUT_BAND_M = 0.3
"""... and out of a chest's drawer: the solver sets it down beside the slid-out drawer, 0.45-0.47 m from the chest's
middle (:func:`gendex.solve.set_down.set_down_point`); the object still in the drawer is in this band too, which the
scene's ``inside`` negated rules out (:func:`generator.steps.scene.out_of_drawer`)."""
REGION_WORDS = {"left": "left side", "right": "right side", "near": "near side", "far": "far side",
                "centre": "middle", "near_left": "near left corner", "near_right": "near right corner",
                "far_left": "far left corner", "far_right": "far right corner"}
"""How a region of the table is said (the reader reads these back)."""
SIDE_WORDS = {"left_of": "to the left of", "right_of": "to the right of", "in_front_of": "in front of",
              "behind": "behind", "next_to": "next to"}
RELATIONS_IN_TURN = ("left_of", "right_of", "in_front_of", "behind", "next_to", "between")
"""Relations the autonomous grammar gives its graspable objects in turn (one each)."""
REGIONS_IN_TURN = ("far_left", "near_right", "left", "far", "right", "near_left", "centre", "far_right", "near")
"""Regions of the table the autonomous grammar sends its graspable objects to in turn."""
TABLE_CENTRE = np.array(RobotSpec().base_pos_m[:2]) + np.array([REGION_AHEAD_M, 0.0])
"""The middle of the table's working area in world xy, where the regions are measured from (the default robot base,
facing +x: the author's scenes keep it)."""


def _radius(a: dict) -> float:
    return 0.5 * float(max(a["size_m"][:2]))


def placed_condition(n: str, a: dict, relation: str, b: dict | None = None, names: tuple[str, ...] = (),
                     region: str | None = None, c: dict | None = None, room: float = HAND_ROOM_M,
                     band: float = BAND_M) -> dict:
    """The ``placed`` success condition for object ``n`` (asset ``a``); ``names``: the reference objects' names;
    ``room`` and ``band``: a side relation's room beyond touching and its width."""
    cond: dict = {"type": "placed", "object": n, "relation": relation}
    if relation == "in_region":
        return cond | {"region": region}
    cond["target"] = names[0]
    if relation == "between":
        return cond | {"other": names[1], "min_gap_m": round(max(_radius(b), _radius(c)) + _radius(a) + 0.02, 3)}
    lo = _radius(b) + _radius(a) + room
    return cond | {"min_gap_m": round(lo, 3), "max_gap_m": round(lo + band, 3)}


def take_out_task(a: dict, b: dict, colors: tuple[str | None, ...], words: Callable[[str], np.random.Generator]
                  ) -> dict:
    """The proposal: ``a`` starts inside container ``b`` and is taken out and set down on the table next to it
    (``next_to`` with :data:`TAKE_OUT_ROOM_M` and :data:`TAKE_OUT_BAND_M`)."""
    n, t = a["category"], b["category"] if b["category"] != a["category"] else b["id"]
    name = camel("take", *painted(a, colors, 0), "out", "of", *painted(b, colors, 1))
    drawer = drawer_joint(b)  # out of a chest's drawer: set down beside the drawer, further from the chest's middle
    where = f"the {drawer_words(b)}drawer of the {word(t)}" if drawer else f"the {word(t)}"
    return {
        "name": name,
        "description": phrase("take_out_drawer" if drawer else "take_out", a, words(name), other=b,
                              amount=drawer_words(b) if drawer else "", **qualifiers(a, b, colors)),
        "objects": [{"name": n, "asset": a["id"], "role": "graspable", "starts_in": t}
                    | ({"color": colors[0]} if colors and colors[0] else {}),
                    {"name": t, "asset": b["id"], "role": "articulated" if drawer else "container"}
                    | ({"color": colors[1]} if len(colors) > 1 and colors[1] else {})],
        "steps": [step("reach", n, "arm", f"Bring the open hand to the {word(n)} in {where}."),
                  step("grasp", n, "hand", f"Close the fingers around the {word(n)}."),
                  step("carry", t, "arm", f"Lift the {word(n)} out of {where} and carry it beside it."),
                  step("release", n, "hand", f"Set the {word(n)} down on the table and let go of it.")],
        "success": placed_condition(n, a, "next_to", b, (t,), room=TAKE_OUT_ROOM_M,
                                    band=DRAWER_TAKE_OUT_BAND_M if drawer else TAKE_OUT_BAND_M),
        "success_text": f"The {word(n)} is out of {where}, on the table next to it.",
    }


def take_out_layout(cond: dict, held: str, rng: np.random.Generator) -> dict[str, list[float]]:
    """Nominal (x, y) of a take-out's container, to one side of the table's middle (the object is set down on the
    side towards the middle, :func:`gendex.solve.set_down.set_down_point`), and of the object in it."""
    side = float(np.sign(rng.uniform(-1, 1)) or 1.0)
    x, y = float(rng.uniform(0.0, 0.15)), side * float(rng.uniform(0.1, 0.2))
    return {cond["target"]: [x, y], held: [x, y]}


DRAWER_CHEST_X_M = 0.6
"""Nominal x of a chest something is taken out of (where its drawers were measured: the "close" layouts), ..."""
DRAWER_CHEST_SIDE_M = 0.15
"""... this far to one side of the table's middle: the object is set down beside its drawer towards the middle."""


def take_out_drawer_layout(cond: dict, held: str, chest: dict, out: float, rng: np.random.Generator
                           ) -> dict[str, list[float]]:
    """Nominal (x, y) of a chest an object is taken out of (its drawer slid ``out``), and (x, y, z) of the object on
    the floor of the drawer's bin, in the middle of the part out of the chest."""
    side = float(np.sign(rng.uniform(-1, 1)) or 1.0)
    x, y = DRAWER_CHEST_X_M + float(rng.uniform(-0.02, 0.02)), side * DRAWER_CHEST_SIDE_M
    sx, sy, sz = drawer_spot(chest, out)
    return {cond["target"]: [x, y], held: [round(x + sx, 3), round(y + sy, 3), round(sz, 3)]}


def command(rng: np.random.Generator, a: dict, relation: str, b: dict | None, c: dict | None,
            region: str | None, colors: tuple[str | None, ...] = ()) -> tuple[str, str]:
    """The bare command (the reader reads it back as ``place_at`` with this relation or region) and its words for
    where the object goes."""
    def name(x: dict, k: int) -> str:
        word = str(rng.choice(names_for(x, "")))
        return f"{colors[k]} {word}" if len(colors) > k and colors[k] else word

    template = str(rng.choice(PLACE_AT))
    o = name(a, 0)
    if relation == "in_region":
        where = f"on the {REGION_WORDS[region]} of the table"
    elif relation == "between":
        where = f"between the {name(b, 1)} and the {name(c, 2)}"
    else:
        where = f"{SIDE_WORDS[relation]} the {name(b, 1)}"
    return template.format(o=o, w=where), where


def placed_task(a: dict, relation: str, refs: list[dict], region: str | None, colors: tuple[str | None, ...],
            words: Callable[[str], np.random.Generator]) -> dict:
    """The proposal: set ``a`` down ``relation`` to the reference objects ``refs`` (none for a region of the
    table); ``words(name)`` seeds the wording of task ``name``."""
    n = a["category"]
    names: list[str] = []
    for r in refs:  # by category, by id where the category is taken (two bowls: 'bowl', 'bowl_large')
        names.append(r["category"] if r["category"] not in (n, *names) else r["id"])
    cond = placed_condition(n, a, relation, *(refs[:1] or [None]), names=tuple(names), region=region,
                            c=refs[1] if len(refs) > 1 else None)
    parts = [relation if relation != "in_region" else region, *(r["id"] for r in refs)]
    name = camel("set", *painted(a, colors, 0), *parts)
    text, where = command(words(name), a, relation, *(refs + [None, None])[:2], region, colors)
    return {
        "name": name, "description": text[:1].upper() + text[1:] + ".",
        "objects": [{"name": m, "asset": x["id"], "role": "graspable" if k == 0 else "support"}
                    | ({"color": colors[k]} if len(colors) > k and colors[k] else {})
                    for k, (m, x) in enumerate(zip([n, *names], [a, *refs], strict=True))],
        "steps": [step("reach", n, "arm", f"Bring the open hand to the {word(n)}."),
                  step("grasp", n, "hand", f"Close the fingers around the {word(n)}."),
                  step("carry", names[0] if names else n, "arm", f"Carry the {word(n)} {where}."),
                  step("release", n, "hand", f"Set the {word(n)} down and let go of it.")],
        "success": cond, "success_text": f"The {word(n)} lies {where}.",
    }


def placed_options(graspable: list[dict], marks: list[dict],
                   words: Callable[[str], np.random.Generator]) -> list[dict]:
    """The autonomous grammar's places: each graspable object by one landmark (two for ``between``) and in one
    region of the table, relations, landmarks and regions taken in turn."""
    out = []
    for k, a in enumerate(graspable):
        rel = RELATIONS_IN_TURN[k % len(RELATIONS_IN_TURN)]
        refs = [b for b in marks[k % len(marks):] + marks if b["category"] != a["category"]]
        refs = refs[:1] + [b for b in refs if b["category"] != refs[0]["category"]][:1]  # two kinds for between
        out.append(placed_task(a, rel, refs[:2 if rel == "between" else 1], None, (), words))
        out.append(placed_task(a, "in_region", [], REGIONS_IN_TURN[k % len(REGIONS_IN_TURN)], (), words))
    return out


def placed_layout(cond: dict, held: str, rng: np.random.Generator) -> dict[str, list[float]]:
    """Nominal (x, y) of the held object and its references: the set-down point inside the grasp region, the
    object starting on the far side of it (the condition false at reset, whatever the ±8 cm randomization)."""
    rel = cond["relation"]
    if rel == "in_region":
        point = TABLE_CENTRE.copy()
        if cond["region"] != "centre":
            for part in cond["region"].split("_"):
                axis, sign = REGION_PARTS[part]
                point[axis] += sign * REGION_DEPTH_M  # where the solver sets it down
        start = 2 * TABLE_CENTRE - point if cond["region"] != "centre" else TABLE_CENTRE + np.array([0.0, 0.22])
        return {held: [float(v) for v in start]}
    if rel == "between":
        gap = cond["min_gap_m"] * 2 + 0.16  # the two references this far apart, the object starting in front
        y0 = float(rng.uniform(-0.04, 0.04))
        return {cond["target"]: [0.2, y0 + gap / 2], cond["other"]: [0.2, y0 - gap / 2], held: [-0.1, y0]}
    mid = (cond["min_gap_m"] + cond["max_gap_m"]) / 2
    if rel in ("left_of", "right_of"):
        s = 1.0 if rel == "left_of" else -1.0
        y_ref = float(rng.uniform(-0.05, 0.0)) * s
        x = float(rng.uniform(0.0, 0.15))
        return {cond["target"]: [x, y_ref], held: [x, y_ref - s * mid]}
    if rel in ("in_front_of", "behind"):
        x_ref = 0.25 if rel == "in_front_of" else -0.05
        y = float(rng.uniform(-0.1, 0.1))
        side = float(np.sign(rng.uniform(-1, 1)) or 1.0)
        return {cond["target"]: [x_ref, y], held: [x_ref, y + side * (mid + 0.1)]}
    # next_to: the object starts beyond the band even where the reset moves both 8 cm towards each other; it is
    # set down on the side it comes from
    y_ref = float(rng.uniform(-0.24, -0.22))
    return {cond["target"]: [0.1, y_ref], held: [0.1, y_ref + cond["max_gap_m"] + 0.18]}


__all__ = ["BAND_M", "DRAWER_CHEST_SIDE_M", "DRAWER_CHEST_X_M", "DRAWER_TAKE_OUT_BAND_M", "HAND_ROOM_M",
           "REGIONS_IN_TURN", "REGION_WORDS", "RELATIONS_IN_TURN", "SIDE_WORDS", "TAKE_OUT_BAND_M", "TAKE_OUT_ROOM_M",
           "command", "placed_condition", "placed_layout", "placed_options", "placed_task", "take_out_drawer_layout",
           "take_out_layout", "take_out_task"]
