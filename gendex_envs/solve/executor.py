"""Stage executor: runs a task's sub-stages in YAML order with planned arm motion and synthesized grasps.

Each stage is mapped to a primitive from the stage's method, its target and what the hand holds:

=====================  ===========================================  ==============================================
stage                  situation                                    primitive
=====================  ===========================================  ==============================================
motion_planning        target is a graspable object, hand empty     ``approach``: grasp synthesis on the object's
                                                                    measured pose, IK, planned path to pre-grasp,
                                                                    straight descent to the grasp pose
motion_planning        hand holds an object, target is another one  ``carry``: lift, planned path until the held
                                                                    object is over the target, lower
RL                     hand empty, target graspable                 ``grasp``: guarded finger-then-thumb closing,
                                                                    squeeze, lift and hold check
RL                     hand holds the target                        ``release`` when the previous stage carried it
                                                                    somewhere, else ``lift`` to the success height
=====================  ===========================================  ==============================================

A stage whose target is articulated (a door, a lid) runs :mod:`gendex_envs.solve.articulated` instead:
``approach_handle`` (motion planning), ``hook`` (RL, hand) and ``pull`` (RL with the arm; it hooks first if no stage
did).

An RL stage runs its trained policy when the task has one (``policies/<stage>.zip``, written by ``gendex train``;
see :mod:`gendex_envs.solve.policy`) until the stage's own ``evaluate`` reports success or its horizon ends; without
a policy the scripted primitive runs and the log says so. The executor is a
:class:`gendex_envs.data.collector.Solver`: it emits
absolute joint targets for the ``pd_joint_pos`` / ``both`` action space, one control step at a time, and re-reads
the object poses between primitives (grasps are planned from the actual pose, never from the nominal one).
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import gymnasium as gym
import numpy as np
import sapien

from gendex_envs.errors import ExecutionError
from gendex_envs.solve.articulated import PRIMITIVES as ARTICULATED_PRIMITIVES
from gendex_envs.solve.articulated import HandlePrimitives
from gendex_envs.solve.collision import ArmCollisionModel, Box
from gendex_envs.solve.grasp import GUARD_RAD, OPEN_HAND, GraspPlan, grasp_candidates
from gendex_envs.solve.ik import ArmIK
from gendex_envs.solve.planner import ArmPlanner, PlanningError
from gendex_envs.solve.policy import StagePolicy
from gendex_envs.stage import POLICIES_DIR

log = logging.getLogger(__name__)


@dataclass
class ExecutorConfig:
    """Speeds and margins of the scripted primitives (control steps at 20 Hz)."""

    descend_m_per_step: float = 0.01
    lift_m: float = 0.15
    lift_m_per_step: float = 0.006
    close_steps: int = 12
    thumb_steps: int = 12
    squeeze_steps: int = 6
    release_steps: int = 8
    carry_clearance_m: float = 0.07
    """Height of the held object's bottom above the target container's rim while carrying."""
    settle_steps: int = 2
    max_arm_step_rad: float = 0.06


@dataclass
class StageLog:
    stage: str
    primitive: str
    policy: str
    steps: int = 0


@dataclass
class StageExecutor:
    """Scripted solver of a task's stages (see the module docstring); name ``stages`` in ``gendex collect``."""

    config: ExecutorConfig = field(default_factory=ExecutorConfig)
    name: str = "stages"
    policy_dir: Path | None = None
    """Folder of trained stage policies (default: the task's ``policies/``)."""
    use_policies: bool = True
    """Run trained policies for RL stages when present (False: always the scripted primitives)."""
    policy_stages: str = "rl"
    """Which stages run a trained policy when one exists: ``rl`` (RL stages; motion-planning stages always plan) or
    ``all`` (every stage; the ablation's all-RL variants)."""
    stop_before: int | None = None
    """Stop (act() returns None) when stage ``stop_before`` would begin: the env then holds the state at the end of
    stage ``stop_before - 1`` (how start states of a stage are collected)."""

    def reset(self, env: gym.Env, obs) -> None:
        u = env.unwrapped
        if getattr(self, "_env", None) is not u:
            self._env = u
            self.ik = ArmIK(u.agent)
            self.collision = ArmCollisionModel(self.ik)
            self.planner = ArmPlanner(self.collision, max_step_rad=self.config.max_arm_step_rad)
            ctrl = u.agent.controller
            self._free = np.array([self.ik.joint_names.index(n) for n in ctrl.free_joint_names])
            self._hand = np.array([i for i in range(len(self.ik.joint_names)) if i not in set(self.ik.arm)])
            if ctrl.config.use_delta or set(self.ik.arm) - set(self._free):
                raise ExecutionError("the stage executor drives absolute arm and hand targets: make the env with "
                                     "control_mode='pd_joint_pos', control_joint='both'")
        self.held: str | None = None
        self.carried = False
        self.logs: list[StageLog] = []
        self._plan: GraspPlan | None = None
        self._articulated = HandlePrimitives(self)
        self.stage_index = -1
        """Index of the stage being executed (-1 before the first)."""
        self.finished = False
        """True once every stage (up to ``stop_before``) ran without an ExecutionError."""
        self._policies: dict[str, StagePolicy] = getattr(self, "_policies", {})
        self._actions = self._episode()

    def act(self, env: gym.Env, obs) -> np.ndarray | None:
        return next(self._actions, None)

    # ------------------------------------------------------------------ helpers
    def _q(self) -> np.ndarray:
        return self._env.agent.robot.get_qpos()[0].cpu().numpy().astype(np.float64)

    def _target(self) -> np.ndarray:
        return self._env.agent.controller._target_qpos[0].cpu().numpy().astype(np.float64)

    def _emit(self, target: np.ndarray, guard: bool = False) -> np.ndarray:
        t = target.copy()
        if guard:
            q = self._q()
            t[self._hand] = np.clip(t[self._hand], q[self._hand] - GUARD_RAD, q[self._hand] + GUARD_RAD)
        self.logs[-1].steps += 1
        return t[self._free].astype(np.float32)

    def _ramp(self, goal: np.ndarray, steps: int, guard: bool = False) -> Iterator[np.ndarray]:
        start = self._target()
        for k in range(1, steps + 1):
            yield self._emit(start + (goal - start) * k / steps, guard)

    def _with_hand(self, q: np.ndarray, hand: dict[str, float]) -> np.ndarray:
        q = q.copy()
        for j, v in hand.items():
            q[self.ik.joint_names.index(j)] = v
        return q

    def _obj_geometry(self, name: str) -> tuple[np.ndarray, float, float, float]:
        """(centre xy, bottom z, height, radius) of object ``name``: extents from its world bounding box now, radius
        from its own (local) box, since the world box of a yawed cylinder is up to √2 too wide."""
        lo, hi = self._world_aabb(name)
        e = self._env._records[name].entry
        size = (np.asarray(e.bbox_max_m) - np.asarray(e.bbox_min_m)) * self._env.task_spec.object(name).scale
        radius = float(np.max(size[:2]) / 2)
        return (lo[:2] + hi[:2]) / 2, float(lo[2]), float(hi[2] - lo[2]), radius

    def _world_aabb(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        u = self._env
        rec = u._records[name]
        scale = u.task_spec.object(name).scale
        lo, hi = np.asarray(rec.entry.bbox_min_m) * scale, np.asarray(rec.entry.bbox_max_m) * scale
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        pose = u.obj(name).pose
        m = sapien.Pose(pose.p[0].cpu().numpy(), pose.q[0].cpu().numpy()).to_transformation_matrix()
        w = corners @ m[:3, :3].T + m[:3, 3]
        return w.min(axis=0), w.max(axis=0)

    def _obstacles(self, exclude: tuple[str, ...] = ()) -> None:
        boxes = []
        for name in self._env.objects:
            if name in exclude:
                continue
            lo, hi = self._world_aabb(name)
            boxes.append(Box(lo - 0.01, hi + 0.01, name))
        self.collision.set_obstacles(boxes)

    def _move_arm(self, q_goal: np.ndarray, hand: np.ndarray | None = None) -> Iterator[np.ndarray]:
        """Planned arm motion to ``q_goal``'s arm joints, hand targets held (or ``hand``'s)."""
        start = self._target()
        goal = start.copy()
        goal[self.ik.arm] = q_goal[self.ik.arm]
        if hand is not None:
            goal[self._hand] = hand[self._hand]
        try:
            path = self.planner.plan(start, goal)
        except PlanningError as e:
            raise ExecutionError(str(e)) from e
        for q in path:
            q = q.copy()
            q[self._hand] = goal[self._hand]
            yield self._emit(q)

    def _cartesian(self, offset: np.ndarray, m_per_step: float, guard: bool = False) -> Iterator[np.ndarray]:
        """Straight palm translation by ``offset`` (world, m), orientation kept, IK per step."""
        target = self._target()
        palm = self.ik.fk(target)
        n = max(1, int(np.ceil(np.linalg.norm(offset) / m_per_step)))
        q = target
        for k in range(1, n + 1):
            goal = sapien.Pose(palm.p + offset * k / n, palm.q)
            nq = self.ik.solve(goal, q, restarts=0)
            if nq is None:
                raise ExecutionError(f"no IK along the straight palm motion at step {k}/{n}")
            q = nq
            t = self._target()
            t[self.ik.arm] = q[self.ik.arm]
            yield self._emit(t, guard)

    # ------------------------------------------------------------------ episode
    def _episode(self) -> Iterator[np.ndarray]:
        u = self._env
        spec = u.task_spec
        for i, stage in enumerate(spec.stages):
            if self.stop_before is not None and i >= self.stop_before:
                self.finished = True
                return
            self.stage_index = i
            learned = stage.method == "RL" or self.policy_stages == "all"
            policy = self._policy_path(stage.name) if learned and self.use_policies else None
            prim = self._choose(stage)
            self.logs.append(StageLog(stage.name, prim, "scripted" if policy is None else str(policy)))
            if policy is not None:
                log.info("stage %r (RL, %s): policy %s", stage.name, stage.control_joint, policy)
                yield from self._run_policy(stage, policy, prim)
                continue
            if stage.method == "RL":
                log.info("stage %r (RL, %s): no trained policy; scripted primitive %r", stage.name,
                         stage.control_joint, prim)
            else:
                log.info("stage %r (motion planning): primitive %r", stage.name, prim)
            if prim in ARTICULATED_PRIMITIVES:
                yield from self._articulated.run(prim, stage)
            else:
                yield from getattr(self, "_" + prim)(stage)
        self.finished = True
        # hold the last targets until the task reports success (or the episode ends)
        self.logs.append(StageLog("settle", "hold", "scripted"))
        for _ in range(spec.success.hold_steps + 10):
            yield self._emit(self._target())

    def _policy_path(self, stage: str) -> Path | None:
        folder = self.policy_dir if self.policy_dir is not None else \
            (Path(self._env.task_dir) / POLICIES_DIR if self._env.task_dir else None)
        p = Path(folder) / f"{stage}.zip" if folder is not None else None
        return p if p is not None and p.exists() else None

    def _run_policy(self, stage, path: Path, prim: str) -> Iterator[np.ndarray]:
        """Run the stage's trained policy until its ``evaluate`` reports success or its horizon ends; then keep the
        same bookkeeping the scripted primitive ``prim`` would (what the hand holds, whether a handle is hooked)."""
        key = str(path)
        if key not in self._policies:
            self._policies[key] = StagePolicy.load(self._env.task_dir, stage.name, path)
        policy = self._policies[key]
        done = False
        info = policy.module.evaluate(self._env)  # one evaluate per step: it feeds the next observation too
        for _ in range(stage.horizon):
            target = policy.targets(self._env, policy.act(self._env, info))[0].cpu().numpy().astype(np.float64)
            yield self._emit(target)
            info = policy.module.evaluate(self._env)
            if bool(info["success"][0]):
                done = True
                break
        if not done:
            raise ExecutionError(f"policy of stage {stage.name!r} did not reach the stage's goal in {stage.horizon} "
                                 "steps")
        if prim == "grasp":
            self.held = stage.target
        elif prim == "carry":
            self.carried = True
        elif prim == "release":
            self.held = None
        elif prim == "hook":
            self._articulated.hooked, self._articulated.target = True, stage.target

    def _choose(self, stage) -> str:
        target = stage.target
        if target is None:
            raise ExecutionError(f"stage {stage.name!r} has no target object: the executor cannot act on it")
        if target in self._env.articulations:
            return self._articulated.choose(stage)  # approach_handle / hook / pull (solve/articulated.py)
        if stage.method == "motion_planning":
            if self.held is None:
                return "approach"
            return "carry" if target != self.held else "lift"
        if self.held is None:
            return "grasp"
        return "release" if (target == self.held and self.carried) else "lift"

    # ------------------------------------------------------------------ primitives
    def _approach(self, stage) -> Iterator[np.ndarray]:
        name = stage.target
        center, bottom, height, radius = self._obj_geometry(name)
        self._obstacles(exclude=(name,))
        base = self.ik.base.p
        prefer = float(np.arctan2(center[1] - base[1], center[0] - base[0]))  # fingers pointing away from the base
        q0 = self._target()
        chosen: tuple[GraspPlan, np.ndarray, np.ndarray] | None = None
        for plan in grasp_candidates(center, bottom, height, radius, prefer_yaw_rad=prefer):
            open_q = self._with_hand(q0, plan.open_hand)
            q_pre = self.ik.solve(plan.pregrasp, open_q, restarts=20, valid=self.collision.is_free)
            if q_pre is None:
                continue
            q_in = self.ik.solve(plan.palm, q_pre, restarts=0)
            if q_in is None:
                continue
            chosen = (plan, q_pre, q_in)
            break
        if chosen is None:
            raise ExecutionError(f"no reachable collision-free grasp of {name!r}")
        plan, q_pre, _ = chosen
        self._plan = plan
        yield from self._move_arm(q_pre, hand=self._with_hand(q0, plan.open_hand))
        yield from self._cartesian(plan.palm.p - plan.pregrasp.p, self.config.descend_m_per_step)
        for _ in range(self.config.settle_steps):
            yield self._emit(self._target())

    def _grasp(self, stage) -> Iterator[np.ndarray]:
        plan = self._plan
        if plan is None:
            raise ExecutionError(f"stage {stage.name!r} grasps {stage.target!r} but no stage approached it")
        c = self.config
        t = self._target()
        yield from self._ramp(self._with_hand(t, plan.fingers), c.close_steps, guard=True)
        yield from self._ramp(self._with_hand(self._target(), plan.thumb), c.thumb_steps, guard=True)
        for _ in range(c.squeeze_steps):
            yield self._emit(self._with_hand(self._target(), plan.fingers | plan.thumb), guard=True)
        self.held = stage.target
        z0 = float(self._env.obj(stage.target).pose.p[0, 2])
        yield from self._cartesian(np.array([0.0, 0.0, c.lift_m]), c.lift_m_per_step, guard=True)
        risen = float(self._env.obj(stage.target).pose.p[0, 2]) - z0
        if risen < 0.5 * c.lift_m:
            self.held = None
            raise ExecutionError(f"grasp of {stage.target!r} failed its lift check (rose {risen:.3f} m of "
                                 f"{c.lift_m:.3f} m)")

    def _lift(self, stage) -> Iterator[np.ndarray]:
        c = self.config
        heights = [cond.min_height_m for cond in self._env.task_spec.success.conditions
                   if cond.type == "lifted" and cond.object == stage.target]
        need = max(heights) if heights else c.lift_m
        risen = float(self._env.obj_height(stage.target)[0])
        if risen < need + 0.02:
            yield from self._cartesian(np.array([0.0, 0.0, need + 0.03 - risen]), c.lift_m_per_step, guard=True)

    def _carry(self, stage) -> Iterator[np.ndarray]:
        c = self.config
        held, target = self.held, stage.target
        held_lo, held_hi = self._world_aabb(held)
        if held_lo[2] < self._env.table_height + 0.5 * c.lift_m:
            # still at the table (a trained grasp policy closes the hand but does not lift, unlike the scripted
            # grasp): lift straight up first, so the planned carry never drags the object across the table
            z0 = float(self._env.obj(held).pose.p[0, 2])
            yield from self._cartesian(np.array([0.0, 0.0, c.lift_m]), c.lift_m_per_step, guard=True)
            risen = float(self._env.obj(held).pose.p[0, 2]) - z0
            if risen < 0.5 * c.lift_m:
                raise ExecutionError(f"{held!r} slipped when lifted for the carry (rose {risen:.3f} m of "
                                     f"{c.lift_m:.3f} m)")
            held_lo, held_hi = self._world_aabb(held)
        t_center = self._obj_geometry(target)[0]
        t_hi = self._world_aabb(target)[1]
        obj_p = (held_lo + held_hi) / 2
        goal_center = np.array([t_center[0], t_center[1], t_hi[2] + c.carry_clearance_m + (obj_p[2] - held_lo[2])])
        offset = goal_center - obj_p
        q_now = self._target()
        palm = self.ik.fk(q_now)
        goal = sapien.Pose(palm.p + offset, palm.q)
        # the held object moves with the palm: plan with it attached, against every other object (the target too)
        self._obstacles(exclude=(held,))
        self.collision.attach(*self._object_spheres(held_lo, held_hi), q_now)
        try:
            q_goal = self.ik.solve(goal, q_now, restarts=20, valid=self.collision.is_free)
            if q_goal is None:
                raise ExecutionError(f"no reachable collision-free pose holding {held!r} above {target!r}")
            yield from self._move_arm(q_goal)
        finally:
            self.collision.detach()
        self.carried = True

    @staticmethod
    def _object_spheres(lo: np.ndarray, hi: np.ndarray, shrink_m: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
        """Spheres covering a held object's box (shrunk a little: the fingers wrap it): [k, 3] centres, [k] radii."""
        size = np.maximum(hi - lo - 2 * shrink_m, 1e-3)
        r = float(min(size[:2]) / 2)
        n = max(1, int(np.ceil(size[2] / (2 * r))))
        z = np.linspace(lo[2] + shrink_m + r, hi[2] - shrink_m - r, n) if n > 1 else np.array([(lo[2] + hi[2]) / 2])
        centre = (lo + hi) / 2
        pts = np.stack([np.full(n, centre[0]), np.full(n, centre[1]), z], axis=1)
        return pts, np.full(n, float(np.linalg.norm(size[:2]) / 2))

    def _release(self, stage) -> Iterator[np.ndarray]:
        t = self._with_hand(self._target(), OPEN_HAND | {j: 0.0 for j in ("THJ3", "THJ1", "THJ0")})
        yield from self._ramp(t, self.config.release_steps)
        self.held = None
        yield from self._cartesian(np.array([0.0, 0.0, 0.05]), 0.01)


def make_stage_executor() -> StageExecutor:
    return StageExecutor()


__all__ = ["ExecutionError", "ExecutorConfig", "StageExecutor", "StageLog", "make_stage_executor"]
