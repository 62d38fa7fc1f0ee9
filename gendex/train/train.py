"""``gendex train``: PPO (stable-baselines3) on one stage of a task version, saved into a *run folder*.

Training never writes into a task version (a published version never changes behaviour). The run folder has the
version's layout for what it produces (:class:`~gendex_envs.task_version.TaskLayout`): the policy with its record,
curve and checkpoints, the stage's start states, and a run record naming the version it was trained from. Train
several stages into the same run folder to chain them (stage K's start states are collected with the policies the
run already has); ``gendex promote RUN`` publishes the version plus the run's policies and start states as the next
version (:func:`promote`).

Stage K > 0 starts from the version's start states of that stage when it has them, else the run's, else they are
collected with the stage executor (earlier stages by motion planning, scripted primitives, or the run's and the
version's trained policies) and saved in the run folder.

Training can start from an earlier policy of the same stage (``init``, :func:`warm_start`): its weights (only the
tensors of its ``policy.pth``, never the zip's pickled ``data``: :func:`~gendex.solve.policy.read_policy_weights`)
and its observation normalization are loaded, and its exploration noise is reset to the preset's ``log_std_init``, so a
policy trained under much noise can be refined under less (what its deterministic actions, the ones the executor
runs, need). Its evaluation before training is then the "untrained" one in the record.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gendex.solve.policy import POLICY_FORMAT, StagePolicy, architecture_of, read_policy_record, read_policy_weights
from gendex.train.envs import TASK_STAGE, make_gpu_vec_env, make_vec_env
from gendex.train.evaluate import EvalResult, evaluate_stage
from gendex.train.presets import PPOPreset, TrainingError, get_preset
from gendex.train.start_states import collect_executor_states
from gendex_envs.atomic_io import atomic_path, write_json
from gendex_envs.start_states import StartStates
from gendex_envs.task_version import Artifacts, PolicyFiles, TaskLayout, TaskVersion, derive_version

log = logging.getLogger(__name__)

START_STATES_PER_STAGE = 64


@dataclass(frozen=True)
class TrainResult:
    stage: str
    policy: PolicyFiles
    steps: int
    """Env steps PPO trained on."""
    start_state_steps: int
    """Env steps spent collecting this stage's start states (0 when they existed already)."""
    wall_s: float
    untrained: EvalResult
    trained: EvalResult


def default_run_dir(version: TaskVersion) -> Path:
    return Path("out") / "train" / f"{version.name}-v{version.version}"


def open_run(run_dir: str | Path, version: TaskVersion) -> TaskLayout:
    """The run folder ``run_dir`` for ``version``: created with its run record, or checked to belong to it."""
    import json

    run = TaskLayout(run_dir)
    record = run.record("run")
    if record.is_file():
        meta = json.loads(record.read_text())
        if meta.get("source") != version.env_id:
            raise TrainingError(f"{run.root} is a training run of {meta.get('source')}, not of {version.env_id}; "
                                "pass another --out")
        return run
    run.root.mkdir(parents=True, exist_ok=True)
    write_json(record, {"source": version.env_id, "source_digest": version.file_digest()}, indent=2)
    return run


def stage_start_states(version: TaskVersion, stage: str, index: int, run: TaskLayout,
                       policy_sources: Sequence[Artifacts], seed: int,
                       n: int = START_STATES_PER_STAGE) -> tuple[StartStates | None, int]:
    """(start states, env steps spent) of a stage: None for the first stage; the version's or the run's, else
    collected into the run folder."""
    if index == 0:
        return None, 0
    for source in (version.artifacts, Artifacts(run.root)):
        found = source.start_states(stage)
        if found is not None:
            return found, 0
    got = collect_executor_states(version, stage, n, seed=seed, policy_sources=policy_sources, progress=True)
    got.states.save(run.start_states(stage))
    return got.states, got.env_steps


def policy_to_start_from(version: TaskVersion, stage: str | int, source: str | Path) -> PolicyFiles:
    """The policy of ``version``'s ``stage`` in ``source``: a training run folder, or a task version (id or folder)
    of the same task; :class:`TrainingError` when it has none."""
    from gendex_envs.registry import resolve_task

    name = TASK_STAGE if stage == TASK_STAGE else version.stage(stage)[1].name
    run = TaskLayout(source)
    if run.record("run").is_file():
        found = Artifacts(run.root).policy(name)
    else:
        other = resolve_task(str(source))
        if other.name != version.name:
            raise TrainingError(f"{other.env_id} is another task than {version.env_id}: no policy to start from")
        found = other.policy(name)
    if found is None:
        raise TrainingError(f"{source} has no trained policy of stage {name!r} to start from")
    return found


def warm_start(model, venv, init: PolicyFiles, control_joint: str, log_std_init: float) -> dict:
    """Load the policy ``init`` (model weights, observation normalization) into a fresh PPO ``model`` and its
    ``VecNormalize`` ``venv``, then set the policy's log standard deviation to ``log_std_init``; returns what the
    record says about it. :class:`TrainingError` when ``init`` does not fit (other joints, observation or network)."""
    import torch

    meta = read_policy_record(init.record)
    norm = meta["obs_norm"]
    if meta.get("control_joint") != control_joint or len(norm["mean"]) != venv.observation_space.shape[0]:
        raise TrainingError(f"{init.where} drives {meta.get('control_joint')!r} from {len(norm['mean'])} "
                            f"observations; this stage drives {control_joint!r} from "
                            f"{venv.observation_space.shape[0]}: it cannot start from it")
    weights = read_policy_weights(init.model)  # weights only: the zip's pickled `data` is never read
    try:
        model.policy.load_state_dict(weights, strict=True)
    except RuntimeError as exc:
        raise TrainingError(f"{init.where}: its network does not match the preset's ({exc})") from None
    with torch.no_grad():
        model.policy.log_std.fill_(log_std_init)
    venv.obs_rms.mean = np.asarray(norm["mean"], dtype=np.float64)
    venv.obs_rms.var = np.asarray(norm["var"], dtype=np.float64)
    venv.obs_rms.count = float(meta.get("steps", 1))
    log.info("warm start from %s (%s steps), log std reset to %.2f", init.where, meta.get("steps"), log_std_init)
    model_path = init.where.resolve()
    shown = model_path.relative_to(Path.cwd()) if model_path.is_relative_to(Path.cwd()) else model_path
    return dict(model=str(shown), steps=meta.get("steps"), source=meta.get("source"),
                command=meta.get("command"))


def train_stage(version: TaskVersion, stage: str | int | None, *, steps: int, run_dir: str | Path,
                preset: str | PPOPreset = "cpu", n_envs: int | None = None, seed: int = 0,
                control_joint: str | None = None, start_states: StartStates | None = None,
                eval_episodes: int = 20, checkpoint_every: int = 50_000, command: str = "",
                progress: bool = True, init: PolicyFiles | None = None) -> TrainResult:
    """Train PPO on ``stage`` (name or index; None: the whole task with every joint) of ``version`` and save it
    into the run folder ``run_dir`` (module doc). ``control_joint`` overrides the stage's joint group (the
    ablation's "no frozen DoFs" variants); ``init``: start from this policy of the stage (:func:`warm_start`)."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import CheckpointCallback
    from stable_baselines3.common.logger import configure
    from stable_baselines3.common.vec_env import VecNormalize

    spec = version.spec
    if stage is None or stage == TASK_STAGE:
        name, index, stage_cj = TASK_STAGE, 0, "both"
    else:
        index, st = version.stage(stage)
        name, stage_cj = st.name, st.control_joint
    cj = control_joint or stage_cj
    p = get_preset(preset) if isinstance(preset, str) else preset
    if n_envs is not None:
        p = dataclasses.replace(p, n_envs=n_envs, gpu_backend=p.gpu_backend and torch.cuda.is_available())
    if p.gpu_backend and not torch.cuda.is_available():
        raise TrainingError(f"preset {p.name!r} runs {p.n_envs} envs on ManiSkill's GPU backend and needs CUDA; "
                            "on a CPU machine pass --envs (processes) or use --preset cpu")
    rollout = p.n_steps * p.n_envs
    if steps < rollout:
        raise TrainingError(f"--steps {steps} is less than one PPO rollout ({p.n_steps} steps × {p.n_envs} envs = "
                            f"{rollout})")
    run = open_run(run_dir, version)
    run_policies = Artifacts(run.root)
    curve_dir = run.policy_curves(name)
    curve_dir.mkdir(parents=True, exist_ok=True)
    if start_states is None and name != TASK_STAGE:
        start_states, state_steps = stage_start_states(version, name, index, run, (run_policies, version.artifacts),
                                                       seed)
    else:
        state_steps = 0
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # the env workers own the cores (PPO on 2 cores: 4x faster than torch's default)
    env_kw = dict(control_joint=cj, start_states=start_states)
    t0 = time.perf_counter()
    make = make_gpu_vec_env if p.gpu_backend else make_vec_env
    venv = VecNormalize(make(version, name, p.n_envs, seed, **env_kw), gamma=p.gamma, clip_obs=10.0)
    judge = version.judge(None if name == TASK_STAGE else name)
    try:
        model = PPO("MlpPolicy", venv, seed=seed, device="cpu", verbose=0, **p.ppo_kwargs())
        started = warm_start(model, venv, init, cj, p.log_std_init) if init is not None else None
        fresh = StagePolicy(stage=name, control_joint=cj, judge=judge, model=model,
                            obs_mean=venv.obs_rms.mean.astype(np.float32).copy(),
                            obs_var=venv.obs_rms.var.astype(np.float32).copy(), clip_obs=venv.clip_obs, meta={})
        untrained, _ = evaluate_stage(version, name, fresh, episodes=min(eval_episodes, 10), **env_kw)
        model.set_logger(configure(str(curve_dir), ["csv"]))
        ckpt = CheckpointCallback(save_freq=max(1, checkpoint_every // p.n_envs),
                                  save_path=str(run.policy_checkpoints(name)), name_prefix=name)
        model.learn(total_timesteps=steps, callback=ckpt, progress_bar=progress)
        norm = dict(mean=venv.obs_rms.mean.tolist(), var=venv.obs_rms.var.tolist(), clip=venv.clip_obs)
    finally:
        venv.close()
        torch.set_num_threads(threads)
    trained_steps = int(model.num_timesteps)
    files = PolicyFiles(name, run.policy(name), run.policy_record(name))
    meta = dict(format=POLICY_FORMAT, task=spec.name, source=version.env_id, stage=name, stage_index=index,
                control_joint=cj, control_mode="pd_joint_delta_pos", preset=dataclasses.asdict(p),
                steps=trained_steps, seed=seed, obs_norm=norm, obs_dim=len(norm["mean"]),
                start_states=len(start_states) if start_states else 0, start_state_steps=state_steps,
                command=command, init=started,
                architecture=architecture_of(p.net_arch, len(norm["mean"]), model.action_space.shape[0]))
    with atomic_path(files.model) as tmp:
        model.save(str(tmp))
    write_json(files.record, meta, indent=2, sort_keys=True)
    policy = StagePolicy.load(version, files)
    trained, _ = evaluate_stage(version, name, policy, episodes=eval_episodes, **env_kw)
    wall = time.perf_counter() - t0
    meta |= dict(evaluation=dict(untrained=untrained.as_dict(), trained=trained.as_dict()),
                 wall_s=round(wall, 1))
    write_json(files.record, meta, indent=2, sort_keys=True)
    log.info("%s/%s: %d steps in %.0f s; success %d/%d (untrained: %d/%d), mean return %.2f (untrained: %.2f)",
             spec.name, name, trained_steps, wall, trained.successes, trained.episodes, untrained.successes,
             untrained.episodes, trained.mean_return, untrained.mean_return)
    return TrainResult(stage=name, policy=files, steps=trained_steps, start_state_steps=state_steps,
                       wall_s=wall, untrained=untrained, trained=trained)


def promote(run_dirs: Sequence[str | Path], command: str = "") -> TaskVersion:
    """Publish the next version of the runs' task version: the version plus the runs' policies and start states
    (later runs win). The runs must come from one version, which must be unchanged since they were trained."""
    import json

    from gendex_envs.registry import resolve_task

    if not run_dirs:
        raise TrainingError("name at least one training run folder to promote")
    sources = []
    for d in run_dirs:
        record = TaskLayout(d).record("run")
        if not record.is_file():
            raise TrainingError(f"{d} is not a training run folder (no {record.name}; `gendex train --out` makes one)")
        sources.append(json.loads(record.read_text()))
    names = {s["source"] for s in sources}
    if len(names) != 1:
        raise TrainingError(f"the runs come from different versions ({sorted(names)}); promote one version's runs")
    version = resolve_task(names.pop())
    if any(s.get("source_digest") != version.file_digest() for s in sources):
        raise TrainingError(f"{version.env_id} changed since the run was trained (its files differ from the "
                            "digest in the run record): retrain from the current version")
    return derive_version(version, [Artifacts(d) for d in run_dirs],
                          {"runs": [str(Path(d)) for d in run_dirs], "command": command})


def progress_rows(run_dir: Path, stage: str) -> list[dict]:
    """Rows of a stage's ``progress.csv`` (SB3's CSV logger) in a run folder, numbers parsed."""
    import csv

    path = TaskLayout(run_dir).policy_curves(stage) / "progress.csv"
    with path.open() as f:
        return [{k: (float(v) if v not in ("", None) else np.nan) for k, v in row.items()} for row in csv.DictReader(f)]
