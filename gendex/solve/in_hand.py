"""Scripted in-hand baseline for RotateTennisBall: an open-loop finger gait that tries to roll the ball about world z.

The hand is palm up (keyframe ``palm_up``: fingers along world +x, thumb on the -y side) and the ball rests over
the knuckles. The index, middle and ring fingers curl deep, so that their tips land on the ball's near (wrist-side)
half, and sweep towards -y with their abduction joints J3: a push towards -y behind the centre is a torque about
+z. They then uncurl part way and swing back, like a hand turning a jar lid; the thumb rotates (THJ4) in step with
the sweep. Parameters were tuned for a few minutes on seeds 0-2 (measured: 54-124 degrees in 120 steps, but the
ball often rolls off near the end).

It drives an env made with ``control_mode="pd_joint_delta_pos"`` and ``control_joint="hand"``: each action moves
the controller's targets towards the gait's absolute joint targets, clipped to the per-step delta limit. It is a
baseline to beat, not a solution; ``benchmarks/rotate_ball.py`` measures it.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import gymnasium as gym
import numpy as np

from gendex_envs.agents.ur10e_shadow import KEYFRAME_QPOS_BY_NAME

log = logging.getLogger(__name__)


@dataclass
class FingerGaitSolver:
    """Open-loop periodic finger gait; ``act`` returns None after ``steps`` steps (default: the env's time limit
    ends the episode first).

    Args:
        period: control steps per gait cycle (push half + return half).
        sweep_rad: half-amplitude of the J3 abduction sweep of the index, middle and ring fingers.
        flex_push / flex_lift: J2 flexion while pushing / while swinging back; J1 flexes ``curl`` times as much.
        thumb_rad: half-amplitude of the thumb's THJ4 rotation, in step with the sweep.
        direction: +1 turns the ball counter-clockwise seen from above (the task's sense), -1 the other way.
    """

    steps: int = 10_000
    period: int = 16
    sweep_rad: float = 0.35
    flex_push: float = 1.57
    flex_lift: float = 0.8
    curl: float = 1.0
    thumb_rad: float = 0.3
    direction: float = 1.0
    name: str = "finger_gait"
    _base: dict[str, float] = field(default_factory=dict, repr=False)

    def reset(self, env: gym.Env, obs) -> None:
        ctrl = env.unwrapped.agent.controller
        if not ctrl.config.use_delta:
            raise ValueError("FingerGaitSolver drives control_mode='pd_joint_delta_pos'")
        self._names = ctrl.free_joint_names
        self._delta = env.unwrapped.agent.controller.config.upper  # per-step bound of each free joint
        self._base = dict(KEYFRAME_QPOS_BY_NAME[env.unwrapped.task_spec.robot.init_keyframe])
        self._t = 0

    def targets(self, t: int) -> dict[str, float]:
        """Absolute joint targets of the gait at control step ``t``."""
        phase = 2.0 * math.pi * (t % self.period) / self.period
        sweep = self.direction * math.sin(phase)  # -1 at the end of the push, +1 at the end of the return
        # curl onto the ball while the sweep pushes, uncurl part way while it swings back
        moving_forward = math.cos(phase) * self.direction < 0.0  # sweep decreasing: J3 rising, tips to -y
        flex = self.flex_push if moving_forward else self.flex_lift
        q = dict(self._base)
        # on the palm-up hand, increasing J3 moves the index/middle/ring tips towards -y (measured)
        for f in ("FF", "MF", "RF"):
            q[f"{f}J3"] = -self.sweep_rad * sweep
            q[f"{f}J2"] = flex
            q[f"{f}J1"] = self.curl * flex
        q["THJ4"] = self._base["THJ4"] + self.thumb_rad * sweep
        q["THJ1"] = 0.3 if moving_forward else 0.0
        return q

    def act(self, env: gym.Env, obs) -> np.ndarray | None:
        if self._t >= self.steps:
            return None
        ctrl = env.unwrapped.agent.controller
        current = ctrl.free_targets()[0].cpu().numpy()  # the controller adds deltas to these targets
        want = self.targets(self._t)
        goal = np.array([want.get(n, c) for n, c in zip(self._names, current, strict=True)], dtype=np.float32)
        self._t += 1
        return np.clip((goal - current) / np.asarray(self._delta, dtype=np.float32), -1.0, 1.0).astype(np.float32)
