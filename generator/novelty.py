"""Is a proposed task new? Near-duplicates of the tasks that exist are skipped before any scene is built.

Two tests, either of which makes a proposal a near-duplicate of an existing task (the latest version of each task in
the output folder and the repository):

- **the same task in other words**: the same task skills (:func:`generator.stats.task_skills`) on the same kinds of
  object (clutter left out): the catalog category of a rigid object, the model of an articulated one (a
  right-hinged cabinet's door is another mechanism than a left-hinged one's). ``PutAppleScanInBowl`` next to
  ``PutAppleBowl`` is one; putting the apple into a pot is not;
- **the same instruction**: the all-MiniLM-L6-v2 cosine similarity of the two instructions is at least
  :data:`NEAR_DUPLICATE_COSINE` (the embedding the library's diversity figure uses; from the optional ``stats``
  extra — without it only the first test runs, and the log says so once).

:func:`near_duplicate` gives the reason in words; the propose step hands it back to the backend as feedback.
"""

from __future__ import annotations

import copy
import hashlib
import logging
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from gendex_envs.spec import GOAL_TARGET, TaskSpec
from generator.catalog_view import asset_dict
from generator.embedding import embed_each
from generator.stats import STAGE_TASK_SKILLS, TASK_SKILLS, condition_skill, part_of, task_skills

log = logging.getLogger(__name__)

NEAR_DUPLICATE_COSINE = 0.9
"""Instructions at least this similar (MiniLM cosine) ask for the same task. For scale: two wordings of one put
task score 0.7-0.9, the same wording with another fruit about 0.8, different skills 0.3-0.5."""

Signature = tuple[tuple[str, ...], tuple[str, ...]]
"""(task skills and how its joints move, sorted object kinds) of a task: see :func:`kind` and :func:`_how`."""


def kind(asset: dict) -> str:
    """What counts as the same object: a rigid object's category, an articulated object's model (its id)."""
    return asset["id"] if asset.get("joints") else asset["category"]


@dataclass(frozen=True)
class ExistingTask:
    env_id: str
    signature: Signature
    instruction: str
    assets: tuple[str, ...] = ()
    """The catalog assets the task's scene holds (what ``gendex stats`` counts as used)."""


def _how(kind_: str, negate: bool, part: str | None) -> str | None:
    """How a joint condition moves its part, beyond its task skill: ``part_way`` (held at a fraction), ``off`` (a
    lever turned back shut), ``on`` (a cap screwed on); None for all the way (a half-open door is another task than
    an open one)."""
    if kind_ == "joint_at":
        return "part_way"
    if kind_ == "joint_open" and negate and part in ("lever", "cap"):
        return "off" if part == "lever" else "on"  # a cap screwed on is another task than one unscrewed
    return None


def spec_signature(spec: TaskSpec) -> Signature:
    cats = sorted({kind(asset_dict(o.asset)) for o in spec.objects if not o.distractor})
    objs = {o.name: asset_dict(o.asset) for o in spec.objects}
    how = {_how(c.type, bool(c.negate), part_of(objs[c.object], c.joint) if objs.get(c.object, {}).get("joints")
                else None) for c in spec.success.conditions if c.object in objs} - {None}
    return task_skills(spec) + tuple(sorted(how)), tuple(cats)


def proposal_signature(proposal: dict) -> Signature:
    """The signature of a proposal as a backend writes it (the JSON object the propose step parses)."""
    objects = {o["name"]: asset_dict(o["asset"]) for o in proposal["objects"]}
    pieces = [asset_dict(o["fill"]["asset"]) for o in proposal["objects"] if o.get("fill")]  # objects of the spec
    found = set()
    for succ in (proposal["success"], *(proposal.get("also") or ())):
        obj, target = objects.get(succ.get("object")), objects.get(succ.get("target"))
        found.add(condition_skill(succ["type"], target_category=target["category"] if target else None,
                                  target_is_goal=succ.get("target") == GOAL_TARGET, negate=bool(succ.get("negate")),
                                  part=part_of(obj) if obj and obj.get("joints") else None,
                                  taken_out=any(o.get("starts_in") == succ.get("target") and o["name"] == succ["object"]
                                                for o in proposal["objects"] if o.get("starts_in"))))
    found |= {s["skill"] for s in proposal["steps"] if s["skill"] in STAGE_TASK_SKILLS}
    how = {_how(c["type"], bool(c.get("negate")), part_of(objects[c["object"]]) if objects.get(
        c.get("object"), {}).get("joints") else None) for c in (proposal["success"], *(proposal.get("also") or ()))}
    return (tuple(k for k in TASK_SKILLS if k in found) + tuple(sorted(how - {None})),
            tuple(sorted({kind(a) for a in (*objects.values(), *pieces)})))


def fresh_first(proposals: list[dict], used: Iterable[str]) -> list[dict]:
    """The ``proposals`` that put an asset in their scene which no existing task uses (``used``), or all of them
    when none does: of the tasks of a drawn skill the autonomous author writes one that widens the library's set of
    objects when it can (the objects issue asks for >= 150 assets in library tasks; a task of the same skill on a
    used object is still written once every object of that skill is used)."""
    used = set(used)
    fresh = [p for p in proposals if set(proposal_assets(p)) - used]
    return fresh or proposals


def existing_tasks(roots: Iterable[Path]) -> list[ExistingTask]:
    """The latest version of every task under ``roots`` (a missing root holds none)."""
    from gendex_envs.registry import discover_tasks
    from generator.stats import latest_versions

    found = discover_tasks([r for r in roots if Path(r).is_dir()])
    return [library_entry(v) for _, v in sorted(latest_versions(found).items())]


def library_entry(version) -> ExistingTask:
    """The near-duplicate test's entry for a committed task version (its facts parsed once per spec's bytes)."""
    return ExistingTask(version.env_id, *_spec_facts(version))


_FACTS: dict[str, tuple[Signature, str, tuple[str, ...]]] = {}
"""(signature, instruction, assets) by the SHA-256 of a spec's bytes: a process generating several batches parses each
library spec once, not once a batch (the catalog the signatures read is fixed for a process)."""


def _spec_facts(version) -> tuple[Signature, str, tuple[str, ...]]:
    key = hashlib.sha256(version.files.spec.read_bytes()).hexdigest()
    hit = _FACTS.get(key)
    if hit is None:
        hit = _FACTS[key] = (spec_signature(version.spec), version.spec.instruction, spec_assets(version.spec))
    return hit


def spec_assets(spec: TaskSpec) -> tuple[str, ...]:
    """The catalog assets of a spec's objects, sorted, each once."""
    return tuple(sorted({o.asset for o in spec.objects}))


def proposal_assets(proposal: dict) -> tuple[str, ...]:
    """The catalog assets a proposal (as a backend writes it) puts in its scene, fills included."""
    found = {o["asset"] for o in proposal["objects"]} | {o["fill"]["asset"] for o in proposal["objects"]
                                                         if o.get("fill")}
    return tuple(sorted(found))


class Novelty:
    """Near-duplicate tests against a fixed set of existing tasks (instructions embedded once)."""

    def __init__(self, existing: list[ExistingTask]):
        self.existing = list(existing)
        self._extensions: dict[tuple[ExistingTask, ...], Novelty] = {}
        self._emb = None
        self.embedding = "not loaded"
        if self.existing:
            try:
                self._emb, self.embedding = embed_each([t.instruction for t in self.existing])
            except ImportError as exc:
                self.embedding = f"none ({exc.name} missing: the optional 'stats' extra)"
                log.info("near-duplicate test by skills and object kinds only: %s", self.embedding)

    def add(self, task: ExistingTask) -> None:
        self.existing.append(task)
        self._extensions = {}  # made from the tasks before this one
        if self._emb is not None:
            import numpy as np

            self._emb = np.vstack([self._emb, embed_each([task.instruction])[0]])

    def extended(self, tasks: Iterable[ExistingTask]) -> Novelty:
        """These tasks and ``tasks``, added one by one as :meth:`add` adds them; this one is unchanged. Extensions
        are remembered, each made from the one a task shorter, so a batch asking for 1, 2, 3 ... added tasks embeds
        each instruction once. The result may be shared: read it, do not add to it."""
        tasks = tuple(tasks)
        if not tasks:
            return self
        hit = self._extensions.get(tasks)
        if hit is None:
            hit = copy.copy(self.extended(tasks[:-1]))
            hit.existing = list(hit.existing)
            hit.add(tasks[-1])  # also gives the copy its own (empty) extensions
            self._extensions[tasks] = hit
        return hit

    def near_duplicate(self, signature: Signature, instruction: str) -> str | None:
        """Why a task of ``signature`` worded ``instruction`` duplicates an existing one, or None."""
        for t in self.existing:
            if t.signature == signature:
                return (f"it duplicates {t.env_id}: the same skills ({', '.join(signature[0])}) on the same kinds of "
                        f"object ({', '.join(signature[1])}); propose another skill or other objects")
        if self._emb is not None and len(self.existing):
            sims = self._emb @ embed_each([instruction])[0][0]
            i = int(sims.argmax())
            if sims[i] >= NEAR_DUPLICATE_COSINE:
                return (f"its instruction reads like {self.existing[i].env_id}'s ('{self.existing[i].instruction}', "
                        f"MiniLM cosine {sims[i]:.2f} >= {NEAR_DUPLICATE_COSINE}); propose a different task")
        return None


MATCH_COSINE = 0.6
"""A library task whose command reads at least this like a refused request (MiniLM cosine) is pointed to: *shut
the oven door* and CloseOvenCompact-v1 0.86, *spin the tennis ball in the hand* and RotateTennisBall-v1 0.77, *put
the apple in the microwave* and PutAppleBowl-v1 0.77; below it, *throw the ball across the room* and a put of a
tennis ball 0.53, *lift the hairbrush* and UnscrewBottle-v1 0.43."""


def closest_tasks(request: str, tasks: Iterable[ExistingTask], k: int = 3,
                  min_cosine: float = MATCH_COSINE) -> list[tuple[str, str, float]]:
    """The (env id, command, cosine) of at most ``k`` of ``tasks`` whose commands (situation and purpose taken off)
    read most like ``request``, at least ``min_cosine``; none without the ``stats`` extra."""
    from generator.phrasing import split

    tasks = list(tasks)
    commands = [split(t.instruction)[1] for t in tasks]
    if not tasks:
        return []
    try:
        emb, _ = embed_each([request, *commands])
    except ImportError:
        return []
    sims = emb[1:] @ emb[0]
    order = sorted(range(len(tasks)), key=lambda i: (-float(sims[i]), tasks[i].env_id))[:k]
    return [(tasks[i].env_id, commands[i], float(sims[i])) for i in order if sims[i] >= min_cosine]


__all__ = ["ExistingTask", "MATCH_COSINE", "NEAR_DUPLICATE_COSINE", "Novelty", "closest_tasks", "existing_tasks",
           "fresh_first", "kind", "library_entry", "proposal_assets", "proposal_signature", "spec_assets",
           "spec_signature"]
