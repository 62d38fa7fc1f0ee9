"""Flat tools with a finger ring (closed scissors, a ring wrench), the first half of their grasp: dragged by the ring
to the table's side edge with the index in it, and, where the finger passes through the ring, hooked on it
(:mod:`gendex.solve.edge_pinch` pinches the rest, and lifts).

No pinch from the table lifts a tool 6-7 mm tall: the fingertip pads (7.1 and 9.2 mm radius) meet its top edge from
above and push it into the table (``docs/solving.md``). A person slides such a tool off the edge of the table first.
:class:`EdgeDrag` does the same when no grasp of the object held in a physics trial and the object is flat with a
hole a fingertip fits in (:func:`~gendex.solve.edge_geometry.find_ring`):

1. **turn** — a ring that is not hooked (below) is narrower than the finger's end, and the index rests wedged on its
   rim (the wrench): the tool keeps its heading while it is dragged, and a tool lying slanted to the edge reaches it
   slanted (its centre of mass near the edge before its ring is far enough past; or lying along it, over the edge
   whole). So the finger goes into such a ring with the hand turned back about the vertical, and the hand turns about
   the finger's end: the wedged finger turns the tool with it, its ring towards the edge
   (:func:`~gendex.solve.edge_geometry.turn_to_edge`; the turn the arm reaches, :data:`TURN_STEP_RAD` a step, the
   finger held where it rests);
2. **drag** — the index fingertip goes down into the ring (fingers pointing down, the index straight and tilted
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
3. **hook** — a hole wider than the finger's end with room to spare (:data:`HOOK_MIN_RADIUS_M`: the scissors'): the
   finger is turned straight down in the ring and pushed through it below the table top (:data:`HOOK_TIP_Z_M`;
   backed up and sent once more where the ring goes down with it, :data:`HOOK_JAM_M`), and the index curls
   (:data:`HOOK_CURL`): the ring's wall is caught in the crook of its middle joint. The hand rises
   :data:`HOOK_RISE_M` with the tool hanging from the finger, the curl eases (:data:`HOOK_HOLD`) and the knuckle flexes
   (:data:`HOOK_FLEX`), bringing the ring to where the thumb reaches; the thumb closes on the ring (guarded) and the
   hand lifts. A ring threaded on the finger cannot slip out of a pinch: the clamp held the scissors in 45-90 % of
   the grasp benchmark's attempts, mostly slipping. Where the finger does not go through, it comes out (curled out
   where the arm rises no higher) and the ring is pinched.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass
from typing import Self

import numpy as np
import sapien

from gendex.solve.edge_geometry import find_ring, table_top_gap, turn_to_edge
from gendex.solve.grasp import axis_rotation, palm_rotation, pose_of
from gendex.solve.hand import TIP_ALONG_M, HandModel
from gendex.solve.motion import ArmHandMotion
from gendex.solve.shape import PosedShape
from gendex_envs.errors import ExecutionError
from gendex_envs.physx import px_bodies

log = logging.getLogger(__name__)

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
TURN_STEP_RAD = np.radians(5.0)
ARM_MARGIN_M = 0.01
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


@dataclass(frozen=True)
class EdgeVariant:
    """Where the drag takes the tool: the edge grasp's physics trials (:mod:`gendex.solve.edge_trial`) try several."""

    other_side: bool = False
    """To the side edge away from the one the ring leads to (turned up to :data:`~gendex.solve.edge_geometry.
    TURN_MAX_RAD` first, as any ring that is not hooked)."""
    aim_x_m: float = DRAG_AIM_X_M
    """Where along the side edge the ring is dragged to (:data:`DRAG_AIM_X_M`)."""
    turn: bool = True
    """A ring that is not hooked is turned towards the edge before the drag (False: dragged as the tool lies)."""

    def __str__(self) -> str:
        edge = "the side edge away from its ring" if self.other_side else "its ring's side edge"
        return f"{edge}, x = {self.aim_x_m:+.2f} m{'' if self.turn else ', not turned first'}"


class EdgeDrag:
    """The drag of one flat ringed object to the table's side edge, and the hook of a ring the finger passes through
    (see the module docstring); :class:`~gendex.solve.edge_pinch.EdgePinch` adds the pinch."""

    def __init__(self, m: ArmHandMotion, hand: HandModel, name: str, ring_in_object: np.ndarray, edge_y: float,
                 mass_kg: float = 0.0, hole_m: float = 0.0, vertices_in_object: np.ndarray | None = None,
                 variant: EdgeVariant = EdgeVariant()):
        self.m, self.hand, self.name, self.mass_kg, self.variant = m, hand, name, mass_kg, variant
        self.ring_local = ring_in_object
        self.verts_local = vertices_in_object
        """[V, 3] the tool's collision vertices in its own frame (where its far end is, as it stands up)."""
        self._axis = np.array([1.0, 0.0, 0.0])
        """The planned hinge's pinch line (world, horizontal)."""
        self.edge_y = edge_y
        self.half_x = float(m.env.task_spec.table.size_m[0]) / 2
        self.hooks = hole_m >= HOOK_MIN_RADIUS_M
        """The ring is hooked (its hole, ``hole_m`` in radius, lets the finger through), not pinched."""
        self.hooked = False
        """The index is curled through the ring and the tool hangs from it (:meth:`drag` did it)."""
        self._high: np.ndarray | None = None
        """Arm joints over the planned pinch (:meth:`plan`), where :meth:`bring_hand` takes the open hand first."""

    @classmethod
    def of(cls, m: ArmHandMotion, hand: HandModel, name: str, shape: PosedShape, variant: EdgeVariant = EdgeVariant()
           ) -> Self | None:
        """The edge grasp of ``name`` (whose posed shape is ``shape``) taken as ``variant`` says, or None when it is
        not a flat ringed object."""
        ring = find_ring(shape)
        if ring is None:
            return None
        inv = cls._pose(m, name).inv()
        verts = shape.vertices @ inv.to_transformation_matrix()[:3, :3].T + inv.p
        return cls(m, hand, name, (inv * sapien.Pose(ring)).p, float(m.env.task_spec.table.size_m[1]) / 2,
                   float(px_bodies(m.env.obj(name))[0].mass), float(shape.signed_distance(ring[None])[0]), verts,
                   variant)

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
        if self.past_edge():  # over the edge already (a second try after a slip)
            return
        overhang = HOOK_OVERHANG_M if self.hooks else HINGE_OVERHANG_M
        lead = ring[1] - self._pose(m, self.name).p[1]  # from the tool's origin
        side = float(np.sign(lead) if abs(lead) > 0.02 else (np.sign(ring[1]) or 1.0))
        side = -side if self.variant.other_side else side
        goal = np.array([self.variant.aim_x_m, side * (self.edge_y + 0.06), 0.0])
        d0 = goal - ring
        d0[2] = 0.0
        d0 /= np.linalg.norm(d0)
        fingers = -np.cos(DRAG_TILT_RAD) * np.array([0.0, 0.0, 1.0]) - np.sin(DRAG_TILT_RAD) * d0
        normal = np.cross(d0, [0.0, 0.0, 1.0])
        normal *= np.sign(normal[0]) or 1.0
        rot = palm_rotation(fingers, normal)
        turn = turn_to_edge(self.ring(), self._com(), side) if self.variant.turn and not self.hooks else 0.0
        if turn:
            rot, z_drag = yield from self._enter_turned(rot, turn)
        else:
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

    def past_edge(self) -> bool:
        """The ring of a tool to be pinched is over a side edge already: there is nothing to drag."""
        return abs(self._ring_on_table()[1]) > self.edge_y and not self.hooks

    def _enter_turned(self, rot: np.ndarray, turn: float) -> Generator[np.ndarray, None, tuple[np.ndarray, float]]:
        """The index into the ring with the hand turned ``-turn`` about the vertical from the drag's ``rot`` (less
        where the arm reaches no such pose), then turned back about the finger's end: a finger wedged in the ring
        turns the tool with it. Returns the palm's rotation reached and the height to drag at."""
        m = self.m
        z = np.array([0.0, 0.0, 1.0])
        for f in (1.0, 0.75, 0.5, 0.25, 0.0):
            start = axis_rotation(z, -f * turn) @ rot
            try:
                z_drag = yield from self._enter_ring(start, m.with_hand(m.target(), DRAG_HAND))
                break
            except ExecutionError:
                if f == 0.0:
                    raise
                log.debug("no IK entering %r's ring turned %.0f°: trying less", self.name, np.degrees(f * turn))
        tip, done = self._tip(m.target()), start
        tip[2] = z_drag  # where the finger rests: pressed on while it turns, it sinks into the ring and wedges there
        n = max(1, int(np.ceil(abs(f * turn) / TURN_STEP_RAD)))
        for k in range(1, n + 1):
            r = axis_rotation(z, -f * turn * (1 - k / n)) @ rot
            q = self._palm_for_tip(r, tip, m.target())
            if q is None:
                log.debug("no IK turning %r further about the finger (%d of %d steps)", self.name, k - 1, n)
                break
            yield self._move_tip(r, tip, q)
            done = r
        rd = self.ring()[:2] - self._com()[:2]
        log.debug("%r turned by the finger in its ring: its ring now %.0f° from the edge's normal", self.name,
                  np.degrees(abs(np.arctan2(abs(rd[0]), abs(rd[1])))))
        return done, z_drag

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

    def _out_of_table(self, q: np.ndarray, n_hand: int) -> bool:
        """No sphere of the collision model at ``q`` dips into the table top's slab: the arm's by
        :data:`ARM_MARGIN_M`, the hand's (the last ``n_hand``) by nothing, as in the grasp synthesis."""
        c, r = self.m.collision.sphere_centres(q)
        margin = np.where(np.arange(len(r)) < len(r) - n_hand, ARM_MARGIN_M, 0.0)
        return bool(np.all(table_top_gap(c, r, self.m.env.table_height, self.edge_y, self.half_x) >= margin))
