"""Arm and hand motion for scripted primitives: absolute joint targets for one env, one control step at a time.

:class:`ArmHandMotion` is what every primitive is built from (the stage executor's and the articulated ones):
planned arm motions (OMPL through :class:`~gendex.solve.planner.ArmPlanner`, collision-checked against the scene's
objects and, for a task with a ``scene``, its fixed structures: :func:`scene_obstacles`), straight palm
translations (IK per step), hand ramps with *guarded* closing (each step a finger target stays within
:data:`~gendex.solve.grasp.GUARD_RAD` of the measured angle, so fingers stop on contact), and the objects' measured
geometry. Each yielded action is the full ``pd_joint_pos`` / ``both`` action (every free joint).

**The episode's budget.** A motion knows the step at which the episode's time limit ends it (:meth:`set_budget`)
and how many steps the stages after the current one are expected to need (:attr:`ArmHandMotion.reserve`). A
motion that would not leave that reserve runs faster (:meth:`ArmHandMotion.pace`, at most :data:`MAX_PACE` times
its nominal speed); with room to spare every motion keeps its nominal speed.
"""

from __future__ import annotations

import logging
from collections.abc import Generator, Iterator
from typing import TYPE_CHECKING

import numpy as np
import sapien

from gendex.solve.collision import ArmCollisionModel, Box, structure_obstacles
from gendex.solve.grasp import GUARD_RAD
from gendex.solve.ik import ArmIK
from gendex.solve.planner import ArmPlanner, PlanningError
from gendex_envs.errors import ExecutionError
from gendex_envs.scene_geometry import structure_boxes

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.task_env import TaskEnv

log = logging.getLogger(__name__)

MAX_PACE = 1.6
"""Largest speed-up of a paced motion over its nominal speed (a short budget): planned arm paths at up to 0.1
rad per joint and step, a carry at up to 19 mm a step."""


class ArmHandMotion:
    """Joint-target motions of one env (``num_envs == 1``, absolute targets for every arm and hand joint)."""

    def __init__(self, env: TaskEnv, max_arm_step_rad: float = 0.06, settle_steps: int = 2):
        ctrl = env.agent.controller
        self.env = env
        self.ik = ArmIK(env.agent)
        self.collision = ArmCollisionModel(self.ik)
        self.collision.set_static(scene_obstacles(env))  # a scene's fixed structures, for every motion
        self.planner = ArmPlanner(self.collision, max_step_rad=max_arm_step_rad)
        self.max_arm_step_rad = max_arm_step_rad
        """Largest arm-joint change per control step of a planned motion (a uniform scale keeps a path on course)."""
        self.settle_steps = settle_steps
        """Steps the targets are held after a move ends (contacts settle before the next primitive reads poses)."""
        names = self.ik.joint_names
        self.free = np.array([names.index(n) for n in ctrl.free_joint_names])
        """Positions of the action's joints among the robot's joints."""
        self.arm = np.asarray(self.ik.arm)
        self.hand = np.array([i for i in range(len(names)) if i not in set(self.ik.arm)])
        if ctrl.config.use_delta or set(self.ik.arm) - set(self.free):
            raise ExecutionError("scripted primitives drive absolute arm and hand targets: make the env with "
                                 "control_mode='pd_joint_pos', control_joint='both'", cause="unsupported")
        self.steps = 0
        """Actions emitted so far."""
        self.deadline: int | None = None
        """Value of :attr:`steps` at which the episode's time limit ends it (None: no limit)."""
        self.reserve = 0
        """Steps the stages after the current one are expected to need (set by the executor per stage)."""

    # ------------------------------------------------------------------ budget
    def set_budget(self, limit: int | None, used: int = 0) -> None:
        """The episode may take ``limit`` steps (None: any number), ``used`` of which are already taken."""
        self.deadline = None if limit is None else self.steps - used + limit
        self.reserve = 0

    def left(self) -> int | None:
        """Steps left in the episode (None: no limit)."""
        return None if self.deadline is None else self.deadline - self.steps

    def pace(self, need: int, after: int = 0) -> float:
        """Speed factor (1 to :data:`MAX_PACE`) of a motion that takes ``need`` steps at its nominal speed and is
        followed by ``after`` more steps of the same primitive: 1 while the episode leaves room for it and for
        :attr:`reserve`, else what makes it fit, up to the cap."""
        left = self.left()
        if left is None or need <= 0:
            return 1.0
        room = left - self.reserve - after
        if need <= room:
            return 1.0
        return float(min(MAX_PACE, need / max(room, 1)))

    # ------------------------------------------------------------------ state
    def qpos(self) -> np.ndarray:
        """[J] measured joint positions."""
        return self.env.agent.robot.get_qpos()[0].cpu().numpy().astype(np.float64)

    def target(self) -> np.ndarray:
        """[J] current drive targets."""
        return self.env.agent.controller.target_qpos[0].cpu().numpy().astype(np.float64)

    def with_hand(self, q: np.ndarray, hand: dict[str, float]) -> np.ndarray:
        """``q`` with the named hand joints set."""
        q = q.copy()
        for j, v in hand.items():
            q[self.ik.joint_names.index(j)] = v
        return q

    # ------------------------------------------------------------------ actions
    def emit(self, target: np.ndarray, guard: bool = False) -> np.ndarray:
        """The action reaching ``target`` [J]; ``guard`` keeps hand targets within GUARD_RAD of the measured angles."""
        t = target.copy()
        if guard:
            q = self.qpos()
            t[self.hand] = np.clip(t[self.hand], q[self.hand] - GUARD_RAD, q[self.hand] + GUARD_RAD)
        self.steps += 1
        return t[self.free].astype(np.float32)

    def hold(self, steps: int) -> Iterator[np.ndarray]:
        for _ in range(steps):
            yield self.emit(self.target())

    def settle(self) -> Iterator[np.ndarray]:
        yield from self.hold(self.settle_steps)

    def come_to_rest(self, max_rad_s: float, max_steps: int) -> Iterator[np.ndarray]:
        """Targets held until no arm joint turns faster than ``max_rad_s`` (at most ``max_steps`` steps)."""
        for _ in range(max_steps):
            if float(np.abs(self.env.agent.robot.get_qvel()[0].cpu().numpy()[self.arm]).max()) < max_rad_s:
                return
            yield self.emit(self.target())

    def ramp(self, goal: np.ndarray, steps: int, guard: bool = False) -> Iterator[np.ndarray]:
        """Targets moving linearly from the current ones to ``goal`` over ``steps`` steps."""
        start = self.target()
        for k in range(1, steps + 1):
            yield self.emit(start + (goal - start) * k / steps, guard)

    def move_arm(self, q_goal: np.ndarray, hand: np.ndarray | None = None, max_step_rad: float | None = None,
                 after: int = 0) -> Iterator[np.ndarray]:
        """Planned arm motion to ``q_goal``'s arm joints, hand targets held (or ``hand``'s); at most
        ``max_step_rad`` per joint and step (default :attr:`max_arm_step_rad`), times the :meth:`pace` the budget
        asks for (``after``: steps of the same primitive that follow)."""
        yield from self.plan_arm(q_goal, hand, max_step_rad=max_step_rad, after=after)

    def plan_arm(self, q_goal: np.ndarray, hand: np.ndarray | None = None, start: np.ndarray | None = None,
                 max_step_rad: float | None = None, after: int = 0) -> Iterator[np.ndarray]:
        """:meth:`move_arm`, planned now (against the collision model as it is now; ``ExecutionError`` with cause
        ``no_plan`` if there is no path) and stepped when iterated; from ``start`` (default: the current targets)
        when other motions will have brought the arm there first."""
        start = self.target() if start is None else start
        goal = start.copy()
        goal[self.arm] = q_goal[self.arm]
        if hand is not None:
            goal[self.hand] = hand[self.hand]
        try:
            path = self.planner.plan(start, goal, max_step_rad)
        except PlanningError as e:
            raise ExecutionError(str(e), cause="no_plan") from e
        pace = self.pace(len(path), after)
        if pace > 1.0:
            path = resample(np.vstack([start[None], path]), pace)
        return self._follow(path, goal)

    def _follow(self, path: np.ndarray, goal: np.ndarray) -> Iterator[np.ndarray]:
        for q in path:
            q = q.copy()
            q[self.hand] = goal[self.hand]
            yield self.emit(q)

    def cartesian(self, offset: np.ndarray, m_per_step: float, guard: bool = False, paced: bool = False,
                  after: int = 0, partial: bool = False) -> Generator[np.ndarray, None, float]:
        """Straight palm translation by ``offset`` (world, m), orientation kept, IK per step; ``paced``: faster by
        the :meth:`pace` the budget asks for (``after``: steps of the same primitive that follow). Returns the
        fraction of ``offset`` done: 1, or with ``partial`` where the arm's reach ends (no IK further on) the
        fraction reached so far instead of an ``ExecutionError``."""
        target = self.target()
        palm = self.ik.fk(target)
        n = max(1, int(np.ceil(np.linalg.norm(offset) / m_per_step)))
        if paced:
            n = max(1, int(np.ceil(n / self.pace(n, after))))
        q = target
        for k in range(1, n + 1):
            goal = sapien.Pose(palm.p + offset * k / n, palm.q)
            nq = self.ik.solve(goal, q, restarts=0)
            if nq is None and partial:
                log.info("straight palm motion stopped at step %d/%d: the arm reaches no further", k - 1, n)
                return (k - 1) / n
            if nq is None:
                raise ExecutionError(f"no IK along the straight palm motion at step {k}/{n}", cause="no_ik")
            q = nq
            t = self.target()
            t[self.arm] = q[self.arm]
            yield self.emit(t, guard)
        return 1.0

    def level_path(self, start: sapien.Pose, goal: sapien.Pose, q: np.ndarray, m_per_step: float, step_rad: float,
                   ramp_steps: int, pace: float = 1.0, turn: float = 0.0, pivot: np.ndarray | None = None
                   ) -> list[np.ndarray] | None:
        """Joint vectors moving the palm straight from ``start`` to ``goal`` at a constant orientation (or turning
        steadily by ``turn`` rad about the vertical through ``pivot``, which moves with the palm: a held object's
        centre), at most ``m_per_step`` a step and ``step_rad`` per joint (both times ``pace``), the speed ramping
        up and down over ``ramp_steps`` (a held ball flies out of a sudden 0.4 m/s start); None if a step has no IK,
        jumps branches (an arm joint moving more than 8 ``step_rad``) or collides."""
        speed, paced_rad = m_per_step * pace, step_rad * pace
        length = float(np.linalg.norm(goal.p - start.p))
        ramp = np.minimum(1.0, np.arange(1, 4 * ramp_steps + int(length / speed) + 2) / ramp_steps) * speed
        travelled, profile = 0.0, []
        for v in ramp:
            if travelled >= length:
                break
            slow = min(1.0, (length - travelled) / (ramp_steps * speed) + 0.2)
            travelled = min(length, travelled + v * slow)
            profile.append(travelled / max(length, 1e-9))
        out = []
        for f in profile:
            pose = sapien.Pose(start.p + (goal.p - start.p) * f, start.q)
            if turn:
                at = sapien.Pose((start.p if pivot is None else pivot) + (goal.p - start.p) * f)
                yaw = turn * f
                pose = at * sapien.Pose(q=[np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]) * at.inv() * pose
            nq = self.ik.solve(pose, q, restarts=0)
            if nq is None or not self.collision.is_free(nq):
                return None
            jump = float(np.max(np.abs(nq[self.arm] - q[self.arm])))
            if jump > 8 * step_rad:  # an IK branch jump, not a fast stretch of the straight line
                return None
            steps = max(1, int(np.ceil(jump / paced_rad)))
            out += [q + (nq - q) * j / steps for j in range(1, steps + 1)]
            q = nq
        return out

    def turn_about(self, pivot: np.ndarray, rotvec: np.ndarray, rad_per_step: float, guard: bool = False
                   ) -> Generator[np.ndarray, None, float]:
        """Turn the palm by the rotation vector ``rotvec`` (a world axis times an angle, rad) about the world point
        ``pivot`` (a held object's centre, which then stays where it is), IK per step. Returns the fraction of the
        turn done: 1, or less where the arm reaches no further."""
        angle = float(np.linalg.norm(rotvec))
        n = max(1, int(np.ceil(angle / rad_per_step)))
        palm, at = self.ik.fk(self.target()), sapien.Pose(np.asarray(pivot, dtype=np.float64))
        q = self.target()
        for k in range(1, n + 1):
            half = angle * k / n / 2
            turn = sapien.Pose(q=np.r_[np.cos(half), np.sin(half) * np.asarray(rotvec) / max(angle, 1e-12)])
            nq = self.ik.solve(at * turn * at.inv() * palm, q, restarts=0)
            if nq is None:
                log.info("turn of the palm stopped at step %d/%d: the arm reaches no further", k - 1, n)
                return (k - 1) / n
            q = nq
            t = self.target()
            t[self.arm] = q[self.arm]
            yield self.emit(t, guard)
        return 1.0

    def rise_clear(self, q: np.ndarray, max_m: float, step_m: float = 0.03) -> tuple[float, np.ndarray]:
        """How far the palm must rise from joint vector ``q`` (0 to ``max_m``, in ``step_m`` steps) before the arm
        and whatever the collision model carries (an opened hand) are clear, and the joint vector there (``q``
        itself when no rise clears it): the planner must start from a free configuration, or it would plan a hand
        that hovers over an object, or rests against one, straight through it."""
        palm = self.ik.fk(q)
        for up in np.arange(0.0, max_m + 1e-9, step_m):
            goal = q if up == 0 else self.ik.solve(sapien.Pose(palm.p + [0.0, 0.0, up], palm.q), q, restarts=0)
            if goal is None:
                break
            if self.collision.is_free(goal):
                return float(up), goal
        return 0.0, q

    # ------------------------------------------------------------------ scene geometry
    def world_aabb(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """World bounding box (lo, hi) of object ``name``'s catalog box, as it is posed now."""
        env = self.env
        entry = env.asset_record(name).entry
        scale = env.task_spec.object(name).scale
        lo, hi = np.asarray(entry.bbox_min_m) * scale, np.asarray(entry.bbox_max_m) * scale
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        pose = env.obj(name).pose
        m = sapien.Pose(pose.p[0].cpu().numpy(), pose.q[0].cpu().numpy()).to_transformation_matrix()
        w = corners @ m[:3, :3].T + m[:3, 3]
        return w.min(axis=0), w.max(axis=0)

    def object_geometry(self, name: str) -> tuple[np.ndarray, float, float, float]:
        """(centre xy, bottom z, height, radius) of object ``name``: extents from its world bounding box now, radius
        from its own (local) box, since the world box of a yawed cylinder is up to √2 too wide."""
        lo, hi = self.world_aabb(name)
        entry = self.env.asset_record(name).entry
        size = (np.asarray(entry.bbox_max_m) - np.asarray(entry.bbox_min_m)) * self.env.task_spec.object(name).scale
        radius = float(np.max(size[:2]) / 2)
        return (lo[:2] + hi[:2]) / 2, float(lo[2]), float(hi[2] - lo[2]), radius

    def object_boxes(self, exclude: tuple[str, ...] = ()) -> list[Box]:
        """World boxes of every object but ``exclude``, inflated 1 cm."""
        boxes = []
        for name in self.env.objects:
            if name in exclude:
                continue
            lo, hi = self.world_aabb(name)
            boxes.append(Box(lo - 0.01, hi + 0.01, name))
        return boxes

    def avoid_objects(self, exclude: tuple[str, ...] = ()) -> None:
        """Make every object but ``exclude`` an obstacle of planned motions (boxes inflated 1 cm)."""
        self.collision.set_obstacles(self.object_boxes(exclude))


def scene_obstacles(env) -> list[Box]:
    """The env's fixed structures (its scene's, or the ``scene=`` it was made with) as static planner obstacles;
    none for an env without a scene."""
    scenery = getattr(env, "scenery", None)
    if scenery is None:
        return []
    return structure_obstacles(structure_boxes(scenery.scene.structures, env.task_spec.table))


def resample(path: np.ndarray, pace: float) -> np.ndarray:
    """The densified joint path ``path`` [T + 1, J] (its start first, straight segments cut into equal steps),
    stepped ``pace`` times faster: the same segments (every corner kept), cut into steps of at most ``pace`` times
    its largest joint change per step; the start is left out."""
    steps = np.diff(path, axis=0)
    step = pace * float(np.max(np.abs(steps)))
    if step <= 0.0:
        return path[1:]
    corner = [k for k in range(1, len(steps)) if not np.allclose(steps[k], steps[k - 1], atol=1e-9)]
    ends = path[[0, *corner, len(path) - 1]]
    out = []
    for a, b in zip(ends[:-1], ends[1:], strict=True):
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step - 1e-9)))
        out.extend(a + (b - a) * k / n for k in range(1, n + 1))
    return np.asarray(out)
