"""Flat ringed tools: the whole edge grasp tried in the physics trials' private scene before the robot does it.

A grasp from the table is ranked by a short trial (:mod:`gendex.solve.grasp_trial`); a flat ringed tool no such grasp
lifts is taken to the table's side edge first (:mod:`gendex.solve.edge_drag`, :mod:`gendex.solve.edge_pinch`), and
whether that works depends on where it is taken: which side edge, and where along it. The drag's contacts decide it
(a ring wedged on the finger, a tool that turns less than the finger, one that slips out of the hinge as it stands
up), not a feature the planner could rank, and a way that fails for one pose of the tool holds for another (grasp
benchmark, wrench, seeds 10300-10319: the other side edge held 3 of the 9 seeds where the ring's own failed;
``docs/solving.md``). So :class:`EdgeTrials` runs the whole grasp — the drag, the pinch, the lift and a hold of
:data:`~gendex.solve.grasp_trial.TRIAL_HOLD_STEPS` — for each of :data:`VARIANTS` in turn, in a rebuilt copy of the
scene set to the solved env's state, and the robot then does the first that held (the first variant where none did).

How well a trial forecasts the robot depends on the solved scene: rebuilt at reset (collection, evaluation and the
grasp benchmark make their envs with :data:`~gendex_envs.registry.HISTORY_FREE`), it starts where the trial's does;
a scene that ran episodes before keeps contact caches the trial's lacks, and over a drag of 200 steps the two part
(dev runs of the wrench in a scene kept between attempts: a trial held and the robot then let the tool slip on 2 of
5 such seeds).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Generator
from dataclasses import replace

import numpy as np
import sapien

from gendex.solve.edge_drag import DRAG_AIM_X_M, EdgeVariant
from gendex.solve.edge_pinch import EdgePinch
from gendex.solve.grasp import GraspPlan
from gendex.solve.grasp_trial import GraspMotion, GraspTrials, TrialResult, approach, close_hand
from gendex.solve.hand import HandModel
from gendex.solve.motion import ArmHandMotion
from gendex.solve.shape import ObjectShape, PosedShape

log = logging.getLogger(__name__)

VARIANTS = (EdgeVariant(), EdgeVariant(aim_x_m=DRAG_AIM_X_M + 0.1), EdgeVariant(other_side=True),
            EdgeVariant(turn=False), EdgeVariant(other_side=True, aim_x_m=DRAG_AIM_X_M + 0.1))
"""The ways to the edge the trials try, in order: the ring's own side edge first (it needs the least turn), 10 cm
nearer the robot, the other side edge, not turned first, the other side edge nearer the robot. Each alone on the
grasp benchmark's wrench seeds 10300-10319: the first three held 11, 6 and 6 times, 15 seeds between them; not turned
first held 2 of the 6 seeds it ran, one of them a seed none of the three held."""


def posed(shape: ObjectShape, m: ArmHandMotion, name: str) -> PosedShape:
    """``name``'s geometry ``shape`` at its pose now in ``m``'s env."""
    p = m.env.obj(name).pose
    return shape.posed(sapien.Pose(p.p[0].cpu().numpy(), p.q[0].cpu().numpy()).to_transformation_matrix())


def reach_edge(m: ArmHandMotion, hand: HandModel, name: str, shape: ObjectShape, variant: EdgeVariant,
               speed: GraspMotion) -> Generator[np.ndarray, None, GraspPlan]:
    """The edge grasp of ``name`` up to the closing: the drag (as ``variant`` says), the pinch's plan, the hand
    brought to it and the approach; returns the plan (its ``lift`` is the tool's own)."""
    edge = EdgePinch.of(m, hand, name, posed(shape, m, name), variant)
    if edge is None:
        raise ValueError(f"{name!r} is not a flat tool with a finger ring: it has no edge grasp")
    yield from edge.drag()
    plan = edge.plan(posed(shape, m, name))
    plan = replace(plan, note=f"{plan.note}; dragged to {variant}")
    yield from edge.bring_hand(plan)
    yield from approach(m, plan, speed)
    return plan


class EdgeTrials:
    """Trials of the edge grasp of one object (see the module docstring)."""

    def __init__(self, trials: GraspTrials, hand: HandModel, shape: ObjectShape):
        self.trials, self.hand, self.shape = trials, hand, shape

    def choose(self, m: ArmHandMotion, name: str, log_to: list[TrialResult] | None = None) -> EdgeVariant:
        """The first of :data:`VARIANTS` whose whole edge grasp of ``name`` held in a trial from the state of
        ``m``'s env now (``m``: the solved env's motion), else the first; each trial's result is appended to
        ``log_to``. A ring over the edge already (the robot grasps again after a slip) is not dragged: one trial.
        An ``ExecutionError`` where the tool is off the table."""
        for variant in self.variants(m, name):
            result = self.trials.rehearse(m, name, self._run(name, variant))
            if log_to is not None:
                log_to.append(result)
            log.info("edge grasp of %r by %s: %s", name, variant, "held" if result.held else result.why)
            if result.held:
                return variant
        return VARIANTS[0]

    def variants(self, m: ArmHandMotion, name: str) -> tuple[EdgeVariant, ...]:
        """The variants to try: :data:`VARIANTS`, or the first alone where the ring is over an edge already."""
        edge = EdgePinch.of(m, self.hand, name, posed(self.shape, m, name))
        return VARIANTS[:1] if edge is not None and edge.past_edge() else VARIANTS

    def _run(self, name: str, variant: EdgeVariant
             ) -> Callable[[ArmHandMotion], Generator[np.ndarray, None, tuple[GraspPlan, float]]]:
        speed = self.trials.speed

        def run(m: ArmHandMotion) -> Generator[np.ndarray, None, tuple[GraspPlan, float]]:
            plan = yield from reach_edge(m, self.hand, name, self.shape, variant, speed)
            yield from close_hand(m, plan, speed)
            lifted = yield from plan.lift(speed.lift_m_per_step)
            return plan, lifted

        return run
