"""Step 1, propose: a task grounded in the catalog (autonomous, or from a human instruction).

The answer is parsed into a :class:`~generator.records.Proposal` and checked: every asset id exists, names are
snake_case and unique, steps use the skills and control modes GenDex has and name listed objects, and the success
condition is one GenDex can evaluate. A failed check is fed back to the backend, a bounded number of times.
"""

from __future__ import annotations

import dataclasses
import logging
from typing import Any

from gendex_envs.attributes import COLORS
from gendex_envs.errors import suggest
from gendex_envs.spec import (
    CONTROL_JOINT_MODES,
    GOAL_TARGET,
    SKILL_MEANINGS,
    SKILLS,
    SNAKE_NAME_RE,
    TASK_NAME_RE,
)
from generator.backends.base import Backend
from generator.catalog_view import asset_dicts, guidance
from generator.errors import ProposalError, RetriesExhaustedError
from generator.instruction import Reading, drawers, skill_vocabulary
from generator.novelty import Novelty, proposal_signature
from generator.records import PROPOSAL_CONDITION_TYPES, ROLES, Proposal, ProposedObject, ProposedStep
from generator.steps.common import ask, parse_json_block

log = logging.getLogger(__name__)

MAX_OBJECTS = 6
"""Objects of a proposal: up to three for one part (a place between two others), more for parts done in turn."""
MAX_PARTS = 4
"""Success conditions of a proposal: one, or one per part of a composed task (``success`` and ``also``): a door or
lid and three rigid parts at most (:data:`generator.backends.sequence.MAX_RIGID_STEPS`)."""
MAX_STEPS = 4 * MAX_PARTS
"""Steps of a proposal: up to 4 for a part (reach, grasp, carry, release)."""
SUCCESS_KEYS = ("type", "object", "target", "negate", "min_height_m", "min_fraction", "max_dist_m", "max_xy_m",
                "min_dz_m", "max_dz_m", "fraction", "max_error", "relation", "other", "region", "min_gap_m",
                "max_gap_m", "max_offset_m", "joint", "min_tilt_deg")
"""Keys a proposal's success condition may carry (``negate`` with ``joint_open``: the joint is shut; ``fraction``
and ``max_error`` with ``joint_at``: the joint set part way; ``relation``, ``other``, ``region`` and the gaps with
``placed``: where the object is set down, seen from the robot; ``joint`` with ``inside``: the drawer of a chest it
lies in)."""


def skill_list() -> str:
    """The skills with what each does, one per line (for prompts)."""
    return "\n".join(f"  - {k}: {v}" for k, v in SKILL_MEANINGS.items())


def parse_proposal(text: str, instruction: str | None = None) -> Proposal:
    """Parse and check a proposal answer; :class:`ProposalError` names the first problem and what is allowed."""
    raw = parse_json_block(text, "proposal", ProposalError)
    if not isinstance(raw, dict):
        raise ProposalError(f"the proposal must be a JSON object, got {type(raw).__name__}")
    need = ("name", "description", "objects", "steps", "success", "success_text")
    missing = [k for k in need if k not in raw]
    if missing:
        raise ProposalError(f"the proposal lacks {missing}; required keys: {list(need)}")
    name = str(raw["name"])
    if not TASK_NAME_RE.match(name):
        raise ProposalError(f"task name {name!r} must be CamelCase ({TASK_NAME_RE.pattern})")
    assets = {a["id"]: a for a in asset_dicts()}
    objects = []
    for i, o in enumerate(raw["objects"] or []):
        if not isinstance(o, dict) or not {"name", "asset", "role"} <= set(o):
            raise ProposalError(f"objects[{i}] must have name, asset and role; got {o!r}")
        if o["asset"] not in assets:
            raise ProposalError(f"objects[{i}]: asset {o['asset']!r} is not in the catalog."
                                f"{suggest(str(o['asset']), assets)} Use an id from the object library exactly.")
        if not SNAKE_NAME_RE.match(str(o["name"])):
            raise ProposalError(f"objects[{i}]: name {o['name']!r} must be snake_case ({SNAKE_NAME_RE.pattern})")
        if o["role"] not in ROLES:
            raise ProposalError(f"objects[{i}]: role {o['role']!r} is not one of {list(ROLES)}")
        if (o["role"] == "articulated") != bool(assets[o["asset"]]["joints"]):
            kind = "is" if assets[o["asset"]]["joints"] else "is not"
            raise ProposalError(f"objects[{i}]: asset {o['asset']!r} {kind} articulated but has role {o['role']!r}")
        if o.get("color") is not None and o["color"] not in COLORS:
            raise ProposalError(f"objects[{i}]: color {o['color']!r} is not one of {list(COLORS)}")
        objects.append(ProposedObject(str(o["name"]), str(o["asset"]), str(o["role"]), o.get("color"),
                                      None if o.get("starts_in") is None else str(o["starts_in"]),
                                      _fill(o.get("fill"), f"objects[{i}]", o["asset"], assets)))
    if not 1 <= len(objects) <= MAX_OBJECTS:
        raise ProposalError(f"a task uses 1 to {MAX_OBJECTS} objects, the proposal has {len(objects)}")
    names = [o.name for o in objects]
    if len(set(names)) != len(names):
        raise ProposalError(f"object names must be unique: {names}")
    holders = {o.name for o in objects if o.role == "container"
               or drawers(assets[o.asset])}
    for i, o in enumerate(objects):
        if o.starts_in is not None and (o.starts_in not in holders or o.role != "graspable"):
            raise ProposalError(f"objects[{i}]: starts_in {o.starts_in!r} must name a container or a chest of "
                                f"drawers of the proposal ({sorted(holders) or 'none'}), for a graspable object")
    steps = []
    for i, s in enumerate(raw["steps"] or []):
        if not isinstance(s, dict):
            raise ProposalError(f"steps[{i}] must be an object with skill, target, control_joint, instruction")
        if s.get("skill") not in SKILLS:
            raise ProposalError(f"steps[{i}]: skill {s.get('skill')!r} is not one of {list(SKILLS)}."
                                f"{suggest(str(s.get('skill')), SKILLS)}")
        if s.get("target") not in names:
            raise ProposalError(f"steps[{i}]: target {s.get('target')!r} is not a proposed object; objects: {names}."
                                f"{suggest(str(s.get('target')), names)}")
        if s.get("control_joint") not in CONTROL_JOINT_MODES:
            raise ProposalError(f"steps[{i}]: control_joint {s.get('control_joint')!r} is not one of "
                                f"{list(CONTROL_JOINT_MODES)}")
        steps.append(ProposedStep(s["skill"], s["target"], s["control_joint"],
                                  str(s.get("instruction") or f"{s['skill']} the {s['target']}")))
    if not 1 <= len(steps) <= MAX_STEPS:
        raise ProposalError(f"a task has 1 to {MAX_STEPS} steps, the proposal has {len(steps)}")
    succ = _condition(raw["success"], "success", names, objects, assets)
    also = raw.get("also") or []
    if not isinstance(also, list) or len(also) > MAX_PARTS - 1:
        raise ProposalError(f"also must be a list of at most {MAX_PARTS - 1} further success conditions, got "
                            f"{also!r}")
    more = tuple(_condition(c, f"also[{i}]", names, objects, assets) for i, c in enumerate(also))
    subs = raw.get("substitutions") or {}
    return Proposal(name=name, description=str(raw["description"]), objects=tuple(objects), steps=tuple(steps),
                    success=succ, also=more,
                    success_text=str(raw["success_text"]), instruction=instruction,
                    substitutions={str(k): str(v) for k, v in subs.items()} if isinstance(subs, dict) else {})


def _fill(fill: Any, where: str, vessel: str, assets: dict) -> dict | None:
    """A proposed object's ``fill`` (what a vessel to pour from holds), checked; None when it has none."""
    from gendex_envs.assets.catalog import get_asset
    from gendex_envs.pouring import MAX_PIECES, POURABLE_TAG, fill_layout

    if fill is None:
        return None
    pieces = sorted(a for a, x in assets.items() if POURABLE_TAG in x["tags"])
    pourers = sorted(a for a, x in assets.items() if "pourer" in x["tags"])
    if not isinstance(fill, dict) or set(fill) != {"asset", "count"}:
        raise ProposalError(f"{where}.fill must be {{\"asset\": <piece>, \"count\": <1-{MAX_PIECES}>}}; got {fill!r}")
    if "pourer" not in assets[vessel]["tags"]:
        raise ProposalError(f"{where}.fill: {vessel!r} is no vessel to pour from; vessels (tag pourer): {pourers}")
    if fill["asset"] not in pieces:
        raise ProposalError(f"{where}.fill.asset {fill['asset']!r} is not a piece a vessel holds; pieces (tag "
                            f"{POURABLE_TAG}): {pieces}")
    count = fill["count"]
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_PIECES:
        raise ProposalError(f"{where}.fill.count {count!r} must be a whole number of pieces, 1 to {MAX_PIECES}")
    try:
        fill_layout(get_asset(vessel), get_asset(fill["asset"]), count)
    except ValueError as exc:
        raise ProposalError(f"{where}.fill: {exc} ({vessel})") from None
    return {"asset": str(fill["asset"]), "count": int(count)}


def _condition(succ: Any, where: str, names: list[str], objects: list[ProposedObject], assets: dict) -> dict:
    """One success condition of a proposal, checked: a known type naming proposed objects."""
    if not isinstance(succ, dict) or succ.get("type") not in PROPOSAL_CONDITION_TYPES:
        raise ProposalError(f"{where}.type {succ.get('type') if isinstance(succ, dict) else succ!r} is not one of "
                            f"{list(PROPOSAL_CONDITION_TYPES)}")
    if succ.get("object") not in names:
        raise ProposalError(f"{where}.object {succ.get('object')!r} is not a proposed object; objects: {names}")
    targets = names + [GOAL_TARGET] if succ["type"] == "near" else names
    if succ["type"] in ("inside", "near", "over", "wiped", "hung", "poured") and succ.get("target") not in targets:
        raise ProposalError(f"{where}.target {succ.get('target')!r} must name a proposed object for a "
                            f"{succ['type']!r} condition; allowed: {targets}")
    if succ["type"] == "wiped" and "wipe_area" not in assets[objects[names.index(succ["target"])].asset]["tags"]:
        raise ProposalError(f"{where}.target {succ['target']!r} has no marks to wipe: a wiped condition's target is a "
                            "wipe area (an asset tagged wipe_area: a spill)")
    if succ["type"] == "hung" and "hang_on" not in assets[objects[names.index(succ["target"])].asset]["tags"]:
        raise ProposalError(f"{where}.target {succ['target']!r} has no pegs to hang on: a hung condition's target is a "
                            "stand tagged hang_on (a mug hook, tree or rack)")
    if succ["type"] == "poured" and objects[names.index(succ["object"])].fill is None:
        raise ProposalError(f"{where}.object {succ['object']!r} holds nothing to pour: a poured condition's object "
                            "is a vessel with a fill ({\"asset\": \"bead\", \"count\": 12})")
    if succ["type"] == "poured" and ("container" not in assets[objects[names.index(succ["target"])].asset]["tags"]
                                     or succ["target"] == succ["object"]):
        raise ProposalError(f"{where}.target {succ['target']!r} is no container to pour into: a poured condition's "
                            "target is another container (a bowl)")
    if succ["type"] == "placed":
        from gendex_envs.conditions import RELATIONS

        rel = succ.get("relation")
        if rel not in RELATIONS:
            raise ProposalError(f"{where}: placed needs a relation, one of {list(RELATIONS)}; got {rel!r}")
        for key in (() if rel == "in_region" else ("target",)) + (("other",) if rel == "between" else ()):
            if succ.get(key) not in names or succ.get(key) == succ["object"]:
                raise ProposalError(f"{where}.{key} {succ.get(key)!r} must name another proposed object for "
                                    f"relation {rel!r}; objects: {names}")
    if succ["type"] in ("joint_open", "joint_at") and not assets[objects[names.index(succ["object"])].asset]["joints"]:
        raise ProposalError(f"{where}: {succ['type']} needs an articulated object, {succ['object']!r} is rigid")
    if succ.get("joint") is not None:
        if succ["type"] != "inside":
            raise ProposalError(f"{where}.joint {succ['joint']!r}: a proposal's condition names a joint only for "
                                f"'inside' (the drawer the object lies in), not for {succ['type']!r}")
        target = assets[objects[names.index(succ["target"])].asset]
        holding = list(drawers(target))
        if succ["joint"] not in holding:
            raise ProposalError(f"{where}.joint {succ['joint']!r} is not a drawer of {succ['target']!r} that holds "
                                f"things; allowed: {holding or 'none (it has no drawer)'}")
    if succ["type"] == "joint_at" and not (isinstance(succ.get("fraction"), (int, float))
                                           and 0.0 <= succ["fraction"] <= 1.0):
        raise ProposalError(f"{where}: joint_at needs a fraction in [0, 1] of the way from closed to open, got "
                            f"{succ.get('fraction')!r}")
    return {k: v for k, v in succ.items() if k in SUCCESS_KEYS}


def with_reading(proposal: Proposal, reading: Reading) -> Proposal:
    """``proposal`` with the reading recorded and every substitution named: the reading's own (objects the catalog
    lacks, kinds it chose from) and any object the backend used instead of the one the person named. Each object the
    person named by colour gets that colour (the first proposed object of the mention's assets, in order), whatever
    the backend wrote: the scene paints it so (:func:`generator.steps.scene.parse_scene`)."""
    subs = dict(reading.substitutions)
    used = [o.asset for o in proposal.objects] + [o.fill["asset"] for o in proposal.objects if o.fill]
    named = reading.all_objects  # every step's
    for m in named:
        if not m.substituted and m.asset and not set(m.options or (m.asset,)) & set(used):
            other = [a for a in used if a not in {x.asset for x in named}]
            subs[m.phrase] = other[0] if other else "(left out)"
    for phrase, asset in proposal.substitutions.items():
        subs.setdefault(phrase, asset)
    objects, taken = list(proposal.objects), set()
    for m in named:  # the colours the person named: the reading is the authority, whatever the backend
        k = next((k for k, o in enumerate(objects) if k not in taken and o.asset in (m.options or (m.asset,))), None)
        if k is None:
            continue  # left out: a substitution above
        taken.add(k)
        if m.color is not None:
            objects[k] = dataclasses.replace(objects[k], color=m.color)
    return dataclasses.replace(proposal, objects=tuple(objects), substitutions=subs, reading=reading.to_dict())


def propose(backend: Backend, *, index: int = 0, existing: tuple[str, ...] = (), instruction: str | None = None,
            reading: Reading | None = None, feedback: str = "", max_attempts: int = 3,
            novelty: Novelty | None = None) -> tuple[Proposal, list[str]]:
    """Ask for a proposal until one passes :func:`parse_proposal`; returns it and the rejection reasons on the way.
    With an ``instruction``, pass its ``reading`` (:func:`generator.instruction.read_instruction`; read here when
    not given): the backend sees it, and the proposal records it with every substitution. ``feedback``: why earlier
    proposals of this task were dropped (shown to the backend with the first request). ``novelty``: the existing
    tasks an autonomous proposal must not duplicate (:mod:`generator.novelty`; a near-duplicate is rejected with
    its reason, like a malformed answer). A human-guided proposal is what the person asked for and is not tested."""
    prompt = "propose" if instruction is None else "propose_guided"
    variables = dict(asset_guidance=guidance(), existing_tasks="\n".join(f"- {n}" for n in existing) or "- (none)",
                     skills=skill_list(), condition_types=", ".join(PROPOSAL_CONDITION_TYPES),
                     control_joints=", ".join(CONTROL_JOINT_MODES))
    if instruction is not None:
        if reading is None:
            from generator.instruction import read_instruction

            reading = read_instruction(instruction, asset_dicts())
        variables |= dict(instruction=instruction, task_skills=skill_vocabulary(),
                          reading="\n".join(reading.lines()))
    reasons: list[str] = []
    for attempt in range(max_attempts):
        context = {"assets": list(asset_dicts()), "existing_tasks": list(existing), "index": index,
                   "attempt": attempt}
        if novelty is not None and instruction is None:
            context["existing_signatures"] = [[list(t.signature[0]), list(t.signature[1])]
                                              for t in novelty.existing]
            context["existing_instructions"] = [t.instruction for t in novelty.existing]
            context["existing_assets"] = sorted({a for t in novelty.existing for a in t.assets})
        if instruction is not None:
            context["instruction"] = instruction
            context["reading"] = reading.to_dict()
        answer = ask(backend, prompt, context=context, feedback=reasons[-1] if reasons else feedback, **variables)
        try:
            proposal = parse_proposal(answer, instruction)
        except ProposalError as exc:
            log.info("proposal attempt %d rejected: %s", attempt + 1, exc)
            reasons.append(str(exc))
            continue
        if proposal.name in existing:
            reasons.append(f"task name {proposal.name!r} already exists; choose a new task or name")
            continue
        if novelty is not None and instruction is None:
            why = novelty.near_duplicate(proposal_signature(dataclasses.asdict(proposal)), proposal.description)
            if why is not None:
                log.info("proposal %s rejected as a near-duplicate: %s", proposal.name, why)
                reasons.append(f"{proposal.name}: {why}")
                existing = (*existing, proposal.name)  # not again
                continue
        if reading is not None:
            proposal = with_reading(proposal, reading)
        return proposal, reasons
    raise RetriesExhaustedError(f"no valid proposal after {max_attempts} attempts; last reason: {reasons[-1]}")

