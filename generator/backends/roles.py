"""What the offline author lets each catalog object be (its roles: graspable, container, openable; which part a
joint moves) and what a proposal does to its articulated objects: the predicates the grammar, the guided author and
the scene sampler share."""

from __future__ import annotations

import functools

from gendex_envs.spec import JOINT_SKILLS

_OPENABLE_LINKS = ("door", "lid", "drawer")


def _part(a: dict) -> str:
    """The kind of part an articulated asset's main joint moves: ``door``, ``drawer``, ``lid`` or ``lever``."""
    return a["joints"][0]["handle_link"].split("_")[0]


def _kind(skill: str, a: dict) -> str:
    """The task skill of ``skill`` (open, close, turn, turn_off, twist, twist_on) on articulated ``a``:
    ``close_door``, ``open_lid``, ``turn``, ``turn_off``, ``twist_on``."""
    return skill if skill in ("turn", "turn_off", "press", "twist", "twist_on") else f"{skill}_{_part(a)}"


MIN_GRASP_RATE = 0.9
"""Lift-and-hold rate (recorded by ``benchmarks/grasp.py --record``) an object needs to be proposed for grasping."""


def _min_xy(a: dict) -> float:
    return float(min(a["size_m"][:2]))


def _held(a: dict) -> bool:
    """Picked up and held by the solver in >= :data:`MIN_GRASP_RATE` of its recorded ``benchmarks/grasp.py``
    attempts (when a record exists): what every role the hand grasps asks."""
    measured = _measured()
    return not measured or a["id"] in measured


def graspable(a: dict) -> bool:
    """Objects the offline grammar lets the hand grasp: compact, not flat, not too heavy, and picked up and held by
    the solver in >= 90 % of the recorded ``benchmarks/grasp.py`` attempts (when a record exists)."""
    s = a["size_m"]
    return ("graspable" in a["tags"] and "container" not in a["tags"] and a["category"] != "plate"
            and 0.035 <= _min_xy(a) and max(s) <= 0.25 and s[2] >= 0.03 and a["mass_kg"] <= 0.6
            and not a.get("joints") and _held(a))


@functools.cache
def _measured() -> frozenset[str]:
    from gendex.solve.lift_check import measured_graspable

    return measured_graspable(MIN_GRASP_RATE)


def handed(a: dict) -> bool:
    """Objects the offline author hands over: the graspable ones, and the small vessels a person takes by hand (a
    mug, a cup, a jar), held by the solver as :func:`graspable` asks."""
    s = a["size_m"]
    vessel = ("graspable" in a["tags"] and "container" in a["tags"] and max(s) <= 0.16 and a["mass_kg"] <= 0.6
              and not a.get("joints") and _held(a))
    return graspable(a) or vessel


CARRY_FALLS_SHORT = {"cracker_box": "carried and set down at 15 of 23 gate attempts: on a tray 8/10 (batch 418093, "
                                     "two slips), into a drawer 1/4 (962143), on a plate 6/9 (1029581, a slip, the "
                                     "carry's task failed, not let go on it); lifted 10/10 (LiftCrackerBox)"}
"""Objects the solver holds and lifts but does not carry to a place reliably (why, measured): the offline author lifts
them and sets nothing of theirs down anywhere."""


def carried(a: dict) -> bool:
    """Objects the offline author carries to a place (puts in, sets on, beside or down, takes out, hands over): the
    ones it holds (:func:`handed`) but those of :data:`CARRY_FALLS_SHORT`."""
    return handed(a) and a["id"] not in CARRY_FALLS_SHORT


def insertable(a: dict) -> bool:
    """A peg: what the offline author inserts into a holder."""
    return "peg" in a["tags"] and not a.get("joints") and _held(a)


def socket(a: dict) -> bool:
    """A holder with a hole a peg goes into (an asset tagged ``insert``)."""
    return "insert" in a["tags"] and not a.get("joints")


HOLE_CLEARANCE_M = (0.004, 0.008)
"""A peg fits a hole of its own shape this much wider (2-4 mm a side): the catalog's pairs have 5-6 mm; the solver
centres the peg to 1.2 mm."""


def fits_hole(peg: dict, holder: dict) -> bool:
    """Whether ``peg`` goes into ``holder``'s hole: the same shape, the hole :data:`HOLE_CLEARANCE_M` wider."""
    from gendex_envs.assets.catalog import get_asset

    p, h = (get_asset(a["id"]).entry.params for a in (peg, holder))
    gap = float(h.get("hole_m", 0.0)) - float(p.get("width_m", 1.0))
    return p.get("shape") == h.get("shape") and HOLE_CLEARANCE_M[0] <= gap <= HOLE_CLEARANCE_M[1]


def wiper(a: dict) -> bool:
    """A sponge that wipes: pinched high and pressed flat on a spill (an asset tagged ``wiper``)."""
    return "wiper" in a["tags"] and not a.get("joints") and _held(a)


def wipe_area(a: dict) -> bool:
    """A spill with marks to wipe (an asset tagged ``wipe_area``)."""
    return "wipe_area" in a["tags"] and not a.get("joints")


def hangable(a: dict) -> bool:
    """Something hung by its handle on a peg (an asset tagged ``hangable``: a mug, its handle's opening recorded)."""
    return "hangable" in a["tags"] and not a.get("joints") and _held(a)


def hook_stand(a: dict) -> bool:
    """A stand with pegs to hang a mug on (an asset tagged ``hang_on``: a mug hook, tree or rack)."""
    return "hang_on" in a["tags"] and not a.get("joints")


def pourer(a: dict) -> bool:
    """A tall open vessel the offline author pours from (an asset tagged ``pourer``: held by its side, tipped over a
    bowl)."""
    return "pourer" in a["tags"] and not a.get("joints") and _held(a)


FLIPPABLE = frozenset({"tumbler", "paper_cup"})
"""What the offline author turns upside down on the table: the vessels the flip primitive was measured on (held by
their side, they drop 3-4 cm onto their rim and stand there). A beaker landed on its side on about half of the
development seeds; a narrow box, a bottle on its cap, a can (grasped by a pinch) topple: ``gendex/solve/flip.py``."""


def flippable(a: dict) -> bool:
    """A vessel the offline author turns upside down (:data:`FLIPPABLE`)."""
    return a["id"] in FLIPPABLE and not a.get("joints")


def pourable(a: dict) -> bool:
    """Loose pieces a vessel holds and pours (an asset tagged ``pourable``: a bead, a marble)."""
    return "pourable" in a["tags"] and not a.get("joints")


POUR_INTO = frozenset({"bowl", "bowl_large"})
"""What the offline author pours into: the bowls the pour primitive was measured on (``benchmarks/results/
skills.md``)."""


def pour_into(a: dict) -> bool:
    """A container the offline author pours into (:data:`POUR_INTO`)."""
    return a["id"] in POUR_INTO and not a.get("joints")


def handover_zone(a: dict) -> bool:
    """The hand-over mat: where the robot leaves what it hands to a person."""
    return "handover" in a["tags"] and not a.get("joints")


def _round(a: dict) -> bool:
    """Round seen from above (a ball, a can, a bowl): any yaw is the same object."""
    s = a["size_m"]
    return abs(s[0] - s[1]) <= 0.1 * max(s[0], s[1])


def container(a: dict) -> bool:
    return "container" in a["tags"] and a["size_m"][2] <= 0.12 and _min_xy(a) >= 0.14 and not a.get("joints")


def openable(a: dict) -> bool:
    """Fixed articulated objects with a door or drawer handle, of a kind the solver's handle primitives open."""
    from gendex.solve.articulated import SOLVED_CATEGORIES

    joints = a.get("joints") or []
    return (bool(a.get("fixed_base")) and bool(joints) and a["category"] in SOLVED_CATEGORIES
            and any(k in joints[0]["handle_link"] for k in _OPENABLE_LINKS))


DRAWER_MAX_LENGTH_M = 0.12
"""Longest side (m, fitted to the hand) of an object the offline author puts into a drawer. A banana (18 cm) into the
one-drawer chest's: three proposals for *put the banana in the drawer* gated 4/7, 1/4 and 2/5, 7 of 9 failures
the banana not let go inside (seed 4710); the objects put in at >= 80 % were at most 11.3 cm long (a toy duck)."""


def fits_in(g: dict, c: dict) -> bool:
    """Grasped object ``g``, fitted to the hand, fits in container ``c`` with room around it; in a chest's drawer
    (:func:`drawer_joint`), no taller than the drawer's walls (a cracker box, 21 cm, slipped on the carry over the
    chest, 1 of 4 in the gate of batch seed 962143; the objects that passed stood at most 12.2 cm) and no longer
    than :data:`DRAWER_MAX_LENGTH_M`."""
    from gendex.solve.grasp import hand_fit_scale

    scale = hand_fit_scale(g["size_m"][:2])
    if drawer_joint(c) is not None:
        (_, _, z0), (_, _, z1) = next(j for j in c["joints"] if j["name"] == drawer_joint(c))["holds_m"]
        return g["size_m"][2] * scale <= z1 - z0 and max(g["size_m"][:2]) * scale <= DRAWER_MAX_LENGTH_M
    return max(g["size_m"][:2]) * scale < 0.7 * _min_xy(c)


def _acts(proposal: dict) -> dict[str, str]:
    """What the proposal does to each articulated object, as a key of :data:`ARTICULATED_LAYOUTS`: its step's skill
    (open, close, turn, twist), ``turn_off`` for a turn and ``twist_on`` for a twist whose success condition is the
    joint shut."""
    shut = {c["object"] for c in (proposal["success"], *(proposal.get("also") or ()))
            if c["type"] == "joint_open" and c.get("negate")}
    back = {"turn": "turn_off", "twist": "twist_on"}
    return {s["target"]: back[s["skill"]] if s["skill"] in back and s["target"] in shut else s["skill"]
            for s in proposal["steps"] if s["skill"] in JOINT_SKILLS}


def _joint_at(n: str, fraction: float) -> dict:
    return {"type": "joint_at", "object": n, "fraction": fraction, "max_error": 0.1}




STICK_OUT_M = 0.03
"""An object the offline author takes out of a container stands at least this far above the container's rim, fitted
to the hand: the fingers close on it above the rim (a can from the bowl: 6/6 in the gate; an apple, whose top is
level with the rim: 3 of 9 held)."""


TAKE_OUT_MAX_HEIGHT_M = 0.19
"""The tallest object (fitted to the hand) the offline author takes out of a container. Taken out at the gate: the
sugar box (17.5 cm) from the large bowl and from the pot, the bottle (22.3 cm) and the shampoo bottle (20 cm) from the
bowl; not: the bottle from the pot (4/7, slips on the carry, batch 1157003) and the shampoo bottle from the storage bin
and from the large bowl (1/4 each, grasps that failed between the walls, batch 1203319). Two of five above 19 cm."""


def sticks_out(g: dict, c: dict) -> bool:
    """Graspable ``g``, fitted to the hand, stands :data:`STICK_OUT_M` above container ``c``'s rim and is no taller
    than :data:`TAKE_OUT_MAX_HEIGHT_M`: what the offline author takes out of ``c``."""
    from gendex.solve.grasp import hand_fit_scale

    height = g["size_m"][2] * hand_fit_scale(g["size_m"][:2])
    return c["size_m"][2] + STICK_OUT_M <= height <= TAKE_OUT_MAX_HEIGHT_M


RECEIVING_DRAWERS = {"drawer_chest_1": "drawer_0_slide", "drawer_chest_2": "drawer_1_slide",
                     "drawer_chest_3": "drawer_2_slide"}
"""The drawer of each chest the offline author puts things in (and, for :data:`EMPTIED_DRAWERS`, takes them out of):
the lowest (solver, 4-6 attempts each, drawer 28 cm out: a can 4/4, an apple 6/6, a lemon 5/6 into chest 1's one
drawer, 6/6 into chest 2's and chest 3's bottom ones; their top drawers, 40 and 52 cm up, 1-5/6 and 2/6: a carry
that high slips)."""
EMPTIED_DRAWERS: frozenset[str] = frozenset()
"""The chests whose :data:`RECEIVING_DRAWERS` drawer the offline author takes things out of: none yet (an apple out of
the two-drawer chest's, a can out of the three-drawer chest's: 0 of 12 gate attempts; the grasp trials fail between
the walls). A chest measured at >= 80 % joins it."""
DRAWER_OUT_M = 0.28
"""How far a drawer something is put into or taken out of starts slid out (of its 0.3 m): 28 cm of its bin clear of
the chest, room for the hand round the object."""


def drawer_joint(a: dict) -> str | None:
    """The joint of the drawer of ``a`` the offline author puts things in (:data:`RECEIVING_DRAWERS`: one whose link
    holds things, ``holds_m``), else None."""
    from generator.instruction import drawers

    name = RECEIVING_DRAWERS.get(a["id"])
    return name if name in drawers(a) else None


def drawer_words(a: dict) -> str:
    """What a request calls the drawer of :func:`drawer_joint`: ``bottom `` of a chest of several, else nothing."""
    return "bottom " if len(a.get("joints") or []) > 1 else ""


def drawer_spot(a: dict, out: float) -> tuple[float, float, float]:
    """(x, y, z) in ``a``'s asset frame, at scale 1, of the middle of the floor of the part of its
    :func:`drawer_joint` drawer's bin that is out of the chest when the drawer is slid ``out`` (m)."""
    j = next(j for j in a["joints"] if j["name"] == drawer_joint(a))
    (x0, y0, z0), (x1, y1, _) = j["holds_m"]
    ox, oy, oz = j["link_origin_m"]
    return ox - out + (x0 + min(x1, out)) / 2, oy + (y0 + y1) / 2, oz + z0


def receptacle(a: dict) -> bool:
    """A box or bin whose lid opens (catalog tag ``container``, a lid joint), or a chest of drawers
    (:func:`drawer_joint`), that the offline author puts things in: a box or bin with a measured layout that starts
    its lid open (:data:`~generator.backends.layouts.ARTICULATED_LAYOUTS`'s
    ``close`` entry: the same layout the press that shuts it afterwards was measured on)."""
    from generator.backends.layouts import ARTICULATED_LAYOUTS

    joints = a.get("joints") or []
    if drawer_joint(a) is not None:
        return True
    return ("container" in a["tags"] and bool(joints) and joints[0]["handle_link"].startswith("lid")
            and bool((ARTICULATED_LAYOUTS.get(("close", a["id"])) or {}).get("measured")))
