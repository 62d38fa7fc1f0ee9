"""``TaskEnv``: the one ManiSkill environment class that builds any GenDex task from its version folder.

A task is data (the spec, :mod:`gendex_envs.spec`) plus a small reward module (:mod:`gendex_envs.reward_module`),
owned by a :class:`~gendex_envs.task_version.TaskVersion`. There are no per-task env classes. Success is decided by
the spec's conditions (:mod:`gendex_envs.success`); the reward module adds ``fail``, diagnostics, the dense reward
and task observations.

``TaskEnv`` is ManiSkill's torch-batched env: every quantity is a tensor ``[num_envs, ...]`` on ``env.device``, also
with one env. ``gym.make`` wraps it into the plain Gymnasium API (numpy, no batch dimension) for one CPU env; the
wrapped env's ``env.unwrapped`` is always this class.

Members that reward code may use (all batched over ``num_envs``, tensors on ``env.device``):

* ``env.agent`` — :class:`~gendex_envs.agents.ur10e_shadow.UR10eShadowHand` (``tip_poses``, ``palm_link``,
  ``get_fsr_*``, ``get_hand_group_obj_mean_force``, ...).
* ``env.obj(name)`` / ``env.objects`` — ManiSkill ``Actor`` or ``Articulation`` per spec object;
  ``env.articulations`` — the articulated ones.
* ``env.obj_pose(name)``, ``env.palm_pose`` (``Pose``: ``p`` [N, 3], ``q`` [N, 4]) and ``env.tip_positions``
  [N, 5, 3] — the same as reading the entities, but read once per step and shared by observation, evaluation and
  reward (prefer them in reward code).
* ``env.handle_link(name)``, ``env.handle_pos(name)`` [N, 3] — the link and world grip point of an articulated
  object's handle; ``env.joint_qpos(name)`` [N], ``env.open_qpos(name)``, ``env.closed_qpos(name)`` (floats),
  ``env.joint_open_fraction(name)`` [N].
* ``env.goal_pos`` [N, 3] (when the task has a goal), ``env.init_obj_pos(name)`` [N, 3] and
  ``env.init_obj_quat(name)`` [N, 4] (pose at the start of the task episode).
* ``env.hand_forces(name)`` [N, 6] — mean contact force of each hand group (th, ff, mf, rf, lf, palm) on an object.
* ``env.task_spec`` — the loaded :class:`~gendex_envs.spec.TaskSpec` (``env.spec`` is Gymnasium's EnvSpec).
* ``env.spec_success()`` [N] bool — the task's success conditions hold now (no ``hold_steps``, no ``fail``).
* ``env.table_height`` (0.0: the table top is the plane z = 0).

``env.appearance`` (not for reward code): what each env's episode looks like, drawn from a ``scene`` section
(:mod:`gendex_envs.scene`); ``scene=`` overrides the task's scene, ``randomize_appearance=False`` keeps it nominal.
"""

from __future__ import annotations

import logging
import math
import os
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import sapien
import torch
from mani_skill.envs.sapien_env import BaseEnv
from mani_skill.sensors.camera import CameraConfig
from mani_skill.utils import common
from mani_skill.utils.structs import Actor, Articulation, Link, Pose
from mani_skill.utils.structs.types import DefaultMaterialsConfig, SceneConfig, SimConfig

from gendex_envs import guard
from gendex_envs.agents.ur10e_shadow import CONTROL_JOINT_GROUPS, KEYFRAME_QPOS_BY_NAME, UR10eShadowHand
from gendex_envs.assets.catalog import AssetRecord, get_asset, lowest_point_z
from gendex_envs.assets.manifest import JointEntry
from gendex_envs.cameras import VIEW_CAMERAS, check_sensors, human_camera_configs, sensor_configs
from gendex_envs.detents import Detents
from gendex_envs.errors import ControlModeError, RenderModeError, StageError, TaskSpecError, suggest
from gendex_envs.geometry import quat_mul, transform_points, yaw_quat
from gendex_envs.heap import freeze_long_lived
from gendex_envs.observation import flat_float_state
from gendex_envs.physx import read_pose
from gendex_envs.placement import Footprint, Item, place, starts_in
from gendex_envs.reward_checks import RESERVED_OBS_KEYS, check_obs_extra, check_reward
from gendex_envs.reward_module import RewardModule, load_reward_module
from gendex_envs.reward_view import reward_info
from gendex_envs.scene import Scenery, build_table_and_ground
from gendex_envs.spec import StageSpec, TaskSpec, resolve_stage
from gendex_envs.start_states import StartStates
from gendex_envs.success import Judge, SuccessTracker, conditions_hold
from gendex_envs.task_version import TaskVersion
from gendex_envs.wiping import Wipes

log = logging.getLogger(__name__)

SIM_FREQ = 120
CONTAINER_INSIDE_SHARE = 0.8
"""Share of a rigid container's half footprint its ``inside`` condition checks (:meth:`TaskEnv.container_extent`)."""
CONTROL_FREQ = 20
DEFAULT_REWARD_MODULE = Path(__file__).resolve().parent / "preview_rewards.py"
"""Reward module of an in-memory spec: no failure, reward = reaching the first stage's target."""

RENDER_MODES = (None, "rgb_array", "sensors", "all", "human")


def _check_render_mode(mode: str | None) -> None:
    if mode not in RENDER_MODES:
        raise RenderModeError(f"render_mode={mode!r} is not a mode; allowed: {list(RENDER_MODES)}")
    if mode == "human" and sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                                     or os.environ.get("WAYLAND_DISPLAY")):
        raise RenderModeError("render_mode='human' opens a viewer window, but this machine has no display (DISPLAY "
                              "and WAYLAND_DISPLAY are unset); use render_mode='rgb_array' for frames as arrays "
                              "(env.render()), or run under a display or Xvfb")


class TaskEnv(BaseEnv):
    """Generic GenDex task: ShadowHand on UR10e at a table, objects and reward from a task version.

    Args:
        task: the :class:`~gendex_envs.task_version.TaskVersion` (or its folder); or ``task_spec`` for a spec held
            in memory (scene previews, refinement), which gets a default reward module.
        control_joint: joint group actions drive (default: the stage's when ``stage`` is given, else ``both``: the
            whole arm and hand, as ``gendex collect`` records).
        stage: a sub-stage (name or index) to run on its own: its ``control_joint``, its reward module, its success
            conditions and start states; episodes are truncated at its ``horizon``. Stages after the first need
            start states.
        start_states: a :class:`~gendex_envs.start_states.StartStates` (or its ``.npz`` path) every reset starts
            from; default for ``stage`` > 0: the task version's.
        gym_api: how ``gym.make`` wraps the env: the plain numpy Gymnasium API (default for one CPU env) or the
            torch-batched one (:class:`~gendex_envs.wrappers.GymApi`).
        trust_remote_code: run the task's reward code without the runtime guard's audit hook even though its folder
            is not the repository's (:mod:`gendex_envs.guard`; like ``transformers``' flag of the same name). The
            restricted builtins and the read-only view apply either way.
        scene: a scene style name or ``scene`` section (mapping) to use instead of the task's own; None: the task's.
        randomize_appearance: draw each episode's look from its seed (default); False: the scene's nominal look.
        sensors: the sensor cameras to declare (:data:`~gendex_envs.cameras.SENSOR_CAMERAS`); None: all. With
            ``obs_mode="rgb"`` every declared camera renders at every step, so name only those you read.
    """

    SUPPORTED_ROBOTS = [UR10eShadowHand.uid]
    agent: UR10eShadowHand

    def __init__(self, *args, task: TaskVersion | str | Path | None = None, task_spec: TaskSpec | None = None,
                 control_joint: str | None = None, stage: str | int | None = None,
                 start_states: StartStates | str | Path | None = None, view_resolution: int = 512,
                 sensor_resolution: int = 128, gym_api: bool | None = None, trust_remote_code: bool = False,
                 scene=None, randomize_appearance: bool = True, sensors: tuple[str, ...] | None = None, **kwargs):
        if (task is None) == (task_spec is None):
            raise TaskSpecError("TaskEnv needs exactly one of task (a task version or its folder) or task_spec "
                                "(a spec held in memory)")
        _check_render_mode(kwargs.get("render_mode"))
        self.task: TaskVersion | None = (task if isinstance(task, TaskVersion) or task is None
                                         else TaskVersion.at(task))
        """The task version this env runs; None for an in-memory spec."""
        self.task_spec: TaskSpec = self.task.spec if self.task is not None else task_spec
        self.scenery = Scenery.of_task(self.task_spec.scene, scene, randomize_appearance)
        """The task's room, lights, structures and appearance draws (:mod:`gendex_envs.scene`); None: plain look."""
        if trust_remote_code and self.task is not None:
            guard.trust(self.task.root)
        self.stage_index: int | None = None
        """Index of the stage this env runs on its own (``stage=``), else None (the whole task)."""
        self.stage_spec: StageSpec | None = None
        if stage is not None:
            self.stage_index, self.stage_spec = resolve_stage(self.task_spec, stage)
        if self.task is not None:
            self.judge: Judge = self.task.judge(self.stage_spec.name if self.stage_spec else None)
        else:
            module = load_reward_module(DEFAULT_REWARD_MODULE)
            self.judge = (Judge.of_stage(self.task_spec, self.stage_spec, module) if self.stage_spec
                          else Judge.of_task(self.task_spec, module))
        """Decides ``success`` of this env's episodes (the task's, or the stage's) and holds its reward module."""
        self.start_states: StartStates | None = self._load_start_states(start_states)
        """States every reset starts from (stage envs after the first), else None."""
        if control_joint is None:
            control_joint = self.stage_spec.control_joint if self.stage_spec is not None else "both"
        if control_joint not in CONTROL_JOINT_GROUPS:
            raise ControlModeError(f"control_joint={control_joint!r} is not a mode; allowed: "
                                   f"{sorted(CONTROL_JOINT_GROUPS)}.{suggest(control_joint, CONTROL_JOINT_GROUPS)}")
        self.control_joint = control_joint
        """Joint group actions drive (default: ``both`` for the task, the stage's group for a stage env)."""
        self.gym_api = gym_api
        """Requested API of ``gym.make``'s wrapper (None: numpy for one CPU env, else batched torch)."""
        self.horizon: int | None = self.stage_spec.horizon if self.stage_spec is not None else None
        """Steps after which an episode is truncated whatever the time limit (a stage env's horizon), else None."""
        self.view_resolution = view_resolution
        self.sensor_resolution = sensor_resolution
        self.sensors = check_sensors(sensors)
        """The sensor cameras the env declares (None: all of :data:`~gendex_envs.cameras.SENSOR_CAMERAS`)."""
        self.table_height = 0.0
        self.objects: dict[str, Actor | Articulation] = {}
        self._frame: dict | None = None
        self.articulations: dict[str, Articulation] = {}
        self._records: dict[str, AssetRecord] = {o.name: get_asset(o.asset) for o in self.task_spec.objects}
        self._container_extent: dict[str, tuple[float, float]] = {
            o.name: (CONTAINER_INSIDE_SHARE * min(self._records[o.name].size_m[:2]) / 2 * o.scale,
                     self._records[o.name].bbox_max_m[2] * o.scale) for o in self.task_spec.objects}
        kwargs.setdefault("robot_uids", UR10eShadowHand.uid)
        freeze_long_lived()  # ManiSkill's full collection at each scene rebuild then walks only what came after
        super().__init__(*args, **kwargs)

    @property
    def reward(self) -> RewardModule:
        """The reward module of this env (the stage's own for a stage env with one, else the task's)."""
        return self.judge.module

    def _load_start_states(self, given: StartStates | str | Path | None) -> StartStates | None:
        if given is not None:
            states = given if isinstance(given, StartStates) else StartStates.load(given)
        elif self.stage_index:
            states = self.task.start_states(self.stage_spec.name) if self.task is not None else None
            if states is None:
                where = self.task.env_id if self.task is not None else "the in-memory spec"
                prev = self.task_spec.stages[self.stage_index - 1].name
                raise StageError(f"stage {self.stage_spec.name!r} starts where stage {prev!r} succeeded, but "
                                 f"{where} has no start states for it; `gendex train` collects them into its run "
                                 "folder (`gendex promote` makes them part of a new version), or pass start_states=")
        else:
            return None
        missing = sorted({o.name for o in self.task_spec.objects} - set(states.obj_reset_pos))
        if missing:
            raise StageError(f"start states of stage {states.stage!r} lack objects {missing} of task "
                             f"{self.task_spec.name!r}")
        return states

    # ------------------------------------------------------------------ configuration
    @property
    def _default_sim_config(self) -> SimConfig:
        return SimConfig(
            sim_freq=SIM_FREQ,
            control_freq=CONTROL_FREQ,
            scene_config=SceneConfig(solver_position_iterations=15, solver_velocity_iterations=1,
                                     contact_offset=0.01, enable_tgs=True, enable_enhanced_determinism=True),
            default_materials_config=DefaultMaterialsConfig(static_friction=1.0, dynamic_friction=0.8),
        )

    @property
    def _default_sensor_configs(self) -> list[CameraConfig]:
        return sensor_configs(self.sensor_resolution, self.agent.palm_link, self.sensors)

    @property
    def _default_human_render_camera_configs(self) -> list[CameraConfig]:
        return human_camera_configs(self.view_resolution)

    # ------------------------------------------------------------------ loading
    def _load_agent(self, options: dict, initial_agent_poses=None, build_separate: bool = False):
        robot = self.task_spec.robot
        yaw = math.radians(robot.base_yaw_deg)
        pose = sapien.Pose(p=list(robot.base_pos_m), q=[math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])
        self.agent = UR10eShadowHand(self.scene, self._control_freq, self._control_mode, initial_pose=pose,
                                     build_separate=build_separate, control_joint=self.control_joint)

    def _load_scene(self, options: dict):
        self.table, self.ground = build_table_and_ground(self.scene, self.task_spec.table, self.scenery is None)

        self.objects.clear()
        self.articulations.clear()
        self.__dict__.pop("_handle_frames", None)  # links of the scene a reconfiguration replaced
        self._art_init_qpos: dict[str, torch.Tensor] = {}
        self._init_pose: dict[str, tuple[torch.Tensor, torch.Tensor]] = {}
        self._layout: list[Item] = []
        for obj in self.task_spec.objects:
            rec = self._records[obj.name]
            p, q = self._spec_pose(obj)
            entity = rec.build(self.scene, obj.name, obj.scale, obj.rgba, obj.fixed,
                               sapien.Pose(p=p.tolist(), q=q.tolist()))
            self.objects[obj.name] = entity
            if rec.articulated:
                self.articulations[obj.name] = entity
                self._art_init_qpos[obj.name] = self._initial_joint_state(obj.name, rec, entity)
            self._init_pose[obj.name] = (torch.tensor(p, dtype=torch.float32, device=self.device),
                                         torch.tensor(q, dtype=torch.float32, device=self.device))
            self._layout.append(Item(obj.name, (float(p[0]), float(p[1])), obj.randomize.xy_m,
                                     math.radians(obj.randomize.yaw_deg), self._footprint(obj, q), obj.fixed,
                                     starts_in(obj, self.task_spec.objects, self._records)))
        with torch.device(self.device):
            self._obj_reset_pos = {n: torch.zeros(self.num_envs, 3) for n in self.objects}
            self._obj_reset_quat = {n: torch.zeros(self.num_envs, 4) for n in self.objects}
        self.success_tracker = SuccessTracker(self.task_spec.success, self.num_envs, self.device)
        self.detents, self.wipes = Detents(self), Wipes(self)
        self.goal_site = None
        if self.task_spec.goal is not None:
            gb = self.scene.create_actor_builder()
            gb.add_sphere_visual(radius=self.task_spec.goal.radius_m,
                                 material=sapien.render.RenderMaterial(base_color=[0.1, 0.9, 0.2, 0.5]))
            gb.initial_pose = sapien.Pose(p=list(self.task_spec.goal.pos_m))
            self.goal_site = gb.build_kinematic("goal_site")
            self._hidden_objects.append(self.goal_site)
        if self.scenery is not None:
            self.scenery.build(self, self._layout)

    def _load_lighting(self, options: dict):
        if self.scenery is None:
            return super()._load_lighting(options)
        self.scenery.load_lighting(self)

    @property
    def appearance(self) -> list[dict]:
        """[num_envs] what each env's current episode looks like (JSON-able; ``{}`` for a task without a scene)."""
        return self.scenery.appearance(self.num_envs) if self.scenery else [{} for _ in range(self.num_envs)]

    def _spec_pose(self, obj) -> tuple[np.ndarray, np.ndarray]:
        """World position (origin z lifted so the lowest point sits ``pos_m[2]`` above the table) and quaternion."""
        rec = self._records[obj.name]
        q = np.asarray(obj.quat_wxyz, dtype=np.float64)
        x, y, clearance = obj.pos_m
        z = self.table_height + clearance - lowest_point_z(rec, obj.scale, q)
        return np.array([x, y, z]), q

    def _footprint(self, obj, q: np.ndarray) -> Footprint:
        """The table rectangle object ``obj`` covers at orientation ``q``: its box's corners turned, seen from above."""
        rec = self._records[obj.name]
        lo, hi = np.asarray(rec.bbox_min_m) * obj.scale, np.asarray(rec.bbox_max_m) * obj.scale
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        xy = (corners @ sapien.Pose(q=q.tolist()).to_transformation_matrix()[:3, :3].T)[:, :2]
        a, b = xy.min(axis=0), xy.max(axis=0)
        return Footprint(offset=(float(a[0] + b[0]) / 2, float(a[1] + b[1]) / 2),
                         half=(float(b[0] - a[0]) / 2, float(b[1] - a[1]) / 2))

    def _initial_joint_state(self, name: str, rec: AssetRecord, art: Articulation) -> torch.Tensor:
        """[dof] joint positions at reset: the spec's joint_state, else the joint's closed value, else its lower
        limit."""
        where = self.task.files.spec if self.task is not None else "<in-memory spec>"
        names = [j.name for j in art.get_active_joints()]
        lower = art.get_qlimits()[0, :, 0].cpu()
        spec_state = self.task_spec.object(name).joint_state
        for joint, value in spec_state.items():
            if joint not in names:
                raise TaskSpecError(f"{where}: objects[{name}].joint_state has joint {joint!r}, which asset "
                                    f"{rec.id!r} lacks; joints: {names}.{suggest(joint, names)}")
            lo, hi = art.get_qlimits()[0, names.index(joint)].tolist()
            if not lo - 1e-6 <= value <= hi + 1e-6:
                raise TaskSpecError(f"{where}: objects[{name}].joint_state.{joint}={value} is outside the joint "
                                    f"limits [{lo:.4f}, {hi:.4f}]")
        closed = {j.name: j.closed_qpos for j in rec.joints}
        return torch.tensor([spec_state.get(n, closed.get(n, float(lower[i]))) for i, n in enumerate(names)],
                            dtype=torch.float32, device=self.device)

    # ------------------------------------------------------------------ episodes
    def reset(self, seed: int | list[int] | None = None, options: dict | None = None):
        # Gymnasium's RNG (env.np_random) follows the reset seed. ManiSkill draws an unseeded episode from torch's
        # global RNG; GenDex derives it from env.np_random instead, so that reset(seed=s) followed by reset() is
        # reproducible, as the Gymnasium API promises.
        if seed is None or isinstance(seed, int):
            gym.Env.reset(self, seed=seed)
        if seed is None:
            seeds = self.np_random.integers(2**31, size=self.num_envs).tolist()
            seed = seeds[0] if self.num_envs == 1 else seeds
        obs, info = super().reset(seed=seed, options=options)
        # BaseEnv.__init__'s first reset (before _init_raw_state, which set_state needs) keeps the task's own state
        if self.start_states is None or not hasattr(self, "_init_raw_state"):
            return obs, info
        env_idx = (options or {}).get("env_idx")
        env_idx = torch.arange(self.num_envs, device=self.device) if env_idx is None else \
            torch.as_tensor(env_idx, device=self.device)
        self._apply_start_states(env_idx)
        info.update(self.get_info())
        return self.get_obs(info), info

    def _apply_start_states(self, env_idx: torch.Tensor) -> None:
        """Restore one saved start state (drawn with ``env.np_random``) into each env of ``env_idx``."""
        s = self.start_states
        s.check_fits(self.get_state().shape[-1], self.objects)  # states of another layout: a typed error, not SAPIEN's
        rows = self.np_random.integers(len(s), size=len(env_idx))
        state = torch.as_tensor(s.state[rows], dtype=torch.float32, device=self.device)
        self.set_state(state, env_idx)
        for name in self.objects:
            self._obj_reset_pos[name][env_idx] = torch.as_tensor(s.obj_reset_pos[name][rows], device=self.device)
            if name in s.obj_reset_quat:
                self._obj_reset_quat[name][env_idx] = torch.as_tensor(s.obj_reset_quat[name][rows],
                                                                      device=self.device)
        self.agent.contacts.invalidate()

    def set_state_dict(self, state: dict, env_idx: torch.Tensor | None = None):
        # ManiSkill restores actors and articulations only; frozen-joint and delta targets live in the controller
        super().set_state_dict(state, env_idx)
        if "controller" in state:
            self.agent.set_controller_state(state["controller"])
        self.agent.contacts.invalidate()

    def set_state(self, state: torch.Tensor, env_idx: torch.Tensor | None = None):
        """Restore a flat state from :meth:`get_state`, controller targets included (ManiSkill drops them)."""
        state = torch.as_tensor(state, device=self.device)
        # ManiSkill's set_state indexes _init_raw_state["actors"], which it leaves out of a scene without dynamic
        # actors (OpenCabinet: one fixed articulation), so the state dict is rebuilt here with the same layout
        actors = self._init_raw_state.get("actors", {})
        arts = self._init_raw_state.get("articulations", {})
        sim, start = {"actors": {}, "articulations": {}}, 0
        for name in actors:
            sim["actors"][name], start = state[:, start:start + 13], start + 13
        for name, raw in arts.items():
            sim["articulations"][name], start = state[:, start:start + raw.shape[-1]], start + raw.shape[-1]
        self.set_state_dict(sim, env_idx)
        sim_dim = start
        tail = state[:, sim_dim:]
        target = self.agent.controller.target_qpos
        if tail.shape[-1] == target.shape[-1]:
            if env_idx is not None and len(tail) != len(target):
                full = target
                full[env_idx] = tail
                tail = full
            self.agent.set_controller_state({"target_qpos": tail.clone()})
        elif tail.shape[-1] != 0:
            raise TaskSpecError(f"state has {tail.shape[-1]} values after the simulation state; expected 0 or "
                                f"{target.shape[-1]} controller targets")

    def _before_control_step(self):
        self.detents.update()  # springs pull buttons and switches to their nearest rest; threads hold caps

    def _after_simulation_step(self):
        self.agent.contacts.invalidate()

    def _after_control_step(self):
        self._frame = {}  # the state is frozen until step() ends: observation, evaluation, reward share reads
        self.wipes.update()  # marks a pressed sponge passed over this step

    def step(self, action):
        try:
            obs, reward, terminated, truncated, info = super().step(action)
        finally:
            self._frame = None
        if self.horizon is not None:  # a stage env's episode lasts the stage's horizon
            truncated = truncated | (self.elapsed_steps >= self.horizon)
        return obs, reward, terminated, truncated, info

    def _cached(self, key, compute):
        """Memoise ``compute()`` for the rest of the current step (no caching outside ``step``)."""
        if self._frame is None:
            return compute()
        return self._frame[key] if key in self._frame else self._frame.setdefault(key, compute())

    def _initialize_episode(self, env_idx: torch.Tensor, options: dict):
        self.agent.contacts.invalidate()
        with torch.device(self.device):
            b = len(env_idx)
            keyframe = KEYFRAME_QPOS_BY_NAME[self.task_spec.robot.init_keyframe]
            qpos = torch.as_tensor(self.agent.qpos_from_names(keyframe))
            self.agent.robot.set_qpos(qpos.expand(b, -1).clone())
            self.agent.robot.set_qvel(torch.zeros(b, qpos.shape[0]))
            table = self.task_spec.table
            noise = place(self._layout, b, (table.size_m[0] / 2, table.size_m[1] / 2), self.device)
            for obj in self.task_spec.objects:
                p0, q0 = self._init_pose[obj.name]
                p = p0.expand(b, 3).clone()
                q = q0.expand(b, 4).clone()
                dxy, dyaw = noise[obj.name]
                p[:, :2] += dxy
                if obj.randomize.yaw_deg > 0:
                    q = quat_mul(yaw_quat(dyaw), q)
                entity = self.objects[obj.name]
                entity.set_pose(Pose.create_from_pq(p, q))
                if obj.name in self.articulations:
                    state = self._art_init_qpos[obj.name]
                    self.articulations[obj.name].set_qpos(state.expand(b, -1).clone())
                    self.articulations[obj.name].set_qvel(torch.zeros(b, state.shape[0]))
                elif not obj.fixed:
                    entity.set_linear_velocity(torch.zeros(b, 3))
                    entity.set_angular_velocity(torch.zeros(b, 3))
            for name, entity in self.objects.items():
                self._obj_reset_pos[name][env_idx] = entity.pose.p[env_idx]
                self._obj_reset_quat[name][env_idx] = entity.pose.q[env_idx]
            self.success_tracker.reset(env_idx)
            self.wipes.reset(env_idx)
        if self.scenery is not None:
            self.scenery.apply(self, env_idx, self._episode_seed)

    # ------------------------------------------------------------------ API for reward code
    def obj_pose(self, name: str) -> Pose:
        """Pose of object ``name`` (p [N, 3], q [N, 4]); read once per step."""
        return self._cached(("pose", name), lambda: read_pose(self.obj(name)))

    @property
    def palm_pose(self) -> Pose:
        """Pose of the palm link; read once per step."""
        return self._cached("palm", lambda: read_pose(self.agent.palm_link))

    @property
    def tip_positions(self) -> torch.Tensor:
        """[N, 5, 3] fingertip positions (th, ff, mf, rf, lf); read once per step."""
        return self._cached("tips", lambda: self.agent.tip_positions)

    def obj(self, name: str) -> Actor | Articulation:
        """The scene entity of spec object ``name``."""
        try:
            return self.objects[name]
        except KeyError:
            raise TaskSpecError(f"task {self.task_spec.name!r} has no object {name!r}; objects: {sorted(self.objects)}."
                                f"{suggest(name, self.objects)}") from None

    def asset_record(self, name: str) -> AssetRecord:
        """The catalog record of object ``name``'s asset (size, bounding box, joints; unscaled)."""
        self.obj(name)  # names the objects when ``name`` is not one
        return self._records[name]

    def container_extent(self, name: str) -> tuple[float, float]:
        """(radius, height) of the space an ``inside`` condition checks in object ``name``: 80 % of its half
        footprint, and its height (scaled)."""
        self.obj(name)
        return self._container_extent[name]

    def hand_forces(self, name: str, part: str | None = None, joint: str | None = None) -> torch.Tensor:
        """[N, 6] mean contact force (N) of each hand group (th, ff, mf, rf, lf, palm) on object ``name``, or on its
        handle link (``part='handle'``); read once per step."""
        def compute():
            entity = self.handle_link(name, joint) if part == "handle" else self.obj(name)
            return self.agent.get_hand_group_obj_mean_force(entity)[..., 0]
        return self._cached(("hand_forces", name, part, joint), compute)

    def joint_record(self, name: str, joint: str | None = None) -> JointEntry:
        """The catalog entry of ``name``'s joint (default: its main joint)."""
        rec = self.asset_record(name)  # names the objects when ``name`` is not one
        if not rec.articulated:
            raise TaskSpecError(f"object {name!r} (asset {rec.id!r}) is not articulated")
        return rec.joints[0] if joint is None else rec.joint(joint)

    def joint_index(self, name: str, joint: str | None = None) -> int:
        """Position of ``name``'s joint among its articulation's active joints."""
        jr = self.joint_record(name, joint)
        names = [j.name for j in self.articulations[name].get_active_joints()]
        return names.index(jr.name)

    def handle_link(self, name: str, joint: str | None = None) -> Link:
        """The link carrying the handle of ``name``'s joint (default: its main joint)."""
        record = self.joint_record(name, joint)  # TaskSpecError for an unknown or rigid object
        return self.articulations[name].links_map[record.handle_link]

    def handle_pos(self, name: str, joint: str | None = None) -> torch.Tensor:
        """[N, 3] world position of the handle's grip point; read once per step."""
        def compute():
            link, local = self._handle_frame(name, joint)
            pose = read_pose(link)
            return transform_points(pose.p, pose.q, local)
        return self._cached(("handle_pos", name, joint), compute)

    def _handle_frame(self, name: str, joint: str | None) -> tuple[Link, torch.Tensor]:
        """(handle link, grip point in its frame, scaled): fixed for the scene's life, so memoised (a reconfiguration
        builds new links and drops the memo)."""
        key = (name, joint)
        cache = self.__dict__.setdefault("_handle_frames", {})
        if key not in cache:
            jr = self.joint_record(name, joint)
            scale = self.task_spec.object(name).scale
            local = torch.tensor(jr.handle_point_m, dtype=torch.float32, device=self.device) * scale
            cache[key] = (self.handle_link(name, joint), local)
        return cache[key]

    def joint_qpos(self, name: str, joint: str | None = None) -> torch.Tensor:
        """[N] current position of ``name``'s joint (default: its main joint); read once per step."""
        return self._cached(("joint_qpos", name, joint),
                            lambda: self.articulations[name].get_qpos()[:, self.joint_index(name, joint)])

    def open_qpos(self, name: str, joint: str | None = None) -> float:
        return self.joint_record(name, joint).open_qpos

    def closed_qpos(self, name: str, joint: str | None = None) -> float:
        return self.joint_record(name, joint).closed_qpos

    def joint_open_fraction(self, name: str, joint: str | None = None) -> torch.Tensor:
        """[N] 0 when closed, 1 when at the open target (may exceed 1)."""
        jr = self.joint_record(name, joint)
        return (self.joint_qpos(name, joint) - jr.closed_qpos) / (jr.open_qpos - jr.closed_qpos)

    @property
    def goal_pos(self) -> torch.Tensor:
        """[N, 3] goal position; TaskSpecError when the task has no goal."""
        if self.goal_site is None:
            raise TaskSpecError(f"task {self.task_spec.name!r} has no goal")
        return read_pose(self.goal_site).p

    def init_obj_pos(self, name: str) -> torch.Tensor:
        """[N, 3] position of object ``name`` at the last reset."""
        return self._obj_reset_pos[name]

    def init_obj_quat(self, name: str) -> torch.Tensor:
        """[N, 4] orientation (wxyz) of object ``name`` at the start of the task episode."""
        return self._obj_reset_quat[name]

    def obj_height(self, name: str) -> torch.Tensor:
        """[N] how far object ``name`` has risen above its reset height, metres."""
        return self.obj_pose(name).p[:, 2] - self._obj_reset_pos[name][:, 2]

    def spec_success(self) -> torch.Tensor:
        """[N] bool: every condition of the task's ``success`` holds now (without ``hold_steps`` or ``fail``)."""
        return conditions_hold(self, self.task_spec.success.conditions)

    # ------------------------------------------------------------------ task hooks
    def evaluate(self) -> dict:
        info = self.judge.evaluate(self)
        # a stage judged by the task's own conditions is judged as the task: after its sequence, for its hold_steps
        if self.stage_spec is None or self.stage_spec.success is None:
            info["success"] = self.success_tracker.update(self, info["success"], self.elapsed_steps)
        info["fail"] = info["fail"] & ~info["success"]
        return info

    def state_observation(self, judge: Judge | None = None, info: dict | None = None) -> torch.Tensor:
        """[N, D] the flat ``state`` observation of the current state as an env judged by ``judge`` would return it
        (a stage env's: its module's extras are part of it); ``info``: ``judge.evaluate(env)`` when the caller has
        it already. How a trained stage policy observes an env of another control mode."""
        judge = self.judge if judge is None else judge
        info = judge.evaluate(self) if info is None else info
        active, self.judge = self.judge, judge
        try:
            state = self._get_obs_state_dict(info)
        finally:
            self.judge = active
        return common.flatten_state_dict(state, use_torch=True, device=self.device)

    def own_obs_keys(self) -> frozenset[str]:
        """Names a reward module's extras may not reuse: the env's own state observations, the agent's and the
        observation's top-level names (:data:`~gendex_envs.reward_checks.RESERVED_OBS_KEYS`)."""
        keys = {"palm_pose", "tip_pos", *(f"{n}_pose" for n in self.objects),
                *(f"{n}_qpos" for n in self.articulations)}
        if self.goal_site is not None:
            keys.add("goal_pos")
        return frozenset(keys) | RESERVED_OBS_KEYS

    def _get_obs_extra(self, info: dict) -> dict:
        extra = dict(palm_pose=self.palm_pose.raw_pose, tip_pos=self.tip_positions.flatten(1))
        for name in self.objects:
            extra[f"{name}_pose"] = self.obj_pose(name).raw_pose
            if name in self.articulations:
                extra[f"{name}_qpos"] = self.articulations[name].get_qpos()
        if self.goal_site is not None:
            extra["goal_pos"] = read_pose(self.goal_site).p
        module = self.reward
        if module.get_obs_extra is not None:  # checked on every call: no key of the env's own, finite [N, k]
            extra.update(check_obs_extra(module.get_obs_extra(self, reward_info(info)), self.num_envs, self.device,
                                         extra, path=module.path, step=self.elapsed_steps))
        return extra

    def _flatten_raw_obs(self, obs):
        flat = flat_float_state(obs) if self._obs_mode == "state" else None
        return flat if flat is not None else super()._flatten_raw_obs(obs)

    def compute_dense_reward(self, obs, action: torch.Tensor, info: dict) -> torch.Tensor:
        """The module's reward, checked on every call; its ``info`` without bookkeeping (``reward_info``)."""
        return check_reward(self.reward.compute_dense_reward(self, obs, action, reward_info(info)), self.num_envs,
                            self.device, path=self.reward.path, step=self.elapsed_steps)

    def compute_normalized_dense_reward(self, obs, action: torch.Tensor, info: dict) -> torch.Tensor:
        return self.compute_dense_reward(obs, action, info) / self.reward.reward_max

    # ------------------------------------------------------------------ rendering
    def render_views(self, names: tuple[str, ...] = VIEW_CAMERAS) -> dict[str, np.ndarray]:
        """uint8 RGB images [N, H, W, 3] of the named human-render cameras (the three scene views)."""
        unknown = [n for n in names if n not in self.scene.human_render_cameras]
        if unknown:
            raise TaskSpecError(f"unknown cameras {unknown}; cameras: {sorted(self.scene.human_render_cameras)}")
        return {n: self.render_rgb_array(camera_name=n).cpu().numpy() for n in names}
