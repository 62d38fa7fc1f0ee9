"""Arm and hand motion for scripted primitives: absolute joint targets for one env, one control step at a time.

:class:`ArmHandMotion` is what every primitive is built from (the stage executor's and the articulated ones):
planned arm motions (OMPL through :class:`~gendex.solve.planner.ArmPlanner`, collision-checked against the scene's
objects), straight palm translations (IK per step), hand ramps with *guarded* closing (each step a finger target
stays within :data:`~gendex.solve.grasp.GUARD_RAD` of the measured angle, so fingers stop on contact), and the
objects' measured geometry. Each yielded action is the full ``pd_joint_pos`` / ``both`` action (every free joint).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np
import sapien

from gendex.solve.collision import ArmCollisionModel, Box
from gendex.solve.grasp import GUARD_RAD
from gendex.solve.ik import ArmIK
from gendex.solve.planner import ArmPlanner, PlanningError
from gendex_envs.errors import ExecutionError

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.task_env import TaskEnv


class ArmHandMotion:
    """Joint-target motions of one env (``num_envs == 1``, absolute targets for every arm and hand joint)."""

    def __init__(self, env: TaskEnv, max_arm_step_rad: float = 0.06, settle_steps: int = 2):
        ctrl = env.agent.controller
        self.env = env
        self.ik = ArmIK(env.agent)
        self.collision = ArmCollisionModel(self.ik)
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

    def ramp(self, goal: np.ndarray, steps: int, guard: bool = False) -> Iterator[np.ndarray]:
        """Targets moving linearly from the current ones to ``goal`` over ``steps`` steps."""
        start = self.target()
        for k in range(1, steps + 1):
            yield self.emit(start + (goal - start) * k / steps, guard)

    def move_arm(self, q_goal: np.ndarray, hand: np.ndarray | None = None, max_step_rad: float | None = None
                 ) -> Iterator[np.ndarray]:
        """Planned arm motion to ``q_goal``'s arm joints, hand targets held (or ``hand``'s); at most
        ``max_step_rad`` per joint and step (default :attr:`max_arm_step_rad`)."""
        yield from self.plan_arm(q_goal, hand, max_step_rad=max_step_rad)

    def plan_arm(self, q_goal: np.ndarray, hand: np.ndarray | None = None, start: np.ndarray | None = None,
                 max_step_rad: float | None = None) -> Iterator[np.ndarray]:
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
        return self._follow(path, goal)

    def _follow(self, path: np.ndarray, goal: np.ndarray) -> Iterator[np.ndarray]:
        for q in path:
            q = q.copy()
            q[self.hand] = goal[self.hand]
            yield self.emit(q)

    def cartesian(self, offset: np.ndarray, m_per_step: float, guard: bool = False) -> Iterator[np.ndarray]:
        """Straight palm translation by ``offset`` (world, m), orientation kept, IK per step."""
        target = self.target()
        palm = self.ik.fk(target)
        n = max(1, int(np.ceil(np.linalg.norm(offset) / m_per_step)))
        q = target
        for k in range(1, n + 1):
            goal = sapien.Pose(palm.p + offset * k / n, palm.q)
            nq = self.ik.solve(goal, q, restarts=0)
            if nq is None:
                raise ExecutionError(f"no IK along the straight palm motion at step {k}/{n}", cause="no_ik")
            q = nq
            t = self.target()
            t[self.arm] = q[self.arm]
            yield self.emit(t, guard)

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

    def avoid_objects(self, exclude: tuple[str, ...] = ()) -> None:
        """Make every object but ``exclude`` an obstacle of planned motions (boxes inflated 1 cm)."""
        boxes = []
        for name in self.env.objects:
            if name in exclude:
                continue
            lo, hi = self.world_aabb(name)
            boxes.append(Box(lo - 0.01, hi + 0.01, name))
        self.collision.set_obstacles(boxes)
