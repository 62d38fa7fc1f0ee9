"""Rank grasp candidates by trying them: a short physics trial in a private copy of the scene.

Kinematics says whether a grasp can be reached; only physics says whether it holds. :class:`GraspTrials` keeps a
second env of the same task (no observations, no rewards) beside the one being solved. A trial copies the solved
env's full state into it (every body, joint and controller target), puts the arm at the candidate's pre-grasp pose
with the hand opened, and runs exactly the actions the executor would: the straight approach, the guarded closing
ramps, the squeeze, the executor's lift (``GraspMotion.lift_m``) and a hold of :data:`TRIAL_HOLD_STEPS` control
steps (1 s). The candidate holds when the object rose at least :data:`HELD_FRACTION` of the lift, ends the hold
still touched by the thumb and a finger, and is not moving. The solved env is never touched, so trials leave its
history — and the episode being recorded — exactly as they were.

The trial env's own history matters too: a PhysX scene keeps contact caches and solver warm starts across
``set_state``, so a trial's outcome depended on every trial run in that scene before it, in earlier episodes as well
(a collection of 204 PutAppleBowl-v1 attempts in one process failed seed 71, which succeeds in a fresh process).
:meth:`GraspTrials.renew` rebuilds the trial scene; the executor calls it at every episode's start, so an episode's
trials depend only on that episode.

A grasp that is a whole sequence of its own (a flat ringed tool's, dragged to the table's edge first:
:mod:`gendex.solve.edge_trial`) is tried whole from where the robot is (:meth:`GraspTrials.rehearse`), each in a
rebuilt scene.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
import sapien
import torch

from gendex.solve.grasp import GraspPlan
from gendex.solve.motion import ArmHandMotion
from gendex.solve.shape import ObjectShape, PosedShape
from gendex_envs.errors import ExecutionError
from gendex_envs.spec import ConditionSpec
from gendex_envs.success import conditions_hold

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.task_env import TaskEnv

log = logging.getLogger(__name__)

EASE_STEPS = 16
EASE_FRACTION = 0.85
"""Grip easing (:func:`ease_grip`): steps at most, and the part of the finger targets' lead over the measured angles
kept each step."""
MIN_LIFT_M = 0.08
"""The least a grasp lifts its object (a slip shows as the object rising less than half of the lift, or of this when
the arm's reach cut the lift shorter)."""
TRIAL_HOLD_STEPS = 20
"""1 s at 20 Hz."""
HELD_FRACTION = 0.8
"""A trial holds when the object rose at least this fraction of the lift by the end of the hold."""
STILL_M_PER_S = 0.15
"""...and moves slower than this at the end of the hold."""
FORCE_MARGIN = 0.6
"""Fraction of a required condition's force ceiling a trial must stay under (:func:`with_margin`)."""
UPRIGHT_SPREAD = 1.25
"""A held object whose footprint grew by more than this factor in the trial (:func:`spread`) swung over in the
hand: unless it still fits what it is set down in or on next (:func:`fits_on`), a poor grasp for that
(:meth:`GraspTrials.trial`'s caller prefers one that keeps it upright)."""

SHOVED_M = 0.03
"""A held trial whose closing hand pushed the object further than this across the table held on the edge of holding:
the robot's own approach, not the trial's teleport to the pre-grasp pose, may push it out of reach (a Rubik's cube's
top grasps pushed it 1-4 cm; :attr:`TrialResult.shoved`; the caller keeps such a grasp as a fallback)."""

FIT_FRACTION = 0.8
"""A held object fits what it is set down in or on when its footprint's diagonal is at most this fraction of that
object's narrower side (:func:`fits_on`; the rest is the container's wall and the carry's aim)."""


@dataclass(frozen=True)
class GraspMotion:
    """Speeds of a grasp, shared by the executor and its trials (control steps at 20 Hz)."""

    approach_m_per_step: float = 0.01
    squeeze_steps: int = 6
    lift_m: float = 0.15
    """The grasp primitive lifts this far right after closing (and checks that the object came along)."""
    lift_m_per_step: float = 0.006
    settle_steps: int = 2
    rest_rad_s: float = 0.05
    """The approach starts once no arm joint turns faster than this (a trial starts at rest; an arm that arrives
    still swinging at 0.5 rad/s pushed a Rubik's cube out of a top grasp that held in its trial)..."""
    rest_steps: int = 10
    """...or after this many steps."""


def close_hand(m: ArmHandMotion, plan: GraspPlan, speed: GraspMotion) -> Iterator[np.ndarray]:
    """The guarded closing ramps of ``plan``, then the squeeze (targets held at the closed shape)."""
    for targets, steps in plan.closing:
        yield from m.ramp(m.with_hand(m.target(), targets), steps, guard=True)
    closed = plan.closed_hand
    for _ in range(speed.squeeze_steps):
        yield m.emit(m.with_hand(m.target(), closed), guard=True)


def rose_with_hand(risen: float, palm_rise: float) -> bool:
    """A grasp's own lift (an edge grasp's, cut short where the arm's reach ends) kept its object: the object rose
    ``risen`` (m), at least half as far as the palm did (``palm_rise``), and half of :data:`MIN_LIFT_M` at least
    (else a lift the arm barely started would pass any object that stayed on the table)."""
    return risen >= 0.5 * max(palm_rise, MIN_LIFT_M)


def approach(m: ArmHandMotion, plan: GraspPlan, speed: GraspMotion) -> Iterator[np.ndarray]:
    """From rest (:attr:`GraspMotion.rest_rad_s`), the straight move from the pre-grasp pose to the grasp pose,
    then a short settle."""
    yield from m.come_to_rest(speed.rest_rad_s, speed.rest_steps)
    yield from m.cartesian(plan.palm.p - plan.pregrasp.p, speed.approach_m_per_step)
    yield from m.hold(speed.settle_steps)


def ease_grip(m: ArmHandMotion, require: tuple[ConditionSpec, ...]) -> Iterator[np.ndarray]:
    """When ``require`` (a grasp stage's own conditions) fails only by a palm-force ceiling (fingers pulling the
    object into the palm too hard), ease the finger targets towards the measured angles a step at a time until it
    holds (at most :data:`EASE_STEPS`)."""
    require = tuple(c for c in require if c.max_palm_force_n is not None)
    loose = tuple(replace(c, max_palm_force_n=None) for c in require)
    for _ in range(EASE_STEPS if require else 0):
        if bool(conditions_hold(m.env, require)[0]):
            return
        if not bool(conditions_hold(m.env, loose)[0]):
            return  # not a matter of force: easing would only loosen a grasp that already fails otherwise
        t, q = m.target(), m.qpos()
        t[m.hand] = q[m.hand] + EASE_FRACTION * (t[m.hand] - q[m.hand])
        yield m.emit(t)


def with_margin(c: ConditionSpec) -> ConditionSpec:
    """Condition ``c`` with its force ceiling lowered to :data:`FORCE_MARGIN` of itself: the executed grasp starts
    from a pose the arm reached by its own motion, not the trial's teleport, and must still meet the ceiling."""
    if c.max_palm_force_n is None:
        return c
    return replace(c, max_palm_force_n=FORCE_MARGIN * c.max_palm_force_n)


def spread(shape: ObjectShape, before: np.ndarray, after: np.ndarray) -> float:
    """How much wider the object's footprint seen from above is at rotation ``after`` [3, 3] than at ``before``
    (ratio of the diagonals of the smallest enclosing rectangles; a turn about the vertical changes nothing). A tall
    box swung 45 degrees in the hand spreads about 2x; a ball does not spread however it turns."""

    def diagonal(rot: np.ndarray) -> float:
        m = np.eye(4)
        m[:3, :3] = rot
        f = shape.posed(m).footprint()
        return float(np.hypot(f.length, f.width))

    return diagonal(after) / max(diagonal(before), 1e-6)


def fits_on(held: PosedShape, target: PosedShape) -> Callable[[float], bool]:
    """A test of a trial's footprint :func:`spread`: True when ``held``, swung that much, still fits ``target`` seen
    from above (its footprint's diagonal within :data:`FIT_FRACTION` of ``target``'s narrower side). A bottle caged
    25 degrees over still fits a large bowl; a sugar box swung 45 degrees does not fit a small one."""
    f, t = held.footprint(), target.footprint()
    diagonal, room = float(np.hypot(f.length, f.width)), FIT_FRACTION * min(t.length, t.width)
    return lambda s: s * diagonal <= room


@dataclass(frozen=True)
class TrialResult:
    plan: GraspPlan | None
    """The grasp tried (None where a rehearsed grasp, :meth:`GraspTrials.rehearse`, failed before planning it)."""
    held: bool
    rise_m: float
    """How far the object rose by the end of the hold."""
    touching: bool
    """Thumb and at least one finger touch the object at the end."""
    speed_m_s: float
    steps: int
    why: str = ""
    spread: float = 1.0
    """How much the object's footprint grew by the end of the hold (:func:`spread`; 1.0 when not measured)."""
    pushed_m: float = 0.0
    """How far the closing hand pushed the object across the table (0.0 when not measured)."""

    @property
    def shoved(self) -> bool:
        """The closing hand pushed the object further than :data:`SHOVED_M`."""
        return self.pushed_m > SHOVED_M

    @property
    def upright(self) -> bool:
        """The object kept its footprint (within :data:`UPRIGHT_SPREAD`) while held."""
        return self.spread <= UPRIGHT_SPREAD

    def __str__(self) -> str:
        verdict = "held" if self.held else f"failed ({self.why})"
        tilt = "" if self.upright else f", footprint spread {self.spread:.2f}x"
        tilt += f", pushed {self.pushed_m:.3f} m while closing" if self.shoved and self.held else ""
        what = self.plan or "a grasp that failed before its plan"
        return f"{what}: {verdict}, rose {self.rise_m:.3f} m in {self.steps} steps{tilt}"


class GraspTrials:
    """Physics trials of grasps of objects in ``env``'s scene (see the module docstring)."""

    def __init__(self, env: TaskEnv, speed: GraspMotion | None = None, max_arm_step_rad: float = 0.06):
        from gendex_envs.task_env import TaskEnv

        self.main = env
        kwargs = dict(control_mode="pd_joint_pos", control_joint="both", obs_mode="none", reward_mode="none",
                      sim_backend="physx_cpu", render_mode=None, render_backend="none", num_envs=1)
        if env.task is not None:
            self.sim = TaskEnv(task=env.task, **kwargs)
        else:
            self.sim = TaskEnv(task_spec=env.task_spec, **kwargs)
        self.sim.reset(seed=0)
        self.motion = ArmHandMotion(self.sim, max_arm_step_rad, settle_steps=2)
        self.speed = speed or GraspMotion()
        self.steps = 0
        """Simulated control steps of every trial so far (none of them are the episode's)."""
        self._stale = False
        self._steps_at_build = 0

    def renew(self) -> None:
        """Have the next trial run in a rebuilt scene (fresh PhysX caches), so that it does not depend on the trials
        before. The rebuild (about 0.7 s) waits for that trial: an episode that tries no grasp pays nothing."""
        self._stale = self.steps > self._steps_at_build  # stepped since it was built

    def _fresh_scene(self) -> None:
        if self._stale:
            self.sim.reset(seed=0, options={"reconfigure": True})
            self._stale = False
            self._steps_at_build = self.steps

    def close(self) -> None:
        self.sim.close()

    def trial(self, plan: GraspPlan, q_pre: np.ndarray, name: str, require: tuple[ConditionSpec, ...] = (),
              shape: ObjectShape | None = None) -> TrialResult:
        """Try ``plan`` on object ``name`` from the pre-grasp joint vector ``q_pre`` [J] (arm and opened hand);
        ``require``: conditions (the task's own ``grasped`` ones) that must hold at the end as well; ``shape``: the
        object's geometry, to measure how far it swung over in the hand (:attr:`TrialResult.spread`)."""
        self._fresh_scene()
        sim, m, speed = self.sim, self.motion, self.speed
        sim.set_state(self.main.get_state())
        q = torch.as_tensor(q_pre[None], dtype=torch.float32)
        sim.agent.robot.set_qpos(q)
        sim.agent.robot.set_qvel(torch.zeros_like(q))
        sim.agent.set_controller_state({"target_qpos": q.clone()})
        obj = sim.obj(name)
        z0 = float(obj.pose.p[0, 2])
        xy0 = obj.pose.p[0, :2].cpu().numpy()
        rot0 = _rotation(obj.pose.q[0])
        before, why = self.steps, ""
        try:
            self._play(approach(m, plan, speed))
            self._play(close_hand(m, plan, speed))
            pushed = float(np.linalg.norm(obj.pose.p[0, :2].cpu().numpy() - xy0))
            self._play(m.cartesian(np.array([0.0, 0.0, speed.lift_m]), speed.lift_m_per_step, guard=True))
            self._play(ease_grip(m, tuple(map(with_margin, require))))  # as the executor's grasp does after its lift
            self._play(m.hold(TRIAL_HOLD_STEPS))
        except ExecutionError as exc:  # an IK failure mid-motion is a failed trial, not a crash
            why = f"motion failed: {exc}"
            pushed = 0.0
        steps = self.steps - before
        rise = float(obj.pose.p[0, 2]) - z0
        touching, speed_now = self._grip(name)
        meets = bool(conditions_hold(sim, tuple(map(with_margin, require)))[0]) if require else True
        held = (not why and rise >= HELD_FRACTION * speed.lift_m and touching and speed_now < STILL_M_PER_S
                and meets)
        if not held and not why:
            why = (f"rose {rise:.3f} m" if rise < HELD_FRACTION * speed.lift_m else
                   "not touched by the thumb and a finger" if not touching else
                   f"still moving {speed_now:.2f} m/s" if speed_now >= STILL_M_PER_S else
                   "the grasp stage's own conditions do not hold")
            if pushed > 0.02:
                why += f", pushed {pushed:.3f} m while closing"
        grew = 1.0 if shape is None else spread(shape, rot0, _rotation(obj.pose.q[0]))
        result = TrialResult(plan, held, rise, touching, speed_now, steps, why, grew, pushed)
        log.debug("grasp trial: %s", result)
        return result

    def rehearse(self, main: ArmHandMotion, name: str,
                 run: Callable[[ArmHandMotion], Generator[np.ndarray, None, tuple[GraspPlan, float]]]) -> TrialResult:
        """Try a whole grasp of object ``name``, from where the robot is, in a rebuilt scene set to the state of
        ``main``'s env now (``main``: the solved env's motion; its episode budget and its planner's searches carry
        over, so that the trial paces and plans as the robot would). ``run(motion)`` yields the grasp's actions and
        returns its plan and how far the palm rose; a hold of :data:`TRIAL_HOLD_STEPS` follows. It held when the
        object rose with the hand (:func:`rose_with_hand`, the executor's own judgement of a grasp's own lift), ends
        touched by the thumb and a finger, and is not moving."""
        self.renew()
        self._fresh_scene()
        sim, m = self.sim, self.motion
        sim.set_state(self.main.get_state())
        left = main.left()
        m.deadline, m.reserve = (None if left is None else m.steps + left), main.reserve
        m.planner.follow(main.planner)
        m.avoid_objects(exclude=(name,))
        obj = sim.obj(name)
        z0 = float(obj.pose.p[0, 2])
        plan, lifted, why, before = None, 0.0, "", self.steps
        try:
            plan, lifted = self._play(run(m))
            self._play(m.hold(TRIAL_HOLD_STEPS))
        except ExecutionError as exc:
            why = f"{exc.cause}: {exc}"
        finally:
            m.deadline, m.reserve = None, 0  # the grasp trials after it are not paced by this episode's budget
        steps = self.steps - before
        rise = float(obj.pose.p[0, 2]) - z0
        touching, speed_now = self._grip(name)
        held = not why and rose_with_hand(rise, lifted) and touching and speed_now < STILL_M_PER_S
        if not held and not why:
            why = (f"rose {rise:.3f} m as the palm rose {lifted:.3f} m" if not rose_with_hand(rise, lifted) else
                   "not touched by the thumb and a finger" if not touching else f"still moving {speed_now:.2f} m/s")
        result = TrialResult(plan, held, rise, touching, speed_now, steps, why)
        log.debug("rehearsed grasp: %s", result)
        return result

    def _play(self, actions: Iterator[np.ndarray]) -> object:
        """Step the trial scene through ``actions`` (counted in :attr:`steps`, an error's partial run too); returns
        what the generator returned."""
        while True:
            try:
                action = next(actions)
            except StopIteration as done:
                return done.value
            self.sim.step(torch.as_tensor(action[None]))
            self.steps += 1

    def _grip(self, name: str) -> tuple[bool, float]:
        """Whether the thumb and at least one finger touch ``name`` in the trial scene, and its speed (m/s)."""
        forces = self.sim.hand_forces(name)[0].cpu().numpy()
        speed = float(torch.linalg.norm(self.sim.obj(name).linear_velocity[0]))
        return bool(forces[0] > 0.3 and np.any(forces[1:5] > 0.3)), speed


def _rotation(q: torch.Tensor) -> np.ndarray:
    """3x3 rotation of a wxyz quaternion."""
    return sapien.Pose([0.0, 0.0, 0.0], q.cpu().numpy().astype(np.float64)).to_transformation_matrix()[:3, :3]
