"""Scripted primitives for rigid targets: approach, grasp, lift, carry, place, push, release (and their failure
causes).

Run by :class:`~gendex.solve.executor.StageExecutor` for stages whose target is a rigid object.

- ``approach`` — grasp synthesis on the object's measured pose and collision geometry
  (:class:`~gendex.solve.grasp.GraspSynthesizer`); each candidate the arm reaches without collision (IK with
  restarts, pre-grasp and grasp pose) is tried in a private copy of the scene
  (:class:`~gendex.solve.grasp_trial.GraspTrials`) until one holds. The arm then goes to a staging pose with the
  opened hand in the collision model and the target an obstacle, and straight on to the pre-grasp pose. If the
  object was disturbed on the way (moved more than :data:`MOVED_M`), the grasp is synthesized again from where it
  is now. Then the straight approach. A flat ringed tool no grasp holds goes to the table's edge first (edge_pinch).
- ``grasp`` — the grasp's guarded closing ramps and squeeze, then a lift of ``lift_m`` (an edge pinch's: as far as
  the arm reaches). If the object did not rise half as far as the hand did (it slipped), the hand opens, backs off
  and grasps once more from where it is (``regrasps``).
- ``lift`` — raise the held object to the task's ``lifted`` height.
- ``carry`` — the held object over the target: a level, eased palm path where the hand's orientation can be kept,
  else a planned arm motion, the held object attached to the palm in the collision model; an object that is no
  longer with the hand at the end has slipped.
- ``place`` — centre the held object over the target and lower it until it rests there.
- ``push`` — slide an object across the table with the flat hand, closed loop on its measured pose
  (:mod:`gendex.solve.push`).
- ``release`` — open the hand back to the grasp's pre-shape and back off.

Every :class:`~gendex_envs.errors.ExecutionError` raised here names its cause (``no_ik``, ``slipped``, ...).
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import sapien

from gendex.solve.collision import box_spheres
from gendex.solve.edge_drag import EdgeVariant
from gendex.solve.edge_geometry import find_ring
from gendex.solve.edge_trial import EdgeTrials, reach_edge
from gendex.solve.grasp import (
    RELEASE_HAND,
    GraspPlan,
    GraspSynthesizer,
    object_heading,
)
from gendex.solve.grasp_trial import (
    MIN_LIFT_M,
    GraspMotion,
    GraspTrials,
    TrialResult,
    approach,
    close_hand,
    ease_grip,
    fits_on,
    rose_with_hand,
)
from gendex.solve.hand import HandModel
from gendex.solve.set_down import POINT, POINT_CARRY_M
from gendex.solve.shape import ObjectShape, PosedShape
from gendex.solve.stage_grip import missed_only_conditions, with_middle_finger
from gendex_envs.errors import ExecutionError
from gendex_envs.physx import px_bodies
from gendex_envs.spec import ConditionSpec

if TYPE_CHECKING:  # pragma: no cover
    from gendex.solve.motion import ArmHandMotion

log = logging.getLogger(__name__)

MOVED_M = 0.005
"""An object that moved more than this between planning its grasp and reaching the pre-grasp is re-planned."""
STAGING_M = tuple(sorted(((b, u, a) for b in (0.0, 0.06, 0.12) for u in (0.0, 0.08, 0.16, 0.24) for a in (0.0, 0.08)
                          if b + u + a > 0), key=lambda o: (sum(x * x for x in o), o)))
"""Staging offsets (m) from a pre-grasp pose (back along the approach, up, away from the object), nearest first."""
ESCAPE_M = 0.15
"""Highest rise of the opened hand out of the collision model's margins before a staged approach is planned."""
UNTILT_MAX_RAD = 0.8
UNTILT_RAD_PER_STEP = 0.03
UNTILT_TOPPLE_RAD = 0.6
"""Before a set-down the hand turns the object back to its tilt at reset (this many rad a step) if it is taller than
wide (topples at under ``UNTILT_TOPPLE_RAD``; a ball's tilt means nothing) and the grasp tilted it by more than half
its toppling angle, but at most ``UNTILT_MAX_RAD`` (more is a grasp that turned it on purpose)."""
RETREATS = 8
RETREAT_M = 0.03
RETREAT_WAIT_STEPS = 5
RETREAT_FORCE_N = 0.05
"""After letting go the hand backs off ``RETREAT_M`` more at a time (at most ``RETREATS`` times, each time waiting
for the object to settle) while a group of it presses on the object with more than ``RETREAT_FORCE_N``."""
PLACE_CORRECTIONS = 3
PLACE_TOLERANCE_M = 0.005
"""Before a place lowers the object, it is moved over the target's centre (at most this many corrections, until
within the tolerance)."""
INSERT_CORRECTIONS = 8
INSERT_TOLERANCE_M = 0.0012
INSERT_TILT_RAD = 0.02
INSERT_SETTLE_STEPS = 6
INSERT_M_PER_STEP = 0.003
"""Into a holder (an asset tagged ``insert``: a hole a few mm wider than its peg) the object's *bottom* is centred
over the hole to this tolerance, after the hand stands it up to within ``INSERT_TILT_RAD``, waiting
``INSERT_SETTLE_STEPS`` after each correction (a peg pinched high swings), then lowered this slowly."""
PLACE_PRESS_M = 0.015
PLACE_RESTING_M = 0.008
"""A place lowers the held object's lowest point to this far *below* the surface under it, and stops as soon as the
palm has gone :data:`PLACE_RESTING_M` further down than the object: an object held tilted (a pinch lets it swing
about the pinch line) is pressed flat on its support before the hand lets go."""
CARRY_YAWS_RAD = (0.0, 0.4, -0.4, 0.8, -0.8)
CARRY_RAISES_M = (0.0, 0.05, 0.1)
"""Turns of the hand (and the held object) about the vertical, tried in turn along a level carry's straight line
(the hand turning steadily on the way) and, where no straight line works, about the vertical through the carry's
goal with extra heights, for a collision-free arm pose there."""
CARRY_M_PER_STEP = 0.012
CARRY_RAMP_STEPS = 6
"""Palm travel per step of a level (straight, orientation-keeping) carry, reached and left over this many steps."""
SLIP_M = 0.03
"""A held object that drifted more than this from its place in the hand during a carry has slipped."""


@dataclass
class RigidConfig:
    """Speeds, margins and search budgets of the rigid primitives (control steps at 20 Hz)."""

    carry_clearance_m: float = 0.07
    """Height of the held object's bottom above the target's top while carrying."""
    carry_step_rad: float = 0.035
    """Largest arm-joint change per step while carrying (the free arm moves up to 0.06): a precision pinch lets go of
    a ball swung at up to ~1 m/s."""
    release_steps: int = 8
    max_trials: int = 10
    """Physics trials per grasp before giving up (0: no trials, the first reachable candidate is used)."""
    thin_trials: int = 48
    """Physics trials per grasp of an object low enough for fingertip pinches at the table (the ``tip`` family):
    side pinches and tip pinches share the budget there, and most of either are near misses. Trying every tip hand
    (palm direction, roll, solve start) of a line on dev seeds showed one hand of 10-14 holding and the rest 0, which
    one depending on the object (knife 14/25 trials, spoon 9/12, fork 4/6), not on a feature of the hand that could
    rank them; so the trials rank them, and need the budget to reach that hand on a few lines. Dev seeds 1000-1009:
    knife 6, spoon 7, fork 10 of 10 with 16 trials; 9, 9 and 10 with 48 (a failed attempt then costs about 20 s of
    trials)."""
    pinch_trials: int = 30
    """Physics trials per grasp of an object only a precision pinch holds (a ball too small for a power grasp): its
    near misses push it while closing, and which of its pinch lines holds depends on where it lies. Seeds 10708 and
    10709 of ``benchmarks/grasp.py`` (golf ball): no trial of 10 held; trials 19 and 11 did."""
    regrasps: int = 1
    """Further grasps after one whose object slipped out while lifting."""
    replans: int = 2
    """Re-syntheses when the object moved before the hand got to it."""
    motion: GraspMotion = GraspMotion()


class RigidPrimitives:
    """The rigid-object primitives of one env (see the module docstring)."""

    def __init__(self, motion: ArmHandMotion, config: RigidConfig | None = None):
        self.m = motion
        self.env = motion.env
        self.config = config or RigidConfig()
        self.held: str | None = None
        """The object the hand holds, if any."""
        self.plan: GraspPlan | None = None
        """The grasp being executed."""
        self.placed_on: str | None = None
        """What the held object was last set down on (by :meth:`place`), until the next grasp."""
        self.trial_log: list[TrialResult] = []
        self._shapes: dict[str, ObjectShape] = {}
        self._hand: HandModel | None = None
        self._trials: GraspTrials | None = None
        self._synth: GraspSynthesizer | None = None
        self._require: tuple[ConditionSpec, ...] = ()
        self._set_on: str | None = None

    def reset(self) -> None:
        """Start an episode: nothing held, and grasp trials in a rebuilt scene (:meth:`GraspTrials.renew`)."""
        self.held = None
        self.plan = None
        self.placed_on = None
        self.trial_log = []
        if self._trials is not None:
            self._trials.renew()

    def close(self) -> None:
        if self._trials is not None:
            self._trials.close()
            self._trials = None

    # ------------------------------------------------------------------ geometry
    @property
    def hand(self) -> HandModel:
        if self._hand is None:
            self._hand = HandModel(self.m.ik, self.env.agent.robot)
        return self._hand

    @property
    def trials(self) -> GraspTrials:
        if self._trials is None:
            self._trials = GraspTrials(self.env, self.config.motion, self.m.max_arm_step_rad)
        return self._trials

    def shape(self, name: str) -> PosedShape:
        """Object ``name``'s collision geometry at its pose now."""
        if name not in self._shapes:
            self._shapes[name] = ObjectShape.of_actor(self.env.obj(name))
        pose = self.env.obj(name).pose
        m = sapien.Pose(pose.p[0].cpu().numpy(), pose.q[0].cpu().numpy()).to_transformation_matrix()
        return self._shapes[name].posed(m)

    def _pose_now(self, name: str) -> np.ndarray:
        pose = self.env.obj(name).pose
        return np.concatenate([pose.p[0].cpu().numpy(), pose.q[0].cpu().numpy()])

    # ------------------------------------------------------------------ approach and grasp
    def choose_grasp(self, name: str, require: tuple[ConditionSpec, ...] = (), set_on: str | None = None
                     ) -> tuple[GraspPlan, np.ndarray]:
        """The first reachable grasp of ``name`` that holds in a trial (meeting the ``grasped`` conditions
        ``require`` as well), and its pre-grasp joint vector. Fallbacks while the trials last: one whose closing pushed
        ``name`` (:attr:`~gendex.solve.grasp_trial.TrialResult.shoved`, the least pushed first), then one that swung
        it over past fitting ``set_on`` (:func:`~gendex.solve.grasp_trial.fits_on`; the least swung), what it is set
        down in or on next: a tilted object catches a container's rim, or lands on its side and topples off a board."""
        m, c, env = self.m, self.config, self.env
        shape = self.shape(name)
        others = tuple(self.shape(o) for o in env.objects if o != name and o not in env.articulations)
        prefer = object_heading(shape.footprint().center, m.ik.base.p[:2])
        # held high: a peg (it goes into its hole bottom first), a sponge (pressed on a spill, the forearm clear)
        into_hole = set_on is not None and bool({"insert", "wipe_area"} & set(env.asset_record(set_on).tags))
        synth = GraspSynthesizer(self.hand, shape, env.table_height, prefer, others, px_bodies(env.obj(name))[0].mass,
                                 high_first=into_hole)
        self._synth = synth
        m.avoid_objects(exclude=(name,))
        q0 = m.target()
        reachable, results, helped_trials = 0, [], 0
        fallback: list[tuple[tuple[bool, float], TrialResult, np.ndarray]] = []  # (rank, trial, pre-grasp)
        shape_now = self._shapes[name] if set_on is not None else None
        fits = fits_on(shape, self.shape(set_on)) if set_on is not None else None

        def tried(plan: GraspPlan, q: np.ndarray) -> bool:
            """Trial ``plan`` from ``q``; True when it is the grasp to take (held, and fitting where asked)."""
            result = self.trials.trial(plan, q, name, require, shape_now)
            results.append(result)
            self.trial_log.append(result)
            fitting = fits is None or result.upright or fits(result.spread)
            if result.held and not (fitting and not result.shoved):
                fallback.append(((not fitting, result.pushed_m if fitting else result.spread), result, q))
            elif result.held:
                log.info("grasp of %r: %s (trial %d)", name, plan, len(results))
            return result.held and fitting and not result.shoved

        families, budget = synth.families(), c.max_trials
        if c.max_trials and "tip" in families:
            budget = max(c.max_trials, c.thin_trials)
        elif c.max_trials and set(families) == {"pinch"}:
            budget = max(c.max_trials, c.pinch_trials)
        # none of the budget held: an object that pinches goes on with its pinches alone, up to pinch_trials (the
        # cheese wedge: 3 of 20 fresh seeds ran out of 10 trials, pinch and top alike), unless it has a ring (a flat
        # tool is dragged to the table's edge instead); an attempt that held within the budget is unchanged
        more = (c.pinch_trials if c.max_trials and "pinch" in families and budget < c.pinch_trials
                and find_ring(self.shape(name)) is None else budget)
        pinch_only = False
        # a sponge to wipe with is pinched: held palm down, the wrist is too low to press it flat (5 of 20 seeds)
        wiping = set_on is not None and "wipe_area" in env.asset_record(set_on).tags
        for plan in (p for p in synth.candidates() if not (wiping and p.kind == "top")):
            if pinch_only and plan.kind != "pinch":
                continue
            open_q = m.with_hand(q0, plan.open_hand)
            q_pre = m.ik.solve(plan.pregrasp, open_q, restarts=20, valid=m.collision.is_free)
            q_at = None if q_pre is None else m.ik.solve(plan.palm, q_pre, restarts=0)
            lifted = sapien.Pose(plan.palm.p + [0.0, 0.0, c.motion.lift_m], plan.palm.q)
            if q_at is None or m.ik.solve(lifted, q_at, restarts=0) is None:
                continue
            reachable += 1
            if c.max_trials == 0 or tried(plan, q_pre):
                return plan, q_pre
            # it held, but the grasp stage wants more fingers on the object: the middle finger joins the index (trials
            # of these come on top of max_trials, at most half as many)
            helped = with_middle_finger(plan, require) if missed_only_conditions(results[-1], c.motion.lift_m) else None
            if helped is not None and synth.hand_clear(helped) and 2 * helped_trials < c.max_trials:
                helped_trials += 1
                q_helped = m.with_hand(q_pre, helped.open_hand)
                if tried(helped, q_helped):
                    return helped, q_helped
            if len(results) - helped_trials >= budget:
                if budget < more and not fallback and not any(r.held for r in results):
                    log.info("no grasp of %r held in %d trials: trying its pinches, up to %d", name, budget, more)
                    budget, pinch_only = more, True
                    continue
                break
        if fallback:
            _, result, q = min(fallback, key=lambda f: f[0])
            log.info("grasp of %r: %s (a fallback: every trial that held pushed it or swung it over)", name, result)
            return result.plan, q
        if not reachable:
            raise ExecutionError(f"no grasp of {name!r} that the arm reaches without collision (families "
                                 f"{synth.families()})", cause="no_ik")
        best = max(results, key=lambda r: r.rise_m)
        raise ExecutionError(f"none of {len(results)} grasps of {name!r} held in a physics trial; best: {best}",
                             cause="grasp_failed")

    def approach(self, name: str, require: tuple[ConditionSpec, ...] = (), set_on: str | None = None
                 ) -> Iterator[np.ndarray]:
        m = self.m
        self._require, self._set_on = require, set_on
        for attempt in range(self.config.replans + 1):
            before = self._pose_now(name)
            try:
                plan, q_pre = self.choose_grasp(name, require, set_on)
            except ExecutionError as err:  # a flat ringed tool: dragged to the table's edge and pinched there
                if err.cause != "grasp_failed" or find_ring(self.shape(name)) is None:
                    raise
                log.info("%s; dragging %r to the table's edge by its ring", err, name)
                variant = (EdgeTrials(self.trials, self.hand, self._shapes[name]).choose(m, name, self.trial_log)
                           if self.config.max_trials else EdgeVariant())
                self.plan = yield from reach_edge(m, self.hand, name, self._shapes[name], variant, self.config.motion)
                return
            yield from self.bring_hand(name, plan, q_pre)
            moved = float(np.linalg.norm(self._pose_now(name)[:3] - before[:3]))
            if moved <= MOVED_M or attempt == self.config.replans:
                break
            log.info("%r moved %.3f m while the arm came: planning its grasp again", name, moved)
        self.plan = plan
        yield from approach(m, plan, self.config.motion)

    def bring_hand(self, name: str, plan: GraspPlan, q_pre: np.ndarray, synth: GraspSynthesizer | None = None
                   ) -> Iterator[np.ndarray]:
        """Planned arm motion to the pre-grasp pose that keeps the opened hand off every object, the target
        included: to a staging pose (:data:`STAGING_M` back along the approach and/or up) planned with the hand's
        spheres in the collision model, then straight to the pre-grasp pose along a path checked against the
        objects' geometry. When no staging pose works, the arm alone is planned to the pre-grasp pose. ``synth``:
        the synthesizer that made ``plan`` (default: the last grasp's)."""
        m, synth = self.m, synth or self._synth
        hand_q = m.with_hand(m.target(), plan.open_hand)
        cover = self.hand.spheres(plan.open_hand)
        up = np.array([0.0, 0.0, 1.0])
        away = np.zeros(3)
        away[:2] = plan.pregrasp.p[:2] - self.shape(name).footprint().center
        away /= max(float(np.linalg.norm(away)), 1e-9)
        step_m = self.config.motion.approach_m_per_step
        n_in = int(np.ceil(np.linalg.norm(plan.palm.p - plan.pregrasp.p) / step_m)) + self.config.motion.settle_steps
        m.avoid_objects()
        m.collision.cover_hand(cover.centers, cover.radii)
        try:
            lift, start = m.rise_clear(hand_q, ESCAPE_M)
            for back, rise, out in STAGING_M:
                offset = -back * plan.approach + rise * up + out * away
                stage = sapien.Pose(plan.pregrasp.p + offset, plan.pregrasp.q)
                if synth is not None and not synth.path_clear(plan.open_hand, plan.pregrasp, offset, np.zeros(3)):
                    log.debug("staging %s: the straight move to the pre-grasp pose touches something", offset)
                    continue
                q_stage = m.ik.solve(stage, q_pre, restarts=4)
                if q_stage is None or not m.collision.is_free(m.with_hand(q_stage, plan.open_hand)):
                    log.debug("staging %s: %s", offset, "no IK" if q_stage is None else "in collision")
                    continue
                n_stage = int(np.ceil(np.linalg.norm(offset) / step_m))
                try:
                    path = m.plan_arm(q_stage, hand=hand_q, start=start, after=n_stage + n_in)
                except ExecutionError as exc:
                    log.debug("staging %s: %s", offset, exc)
                    continue
                m.collision.cover_hand(None)
                if lift > 0:
                    yield from m.cartesian(np.array([0.0, 0.0, lift]), step_m, paced=True)
                yield from path
                yield from m.cartesian(-offset, step_m, paced=True, after=n_in)
                return
        finally:
            m.collision.cover_hand(None)
            m.avoid_objects(exclude=(name,))
        log.info("no staged approach to the %s: planning the arm alone", plan)
        yield from m.move_arm(q_pre, hand=hand_q, after=n_in)

    def carry_bottom(self, target: str) -> float:
        """Height (world z) of a carried object's bottom over ``target`` (its top + ``carry_clearance_m``)."""
        return float(self.m.world_aabb(target)[1][2]) + self.config.carry_clearance_m

    def grasp(self, name: str, lift_to: float | None = None) -> Iterator[np.ndarray]:
        """Close the planned grasp on ``name`` and lift it ``lift_m`` (or, ``lift_to``, until its bottom is that
        high, when that is less: a carry goes on from there; at least :data:`MIN_LIFT_M`); open, back off and grasp
        again if it did not come up."""
        m, c = self.m, self.config
        if self.plan is None:
            raise ExecutionError(f"grasping {name!r} needs a stage that approached it first", cause="unsupported")
        self.placed_on = None
        for attempt in range(c.regrasps + 1):
            z0, planned = float(self.env.obj(name).pose.p[0, 2]), self.plan.lift is not None  # planned: an edge grasp's
            offset = np.array([0.0, 0.0, c.motion.lift_m])
            if lift_to is not None and not planned:
                offset[2] = float(np.clip(lift_to - m.world_aabb(name)[0][2], MIN_LIFT_M, offset[2]))
            yield from close_hand(m, self.plan, c.motion)
            self.held = name
            done = yield from (self.plan.lift(c.motion.lift_m_per_step) if planned else
                               m.cartesian(offset, c.motion.lift_m_per_step, True, True))
            lifted = max(done, MIN_LIFT_M) if planned else offset[2]  # where the arm's reach ended
            risen = float(self.env.obj(name).pose.p[0, 2]) - z0
            # an object flung onto something higher (a lemon onto a cutting board) rose but is out of the hand
            touched = int(np.sum(self.env.hand_forces(name)[0].cpu().numpy() > 0.3))
            if rose_with_hand(risen, lifted) and touched >= 2:
                yield from ease_grip(m, self._require)
                return
            self.held = None
            why = f"rose {risen:.3f} m of {lifted:.3f} m, touched by {touched} part(s) of the hand"
            if attempt == c.regrasps:
                raise ExecutionError(f"{name!r} slipped out of the {self.plan} while lifting ({why})", cause="slipped")
            log.info("%r slipped (%s): opening and grasping again", name, why)
            yield from self._let_go()
            yield from self.approach(name, self._require, self._set_on)

    def _let_go(self) -> Iterator[np.ndarray]:
        """Open the hand and back off upwards (as far as the arm reaches, up to 8 cm)."""
        m = self.m
        yield from m.ramp(m.with_hand(m.target(), RELEASE_HAND), self.config.release_steps)
        for up in (0.08, 0.04):
            if m.ik.solve(sapien.Pose(m.ik.fk(m.target()).p + [0.0, 0.0, up], m.ik.fk(m.target()).q), m.target(),
                          restarts=0) is not None:
                yield from m.cartesian(np.array([0.0, 0.0, up]), 0.01)
                return

    # ------------------------------------------------------------------ moving what is held
    def lift(self, name: str, need_m: float) -> Iterator[np.ndarray]:
        risen = float(self.env.obj_height(name)[0])
        if risen < need_m + 0.02:
            yield from self.m.cartesian(np.array([0.0, 0.0, need_m + 0.03 - risen]),
                                        self.config.motion.lift_m_per_step, guard=True, paced=True)

    def carry(self, target: str, point: np.ndarray | None = None) -> Iterator[np.ndarray]:
        """Carry the held object over ``target`` (its top + ``carry_clearance_m``), or over table ``point`` (xy) at
        that height (:data:`~gendex.solve.set_down.POINT_CARRY_M` over the table when ``target`` is the held one)."""
        c, m, held = self.config, self.m, self.held
        if held is None:
            raise ExecutionError(f"carrying to {target!r} needs an object in the hand; it holds nothing", "slipped")
        held_lo, held_hi = m.world_aabb(held)
        if held_lo[2] < self.env.table_height + 0.5 * c.motion.lift_m:
            # still at the table (a trained grasp policy closes the hand but does not lift, unlike the scripted
            # grasp): lift straight up first, so the planned carry never drags the object across the table
            # (as far as the arm reaches: a tall object held high leaves little; the carry plans from there)
            z0 = float(self.env.obj(held).pose.p[0, 2])
            done = yield from m.cartesian(np.array([0.0, 0.0, c.motion.lift_m]), c.motion.lift_m_per_step,
                                          guard=True, partial=True)
            risen = float(self.env.obj(held).pose.p[0, 2]) - z0
            if risen < 0.5 * done * c.motion.lift_m:
                raise ExecutionError(f"{held!r} slipped when lifted for the carry (rose {risen:.3f} m of "
                                     f"{done * c.motion.lift_m:.3f} m)", cause="slipped")
            held_lo, held_hi = m.world_aabb(held)
        t_center = m.object_geometry(target)[0] if point is None else point
        top = float(m.world_aabb(target)[1][2]) if target != held else self.env.table_height + POINT_CARRY_M
        obj_p = (held_lo + held_hi) / 2
        goal_center = np.array([t_center[0], t_center[1], top + c.carry_clearance_m + (obj_p[2] - held_lo[2])])
        q_now = m.target()
        palm = m.ik.fk(q_now)
        in_hand = m.ik.fk(m.qpos()).inv() * sapien.Pose(self._pose_now(held)[:3])
        goal = sapien.Pose(palm.p + (goal_center - obj_p), palm.q)
        # the held object moves with the palm: plan with it attached, against every other object (the target too)
        m.avoid_objects(exclude=(held,))
        m.collision.attach(*box_spheres(held_lo, held_hi), q_now)
        try:
            # a straight line, the hand level; turning about the vertical along the way where it must (an object
            # carried past the robot's base)
            straight, turn = None, 0.0
            level = (CARRY_M_PER_STEP, c.carry_step_rad, CARRY_RAMP_STEPS)
            for turn in CARRY_YAWS_RAD:
                straight = m.level_path(palm, goal, q_now, *level, turn=turn, pivot=obj_p)
                if straight is not None:
                    break
            pace = 1.0 if straight is None else m.pace(len(straight))
            if pace > 1.0:  # a short budget: the same line, faster
                straight = m.level_path(palm, goal, q_now, *level, pace, turn, obj_p) or straight
            if straight is not None:  # the hand stays level: nothing held is tipped out on the way
                log.info("carrying %r to %r on a straight line, turning %+.1f rad: %d steps (pace %.2f)", held,
                         target, turn, len(straight), pace)
                for q in straight:
                    t = m.target()
                    t[m.arm] = q[m.arm]
                    yield m.emit(t)
            else:
                q_goal = None
                # the object may arrive turned about the vertical, or higher: still over the target (a place or a
                # release lowers it)
                for up, yaw in ((u, y) for u in CARRY_RAISES_M for y in CARRY_YAWS_RAD):
                    turn = sapien.Pose(q=[np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])
                    pivot = sapien.Pose(goal_center)
                    pose = sapien.Pose([0.0, 0.0, up]) * pivot * turn * pivot.inv() * goal
                    q_goal = m.ik.solve(pose, q_now, restarts=20, valid=m.collision.is_free)
                    if q_goal is not None:
                        break
                if q_goal is None:
                    raise ExecutionError(f"no reachable collision-free pose holding {held!r} above {target!r}",
                                         cause="no_ik")
                yield from m.move_arm(q_goal, max_step_rad=c.carry_step_rad)
        finally:
            m.collision.detach()
        drift = float(np.linalg.norm((m.ik.fk(m.qpos()) * in_hand).p - self._pose_now(held)[:3]))
        if drift > SLIP_M:
            raise ExecutionError(f"{held!r} slipped in the hand while carried to {target!r} (drifted {drift:.3f} m)",
                                 cause="slipped")

    def place(self, target: str, point: np.ndarray | None = None, at: np.ndarray | None = None,
              floor: float | None = None) -> Iterator[np.ndarray]:
        """Lower the held object onto ``target`` (a surface, an object, a container's floor; at ``at`` or its middle),
        or at ``point`` (xy) onto the table or a ``floor`` that high (a drawer's), until it rests: the palm descends
        (grip guarded) to a little below the top under the object, and stops once the object stops following it."""
        c, m, held = self.config, self.m, self.held
        if held is None:
            raise ExecutionError(f"placing on {target!r} needs an object in the hand; it holds nothing", "slipped")
        insert = point is None and "insert" in self.env.asset_record(target).tags
        yield from self.stand_as_before(held, INSERT_TILT_RAD if insert else None)
        if insert:
            yield from self._square_to(held, target)
        goal_xy = (np.asarray(point, dtype=np.float64) if point is not None
                   else np.asarray(at, dtype=np.float64) if at is not None else self.shape(target).footprint().center)
        last, move = np.inf, np.zeros(3)
        for _ in range(INSERT_CORRECTIONS if insert else PLACE_CORRECTIONS):
            # the carry ends within a few cm: centre the object (its bottom, into a hole) over the target
            lo, hi = m.world_aabb(held)
            now = self._pose_now(held)[:2] if insert else (lo[:2] + hi[:2]) / 2
            error = goal_xy - now
            off = float(np.linalg.norm(error))
            log.debug("centring %r over %r: %.1f mm off", held, target, 1000 * off)
            if off < (INSERT_TOLERANCE_M if insert else PLACE_TOLERANCE_M):
                break
            if insert and off > last:  # a peg pinched high swung rather than followed: back to the nearest
                yield from m.cartesian(-move, c.motion.lift_m_per_step, guard=True, partial=True)
                yield from m.hold(INSERT_SETTLE_STEPS)
                break
            last, move = off, np.array([error[0], error[1], 0.0])
            yield from m.cartesian(move, c.motion.lift_m_per_step, guard=True, paced=True,
                                   partial=insert)  # a mm short of a hole: the next try, or the chamfer
            yield from m.hold(INSERT_SETTLE_STEPS if insert else c.motion.settle_steps)
        lo, hi = m.world_aabb(held)
        xy = (lo[:2] + hi[:2]) / 2
        surface = self.shape(target).top_at(xy) if point is None else self.env.table_height if floor is None else floor
        if surface is None:
            raise ExecutionError(f"the held {held!r} is not over {target!r} (nothing of it under {xy.round(3)})",
                                 cause="target_not_reached")
        drop = float(lo[2] - surface + PLACE_PRESS_M)
        if drop <= 0:
            return
        speed = INSERT_M_PER_STEP if insert else c.motion.lift_m_per_step
        speed *= m.pace(int(np.ceil(drop / speed)))
        n = max(1, int(np.ceil(drop / speed)))
        palm0, z0 = m.ik.fk(m.qpos()).p[2], float(self.env.obj(held).pose.p[0, 2])
        for k, action in enumerate(m.cartesian(np.array([0.0, 0.0, -drop]), speed, guard=True)):
            yield action
            lag = (palm0 - m.ik.fk(m.qpos()).p[2]) - (z0 - float(self.env.obj(held).pose.p[0, 2]))
            if k < n - 1 and lag > PLACE_RESTING_M:
                break  # the object stopped while the palm went on: it rests on something
        yield from m.hold(self.config.motion.settle_steps)
        self.placed_on = target if point is None else POINT
        lag = (palm0 - m.ik.fk(m.qpos()).p[2]) - (z0 - float(self.env.obj(held).pose.p[0, 2]))
        if lag > 0.002:  # take the press off: the object rests on its support under its own weight
            yield from m.cartesian(np.array([0.0, 0.0, min(lag, PLACE_PRESS_M)]), c.motion.lift_m_per_step,
                                   guard=True)

    def _square_to(self, held: str, target: str) -> Iterator[np.ndarray]:
        """Turn the hand about the vertical through the held object until its sides line up with a square hole's
        (a square peg fits a hole 6 mm wider only within about 14° of it)."""
        shapes = [self.env.asset_record(n).entry.params.get("shape") for n in (held, target)]
        if shapes != ["square", "square"]:
            return

        def yaw(name: str) -> float:
            x = sapien.Pose(q=self._pose_now(name)[3:]).to_transformation_matrix()[:3, 0]
            return float(np.arctan2(x[1], x[0]))

        for other_way in (False, True):  # the short way round; where the arm's reach ends, the long way (90° less)
            error = (yaw(target) - yaw(held) + np.pi / 4) % (np.pi / 2) - np.pi / 4
            if abs(error) <= INSERT_TILT_RAD:
                return
            turn = error - np.sign(error) * np.pi / 2 if other_way else error
            lo, hi = self.m.world_aabb(held)
            done = yield from self.m.turn_about((lo + hi) / 2, np.array([0.0, 0.0, turn]), UNTILT_RAD_PER_STEP,
                                               guard=True)
            if done >= 1.0:
                return

    def stand_as_before(self, held: str, min_rad: float | None = None) -> Iterator[np.ndarray]:
        """Turn the hand about the held object's centre back to the object's tilt at reset (when: see
        :data:`UNTILT_TOPPLE_RAD`; ``min_rad``: any tilt over it, of any object): a bottle a side grasp lifted 24°
        askew falls when let go, on thumb or tray; a peg must go into its hole straight, a sponge onto a spill flat."""
        q_now = self.env.obj(held).pose.q[0].cpu().numpy()
        q_init = self.env.init_obj_quat(held)[0].cpu().numpy()
        up_now = sapien.Pose(q=q_now).to_transformation_matrix()[:3, 2]
        up_then = sapien.Pose(q=q_init).to_transformation_matrix()[:3, 2]
        angle = float(np.arccos(np.clip(up_now @ up_then, -1.0, 1.0)))
        self.shape(held)  # reads the collision shape once
        standing = self._shapes[held].posed(sapien.Pose(q=q_init).to_transformation_matrix())
        base = standing.footprint()
        topple = float(np.arctan2(base.width / 2, standing.centroid()[2] - base.bottom))
        if (min_rad is None and topple > UNTILT_TOPPLE_RAD
                or not (topple / 2 if min_rad is None else min_rad) < angle <= UNTILT_MAX_RAD):
            return
        axis, (lo, hi) = np.cross(up_now, up_then), self.m.world_aabb(held)
        done = yield from self.m.turn_about((lo + hi) / 2, axis / np.linalg.norm(axis) * angle, UNTILT_RAD_PER_STEP,
                                            guard=True)
        log.info("stood %r back up before setting it down: %.0f%% of a %.0f° tilt (it topples at %.0f°)", held,
                 100 * done, np.degrees(angle), np.degrees(topple))

    # ------------------------------------------------------------------ pushing
    def push(self, name: str, goal_xy: np.ndarray, tolerance_m: float) -> Iterator[np.ndarray]:
        """Slide ``name`` across the table to ``goal_xy`` with the flat hand (:func:`gendex.solve.push.push`)."""
        from gendex.solve.push import push

        yield from push(self, name, goal_xy, tolerance_m)

    def release(self) -> Iterator[np.ndarray]:
        """Let go: the fingers go back to the grasp's own pre-shape (the least motion that frees the object, no
        sweeping thumb), and the hand backs off 5 cm, up and the way it came in; then on, a little at a time, while
        the object still touches it (a tall object set down tilted leans on the thumb and follows it)."""
        m, plan, held = self.m, self.plan, self.held
        # every joint the grasp closed goes back: to its pre-shape value where the plan has one, else fully open
        opened = RELEASE_HAND if plan is None else RELEASE_HAND | plan.open_hand
        yield from m.ramp(m.with_hand(m.target(), opened), self.config.release_steps)
        self.held = None
        back = np.array([0.0, 0.0, 1.0]) - (0.0 if plan is None else plan.approach)
        back = back / np.linalg.norm(back)
        yield from m.cartesian(0.05 * back, 0.01)
        for _ in range(RETREATS):
            if held is None or float(self.env.hand_forces(held)[0].max()) <= RETREAT_FORCE_N:
                return
            if (yield from m.cartesian(RETREAT_M * back, 0.01, partial=True)) < 1.0:
                return  # as far as the arm reaches
            yield from m.hold(RETREAT_WAIT_STEPS)
