"""The ``offline`` backend: a deterministic, seeded task author that is NOT a language model.

It answers every request the pipeline makes, from the request's structured ``context`` alone (it never reads the
prompt text), in the same text format a model must use, so its answers go through the same parsers, checks and
validators as a model's:

``propose``
    a small task grammar over catalog affordances: lift a graspable object; put it into a container; set it on a
    plate; stack a block on a block; push an object onto a goal mark; open an articulated object by its handle; and
    on the articulated objects the solver was measured on (:data:`ARTICULATED_LAYOUTS`), close a door or drawer,
    open or close a lid, turn a faucet. Choices are seeded and avoid the tasks and wordings that already exist.
``propose_guided``
    the task of the skill and objects the pipeline read from the instruction (:mod:`generator.instruction`,
    passed in the request's context), built from the same templates; a request this grammar has no task for
    raises :class:`~generator.instruction.InstructionError` saying what it can write instead.
``scene``
    a naive layout sampler: objects at random spots of the table top in front of the robot, scale 1, and in
    :data:`DISTRACTOR_P` of the scenes with movable objects one object of clutter (``distractor: true``). It checks
    nothing on purpose — choosing the best of several candidates and the critic's refinement are what make scenes sound.
    Each is set in a place: a scene style taken in turn by task index (:mod:`generator.backends.offline_style`).
``plan``
    one stage per proposal step, with its skill (reach / carry -> motion planning; finger and contact work -> RL);
    the plan step adds the standard success conditions of each RL stage's skill.
``reward``
    modules composed from the vetted terms of :mod:`gendex_envs.reward_terms` (see
    :mod:`generator.reward_library`).

``analyze`` (vision) is never sent here: ``sees_images`` is False, so the critic uses the physical checks alone.
"""

from __future__ import annotations

import hashlib
import json
import zlib

import numpy as np
import yaml

from gendex_envs.spec import JOINT_SKILLS
from generator.backends import placed as placed_tasks
from generator.backends import sequence
from generator.backends.base import ModelRequest, ModelResponse
from generator.backends.dexterous import flip_task, hang_task, insert_task, joint_goal, pour_task, wipe_task
from generator.backends.layouts import ARTICULATED_LAYOUTS
from generator.backends.offline_scene import scene_spec
from generator.backends.roles import (
    CARRY_FALLS_SHORT,
    EMPTIED_DRAWERS,
    STICK_OUT_M,
    TAKE_OUT_MAX_HEIGHT_M,
    _acts,
    _joint_at,
    _kind,
    _min_xy,
    _part,
    _round,
    carried,
    container,
    drawer_joint,
    drawer_words,
    fits_hole,
    fits_in,
    flippable,
    graspable,
    handed,
    handover_zone,
    hangable,
    hook_stand,
    insertable,
    openable,
    pour_into,
    pourable,
    pourer,
    receptacle,
    socket,
    sticks_out,
    wipe_area,
    wiper,
)
from generator.backends.wording import camel as _camel
from generator.backends.wording import carry_steps
from generator.backends.wording import fence as _fence
from generator.backends.wording import step as _step
from generator.backends.wording import word as _w
from generator.constructs import amount_text, amount_word, joint_fraction
from generator.errors import BackendError
from generator.instruction import InstructionError, is_surface
from generator.phrasing import Part, object_words, painted, phrase, phrase_parts, qualifiers
from generator.reword import ProposalWording

MODEL_ID = "gendex-offline-1"

STACK_PAIRS: dict[tuple[str, str], str | None] = {
    ("block_medium", "block_large"): "StackBlocks 93-100 % on unseen seeds", ("rubiks_cube", "block_large"): None,
    ("foam_brick", "block_large"): None, ("block_small", "block_medium"): None}
"""(top, base) pairs the autonomous grammar stacks (the base is a block), with where the pair was measured; None: a
candidate the solvability gate judges. The small block on the large one was 6/10 (it lands more than 3 cm off the
base's centre): written only when asked for."""
PUSHED: dict[str, str | None] = {"block_large": "PushBlockToGoal 50/50, a generated push 10/10",
                                 "rubiks_cube": None, "foam_brick": None, "tuna_can": None, "sponge": None}
"""Objects the autonomous grammar pushes, as :data:`STACK_PAIRS`."""
PART_TURN = 0.65
"""How far the autonomous grammar turns a lever part way (0.65 of a 1.2 rad range: 45 degrees)."""
TASK_KINDS = ("lift", "put_in", "place_on", "stack", "push", "open_door", "open_drawer", "open_lid", "close_door",
              "close_drawer", "close_lid", "turn", "turn_off", "open_part", "turn_part", "place_at", "take_out",
              "press", "hand_over", "twist", "twist_on", "insert", "wipe", "hang", "pour", "flip",
              "several", "composed")
"""The kinds of task the autonomous grammar draws evenly (:meth:`OfflineBackend.task_options`): a task skill, a door
or drawer held part way open (``open_part``), a lever turned part way (``turn_part``: none while no lever's layout
is measured turning part way, see :mod:`generator.backends.layouts`), or two tasks in turn
(``composed``), or several objects (``several``: two put in one container, a tower of blocks)."""
TWO_IN_M = 0.2
"""A container the autonomous grammar puts two objects in is at least this wide and round (the large bowl): its
sloped floor brings the second object in beside the first; in a flat-floored open box the second came to rest
outside the inside region (its 80 % disc) in 2 of 4 proposals (batch 1236917: a chess king after a shampoo bottle in
the storage bin 0/3, a racquetball after a roll of tape in the basket 6/9)."""
COMPOSE_STRIDE = 12
"""Each articulated first part is composed with every COMPOSE_STRIDE-th rigid task (a different slice for each)."""
PROPOSAL_DRAWS = 4
"""Tasks of the drawn skill the author words; it proposes the one whose command reads least like the library's
(:meth:`generator.reword.ProposalWording.least_alike`)."""
COMPOSED_WEIGHT = 2.0
"""How much likelier a composed task is drawn than the tasks of any one skill."""
OPTIONS_KEPT = 4
"""(seed, assets) whose task options (:meth:`OfflineBackend.task_options`) a process keeps written."""
_OPTIONS: dict[tuple[int, str], list[tuple[str, dict]]] = {}
STACK_GAP_M = 0.03
"""A stacked block rests on its base when it is this close above the base's top (the ``over`` band's width)."""
HANDOVER_XY_M = 0.08
"""A handed-over object lies on the mat when its middle is this close to the mat's (the mat is 22 cm square)."""
HANDOVER_DZ_M = (-0.01, 0.05)
"""... and this high above the mat's base: standing on it, or lying on it on its side (a can: 3.3 cm up)."""


class OfflineBackend:
    """Deterministic stand-in for a model; see the module docstring. Same seed and requests, same answers."""

    name = "offline"
    model = MODEL_ID
    sees_images = False
    is_language_model = False

    def __init__(self, seed: int = 0, kinds: tuple[str, ...] | list[str] | None = None):
        self.seed = int(seed)
        unknown = sorted(set(kinds or ()) - set(TASK_KINDS))
        if unknown:
            raise BackendError(f"unknown kind(s) of task {unknown}; the offline grammar writes: "
                               f"{', '.join(TASK_KINDS)}")
        self.kinds = tuple(kinds) if kinds else None
        """The kinds of task :meth:`_propose` draws from (None: every kind, :data:`TASK_KINDS`)."""
        self._wording = ProposalWording()

    def _rng(self, request: ModelRequest, *keys: int) -> np.random.Generator:
        return np.random.default_rng([self.seed, *(int(k) for k in keys), len(request.step)])

    def complete(self, request: ModelRequest) -> ModelResponse:
        handler = getattr(self, "_" + request.step, None)
        if handler is None:
            raise BackendError(f"the offline backend cannot answer {request.step!r} requests (it sees no images)")
        return ModelResponse(text=handler(request, request.context), backend=self.name, model=self.model)

    # ------------------------------------------------------------------ proposals
    def _propose(self, request: ModelRequest, ctx: dict) -> str:
        """A task of a skill drawn evenly from those with a task left to write (so a batch is not six "put X into
        Y"), then of :data:`PROPOSAL_DRAWS` of that skill's tasks that bring an object the library has not used
        (:func:`generator.novelty.fresh_first`) the one whose command reads least like the library's, worded least
        like them (:class:`generator.reword.ProposalWording`); never an existing name, nor a task with the skills
        and object kinds of an existing one (``ctx["existing_signatures"]``, :func:`generator.novelty.signature`)."""
        existing = set(ctx.get("existing_tasks", []))
        taken = {tuple(map(tuple, s)) for s in ctx.get("existing_signatures", [])}
        rng = self._rng(request, ctx.get("index", 0), ctx.get("attempt", 0))
        from generator.novelty import fresh_first, proposal_signature

        by_skill: dict[str, list[dict]] = {}
        options = self.task_options(ctx["assets"])
        for skill, proposal in options:
            if (proposal["name"] not in existing and proposal_signature(proposal) not in taken
                    and (self.kinds is None or skill in self.kinds)):
                by_skill.setdefault(skill, []).append(proposal)
        if not by_skill:
            of = "" if self.kinds is None else f" of the kinds {list(self.kinds)}"
            raise BackendError(f"the offline task grammar is exhausted: all tasks it can write{of} exist, or duplicate "
                               "an existing task's skills and objects")
        skills = sorted(by_skill)
        weights = np.array([COMPOSED_WEIGHT if k == "composed" else 1.0 for k in skills])
        skill = skills[int(rng.choice(len(skills), p=weights / weights.sum()))]
        pool = fresh_first(by_skill[skill], ctx.get("existing_assets") or ())
        drawn = rng.choice(len(pool), size=min(PROPOSAL_DRAWS, len(pool)), replace=False)
        chosen = self._wording.least_alike([pool[int(i)] for i in drawn], ctx.get("existing_instructions") or ())
        return _fence("json", json.dumps(chosen, indent=2))

    def _words(self, name: str) -> np.random.Generator:
        """The generator that words task ``name`` (:func:`generator.phrasing.phrase`): the same seed and task, the
        same sentence, whatever else the author was asked."""
        return np.random.default_rng([self.seed, zlib.crc32(name.encode())])

    def task_options(self, assets: list[dict]) -> list[tuple[str, dict]]:
        """Every task this grammar can write from ``assets``, each with its task skill. The list depends on the seed
        (its wordings) and the assets alone, and takes seconds to write (thousands of composed tasks): it is kept
        for the last few (seed, assets), and its proposals are shared, to be read, not changed."""
        key = (self.seed, hashlib.sha256(json.dumps(assets, sort_keys=True, default=str).encode()).hexdigest())
        if key not in _OPTIONS:
            while len(_OPTIONS) >= OPTIONS_KEPT:
                _OPTIONS.pop(next(iter(_OPTIONS)))
            _OPTIONS[key] = self._all_options(assets)
        return list(_OPTIONS[key])

    def _all_options(self, assets: list[dict]) -> list[tuple[str, dict]]:
        g = [a for a in assets if graspable(a)]
        m = [a for a in g if carried(a)]  # carried to a place; g are lifted
        c = [a for a in assets if container(a)]
        p = [a for a in assets if is_surface(a)]
        o = [a for a in assets if openable(a)]
        out = [("lift", self._lift_task(a)) for a in g]
        out += [("put_in", self._put_task(a, b)) for a in m for b in c if fits_in(a, b)]
        out += [("put_in", self._put_task(a, b)) for a in m for b in assets if drawer_joint(b) and fits_in(a, b)]
        out += [("place_on", self._plate_task(a, b)) for a in m for b in p]
        out += [("open_" + _part(a), self._open_task(a)) for a in o]
        usable = {a["id"]: a for a in g}
        out += [("stack", self._stack_task(usable[t], usable[b])) for t, b in STACK_PAIRS
                if t in usable and b in usable and usable[b]["category"] == "block"]
        out += [("push", self._push_task(a)) for a in g if a["id"] in PUSHED]
        by_id = {a["id"]: a for a in assets}
        zone = next((a for a in assets if handover_zone(a)), None)
        out += [("hand_over", self._handover_task(a, zone)) for a in assets if zone is not None and carried(a)]
        out += [("insert", insert_task(a, b, self._words)) for a in assets if insertable(a) for b in assets
                if socket(b) and fits_hole(a, b)]
        out += [("wipe", wipe_task(a, b, self._words)) for a in assets if wiper(a) for b in assets if wipe_area(b)]
        out += [("hang", hang_task(a, b, self._words)) for a in assets if hangable(a) for b in assets if hook_stand(b)]
        out += [("pour", pour_task(p, a, b, self._words)) for p in assets if pourable(p) for a in assets if pourer(a)
                for b in assets if pour_into(b)]
        out += [("flip", flip_task(a, self._words)) for a in assets if flippable(a)]
        for (skill, i) in ARTICULATED_LAYOUTS:
            if i in by_id:
                out.append((_kind(skill, by_id[i]), self._articulated_task(skill, by_id[i])))
        # part way: a door or drawer held half open by its handle; a lever turned to PART_TURN of its range
        out += [("open_part", self._open_task(a, 0.5)) for a in o if _part(a) in ("door", "drawer")]
        out += [("turn_part", self._articulated_task("turn", by_id[i], PART_TURN)) for (s, i), lay
                in ARTICULATED_LAYOUTS.items() if s == "turn" and i in by_id and lay["measured"]
                and not lay.get("part_way_failed")]
        out += [("place_at", t) for t in placed_tasks.placed_options(m, c + p, self._words)]
        out += [("take_out", placed_tasks.take_out_task(a, b, (), self._words))
                for a in m for b in c if fits_in(a, b) and sticks_out(a, b)]
        # several objects: two put in one large container (each gets 80 % of it to itself: the second lands beside
        # the first); a tower of the three blocks, the smallest on top
        names = lambda i: object_words(by_id[i])  # noqa: E731
        for k, a in enumerate(m):
            b, box = m[(3 * k + 5) % len(m)], [x for x in c if _min_xy(x) >= TWO_IN_M and _round(x)]
            if box and a["category"] != b["category"] and all(fits_in(x, box[k % len(box)]) for x in (a, b)):
                parts = [self._put_task(a, box[k % len(box)]), self._put_task(b, box[k % len(box)])]
                out.append(("several", sequence.join_steps(parts, _acts, set(), names)))
        blocks = sorted((x for x in g if x["category"] == "block"), key=_min_xy)
        if len(blocks) >= 3:
            out.append(("several", sequence.join_steps([self._stack_task(blocks[1], blocks[2]),
                                                        self._stack_task(blocks[0], blocks[1])], _acts, set(), names)))
        # composed: a door or lid the open hand shuts or opens (it leaves the hand free; a faucet or valve stands
        # in the middle of where the rigid part works: measured 0/3), then a rigid task
        firsts = [(skill, by_id[i]) for (skill, i), lay in ARTICULATED_LAYOUTS.items()
                  if i in by_id and not lay["grasp"] and lay["measured"]
                  and skill not in ("turn", "turn_off", "press", "twist", "twist_on")
                  and lay.get("composed", True)]
        seconds = ([("lift", a, None) for a in g] + [("put_in", a, b) for a in m for b in c if fits_in(a, b)]
                   + [("place_on", a, b) for a in m for b in p])
        for k, (skill, art) in enumerate(firsts):
            for second in seconds[k % COMPOSE_STRIDE::COMPOSE_STRIDE]:
                composed = self._composed_task(skill, art, *second)
                if composed is not None:
                    out.append(("composed", composed))
        return out

    def _composed_task(self, skill: str, art: dict, second: str, a: dict, b: dict | None) -> dict | None:
        """``skill`` (close, open by pressing, turn) on ``art``, then ``second`` (lift, put_in, place_on) on ``a``
        (into / onto ``b``): one task, both success conditions (``success`` and ``also``); None when the two parts'
        object names clash."""
        first = self._articulated_task(skill, art)
        rest = {"lift": lambda: self._lift_task(a), "put_in": lambda: self._put_task(a, b),
                "place_on": lambda: self._plate_task(a, b)}[second]()
        if {o["name"] for o in first["objects"]} & {o["name"] for o in rest["objects"]}:
            return None
        name = f"{first['name']}Then{rest['name']}"
        parts = [Part(_kind(skill, art), art), Part(second, a, b, **qualifiers(a, b))]
        text = rest["success_text"]
        return {
            "name": name, "description": phrase_parts(parts, self._words(name)),
            "objects": first["objects"] + rest["objects"], "steps": first["steps"] + rest["steps"],
            "success": first["success"], "also": [rest["success"]],
            "success_text": f"{first['success_text'][:-1]}, and {text[:1].lower()}{text[1:]}",
        }

    def _lift_task(self, a: dict, colors: tuple[str | None, ...] = ()) -> dict:
        n = a["category"]
        name = _camel("lift", *filter(None, colors[:1]), a["id"])
        return {
            "name": name, "description": phrase("lift", a, self._words(name), **qualifiers(a, None, colors)),
            "objects": [{"name": n, "asset": a["id"], "role": "graspable"}],
            "steps": [
                _step("reach", n, "arm", f"Bring the open hand to the {_w(n)}."),
                _step("grasp", n, "hand", f"Close the fingers around the {_w(n)}."),
                _step("lift", n, "lift_inspire", f"Lift the {_w(n)} 10 cm."),
            ],
            "success": {"type": "lifted", "object": n, "target": None, "min_height_m": 0.1, "min_fraction": None,
                        "max_dist_m": None},
            "success_text": f"The {_w(n)} is held at least 10 cm above where it started.",
        }

    _carry_steps = staticmethod(carry_steps)

    def _put_task(self, a: dict, b: dict, colors: tuple[str | None, ...] = ()) -> dict:
        n, t = a["category"], b["category"]
        t = t if t != n else t + "_2"
        drawer = drawer_joint(b)
        name = _camel("put", *painted(a, colors, 0), "in", *painted(b, colors, 1))
        return {
            "name": name, "description": phrase("put_in_drawer" if drawer else "put_in", a, self._words(name), other=b,
                                                amount=drawer_words(b) if drawer else "", **qualifiers(a, b, colors)),
            "objects": [{"name": n, "asset": a["id"], "role": "graspable"},
                        {"name": t, "asset": b["id"], "role": "articulated" if b.get("joints") else "container"}],
            "steps": self._carry_steps(n, t, "above"),
            "success": {"type": "inside", "object": n, "target": t, "min_height_m": None, "min_fraction": None,
                        "max_dist_m": None, **({"joint": drawer} if drawer else {})},
            "success_text": (f"The {_w(n)} rests in the {drawer_words(b)}drawer of the {_w(t)}." if drawer else
                             f"The {_w(n)} rests inside the {_w(t)}."),
        }

    def _plate_task(self, a: dict, b: dict, colors: tuple[str | None, ...] = ()) -> dict:
        n, t = a["category"], b["category"]
        name = _camel("set", *painted(a, colors, 0), "on", *painted(b, colors, 1))
        return {
            "name": name, "description": phrase("place_on", a, self._words(name), other=b,
                                                **qualifiers(a, b, colors)),
            "objects": [{"name": n, "asset": a["id"], "role": "graspable"},
                        {"name": t, "asset": b["id"], "role": "support"}],
            "steps": self._carry_steps(n, t, "over"),
            "success": {"type": "near", "object": n, "target": t, "min_height_m": None, "min_fraction": None,
                        "max_dist_m": round(0.4 * _min_xy(b), 3)},
            "success_text": f"The {_w(n)} lies on the {_w(t)}.",
        }

    def _open_task(self, a: dict, fraction: float | None = None) -> dict:
        """Open ``a``'s door or drawer by its handle: at least 80 % of the way, or to ``fraction`` of it (held
        there)."""
        n = a["category"]
        part = _part(a)
        if fraction is None:
            name = _camel("open", a["id"])
            description = phrase(f"open_{part}", a, self._words(name))
            success = {"type": "joint_open", "object": n, "target": None, "min_height_m": None, "min_fraction": 0.8,
                       "max_dist_m": None}
            text = f"The {part} is open to at least 80 % of its opening."
        else:
            name = _camel("open", a["id"], amount_word(fraction, a))
            description = phrase(f"open_{part}_part", a, self._words(name), amount=amount_text(fraction, a))
            success = _joint_at(n, fraction)
            text = f"The {part} stays open {amount_text(fraction, a)} (within 10 % of its opening)."
        return {
            "name": name, "description": description,
            "objects": [{"name": n, "asset": a["id"], "role": "articulated"}],
            "steps": [
                _step("reach", n, "arm", f"Bring the open hand to the {part} handle."),
                _step("grasp", n, "hand", "Hook the fingers around the handle."),
                _step("open", n, "both", f"Pull the {part} open along its path" +
                      ("." if fraction is None else f", {amount_text(fraction, a)}, and hold it there.")),
            ],
            "success": success, "success_text": text,
        }

    def _stack_task(self, a: dict, b: dict, colors: tuple[str | None, ...] = ()) -> dict:
        n, t = a["id"], b["id"]
        h = float(b["size_m"][2])
        name = _camel("stack", *painted(a, colors, 0), "on", *painted(b, colors, 1))
        return {
            "name": name, "description": phrase("stack", a, self._words(name), other=b,
                                                **qualifiers(a, b, colors)),
            "objects": [{"name": n, "asset": a["id"], "role": "graspable"},
                        {"name": t, "asset": b["id"], "role": "support"}],
            "steps": [*self._carry_steps(n, t, "above")[:3],
                      _step("place", t, "arm", f"Set the {_w(n)} down on the {_w(t)}'s top."),
                      _step("release", n, "hand", f"Open the hand and leave the {_w(n)} on the {_w(t)}.")],
            "success": {"type": "over", "object": n, "target": t, "max_xy_m": 0.03,
                        "min_dz_m": round(h - 0.01, 3), "max_dz_m": round(h + STACK_GAP_M, 3)},
            "success_text": f"The {_w(n)} rests on top of the {_w(t)}.",
        }

    def _handover_task(self, a: dict, zone: dict, colors: tuple[str | None, ...] = ()) -> dict:
        """Hand ``a`` over: carry it to the hand-over mat ``zone`` and let go of it there. The scene step adds that it
        must come to rest, standing as it stood (:func:`generator.steps.scene.hand_over_settles`)."""
        n, t = a["category"], "mat"
        name = _camel("hand", "over", *painted(a, colors, 0))
        return {
            "name": name, "description": phrase("hand_over", a, self._words(name), **qualifiers(a, None, colors)),
            "objects": [{"name": n, "asset": a["id"], "role": "graspable"},
                        {"name": t, "asset": zone["id"], "role": "support"}],
            "steps": [*self._carry_steps(n, t, "over")[:3],
                      _step("release", n, "hand", f"Let go of the {_w(n)} on the {_w(t)} and leave it there.")],
            "success": {"type": "over", "object": n, "target": t, "max_xy_m": HANDOVER_XY_M,
                        "min_dz_m": HANDOVER_DZ_M[0], "max_dz_m": HANDOVER_DZ_M[1]},
            "success_text": f"The {_w(n)} has been let go on the hand-over mat and rests there.",
        }

    def _push_task(self, a: dict) -> dict:
        n = a["category"]
        name = _camel("push", a["id"], "to", "goal")
        return {
            "name": name, "description": phrase("push", a, self._words(name), **qualifiers(a, None)),
            "objects": [{"name": n, "asset": a["id"], "role": "graspable"}],
            "steps": [_step("push", n, "arm", f"Push the {_w(n)} onto the goal mark.")],
            "success": {"type": "near", "object": n, "target": "goal", "max_dist_m": 0.04},
            "success_text": f"The {_w(n)}'s centre is within 4 cm of the goal mark.",
        }

    def _articulated_task(self, skill: str, a: dict, fraction: float | None = None) -> dict:
        """Close a door or drawer, open or close a lid, turn a lever on or off: one of :data:`ARTICULATED_LAYOUTS`;
        a turn to ``fraction`` of the lever's range (held there) when one is given."""
        if fraction is not None:
            return self._turn_to(a, fraction)
        layout = ARTICULATED_LAYOUTS[skill, a["id"]]
        n = a["category"]
        part = _part(a)
        steps = [_step("reach", n, "arm", f"Bring the open hand to the {_w(n)}'s {part}.")]
        if layout["grasp"]:
            steps.append(_step("grasp", n, "hand", "Hook the fingers around the handle."))
        verb, doing, success, text = joint_goal(skill, a, n, part)
        steps.append(_step(verb, n, "both", doing))
        model = a["id"].removeprefix("screw_")  # screw_jar_small: UnscrewJarSmall, not a second UnscrewJar
        name = (_camel("turn", a["id"], "off") if skill == "turn_off" else _camel("unscrew", model) if skill == "twist"
                else _camel("screw", "on", model) if skill == "twist_on" else _camel(skill, a["id"]))
        return {
            "name": name, "description": phrase(f"press_{a['category']}" if skill == "press" else _kind(skill, a),
                                                a, self._words(name)),
            "objects": [{"name": n, "asset": a["id"], "role": "articulated"}],
            "steps": steps, "success": success, "success_text": text,
        }

    def _turn_to(self, a: dict, fraction: float) -> dict:
        """Turn ``a``'s lever from off to ``fraction`` of its range (the turn layout) and hold it there."""
        n, part = a["category"], _part(a)
        name = _camel("turn", a["id"], amount_word(fraction, a))
        return {
            "name": name, "description": phrase("turn_part", a, self._words(name), amount=amount_text(fraction, a)),
            "objects": [{"name": n, "asset": a["id"], "role": "articulated"}],
            "steps": [_step("reach", n, "arm", f"Bring the open hand to the {_w(n)}'s {part}."),
                      _step("turn", n, "both", f"Push the {part} round {amount_text(fraction, a)} and stop there.")],
            "success": _joint_at(n, fraction),
            "success_text": f"The {part} stays turned {amount_text(fraction, a)} (within 10 % of its range).",
        }

    def _propose_guided(self, request: ModelRequest, ctx: dict) -> str:
        """The task the pipeline's reading of the instruction asks for (``ctx["reading"]``), from the grammar's
        templates; :class:`InstructionError` when the grammar has none for it."""
        reading = ctx.get("reading")
        if reading is None:
            raise BackendError("the offline author needs the pipeline's reading of the instruction "
                               "(generator.instruction.read_instruction) in the request context")
        assets = {a["id"]: a for a in ctx["assets"]}
        existing = set(ctx.get("existing_tasks", []))
        # steps in order (and towers: one stack per block): each its own task, joined where the solver does them
        # in turn; a step is named as if alone, the joined task apart from the existing ones
        step = lambda r: sequence.parse_step(self._propose_guided(request, ctx | {"reading": r,  # noqa: E731
                                                                                 "existing_tasks": []}))
        names = lambda i: object_words(assets[i])  # noqa: E731
        if reading.get("then"):
            return _fence("json", json.dumps(sequence.sequence_task(step, reading, _acts, existing, names), indent=2))
        skill = reading["skill"]
        mentions = reading["objects"]
        if skill == "stack" and len(mentions) > 2:  # a tower, top first: the base's neighbour on it first
            steps = [step(reading | {"objects": [mentions[k - 1], mentions[k]]})
                     for k in range(len(mentions) - 1, 0, -1)]
            return _fence("json", json.dumps(sequence.join_steps(steps, _acts, existing, names), indent=2))
        subs: dict[str, str] = {}

        def pick(k: int, ok, what: str, smallest: bool = False) -> dict:
            """The k-th object of the reading, or the first of its options this grammar can use (``smallest``: the
            smallest of them; a recorded substitution when it is not the one read)."""
            m = mentions[k]
            options = [assets[i] for i in (m["options"] or [m["asset"]]) if i in assets]
            usable = sorted((a for a in options if ok(a)), key=_min_xy) if smallest else [a for a in options if ok(a)]
            if usable:
                return usable[0]
            fallback = sorted((a for a in assets.values() if ok(a)), key=lambda a: a["id"])
            if not fallback:
                raise InstructionError(f"the offline author has no {what} for '{skill}'")
            if m["how"] in ("substitute", "kind"):
                subs[m["phrase"]] = fallback[0]["id"]
                return fallback[0]
            why = f" (it is lifted, not carried: {CARRY_FALLS_SHORT[m['asset']]})" if m["asset"] in CARRY_FALLS_SHORT \
                else ""
            raise InstructionError(
                f"'{m['phrase']}' ({m['asset']}) cannot be the {what} of a '{skill}' task this author writes{why}; "
                f"it writes them with: {', '.join(a['id'] for a in fallback)}")

        colors = tuple(m.get("color") for m in mentions)
        amount = reading.get("amount")
        if skill == "lift":
            proposal = self._lift_task(pick(0, handed, "object to lift"), colors)
        elif skill == "put_in":
            g = pick(0, lambda x: graspable(x) and carried(x), "object to put in")
            proposal = self._put_task(g, pick(1, lambda x: (container(x) or receptacle(x)) and fits_in(g, x),
                                              "container it fits in"), colors)
        elif skill == "place_on":
            proposal = self._plate_task(pick(0, carried, "object to set down"),
                                        pick(1, is_surface, "plate, tray or board"), colors)
        elif skill == "stack":  # blocks named by colour alone: the smallest on top, the next size under it
            tops = {t for t, _ in STACK_PAIRS}  # and what the grammar stacks on a block (a rubik's cube)
            a = pick(0, lambda x: graspable(x) and (x["category"] == "block" or x["id"] in tops), "block to stack",
                     smallest=True)
            proposal = self._stack_task(a, pick(1, lambda x: x["category"] == "block" and _min_xy(x) > _min_xy(a) and (
                a["category"] == "block" or (a["id"], x["id"]) in STACK_PAIRS), "larger block to stack on",
                smallest=True), colors)
        elif skill == "place_at":
            rel = reading.get("relation") or "in_region"
            refs = [pick(k, lambda x: not x.get("joints"), "object to set it by") for k in range(1, len(mentions))]
            a = pick(0, carried, "object to set down")
            proposal = placed_tasks.placed_task(a, rel, refs, reading.get("region"), colors, self._words)
        elif skill == "take_out":
            g = pick(0, lambda x: graspable(x) and carried(x), "object to take out")
            box = pick(1, lambda x: (container(x) and fits_in(g, x)) or drawer_joint(x) is not None,
                       "container or drawer it fits in")
            if drawer_joint(box) and box["id"] not in EMPTIED_DRAWERS:
                raise InstructionError(
                    f"the offline author does not take things out of a drawer yet: the solver's grasps of an object "
                    f"lying in a drawer's bin, between its walls, failed (an apple and a can in the {box['id']} "
                    f"and its like: 0 of 12 attempts); it puts things into one ('put the {g['category']} in the "
                    f"drawer') and takes them out of a bowl or a pot")
            if not drawer_joint(box) and not sticks_out(g, box):
                able = sorted(a["id"] for a in assets.values()
                              if graspable(a) and fits_in(a, box) and sticks_out(a, box))
                raise InstructionError(
                    f"the offline author takes out of a container only objects that stand {STICK_OUT_M * 100:.0f} cm "
                    f"above its rim, where the fingers close, and no taller than {TAKE_OUT_MAX_HEIGHT_M * 100:.0f} cm "
                    f"('{mentions[0]['phrase']}' ({g['id']}) in the {box['id']} is not); from the {box['id']} it "
                    f"takes out: {', '.join(able) or 'nothing'}")
            proposal = placed_tasks.take_out_task(g, box, colors, self._words)
        elif skill == "hand_over":
            zone = next((x for x in assets.values() if handover_zone(x)), None)
            if zone is None:
                raise InstructionError("the offline author needs the hand-over mat (handover_mat) in the catalog to "
                                       "hand something over")
            proposal = self._handover_task(pick(0, carried, "object to hand over"), zone, colors)
        elif skill == "insert":
            peg = pick(0, insertable, "peg to insert")
            fits = [x for x in sorted(assets.values(), key=lambda x: x["id"]) if socket(x) and fits_hole(peg, x)]
            holder = (pick(1, lambda x: socket(x) and fits_hole(peg, x), f"holder the {peg['id']} fits")
                      if len(mentions) > 1 else next(iter(fits), None))
            if holder is None:
                raise InstructionError(f"the catalog has no holder with a hole the {peg['id']} fits")
            proposal = insert_task(peg, holder, self._words, colors)
        elif skill == "wipe":
            k = 0 if mentions and wiper(assets[mentions[0]["asset"]]) else 1  # the reader may put the spill first
            sponge, spill = pick(k, wiper, "sponge to wipe with"), pick(1 - k, wipe_area, "spill to wipe")
            proposal = wipe_task(sponge, spill, self._words, (colors[k], colors[1 - k]) if len(colors) > 1 else colors)
        elif skill == "hang":
            proposal = hang_task(pick(0, hangable, "mug to hang by its handle"),
                                 pick(1, hook_stand, "hook, mug tree or rack to hang it on") if len(mentions) > 1
                                 else next(x for x in sorted(assets.values(), key=lambda x: x["id"]) if hook_stand(x)),
                                 self._words, colors)
        elif skill == "pour":  # the reader puts the pieces first, then the vessel, then the container
            if colors and colors[0]:
                raise InstructionError(f"painting the pieces a vessel pours is not built yet ('{colors[0]} "
                                       f"{mentions[0]['phrase']}'); ask for them without a colour")
            proposal = pour_task(pick(0, pourable, "pieces to pour"), pick(1, pourer, "glass, beaker or cup to pour "
                                 "from"), pick(2, pour_into, "bowl to pour into"), self._words, colors)
        elif skill == "flip":
            proposal = flip_task(pick(0, flippable, "glass or paper cup to turn upside down"), self._words,
                                 colors)
        elif skill == "push":
            proposal = self._push_task(pick(0, lambda x: graspable(x) and (x["category"] == "block"
                                                                           or x["id"] in PUSHED), "block to push"))
        elif skill == "open" and mentions and any(
                (i in assets and openable(assets[i])) for i in (mentions[0]["options"] or [mentions[0]["asset"]])):
            a = pick(0, openable, "door or drawer to open")
            if amount is not None and _part(a) not in ("door", "drawer"):
                raise InstructionError(f"the offline author opens only doors and drawers part way (a lid let go part "
                                       f"way falls); '{mentions[0]['phrase']}' ({a['id']}) opens by its {_part(a)}")
            proposal = self._open_task(a, None if amount is None else joint_fraction(amount, a))
        elif skill in JOINT_SKILLS:
            act = {("turn", "off"): "turn_off", ("twist", "on"): "twist_on"}.get((skill, reading.get("direction")),
                                                                                 skill)
            if amount is not None and act != "turn":
                raise InstructionError(f"the offline author opens only doors and drawers part way (by their handle: "
                                       f"a lid let go part way falls); it cannot {act} "
                                       f"'{mentions[0]['phrase']}' {amount}")
            a = self._measured_variant(act, mentions[0], assets, subs)
            proposal = self._articulated_task(act, a, None if amount is None else joint_fraction(amount, a))
        else:
            raise InstructionError(
                f"the offline author writes no '{skill}' task: in-hand reorientation needs a trained stage policy "
                "(see GenDex/RotateTennisBall-v0 and `gendex train`). It writes: lift, put_in, place_on, stack, "
                "push, open, close, turn, press, take_out, place_at, hand_over, twist, insert, wipe, hang, pour, flip.")
        name, k = proposal["name"], 2
        while proposal["name"] in existing:
            proposal["name"] = f"{name}{k}"
            k += 1
        if subs:
            proposal["description"] += " (Substituted: " + ", ".join(f"{w} -> {i}" for w, i in subs.items()) + ".)"
        proposal["substitutions"] = subs
        return _fence("json", json.dumps(proposal, indent=2))

    @staticmethod
    def _measured_variant(skill: str, mention: dict, assets: dict[str, dict], subs: dict[str, str]) -> dict:
        """The asset of ``mention`` this author has a measured layout for ``skill`` of (:data:`ARTICULATED_LAYOUTS`),
        a same-category variant recorded as a substitution, or :class:`InstructionError` naming what it has."""
        options = mention["options"] or [mention["asset"]]
        laid_out = [i for i in options if (skill, i) in ARTICULATED_LAYOUTS and i in assets]
        for i in sorted(laid_out, key=lambda i: ARTICULATED_LAYOUTS[skill, i]["measured"] is None):
            return assets[i]  # a measured layout before a candidate one
        category = assets[mention["asset"]]["category"] if mention["asset"] in assets else None
        for (s, i) in ARTICULATED_LAYOUTS:
            if s == skill and i in assets and assets[i]["category"] == category:
                subs[mention["phrase"]] = i
                return assets[i]
        have = sorted(i for (s, i) in ARTICULATED_LAYOUTS if s == skill)
        raise InstructionError(f"the offline author has no layout to {skill} '{mention['phrase']}' "
                               f"({mention['asset']}) in; it lays out {skill} tasks for: {', '.join(have)}")

    # ------------------------------------------------------------------ scene
    def _scene(self, request: ModelRequest, ctx: dict) -> str:
        rng = self._rng(request, ctx.get("index", 0), ctx["candidate_index"], ctx.get("attempt", 0))
        return scene_spec(ctx["proposal"], {a["id"]: a for a in ctx["assets"]}, rng, (self.seed, ctx.get("index", 0)))

    # ------------------------------------------------------------------ plan
    _PLAN = {"reach": ("motion_planning", "arm", 60), "carry": ("motion_planning", "arm", 60),
             "place": ("motion_planning", "arm", 30),
             "grasp": ("RL", "hand", 40), "lift": ("RL", "lift_inspire", 40), "release": ("RL", "hand", 20),
             "open": ("RL", "both", 80), "close": ("RL", "both", 80), "push": ("RL", "both", 60)}

    def _plan(self, request: ModelRequest, ctx: dict) -> str:
        out = []
        for s in ctx["spec"]["stages"]:
            method, joint, horizon = self._PLAN.get(s["skill"], (s["method"], s["control_joint"],
                                                                 s.get("horizon", 60)))
            out.append({"name": s["name"], "instruction": s["instruction"], "skill": s["skill"], "method": method,
                        "control_joint": joint, "horizon": horizon, "target": s.get("target")})
        return _fence("yaml", yaml.safe_dump(out, sort_keys=False, width=110))

    # ------------------------------------------------------------------ reward
    def _reward(self, request: ModelRequest, ctx: dict) -> str:
        from generator.reward_library import compose_stage_module, compose_task_module

        if ctx.get("stage") is None:
            return _fence("python", compose_task_module(ctx["spec"], ctx["roles"]))
        return _fence("python", compose_stage_module(ctx["spec"], ctx["stage"], ctx["roles"]))

