"""``Episode``: one rollout of a GenDex task, as the collector records it and the exporters write it.

Arrays are per control step. ``T`` is the number of actions; observations and env states have ``T + 1`` rows
(the state after reset, then after each action), as in ManiSkill's trajectory format.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gendex_envs.errors import GenDexError


class EpisodeError(GenDexError, ValueError):
    """An episode's arrays are inconsistent (lengths, dtypes) or it cannot be exported as asked."""


@dataclass
class Episode:
    """One rollout (num_envs = 1 rows, no batch dimension)."""

    task_id: str
    """Gymnasium id, e.g. ``GenDex/PutAppleBowl-v0``."""
    instruction: str
    """The task's natural-language instruction (LeRobot's ``task``)."""
    seed: int
    """Reset seed: ``env.reset(seed=seed)`` reproduces the initial state."""
    control_mode: str
    """``pd_joint_pos`` or ``pd_joint_delta_pos``."""
    control_joint: str
    """Joint group the actions drive (see ``docs/robot.md``)."""
    fps: int
    """Control frequency (Hz)."""
    state: np.ndarray
    """[T + 1, S] float32 robot state (joint positions then velocities) after reset and after each action."""
    action: np.ndarray
    """[T, A] float32 actions as given to ``env.step``."""
    reward: np.ndarray
    """[T] float32 dense reward."""
    success: np.ndarray
    """[T] bool: the task's ``evaluate()['success']`` after each action."""
    fail: np.ndarray
    """[T] bool."""
    env_states: np.ndarray
    """[T + 1, E] float32 flattened ``env.get_state()`` (for exact replay)."""
    images: dict[str, np.ndarray] = field(default_factory=dict)
    """camera name -> [T + 1, H, W, 3] uint8 RGB (optional)."""
    environment_state: np.ndarray | None = None
    """[T + 1, K] float32 the world as a learner observes it (:func:`gendex_envs.observation.environment_state`:
    object poses, articulation joint positions, the goal mark), after reset and after each action; None when not
    recorded."""
    environment_state_names: tuple[str, ...] = ()
    """The K names of :attr:`environment_state`'s columns."""
    reset_kwargs: dict = field(default_factory=dict)
    """Keyword arguments of the reset that started the episode (``{"seed": seed}`` at least)."""
    info: dict = field(default_factory=dict)
    """Anything else worth keeping (solver name, env steps used, ...), JSON-able."""
    appearance: dict = field(default_factory=dict)
    """What the episode looked like (``env.unwrapped.appearance``: the surface, floor, background, lights, camera
    jitter and structure paints its seed drew from the task's ``scene``), JSON-able; empty for a task without one."""

    def __post_init__(self):
        t = len(self.action)
        checks = {"state": (self.state, t + 1), "reward": (self.reward, t), "success": (self.success, t),
                  "fail": (self.fail, t), "env_states": (self.env_states, t + 1)}
        checks.update({f"images[{k}]": (v, t + 1) for k, v in self.images.items()})
        if self.environment_state is not None:
            checks["environment_state"] = (self.environment_state, t + 1)
            if np.asarray(self.environment_state).shape[1:] != (len(self.environment_state_names),):
                raise EpisodeError(f"episode of {self.task_id} (seed {self.seed}): environment_state has "
                                   f"{np.asarray(self.environment_state).shape[1:]} columns and "
                                   f"{len(self.environment_state_names)} names; they must match")
        bad = {k: len(v) for k, (v, n) in checks.items() if len(v) != n}
        if t == 0 or bad:
            raise EpisodeError(f"episode of {self.task_id} (seed {self.seed}) has {t} actions; rows expected: "
                               f"T+1 for state/env_states/images, T for reward/success/fail; got {bad}")

    @property
    def length(self) -> int:
        """Number of actions T."""
        return len(self.action)

    @property
    def succeeded(self) -> bool:
        """True when the task reported success at the last step."""
        return bool(self.success[-1])
