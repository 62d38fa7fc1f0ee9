"""Flat tools with a finger ring (closed scissors, a ring wrench): dragged by the ring to the table's side edge, then
pinched across the ring where it overhangs.

No pinch from the table lifts a tool 6-7 mm tall: the fingertip pads (7.1 and 9.2 mm radius) meet its top edge from
above and push it into the table (``docs/solving.md``). A person slides such a tool off the edge of the table first.
:class:`EdgePinch` does the same when no grasp of the object held in a physics trial and the object is flat with a
hole a fingertip fits in (:func:`find_ring`):

1. **drag** — the index fingertip goes down into the ring (fingers pointing down, the index straight and tilted
   :data:`DRAG_TILT_RAD` so its tip trails its knuckle: a finger whose tip leads is lifted out of the ring by the
   wall's reaction), its end pressed lightly on the table (:data:`DRAG_TIP_Z_M`) or, where the hole is narrower than
   the finger's end and it rests on the ring's rim (the wrench), held where it rests: pressed there it jams the ring,
   and the tool keeps its heading instead of trailing behind the ring (it reached the edge lying along it and fell
   off); the ring is pulled towards the side edge it leads to (a tool pushed ahead of its ring goes over the edge
   first), re-aimed every step from the ring's measured position, the commanded tip at most
   :data:`DRAG_LEAD_MAX_M` ahead of it (where the arm's configuration reaches no further, the finger grips the
   ring again from one solved past the edge, :data:`MAX_REGRIPS`); it stops when the ring's centre is
   :data:`OVERHANG_M` past the edge;
2. **pinch** — the finger comes out (curled out where the arm rises no higher), and the open hand pinches the
   overhanging ring. A tool whose weight turns it little about the ring (:data:`HINGE_MIN_MOMENT_NM`: the closed
   scissors) is *clamped*: the hand comes down outside the edge and slides in with the fingers along the edge and the
   palm facing the table's side, the thumb's pad under the ring and the index's over it at the +y edge, the other way
   round at the -y edge (the arm reaches no pose with the fingers pointing across the table), both closed on the
   ring's far side with a :data:`LEAD_M` lead. A heavier one (the wrench) is *hinged*: the hand comes down over the
   ring and pinches it across, level with it, along a line about square to the tool (:data:`HANG_HEADINGS_DEG`):
   past the edge the fingers may reach below the table top, so the pads meet the ring's outer wall side-on. Of the
   pinches the synthesis offers there (:meth:`~gendex.solve.grasp.GraspSynthesizer.pinch_plans`, the table cut off
   at its edge), the one whose pads cross their contact points at the most even height while closing comes first (a
   pad passing low lifts its side and rolls the tool over); the arm must reach it without the arm or the open hand
   dipping into the table top. Lifted :data:`HANG_UP_M` straight up, the tool turns about the pinch line, its far end
   slides to the edge, and it hangs below the pads, held by friction along them rather than against its own moment.
"""

from __future__ import annotations

import logging
from collections.abc import Generator, Iterator
from dataclasses import replace

import numpy as np
import sapien

from gendex.solve.grasp import PINCH_MAX_WIDTH_M, GraspPlan, GraspSynthesizer, PinchLine, palm_rotation, pose_of
from gendex.solve.hand import PAD_RADIUS_M, TIP_ALONG_M, HandModel
from gendex.solve.motion import ArmHandMotion
from gendex.solve.shape import PosedShape
from gendex_envs.errors import ExecutionError
from gendex_envs.physx import px_bodies

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
CURL_INDEX = {"FFJ2": 1.4, "FFJ1": 1.4, "FFJ0": 1.2}
"""The index curled: its tip rises out of a ring where the arm reaches no higher."""
DRAG_TILT_RAD = np.radians(25.0)
DRAG_TIP_Z_M = 0.004
"""Commanded height of the index's end-cap centre while it drags: 3 mm below where the finger's end rests on the
table, so that it presses lightly and stays in the ring (not where the finger is wedged in a narrow ring:
:data:`WEDGED_Z_M`)."""
SETTLE_STEPS = 6
WEDGED_Z_M = 0.0085
"""A finger's end whose centre stays higher than this in the ring, :data:`SETTLE_STEPS` after it was sent down (it
rests on the table at 7.1 mm), is wedged in it."""
DRAG_M_PER_STEP = 0.005
DRAG_LEAD_MAX_M = 0.025
DRAG_MAX_STEPS = 200
MAX_REGRIPS = 1
"""Where the arm's configuration reaches no further while dragging, the finger leaves the ring and comes back in
from a configuration solved past the edge, this many times."""
DRAG_AIM_X_M = -0.2
"""Where along the side edge the ring is dragged to: an x the arm reaches with room to lift (at x = 0.25 the palm is
1.24 m from the base and the arm could not lift from there)."""
OVERHANG_M = 0.02
"""How far past the edge the ring's centre is dragged (3.5 cm tipped closed scissors off when the finger moved)."""
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
scissors (0.08 kg, 0.03 N m about the ring) in 50-80 % of the grasp benchmark's attempts and the wrench (0.15 kg,
0.11 N m) in 0-15 %: its pads resist the tool's turn about the ring by friction over the 7 mm of its thickness. The
hinge lets the tool turn, and the tool hangs below it."""
HANG_HEADINGS_DEG = (0.0, 20.0, -20.0, 40.0, -40.0)
"""Pinch lines through the ring's centre, level with it, in degrees from square to the tool (each both ways round):
square to it, the line crosses the wrench's ring through its centre and the tool turns about it in its own plane."""
HANG_UP_M = 0.24
"""The lift after the pinch, straight up: the tool turns about the pinch line and hangs below the pads, its far end
above the table top. Its far end leaves the edge when it hangs nearly straight down and it barely swings; lifted 6 cm
outwards as well, the far end left the edge early, the tool swung down and the wrench twisted out of the pads."""
ARM_MARGIN_M = 0.01
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

    def __init__(self, m: ArmHandMotion, hand: HandModel, name: str, ring_in_object: np.ndarray, edge_y: float,
                 mass_kg: float = 0.0):
        self.m, self.hand, self.name, self.mass_kg = m, hand, name, mass_kg
        self.ring_local = ring_in_object
        self.edge_y = edge_y
        self.half_x = float(m.env.task_spec.table.size_m[0]) / 2
        self._high: np.ndarray | None = None
        """Arm joints over the planned pinch (:meth:`plan`), where :meth:`bring_hand` takes the open hand first."""

    @classmethod
    def of(cls, m: ArmHandMotion, hand: HandModel, name: str, shape: PosedShape) -> EdgePinch | None:
        """The edge pinch of ``name`` (whose posed shape is ``shape``), or None when it is not a flat ringed object."""
        ring = find_ring(shape)
        if ring is None:
            return None
        local = (cls._pose(m, name).inv() * sapien.Pose(ring)).p
        return cls(m, hand, name, local, float(m.env.task_spec.table.size_m[1]) / 2,
                   float(px_bodies(m.env.obj(name))[0].mass))

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
        ring = self._ring_on_table()
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
        z_drag = yield from self._enter_ring(rot, m.with_hand(m.target(), DRAG_HAND))
        tip, regrips = self._tip(m.target()), 0
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
            tip[2] = z_drag
            q = self._palm_for_tip(rot, tip, m.target())
            if q is None and regrips < MAX_REGRIPS:
                # the arm's configuration reaches no further: finger out, and back in from a configuration that
                # reaches past the edge (solved there with restarts)
                regrips += 1
                past = ring + d / np.linalg.norm(d) * (self.edge_y + OVERHANG_M + 0.01 - side * ring[1])
                seed = self._palm_for_tip(rot, np.array([past[0], past[1], z_drag]),
                                          m.with_hand(m.target(), DRAG_HAND), restarts=12)
                if seed is not None:
                    log.debug("no IK dragging %r's ring on: the finger grips it again", self.name)
                    yield from self._leave_ring(rot, tip)
                    z_drag = yield from self._enter_ring(rot, m.with_hand(seed, DRAG_HAND))
                    tip = self._tip(m.target())
                    continue
            if q is None and side * ring[1] > self.edge_y:
                break  # the arm reaches no further, but the ring is over the edge
            yield self._move_tip(rot, tip, q)
        else:
            raise ExecutionError(f"{self.name!r}'s ring is still {self.edge_y - side * self.ring()[1]:.3f} m short of "
                                 f"the table's edge after {DRAG_MAX_STEPS} steps", cause="target_not_reached")
        yield from self._leave_ring(rot, tip)

    def _enter_ring(self, rot: np.ndarray, seed: np.ndarray) -> Generator[np.ndarray, None, float]:
        """The straight index down into the ring (the arm solved near ``seed``, a joint vector); returns the height
        to drag at: :data:`DRAG_TIP_Z_M`, or where the finger rests when it is wedged in the ring."""
        m = self.m
        ring = self.ring()
        above = np.array([ring[0], ring[1], DRAG_TIP_Z_M + 0.08])
        q = self._palm_for_tip(rot, above, seed, restarts=12)
        if q is None:
            raise ExecutionError(f"no IK above the ring of {self.name!r}", cause="no_ik")
        yield from m.move_arm(q, hand=m.with_hand(m.target(), DRAG_HAND))
        for z in np.linspace(above[2], DRAG_TIP_Z_M, 20):
            ring = self.ring()
            yield self._move_tip(rot, np.array([ring[0], ring[1], z]))
        yield from m.hold(SETTLE_STEPS)
        # a finger resting on the ring's rim (a hole narrower than its end) is not pressed on: pressed, it jams the
        # ring and the tool keeps its heading instead of trailing behind the ring
        rest = float(self._tip(m.qpos())[2])
        return rest if rest > WEDGED_Z_M else DRAG_TIP_Z_M

    def _leave_ring(self, rot: np.ndarray, tip: np.ndarray) -> Iterator[np.ndarray]:
        """The index out of the ring after the drag: centred in it (so that it leaves without pulling), then up 5
        cm; where the arm reaches no further, from where it is, and by curling (:data:`CURL_INDEX`) where the arm
        rises no higher (at the +y edge the arm often reaches no pose 2.5 cm above the dragged ring)."""
        m = self.m
        ring = self.ring()
        for k in range(1, 4):  # centre the finger in the ring, so that it leaves without pulling
            goal = tip + (np.array([ring[0], ring[1], tip[2]]) - tip) * k / 3
            q = self._palm_for_tip(rot, goal, m.target())
            if q is None:  # at the arm's reach: the finger leaves from where it is
                log.debug("no IK centring the finger in %r's ring: raising it from where it is", self.name)
                break
            yield self._move_tip(rot, goal, q)
        tip = self._tip(m.target())
        for k in range(1, 11):
            q = self._palm_for_tip(rot, tip + [0.0, 0.0, 0.005 * k], m.target())
            if q is None:  # the arm rises no further with this hand: the index curls out of the ring instead
                log.debug("no IK raising the finger out of %r's ring at %d mm: curling it", self.name, 5 * k)
                yield from m.ramp(m.with_hand(m.target(), CURL_INDEX), 10)
                return
            yield self._move_tip(rot, tip + [0.0, 0.0, 0.005 * k], q)

    def plan(self, shape: PosedShape) -> GraspPlan:
        """The pinch of the overhanging ring (``shape``: the object's geometry now): a clamp across its far side
        when the tool's weight twists it little about the ring, else a hinge across it (:data:`HINGE_MIN_MOMENT_NM`)."""
        ring = self._ring_on_table()
        lever = float(np.linalg.norm(shape.centroid()[:2] - ring[:2]))
        return (self._hinge(shape, ring) if self.mass_kg * GRAVITY * lever >= HINGE_MIN_MOMENT_NM else
                self._clamp(shape, ring))

    def _ring_on_table(self) -> np.ndarray:
        """The ring's centre now; an ``ExecutionError`` when the tool has fallen off the table."""
        ring = self.ring()
        if ring[2] < self.m.env.table_height - 0.02:
            raise ExecutionError(f"{self.name!r} is off the table (its ring {-ring[2]:.2f} m below the top)",
                                 cause="slipped")
        return ring

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
        synth = _PastEdge(self.hand, shape, m.env.table_height, self.edge_y, self.half_x)
        along = shape.centroid()[:2] - ring[:2]  # the tool hangs along this from the pinch
        across = np.arctan2(along[0], -along[1])  # heading of the horizontal line square to it
        found = []
        for deg in HANG_HEADINGS_DEG:
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
                            found.append((abs(float(dz[0] - dz[1])), len(found), p))
                            break
        lift = (0.0, 0.0, HANG_UP_M)
        for tilt, _, p in sorted(found):
            q = self._reach(p, np.array(lift))
            if q is None:
                continue
            self._high = q
            gap = 1000 * (side * ring[1] - self.edge_y)
            log.debug("edge hinge of %r: ring %.0f mm past the edge, pads %.1f mm apart in height, %s", self.name,
                      gap, 1000 * tilt, p.note)
            return replace(p, kind="edge", lift=lift, note=f"hinge, ring {gap:.0f} mm past the edge, {p.note}")
        raise ExecutionError(f"no pinch across the ring of {self.name!r} past the table's edge that the arm reaches "
                             f"({len(found)} clear of the table and the tool)", cause="no_ik")

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

    def _reach(self, plan: GraspPlan, lift: np.ndarray) -> np.ndarray | None:
        """Arm joints :data:`ABOVE_M` over ``plan``'s pre-grasp pose when the arm reaches that, the grasp pose and the
        top of the lift from there, keeping the arm and the open hand out of the table top on the way (the joint
        ramp there included), else None."""
        m = self.m
        q = self._over(plan)
        if q is None:
            return None
        start = m.with_hand(m.target(), plan.open_hand)
        path = [start + t * (q - start) for t in np.linspace(0.0, 1.0, 9)[1:]]
        for p in (plan.pregrasp.p, plan.palm.p, plan.palm.p + lift):
            path.append(m.ik.solve(sapien.Pose(p, plan.palm.q), path[-1], restarts=4))
            if path[-1] is None:
                return None
        cover = self.hand.spheres(plan.open_hand)
        m.collision.cover_hand(cover.centers, cover.radii)
        try:
            return q if all(self._out_of_table(x, len(cover.radii)) for x in path) else None
        finally:
            m.collision.cover_hand(None)

    def _out_of_table(self, q: np.ndarray, n_hand: int) -> bool:
        """No sphere of the collision model at ``q`` dips into the table top's slab: the arm's by
        :data:`ARM_MARGIN_M`, the hand's (the last ``n_hand``) by nothing, as in the grasp synthesis."""
        c, r = self.m.collision.sphere_centres(q)
        margin = np.where(np.arange(len(r)) < len(r) - n_hand, ARM_MARGIN_M, 0.0)
        over = (np.abs(c[:, 0]) < self.half_x + r) & (np.abs(c[:, 1]) < self.edge_y + r)
        return not np.any(over & (c[:, 2] - r < self.m.env.table_height + margin))

    def bring_hand(self, plan: GraspPlan) -> Iterator[np.ndarray]:
        """The open hand to :data:`ABOVE_M` over the pre-grasp pose, then straight down outside the edge to it.
        The first move is a joint-space ramp, not a planned path: the arm's collision model takes the table for a
        plane everywhere, and past the edge the forearm hangs below it (both ends of the ramp are over the edge,
        the hand 5 cm or more above the table)."""
        m = self.m
        start = m.with_hand(m.target(), plan.open_hand)
        goal = start.copy()
        goal[m.arm] = self._high[m.arm]
        yield from m.ramp(goal, BRING_STEPS)
        yield from m.cartesian(np.array([0.0, 0.0, -ABOVE_M]), 0.005)


class _PastEdge(GraspSynthesizer):
    """Pinches of a tool overhanging the table's side edge: past the edge the hand may reach below the table top."""

    def __init__(self, hand: HandModel, shape: PosedShape, table_z: float, edge_y: float, half_x: float):
        super().__init__(hand, shape, table_z)
        self.edge_y, self.half_x = edge_y, half_x

    def table_gap(self, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
        off = (np.abs(centers[:, 1]) >= self.edge_y + radii) | (np.abs(centers[:, 0]) >= self.half_x + radii)
        return np.where(off, np.inf, super().table_gap(centers, radii))
