"""PPO hyperparameter presets for stage training.

``paper`` is the seed paper's table (1024 parallel envs, lr 3e-4, γ 0.998, GAE λ 0.95, 4 epochs, clip 0.2, entropy
0.01, value 0.75, MLP [1024, 1024, 512] ReLU), meant for ManiSkill's GPU backend. ``cpu`` keeps the paper's
update rule but is sized for a 2-core machine: two env processes, a [256, 256] MLP and short rollouts, so a stage
learns within a few hundred thousand steps; γ is lowered to 0.99 because CPU stages are 20–200 steps long.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from gendex_envs.errors import GenDexError, suggest


class TrainingError(GenDexError, ValueError):
    """A training request is invalid (unknown preset, too few steps, a stage that cannot be trained)."""


@dataclass(frozen=True)
class PPOPreset:
    """Hyperparameters of one PPO run (stable-baselines3 names where they exist)."""

    name: str
    n_envs: int
    """Parallel envs: processes on the CPU backend, batched sub-scenes on the GPU backend."""
    n_steps: int
    """Rollout length per env between updates."""
    batch_size: int
    n_epochs: int
    learning_rate: float
    gamma: float
    gae_lambda: float
    clip_range: float
    ent_coef: float
    vf_coef: float
    max_grad_norm: float
    net_arch: tuple[int, ...]
    log_std_init: float
    """Initial log standard deviation of the Gaussian policy (actions are normalized to [-1, 1])."""
    gpu_backend: bool = False
    """Run the envs on ManiSkill's GPU backend (one process, ``n_envs`` sub-scenes)."""

    def with_overrides(self, **changes) -> PPOPreset:
        unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(self)})
        if unknown:
            allowed = [f.name for f in dataclasses.fields(self)]
            raise TrainingError(f"unknown PPO settings {unknown}; allowed: {allowed}")
        return dataclasses.replace(self, **{k: v for k, v in changes.items() if v is not None})

    def ppo_kwargs(self) -> dict:
        """Keyword arguments of ``stable_baselines3.PPO`` (policy network included)."""
        import torch

        return dict(n_steps=self.n_steps, batch_size=self.batch_size, n_epochs=self.n_epochs,
                    learning_rate=self.learning_rate, gamma=self.gamma, gae_lambda=self.gae_lambda,
                    clip_range=self.clip_range, ent_coef=self.ent_coef, vf_coef=self.vf_coef,
                    max_grad_norm=self.max_grad_norm,
                    policy_kwargs=dict(net_arch=list(self.net_arch), activation_fn=torch.nn.ReLU,
                                       log_std_init=self.log_std_init))


PRESETS: dict[str, PPOPreset] = {
    "paper": PPOPreset(name="paper", n_envs=1024, n_steps=16, batch_size=4096, n_epochs=4, learning_rate=3e-4,
                       gamma=0.998, gae_lambda=0.95, clip_range=0.2, ent_coef=0.01, vf_coef=0.75, max_grad_norm=0.5,
                       net_arch=(1024, 1024, 512), log_std_init=0.0, gpu_backend=True),
    "cpu": PPOPreset(name="cpu", n_envs=2, n_steps=512, batch_size=128, n_epochs=8, learning_rate=3e-4, gamma=0.99,
                     gae_lambda=0.95, clip_range=0.2, ent_coef=0.0, vf_coef=0.75, max_grad_norm=0.5,
                     net_arch=(256, 256), log_std_init=-0.5),
}
"""Preset name -> hyperparameters. ``paper``'s rollout (16 steps × 1024 envs) and minibatch are not in the paper's
table; they follow ManiSkill's PPO baseline."""


def parse_overrides(items: list[str]) -> dict:
    """``["log_std_init=-1.5", "net_arch=256,256"]`` -> preset settings typed like :class:`PPOPreset`'s fields
    (:class:`TrainingError` for a malformed item or an unknown setting)."""
    fields = {f.name: getattr(PRESETS["cpu"], f.name) for f in dataclasses.fields(PPOPreset)}
    out: dict = {}
    for item in items:
        key, sep, raw = item.partition("=")
        key, raw = key.strip(), raw.strip()
        if not sep or not raw:
            raise TrainingError(f"PPO setting {item!r}: write KEY=VALUE")
        if key not in fields or key == "name":
            raise TrainingError(f"unknown PPO setting {key!r}; settings: {sorted(set(fields) - {'name'})}."
                                f"{suggest(key, fields)}")
        kind = type(fields[key])
        try:
            if kind is bool:
                if raw.lower() not in ("true", "false", "1", "0"):
                    raise ValueError(raw)
                out[key] = raw.lower() in ("true", "1")
            elif kind is tuple:
                out[key] = tuple(int(x) for x in raw.split(","))
            else:
                out[key] = kind(raw)
        except ValueError:
            raise TrainingError(f"PPO setting {key}: {raw!r} is not a {kind.__name__}") from None
    return out


def get_preset(name: str) -> PPOPreset:
    try:
        return PRESETS[name]
    except KeyError:
        raise TrainingError(f"unknown preset {name!r}; presets: {sorted(PRESETS)}.{suggest(name, PRESETS)}") from None
