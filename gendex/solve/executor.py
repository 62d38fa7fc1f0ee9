"""Stage executor: runs a task's stages in spec order, each by the primitive its skill names.

Every stage declares a ``skill`` (:data:`gendex_envs.spec.SKILLS`) and a ``target``; the primitive follows from the
skill and from what the target is:

==========  ===================  ==============================================  ==================================
skill       rigid target         articulated target a stage grasps               articulated target no stage grasps
                                 (:mod:`gendex.solve.articulated`)               (:mod:`gendex.solve.press`)
==========  ===================  ==============================================  ==================================
reach       ``approach``         ``approach_handle``                             ``approach_press``
grasp       ``grasp``            ``hook``
lift        ``lift``
carry       ``carry``
place       ``place``
release     ``release``
push        ``push``
open                             ``pull``: a door's arc, a drawer's slide        ``press`` towards open
close                            ``shut``: the same hook, run back to closed     ``press`` towards closed
turn                                                                             ``press`` as ``joint_open`` points
==========  ===================  ==============================================  ==================================

The rigid primitives (:mod:`gendex.solve.rigid`) synthesize grasps over the object's geometry, rank them by a
physics trial in a private copy of the scene, and grasp again once after a slip. A skill without a primitive for
its target raises :class:`~gendex_envs.errors.ExecutionError` naming what exists.

Every ``ExecutionError`` that ends an attempt carries its cause (:data:`~gendex_envs.errors.FAILURE_CAUSES`) and
the stage and skill it happened in; ``gendex collect`` counts them.

The executor knows the episode's step limit and the steps used (:meth:`ArmHandMotion.set_budget`); before each
stage it tells the motions how many steps the stages after it usually take (:data:`SKILL_STEPS`), and a motion that
would not leave them runs faster, up to :data:`~gendex.solve.motion.MAX_PACE` times its nominal speed.

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

from gendex.solve.articulated import HOOK_OPEN, HandlePrimitives
from gendex.solve.flip import flip
from gendex.solve.grasp import GraspPlan
from gendex.solve.hang import hang
from gendex.solve.motion import ArmHandMotion
from gendex.solve.policy import StagePolicy
from gendex.solve.pour import pour
from gendex.solve.press import PressPrimitives
from gendex.solve.rigid import CARRY_M_PER_STEP, RigidConfig, RigidPrimitives
from gendex.solve.set_down import (
    POINT,
    free_spot,
    holds_condition,
    holds_height,
    holds_spot,
    placed_condition,
    set_down_point,
)
from gendex.solve.twist import TWIST_PRIMITIVES, TwistPrimitives
from gendex.solve.wipe import wipe
from gendex_envs.errors import ExecutionError
from gendex_envs.spec import GOAL_TARGET
from gendex_envs.success import SET_DOWN_CONDITIONS
from gendex_envs.task_version import Artifacts, PolicyFiles
from gendex_envs.wrappers import time_limit

log = logging.getLogger(__name__)

RIGID_PRIMITIVES = {"reach": "approach", "grasp": "grasp", "lift": "lift", "carry": "carry", "place": "place",
                    "release": "release", "push": "push", "wipe": "wipe", "hang": "hang",
                    "pour": "pour", "flip": "flip"}
"""Skill -> primitive for a rigid target."""
TO_A_PLACE = ("carry", "place")
"""Skills whose target is where the held object goes: the rigid primitives, also when that is an articulated object
(a lidded box whose lid is open: carried over its body's box)."""
DRAWER_CLEAR_M = 0.15
"""After letting go in a drawer the palm rises to this far over the drawer's walls: the fingers hang about 12 cm under
it, and fingers left in the bin caught its front wall on the way to its handle and pulled it out (2 of 8)."""
ARTICULATED_PRIMITIVES = {"reach": "approach_handle", "grasp": "hook", "open": "pull", "close": "shut"}
"""Skill -> primitive for an articulated target that a stage grasps (hooks by its handle)."""
PRESS_PRIMITIVES = {"reach": "approach_press", "open": "press", "close": "press", "turn": "press", "press": "press"}
"""Skill -> primitive for an articulated target that no stage grasps: the open hand pushes the moving part."""
SKILL_STEPS = {"reach": 60, "grasp": 55, "lift": 15, "carry": 50, "place": 30, "release": 15, "push": 90,
               "open": 50, "close": 50, "turn": 40, "press": 30, "twist": 500,
               "wipe": 200, "hang": 120, "pour": 160, "flip": 150}
"""Steps a stage of each skill usually takes at nominal speed (measured on the committed tasks; a release that
sets its object down first takes a place's more; a carry is estimated from how far it goes,
:data:`CARRY_EXTRA_STEPS`): what the stages after the current one are expected to need."""
SWING_WAIT_STEPS = 150
"""A mug let go on a peg swings there a while (2-5 s): where the task's success has a ``hung`` condition the final
hold goes on, at most this many steps, until the success conditions hold."""
CARRY_EXTRA_STEPS = 15
"""A level carry takes its length over :data:`~gendex.solve.rigid.CARRY_M_PER_STEP` plus about this many steps
(easing in and out, rising to the carry height)."""


@dataclass
class ExecutorConfig:
    """Arm motion limits and the rigid primitives' settings (control steps at 20 Hz)."""

    settle_steps: int = 2
    max_arm_step_rad: float = 0.06
    rigid: RigidConfig = field(default_factory=RigidConfig)


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
            self.rigid = RigidPrimitives(self.motion, self.config.rigid)
        self.rigid.reset()
        # the episode's own randomness (env.np_random follows the reset seed): the same seed plans the same paths
        self.motion.planner.reseed(int(u.np_random.integers(2**31)))
        self.carried = False
        self._points: dict[str, np.ndarray] = {}
        """Set-down points of ``placed`` conditions, by held object (:meth:`_point`)."""
        self.logs: list[StageLog] = []
        self._handles = HandlePrimitives(self.motion, hand_cover=self._hand_cover)
        self._presses = PressPrimitives(self.motion, self._hand_cover)
        self._twists = TwistPrimitives(self.rigid)
        limit = [n for n in (time_limit(env), getattr(u, "horizon", None)) if n is not None]
        self.motion.set_budget(min(limit) if limit else None, int(u.elapsed_steps[0]))
        self.stage_index = -1
        """Index of the stage being executed (-1 before the first)."""
        self.finished = False
        """True once every stage (up to ``stop_before``) ran without an ExecutionError."""
        self._actions = self._episode()

    def act(self, env: gym.Env, obs) -> np.ndarray | None:
        before = self.motion.steps
        try:
            action = next(self._actions, None)
        except ExecutionError as exc:  # say where it happened
            stage = self.current_stage
            if stage is not None and exc.stage is None:
                exc.stage, exc.skill = stage.name, stage.skill
            raise
        if self.logs:
            self.logs[-1].steps += self.motion.steps - before
        return action

    def _hand_cover(self, hand: dict[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Sphere cover (palm frame: centres, radii) of the hand at ``hand`` (default: opened flat for a press)."""
        cover = self.rigid.hand.spheres(HOOK_OPEN if hand is None else hand)
        return cover.centers, cover.radii

    @property
    def current_stage(self):
        """The spec of the stage being executed (None before the first and after the last)."""
        stages = self._env.task_spec.stages
        return stages[self.stage_index] if 0 <= self.stage_index < len(stages) and not self.finished else None

    @property
    def held(self) -> str | None:
        """The object the hand holds, if any."""
        return self.rigid.held

    @property
    def grasp_plan(self) -> GraspPlan | None:
        """The grasp the rigid primitives executed last."""
        return self.rigid.plan

    # ------------------------------------------------------------------ dispatch
    def primitive(self, stage) -> str:
        """The primitive that runs ``stage`` (module docstring); ExecutionError when there is none."""
        if stage.target is None:
            raise ExecutionError(f"stage {stage.name!r} has no target object: the executor cannot act on it",
                                 cause="unsupported", stage=stage.name, skill=stage.skill)
        if stage.target not in self._env.articulations or stage.skill in TO_A_PLACE:
            table, kind = RIGID_PRIMITIVES, "a rigid"
        elif any(s.skill == "twist" and s.target == stage.target for s in self._env.task_spec.stages):
            table, kind = TWIST_PRIMITIVES, "a twisted articulated"
        elif self._grasped(stage.target):
            table, kind = ARTICULATED_PRIMITIVES, "a hooked articulated"
        else:
            table, kind = PRESS_PRIMITIVES, "an ungrasped articulated"
        if stage.skill not in table:
            raise ExecutionError(f"stage {stage.name!r}: the executor has no primitive for skill {stage.skill!r} on "
                                 f"{kind} target ({stage.target!r}); skills it runs there: {sorted(table)}",
                                 cause="unsupported", stage=stage.name, skill=stage.skill)
        return table[stage.skill]

    def _reserve(self, index: int) -> int:
        """Steps the stages after stage ``index`` are expected to take (:data:`SKILL_STEPS`; a skill not listed: its
        horizon; a carry: from how far the object it carries is from its target now), and the success's hold."""
        env, spec = self._env, self._env.task_spec
        total = spec.success.hold_steps
        for k in range(index + 1, len(spec.stages)):
            stage = spec.stages[k]
            steps = SKILL_STEPS.get(stage.skill, stage.horizon)
            held = next((s.target for s in reversed(spec.stages[:k]) if s.skill == "grasp"), None)
            if stage.skill == "carry" and held in env.objects and stage.target in env.objects:
                d = env.obj_pose(held).p[0, :2] - env.obj_pose(stage.target).p[0, :2]
                steps = int(float(d.norm()) / CARRY_M_PER_STEP) + CARRY_EXTRA_STEPS
            if stage.skill == "release" and self._set_down_on(stage, stage.target) is not None:
                steps += SKILL_STEPS["place"]
            total += steps
        return total

    def _grasped(self, name: str) -> bool:
        """Whether a stage of the task grasps ``name`` (an articulated target: hooks its handle)."""
        return any(s.skill == "grasp" and s.target == name for s in self._env.task_spec.stages)

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
            self.motion.reserve = self._reserve(i)
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
            if prim in TWIST_PRIMITIVES.values():
                yield from self._twists.run(prim, stage)
            elif prim in PRESS_PRIMITIVES.values():
                yield from self._presses.run(prim, stage)
            elif prim in ARTICULATED_PRIMITIVES.values():
                yield from self._handles.run(prim, stage)
            else:
                yield from getattr(self, "_" + prim)(stage)
        self.finished = True
        # hold the last targets until the task reports success (or the episode ends)
        self.logs.append(StageLog("settle", "hold", "scripted"))
        yield from self.motion.hold(spec.success.hold_steps + 10)
        if any(c.type == "hung" for c in spec.success.conditions):
            for _ in range(SWING_WAIT_STEPS):
                if bool(self._env.spec_success()[0]):
                    break
                yield from self.motion.hold(1)
            yield from self.motion.hold(spec.success.hold_steps)

    def _run_policy(self, stage, files: PolicyFiles) -> Iterator[np.ndarray]:
        """Run the stage's trained policy until the stage's success conditions hold (for the steps its env counts
        them, :attr:`~gendex.solve.policy.StagePolicy.hold_steps`) or its horizon ends; then keep the bookkeeping
        its skill implies (what the hand holds, whether a handle is hooked)."""
        key = str(files.model)
        if key not in self._policies:
            self._policies[key] = StagePolicy.load(self._env.task, files)
        policy = self._policies[key]
        env = self._env
        info = policy.judge.evaluate(env)  # one evaluation per step: it feeds the next observation too
        done, streak = False, 0
        for _ in range(stage.horizon):
            target = policy.targets(env, policy.act(env, info))[0].cpu().numpy().astype(np.float64)
            yield self.motion.emit(target)
            info = policy.judge.evaluate(env)
            streak = streak + 1 if bool(info["success"][0]) else 0
            if streak >= policy.hold_steps:
                done = True
                break
        if not done:
            raise ExecutionError(f"policy of stage {stage.name!r} did not reach the stage's goal in {stage.horizon} "
                                 "steps", cause="target_not_reached")
        articulated = stage.target in env.articulations
        if stage.skill == "grasp" and articulated:
            self._handles.mark_hooked(stage.target)
        elif stage.skill == "grasp":
            self.rigid.held = stage.target
        elif stage.skill == "carry":
            self.carried = True
        elif stage.skill == "release":
            self.rigid.held = None

    # ------------------------------------------------------------------ primitives
    def _approach(self, stage) -> Iterator[np.ndarray]:
        yield from self.rigid.approach(stage.target, self._grip_conditions(stage.target),
                                       set_on=self._set_on(stage.target))

    def _set_on(self, name: str) -> str | None:
        """The object a later release sets ``name`` down in, on or next to (the target of an ``inside``, ``over`` or
        ``near`` condition on ``name``), if any: a tall object that swung over in the hand catches a container's rim,
        or lands on its side and topples off a board, so a grasp that lets it swing over too far to fit the target is
        taken only when no trial does better (:meth:`~gendex.solve.rigid.RigidPrimitives.choose_grasp`)."""
        spec = self._env.task_spec
        conds = (*spec.success.conditions, *(c for s in spec.stages[self.stage_index + 1:] for c in s.success or ()))
        return next((c.target for c in conds if c.type in (*SET_DOWN_CONDITIONS, "wiped", "hung") and c.object == name
                     and not c.negate
                     and c.target in self._env.objects and c.target not in self._env.articulations), None)

    def _grip_conditions(self, name: str) -> tuple:
        """The ``grasped`` conditions the next grasp stage on ``name`` declares: a grasp is only chosen if its trial
        meets them too (how many fingers, palm force), so the stage's success follows from the grasp."""
        spec = self._env.task_spec
        for later in spec.stages[self.stage_index + 1:]:
            if later.skill == "grasp" and later.target == name:
                return tuple(c for c in later.success or () if c.type == "grasped" and c.object == name
                             and not c.negate)
        return ()

    def _grasp(self, stage) -> Iterator[np.ndarray]:
        """Grasp and lift; only to the carry's height when a carry of the object comes next."""
        stages = self._env.task_spec.stages
        after = stages[self.stage_index + 1] if self.stage_index + 1 < len(stages) else None
        lift_to = None
        if after is not None and after.skill == "carry" and after.target in self._env.objects \
                and after.target != stage.target:
            lift_to = self.rigid.carry_bottom(after.target)
        yield from self.rigid.grasp(stage.target, lift_to)

    def _lift(self, stage) -> Iterator[np.ndarray]:
        heights = [cond.min_height_m for cond in self._env.task_spec.success.conditions
                   if cond.type == "lifted" and cond.object == stage.target]
        yield from self.rigid.lift(stage.target, max(heights) if heights else self.config.rigid.motion.lift_m)

    def _point(self, stage, held: str | None) -> np.ndarray | None:
        """The table point a ``placed`` condition on ``held`` wants it set down at (:mod:`gendex.solve.set_down`),
        fixed when first asked for in an episode (the target does not move under the carry), else None."""
        if held is None:
            return None
        c = placed_condition(self._env, held, stage)
        bin_ = None if c is not None else holds_condition(self._env, held, stage)
        if c is None and bin_ is None:
            return None
        if self._points.get(held) is None:
            self._points[held] = set_down_point(self._env, c) if c is not None else holds_spot(self._env, bin_)[:2]
        return self._points[held]

    def _floor(self, stage, held: str | None) -> float | None:
        """World z of the floor a held object is set down on at its :meth:`_point`: a drawer's bin's for an
        ``inside`` condition with a joint, else None (the table)."""
        c = None if held is None else holds_condition(self._env, held, stage)
        return None if c is None else float(holds_spot(self._env, c)[2])

    def _carry(self, stage) -> Iterator[np.ndarray]:
        yield from self.rigid.carry(stage.target, self._point(stage, self.rigid.held))
        self.carried = True

    def _place(self, stage) -> Iterator[np.ndarray]:
        yield from self.rigid.place(stage.target, self._point(stage, self.rigid.held))

    def _push(self, stage) -> Iterator[np.ndarray]:
        """Push the target to where a ``near`` condition on it (the stage's, else the task's) wants it."""
        env = self._env
        conds = [c for c in (*(stage.success or ()), *env.task_spec.success.conditions)
                 if c.type == "near" and c.object == stage.target and not c.negate]
        if not conds:
            raise ExecutionError(f"stage {stage.name!r} pushes {stage.target!r} but no near condition says where to",
                                 cause="unsupported")
        c = conds[0]
        goal = env.goal_pos if c.target == GOAL_TARGET else env.obj_pose(c.target).p
        yield from self.rigid.push(stage.target, goal[0, :2].cpu().numpy().astype(np.float64), c.max_dist_m)

    def _set_down_on(self, stage, held: str | None) -> str | None:
        """The object an ``inside``, ``over`` or ``near`` condition (the stage's, else the task's) wants ``held`` in, on
        or by (a ``near`` on the goal point sets nothing down: pushes use it)."""
        conds = (*(stage.success or ()), *self._env.task_spec.success.conditions)
        return next((c.target for c in conds if c.type in SET_DOWN_CONDITIONS and c.object == held and not c.negate
                     and c.target in self._env.objects and c.target not in self._env.articulations), None)

    def _wipe(self, stage) -> Iterator[np.ndarray]:
        """Wipe the target (a spill) with the held sponge (:mod:`gendex.solve.wipe`)."""
        yield from wipe(self.rigid, stage.target)

    def _hang(self, stage) -> Iterator[np.ndarray]:
        """Hang the held mug by its handle on a peg of the target (:mod:`gendex.solve.hang`)."""
        yield from hang(self.rigid, stage.target)

    def _pour(self, stage) -> Iterator[np.ndarray]:
        """Tip the held vessel over the target until what it holds falls in; stand it up (:mod:`gendex.solve.pour`)."""
        yield from pour(self.rigid, stage.target)

    def _flip(self, stage) -> Iterator[np.ndarray]:
        """Turn the held target upside down and set it down on its top (:mod:`gendex.solve.flip`)."""
        yield from flip(self.rigid, stage.target)

    def _release(self, stage) -> Iterator[np.ndarray]:
        """Let go; an object held over what a condition wants it in, on or by is first set down there (a dropped tall
        object topples out of a bowl; a dropped ball bounces off a flat board)."""
        held = self.rigid.held
        onto = self._set_down_on(stage, held)
        point = self._point(stage, held)
        if point is not None and self.rigid.placed_on != POINT:
            yield from self.rigid.place(held, point, floor=self._floor(stage, held))
        elif held is not None and onto is not None and self.rigid.placed_on != onto:
            inside = any(c.type in ("inside", "near") and c.object == held and c.target == onto
                         for c in (*(stage.success or ()), *self._env.task_spec.success.conditions))
            yield from self.rigid.place(onto, at=free_spot(self._env, onto, held) if inside else None)
        yield from self.rigid.release()
        drawer = None if held is None else holds_condition(self._env, held, stage)
        if drawer is not None:  # out of the drawer before anything else: fingers left in it catch its front
            m = self.rigid.m
            top = float(holds_spot(self._env, drawer)[2]) + float(holds_height(self._env, drawer))
            up = top + DRAWER_CLEAR_M - float(m.ik.fk(m.target()).p[2])
            if up > 0:
                yield from m.cartesian(np.array([0.0, 0.0, up]), 0.01, partial=True)


__all__ = ["ARTICULATED_PRIMITIVES", "PRESS_PRIMITIVES", "RIGID_PRIMITIVES", "SKILL_STEPS", "ExecutionError",
           "ExecutorConfig", "StageExecutor", "StageLog"]
