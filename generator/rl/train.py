"""``gendex train``: PPO (stable-baselines3) on one stage of a task, saved with the task version.

Outputs, in ``policy_dir`` (default ``<task>/v<N>/policies``)::

    <stage>.zip                  the PPO model (policy + value network)
    <stage>.json                 preset, steps, seed, observation normalization, evaluation, command
    <stage>/progress.csv         SB3's training curve (rollout/ep_rew_mean, rollout/success_rate, losses, ...)
    <stage>/checkpoints/*.zip    intermediate models (not committed)

Stage K > 0 starts from ``start_states/<stage>.npz`` beside the policy folder, collected with the stage executor
(earlier stages by motion planning / scripted primitives / trained policies) when the file does not exist yet.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gendex_envs.atomic_io import atomic_path, write_json
from gendex_envs.reward_module import load_reward_module
from gendex_envs.solve.policy import POLICY_FORMAT, StagePolicy
from gendex_envs.spec import load_task_spec
from gendex_envs.stage import POLICIES_DIR, START_STATES_DIR, StartStates, resolve_stage, stage_reward_path
from generator.rl.envs import TASK_STAGE, make_gpu_vec_env, make_vec_env
from generator.rl.evaluate import EvalResult, evaluate_stage
from generator.rl.presets import PPOPreset, TrainingError, get_preset
from generator.rl.start_states import collect_executor_states

log = logging.getLogger(__name__)

START_STATES_PER_STAGE = 64


@dataclass(frozen=True)
class TrainResult:
    stage: str
    policy_path: Path
    steps: int
    """Env steps PPO trained on."""
    start_state_steps: int
    """Env steps spent collecting this stage's start states (0 when they existed already)."""
    wall_s: float
    untrained: EvalResult
    trained: EvalResult


def stage_start_states(task_dir: Path, stage: str, index: int, states_dir: Path, policy_dir: Path | None,
                       seed: int, n: int = START_STATES_PER_STAGE) -> tuple[StartStates | None, int]:
    """(start states, env steps spent) of a stage: None for the first stage; loaded, or collected and saved."""
    if index == 0:
        return None, 0
    path = states_dir / f"{stage}.npz"
    if path.is_file():
        return StartStates.load(path), 0
    got = collect_executor_states(task_dir, stage, n, seed=seed, policy_dir=policy_dir, progress=True)
    got.states.save(path)
    return got.states, got.env_steps


def train_stage(task_dir: str | Path, stage: str | int | None, *, steps: int, preset: str | PPOPreset = "cpu",
                n_envs: int | None = None, seed: int = 0, policy_dir: str | Path | None = None,
                control_joint: str | None = None, start_states: StartStates | None = None,
                eval_episodes: int = 20, checkpoint_every: int = 50_000, command: str = "",
                progress: bool = True) -> TrainResult:
    """Train PPO on ``stage`` (name or index; None: the whole task with every joint) and save it (module doc).

    ``control_joint`` overrides the stage's joint group (the ablation's "no frozen DoFs" variants).
    """
    import torch  # noqa: PLC0415
    from stable_baselines3 import PPO  # noqa: PLC0415
    from stable_baselines3.common.callbacks import CheckpointCallback  # noqa: PLC0415
    from stable_baselines3.common.logger import configure  # noqa: PLC0415
    from stable_baselines3.common.vec_env import VecNormalize  # noqa: PLC0415

    task_dir = Path(task_dir)
    spec = load_task_spec(task_dir / "task.yaml")
    if stage is None or stage == TASK_STAGE:
        name, index, stage_cj = TASK_STAGE, 0, "both"
    else:
        index, st = resolve_stage(spec, stage)
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
    policy_dir = Path(policy_dir) if policy_dir is not None else task_dir / POLICIES_DIR
    curve_dir = policy_dir / name
    curve_dir.mkdir(parents=True, exist_ok=True)
    if start_states is None and name != TASK_STAGE:
        start_states, state_steps = stage_start_states(task_dir, name, index, policy_dir.parent / START_STATES_DIR,
                                                       policy_dir, seed)
    else:
        state_steps = 0
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # the env workers own the cores (PPO on 2 cores: 4x faster than torch's default)
    env_kw = dict(control_joint=cj, start_states=start_states)
    t0 = time.perf_counter()
    make = make_gpu_vec_env if p.gpu_backend else make_vec_env
    venv = VecNormalize(make(task_dir, name, p.n_envs, seed, **env_kw), gamma=p.gamma, clip_obs=10.0)
    try:
        model = PPO("MlpPolicy", venv, seed=seed, device="cpu", verbose=0, **p.ppo_kwargs())
        fresh = StagePolicy(stage=name, control_joint=cj, module=load_reward_module(stage_reward_path(task_dir, name)),
                            model=model, obs_mean=venv.obs_rms.mean.astype(np.float32).copy(),
                            obs_var=venv.obs_rms.var.astype(np.float32).copy(), clip_obs=venv.clip_obs, meta={})
        untrained, _ = evaluate_stage(task_dir, name, fresh, episodes=min(eval_episodes, 10), **env_kw)
        model.set_logger(configure(str(curve_dir), ["csv"]))
        ckpt = CheckpointCallback(save_freq=max(1, checkpoint_every // p.n_envs),
                                  save_path=str(curve_dir / "checkpoints"), name_prefix=name)
        model.learn(total_timesteps=steps, callback=ckpt, progress_bar=progress)
        norm = dict(mean=venv.obs_rms.mean.tolist(), var=venv.obs_rms.var.tolist(), clip=venv.clip_obs)
    finally:
        venv.close()
        torch.set_num_threads(threads)
    trained_steps = int(model.num_timesteps)
    path = policy_dir / f"{name}.zip"
    meta = dict(format=POLICY_FORMAT, task=spec.name, stage=name, stage_index=index, control_joint=cj,
                control_mode="pd_joint_delta_pos", preset=dataclasses.asdict(p), steps=trained_steps, seed=seed,
                obs_norm=norm, obs_dim=len(norm["mean"]), start_states=len(start_states) if start_states else 0,
                start_state_steps=state_steps, command=command)
    with atomic_path(path) as tmp:
        model.save(str(tmp))
    write_json(path.with_suffix(".json"), meta, indent=2, sort_keys=True)
    policy = StagePolicy.load(task_dir, name, path)
    trained, _ = evaluate_stage(task_dir, name, policy, episodes=eval_episodes, **env_kw)
    wall = time.perf_counter() - t0
    meta |= dict(evaluation=dict(untrained=untrained.as_dict(), trained=trained.as_dict()),
                 wall_s=round(wall, 1))
    write_json(path.with_suffix(".json"), meta, indent=2, sort_keys=True)
    log.info("%s/%s: %d steps in %.0f s; success %d/%d (untrained: %d/%d), mean return %.2f (untrained: %.2f)",
             spec.name, name, trained_steps, wall, trained.successes, trained.episodes, untrained.successes,
             untrained.episodes, trained.mean_return, untrained.mean_return)
    return TrainResult(stage=name, policy_path=path, steps=trained_steps, start_state_steps=state_steps,
                       wall_s=wall, untrained=untrained, trained=trained)


def progress_rows(policy_dir: Path, stage: str) -> list[dict]:
    """Rows of ``<stage>/progress.csv`` (SB3's CSV logger), numbers parsed."""
    import csv  # noqa: PLC0415

    path = Path(policy_dir) / stage / "progress.csv"
    with path.open() as f:
        return [{k: (float(v) if v not in ("", None) else np.nan) for k, v in row.items()} for row in csv.DictReader(f)]
