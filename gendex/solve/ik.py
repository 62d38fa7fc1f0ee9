"""Inverse kinematics of the UR10e arm for any robot link (usually the palm), limit-aware, with restarts.

SAPIEN's Pinocchio model solves IK by local iteration and ignores joint limits: the answer depends on the start and
may lie outside the limits by multiples of 2π. :class:`ArmIK` wraps every revolute answer to the equivalent angle
nearest the start, rejects answers still outside the limits, and retries from seeded random starts. Planning runs per
env on the CPU (like ManiSkill's motion-planning solutions); inputs and outputs are numpy, one env at a time.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np
import sapien

from gendex_envs.agents.ur10e_shadow import ARM_JOINTS, UR10eShadowHand
from gendex_envs.physx import px_objects

log = logging.getLogger(__name__)

TWO_PI = 2.0 * np.pi


class ArmIK:
    """IK and FK of one robot (env 0 of a ManiSkill agent). Joint vectors are [dof] in articulation order."""

    def __init__(self, agent: UR10eShadowHand):
        robot = agent.robot
        self.model = px_objects(robot)[0].create_pinocchio_model()
        self.joint_names = [j.name for j in robot.get_active_joints()]
        self.link_names = [link.name for link in robot.get_links()]
        self.arm = np.array([self.joint_names.index(n) for n in ARM_JOINTS])
        """[6] indices of the arm joints in the joint vector."""
        self.mask = np.zeros(len(self.joint_names), dtype=np.int32)
        self.mask[self.arm] = 1
        self.limits = robot.get_qlimits()[0].cpu().numpy().astype(np.float64)  # [dof, 2]
        self.base = robot.pose.sp  # the arm base in the world (env 0)

    def fk(self, q: np.ndarray, link: str = "palm") -> sapien.Pose:
        """World pose of ``link`` at joint positions ``q`` [dof]."""
        self.model.compute_forward_kinematics(np.asarray(q, dtype=np.float64))
        return self.base * self.model.get_link_pose(self.link_names.index(link))

    def _wrap(self, q: np.ndarray, start: np.ndarray) -> np.ndarray:
        q = q.copy()
        q[self.arm] += TWO_PI * np.round((start[self.arm] - q[self.arm]) / TWO_PI)
        return q

    def _within_limits(self, q: np.ndarray) -> bool:
        lo, hi = self.limits[self.arm, 0], self.limits[self.arm, 1]
        return bool(np.all(q[self.arm] >= lo - 1e-6) and np.all(q[self.arm] <= hi + 1e-6))

    def solve(self, target: sapien.Pose, q_start: np.ndarray, link: str = "palm", restarts: int = 12, seed: int = 0,
              pos_tol_m: float = 1e-3, rot_tol_rad: float = 1e-2,
              valid: Callable[[np.ndarray], bool] | None = None) -> np.ndarray | None:
        """Arm joint positions putting ``link`` at world pose ``target``; hand joints keep ``q_start``'s values.

        Tries from ``q_start`` first, then from seeded random arm configurations; among the answers that are within
        the limits and pass ``valid`` (e.g. a collision check) returns the one nearest ``q_start`` (joint-space
        distance), or None when none does.
        """
        q_start = np.asarray(q_start, dtype=np.float64)
        goal = self.base.inv() * target
        idx = self.link_names.index(link)
        rng = np.random.default_rng(seed)
        best, best_dist = None, np.inf
        for attempt in range(restarts + 1):
            init = q_start.copy()
            if attempt:
                init[self.arm] = q_start[self.arm] + rng.uniform(-np.pi, np.pi, len(self.arm))
                init[self.arm] = np.clip(init[self.arm], self.limits[self.arm, 0], self.limits[self.arm, 1])
            q, _, _ = self.model.compute_inverse_kinematics(idx, goal, init, self.mask, max_iterations=300)
            q = self._wrap(np.asarray(q, dtype=np.float64), q_start)
            if not self._within_limits(q) or not self._close(self.fk(q, link), target, pos_tol_m, rot_tol_rad):
                continue
            if valid is not None and not valid(q):
                continue
            dist = float(np.linalg.norm(q[self.arm] - q_start[self.arm]))
            if dist < best_dist:
                best, best_dist = q, dist
            if attempt == 0:
                break  # the start's own basin is what a smooth motion wants
        return best

    @staticmethod
    def _close(a: sapien.Pose, b: sapien.Pose, pos_tol: float, rot_tol: float) -> bool:
        if np.linalg.norm(a.p - b.p) > pos_tol:
            return False
        dot = abs(float(np.dot(a.q, b.q)))
        return 2.0 * np.arccos(min(1.0, dot)) <= rot_tol
