"""Run a trained stage policy (``policies/<stage>.zip``) inside an env of any control mode.

A policy is trained on the stage's own env (:mod:`gendex_envs.stage`): observation = ManiSkill's flat ``state`` of
that env (agent qpos, qvel and controller targets, then the env's extras with the stage module's
``_get_obs_extra``), normalized with the running mean and variance saved in ``policies/<stage>.json``; action =
normalized joint-target deltas of the stage's ``control_joint`` group. :class:`StagePolicy` rebuilds exactly that
observation on another env of the same task (the stage executor's, which drives every joint with absolute targets)
and turns the policy's deltas into absolute targets for all joints, so one policy file serves training, evaluation
and data collection. Everything is batched over ``num_envs``.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
from mani_skill.utils import common

from gendex_envs.agents.ur10e_shadow import delta_limits, free_joints
from gendex_envs.errors import PolicyError, StageError
from gendex_envs.reward_module import RewardModule, load_reward_module
from gendex_envs.stage import policy_path, stage_reward_path

log = logging.getLogger(__name__)

POLICY_FORMAT = 1
"""Version of the ``policies/<stage>.json`` record; bumped when the observation or action layout changes."""


def stage_observation(env, module: RewardModule, info: dict | None = None) -> torch.Tensor:
    """[N, D] the flat ``state`` observation a stage env with reward ``module`` would return for ``env``'s state
    (``info``: what ``module.evaluate`` returned for this state, if the caller has it already)."""
    u = env.unwrapped
    info = dict(module.evaluate(u) if info is None else info)
    info.setdefault("fail", torch.zeros(u.num_envs, dtype=torch.bool, device=u.device))
    active = u.reward
    u.reward = module  # _get_obs_extra reads the stage module's extras; restored at once
    try:
        state = u._get_obs_state_dict(info)
    finally:
        u.reward = active
    return common.flatten_state_dict(state, use_torch=True, device=u.device)


@dataclass
class StagePolicy:
    """A trained PPO policy of one stage, with what it needs to run on another env of the task."""

    stage: str
    control_joint: str
    module: RewardModule
    """The stage's reward module: its extras feed the observation, its ``evaluate`` tells when the stage is done."""
    model: object
    """stable-baselines3 policy (``model.policy`` of the saved PPO)."""
    obs_mean: np.ndarray
    obs_var: np.ndarray
    clip_obs: float
    meta: dict
    _joints: tuple | None = field(default=None, init=False, repr=False)
    """(controller, joint indices, per-joint delta bounds), computed once per controller."""

    @classmethod
    def load(cls, task_dir: str | Path, stage: str, path: str | Path | None = None) -> StagePolicy:
        """Load ``policies/<stage>.zip`` (or ``path``) and its JSON record; :class:`StageError` when absent."""
        from stable_baselines3 import PPO  # noqa: PLC0415  (heavy; only needed when a policy runs)

        path = Path(path) if path is not None else policy_path(task_dir, stage)
        json_path = path.with_suffix(".json")
        meta = json.loads(json_path.read_text()) if json_path.is_file() else None
        if not path.is_file() or meta is None:
            raise StageError(f"no trained policy for stage {stage!r}: need {path} and {json_path} "
                             "(`gendex train` writes both)")
        if meta.get("format") != POLICY_FORMAT:
            raise PolicyError(f"{json_path}: policy format {meta.get('format')!r}, this GenDex reads {POLICY_FORMAT}")
        model = PPO.load(str(path), device="cpu")
        module = load_reward_module(stage_reward_path(task_dir, stage))
        norm = meta["obs_norm"]
        return cls(stage=stage, control_joint=meta["control_joint"], module=module, model=model,
                   obs_mean=np.asarray(norm["mean"], dtype=np.float32),
                   obs_var=np.asarray(norm["var"], dtype=np.float32),
                   clip_obs=float(norm["clip"]), meta=meta)

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
        """[N, F] normalized deltas in [-1, 1] for the stage's free joints (``info``: the stage module's
        ``evaluate`` of the current state, when the caller has it)."""
        obs = stage_observation(env, self.module, info).cpu().numpy()
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
