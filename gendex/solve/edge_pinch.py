"""Flat tools with a finger ring (closed scissors, a ring wrench): dragged by the ring to the table's side edge, then
pinched across the ring where it overhangs.

No pinch from the table lifts a tool 6-7 mm tall: the fingertip pads (7.1 and 9.2 mm radius) meet its top edge from
above and push it into the table (``docs/solving.md``). A person slides such a tool off the edge of the table first.
:class:`EdgePinch` does the same when no grasp of the object held in a physics trial and the object is flat with a
hole a fingertip fits in (:func:`find_ring`):

1. **drag** — the index fingertip goes down into the ring (fingers pointing down, the index straight and tilted
   :data:`DRAG_TILT_RAD` so its tip trails its knuckle: a finger whose tip leads is lifted out of the ring by the
   wall's reaction), its end pressed lightly on the table (:data:`DRAG_TIP_Z_M`), and pulls the ring towards the
   side edge the ring leads to (a tool pushed ahead of its ring goes over the edge first), re-aimed every step from
   the ring's measured position, the commanded tip at most :data:`DRAG_LEAD_MAX_M` ahead of it; it stops when the
   ring's centre is :data:`OVERHANG_M` past the edge;
2. **pinch** — the finger comes out, and the open hand comes down outside the edge and slides in with the fingers
   along the edge (+x) and the palm facing the table's side: the thumb pad under the ring and the index pad over it
   at the +y edge, the other way round at the -y edge (the arm reaches no pose with the fingers pointing across the
   table). The returned :class:`~gendex.solve.grasp.GraspPlan` closes both pads on the ring's far side with a
   :data:`LEAD_M` lead; the grasp primitive lifts it like any other grasp.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator

import numpy as np
import sapien

from gendex.solve.grasp import GraspPlan, palm_rotation, pose_of
from gendex.solve.hand import TIP_ALONG_M, HandModel
from gendex.solve.motion import ArmHandMotion
from gendex.solve.shape import PosedShape
from gendex_envs.errors import ExecutionError

log = logging.getLogger(__name__)

FLAT_M = 0.012
"""Only objects at most this tall are dragged to the edge."""
RING_MIN_RADIUS_M = 0.006
"""A hole the index fingertip fits in (its end cap, 7.1 mm radius, is narrower at the height of a 7 mm ring;
the wrench's octagonal 15 mm ring is 6.9 mm to its flats)."""
RING_MAX_RADIUS_M = 0.015
"""Larger holes are not looked for (a point that far from all material is beside the tool)."""
RING_ROUND = 1.5
"""A hole is a ring when material surrounds it in every horizontal direction within this many times its radius (a
notch in the outline is open on one side)."""
DRAG_HAND = {"FFJ3": 0.0, "FFJ2": 0.0, "FFJ1": 0.0, "FFJ0": 0.0,
             "MFJ2": 1.5, "MFJ1": 1.5, "MFJ0": 1.2, "RFJ2": 1.5, "RFJ1": 1.5, "RFJ0": 1.2,
             "LFJ2": 1.5, "LFJ1": 1.5, "LFJ0": 1.2, "THJ4": 1.0, "THJ3": 1.2, "THJ0": -1.0}
"""The index straight, the other fingers and the thumb curled out of its way."""
DRAG_TILT_RAD = np.radians(25.0)
DRAG_TIP_Z_M = 0.004
"""Commanded height of the index's end-cap centre while it drags: 3 mm below where the finger's end rests on the
table, so that it presses lightly and stays in the ring."""
DRAG_M_PER_STEP = 0.005
DRAG_LEAD_MAX_M = 0.025
DRAG_MAX_STEPS = 200
DRAG_AIM_X_M = -0.2
"""Where along the side edge the ring is dragged to: an x the arm reaches with room to lift (at x = 0.25 the palm is
1.24 m from the base and the arm could not lift from there)."""
OVERHANG_M = 0.02
"""How far past the edge the ring's centre is dragged (3.5 cm tipped closed scissors off when the finger moved)."""
PINCH_POINT_PALM = np.array([0.04, -0.07, 0.08])
"""Palm-frame point where the thumb's and the index's pads meet across the ring (found by finger IK: both reach
within 1.5 mm of it 1.1 and 1.3 cm to either side)."""
OPEN_GAP_M = 0.035
LEAD_M = 0.012
"""The pads' closing targets lie this far past the pinch point (the closing guard keeps them near the measured angles:
3-4 N a pad at 4 mm, and the scissors slipped while lifting; 4-6 N at 10 mm, 6-8 N at 16 mm held)."""
APPROACH_OUT_M = 0.07
ABOVE_M = 0.12
BRING_STEPS = 40


def find_ring(shape: PosedShape, step_m: float = 0.001) -> np.ndarray | None:
    """World centre [3] (at mid-height) of the widest hole through a flat ``shape`` that a fingertip fits in and
    material surrounds (:data:`RING_MIN_RADIUS_M`, :data:`RING_ROUND`), or None."""
    fp = shape.footprint()
    if fp.height > FLAT_M:
        return None
    z = fp.bottom + fp.height / 2
    side = np.array([-fp.axis[1], fp.axis[0]])
    a = np.arange(-fp.length / 2, fp.length / 2, step_m)
    b = np.arange(-fp.width / 2, fp.width / 2, step_m)
    pts = np.array([[*(fp.center + s * fp.axis + t * side), z] for s in a for t in b])
    sd = shape.signed_distance(pts)
    dirs = [np.array([np.cos(t), np.sin(t), 0.0]) for t in np.linspace(0, 2 * np.pi, 8, endpoint=False)]
    for i in np.argsort(-sd):
        if sd[i] > RING_MAX_RADIUS_M:
            continue  # open table beside the tool, not a hole in it
        if sd[i] < RING_MIN_RADIUS_M:
            return None
        ahead = [[a for a, b in shape.ray_intervals(pts[i], d) if b > 0.0] for d in dirs]
        if all(h and min(h) <= RING_ROUND * sd[i] for h in ahead):
            return pts[i]
    return None


class EdgePinch:
    """The drag and the pinch of one flat ringed object (see the module docstring)."""

    def __init__(self, m: ArmHandMotion, hand: HandModel, name: str, ring_in_object: np.ndarray, edge_y: float):
        self.m, self.hand, self.name = m, hand, name
        self.ring_local = ring_in_object
        self.edge_y = edge_y

    @classmethod
    def of(cls, m: ArmHandMotion, hand: HandModel, name: str, shape: PosedShape) -> EdgePinch | None:
        """The edge pinch of ``name`` (whose posed shape is ``shape``), or None when it is not a flat ringed object."""
        ring = find_ring(shape)
        if ring is None:
            return None
        local = (cls._pose(m, name).inv() * sapien.Pose(ring)).p
        return cls(m, hand, name, local, float(m.env.task_spec.table.size_m[1]) / 2)

    @staticmethod
    def _pose(m: ArmHandMotion, name: str) -> sapien.Pose:
        p = m.env.obj(name).pose
        return sapien.Pose(p.p[0].cpu().numpy(), p.q[0].cpu().numpy())

    def ring(self) -> np.ndarray:
        """The ring's measured centre (world) now."""
        return (self._pose(self.m, self.name) * sapien.Pose(self.ring_local)).p

    # ------------------------------------------------------------------ the index's tip
    def _tip(self, q: np.ndarray) -> np.ndarray:
        return (self.m.ik.fk(q, "ffdistal") * sapien.Pose([0.0, 0.0, TIP_ALONG_M])).p

    def _palm_for_tip(self, rot: np.ndarray, tip: np.ndarray, q: np.ndarray, restarts: int = 0) -> np.ndarray | None:
        """Arm joints putting the index's end at ``tip`` with the palm turned ``rot`` (fixed point on the tip's
        offset from the palm)."""
        palm = pose_of(rot, tip + (self.m.ik.fk(q).p - self._tip(q)))
        for _ in range(3):
            sol = self.m.ik.solve(palm, q, restarts=restarts)
            if sol is None:
                return None
            palm = pose_of(rot, palm.p + tip - self._tip(sol))
            q, restarts = sol, 0
        return self.m.ik.solve(palm, q, restarts=0)

    def _move_tip(self, rot: np.ndarray, tip: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
        q = self._palm_for_tip(rot, tip, self.m.target()) if q is None else q
        if q is None:
            raise ExecutionError(f"no IK for the index's tip at {np.round(tip, 3)} dragging {self.name!r} to the "
                                 "table's edge", cause="no_ik")
        t = self.m.target()
        t[self.m.arm] = q[self.m.arm]
        return self.m.emit(t)

    # ------------------------------------------------------------------ the sequence
    def drag(self) -> Iterator[np.ndarray]:
        """Index into the ring, ring dragged :data:`OVERHANG_M` past the side edge, index out and up."""
        m = self.m
        ring = self.ring()
        if abs(ring[1]) > self.edge_y:  # over the edge already (a second try after a slip)
            return
        com = self._pose(m, self.name).p
        lead = ring[1] - com[1]
        side = float(np.sign(lead) if abs(lead) > 0.02 else (np.sign(ring[1]) or 1.0))
        goal = np.array([DRAG_AIM_X_M, side * (self.edge_y + 0.06), 0.0])
        d0 = goal - ring
        d0[2] = 0.0
        d0 /= np.linalg.norm(d0)
        fingers = -np.cos(DRAG_TILT_RAD) * np.array([0.0, 0.0, 1.0]) - np.sin(DRAG_TILT_RAD) * d0
        normal = np.cross(d0, [0.0, 0.0, 1.0])
        rot = palm_rotation(fingers, normal * (np.sign(normal[0]) or 1.0))
        above = np.array([ring[0], ring[1], DRAG_TIP_Z_M + 0.08])
        q = self._palm_for_tip(rot, above, m.with_hand(m.target(), DRAG_HAND), restarts=12)
        if q is None:
            raise ExecutionError(f"no IK above the ring of {self.name!r}", cause="no_ik")
        yield from m.move_arm(q, hand=m.with_hand(m.target(), DRAG_HAND))
        for z in np.linspace(above[2], DRAG_TIP_Z_M, 20):
            ring = self.ring()
            yield self._move_tip(rot, np.array([ring[0], ring[1], z]))
        tip = self._tip(m.target())
        for _ in range(DRAG_MAX_STEPS):
            ring = self.ring()
            if side * ring[1] > self.edge_y + OVERHANG_M:
                break
            d = goal - ring
            d[2] = 0.0
            tip = tip + DRAG_M_PER_STEP * d / np.linalg.norm(d)
            ahead = tip[:2] - ring[:2]
            if np.linalg.norm(ahead) > DRAG_LEAD_MAX_M:
                tip[:2] = ring[:2] + DRAG_LEAD_MAX_M * ahead / np.linalg.norm(ahead)
            tip[2] = DRAG_TIP_Z_M
            q = self._palm_for_tip(rot, tip, m.target())
            if q is None and side * ring[1] > self.edge_y:
                break  # the arm reaches no further, but the ring is over the edge
            yield self._move_tip(rot, tip, q)
        else:
            raise ExecutionError(f"{self.name!r}'s ring is still {self.edge_y - side * self.ring()[1]:.3f} m short of "
                                 f"the table's edge after {DRAG_MAX_STEPS} steps", cause="target_not_reached")
        ring = self.ring()
        for k in range(1, 4):  # centre the finger in the ring, so that it leaves without pulling
            yield self._move_tip(rot, tip + (np.array([ring[0], ring[1], tip[2]]) - tip) * k / 3)
        tip = np.array([ring[0], ring[1], tip[2]])
        for k in range(1, 11):
            yield self._move_tip(rot, tip + [0.0, 0.0, 0.005 * k])

    def plan(self, shape: PosedShape) -> GraspPlan:
        """The pinch across the overhanging ring's far side (``shape``: the object's geometry now)."""
        ring = self.ring()
        side = float(np.sign(ring[1]))  # the edge it was dragged over
        out = np.array([0.0, side, 0.0])
        spans = sorted((a, b) for a, b in shape.ray_intervals(ring, out) if b > 0.0)
        if not spans:
            raise ExecutionError(f"no material of {self.name!r} beyond its ring", cause="grasp_failed")
        point = ring + out * (max(spans[0][0], 0.0) + spans[0][1]) / 2
        log.debug("edge pinch of %r: ring at %s, pinch point %s", self.name, np.round(ring, 3), np.round(point, 3))
        rot = palm_rotation(np.array([1.0, 0.0, 0.0]), -out)
        up = rot.T @ np.array([0.0, 0.0, 1.0 if rot[2, 0] < 0 else -1.0])  # palm frame, from the thumb to the index

        def pads(gap: float) -> dict[str, float]:
            ff, _ = self.hand.finger_ik("ff", PINCH_POINT_PALM + gap * up)
            th, _ = self.hand.finger_ik("th", PINCH_POINT_PALM - gap * up)
            return ff | th

        return GraspPlan("edge", pose_of(rot, point - rot @ PINCH_POINT_PALM), -out, approach_m=APPROACH_OUT_M,
                         open_hand=pads(OPEN_GAP_M), closing=((pads(-LEAD_M), 15),),
                         note=f"edge pinch of the ring {1000 * (side * point[1] - self.edge_y):.0f} "
                              "mm past the table's edge, thumb " + ("below" if rot[2, 0] < 0 else "above"))

    def bring_hand(self, plan: GraspPlan) -> Iterator[np.ndarray]:
        """The open hand to :data:`ABOVE_M` over the pre-grasp pose, then straight down outside the edge to it.
        The first move is a joint-space ramp, not a planned path: the arm's collision model takes the table for a
        plane everywhere, and past the edge the forearm hangs below it (both ends of the ramp are over the edge,
        the hand 5 cm or more above the table)."""
        m = self.m
        start = m.with_hand(m.target(), plan.open_hand)
        high = sapien.Pose(plan.pregrasp.p + [0.0, 0.0, ABOVE_M], plan.palm.q)
        q = m.ik.solve(high, start, restarts=16)
        if q is None:
            raise ExecutionError(f"no IK over the edge pinch of {self.name!r}", cause="no_ik")
        goal = start.copy()
        goal[m.arm] = q[m.arm]
        yield from m.ramp(goal, BRING_STEPS)
        yield from m.cartesian(np.array([0.0, 0.0, -ABOVE_M]), 0.005)
