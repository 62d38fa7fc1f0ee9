"""Run a trained stage policy inside an env of any control mode.

A policy is trained on the stage's own env (``TaskEnv(stage=...)``): observation = ManiSkill's flat ``state`` of that
env (agent qpos, qvel and controller targets, then the env's extras with the stage module's ``_get_obs_extra``),
normalized with the running mean and variance saved in the policy's record; action = normalized joint-target deltas
of the stage's ``control_joint`` group. :class:`StagePolicy` rebuilds exactly that observation on another env of the
same task (the stage executor's, which drives every joint with absolute targets,
:meth:`~gendex_envs.task_env.TaskEnv.state_observation`) and turns the policy's deltas into absolute targets for all
joints, so one policy file serves training, evaluation and data collection. Everything is batched over
``num_envs``. Where the files lie is the task version's business (:class:`~gendex_envs.task_version.PolicyFiles`).
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field

import numpy as np
import torch

from gendex_envs.agents.ur10e_shadow import delta_limits, free_joints
from gendex_envs.errors import PolicyError, StageError
from gendex_envs.success import Judge
from gendex_envs.task_version import PolicyFiles, TaskVersion

log = logging.getLogger(__name__)

POLICY_FORMAT = 1
"""Version of a policy's JSON record; bumped when the observation or action layout changes."""
WHOLE_TASK = "task"
"""Stage name of a policy trained on the whole task (every joint, the task's reward and success)."""


def stage_observation(env, judge: Judge, info: dict | None = None) -> torch.Tensor:
    """[N, D] the flat ``state`` observation a stage env judged by ``judge`` would return for ``env``'s state
    (``info``: ``judge.evaluate`` of this state, if the caller has it already)."""
    return env.unwrapped.state_observation(judge, info)


def success_hold_steps(version: TaskVersion, stage: str) -> int:
    """Consecutive steps ``stage``'s success must hold in its env (:attr:`StagePolicy.hold_steps`)."""
    own = stage != WHOLE_TASK and version.stage(stage)[1].success is not None
    return 1 if own else max(1, version.spec.success.hold_steps)


@dataclass
class StagePolicy:
    """A trained PPO policy of one stage, with what it needs to run on another env of the task."""

    stage: str
    control_joint: str
    judge: Judge
    """The stage's judge: its reward module's extras feed the observation; it tells when the stage is done."""
    model: object
    """stable-baselines3 policy (``model.policy`` of the saved PPO)."""
    obs_mean: np.ndarray
    obs_var: np.ndarray
    clip_obs: float
    meta: dict
    hold_steps: int = 1
    """Consecutive steps the stage's success must hold before its env counts it (the task's ``hold_steps`` when the
    stage is judged by the task's conditions, as :meth:`~gendex_envs.task_env.TaskEnv.evaluate` counts it; else 1):
    the policy was trained and evaluated acting through them, so it runs through them."""
    _joints: tuple | None = field(default=None, init=False, repr=False)
    """(controller, joint indices, per-joint delta bounds), computed once per controller."""

    @classmethod
    def load(cls, version: TaskVersion, files: PolicyFiles) -> StagePolicy:
        """Load a trained policy of one of ``version``'s stages (``files``: its model and record, from the version
        or from a training run of it); :class:`StageError` when a file is missing."""
        from stable_baselines3 import PPO

        if not files.model.is_file() or not files.record.is_file():
            raise StageError(f"no trained policy for stage {files.stage!r}: need {files.model} and {files.record} "
                             "(`gendex train` writes both)")
        meta = json.loads(files.record.read_text())
        if meta.get("format") != POLICY_FORMAT:
            raise PolicyError(f"{files.record}: policy format {meta.get('format')!r}, this GenDex reads "
                              f"{POLICY_FORMAT}")
        model = PPO.load(str(files.model), device="cpu")
        norm = meta["obs_norm"]
        judge = version.judge(None if files.stage == WHOLE_TASK else files.stage)
        return cls(stage=files.stage, control_joint=meta["control_joint"], judge=judge,
                   model=model, obs_mean=np.asarray(norm["mean"], dtype=np.float32),
                   obs_var=np.asarray(norm["var"], dtype=np.float32), clip_obs=float(norm["clip"]), meta=meta,
                   hold_steps=success_hold_steps(version, files.stage))

    def normalize(self, obs: np.ndarray) -> np.ndarray:
        """Raw flat observation(s) -> what the network takes (the training run's running mean and variance)."""
        if np.shape(obs)[-1] != self.obs_mean.shape[0]:
            raise PolicyError(f"stage {self.stage!r}: observation has {np.shape(obs)[-1]} values, the policy was "
                              f"trained on {self.obs_mean.shape[0]} (different task version or reward module?)")
        return np.clip((obs - self.obs_mean) / np.sqrt(self.obs_var + 1e-8), -self.clip_obs, self.clip_obs)

    def predict(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        """Normalized action(s) in [-1, 1] for raw observation(s) of the stage's own env."""
        action, _ = self.model.predict(self.normalize(np.asarray(obs, dtype=np.float32)), deterministic=deterministic)
        return np.clip(np.asarray(action, dtype=np.float32), -1.0, 1.0)

    def act(self, env, info: dict | None = None, deterministic: bool = True) -> np.ndarray:
        """[N, F] normalized deltas in [-1, 1] for the stage's free joints (``info``: the stage judge's
        ``evaluate`` of the current state, when the caller has it)."""
        obs = stage_observation(env, self.judge, info).cpu().numpy()
        return self.predict(obs, deterministic).reshape(env.unwrapped.num_envs, -1)

    def targets(self, env, action: np.ndarray) -> torch.Tensor:
        """[N, J] absolute targets of every controller joint after applying ``action`` (the stage env's rule:
        free joints move by ``action`` × the per-step delta bound from their current target, clipped to the joint
        limits; coupled distal joints copy their leader)."""
        ctrl = env.unwrapped.agent.controller
        if self._joints is None or self._joints[0] is not ctrl:
            free = free_joints(self.control_joint)
            self._joints = (ctrl, ctrl.joint_indices(free),
                            torch.tensor(delta_limits(free), dtype=torch.float32, device=ctrl.device))
        _, idx, bound = self._joints
        if action.shape[-1] != len(idx):
            raise PolicyError(f"stage {self.stage!r}: policy gives {action.shape[-1]} actions, control_joint "
                              f"{self.control_joint!r} has {len(idx)} free joints")
        return ctrl.moved_targets(idx, torch.as_tensor(action, device=ctrl.device) * bound)
