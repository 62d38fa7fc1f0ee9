"""``eval_info.json``: what ``gendex eval`` writes, in lerobot 0.4's layout, and one reading of results of either
layout.

lerobot 0.4's ``lerobot-eval`` writes three keys: ``per_task``, a list of ``{"task_group", "task_id", "metrics":
{"sum_rewards", "max_rewards", "successes", "video_paths"}}`` (one value per episode); ``per_group``, per task group
``avg_sum_reward``, ``avg_max_reward``, ``pc_success``, ``n_episodes``, ``video_paths``; and ``overall``, the same
over every episode with ``eval_s`` and ``eval_ep_s``. :func:`build` writes exactly that, a task's group being the
skills it exercises (``lift``, ``close_door+put_in``; the suite's name when no groups are given), and adds what GenDex
results carry besides:

- per task: the episodes' ``seeds``, ``successes_once``, ``lengths`` and ``failures`` in ``metrics``; beside them the
  count of ``episodes`` and ``n_successes``, ``pc_success`` with its 95 % Wilson interval (``wilson95``),
  ``pc_success_once``, ``mean_length``, ``env_steps`` and ``policy_failures``;
- per group and overall: ``wilson95``, ``mean_task_pc_success`` and the group's ``tasks``; overall ``env_steps``;
- ``layout`` (:data:`LAYOUT`), ``suite`` (name, hash, metric, episodes per task, seeds, complete), ``policy``,
  ``gendex_version``, ``task_digests`` (the digest of each task's files as they ran).

``successes`` holds the suite's metric (``success_at_end`` unless the suite says otherwise), as lerobot's holds its
success. Results filed before this layout (the v1 suites' board) use lerobot's pre-0.4 one (``per_episode``,
``per_task`` keyed by task, ``aggregated``); :func:`summary` reads either into the same :class:`Summary`, and
:func:`problems` says where a result's numbers do not add up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gendex.eval.metrics import wilson

LAYOUT = "lerobot-0.4"
OLD_LAYOUT = "lerobot-0.3"


@dataclass(frozen=True)
class Summary:
    """A result read the same way whatever its layout."""

    per_task: dict[str, dict]
    """Task -> ``episodes``, ``successes`` (a count), ``pc_success``, ``wilson95``, ``pc_success_once``,
    ``mean_length``, ``seeds`` and ``group`` (None in the old layout)."""
    overall: dict
    """``episodes``, ``successes``, ``pc_success``, ``wilson95``, ``mean_task_pc_success``."""
    layout: str


def _rate(k: int, n: int) -> tuple[float, list[float]]:
    lo, hi = wilson(k, n)
    return (100.0 * k / n if n else 0.0), [100.0 * lo, 100.0 * hi]


def _pool(entries: list[dict]) -> dict:
    """lerobot's aggregate of the episodes of ``entries`` (per-task entries of this layout), with GenDex's extras."""
    m = [e["metrics"] for e in entries]
    succ = [bool(s) for x in m for s in x["successes"]]
    sums = [r for x in m for r in x["sum_rewards"]]
    maxs = [r for x in m for r in x["max_rewards"]]
    pc, ci = _rate(sum(succ), len(succ))
    return {"avg_sum_reward": float(np.mean(sums)) if sums else 0.0,
            "avg_max_reward": float(np.mean(maxs)) if maxs else 0.0, "pc_success": pc, "n_episodes": len(succ),
            "video_paths": [p for x in m for p in x["video_paths"]], "wilson95": ci,
            "mean_task_pc_success": float(np.mean([e["pc_success"] for e in entries])) if entries else 0.0}


def build(suite, spec: str, rows: list[dict], seeds: list[int], seconds: float, *, gendex_version: str,
          task_digests: dict[str, str] | None = None, groups: dict[str, str] | None = None) -> dict:
    """The eval_info of ``rows`` (episode dicts of :class:`gendex.eval.runner.EpisodeResult`) on ``suite``'s tasks
    and ``seeds``, in the suite's task order and seed order."""
    order = {t: i for i, t in enumerate(suite.tasks)}
    wanted = set(seeds)
    rows = sorted((r for r in rows if r["task"] in order and r["seed"] in wanted),
                  key=lambda r: (order[r["task"]], r["seed"]))
    per_task = []
    for task in suite.tasks:
        mine = [r for r in rows if r["task"] == task]
        if not mine:
            continue
        succ = [bool(r[suite.metric]) for r in mine]
        fails: dict[str, int] = {}
        for r in mine:
            if r["failure"]:
                fails[r["failure"]] = fails.get(r["failure"], 0) + 1
        pc, ci = _rate(sum(succ), len(mine))
        per_task.append({
            "task_group": (groups or {}).get(task, suite.name), "task_id": task,
            "metrics": {"sum_rewards": [float(r["sum_reward"]) for r in mine],
                        "max_rewards": [float(r["max_reward"]) for r in mine], "successes": succ,
                        "video_paths": [r["video"] for r in mine if r.get("video")],
                        "seeds": [int(r["seed"]) for r in mine],
                        "successes_once": [bool(r["success_once"]) for r in mine],
                        "lengths": [int(r["length"]) for r in mine], "failures": [r["failure"] for r in mine]},
            "episodes": len(mine), "n_successes": sum(succ), "pc_success": pc, "wilson95": ci,
            "pc_success_once": 100.0 * sum(bool(r["success_once"]) for r in mine) / len(mine),
            "mean_length": float(np.mean([r["length"] for r in mine])),
            "env_steps": int(sum(r["length"] for r in mine)), "policy_failures": fails})
    per_group = {}
    for group in dict.fromkeys(e["task_group"] for e in per_task):
        mine = [e for e in per_task if e["task_group"] == group]
        per_group[group] = {**_pool(mine), "tasks": [e["task_id"] for e in mine]}
    n = sum(e["episodes"] for e in per_task)
    overall = {**_pool(per_task), "eval_s": round(seconds, 1), "eval_ep_s": round(seconds / n, 2) if n else 0.0,
               "env_steps": int(sum(e["env_steps"] for e in per_task))}
    done = {e["task_id"]: e["episodes"] for e in per_task}
    complete = all(done.get(t) == suite.episodes for t in suite.tasks)
    return {"layout": LAYOUT, "per_task": per_task, "per_group": per_group, "overall": overall,
            "suite": {"name": suite.name, "hash": suite.hash, "metric": suite.metric, "episodes_per_task": len(seeds),
                      "seeds": [seeds[0], seeds[-1]], "complete": complete},
            "policy": spec, "gendex_version": gendex_version,
            **({"task_digests": {t: task_digests[t] for t in suite.tasks if t in task_digests}}
               if task_digests is not None else {})}


def layout_of(info: dict) -> str:
    """:data:`LAYOUT` or :data:`OLD_LAYOUT`; ValueError for neither."""
    if isinstance(info.get("per_task"), list) and "overall" in info:
        return LAYOUT
    if isinstance(info.get("per_task"), dict) and "aggregated" in info and "per_episode" in info:
        return OLD_LAYOUT
    raise ValueError("eval_info is in neither lerobot 0.4's layout (per_task list, per_group, overall) nor the "
                     "earlier one (per_episode, per_task, aggregated): use the eval_info.json gendex eval writes")


def summary(info: dict) -> Summary:
    """Per-task and overall numbers of a result of either layout (as claimed: :func:`problems` checks them)."""
    if layout_of(info) == OLD_LAYOUT:
        seeds: dict[str, list[int]] = {}
        for r in info["per_episode"]:
            seeds.setdefault(r.get("task"), []).append(r.get("seed"))
        per_task = {t: {**d, "seeds": seeds.get(t, []), "group": None} for t, d in info["per_task"].items()}
        a = info["aggregated"]
        k = sum(d.get("successes", 0) for d in info["per_task"].values())
        overall = {"episodes": a.get("episodes"), "successes": k, "pc_success": a.get("pc_success"),
                   "wilson95": a.get("wilson95"), "mean_task_pc_success": a.get("mean_task_pc_success")}
        return Summary(per_task, overall, OLD_LAYOUT)
    per_task = {}
    for e in info["per_task"]:
        m = e["metrics"]
        per_task[e["task_id"]] = {"episodes": e["episodes"], "successes": e["n_successes"],
                                  "pc_success": e["pc_success"], "wilson95": e["wilson95"],
                                  "pc_success_once": e["pc_success_once"], "mean_length": e["mean_length"],
                                  "seeds": m["seeds"], "group": e["task_group"]}
    o = info["overall"]
    overall = {"episodes": o["n_episodes"], "successes": sum(t["successes"] for t in per_task.values()),
               "pc_success": o["pc_success"], "wilson95": o["wilson95"],
               "mean_task_pc_success": o["mean_task_pc_success"]}
    return Summary(per_task, overall, LAYOUT)


def _num(x) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _count(x) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


def _new_layout_problems(info: dict) -> list[str]:
    problems = []
    lists = ("sum_rewards", "max_rewards", "successes", "seeds", "successes_once", "lengths")
    for e in info["per_task"]:
        task = e.get("task_id") if isinstance(e, dict) else None
        m = e.get("metrics") if isinstance(e, dict) else None
        if not isinstance(task, str) or not isinstance(m, dict) or not all(isinstance(m.get(k), list) for k in lists):
            problems.append(f"per_task entry {str(e)[:80]} lacks task_id or the per-episode lists {list(lists)}")
            continue
        n, succ = e.get("episodes"), m["successes"]
        if not (_count(n) and _count(e.get("n_successes")) and _num(e.get("pc_success"))):
            problems.append(f"{task}: episodes and n_successes must be integers and pc_success a number")
            continue
        if n < 1:
            problems.append(f"{task}: {n} episodes; a result has at least one episode per task")
        elif any(len(m[k]) != n for k in lists):
            problems.append(f"{task}: {n} episodes, but its per-episode lists hold "
                            f"{sorted({len(m[k]) for k in lists})} values")
        elif not all(isinstance(s, bool) for s in succ) or sum(succ) != e["n_successes"]:
            problems.append(f"{task}: n_successes {e['n_successes']} is not the {sum(map(bool, succ))} successful "
                            "episodes it lists")
        elif abs(100.0 * e["n_successes"] / n - e["pc_success"]) > 1e-6:
            problems.append(f"{task}: {e['n_successes']} of {n} is not {e['pc_success']} %")
    if problems:
        return problems
    o = info["overall"]
    k = sum(e["n_successes"] for e in info["per_task"])
    n = sum(e["episodes"] for e in info["per_task"])
    if not isinstance(o, dict) or not _num(o.get("pc_success")) or abs(100.0 * k / n - o["pc_success"]) > 1e-6 \
            or o.get("n_episodes") != n:
        problems.append(f"overall pc_success {str(o.get('pc_success') if isinstance(o, dict) else o)[:40]} is not "
                        f"the tasks' {k} of {n} episodes ({100.0 * k / n:.4g} %)")
    groups = info.get("per_group")
    if not isinstance(groups, dict):
        return [*problems, "per_group is missing"]
    for group, g in groups.items():
        mine = [e for e in info["per_task"] if e.get("task_group") == group]
        gk, gn = sum(e["n_successes"] for e in mine), sum(e["episodes"] for e in mine)
        if not mine or not isinstance(g, dict) or not _num(g.get("pc_success")) \
                or abs(100.0 * gk / gn - g["pc_success"]) > 1e-6:
            problems.append(f"group {group!r}: pc_success is not its tasks' {gk} of {gn} episodes")
    missing = sorted({e.get("task_group") for e in info["per_task"]} - set(groups))
    if missing:
        problems.append(f"task groups {missing} have no per_group entry")
    return problems


def _old_layout_problems(info: dict) -> list[str]:
    problems, total = [], [0, 0]
    for task, t in info["per_task"].items():
        counts = [t.get(k) if isinstance(t, dict) else None for k in ("successes", "episodes", "pc_success")]
        if not (all(_count(c) for c in counts[:2]) and _num(counts[2])):
            problems.append(f"{task}: successes and episodes must be integers and pc_success a number")
            continue
        successes, episodes, pc = counts
        if episodes < 1:
            problems.append(f"{task}: {episodes} episodes; a result has at least one episode per task")
        elif not 0 <= successes <= episodes or abs(100.0 * successes / episodes - pc) > 1e-6:
            problems.append(f"{task}: {successes} of {episodes} is not {pc} %")
        total = [total[0] + successes, total[1] + episodes]
    agg = info["aggregated"]
    claimed = agg.get("pc_success") if isinstance(agg, dict) else None
    if not problems and (not _num(claimed) or abs(100.0 * total[0] / total[1] - claimed) > 1e-6):
        problems.append(f"aggregated pc_success {str(claimed)[:40]} is not the tasks' {total[0]} of {total[1]} "
                        f"episodes ({100.0 * total[0] / total[1]:.4g} %)")
    return problems


def problems(info: dict) -> list[str]:
    """Where a result's numbers do not add up (empty when they do): per task, a count against its episodes and
    rate; overall and per group, the rate against the tasks'."""
    try:
        layout = layout_of(info)
    except ValueError as exc:
        return [str(exc)]
    if "suite" not in info or not isinstance(info["suite"], dict):
        return ["eval_info has no 'suite': use the eval_info.json gendex eval writes"]
    return _new_layout_problems(info) if layout == LAYOUT else _old_layout_problems(info)


def skill_rates(s: Summary) -> dict[str, tuple[int, int]]:
    """Skill -> (successes, episodes) over the tasks exercising it (a task of group ``close_door+put_in`` counts
    for both skills); empty for results without groups."""
    out: dict[str, list[int]] = {}
    for t in s.per_task.values():
        for skill in (t["group"] or "").split("+"):
            if skill:
                acc = out.setdefault(skill, [0, 0])
                acc[0] += t["successes"]
                acc[1] += t["episodes"]
    return {k: (v[0], v[1]) for k, v in out.items()}


__all__ = ["LAYOUT", "OLD_LAYOUT", "Summary", "build", "layout_of", "problems", "skill_rates", "summary"]
