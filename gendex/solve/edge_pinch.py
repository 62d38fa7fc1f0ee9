"""Flat tools with a finger ring, the second half of their grasp: the ring that :mod:`gendex.solve.edge_drag` dragged
past the table's side edge is pinched there, and the tool lifted.

A tool whose weight turns it little about the ring (:data:`HINGE_MIN_MOMENT_NM`) is *clamped*: the hand comes down
outside the edge and slides in with the fingers along the edge and the palm facing the table's side, the thumb's pad
under the ring and the index's over it at the +y edge, the other way round at the -y edge (the arm reaches no pose with
the fingers pointing across the table), both closed on the ring's far side with a :data:`LEAD_M` lead. A heavier one
(the wrench, whose 6.9 mm hole the finger does not pass) is *hinged*: the hand comes down over the ring and pinches it
across, level with it, along a line about square to the tool
(:data:`~gendex.solve.edge_geometry.HANG_HEADINGS_DEG`): past the edge the fingers may reach below the table top, so
the pads meet the ring's outer wall side-on. Of the pinches the synthesis offers there
(:meth:`~gendex.solve.grasp.GraspSynthesizer.pinch_plans`, the table cut off at its edge), the one whose pads cross
their contact points at the most even height while closing comes first (a pad passing low lifts its side and rolls the
tool over); the arm must reach it, and the stand-up below, without the arm or the open hand dipping into the table top.

The hinged tool is then stood up on its far end (:meth:`EdgePinch._stand_up`): the hand carries the ring along the arc
about the tool's far edge on the table (:func:`~gendex.solve.edge_geometry.pivot_step`, re-aimed every step from the
measured poses), so that the far end need not slide over the table and drop off its edge, until the tool stands about
upright below the pads (:data:`PIVOT_UPRIGHT_RAD`); then the hand lifts it :data:`PIVOT_CLEAR_M` straight up. Lifted
straight up from the start instead, its far end slid to the edge and dropped, and the tool often twisted out of the
pads as it swung (``docs/solving.md``).
"""

from __future__ import annotations

import logging
from collections.abc import Generator, Iterator
from dataclasses import replace

import numpy as np
import sapien

from gendex.solve.edge_drag import DRAG_HAND, HOOK_FLEX, HOOK_HOLD, HOOK_STEPS, EdgeDrag
from gendex.solve.edge_geometry import PastEdge, far_edge, hinge_headings, pivot_step
from gendex.solve.grasp import PINCH_MAX_WIDTH_M, GraspPlan, PinchLine, palm_rotation, pose_of
from gendex.solve.hand import PAD_RADIUS_M
from gendex.solve.shape import PosedShape
from gendex_envs.errors import ExecutionError

log = logging.getLogger(__name__)

PINCH_POINT_PALM = np.array([0.04, -0.07, 0.08])
"""Palm-frame point where the clamp's thumb and index pads meet across the ring (found by finger IK: both reach
within 1.5 mm of it 1.1 and 1.3 cm to either side)."""
OPEN_GAP_M = 0.035
LEAD_M = 0.012
"""The clamp's closing targets lie this far past the pinch point (the closing guard keeps them near the measured
angles: 3-4 N a pad at 4 mm, and the scissors slipped while lifting; 4-6 N at 10 mm, 6-8 N at 16 mm held)."""
APPROACH_OUT_M = 0.07
GRAVITY = 9.81
HINGE_MIN_MOMENT_NM = 0.08
"""A tool whose weight pulls this hard (N m) about its ring is hinged, not clamped. The clamp held the closed
scissors (0.08 kg, 0.03 N m about the ring) in 45-90 % of the grasp benchmark's attempts and the wrench (0.15 kg,
0.11 N m) in 0-15 %: its pads resist the tool's turn about the ring by friction over the 7 mm of its thickness. The
hinge lets the tool turn, and the tool hangs below it."""
HANG_UP_M = 0.24
"""The lift of a hooked tool, straight up (it hangs from the finger). A hinged tool lifted so from the pinch turned
about the pinch line, its far end slid to the edge, and often it twisted out of the pads as it swung down (lifted 6 cm
outwards as well, the far end left the edge early and it swung further): it is stood up on its far end instead."""
PIVOT_CLEAR_M = 0.06
"""After the tool has stood up on its far end (:func:`~gendex.solve.edge_geometry.pivot_step`), the hand lifts it this
much straight up: it hangs clear of the table."""
PIVOT_MAX_STEPS = 120
PIVOT_UPRIGHT_RAD = np.radians(12.0)
"""The tool stands up until the line from its centre of mass to the ring is this close to vertical."""
PIVOT_LOST_M = 0.03
"""The stand-up ends where the ring is this far from where it was in the hand: the pinch lost it (else the hand went
on round an arc about a tool that stays on the table)."""
PIVOT_PLAN_STEP_M = 0.03
"""Arc steps of the predicted stand-up along which the plan checks the arm's reach."""
ABOVE_M = 0.12
BRING_STEPS = 40


class EdgePinch(EdgeDrag):
    """The drag (:class:`~gendex.solve.edge_drag.EdgeDrag`), then the pinch and the lift of one flat ringed object
    (see the module docstring)."""

    def plan(self, shape: PosedShape) -> GraspPlan:
        """The pinch of the overhanging ring (``shape``: the object's geometry now): a clamp across its far side
        when the tool's weight twists it little about the ring, else a hinge across it (:data:`HINGE_MIN_MOMENT_NM`);
        the thumb closed on a hooked ring."""
        if self.hooked:
            return self._thumb_on_hook()
        ring = self._ring_on_table()
        lever = float(np.linalg.norm(shape.centroid()[:2] - ring[:2]))
        return (self._hinge(shape, ring) if self.mass_kg * GRAVITY * lever >= HINGE_MIN_MOMENT_NM else
                self._clamp(shape, ring))

    def _thumb_on_hook(self) -> GraspPlan:
        """The hooked ring's grasp: the thumb's pad closed (guarded) towards the ring's measured centre, the hand where
        it is, then the lift."""
        m = self.m
        thumb, miss = self._thumb_reach()
        hand = {j: float(m.target()[m.ik.joint_names.index(j)]) for j in DRAG_HAND | HOOK_HOLD | HOOK_FLEX}
        return GraspPlan("edge", m.ik.fk(m.target()), np.array([0.0, 0.0, -1.0]), approach_m=0.0,
                         open_hand=hand, closing=((thumb, HOOK_STEPS),),
                         note=f"hook, the index curled through the ring, the thumb closed on it ({1000 * miss:.0f} mm "
                              "short of its centre)", lift=self._rise)

    def _over(self, plan: GraspPlan) -> np.ndarray | None:
        """Arm joints :data:`ABOVE_M` over ``plan``'s pre-grasp pose (the hand open as planned), or None."""
        start = self.m.with_hand(self.m.target(), plan.open_hand)
        return self.m.ik.solve(sapien.Pose(plan.pregrasp.p + [0.0, 0.0, ABOVE_M], plan.palm.q), start, restarts=16)

    def _clamp(self, shape: PosedShape, ring: np.ndarray) -> GraspPlan:
        """The thumb's and the index's pads closed on the ring's far side from below and above, the fingers along
        the edge and the palm facing the table's side: the thumb under the ring at the +y edge, over it at the -y
        edge (the arm reaches no pose with the fingers pointing across the table)."""
        side = float(np.sign(ring[1]))  # the edge it was dragged over
        out = np.array([0.0, side, 0.0])
        spans = sorted((a, b) for a, b in shape.ray_intervals(ring, out) if b > 0.0)
        if not spans:
            raise ExecutionError(f"no material of {self.name!r} beyond its ring", cause="grasp_failed")
        point = ring + out * (max(spans[0][0], 0.0) + spans[0][1]) / 2
        log.debug("edge clamp of %r: ring at %s, pinch point %s", self.name, np.round(ring, 3), np.round(point, 3))
        rot = palm_rotation(np.array([1.0, 0.0, 0.0]), -out)
        up = rot.T @ np.array([0.0, 0.0, 1.0 if rot[2, 0] < 0 else -1.0])  # palm frame, from the thumb to the index

        def pads(gap: float) -> dict[str, float]:
            ff, _ = self.hand.finger_ik("ff", PINCH_POINT_PALM + gap * up)
            th, _ = self.hand.finger_ik("th", PINCH_POINT_PALM - gap * up)
            return ff | th

        plan = GraspPlan("edge", pose_of(rot, point - rot @ PINCH_POINT_PALM), -out, approach_m=APPROACH_OUT_M,
                         open_hand=pads(OPEN_GAP_M), closing=((pads(-LEAD_M), 15),),
                         note=f"clamp of the ring {1000 * (side * point[1] - self.edge_y):.0f} mm past the table's "
                              "edge, thumb " + ("below" if rot[2, 0] < 0 else "above"))
        self._high = self._over(plan)
        if self._high is None:
            raise ExecutionError(f"no IK over the edge clamp of {self.name!r}", cause="no_ik")
        return plan

    def _hinge(self, shape: PosedShape, ring: np.ndarray) -> GraspPlan:
        """A pinch across the overhanging ring, level with it (``shape``: the object's geometry now): the first
        candidate whose open hand keeps out of the table and the tool and that the arm reaches over the edge."""
        m = self.m
        side = float(np.sign(ring[1]))  # the edge it was dragged over
        fp = shape.footprint()
        centre = np.array([ring[0], ring[1], fp.bottom + fp.height / 2])
        synth = PastEdge(self.hand, shape, m.env.table_height, self.edge_y, self.half_x)
        along = shape.centroid()[:2] - ring[:2]  # the tool hangs along this from the pinch
        across = np.arctan2(along[0], -along[1])  # heading of the horizontal line square to it
        found = []
        for deg in hinge_headings(across):
            for sign in (1.0, -1.0):
                a = across + np.radians(deg)
                d = sign * np.array([np.cos(a), np.sin(a), 0.0])
                origin = centre - 0.1 * d
                spans = shape.ray_intervals(origin, d)
                if not spans or spans[-1][1] - spans[0][0] > PINCH_MAX_WIDTH_M:
                    continue
                line = PinchLine(origin + spans[0][0] * d, origin + spans[-1][1] * d, f"across the ring, {deg:+.0f}°")
                for group in synth.pinch_plans(line):
                    for p in group:
                        dz = self._closing_dz(p, line)
                        p = replace(p, palm=sapien.Pose(p.palm.p - [0.0, 0.0, float(np.mean(dz))], p.palm.q))
                        if synth.hand_clear(p):
                            found.append((abs(float(dz[0] - dz[1])), len(found), p, line.axis))
                            break
        for tilt, _, p, axis in sorted(found, key=lambda f: f[:2]):
            far, via = far_edge(shape.vertices, centre, axis, along, m.env.table_height), [np.zeros(3)]
            while (step := pivot_step(centre + via[-1], far, axis, PIVOT_PLAN_STEP_M)) is not None:
                via.append(via[-1] + step)
            q = self._reach(p, [*via[1:], via[-1] + [0.0, 0.0, PIVOT_CLEAR_M]])
            if q is None:
                continue
            self._high, self._axis = q, axis
            gap = 1000 * (side * ring[1] - self.edge_y)
            log.debug("edge hinge of %r: ring %.0f mm past the edge, pads %.1f mm apart in height, %s", self.name,
                      gap, 1000 * tilt, p.note)
            return replace(p, kind="edge", lift=self._stand_up,
                           note=f"hinge, ring {gap:.0f} mm past the edge, {p.note}")
        raise ExecutionError(f"no pinch across the ring of {self.name!r} past the table's edge that the arm reaches "
                             f"({len(found)} clear of the table and the tool)", cause="no_ik")

    def _rise(self, m_per_step: float, up_m: float = HANG_UP_M) -> Generator[np.ndarray, None, float]:
        """The palm straight up ``up_m`` (as far as the arm reaches); returns how far it rose."""
        done = yield from self.m.cartesian(np.array([0.0, 0.0, up_m]), m_per_step, True, partial=True)
        return done * up_m

    def _stand_up(self, m_per_step: float) -> Generator[np.ndarray, None, float]:
        """The hinged tool stood up on its far end (:func:`pivot_step`, re-aimed every step from the ring's and the
        tool's measured poses, so that its far end need not slide), then lifted :data:`PIVOT_CLEAR_M` straight up;
        returns how far the palm rose."""
        m = self.m
        z0 = float(m.ik.fk(m.target()).p[2])
        toward = self._com()[:2] - self.ring()[:2]
        held = m.ik.fk(m.qpos()).inv() * sapien.Pose(self.ring())  # the ring in the palm's frame
        for _ in range(PIVOT_MAX_STEPS):
            ring = self.ring()
            if np.linalg.norm((m.ik.fk(m.qpos()) * held).p - ring) > PIVOT_LOST_M:
                log.debug("%r's ring is no longer in the pinch: it is not stood up further", self.name)
                break
            down = ring - self._com()
            if down[2] > np.cos(PIVOT_UPRIGHT_RAD) * np.linalg.norm(down):
                break  # it stands (about) upright below the ring
            pose = self._pose(m, self.name).to_transformation_matrix()
            verts = self.verts_local @ pose[:3, :3].T + pose[:3, 3]
            far = far_edge(verts, ring, self._axis, toward, m.env.table_height)
            step = pivot_step(ring, far, self._axis, m_per_step)
            if step is None:
                break
            # one guarded palm step (an arc step's chord is shorter than m_per_step)
            if (yield from m.cartesian(step, m_per_step, True, partial=True)) < 1.0:
                log.debug("no IK standing %r up on its far end: it is lifted from here", self.name)
                break
        yield from self._rise(m_per_step, PIVOT_CLEAR_M)
        return float(m.ik.fk(m.target()).p[2]) - z0

    def _closing_dz(self, plan: GraspPlan, line: PinchLine) -> np.ndarray:
        """[2] height (m) of the thumb's and the index's pad over ``line`` where each crosses its contact point
        while the hand closes from ``plan.open_hand`` to its closing targets (straight in joint space)."""
        close = plan.closed_hand
        rot = plan.palm.to_transformation_matrix()[:3, :3]
        ts = np.linspace(0.0, 1.0, 41)
        pads = np.array([self.hand.pads({j: plan.open_hand.get(j, v) + t * (v - plan.open_hand.get(j, v))
                                         for j, v in close.items()}) for t in ts])[:, :2] @ rot.T + plan.palm.p
        out = np.zeros(2)
        for k, (contact, r) in enumerate(((line.thumb, PAD_RADIUS_M["th"]), (line.finger, PAD_RADIUS_M["ff"]))):
            inward = line.axis if k == 0 else -line.axis
            s = (pads[:, k] - contact) @ inward + r  # > 0: the pad's surface is past the contact point
            i = int(np.argmax(s > 0.0)) if np.any(s > 0.0) else len(ts) - 1
            out[k] = pads[i, k, 2] - contact[2]
        return out

    def _reach(self, plan: GraspPlan, lift: list[np.ndarray]) -> np.ndarray | None:
        """Arm joints :data:`ABOVE_M` over ``plan``'s pre-grasp pose when the arm reaches that, the grasp pose and each
        point of the lift from there (``lift``: the palm's offsets from the grasp pose, in order), keeping the arm and
        the open hand out of the table top on the way (the joint ramp there included), else None."""
        m = self.m
        q = self._over(plan)
        if q is None:
            return None
        start = m.with_hand(m.target(), plan.open_hand)
        path = [start + t * (q - start) for t in np.linspace(0.0, 1.0, 9)[1:]]
        for p in (plan.pregrasp.p, plan.palm.p, *(plan.palm.p + v for v in lift)):
            path.append(m.ik.solve(sapien.Pose(p, plan.palm.q), path[-1], restarts=4))
            if path[-1] is None:
                return None
        cover = self.hand.spheres(plan.open_hand)
        m.collision.cover_hand(cover.centers, cover.radii)
        try:
            return q if all(self._out_of_table(x, len(cover.radii)) for x in path) else None
        finally:
            m.collision.cover_hand(None)

    def bring_hand(self, plan: GraspPlan) -> Iterator[np.ndarray]:
        """The open hand to :data:`ABOVE_M` over the pre-grasp pose, then straight down outside the edge to it.
        The first move is a joint-space ramp, not a planned path: the arm's collision model takes the table for a
        plane everywhere, and past the edge the forearm hangs below it (both ends of the ramp are over the edge,
        the hand 5 cm or more above the table)."""
        m = self.m
        if self.hooked:  # the hand is at the hooked ring's grasp already
            return
        start = m.with_hand(m.target(), plan.open_hand)
        goal = start.copy()
        goal[m.arm] = self._high[m.arm]
        yield from m.ramp(goal, BRING_STEPS)
        yield from m.cartesian(np.array([0.0, 0.0, -ABOVE_M]), 0.005)
