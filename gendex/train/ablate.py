"""``gendex ablate``: the seed paper's four-variant comparison (its Fig. "RLresult"), at a CPU budget.

Variants, each given the same budget of PPO env steps per task:

(i) ``no_subgoals``   one PPO policy for the whole task, every joint, the task's reward, the task's episode length.
(ii) ``subgoals``     every stage trained with PPO in order (budget split evenly), every joint, the stage's reward;
                      stage K starts from the states where stage K-1's policy succeeded in evaluation.
(iii) ``frozen_dofs`` as (ii), each stage driving only its ``control_joint`` group.
(iv) ``mp_rl``        motion-planning stages by the planner, RL stages by PPO (budget split over them), frozen DoFs;
                      RL stage K starts from executor runs of stages 0..K-1 (with the policies trained so far).

Each cell reports the task success rate over ``eval_episodes`` fresh seeds (the trained policies chained by the
stage executor), and the env steps to N successful trajectories: PPO steps + start-state collection steps +
N / success rate × env steps per evaluation episode (the paper's measure, with N = 1000).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import logging
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from gendex.episode_loop import Hooks, SolverAgent, run_episode
from gendex.fanout import Backend, ordered_map
from gendex.solve.executor import StageExecutor
from gendex.solve.policy import StagePolicy
from gendex.train.envs import TASK_STAGE
from gendex.train.evaluate import evaluate_stage
from gendex.train.presets import TrainingError, get_preset
from gendex.train.start_states import collect_executor_states
from gendex.train.train import train_stage
from gendex_envs.errors import ExecutionError, StageError
from gendex_envs.task_version import Artifacts, TaskVersion

log = logging.getLogger(__name__)

VARIANTS: dict[str, str] = {
    "no_subgoals": "(i) no sub-goals",
    "subgoals": "(ii) sub-goals",
    "frozen_dofs": "(iii) sub-goals + frozen DoFs",
    "mp_rl": "(iv) motion planning + RL",
}
PAPER: dict[str, dict[str, str]] = {
    "OpenCabinet": {"mp_rl": "100 %, 25.9 M"},
    "PickUpBottle": {"mp_rl": "60 %, 88.6 M"},
    "PutAppleBowl": {"mp_rl": "40 %, 78.0 M"},
}
"""The paper's numbers (success, env steps to 1000 successes). Its text gives them for variant (iv) only; the other
variants appear as bars without values."""
START_STATES = 64
CAPTURE_EPISODES = 40
FLOOR_STEPS = 1e4
"""Bottom of the plot's log axis."""
"""Evaluation episodes of an all-RL stage whose successes become the next stage's start states."""


@dataclass
class StageRecord:
    stage: str
    method: str
    """``RL`` (PPO-trained here) or ``motion_planning`` (the planner; no training)."""
    control_joint: str
    train_steps: int = 0
    collect_steps: int = 0
    stage_success: float | None = None
    note: str = ""


@dataclass
class Cell:
    task: str
    variant: str
    budget: int
    eval_episodes: int
    successes: int = 0
    train_steps: int = 0
    collect_steps: int = 0
    eval_steps: int = 0
    wall_s: float = 0.0
    stages: list[StageRecord] = field(default_factory=list)
    note: str = ""

    @property
    def success_rate(self) -> float:
        return self.successes / self.eval_episodes if self.eval_episodes else 0.0

    def steps_to(self, n: int) -> float:
        """Env steps to ``n`` successful trajectories (inf when the variant never succeeded)."""
        if self.successes == 0:
            return math.inf
        per_episode = self.eval_steps / self.eval_episodes
        return self.train_steps + self.collect_steps + n / self.success_rate * per_episode

    def as_dict(self) -> dict:
        d = asdict(self)
        d["success_rate"] = self.success_rate
        d["steps_to_1000"] = None if math.isinf(self.steps_to(1000)) else self.steps_to(1000)
        return d


def _split(budget: int, parts: int, rollout: int) -> int:
    """Steps per trained stage: an even share of the budget, at least one PPO rollout."""
    if parts == 0:
        return 0
    share = budget // parts
    if share < rollout:
        raise TrainingError(f"budget {budget} over {parts} stages is less than one PPO rollout ({rollout} steps) each")
    return share


def run_cell(version: TaskVersion, variant: str, budget: int, out: Path, *, seed: int = 0, eval_episodes: int = 20,
             preset: str = "cpu", n_envs: int | None = None) -> Cell:
    """Train and evaluate one (task, variant) cell; the cell's run folder is ``out/<task>/<variant>/``."""
    if variant not in VARIANTS:
        raise TrainingError(f"unknown variant {variant!r}; variants: {list(VARIANTS)}")
    spec = version.spec
    run = out / spec.name / variant
    policies = Artifacts(run)
    p = get_preset(preset)
    rollout = p.n_steps * (n_envs or p.n_envs)
    cell = Cell(task=spec.name, variant=variant, budget=budget, eval_episodes=eval_episodes)
    t0 = time.perf_counter()
    kw = dict(preset=preset, n_envs=n_envs, seed=seed, run_dir=run, progress=False)
    if variant == "no_subgoals":
        r = train_stage(version, None, steps=budget, control_joint="both", eval_episodes=eval_episodes, **kw)
        cell.train_steps = r.steps
        cell.stages.append(StageRecord(TASK_STAGE, "RL", "both", r.steps, 0, r.trained.success_rate))
        cell.successes, cell.eval_steps = r.trained.successes, r.trained.env_steps
    else:
        all_rl = variant in ("subgoals", "frozen_dofs")
        trained = [s for s in spec.stages if all_rl or s.method == "RL"]
        share = _split(budget, len(trained), rollout)
        states = None
        for i, st in enumerate(spec.stages):
            cj = "both" if variant == "subgoals" else st.control_joint
            rec = StageRecord(st.name, "RL" if st in trained else "motion_planning", cj)
            cell.stages.append(rec)
            if st not in trained:
                continue
            if i > 0 and not all_rl:  # (iv): executor runs earlier stages (planner + the policies trained so far)
                try:
                    got = collect_executor_states(version, i, START_STATES, seed=seed, policy_sources=[policies])
                except StageError as e:
                    rec.note = cell.note = f"no start states: {e}"
                    break
                states, rec.collect_steps = got.states, got.env_steps
                cell.collect_steps += got.env_steps
            elif i > 0 and states is None:
                rec.note = cell.note = f"stage {spec.stages[i - 1].name!r} never succeeded: chain broken"
                break
            r = train_stage(version, st.name, steps=share, control_joint=cj, start_states=states,
                            eval_episodes=eval_episodes, **kw)
            rec.train_steps, rec.stage_success = r.steps, r.trained.success_rate
            cell.train_steps += r.steps
            if all_rl and i + 1 < len(spec.stages):
                policy = StagePolicy.load(version, r.policy)
                res, states = evaluate_stage(version, st.name, policy, episodes=CAPTURE_EPISODES, seed=seed + 50_000,
                                             control_joint=cj, start_states=states, capture=True)
                rec.collect_steps = res.env_steps
                cell.collect_steps += res.env_steps
                if states is not None:  # captured at this stage's success: the next stage's start states
                    states = dataclasses.replace(states, stage=spec.stages[i + 1].name)
        else:
            cell.successes, cell.eval_steps = evaluate_executor(version, policies, eval_episodes, seed=seed + 100_000,
                                                                policy_stages="all" if all_rl else "rl")
    cell.wall_s = time.perf_counter() - t0
    (run / "cell.json").write_text(json.dumps(cell.as_dict(), indent=2) + "\n")
    log.info("%s %s: %d/%d successes, %d train + %d collect steps, %.0f s", spec.name, variant, cell.successes,
             eval_episodes, cell.train_steps, cell.collect_steps, cell.wall_s)
    return cell


def evaluate_executor(version: TaskVersion, policies: Artifacts, episodes: int, *, seed: int,
                      policy_stages: str) -> tuple[int, int]:
    """(successes, env steps) of the stage executor running the whole task with the policies of ``policies``; an
    episode ends at its first success (:func:`gendex.episode_loop.run_episode`), when the executor gives up or is
    done, or at the time limit."""
    from gendex_envs.registry import make_env

    spec = version.spec
    limit = max(spec.max_episode_steps, sum(s.horizon for s in spec.stages) + spec.success.hold_steps + 10)
    env = make_env(version, control_mode="pd_joint_pos", control_joint="both", max_episode_steps=limit)
    agent = SolverAgent(StageExecutor(policy_sources=[policies], policy_stages=policy_stages), env)
    hooks = Hooks(stop=lambda step: step.success, catch=(ExecutionError,))
    successes = steps = 0
    try:
        for ep in range(episodes):
            out = run_episode(env, agent, seed + ep, hooks)
            if out.error is not None:
                log.debug("episode %d: %s", ep, out.error)
            steps += out.steps
            successes += out.success_at_end
    finally:
        env.close()
    return successes, steps


def load_cell(path: Path) -> Cell:
    d = json.loads(path.read_text())
    stages = [StageRecord(**s) for s in d.pop("stages")]
    for k in ("success_rate", "steps_to_1000"):
        d.pop(k, None)
    return Cell(**d, stages=stages)


def _cell_worker(budget: int, out: Path, seed: int, eval_episodes: int, preset: str, n_envs: int | None):
    """A worker of :func:`gendex.fanout.ordered_map`: trains and evaluates one (version, variant) cell per job."""
    def run(job: tuple[TaskVersion, str]) -> Cell:
        version, variant = job
        return run_cell(version, variant, budget, out, seed=seed, eval_episodes=eval_episodes, preset=preset,
                        n_envs=n_envs)
    return run


def run_ablation(versions: list[TaskVersion], budget: int, out: Path, *, variants: tuple[str, ...] = tuple(VARIANTS),
                 seed: int = 0, eval_episodes: int = 20, preset: str = "cpu", n_envs: int | None = None,
                 resume: bool = True, progress=None, backend: Backend | None = None) -> list[Cell]:
    """Every (task, variant) cell; with ``resume``, a cell already saved with the same budget and episodes is kept.
    ``backend`` (:class:`gendex.fanout.Backend`, default this process) trains the missing cells in parallel; each
    cell is seeded by ``seed`` alone, so where it runs does not change it."""
    found: dict[tuple[str, str], Cell] = {}
    todo: list[tuple[TaskVersion, str]] = []
    for version in versions:
        for variant in variants:
            saved = out / version.name / variant / "cell.json"
            cell = load_cell(saved) if resume and saved.is_file() else None
            if cell is not None and cell.budget == budget and cell.eval_episodes == eval_episodes:
                log.info("%s %s: kept from %s", version.name, variant, saved)
                found[(version.name, variant)] = cell
                if progress:
                    progress(cell)
            else:
                todo.append((version, variant))
    worker = functools.partial(_cell_worker, budget, out, seed, eval_episodes, preset, n_envs)
    for (version, variant), cell in zip(todo, ordered_map(worker, todo, backend), strict=True):
        found[(version.name, variant)] = cell
        if progress:
            progress(cell)
    return [found[(v.name, variant)] for v in versions for variant in variants]


def _stage_cell(s: StageRecord) -> str:
    if s.method == "motion_planning":
        return "planner"
    return "not reached" if s.stage_success is None else f"{100 * s.stage_success:.0f} %"


def _fmt_steps(x: float) -> str:
    if math.isinf(x):
        return "— (no success)"
    return f"{x / 1e6:.2f} M" if x >= 1e5 else f"{x / 1e3:.0f} k"


def write_results(cells: list[Cell], path: Path, plot: Path, command: str, budget: int, n: int = 1000) -> Path:
    """The four-variant table (and a plot) as Markdown, beside the paper's numbers."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tasks = list(dict.fromkeys(c.task for c in cells))
    variants = [v for v in VARIANTS if any(c.variant == v for c in cells)]
    by = {(c.task, c.variant): c for c in cells}
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    width = 0.8 / max(1, len(variants))
    for j, v in enumerate(variants):
        xs = [i + (j - (len(variants) - 1) / 2) * width for i in range(len(tasks))]
        rate = [100 * by[(t, v)].success_rate if (t, v) in by else 0 for t in tasks]
        steps = [by[(t, v)].steps_to(n) if (t, v) in by else math.inf for t in tasks]
        color = f"C{list(VARIANTS).index(v)}"  # one colour per variant in every plot
        axes[0].bar(xs, rate, width, label=VARIANTS[v], color=color)
        bars = axes[1].bar(xs, [s if not math.isinf(s) else 0 for s in steps], width, label=VARIANTS[v],
                           color=color)
        for x, s, bar in zip(xs, steps, bars, strict=True):
            if math.isinf(s):  # never succeeded: a marker at the axis instead of an invisible bar
                axes[1].plot(x, FLOOR_STEPS * 1.3, marker="x", color=bar.get_facecolor(), markersize=6)
    titles = ("success rate (%)", f"env steps to {n} successes (log; × = never succeeded)")
    for ax, title in zip(axes, titles, strict=True):
        ax.set_xticks(range(len(tasks)), tasks)
        ax.set_title(title, fontsize=10)
    for i, t in enumerate(tasks):  # the paper's variant (iv), where its text gives numbers
        if "mp_rl" in PAPER.get(t, {}):
            rate, steps = PAPER[t]["mp_rl"].replace(" %", "").replace(" M", "").split(", ")
            axes[0].plot(i, float(rate), marker="*", color="k", markersize=9, label="paper (iv)" if i == 0 else None)
            axes[1].plot(i, float(steps) * 1e6, marker="*", color="k", markersize=9)
    axes[1].set_yscale("log")
    axes[1].set_ylim(bottom=FLOOR_STEPS)
    axes[0].set_ylim(0, 105)
    axes[0].legend(fontsize=7, loc="upper right")
    fig.suptitle(f"GenDex ablation, {budget:,} PPO env steps per task and variant (2 CPU cores)", fontsize=10)
    fig.tight_layout()
    plot.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(plot, dpi=110)
    plt.close(fig)

    lines = ["| task | variant | success | env steps to 1000 successes | PPO steps | start-state / capture steps | "
             "per-stage success (evaluated alone) | paper (success, steps to 1000) |",
             "|---|---|---|---|---|---|---|---|"]
    for t in tasks:
        for v in variants:
            c = by.get((t, v))
            if c is None:
                continue
            stages = ", ".join(f"{s.stage}: {_stage_cell(s)}" for s in c.stages)
            lines.append(f"| {t} | {VARIANTS[v]} | {c.successes}/{c.eval_episodes} ({100 * c.success_rate:.0f} %) | "
                         f"{_fmt_steps(c.steps_to(n))} | {c.train_steps:,} | {c.collect_steps:,} | {stages} | "
                         f"{PAPER.get(t, {}).get(v, 'bar only')} |")
    table = "\n".join(lines)
    path.parent.mkdir(parents=True, exist_ok=True)
    rel = plot.relative_to(path.parent) if plot.is_relative_to(path.parent) else plot
    begin, end = ablation_markers(budget)
    text = (begin + f"\nCommand: `{command}` (budget {budget:,} PPO env steps per task and variant, "
            f"{cells[0].eval_episodes} evaluation episodes per cell).\n\n{table}\n\n![ablation]({rel})\n"
            + end)
    old = path.read_text() if path.is_file() else "# Results\n\n"
    if begin in old and end in old:  # one block per budget, replaced in place
        head, rest = old.split(begin, 1)
        new = head + text + rest.split(end, 1)[1]
    else:
        new = old.rstrip("\n") + "\n\n" + text + "\n"
    path.write_text(new)
    return path


def ablation_markers(budget: int) -> tuple[str, str]:
    """HTML comments around the table of one budget in the results file."""
    return (f"<!-- ablation table, budget {budget}: written by `gendex ablate` -->",
            f"<!-- end of ablation table, budget {budget} -->")
