"""How much of the raw physics speed does a GenDex env keep?

Measures, in one process and one run:

(a) ``env.step`` per second of a GenDex task through the public API (``gym.make``, one CPU env, random
    ``pd_joint_delta_pos`` actions; episode resets happen outside the timed region and are counted);
(b) control steps per second of the *same physical scene* built with plain SAPIEN, without ManiSkill and without a
    renderer: same URDF, build order, table, ground and catalog objects, physx configuration (the env's
    ``sim_config``), and the robot's gravity flags, collision groups and drive properties copied from the env's robot
    (given the same actions both simulate bit-identical trajectories). One raw control step = new drive targets for
    all joints (random deltas for the joints the env's action drives, distal J0 copies J1) + ``sim_freq /
    control_freq`` ``px.step()`` calls. No observation, reward or rendering work: exactly what (a) pays on top.
(c) the ratio (a) / (b); the project's goal is >= 0.5.

Run: ``.venv/bin/python benchmarks/step_rate.py [--steps 1000] [--repeats 3] [--task GenDex/PutAppleBowl-v0]``.

``--untrusted`` measures instead, in one run, ``env.step`` per second of the task as committed (trusted: its
reward module runs in this process) and of an untrusted copy of the same folder under a temporary task root (its
reward module runs in the sandbox: recorded by its confined worker, replayed in this process,
:mod:`gendex_envs.sandbox`), interleaved in chunks of ``--chunk`` steps (the machine's speed drifts within seconds),
and their ratio (issue 43's goal: >= 0.85). Episode resets are not timed on either side.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import time

# isort: off
import gendex_envs.blas  # first: it pins OpenBLAS's kernels before numpy loads
# isort: on

import gymnasium as gym
import numpy as np
import sapien
import torch
from sapien import physx
from sapien.wrapper.actor_builder import ActorBuilder
from sapien.wrapper.articulation_builder import ArticulationBuilder
from sapien.wrapper.urdf_loader import URDFLoader

import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
from gendex_envs.agents.robot_model import robot_urdf_path
from gendex_envs.assets.catalog import get_asset, lowest_point_z
from gendex_envs.physx import px_objects


# ---------------------------------------------------------------------------------------------- raw SAPIEN scene
class _NoVisualActorBuilder(ActorBuilder):
    def build_entity(self):
        self.visual_records = []  # a physics-only scene has no render system to hold visual shapes
        return super().build_entity()


class _NoVisualArticulationBuilder(ArticulationBuilder):
    def build_entities(self, *args, **kwargs):
        for link in self.link_builders:
            link.visual_records = []
        return super().build_entities(*args, **kwargs)

    def build(self, name=None, fix_root_link=None, build_mimic_joints=True):  # ManiSkill's signature (with name)
        return super().build(fix_root_link=fix_root_link, build_mimic_joints=build_mimic_joints)


class PhysicsOnlyScene(sapien.Scene):
    """A ``sapien.Scene`` with only a CPU PhysX system; builders drop visual shapes, so catalog builders work."""

    def __init__(self):
        super().__init__([physx.PhysxCpuSystem()])

    def create_actor_builder(self):
        return _NoVisualActorBuilder().set_scene(self)

    def create_articulation_builder(self):
        return _NoVisualArticulationBuilder().set_scene(self)

    def create_urdf_loader(self):
        return _DictURDFLoader.for_scene(self)


class _DictURDFLoader(URDFLoader):
    """SAPIEN's URDF loader with ManiSkill's ``parse`` result (a dict) and ``name`` attribute, physics only."""

    name = None

    @classmethod
    def for_scene(cls, scene):
        loader = cls()
        loader.set_scene(scene)
        return loader

    def parse(self, urdf_file, srdf_file=None, package_dir=None):
        articulation_builders, actor_builders, cameras = super().parse(urdf_file, srdf_file, package_dir)
        for b in articulation_builders:
            b.__class__ = _NoVisualArticulationBuilder
        return {"articulation_builders": articulation_builders, "actor_builders": actor_builders, "cameras": cameras}


class RawScene:
    """The physical scene of a :class:`~gendex_envs.task_env.TaskEnv`, rebuilt with plain SAPIEN."""

    def __init__(self, env, seed: int):
        cfg, spec = env.sim_config, env.task_spec
        sc = cfg.scene_config
        physx.set_shape_config(contact_offset=sc.contact_offset, rest_offset=sc.rest_offset)
        physx.set_body_config(solver_position_iterations=sc.solver_position_iterations,
                              solver_velocity_iterations=sc.solver_velocity_iterations,
                              sleep_threshold=sc.sleep_threshold)
        physx.set_scene_config(gravity=np.asarray(sc.gravity, dtype=np.float32), bounce_threshold=sc.bounce_threshold,
                               enable_pcm=sc.enable_pcm, enable_tgs=sc.enable_tgs, enable_ccd=sc.enable_ccd,
                               enable_enhanced_determinism=sc.enable_enhanced_determinism,
                               enable_friction_every_iteration=sc.enable_friction_every_iteration,
                               cpu_workers=sc.cpu_workers)
        physx.set_default_material(**cfg.default_materials_config.dict())
        self.scene = PhysicsOnlyScene()
        self.px = self.scene.physx_system
        self.px.timestep = 1.0 / cfg.sim_freq
        self.substeps = cfg.sim_freq // cfg.control_freq
        self.rng = np.random.default_rng(seed)
        self.episode_steps, self.elapsed = spec.max_episode_steps, 0

        robot = spec.robot  # the robot first, as ManiSkill loads the agent before the scene (same PhysX order)
        loader = self.scene.create_urdf_loader()
        loader.fix_root_link = True
        builder = loader.parse(str(robot_urdf_path()))["articulation_builders"][0]
        yaw = math.radians(robot.base_yaw_deg)
        builder.initial_pose = sapien.Pose(list(robot.base_pos_m), [math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)])
        self.robot = builder.build(fix_root_link=True)
        # mirror the env's robot: gravity flags and collision groups per link, drive properties per joint
        src_links = {link.name: px_objects(link)[0] for link in env.agent.robot.get_links()}
        for link in self.robot.links:
            src = src_links[link.name]
            link.disable_gravity = src.disable_gravity
            for shape, src_shape in zip(link.collision_shapes, src.collision_shapes, strict=True):
                shape.set_collision_groups(src_shape.get_collision_groups())
        src_joints = {j.name: px_objects(j)[0] for j in env.agent.robot.get_active_joints()}
        self.joints = self.robot.active_joints
        for j in self.joints:
            src = src_joints[j.name]
            j.set_drive_properties(src.stiffness, src.damping, force_limit=src.force_limit, mode=src.drive_mode)
            j.set_friction(src.friction)
        # the action drives the controller's free joints by at most +-delta each; followers copy their leader
        ctrl = env.agent.controller
        names = [j.name for j in self.joints]
        self.free_idx = np.array([names.index(n) for n in ctrl.free_joint_names])
        self.delta = np.asarray(ctrl.config.upper, dtype=np.float32)
        self.follower_idx = np.array([names.index(n) for n in ctrl.config.mimic])
        self.leader_idx = np.array([names.index(n) for n in ctrl.config.mimic.values()])
        env_qpos = dict(zip(src_joints, env.agent.robot.get_qpos()[0].tolist(), strict=True))  # the env was just reset
        self.rest = np.array([env_qpos[n] for n in names], dtype=np.float32)

        table = spec.table  # static table top (top face at z = 0) and a ground plane under the legs
        b = self.scene.create_actor_builder()
        b.add_box_collision(sapien.Pose([0, 0, -0.025]), [table.size_m[0] / 2, table.size_m[1] / 2, 0.025],
                            material=physx.PhysxMaterial(table.friction, 0.8 * table.friction, 0.0))
        b.build_static("table")
        b = self.scene.create_actor_builder()
        b.add_plane_collision(sapien.Pose([0, 0, -table.height_m], [0.7071068, 0, -0.7071068, 0]))
        b.build_static("ground")

        self.objects = []  # (entity, initial pose, joint state or None)
        for obj in spec.objects:
            rec = get_asset(obj.asset)
            x, y, clearance = obj.pos_m
            pose = sapien.Pose([x, y, clearance - lowest_point_z(rec, obj.scale, obj.quat_wxyz)], list(obj.quat_wxyz))
            entity = rec.build(self.scene, obj.name, obj.scale, obj.color_rgba, obj.fixed, pose)
            qpos = None
            if rec.articulated:
                qpos = np.array([obj.joint_state.get(j.name, rec.joint(j.name).closed_qpos)
                                 for j in entity.active_joints], dtype=np.float32)
            self.objects.append((entity, pose, qpos))
        self.reset()

    def reset(self):
        self.elapsed = 0
        self.robot.qpos, self.robot.qvel = self.rest, np.zeros_like(self.rest)
        self.targets = self.rest.copy()
        for j, t in zip(self.joints, self.targets, strict=True):
            j.set_drive_target(float(t))
        for entity, pose, qpos in self.objects:
            if qpos is not None:  # articulated object
                entity.root_pose, entity.qpos, entity.qvel = pose, qpos, np.zeros_like(qpos)
                continue
            entity.pose = pose
            body = entity.find_component_by_type(physx.PhysxRigidDynamicComponent)
            if body is not None and not body.kinematic:
                body.linear_velocity, body.angular_velocity = np.zeros(3), np.zeros(3)

    def sample_action(self) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, len(self.free_idx)).astype(np.float32)

    def step(self, action: np.ndarray) -> bool:
        """One control step: delta joint targets (followers copy leaders), then the physics substeps.
        Returns True when an episode of the env's length is over (the caller resets, like a time limit)."""
        self.targets[self.free_idx] += np.clip(action, -1.0, 1.0) * self.delta
        self.targets[self.follower_idx] = self.targets[self.leader_idx]
        for j, t in zip(self.joints, self.targets.tolist(), strict=True):
            j.set_drive_target(t)
        for _ in range(self.substeps):
            self.px.step()
        self.elapsed += 1
        return self.elapsed >= self.episode_steps


# ---------------------------------------------------------------------------------------------- timing
def timed_rate(sample, step, reset, steps: int) -> tuple[float, int]:
    """Steps/s of ``step(sample())`` (only ``step`` is timed; resets when it returns True) and the reset count."""
    busy, resets = 0.0, 0
    for _ in range(steps):
        action = sample()
        t0 = time.perf_counter()
        done = step(action)
        busy += time.perf_counter() - t0
        if done:
            reset()
            resets += 1
    return steps / busy, resets


def untrusted_comparison(args) -> None:
    """``--untrusted``: the committed task and an untrusted copy of its folder, interleaved (see the module doc)."""
    import tempfile
    from pathlib import Path

    from gendex_envs import guard
    from gendex_envs.registry import make_env, resolve_task

    version = resolve_task(args.task)
    with tempfile.TemporaryDirectory(prefix="gendex_step_rate_") as tmp:
        copy = Path(tmp) / "tasks" / version.name / version.root.name
        version.copy_to(copy)
        assert guard.is_trusted(version.root) and not guard.is_trusted(copy)
        envs = {"trusted": make_env(version, control_mode="pd_joint_delta_pos"),
                "untrusted": make_env(copy, control_mode="pd_joint_delta_pos")}
        try:
            print(f"task {args.task} ({version.root})  untrusted copy {copy}")
            print(f"machine: {platform.processor() or platform.machine()}  os.cpu_count()={os.cpu_count()}  "
                  f"affinity={len(os.sched_getaffinity(0))}  torch threads={torch.get_num_threads()}  "
                  f"torch {torch.__version__}")
            sides = {}
            for name, env in envs.items():
                env.reset(seed=args.seed)
                env.action_space.seed(args.seed)

                def step(action, env=env) -> bool:
                    _, _, terminated, truncated, _ = env.step(action)
                    return bool(terminated or truncated)

                sides[name] = (env.action_space.sample, step, env.reset)
            rates = {name: [] for name in sides}
            for sample, step, reset in sides.values():
                timed_rate(sample, step, reset, args.warmup)
            for _, _, reset in sides.values():
                reset()
            for r in range(args.repeats):  # interleaved in chunks, so the machine's drifts hit both sides alike
                busy = dict.fromkeys(sides, 0.0)
                done = 0
                while done < args.steps:
                    n = min(args.chunk, args.steps - done)
                    for name, (sample, step, reset) in sides.items():
                        busy[name] += n / timed_rate(sample, step, reset, n)[0]
                    done += n
                for name in sides:
                    rates[name].append(args.steps / busy[name])
                print(f"  repeat {r + 1}: trusted {rates['trusted'][-1]:8.1f} /s   untrusted "
                      f"{rates['untrusted'][-1]:8.1f} /s   ratio {rates['untrusted'][-1] / rates['trusted'][-1]:.3f}")
            trusted, untrusted = statistics.median(rates["trusted"]), statistics.median(rates["untrusted"])
            print(f"\nmedian of {args.repeats} x {args.steps} steps")
            print(f"  {'trusted env.step/s':28s} {trusted:10.1f}   ({1e3 / trusted:.3f} ms/step)")
            print(f"  {'untrusted env.step/s':28s} {untrusted:10.1f}   ({1e3 / untrusted:.3f} ms/step)")
            print(f"  {'ratio untrusted / trusted':28s} {untrusted / trusted:10.3f}   (goal >= 0.85)")
        finally:
            for env in envs.values():
                env.close()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", default="GenDex/PutAppleBowl-v0")
    ap.add_argument("--steps", type=int, default=1000, help="timed control steps per repeat and side")
    ap.add_argument("--warmup", type=int, default=50)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--chunk", type=int, default=25, help="--untrusted: steps per side before switching sides")
    ap.add_argument("--torch-threads", type=int, default=None, help="torch.set_num_threads(N) (default: leave)")
    ap.add_argument("--untrusted", action="store_true",
                    help="compare the committed task with an untrusted copy of it (sandboxed reward code)")
    args = ap.parse_args()
    if args.torch_threads is not None:
        torch.set_num_threads(args.torch_threads)
    if args.untrusted:
        untrusted_comparison(args)
        return

    env = gym.make(args.task, control_mode="pd_joint_delta_pos")
    env.reset(seed=args.seed)
    env.action_space.seed(args.seed)
    u = env.unwrapped
    raw = RawScene(u, args.seed)
    env_px, raw_px = u.scene.sub_scenes[0].physx_system, raw.px
    count = lambda px: (len(px.rigid_dynamic_components), len(px.rigid_static_components),  # noqa: E731
                        len(px.articulation_link_components))
    print(f"task {args.task}  control_joint={u.control_joint}  action dim {env.action_space.shape[0]}  "
          f"substeps {raw.substeps}  episode {raw.episode_steps} steps")
    print(f"bodies (dynamic, static, links): env {count(env_px)}  raw {count(raw_px)}")
    print(f"machine: {platform.processor() or platform.machine()}  os.cpu_count()={os.cpu_count()}  "
          f"affinity={len(os.sched_getaffinity(0))}  torch threads={torch.get_num_threads()}  "
          f"torch {torch.__version__}  sapien {sapien.__version__}")

    def env_step(action) -> bool:
        _, _, terminated, truncated, _ = env.step(action)
        return bool(terminated or truncated)

    sides = dict(env=(env.action_space.sample, env_step, env.reset), raw=(raw.sample_action, raw.step, raw.reset))
    rates, resets = {name: [] for name in sides}, {name: 0 for name in sides}
    for sample, step, reset in sides.values():
        timed_rate(sample, step, reset, args.warmup)
    for r in range(args.repeats):  # interleaved, so slow drifts of the machine hit both sides
        for name, (sample, step, reset) in sides.items():
            reset()
            rate, n = timed_rate(sample, step, reset, args.steps)
            rates[name].append(rate)
            resets[name] += n
        print(f"  repeat {r + 1}: env {rates['env'][-1]:8.1f} /s   raw {rates['raw'][-1]:8.1f} /s")
    env_rate, raw_rate = statistics.median(rates["env"]), statistics.median(rates["raw"])
    print(f"\nmedian of {args.repeats} x {args.steps} steps ({resets['env']} env resets, not timed)")
    print(f"  {'env.step/s':28s} {env_rate:10.1f}   ({1e3 / env_rate:.3f} ms/step)")
    print(f"  {'raw control steps/s':28s} {raw_rate:10.1f}   ({1e3 / raw_rate:.3f} ms/step)")
    print(f"  {'raw physics steps/s':28s} {raw_rate * raw.substeps:10.1f}")
    print(f"  {'ratio env / raw':28s} {env_rate / raw_rate:10.3f}   (goal >= 0.5)")
    env.close()


if __name__ == "__main__":
    main()
