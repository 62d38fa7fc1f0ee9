"""What a learner observes: the observation contract of GenDex datasets, and the wrapper that gives it in the env.

A dataset exported by ``gendex collect`` holds, per frame, the features below; :class:`LeRobotObservation` turns any
GenDex env made with ``gym.make`` into one whose observations are exactly those features, so a policy trained on the
data runs in the env unchanged:

``observation.state``
    the robot: every active joint's position, then every joint's velocity (``<joint>.pos``, ``<joint>.vel``);
``observation.environment_state``
    the world: for every task object, in the task's order, its position and orientation (``<object>.pos.x`` ..
    ``<object>.quat.w`` .. ``.quat.z``, wxyz), then for an articulated object each joint's position
    (``<object>.<joint>.qpos``); then the goal mark's position (``goal.pos.x`` ..) when the task has one. Clutter
    (``distractor: true``) is included: a policy must see what it has to avoid;
``observation.images.<camera>``
    RGB images of the env's sensor cameras, when the env renders them (``obs_mode="rgb"``).

The functions read the env's current state as ``[num_envs, D]`` tensors, so the same contract serves the batched
GPU backend.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import gymnasium as gym
import numpy as np
import torch

from gendex_envs.errors import GenDexError

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.task_env import TaskEnv

STATE = "observation.state"
ENVIRONMENT_STATE = "observation.environment_state"
IMAGES = "observation.images."
POSE_FIELDS = ("pos.x", "pos.y", "pos.z", "quat.w", "quat.x", "quat.y", "quat.z")
POSITION_SUFFIX, VELOCITY_SUFFIX = ".pos", ".vel"
"""How ``observation.state`` names a joint's position and velocity (``<joint>.pos``, ``<joint>.vel``)."""


def _task_env(env: gym.Env) -> TaskEnv:
    from gendex_envs.task_env import TaskEnv

    base = env.unwrapped
    if not isinstance(base, TaskEnv):
        raise GenDexError(f"{type(base).__name__} is not a GenDex TaskEnv; the observation contract is GenDex's")
    return base


def robot_state_names(env: gym.Env) -> list[str]:
    names = [j.name for j in _task_env(env).agent.robot.get_active_joints()]
    return [f"{n}{POSITION_SUFFIX}" for n in names] + [f"{n}{VELOCITY_SUFFIX}" for n in names]


def robot_state(env: gym.Env) -> torch.Tensor:
    """[N, 2 J] float32: the robot's joint positions, then velocities."""
    robot = _task_env(env).agent.robot
    return torch.cat([robot.get_qpos(), robot.get_qvel()], dim=-1).to(torch.float32)


def environment_state_names(env: gym.Env) -> list[str]:
    u = _task_env(env)
    names = []
    for obj in u.task_spec.objects:
        names += [f"{obj.name}.{f}" for f in POSE_FIELDS]
        if obj.name in u.articulations:
            names += [f"{obj.name}.{j.name}.qpos" for j in u.articulations[obj.name].get_active_joints()]
    if u.goal_site is not None:
        names += ["goal.pos.x", "goal.pos.y", "goal.pos.z"]
    return names


def environment_state(env: gym.Env) -> torch.Tensor:
    """[N, K] float32: the world as :func:`environment_state_names` names it."""
    u = _task_env(env)
    parts = []
    for obj in u.task_spec.objects:
        parts.append(u.objects[obj.name].pose.raw_pose)
        if obj.name in u.articulations:
            parts.append(u.articulations[obj.name].get_qpos())
    if u.goal_site is not None:
        parts.append(u.goal_site.pose.p)
    return torch.cat([p.to(torch.float32).reshape(u.num_envs, -1) for p in parts], dim=-1)


def flat_float_state(tree: dict) -> torch.Tensor | None:
    """A state observation dict flattened as ManiSkill's ``common.flatten_state_dict`` flattens it ([N, D]: the
    leaves in order, a [N] leaf as [N, 1]), by one ``torch.cat`` instead of an ``hstack`` per nested dict (a third of
    the cost, the same tensor); None when a leaf is not a float32 tensor of one or two dimensions, or there is none
    (ManiSkill's flatten handles those)."""
    leaves: list[torch.Tensor] = []

    def collect(node: dict) -> bool:
        for value in node.values():
            if isinstance(value, dict):
                if not collect(value):
                    return False
            elif isinstance(value, torch.Tensor) and value.dtype == torch.float32 and value.dim() in (1, 2):
                leaves.append(value[:, None] if value.dim() == 1 else value)
            else:
                return False
        return True

    return torch.cat(leaves, dim=1) if collect(tree) and leaves else None


def feature_names(env: gym.Env) -> dict[str, list[str]]:
    """The named vector features of :class:`LeRobotObservation` (as a dataset's ``meta/info.json`` names them)."""
    return {STATE: robot_state_names(env), ENVIRONMENT_STATE: environment_state_names(env)}


class LeRobotObservation(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """Observations as GenDex datasets store them: ``{"observation.state": [S], "observation.environment_state":
    [K], "observation.images.<camera>": [H, W, 3] uint8, ...}`` (numpy, one env: wrap a ``gym.make`` env with the
    default numpy API). Images come from the wrapped env's sensor data, so make it with ``obs_mode="rgb"`` to have
    them."""

    def __init__(self, env: gym.Env):
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ObservationWrapper.__init__(self, env)
        u = _task_env(env)
        if u.num_envs != 1 or not getattr(env, "numpy", True):
            raise GenDexError("LeRobotObservation wraps one env with the numpy API (gym.make(id) with num_envs=1)")
        names = feature_names(env)
        spaces = {k: gym.spaces.Box(-np.inf, np.inf, (len(v),), np.float32) for k, v in names.items()}
        space = env.observation_space
        sensors = space["sensor_data"] if isinstance(space, gym.spaces.Dict) and "sensor_data" in space.spaces \
            else {}
        self.cameras = tuple(c for c in sensors if "rgb" in sensors[c].spaces)
        for cam in self.cameras:
            space = env.observation_space["sensor_data"][cam]["rgb"]
            spaces[IMAGES + cam] = gym.spaces.Box(0, 255, space.shape[-3:], np.uint8)
        self.observation_space = gym.spaces.Dict(spaces)

    def observation(self, observation):
        out = {STATE: robot_state(self.env)[0].cpu().numpy(),
               ENVIRONMENT_STATE: environment_state(self.env)[0].cpu().numpy()}
        for cam in self.cameras:
            out[IMAGES + cam] = np.asarray(observation["sensor_data"][cam]["rgb"], dtype=np.uint8)
        return out


__all__ = ["ENVIRONMENT_STATE", "IMAGES", "POSITION_SUFFIX", "STATE", "VELOCITY_SUFFIX", "LeRobotObservation",
           "environment_state", "flat_float_state", "environment_state_names", "feature_names", "robot_state",
           "robot_state_names"]
