"""Stage executor: runs a task's stages in spec order, each by the primitive its skill names.

Every stage declares a ``skill`` (:data:`gendex_envs.spec.SKILLS`) and a ``target``; the primitive follows from the
skill and from what the target is:

==========  ===================  =============================================================================
skill       rigid target         articulated target (a door, a lid; :mod:`gendex.solve.articulated`)
==========  ===================  =============================================================================
reach       ``approach``         ``approach_handle``
grasp       ``grasp``            ``hook``
lift        ``lift``
carry       ``carry``
release     ``release``
open                             ``pull`` (hooks first when no stage did)
==========  ===================  =============================================================================

``approach``: grasp synthesis on the object's measured pose, IK, planned path to the pre-grasp, straight descent.
``grasp``: guarded finger-then-thumb closing, squeeze, lift and a hold check. ``lift``: raise the held object to
the success height. ``carry``: planned path (the held object attached to the palm in the collision model) until
the held object is over the target. ``release``: open the hand and back off. A skill without a primitive for its
target raises :class:`~gendex_envs.errors.ExecutionError` naming what exists.

A stage whose trained policy is present (in the task version, or in the policy folders given) runs the policy
instead — for RL stages, or for every stage with ``policy_stages="all"`` — until the stage's success conditions
hold or its horizon ends (:mod:`gendex.solve.policy`). The executor is a :class:`~gendex.solve.Solver`: it emits
absolute joint targets for the ``pd_joint_pos`` / ``both`` action space, one control step at a time, and re-reads
object poses between primitives (grasps are planned from the actual pose, never from the nominal one).
"""

from __future__ import annotations

import logging
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field

import gymnasium as gym
import numpy as np
import sapien

from gendex.solve.articulated import HandlePrimitives
from gendex.solve.grasp import OPEN_HAND, GraspPlan, grasp_candidates
from gendex.solve.motion import ArmHandMotion
from gendex.solve.policy import StagePolicy
from gendex_envs.errors import ExecutionError
from gendex_envs.task_version import Artifacts, PolicyFiles

log = logging.getLogger(__name__)

RIGID_PRIMITIVES = {"reach": "approach", "grasp": "grasp", "lift": "lift", "carry": "carry", "release": "release"}
"""Skill -> primitive for a rigid target."""
ARTICULATED_PRIMITIVES = {"reach": "approach_handle", "grasp": "hook", "open": "pull"}
"""Skill -> primitive for an articulated target."""


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
    policy_sources: Sequence[Artifacts] | None = None
    """Folders whose trained stage policies run, searched in order (a training run, then the task version, say);
    None: the task version's own."""
    use_policies: bool = True
    """Run trained policies when present (False: always the scripted primitives)."""
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
            self.motion = ArmHandMotion(u, self.config.max_arm_step_rad, self.config.settle_steps)
            self._policies: dict[str, StagePolicy] = {}
        self.held: str | None = None
        self.carried = False
        self.logs: list[StageLog] = []
        self._plan: GraspPlan | None = None
        self._handles = HandlePrimitives(self.motion)
        self.stage_index = -1
        """Index of the stage being executed (-1 before the first)."""
        self.finished = False
        """True once every stage (up to ``stop_before``) ran without an ExecutionError."""
        self._actions = self._episode()

    def act(self, env: gym.Env, obs) -> np.ndarray | None:
        before = self.motion.steps
        action = next(self._actions, None)
        if self.logs:
            self.logs[-1].steps += self.motion.steps - before
        return action

    # ------------------------------------------------------------------ dispatch
    def primitive(self, stage) -> str:
        """The primitive that runs ``stage`` (module docstring); ExecutionError when there is none."""
        if stage.target is None:
            raise ExecutionError(f"stage {stage.name!r} has no target object: the executor cannot act on it")
        articulated = stage.target in self._env.articulations
        table = ARTICULATED_PRIMITIVES if articulated else RIGID_PRIMITIVES
        if stage.skill not in table:
            kind = "an articulated" if articulated else "a rigid"
            raise ExecutionError(f"stage {stage.name!r}: the executor has no primitive for skill {stage.skill!r} on "
                                 f"{kind} target ({stage.target!r}); skills it runs there: {sorted(table)}")
        return table[stage.skill]

    def _policy_files(self, stage) -> PolicyFiles | None:
        learned = stage.method == "RL" or self.policy_stages == "all"
        if not (learned and self.use_policies):
            return None
        sources = self.policy_sources
        if sources is None:
            sources = [self._env.task.artifacts] if self._env.task is not None else []
        return next((f for f in (s.policy(stage.name) for s in sources) if f is not None), None)

    # ------------------------------------------------------------------ episode
    def _episode(self) -> Iterator[np.ndarray]:
        spec = self._env.task_spec
        for i, stage in enumerate(spec.stages):
            if self.stop_before is not None and i >= self.stop_before:
                self.finished = True
                return
            self.stage_index = i
            files = self._policy_files(stage)
            if files is not None:
                self.logs.append(StageLog(stage.name, "policy", str(files.model)))
                log.info("stage %r (%s, %s): policy %s", stage.name, stage.skill, stage.control_joint, files.model)
                yield from self._run_policy(stage, files)
                continue
            prim = self.primitive(stage)
            self.logs.append(StageLog(stage.name, prim, "scripted"))
            log.info("stage %r (%s, %s): primitive %r%s", stage.name, stage.skill, stage.method, prim,
                     " (no trained policy)" if stage.method == "RL" else "")
            if prim in ARTICULATED_PRIMITIVES.values():
                yield from self._handles.run(prim, stage)
            else:
                yield from getattr(self, "_" + prim)(stage)
        self.finished = True
        # hold the last targets until the task reports success (or the episode ends)
        self.logs.append(StageLog("settle", "hold", "scripted"))
        yield from self.motion.hold(spec.success.hold_steps + 10)

    def _run_policy(self, stage, files: PolicyFiles) -> Iterator[np.ndarray]:
        """Run the stage's trained policy until the stage's success conditions hold or its horizon ends; then keep
        the bookkeeping its skill implies (what the hand holds, whether a handle is hooked)."""
        key = str(files.model)
        if key not in self._policies:
            self._policies[key] = StagePolicy.load(self._env.task, files)
        policy = self._policies[key]
        env = self._env
        info = policy.judge.evaluate(env)  # one evaluation per step: it feeds the next observation too
        done = False
        for _ in range(stage.horizon):
            target = policy.targets(env, policy.act(env, info))[0].cpu().numpy().astype(np.float64)
            yield self.motion.emit(target)
            info = policy.judge.evaluate(env)
            if bool(info["success"][0]):
                done = True
                break
        if not done:
            raise ExecutionError(f"policy of stage {stage.name!r} did not reach the stage's goal in {stage.horizon} "
                                 "steps")
        articulated = stage.target in env.articulations
        if stage.skill == "grasp" and articulated:
            self._handles.mark_hooked(stage.target)
        elif stage.skill == "grasp":
            self.held = stage.target
        elif stage.skill == "carry":
            self.carried = True
        elif stage.skill == "release":
            self.held = None

    # ------------------------------------------------------------------ primitives
    def _approach(self, stage) -> Iterator[np.ndarray]:
        m, name = self.motion, stage.target
        center, bottom, height, radius = m.object_geometry(name)
        m.avoid_objects(exclude=(name,))
        base = m.ik.base.p
        prefer = float(np.arctan2(center[1] - base[1], center[0] - base[0]))  # fingers pointing away from the base
        q0 = m.target()
        chosen: tuple[GraspPlan, np.ndarray] | None = None
        for plan in grasp_candidates(center, bottom, height, radius, prefer_yaw_rad=prefer):
            open_q = m.with_hand(q0, plan.open_hand)
            q_pre = m.ik.solve(plan.pregrasp, open_q, restarts=20, valid=m.collision.is_free)
            if q_pre is None or m.ik.solve(plan.palm, q_pre, restarts=0) is None:
                continue
            chosen = (plan, q_pre)
            break
        if chosen is None:
            raise ExecutionError(f"no reachable collision-free grasp of {name!r}")
        plan, q_pre = chosen
        self._plan = plan
        yield from m.move_arm(q_pre, hand=m.with_hand(q0, plan.open_hand))
        yield from m.cartesian(plan.palm.p - plan.pregrasp.p, self.config.descend_m_per_step)
        yield from m.settle()

    def _grasp(self, stage) -> Iterator[np.ndarray]:
        plan, m, c = self._plan, self.motion, self.config
        if plan is None:
            raise ExecutionError(f"stage {stage.name!r} grasps {stage.target!r} but no stage approached it")
        yield from m.ramp(m.with_hand(m.target(), plan.fingers), c.close_steps, guard=True)
        yield from m.ramp(m.with_hand(m.target(), plan.thumb), c.thumb_steps, guard=True)
        for _ in range(c.squeeze_steps):
            yield m.emit(m.with_hand(m.target(), plan.fingers | plan.thumb), guard=True)
        self.held = stage.target
        z0 = float(self._env.obj(stage.target).pose.p[0, 2])
        yield from m.cartesian(np.array([0.0, 0.0, c.lift_m]), c.lift_m_per_step, guard=True)
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
            yield from self.motion.cartesian(np.array([0.0, 0.0, need + 0.03 - risen]), c.lift_m_per_step, guard=True)

    def _carry(self, stage) -> Iterator[np.ndarray]:
        c, m = self.config, self.motion
        held, target = self.held, stage.target
        if held is None:
            raise ExecutionError(f"stage {stage.name!r} carries to {target!r} but the hand holds nothing")
        held_lo, held_hi = m.world_aabb(held)
        if held_lo[2] < self._env.table_height + 0.5 * c.lift_m:
            # still at the table (a trained grasp policy closes the hand but does not lift, unlike the scripted
            # grasp): lift straight up first, so the planned carry never drags the object across the table
            z0 = float(self._env.obj(held).pose.p[0, 2])
            yield from m.cartesian(np.array([0.0, 0.0, c.lift_m]), c.lift_m_per_step, guard=True)
            risen = float(self._env.obj(held).pose.p[0, 2]) - z0
            if risen < 0.5 * c.lift_m:
                raise ExecutionError(f"{held!r} slipped when lifted for the carry (rose {risen:.3f} m of "
                                     f"{c.lift_m:.3f} m)")
            held_lo, held_hi = m.world_aabb(held)
        t_center = m.object_geometry(target)[0]
        t_hi = m.world_aabb(target)[1]
        obj_p = (held_lo + held_hi) / 2
        goal_center = np.array([t_center[0], t_center[1], t_hi[2] + c.carry_clearance_m + (obj_p[2] - held_lo[2])])
        q_now = m.target()
        palm = m.ik.fk(q_now)
        goal = sapien.Pose(palm.p + (goal_center - obj_p), palm.q)
        # the held object moves with the palm: plan with it attached, against every other object (the target too)
        m.avoid_objects(exclude=(held,))
        m.collision.attach(*self._object_spheres(held_lo, held_hi), q_now)
        try:
            q_goal = m.ik.solve(goal, q_now, restarts=20, valid=m.collision.is_free)
            if q_goal is None:
                raise ExecutionError(f"no reachable collision-free pose holding {held!r} above {target!r}")
            yield from m.move_arm(q_goal)
        finally:
            m.collision.detach()
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
        m = self.motion
        t = m.with_hand(m.target(), OPEN_HAND | {j: 0.0 for j in ("THJ3", "THJ1", "THJ0")})
        yield from m.ramp(t, self.config.release_steps)
        self.held = None
        yield from m.cartesian(np.array([0.0, 0.0, 0.05]), 0.01)


__all__ = ["ARTICULATED_PRIMITIVES", "RIGID_PRIMITIVES", "ExecutionError", "ExecutorConfig", "StageExecutor",
           "StageLog"]
