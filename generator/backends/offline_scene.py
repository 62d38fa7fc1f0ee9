"""The offline author's scene sampler: objects at random spots of the table top in front of the robot, scale 1,
articulated objects at the layouts the solver was measured on (:data:`~generator.backends.layouts.ARTICULATED_LAYOUTS`),
and in :data:`DISTRACTOR_P` of the scenes with movable objects one object of clutter. It checks nothing on purpose:
choosing the best of several candidates and the critic's refinement make scenes sound. Each scene names the place
it happens in (``scene: {style: ...}``, :mod:`generator.backends.offline_style`)."""

from __future__ import annotations

from typing import Any

import numpy as np
import yaml

from generator.backends import placed as placed_tasks
from generator.backends.layouts import ARTICULATED_LAYOUTS, LAYOUT_JITTER_M
from generator.backends.offline_style import style_for
from generator.backends.roles import (
    DRAWER_OUT_M,
    _acts,
    _round,
    drawer_joint,
    graspable,
    handover_zone,
    hangable,
    hook_stand,
    insertable,
    socket,
    wipe_area,
    wiper,
)
from generator.backends.wording import fence as _fence
from generator.critic.physical import CONTAINER_FLOOR_M

STAGE_HORIZONS = {"twist": 700, "wipe": 250, "hang": 250, "pour": 250, "flip": 200}
"""Stage horizons (control steps) of skills that take longer than a stage's usual 40 (a twist: 5-6 grasps a turn,
about 90 steps each; hand-written trials 525-741 steps with the reach)."""
PUSH_M = 0.22
"""How far a push task's goal mark lies from the object's nominal place (PushBlockToGoal: 22 cm, 50/50)."""
COMPOSED_SIDE_M = 0.1
"""Articulated object this far off the middle (|y|): a composed task's movables on the other side, else in front."""
DISTRACTOR_P = 0.4
"""Share of scenes with movable objects that get one object of clutter (``distractor: true``)."""
MOVABLE_REGION_M = ((-0.02, 0.18), (-0.26, 0.26))
"""Where the offline author puts a movable object's nominal (x, y). With +-8 cm of randomization it stays close to
where the solver was measured to work: benchmarks/grasp.py's region (x -0.02..0.22, y -0.22..0.22, 34 objects
held >= 90 %) and the reference tasks' v1 layouts (y to +-0.24, 50/50). Sampling the whole table front (x -0.35..0.7,
y -0.55..0.55, as before) put a plate 1.26 m from the base: 0/10 carries found an arm pose above it."""
HANDOVER_REGION_M = ((0.36, 0.44), (-0.22, 0.22))
"""Where the hand-over mat lies: on the far side of the table, where a person across it reaches (its middle 0.18 m
or more beyond the movable objects' region; hand-written trials with the mat at (0.4, -0.2): 18 of 20 handed over)."""
HANDOVER_RANDOMIZE = {"xy_m": [0.03, 0.05], "yaw_deg": 0.0}
"""How far the mat moves at reset."""
INSERT_RANDOMIZE = {"xy_m": [0.05, 0.05]}
SPILL_REGION_M = ((0.06, 0.18), (-0.15, 0.15))
"""Where a spill's middle is put: the hand must reach 9-13 cm past it on every side, low, holding a sponge (a spill
at the movable region's edge, x 0.0, y -0.3, lost 3 of 7 wipes to the arm's reach)."""
WIPE_RANDOMIZE = {"xy_m": [0.08, 0.08], "yaw_deg": 90.0}
SPILL_RANDOMIZE = {"xy_m": [0.05, 0.05], "yaw_deg": 30.0}
"""How far a sponge and its (fixed) spill move at reset: the sponge +-8 cm, turned either way up to 90 deg; the spill
+-5 cm, turned up to 30 deg (their footprints stay 3 cm apart, :data:`generator.critic.skill_checks.WIPE_APART_M`).
With the sponge at +-4 cm a blind replay of one recorded wipe of the square spill wiped it on 6 of 50 new seeds."""
STAND_REGION_M = ((0.14, 0.24), (0.1, 0.2))
"""Where a mug stand's middle is put (y on either side): its pegs 20-30 cm up, ahead of the robot, where the arm
reaches round them with a mug in the hand, and off the middle, where the hand hangs at the robot's rest pose (a
34 cm mug tree at y 0 met its fingers)."""
STAND_RANDOMIZE = {"xy_m": [0.03, 0.03], "yaw_deg": 30.0}
HANG_RANDOMIZE = {"xy_m": [0.08, 0.08], "yaw_deg": 90.0}
"""How far a stand (fixed) and the mug to hang on it move at reset: the stand +-3 cm, turned up to 30 deg (a peg of
each stand still faces the robot's side); the mug +-8 cm, turned either way up to 90 deg."""
POUR_VESSEL_REGION_M = ((-0.03, 0.05), (0.08, 0.13))
"""Where a vessel to pour from is put (|y|: either side); the bowl it pours into goes further ahead on the other
side, as far across as :data:`generator.critic.skill_checks.POUR_APART_M` asks and up to :data:`POUR_SPREAD_M` more
(the pour primitive's measured layout: the glass at (0, -0.12), the bowl at (0.1, 0.15))."""
POUR_BOWL_X_M = (0.06, 0.14)
POUR_SPREAD_M = 0.04
POUR_RANDOMIZE = ({"xy_m": [0.05, 0.05], "yaw_deg": 90.0}, {"xy_m": [0.03, 0.03], "yaw_deg": 30.0})
"""How far they move at reset: the vessel +-5 cm, turned either way up to 90 deg; the bowl +-3 cm and 30 deg."""
FLIP_REGION_M = ((0.02, 0.06), (-0.02, 0.02))
"""Where a glass to turn over is put: the middle of the table ahead of the robot, where it is raised 32 cm, turned
about the hand's fingers and lowered again; it moves +-12 x +-20 cm at reset (:data:`FLIP_RANDOMIZE`). The flip
primitive's measured layout: (0.04, 0) +-12 x +-20 cm, 20/20 and 19/20; at +-8 cm a blind replay of one recorded flip
turned the glass over on 9 and 10 of 50 new seeds (benchmarks/results/skills.md)."""
FLIP_RANDOMIZE = {"xy_m": [0.12, 0.2], "yaw_deg": 180.0}
HOLDER_YAW_DEG = 20.0
"""How far a peg and its (fixed) holder move at reset: +-5 cm each (a hole 3 mm wider than its peg; their footprints
stay 5 cm apart, :data:`generator.critic.skill_checks.INSERT_APART_M`), the holder turned up to 20°, the peg any way
(a square one up to 45°: the solver lines it up with its hole)."""
ARTICULATED_REGION_M = ((0.52, 0.68), (-0.2, 0.2))
"""The same for articulated objects (their front faces the robot): OpenCabinet, OpenDrawer and CloseDrawer succeed
48-50/50 at (0.55-0.6, 0-0.1) +-5 cm; a batch sampled over x 0.3..0.75, y +-0.45 lost 3/10 drawer openings to
unreachable hook poses."""

DRAWER_FRONT_REGION_M = ((-0.14, -0.06), (-0.22, 0.22))
"""Where movable objects go when one is put into a chest's drawer: the drawer, slid out towards the robot, reaches
x = 0.15 (its chest at 0.6), and a hand closing on an object within ~10 cm of its front or side walls meets them.
Measured on PutBlockMediumInDrawerChest1 (batch seed 1004729, rejected by its gate at 1/4; seeds 7100-7109): the
block at (0.083, 0.114) 3/10 (7 attempts found no grasp that held), at (0.03, 0.22) 4/10 (4 slipped), at (-0.11, 0.12)
and at (-0.06, 0) 9/10 each, and with the chest taken aside 3/3; the library's drawer put-ins (x about -0.13) 4-5/5."""


def _movable_region(proposal: dict, assets: dict[str, dict], acts: dict[str, str]) -> tuple:
    """Where movable objects go: :data:`MOVABLE_REGION_M`, or in a composed task the half of it away from the
    articulated object's measured layout (the hand works on that object first, and its door or lid swings there),
    or before the chest when something is put into a drawer (:data:`DRAWER_FRONT_REGION_M`)."""
    receivers = {c.get("target") for c in (proposal["success"], *(proposal.get("also") or ())) if c["type"] == "inside"}
    if any(o["name"] in receivers and drawer_joint(assets[o["asset"]]) for o in proposal["objects"]):
        return DRAWER_FRONT_REGION_M
    (x0, x1), (y0, y1) = MOVABLE_REGION_M
    for o in proposal["objects"]:
        layout = ARTICULATED_LAYOUTS.get((acts.get(o["name"], ""), o["asset"]))
        if layout is not None and len(proposal["objects"]) > 1:
            y = layout["pos_m"][1]
            if abs(y) >= COMPOSED_SIDE_M:
                return (x0, x1), ((y0, 0.0) if y > 0 else (0.0, y1))
            return (x0, min(x1, 0.08)), (y0, y1)
    return MOVABLE_REGION_M



def _spots(place: dict, inside: dict[str, str], chest: dict | None, rng: np.random.Generator) -> dict[str, list]:
    """Nominal places of a place's objects: taken out of a ``chest``'s drawer, out of a container, or set by
    another object (:mod:`generator.backends.placed`)."""
    held = place["object"]
    if held in inside and chest is not None:
        return placed_tasks.take_out_drawer_layout(place, held, chest, DRAWER_OUT_M, rng)
    if held in inside:
        return placed_tasks.take_out_layout(place, held, rng)
    return placed_tasks.placed_layout(place, held, rng)


def scene_spec(proposal: dict, assets: dict[str, dict], rng: np.random.Generator, style_key: tuple[int, int] = (0, 0)
               ) -> str:
    """A scene answer (a fenced YAML spec) for ``proposal``, drawn with ``rng``, in the style of task ``style_key``
    = (author seed, task index) (:func:`~generator.backends.offline_style.style_for`; it draws nothing from ``rng``)."""
    objects = []
    acts = _acts(proposal)
    goal = None
    movable = _movable_region(proposal, assets, acts)
    place = next((c for c in (proposal["success"], *(proposal.get("also") or ())) if c["type"] == "placed"), None)
    inside = {o["name"]: o["starts_in"] for o in proposal["objects"] if o.get("starts_in")}
    receivers = {c.get("target") for c in (proposal["success"], *(proposal.get("also") or ())) if c["type"] == "inside"}
    drawers = {c["target"]: c["joint"] for c in (proposal["success"], *(proposal.get("also") or ()))
               if c["type"] == "inside" and c.get("joint")}
    by_name = {o["name"]: o for o in proposal["objects"]}
    hung = {c["object"] for c in (proposal["success"], *(proposal.get("also") or ())) if c["type"] == "hung"}
    poured = {c["object"]: c["target"] for c in (proposal["success"], *(proposal.get("also") or ()))
              if c["type"] == "poured"}
    flipped = {c["object"] for c in (proposal["success"], *(proposal.get("also") or ())) if c["type"] == "flipped"}
    pour_at = _pour_layout(poured, {o["name"]: assets[o["asset"]] for o in proposal["objects"]}, rng)
    for box in (o for o in proposal["objects"] if o["name"] in inside.values()):  # taken out of a drawer
        if drawer_joint(assets[box["asset"]]):
            drawers[box["name"]] = drawer_joint(assets[box["asset"]])
    spots = {} if place is None else _spots(place, inside, assets[by_name[place["target"]]["asset"]]
                                            if place.get("target") in drawers else None, rng)
    for o in proposal["objects"]:
        a = assets[o["asset"]]
        # articulated objects anywhere at the back, movable ones where the solver measurably works (module
        # constant); overlaps and support are the critic's job
        (x0, x1), (y0, y1) = ARTICULATED_REGION_M if o["role"] == "articulated" else movable
        x, y = (spots.get(o["name"]) or (rng.uniform(x0, x1), rng.uniform(y0, y1)))[:2]
        entry: dict[str, Any] = {"name": o["name"], "asset": o["asset"], "pos_m": [round(x, 3), round(y, 3), 0.0]}
        if o.get("color"):
            entry["color"] = o["color"]
        # a box or bin something is put in starts with its lid open (the layout its shutting was measured on)
        act = acts.get(o["name"]) or ("close" if o["role"] == "articulated" and o["name"] in receivers else "")
        layout = ARTICULATED_LAYOUTS.get((act, o["asset"]))
        if layout is not None:  # the measured layout of this skill on this object, jittered a little
            targets = [st["target"] for st in proposal["steps"]]
            stays = o["name"] in targets and targets[::-1].index(o["name"]) > 0  # the hand moves on
            at = layout.get("composed_pos_m", layout["pos_m"]) if stays else layout["pos_m"]
            x, y = (v + rng.uniform(-LAYOUT_JITTER_M, LAYOUT_JITTER_M) for v in at)
            entry["pos_m"] = [round(x, 3), round(y, 3), 0.0]
            if layout["yaw_deg"]:
                half = np.radians(layout["yaw_deg"]) / 2
                entry["quat_wxyz"] = [round(float(np.cos(half)), 7), 0.0, 0.0, round(float(np.sin(half)), 7)]
            entry["fixed"] = layout.get("fixed", True)
            entry["joint_state"] = {a["joints"][0]["name"]: float(layout["start"])}
            if o["name"] in drawers and act != "open":  # the drawer it goes in (or comes out of) slid out (as far
                j = a["joints"][0]  # as its shutting was measured from when a step shuts it), the chest's others shut
                out = float(layout["start"]) if acts.get(o["name"]) == "close" else DRAWER_OUT_M
                entry["joint_state"] = {j["name"]: float(j["closed_qpos"]), drawers[o["name"]]: out}
            entry["randomize"] = dict(layout.get("randomize") or {"xy_m": [0.05, 0.05], "yaw_deg": 15.0})
        elif handover_zone(a):  # the hand-over mat: fixed, on the person's side of the table
            (x0, x1), (y0, y1) = HANDOVER_REGION_M
            entry["pos_m"] = [round(float(rng.uniform(x0, x1)), 3), round(float(rng.uniform(y0, y1)), 3), 0.0]
            entry["fixed"] = True
            entry["randomize"] = dict(HANDOVER_RANDOMIZE)
        elif wipe_area(a) or wiper(a):  # a spill stays put (it moves at reset); the sponge starts beside it
            if wipe_area(a):
                (x0, x1), (y0, y1) = SPILL_REGION_M
                entry["pos_m"] = [round(float(rng.uniform(x0, x1)), 3), round(float(rng.uniform(y0, y1)), 3), 0.0]
            entry["fixed"] = wipe_area(a)
            entry["randomize"] = dict(SPILL_RANDOMIZE if wipe_area(a) else WIPE_RANDOMIZE)
        elif hook_stand(a) or (hangable(a) and o["name"] in hung):  # a stand stays put (it moves at reset)
            if hook_stand(a):
                (x0, x1), (y0, y1) = STAND_REGION_M
                y = float(rng.choice([-1.0, 1.0]) * rng.uniform(y0, y1))
                entry["pos_m"] = [round(float(rng.uniform(x0, x1)), 3), round(y, 3), 0.0]
            entry["fixed"] = hook_stand(a)
            entry["randomize"] = dict(STAND_RANDOMIZE if hook_stand(a) else HANG_RANDOMIZE)
        elif o["name"] in flipped:  # a glass to turn over: ahead of the robot, in the middle
            (x0, x1), (y0, y1) = FLIP_REGION_M
            entry["pos_m"] = [round(float(rng.uniform(x0, x1)), 3), round(float(rng.uniform(y0, y1)), 3), 0.0]
            entry["randomize"] = dict(FLIP_RANDOMIZE)
        elif o["name"] in pour_at:  # a vessel on one side, the bowl it pours into on the other
            entry["pos_m"] = pour_at[o["name"]]
            entry["randomize"] = dict(POUR_RANDOMIZE[int(o["name"] not in poured)])
        elif socket(a) or insertable(a):  # a holder stays put; the hole and the peg move at reset
            entry["fixed"] = socket(a)
            entry["randomize"] = dict(INSERT_RANDOMIZE, yaw_deg=HOLDER_YAW_DEG if socket(a) else
                                      180.0 if _round(a) else 45.0)
        elif o["role"] == "articulated":
            j = a["joints"][0]
            entry["fixed"] = True
            entry["joint_state"] = {j["name"]: float(j["closed_qpos"])}
            if o["name"] in drawers:  # something is taken out of this drawer: slid out
                entry["joint_state"][drawers[o["name"]]] = DRAWER_OUT_M
            entry["randomize"] = {"xy_m": [0.05, 0.05], "yaw_deg": 15.0}
        else:  # what the solver issue asks of every task: +-8 cm, any yaw if round, else +-45 deg
            entry["randomize"] = {"xy_m": [0.08, 0.08], "yaw_deg": 180.0 if _round(a) else 45.0}
            if o["name"] in inside:  # on the floor of its container (or drawer), moving with it at reset
                entry["pos_m"][2] = spots[o["name"]][2] if len(spots.get(o["name"], ())) > 2 else CONTAINER_FLOOR_M
                entry["randomize"]["xy_m"] = [0.0, 0.0]
            if proposal["success"].get("target") == "goal" and goal is None:
                # a push: the goal mark PUSH_M across the table, towards its middle
                gy = y - np.sign(y or 1.0) * PUSH_M
                goal = {"pos_m": [round(x, 3), round(float(gy), 3), 0.0], "radius_m": 0.03}
        objects.append(entry)
    if (any(o["role"] != "articulated" for o in proposal["objects"]) and rng.random() < DISTRACTOR_P and not spots
            and not flipped):  # a glass turned over is lowered onto its rim where it stood: nothing beside it
        clutter = _distractor(proposal, assets, rng, movable)
        objects += [clutter] if clutter else []
    stages = []
    for i, s in enumerate(proposal["steps"]):
        method = "motion_planning" if s["skill"] in ("reach", "carry", "place") else "RL"
        name = f"{s['skill']}_{s['target']}"
        repeated = (i > 0 and s["skill"] == proposal["steps"][i - 1]["skill"]) or any(st["name"] == name
                                                                                       for st in stages)
        stages.append({"name": name + (f"_{i}" if repeated else ""),
                       "instruction": s["instruction"], "skill": s["skill"], "method": method,
                       "control_joint": "arm" if method == "motion_planning" else s["control_joint"],
                       "horizon": STAGE_HORIZONS.get(s["skill"], 60 if method == "motion_planning" else 40),
                       "target": s["target"]})
    conds = [{k: v for k, v in c.items() if v is not None}
             for c in (proposal["success"], *(proposal.get("also") or ()))]
    spec = {"name": proposal["name"], "instruction": proposal["description"], "objects": objects,
            **({"goal": goal} if goal else {}),
            "stages": stages, "success": {"description": proposal["success_text"], "conditions": conds},
            # room for a re-planned approach, a regrasp or a slow door: twice the stages' horizons
            "max_episode_steps": max(250, 2 * sum(st["horizon"] for st in stages))}
    spec["scene"] = {"style": style_for(spec, *style_key)}
    return _fence("yaml", yaml.safe_dump(spec, sort_keys=False, default_flow_style=None, width=110))

def _pour_layout(poured: dict[str, str], assets: dict[str, dict], rng: np.random.Generator) -> dict[str, list]:
    """Where each vessel of ``poured`` (vessel -> container) and its container go (module constants): ``pos_m``
    by object name."""
    from generator.critic.skill_checks import POUR_APART_M

    out = {}
    for vessel, into in poured.items():
        side = float(rng.choice([-1.0, 1.0]))  # the bowl's side of the table; the vessel's is the other
        (x0, x1), (y0, y1) = POUR_VESSEL_REGION_M
        vy = -side * float(rng.uniform(y0, y1))
        half = (max(assets[vessel]["size_m"][:2]) + max(assets[into]["size_m"][:2])) / 2
        moves = sum(r["xy_m"][1] for r in POUR_RANDOMIZE)
        by = vy + side * (half + moves + POUR_APART_M + float(rng.uniform(0.0, POUR_SPREAD_M)))
        out[vessel] = [round(float(rng.uniform(x0, x1)), 3), round(vy, 3), 0.0]
        out[into] = [round(float(rng.uniform(*POUR_BOWL_X_M)), 3), round(by, 3), 0.0]
    return out


def _distractor(proposal: dict, assets: dict[str, dict], rng: np.random.Generator, region: tuple) -> dict | None:
    """One object of clutter: a graspable catalog object the task does not use, of no group the request names
    (:mod:`generator.groups`), in ``region``: where the task's movable objects go, clear of a door the hand works
    first (the critic moves it if it overlaps); None when no object is left."""
    from generator.catalog_view import asset_dicts
    from generator.groups import covered, group_kinds

    used = {o["asset"] for o in proposal["objects"]}
    kinds = group_kinds(proposal.get("reading"))  # 'all the fruit': no other fruit on the table
    pool = sorted((a for a in asset_dicts() if graspable(a) and a["id"] not in used and not covered(a, kinds)
                   and a["category"] not in {assets[i]["category"] for i in used if i in assets}),
                  key=lambda a: a["id"])
    if not pool:
        return None
    a = pool[int(rng.integers(len(pool)))]
    (x0, x1), (y0, y1) = region
    return {"name": f"distractor_{a['category']}", "asset": a["id"], "distractor": True,
            "pos_m": [round(float(rng.uniform(x0, x1)), 3), round(float(rng.uniform(y0, y1)), 3), 0.0],
            "randomize": {"xy_m": [0.08, 0.08], "yaw_deg": 180.0 if _round(a) else 45.0}}


__all__ = ["ARTICULATED_REGION_M", "DISTRACTOR_P", "HANDOVER_REGION_M", "MOVABLE_REGION_M", "PUSH_M", "scene_spec"]
