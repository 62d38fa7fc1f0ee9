"""Flat tools with a finger ring (closed scissors, a ring wrench): dragged by the ring to the table's side edge, then
hooked on the index through the ring, or pinched across the ring where it overhangs.

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
   :data:`HINGE_OVERHANG_M` past the edge (:data:`HOOK_OVERHANG_M` for a ring to be hooked), or, once it is
   :data:`OVERHANG_M` past, where the tool's centre of mass comes within :data:`COM_INSIDE_M` of the edge;
2. **hook** — a hole wider than the finger's end with room to spare (:data:`HOOK_MIN_RADIUS_M`: the scissors'): the
   finger is turned straight down in the ring and pushed through it below the table top (:data:`HOOK_TIP_Z_M`;
   backed up and sent once more where the ring goes down with it, :data:`HOOK_JAM_M`), and the index curls
   (:data:`HOOK_CURL`): the ring's wall is caught in the crook of its middle joint. The hand rises
   :data:`HOOK_RISE_M` with the tool hanging from the finger, the curl eases (:data:`HOOK_HOLD`) and the knuckle flexes
   (:data:`HOOK_FLEX`), bringing the ring to where the thumb reaches; the thumb closes on the ring (guarded) and the
   hand lifts. A ring threaded on the finger cannot slip out of a pinch: the clamp below held the scissors in 45-90 %
   of the grasp benchmark's attempts, mostly slipping. Where the finger does not go through, it is pinched instead;
3. **pinch** — the finger comes out (curled out where the arm rises no higher), and the open hand pinches the
   overhanging ring. A tool whose weight turns it little about the ring (:data:`HINGE_MIN_MOMENT_NM`) is *clamped*:
   the hand comes down outside the edge and slides in with the fingers along the edge and the palm facing the
   table's side, the thumb's pad under the ring and the index's over it at the +y edge, the other way round at the -y
   edge (the arm reaches no pose with the fingers pointing across the table), both closed on the ring's far side
   with a :data:`LEAD_M` lead. A heavier one (the wrench, whose 6.9 mm hole the finger does not pass) is *hinged*:
   the hand comes down over the ring and pinches it across, level with it, along a line about square to the tool
   (:data:`HANG_HEADINGS_DEG`): past the edge the fingers may reach below the table top, so the pads meet the ring's
   outer wall side-on. Of the pinches the synthesis offers there
   (:meth:`~gendex.solve.grasp.GraspSynthesizer.pinch_plans`, the table cut off at its edge), the one whose pads
   cross their contact points at the most even height while closing comes first (a pad passing low lifts its side
   and rolls the tool over); the arm must reach it without the arm or the open hand dipping into the table top.
   Lifted :data:`HANG_UP_M` straight up, the tool turns about the pinch line, its far end slides to the edge, and it
   hangs below the pads, held by friction along them rather than against its own moment.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Generator, Iterator
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
"""How far past the edge the ring's centre is dragged at least (3.5 cm tipped closed scissors off when the finger
moved)."""
HINGE_OVERHANG_M = 0.04
"""How far past the edge the ring of a tool to be hinged is dragged, unless its centre of mass comes within
:data:`COM_INSIDE_M` of the edge first. With the ring 2 cm past the edge the pads' pinch often dipped into the table
or its edge (no candidate clear of it) or the tool went off the table. At 4 cm the wrench held in 23 of 40 fresh
seeds (10220-10259) against 14 of 40 at 2 cm (the same seeds; ``docs/solving.md``)."""
COM_INSIDE_M = 0.03
"""The drag stops once the ring is :data:`OVERHANG_M` past the edge and the tool's centre of mass this close to it
(a tool lying at a slant to the edge)."""
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
HANG_HEADINGS_DEG = (0.0, 20.0, -20.0, 40.0, -40.0)
"""Pinch lines through the ring's centre, level with it, in degrees from square to the tool (each both ways round):
square to it, the line crosses the wrench's ring through its centre and the tool turns about it in its own plane.
The line along the edge is tried as well where it is at most :data:`ALONG_EDGE_MAX_DEG` from square: both pads are
then as far past the edge as the ring's centre (a slanted line brings the inner pad over the table top)."""
ALONG_EDGE_MAX_DEG = 60.0
HANG_UP_M = 0.24
"""The lift after the pinch, straight up: the tool turns about the pinch line and hangs below the pads, its far end
above the table top. Its far end leaves the edge when it hangs nearly straight down and it barely swings; lifted 6 cm
outwards as well, the far end left the edge early, the tool swung down and the wrench twisted out of the pads."""
ARM_MARGIN_M = 0.01
ABOVE_M = 0.12
BRING_STEPS = 40
HOOK_MIN_RADIUS_M = 0.008
"""A ring whose hole is at least this wide (the largest circle in it) is hooked, not pinched: the index's end (7.1 mm
radius) passes through it straight down (the scissors' rings, 8.6-8.8 mm; not the wrench's, 6.9 mm)."""
HOOK_OVERHANG_M = 0.013
"""How far past the edge a hooked ring's centre is dragged: far enough for the finger to pass the table's side
through it, close enough that the tool does not tip over the edge while the finger turns in it (at 2 cm, closed
scissors tipped off on 1 of 3 dev seeds)."""
HOOK_TIP_Z_M = -0.05
"""Height of the index's end below the table top before it curls: its middle joint level with the ring (at -3 cm
the curling middle phalanx folded the finger back up out of the ring)."""
HOOK_CURL = {"FFJ1": 1.3, "FFJ0": 1.3}
"""The index's middle and end joints (coupled) curled round the ring's wall."""
HOOK_RISE_M = 0.16
"""The hand rises this far with the tool hanging from the curled index before the knuckle flexes: the tool hangs
clear of the table (the scissors are 14 cm long)."""
HOOK_HOLD = {"FFJ1": 0.9, "FFJ0": 0.9}
"""The curl eased before the knuckle flexes: still a hook, but no longer squeezing the ring into the crook (the
squeeze, 50-70 N, pressed the finger's first phalanx back, and the knuckle did not move on 2 of 10 dev seeds)."""
HOOK_FLEX = {"FFJ2": 1.2}
"""The index's knuckle flexed: the hooked ring comes 2-3 cm from the thumb's reach to within it (the thumb's pad
reaches the middle joint from 1.2 rad on)."""
HOOK_FLEX_MORE = {"FFJ2": 1.5}
HOOK_THUMB_MISS_M = 0.01
"""Where the thumb's pad reaches no nearer than this to the ring's centre after :data:`HOOK_FLEX`, the knuckle flexes
on to :data:`HOOK_FLEX_MORE`. Where the hanging tool leans on the other, curled fingers the knuckle stops short all
the same (dev seed 785011: 0.78 rad, the thumb 17 mm short, and it held; 785020: 27 mm short, the thumb did not touch
the ring, and the attempt failed)."""
HOOK_STEPS = 15
HOOK_JAM_M = 0.008
"""The finger is jammed in the ring when the ring's centre drops this far while the finger goes down through it (the
tool then tips over the edge: 2 of 20 dev seeds)."""
HOOK_LAG_M = 0.02
"""The arm does not follow the index through the ring when its end is this far from where it was sent (the forearm
on the table's edge after a re-grip: 3 of 60 dev runs)."""


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
                 mass_kg: float = 0.0, hole_m: float = 0.0):
        self.m, self.hand, self.name, self.mass_kg = m, hand, name, mass_kg
        self.ring_local = ring_in_object
        self.edge_y = edge_y
        self.half_x = float(m.env.task_spec.table.size_m[0]) / 2
        self.hooks = hole_m >= HOOK_MIN_RADIUS_M
        """The ring is hooked (its hole, ``hole_m`` in radius, lets the finger through), not pinched."""
        self.hooked = False
        """The index is curled through the ring and the tool hangs from it (:meth:`drag` did it)."""
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
                   float(px_bodies(m.env.obj(name))[0].mass), float(shape.signed_distance(ring[None])[0]))

    @staticmethod
    def _pose(m: ArmHandMotion, name: str) -> sapien.Pose:
        p = m.env.obj(name).pose
        return sapien.Pose(p.p[0].cpu().numpy(), p.q[0].cpu().numpy())

    def _com(self) -> np.ndarray:
        """The tool's centre of mass (world) now."""
        body = px_bodies(self.m.env.obj(self.name))[0]
        return (self._pose(self.m, self.name) * body.cmass_local_pose).p

    def ring(self) -> np.ndarray:
        """The ring's measured centre (world) now."""
        return (self._pose(self.m, self.name) * sapien.Pose(self.ring_local)).p

    # ------------------------------------------------------------------ the index's tip
    def _tip(self, q: np.ndarray) -> np.ndarray:
        return (self.m.ik.fk(q, "ffdistal") * sapien.Pose([0.0, 0.0, TIP_ALONG_M])).p

    def _palm_for_tip(self, rot: np.ndarray, tip: np.ndarray, q: np.ndarray, restarts: int = 0,
                      valid: Callable[[np.ndarray], bool] | None = None) -> np.ndarray | None:
        """Arm joints putting the index's end at ``tip`` with the palm turned ``rot`` (fixed point on the tip's
        offset from the palm; ``valid``: a check of the joints, as in :meth:`~gendex.solve.ik.ArmIK.solve`)."""
        palm = pose_of(rot, tip + (self.m.ik.fk(q).p - self._tip(q)))
        for _ in range(3):
            sol = self.m.ik.solve(palm, q, restarts=restarts, valid=valid)
            if sol is None:
                return None
            palm = pose_of(rot, palm.p + tip - self._tip(sol))
            q, restarts = sol, 0
        return self.m.ik.solve(palm, q, restarts=0, valid=valid)

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
        """Index into the ring, ring dragged :data:`OVERHANG_M` past the side edge, index out and up; or, for a
        ring the finger passes through, dragged :data:`HOOK_OVERHANG_M` past it and hooked (:meth:`_hook`)."""
        m = self.m
        ring = self._ring_on_table()
        if abs(ring[1]) > self.edge_y and not self.hooks:  # over the edge already (a second try after a slip)
            return
        overhang = HOOK_OVERHANG_M if self.hooks else HINGE_OVERHANG_M
        lead = ring[1] - self._pose(m, self.name).p[1]  # from the tool's origin
        side = float(np.sign(lead) if abs(lead) > 0.02 else (np.sign(ring[1]) or 1.0))
        goal = np.array([DRAG_AIM_X_M, side * (self.edge_y + 0.06), 0.0])
        d0 = goal - ring
        d0[2] = 0.0
        d0 /= np.linalg.norm(d0)
        fingers = -np.cos(DRAG_TILT_RAD) * np.array([0.0, 0.0, 1.0]) - np.sin(DRAG_TILT_RAD) * d0
        normal = np.cross(d0, [0.0, 0.0, 1.0])
        normal *= np.sign(normal[0]) or 1.0
        rot = palm_rotation(fingers, normal)
        z_drag = yield from self._enter_ring(rot, m.with_hand(m.target(), DRAG_HAND))
        tip, regrips = self._tip(m.target()), 0
        for _ in range(DRAG_MAX_STEPS):
            ring = self.ring()
            if side * ring[1] > self.edge_y + overhang:
                break
            least = side * ring[1] > self.edge_y + OVERHANG_M
            if least and not self.hooks and side * self._com()[1] > self.edge_y - COM_INSIDE_M:
                break  # further, and the tool's weight would tip it over the edge
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
                past = ring + d / np.linalg.norm(d) * (self.edge_y + overhang + 0.01 - side * ring[1])
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
        if self.hooks and z_drag == DRAG_TIP_Z_M:
            self.hooked = yield from self._hook(tip, d0, normal)
            tip = self._tip(m.target())
        if not self.hooked:
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
        yield from self._centre(rot, tip)  # so that it leaves without pulling
        tip = self._tip(m.target())
        for k in range(1, 11):
            q = self._palm_for_tip(rot, tip + [0.0, 0.0, 0.005 * k], m.target())
            if q is None:  # the arm rises no further with this hand: the index curls out of the ring instead
                log.debug("no IK raising the finger out of %r's ring at %d mm: curling it", self.name, 5 * k)
                yield from m.ramp(m.with_hand(m.target(), CURL_INDEX), 10)
                return
            yield self._move_tip(rot, tip + [0.0, 0.0, 0.005 * k], q)

    def _centre(self, rot: np.ndarray, tip: np.ndarray) -> Iterator[np.ndarray]:
        """The index's end moved from ``tip`` to the ring's centre, at its height (as far as the arm reaches)."""
        m = self.m
        ring = self.ring()
        for k in range(1, 4):
            goal = tip + (np.array([ring[0], ring[1], tip[2]]) - tip) * k / 3
            q = self._palm_for_tip(rot, goal, m.target())
            if q is None:
                log.debug("no IK centring the finger in %r's ring: it goes on from where it is", self.name)
                return
            yield self._move_tip(rot, goal, q)

    def _hook(self, tip: np.ndarray, ahead: np.ndarray, normal: np.ndarray) -> Generator[np.ndarray, None, bool]:
        """The dragged ring hooked on the index (the drag's end at ``tip``, its horizontal direction ``ahead``, the
        palm's normal ``normal``): centred, the finger turned straight down and pushed through the ring, curled,
        raised with the tool hanging from it, and flexed at the knuckle (see the module docstring). False when the
        finger does not pass through the ring (:meth:`_through_ring`), nor after entering it again
        (:meth:`_enter_again`)."""
        m = self.m
        up = np.array([0.0, 0.0, 1.0])
        rots = [palm_rotation(-np.cos(t) * up - np.sin(t) * ahead, normal) for t in np.linspace(DRAG_TILT_RAD, 0, 8)]
        yield from self._centre(rots[0], tip)
        through = yield from self._through_ring(rots)
        if not through:
            through = yield from self._enter_again(rots[-1], rots[0])
        if not through:
            return False
        yield from m.ramp(m.with_hand(m.target(), HOOK_CURL), HOOK_STEPS)
        yield from m.hold(SETTLE_STEPS)
        yield from m.cartesian(HOOK_RISE_M * up, DRAG_M_PER_STEP, partial=True)
        yield from m.ramp(m.with_hand(m.target(), HOOK_HOLD), HOOK_STEPS)
        yield from m.ramp(m.with_hand(m.target(), HOOK_FLEX), HOOK_STEPS)
        if self._thumb_reach()[1] > HOOK_THUMB_MISS_M:  # the ring sits further out along the finger
            yield from m.ramp(m.with_hand(m.target(), HOOK_FLEX_MORE), HOOK_STEPS)
        return True

    def _through_ring(self, rots: list[np.ndarray]) -> Generator[np.ndarray, None, bool]:
        """The index straightened where it is (``rots``: palm rotations from the drag's tilt to straight down; a
        tilted finger pushed down takes the ring down with it), then pushed through the ring to :data:`HOOK_TIP_Z_M`.
        Where the ring goes down with it all the same (:data:`HOOK_JAM_M`), the finger goes back up and tries once
        more; False (the finger back at the ring's height) when it jams again, or where the arm does not follow
        (:data:`HOOK_LAG_M`: the arm on the table's edge) or reaches no further."""
        m = self.m
        z = float(self._tip(m.target())[2])
        steps = [(rot, z, False) for rot in rots[1:]]
        for attempt in range(2):
            steps += [(rots[-1], h, True) for h in np.linspace(z, HOOK_TIP_Z_M, 15)[1:]]
            ring_z = None
            for rot, h, down in steps:
                ring = self.ring()
                ring_z = float(ring[2]) if down and ring_z is None else ring_z
                goal = np.array([ring[0], ring[1], h])
                q = self._palm_for_tip(rot, goal, m.target())
                if q is None:
                    log.debug("no IK for the index's end at %s through %r's ring", np.round(goal, 3), self.name)
                    return False
                yield self._move_tip(rot, goal, q)
                if np.linalg.norm(self._tip(m.qpos()) - goal) > HOOK_LAG_M:
                    log.debug("the arm does not follow the index through %r's ring: no hook", self.name)
                    return False
                if down and self.ring()[2] < ring_z - HOOK_JAM_M:
                    break
            else:
                return True
            log.debug("%r's ring goes down with the finger (try %d): the finger goes back up", self.name, attempt + 1)
            yield from self._raise_tip(rots[-1], z)
            steps = []
        return False

    def _enter_again(self, down: np.ndarray, tilted: np.ndarray) -> Generator[np.ndarray, None, bool]:
        """The finger out of the ring (turned ``tilted``) and back in, straight down (``down``), from an arm
        configuration that takes it through the ring with the arm clear of the table top (solved with restarts), then
        through it (:meth:`_through_ring`): where the drag's configuration does not let the finger straighten (the
        forearm met the table's edge: 3 of 60 dev runs) or the finger jammed twice. False when that fails too."""
        m = self.m
        yield from self._leave_ring(tilted, self._tip(m.target()))
        ring = self.ring()
        deep = self._palm_for_tip(down, np.array([ring[0], ring[1], HOOK_TIP_Z_M]),
                                  m.with_hand(m.target(), DRAG_HAND), restarts=12,
                                  valid=lambda q: self._out_of_table(q, 0))
        if deep is None:
            log.debug("no arm configuration takes the index through %r's ring clear of the table", self.name)
            return False
        log.debug("the index enters %r's ring again, straight down", self.name)
        try:
            rest = yield from self._enter_ring(down, deep)
        except ExecutionError as err:
            log.debug("%s", err)
            return False
        return rest == DRAG_TIP_Z_M and (yield from self._through_ring([down, down]))

    def _raise_tip(self, rot: np.ndarray, z: float) -> Iterator[np.ndarray]:
        """The index's end back up to height ``z`` over the ring's centre (as far as the arm reaches)."""
        m = self.m
        for h in np.linspace(float(self._tip(m.target())[2]), z, 6)[1:]:
            ring = self.ring()
            q = self._palm_for_tip(rot, np.array([ring[0], ring[1], h]), m.target())
            if q is None:
                return
            yield self._move_tip(rot, np.array([ring[0], ring[1], h]), q)

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
                              "short of its centre)", lift=(0.0, 0.0, HANG_UP_M))

    def _thumb_reach(self) -> tuple[dict[str, float], float]:
        """The thumb's joints putting its pad nearest the hooked ring's measured centre, and how far from it (m)."""
        m = self.m
        return self.hand.finger_ik("th", (m.ik.fk(m.qpos()).inv() * sapien.Pose(self._ring_on_table())).p)

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
        return bool(np.all(_table_top_gap(c, r, self.m.env.table_height, self.edge_y, self.half_x) >= margin))

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


def hinge_headings(across: float) -> tuple[float, ...]:
    """Headings (degrees from ``across``, the heading in rad of the horizontal line square to the tool) of the hinge's
    pinch lines: :data:`HANG_HEADINGS_DEG`, and the line along the table's side edge where it is at most
    :data:`ALONG_EDGE_MAX_DEG` from square and not within 5 degrees of one of those."""
    along_edge = float((np.degrees(-across) + 90.0) % 180.0 - 90.0)
    if abs(along_edge) > ALONG_EDGE_MAX_DEG or min(abs(along_edge - h) for h in HANG_HEADINGS_DEG) <= 5.0:
        return HANG_HEADINGS_DEG
    return (*HANG_HEADINGS_DEG, round(along_edge, 1))


class _PastEdge(GraspSynthesizer):
    """Pinches of a tool overhanging the table's side edge: past the edge the hand may reach below the table top."""

    def __init__(self, hand: HandModel, shape: PosedShape, table_z: float, edge_y: float, half_x: float):
        super().__init__(hand, shape, table_z)
        self.edge_y, self.half_x = edge_y, half_x

    def table_gap(self, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
        return _table_top_gap(centers, radii, self.table_z, self.edge_y, self.half_x)


def _table_top_gap(centers: np.ndarray, radii: np.ndarray, table_z: float, edge_y: float, half_x: float) -> np.ndarray:
    """[n] how far each sphere (``centers`` [n, 3], ``radii`` [n]) is above the table top (negative: in it), the top
    a slab ending at ``|y| = edge_y`` and ``|x| = half_x``: inf for a sphere wholly past an edge."""
    off = (np.abs(centers[:, 1]) >= edge_y + radii) | (np.abs(centers[:, 0]) >= half_x + radii)
    return np.where(off, np.inf, centers[:, 2] - radii - table_z)
