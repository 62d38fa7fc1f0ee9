"""The twist primitives: unscrew a cap (or screw it on) about its own axis, a slice at a time, regrasping between
slices, as a person opens a jar.

Run by :class:`~gendex.solve.executor.StageExecutor` for an articulated target that a stage with skill ``twist``
acts on (:data:`TWIST_PRIMITIVES`):

- ``approach_twist`` — grasp synthesis on the cap's own collision shape (the container under it and every other
  object kept clear): the first *top* grasp (palm on the cap, fingers curled over its far rim, thumb on the near one)
  that the arm reaches without collision; a planned arm motion to its pre-grasp pose, then the straight approach.
- ``twist`` — cycles of: close the grasp (guarded ramps and squeeze); turn the palm :data:`TWIST_SLICE_RAD` about
  the cap's axis through its top centre (the cap turns with the grip); open the hand with the thumb swung out
  (the top grasp's thumb hooks under the rim: opened to its pre-shape it dragged the cap back); lift
  :data:`TWIST_LIFT_M` along the axis; turn back; come down onto the cap again. Until the joint is past the task's
  fraction (a margin beyond it), or :data:`TWIST_MAX_CYCLES`.

Every :class:`~gendex_envs.errors.ExecutionError` names its cause.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np
import sapien

from gendex.solve.articulated import closing_goal, opening_goal, read_joint
from gendex.solve.grasp import RELEASE_HAND, GraspPlan, GraspSynthesizer, object_heading
from gendex.solve.grasp_trial import approach, close_hand
from gendex.solve.shape import ObjectShape, PosedShape
from gendex_envs.errors import ExecutionError

if TYPE_CHECKING:  # pragma: no cover
    from gendex.solve.rigid import RigidPrimitives

log = logging.getLogger(__name__)

TWIST_PRIMITIVES = {"reach": "approach_twist", "twist": "twist"}
"""Skill -> primitive for an articulated target a ``twist`` stage turns."""
TWIST_FAMILIES = ("top",)
"""Grasp families that turn a cap: the palm on it, the fingers round its rim."""
NARROW_CAP_M = 0.035
"""Caps narrower than this radius (a bottle's) are pinched first (thumb and fingers round the rim): a top grasp of
one held it under a single finger pressing on its top, turning it without holding it (the bottle caps, seeds
59769400-59769401)."""
NARROW_FAMILIES = ("pinch", "top")
TWIST_SLICE_RAD = math.radians(90)
"""How far the palm turns per grasp (the cap follows 55-65° of it: the grip winds up and closing turns it back a
little; prototype on screw_jar, seeds 0-1: 90° slices 6 grasps a turn, 60° slices 9)."""
TWIST_RAD_PER_STEP = 0.04
TWIST_BACK_RAD_PER_STEP = 0.06
TWIST_LIFT_M = 0.03
"""The opened hand rises this far off the cap before it turns back (less, and the fingers dragged it back)."""
TWIST_MAX_CYCLES = 14
TWIST_MARGIN = 0.04
"""The twist goes this fraction of the joint's range past the task's fraction."""


class TwistPrimitives:
    """The twist primitives of one episode, on the rigid primitives' motion and hand model."""

    def __init__(self, rigid: RigidPrimitives):
        self.rigid = rigid
        self.plan: GraspPlan | None = None

    def run(self, prim: str, stage) -> Iterator[np.ndarray]:
        if prim not in TWIST_PRIMITIVES.values():
            raise ExecutionError(f"no twist primitive {prim!r}; primitives: {', '.join(TWIST_PRIMITIVES.values())}",
                                 cause="unsupported")
        return getattr(self, prim)(stage)

    def _shapes(self, name: str) -> tuple[PosedShape, tuple[PosedShape, ...]]:
        """The cap's collision shape as posed now, and every other body's (the container under it, other objects)."""
        env = self.rigid.env
        art = env.articulations[name]
        cap = env.handle_link(name)

        def posed(entity) -> PosedShape:
            p = entity.pose
            m = sapien.Pose(p.p[0].cpu().numpy(), p.q[0].cpu().numpy()).to_transformation_matrix()
            return ObjectShape.of_actor(entity).posed(m)

        others = [posed(link) for link in art.get_links() if link.name != cap.name]
        others += [self.rigid.shape(o) for o in env.objects if o not in env.articulations]
        return posed(cap), tuple(others)

    def approach_twist(self, stage) -> Iterator[np.ndarray]:
        rigid, name = self.rigid, stage.target
        m, env = rigid.m, rigid.env
        cap, others = self._shapes(name)
        prefer = object_heading(cap.footprint().center, m.ik.base.p[:2])
        synth = GraspSynthesizer(rigid.hand, cap, env.table_height, prefer, others)
        m.avoid_objects()
        radius = float(env.asset_record(name).entry.params.get("cap_radius", 1.0)) * env.task_spec.object(name).scale
        families = NARROW_FAMILIES if radius < NARROW_CAP_M else TWIST_FAMILIES
        candidates = list(synth.candidates())
        sign = self._goal(stage)[0]  # the slice turns the way the task moves the cap
        for plan in (p for fam in families for p in candidates if p.kind == fam):
            q_pre = m.ik.solve(plan.pregrasp, m.with_hand(m.target(), plan.open_hand), restarts=20,
                               valid=m.collision.is_free)
            q_palm = None if q_pre is None else m.ik.solve(plan.palm, q_pre, restarts=0)
            if q_palm is None or not self._turns(plan, q_palm, env.handle_pos(name)[0].cpu().numpy(), sign):
                continue
            log.info("twisting %r with a %s", name, plan)
            self.plan = plan
            yield from m.plan_arm(q_pre, m.with_hand(q_pre, plan.open_hand))
            yield from approach(m, plan, rigid.config.motion)
            return
        raise ExecutionError(f"no grasp of {name!r}'s cap ({', '.join(TWIST_FAMILIES)}) that the arm reaches "
                             f"without collision (families {synth.families()})", cause="no_ik")

    def _turns(self, plan: GraspPlan, q: np.ndarray, pivot: np.ndarray, sign: float = 1.0) -> bool:
        """Whether the arm turns the palm of ``plan`` (at joint positions ``q``) a whole slice about ``pivot``,
        counter-clockwise (``sign`` +1: unscrewing) or clockwise (-1: screwing on), IK step by step as
        :meth:`~gendex.solve.motion.Motion.turn_about` will."""
        ik, at = self.rigid.m.ik, sapien.Pose(np.asarray(pivot, dtype=np.float64))
        n = int(np.ceil(TWIST_SLICE_RAD / TWIST_RAD_PER_STEP))
        for k in range(1, n + 1):
            half = sign * TWIST_SLICE_RAD * k / n / 2
            q = ik.solve(at * sapien.Pose(q=[np.cos(half), 0.0, 0.0, np.sin(half)]) * at.inv() * plan.palm, q,
                         restarts=0)
            if q is None:
                return False
        return True

    def _goal(self, stage) -> tuple[float, float]:
        """(sign, goal joint position): +1 towards open (unscrewing) past the task's fraction, or -1 towards shut."""
        env, name = self.rigid.env, stage.target
        spec = env.task_spec
        conds = [c for c in (*(stage.success or ()), *spec.success.conditions)
                 if c.type == "joint_open" and c.object == name]
        sign = -1.0 if conds and all(c.negate for c in conds) else 1.0
        span = env.open_qpos(name) - env.closed_qpos(name)
        goal = opening_goal(env, name) if sign > 0 else closing_goal(env, name, 1.0)
        return sign, goal + sign * TWIST_MARGIN * abs(span)

    def twist(self, stage) -> Iterator[np.ndarray]:
        rigid, name, plan = self.rigid, stage.target, self.plan
        m, env = rigid.m, rigid.env
        if plan is None:
            raise ExecutionError(f"twisting {name!r} needs a stage that brought the hand to its cap first",
                                 cause="unsupported")
        sign, goal = self._goal(stage)
        joint = read_joint(env, name)
        pivot = env.handle_pos(name)[0].cpu().numpy().astype(np.float64)
        q_of = lambda: float(env.joint_qpos(name)[0])  # noqa: E731
        for cycle in range(TWIST_MAX_CYCLES):
            if sign * (q_of() - goal) >= 0:
                return
            yield from close_hand(m, plan, rigid.config.motion)
            before = q_of()
            turn = sign * TWIST_SLICE_RAD * joint.axis
            done = yield from m.turn_about(pivot, turn, TWIST_RAD_PER_STEP, guard=True)
            log.info("twist %d of %r: palm %.0f°, cap %.0f° -> %.0f°", cycle, name,
                     math.degrees(done * TWIST_SLICE_RAD), math.degrees(before), math.degrees(q_of()))
            if done == 0.0:
                raise ExecutionError(f"the arm cannot turn the hand on {name!r}'s cap", cause="no_ik")
            if sign * (q_of() - goal) >= 0:
                return
            yield from m.ramp(m.with_hand(m.target(), RELEASE_HAND), rigid.config.release_steps)
            up = TWIST_LIFT_M * joint.axis * (1.0 if joint.axis[2] >= 0 else -1.0)
            yield from m.cartesian(up, 0.01)
            yield from m.turn_about(pivot + up, -done * turn, TWIST_BACK_RAD_PER_STEP)
            yield from m.cartesian(-up, 0.01)
        raise ExecutionError(f"{name!r}'s cap at {math.degrees(q_of()):.0f}° after {TWIST_MAX_CYCLES} turns of the "
                             f"hand (goal {math.degrees(goal):.0f}°)", cause="target_not_reached")


__all__ = ["TWIST_FAMILIES", "TWIST_PRIMITIVES", "TwistPrimitives"]
