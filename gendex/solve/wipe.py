"""The ``wipe`` primitive: slide a held sponge over a wipe area's marks, pressed down (:mod:`gendex_envs.wiping`).

The sponge (a thick one, tagged ``wiper``) has been pinched high and carried over the area (the rigid primitives:
:meth:`~gendex.solve.rigid.RigidPrimitives.choose_grasp` pinches it, never palm down). What failed on the way here,
and why the primitive is as it is: a 3 cm sponge pinched at its middle slid out from between the digits when pressed
(10-30 N, as a plain set-down presses) or dragged across the pinch (4 of 10 tries); a flat, palm-down hand cannot
come low enough over it (the forearm's housing met the table), and straight fingers pressing at an angle pushed it
away. So :func:`wipe`

1. levels the sponge in the hand and brings it over the area in the arm configuration that reaches the whole area
   with the most room between the arm and the table (:meth:`_Wiper.over`),
2. lowers it until it presses with :data:`PRESS_LOW_N` (the simulator's contact force between sponge and area, as
   the ``wiped`` condition reads it),
3. slides it along the line from the thumb to the fingers (:func:`pinch_axis`: the drag bears on a pad), pass after
   pass across the marks, each as wide as the sponge across it less :data:`WIPE_EDGE_M` a side and running
   :data:`WIPE_OVERRUN_M` past its outermost marks; each step the palm goes down or up :data:`PRESS_STEP_M` to keep
   the press between :data:`PRESS_LOW_N` and :data:`PRESS_HIGH_N`; between passes the sponge is lifted
   :data:`WIPE_HOVER_M` and set down again,
4. goes back over the marks still unwiped (the env's own record of them), up to :data:`WIPE_TOUCH_UPS` times,
5. lifts it off.
"""

from __future__ import annotations

import logging
from collections.abc import Generator, Iterator
from typing import TYPE_CHECKING

import numpy as np
import sapien

from gendex_envs.errors import ExecutionError
from gendex_envs.geometry import quat_rotate

if TYPE_CHECKING:  # pragma: no cover
    from gendex.solve.rigid import RigidPrimitives
    from gendex_envs.conditions import ConditionSpec

log = logging.getLogger(__name__)

PRESS_LOW_N = 1.5
PRESS_HIGH_N = 3.0
"""The press force kept while wiping (N): above the ``wiped`` condition's default 1 N, below what the pinch holds."""
PRESS_STEP_M = 0.0005
"""How far the palm goes down (or up) in a step while the press is too light (too hard)."""
WIPE_M_PER_STEP = 0.004
"""Palm speed along a pass (8 cm/s at 20 Hz)."""
WIPE_EDGE_M = 0.012
"""A pass covers the sponge's footprint less this much at each side."""
WIPE_OVERRUN_M = 0.02
"""A pass runs this far past the outermost marks."""
WIPE_TOUCH_UPS = 2
"""Rounds of going back over the marks still unwiped after the passes."""
WIPE_HOVER_M = 0.015
"""How high the sponge is lifted off the area from one pass to the next."""
WIPE_LIFT_M = 0.05
"""How high the sponge is lifted off when done."""
WIPE_LEVEL_RAD = 0.03
"""A held sponge tilted more than this is turned level before it is lowered (pressed at an edge, it rolled out of a
pinch)."""
ARM_CLEARANCE_M = 0.005
"""The least gap between the arm's collision spheres and the table while wiping (the planner keeps 2 cm: at a
spill's far corners the arm's wrist passes closer than that)."""
OVER_YAWS_RAD = (0.0, 0.4, -0.4, 0.8, -0.8, 1.2, -1.2)
"""Turns of the hand about the vertical through the sponge tried before setting it down."""
SET_DOWN_GAP_M = 0.02
"""How high over the area the sponge is brought before it is lowered onto it."""
REARRANGE_DROP_M = 0.03
"""How much lower than where the arm stopped another arm configuration must hold the palm."""
REARRANGE_MAX_RAD = 1.5
"""... within this of the current configuration at every joint (a flip of the wrist swings the sponge about)."""
SLIP_M = 0.03
"""A sponge that falls this far behind the palm while sliding has slipped out of the hand."""
DESCENT_M_PER_STEP = 0.002
"""Palm speed lowering the sponge onto the area."""
DESCENT_MAX_M = 0.15
"""The furthest the sponge is lowered looking for the area."""


def wiping_conditions(env) -> list[ConditionSpec]:
    """The task's ``wiped`` conditions (its success's, its stages')."""
    spec = env.task_spec
    return [c for c in (*spec.success.conditions, *(c for s in spec.stages for c in s.success or ()))
            if c.type == "wiped" and not c.negate]


def marks_world(env, area: str, cond: ConditionSpec) -> np.ndarray:
    """[M, 2] where the area's marks are now (env 0)."""
    w = env.wipes.items[env.wipes.key(cond)]
    pose = env.obj_pose(area)
    pts = pose.p[:1] + quat_rotate(pose.q[:1].expand(len(w.marks), 4), w.marks)
    return pts[:, :2].cpu().numpy().astype(np.float64)


def passes(marks: np.ndarray, along: np.ndarray, width_m: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Passes (start, end: xy) over ``marks`` [M, 2] along the unit vector ``along``, for a footprint ``width_m``
    across it: greedy bands across ``along`` from the marks on one side on, alternating direction, each running
    :data:`WIPE_OVERRUN_M` past its outermost marks."""
    across = np.array([-along[1], along[0]])
    u, v = marks @ along, marks @ across
    half = max(width_m / 2 - WIPE_EDGE_M, 0.005)
    left = np.argsort(v)
    out: list[tuple[np.ndarray, np.ndarray]] = []
    while len(left):
        c = v[left[0]] + half
        band, left = left[v[left] <= c + half + 1e-3], left[v[left] > c + half + 1e-3]
        lo, hi = float(u[band].min()) - WIPE_OVERRUN_M, float(u[band].max()) + WIPE_OVERRUN_M
        a, b = lo * along + c * across, hi * along + c * across
        out.append((a, b) if len(out) % 2 == 0 else (b, a))
    return out


def pinch_axis(env, held: str) -> np.ndarray | None:
    """The horizontal unit vector from the thumb's tip to the fingers touching ``held`` (env 0): dragged along it,
    the sponge bears on a digit's pad. None when the thumb or no finger touches."""
    force = env.hand_forces(held)[0].cpu().numpy()
    tips = env.tip_positions[0].cpu().numpy()
    fingers = [k for k in range(1, 5) if force[k] > 0.3]
    if force[0] <= 0.3 or not fingers:
        return None
    d = tips[fingers].mean(axis=0)[:2] - tips[0, :2]
    n = float(np.linalg.norm(d))
    return d / n if n > 1e-3 else None


class _Wiper:
    """The palm moves of one wipe: each step one IK solve for a small palm translation."""

    def __init__(self, rigid: RigidPrimitives, cond: ConditionSpec):
        self.env, self.m, self.cond, self.held = rigid.env, rigid.m, cond, cond.object

    def force(self) -> float:
        """How hard the sponge pressed on the area at the last step (N, env 0)."""
        return float(self.env.wipes.force(self.cond)[0])

    def centre(self) -> np.ndarray:
        return self.m.object_geometry(self.held)[0]

    def clear(self, q: np.ndarray) -> bool:
        """The arm and the forearm's housing stay :data:`ARM_CLEARANCE_M` off the table at ``q`` (an elbow-down IK
        answer laid the upper arm on it)."""
        c = self.m.collision
        return c.clearance(q) + c.margin_m >= ARM_CLEARANCE_M

    def step(self, offset) -> np.ndarray | None:
        """The action moving the palm target by ``offset`` (world, m); None where the arm reaches no further."""
        m = self.m
        target = m.target()
        palm = m.ik.fk(target)
        q = m.ik.solve(sapien.Pose(palm.p + np.asarray(offset, dtype=np.float64), palm.q), target, restarts=0,
                       valid=self.clear)
        if q is None:
            return None
        target[m.arm] = q[m.arm]
        return m.emit(target, guard=True)

    def down(self) -> Iterator[np.ndarray]:
        """Lower until the sponge presses with :data:`PRESS_LOW_N`."""
        for _ in range(int(DESCENT_MAX_M / DESCENT_M_PER_STEP)):
            if self.force() >= PRESS_LOW_N:
                return
            action = self.step([0.0, 0.0, -DESCENT_M_PER_STEP if self.force() < 0.2 else -PRESS_STEP_M])
            if action is None and (yield from self.rearrange()):
                continue
            if action is None:
                raise ExecutionError(f"the arm reaches no lower towards {self.cond.target!r} (clearance "
                                     f"{self.m.collision.clearance(self.m.target()) + self.m.collision.margin_m:.3f} m "
                                     "from the arm to the table)", cause="no_ik")
            yield action
        raise ExecutionError(f"the {self.held!r} never pressed on {self.cond.target!r} (lowered "
                             f"{DESCENT_MAX_M:.2f} m)", cause="target_not_reached")

    def over(self, xy: np.ndarray, reach: np.ndarray) -> Iterator[np.ndarray]:
        """Bring the sponge over ``xy``, :data:`SET_DOWN_GAP_M` above the area, by a planned arm motion to an arm
        configuration that holds it down on the area at ``xy`` and at every point of ``reach`` ([K, 2]: where the
        wipe will take it) with the most room between the arm and the table, of those turning the hand about the
        vertical through the sponge by :data:`OVER_YAWS_RAD`. After a level carry the wrist could hang so low that
        the arm reached no lower (4 of 16 layouts)."""
        m = self.m
        target = m.target()
        palm = m.ik.fk(target)
        drop = float(m.world_aabb(self.held)[0][2] - m.world_aabb(self.cond.target)[1][2])
        lo, hi = m.world_aabb(self.held)
        pivot = sapien.Pose((lo + hi) / 2)
        best: tuple[float, float, np.ndarray] | None = None
        for yaw in OVER_YAWS_RAD:
            turn = sapien.Pose(q=[np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])
            turned = pivot * turn * pivot.inv() * palm
            rooms, q_high = [], None
            for k, p in enumerate([xy, *reach]):
                d = np.asarray(p, dtype=np.float64) - self.centre()
                low = sapien.Pose(turned.p + [d[0], d[1], -drop], turned.q)
                q_low = m.ik.solve(low, target, restarts=8 if k == 0 else 2, valid=self.clear)
                if q_low is None:
                    break
                rooms.append(m.collision.clearance(q_low))
                if k == 0:
                    q_high = m.ik.solve(sapien.Pose(low.p + [0.0, 0.0, SET_DOWN_GAP_M], low.q), q_low, restarts=0)
            if q_high is not None and len(rooms) == len(reach) + 1 and (best is None or min(rooms) > best[0]):
                best = (min(rooms), yaw, q_high)
        if best is None:
            log.info("no arm configuration reaches the whole area clear of the table: going on from here")
            return
        log.info("over %s with the hand turned %+.1f rad (at least %.3f m from the arm to the table down there)",
                 np.round(xy, 3), best[1], best[0] + m.collision.margin_m)
        yield from m.move_arm(best[2])

    def rearrange(self) -> Generator[np.ndarray, None, bool]:
        """Where the arm reaches no lower (its wrist near the table after a long level carry), move it, planned, to
        another arm configuration holding the palm :data:`REARRANGE_DROP_M` lower; False if there is none."""
        m = self.m
        target = m.target()
        palm = m.ik.fk(target)
        goal = sapien.Pose(palm.p - [0.0, 0.0, REARRANGE_DROP_M], palm.q)
        q = m.ik.solve(goal, target, restarts=20, valid=m.collision.is_free)
        if q is None or float(np.abs(q - target).max()) > REARRANGE_MAX_RAD:
            return False
        log.info("the arm reaches no lower: another arm configuration, %.2f rad away", float(np.abs(q - target).max()))
        yield from m.move_arm(q)
        return True

    def up(self, dz: float) -> Iterator[np.ndarray]:
        yield from self.to(np.array([0.0, 0.0, dz]), DESCENT_M_PER_STEP * 2)

    def to(self, offset: np.ndarray, m_per_step: float) -> Iterator[np.ndarray]:
        """Move the palm by ``offset`` in a straight line, as far as the arm reaches."""
        n = max(1, int(np.ceil(np.linalg.norm(offset) / m_per_step)))
        for _ in range(n):
            action = self.step(offset / n)
            if action is None:
                log.info("the arm reaches no further along %s", np.round(offset, 3))
                return
            yield action

    def hover(self, xy: np.ndarray, lift: bool = True) -> Iterator[np.ndarray]:
        """Lift the sponge :data:`WIPE_HOVER_M` (``lift``), carry it over ``xy`` and lower it there until it
        presses."""
        if lift:
            yield from self.up(WIPE_HOVER_M)
        d = np.asarray(xy, dtype=np.float64) - self.centre()
        yield from self.to(np.array([d[0], d[1], 0.0]), WIPE_M_PER_STEP * 2)
        yield from self.down()

    def slide(self, xy: np.ndarray) -> Iterator[np.ndarray]:
        """Slide the pressed sponge's middle to ``xy``, holding the press between the bounds."""
        m = self.m
        offset = self.centre() - m.ik.fk(m.qpos()).p[:2]
        for _ in range(200):
            if float(np.linalg.norm(self.centre() - m.ik.fk(m.qpos()).p[:2] - offset)) > SLIP_M:
                raise ExecutionError(f"the {self.held!r} stayed behind the hand wiping {self.cond.target!r}",
                                     cause="slipped")
            d = np.asarray(xy, dtype=np.float64) - self.centre()
            dist = float(np.linalg.norm(d))
            if dist < 0.003:
                return
            f = self.force()
            dz = -PRESS_STEP_M if f < PRESS_LOW_N else PRESS_STEP_M if f > PRESS_HIGH_N else 0.0
            move = d / dist * min(WIPE_M_PER_STEP, dist)
            action = self.step([move[0], move[1], dz])
            if action is None:
                log.info("the arm reaches no further towards %s", np.round(xy, 3))
                return
            yield action


def wipe(rigid: RigidPrimitives, area: str) -> Iterator[np.ndarray]:
    """Wipe ``area`` with the held sponge (module docstring)."""
    env, m, held = rigid.env, rigid.m, rigid.held
    cond = next((c for c in wiping_conditions(env) if c.target == area and c.object == held), None)
    if cond is None:
        raise ExecutionError(f"wiping {area!r} needs what a 'wiped' condition on it wipes with in the hand; it "
                             f"holds {held!r}", cause="slipped" if held is None else "unsupported")
    w = _Wiper(rigid, cond)
    m.collision.set_obstacles([])  # the arm against the table only: the sponge touches the area on purpose
    yield from rigid.stand_as_before(held, WIPE_LEVEL_RAD)  # pinched at its side it hangs askew: flat on the area
    marks = marks_world(env, area, cond)
    lo, hi = marks.min(axis=0) - WIPE_OVERRUN_M, marks.max(axis=0) + WIPE_OVERRUN_M
    yield from w.over(marks.mean(axis=0), np.array([[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]]]))
    marks = marks_world(env, area, cond)
    along = pinch_axis(env, held)
    along = np.array([0.0, 1.0]) if along is None else along
    lo_w, hi_w = rigid.shape(held).extent_along(np.array([-along[1], along[0], 0.0]))  # the sponge across the passes
    plan = passes(marks, along, hi_w - lo_w)
    log.info("wiping %r with %r: %d marks in %d passes along (%.2f, %.2f)", area, held, len(marks), len(plan),
             *along)
    yield from w.hover(plan[0][0], lift=False)
    for k, (a, b) in enumerate(plan):
        if k:
            yield from w.hover(a)
        yield from w.slide(b)
    for _ in range(WIPE_TOUCH_UPS):
        missed = ~env.wipes.wiped(cond)[0].cpu().numpy()
        if float(1.0 - missed.mean()) >= cond.min_fraction or not missed.any():
            break
        log.info("%d marks of %r still unwiped: going over them", int(missed.sum()), area)
        for xy in marks_world(env, area, cond)[missed]:
            yield from w.hover(xy - WIPE_OVERRUN_M * along)
            yield from w.slide(xy + WIPE_OVERRUN_M * along)
    yield from w.up(WIPE_LIFT_M)
