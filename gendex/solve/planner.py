"""Collision-aware joint-space motion planning for the UR10e (OMPL RRT-Connect over :class:`ArmCollisionModel`).

A motion is asked for as start and goal arm configurations (the goal usually from :class:`ArmIK`). The straight
joint-space segment is tried first (most table-top motions are free); otherwise RRT-Connect searches the 6-D joint
space and the path is shortcut-simplified. Either way the result is densified into per-control-step waypoints no
more than ``max_step_rad`` apart, so a position-controlled arm tracks it closely.
"""

from __future__ import annotations

import logging
import time
from itertools import pairwise

import numpy as np

from gendex.solve.collision import ArmCollisionModel
from gendex_envs.errors import GenDexError

log = logging.getLogger(__name__)


START_SLACK_M = 0.002
"""A path from a start in collision may go this much deeper than the start (the check's own resolution)."""
MAX_CHECKS = 20_000
"""A search's budget: RRT-Connect stops after this many collision checks. Counted work, not seconds, so a search
ends the same way on a loaded machine or a slow one (a wall-clock budget had made dataset builds differ with load)."""
HANG_GUARD_S = 120.0
"""Wall-clock guard only against a runaway search; the check budget ends every search long before it."""


class PlanningError(GenDexError):
    """No collision-free arm motion was found (start or goal in collision, or the search used up its budget)."""


class ArmPlanner:
    """Plans arm motions for one env; joint vectors are full [dof] vectors, only the arm entries move."""

    def __init__(self, collision: ArmCollisionModel, max_step_rad: float = 0.04, check_step_rad: float = 0.02,
                 max_checks: int = MAX_CHECKS, seed: int = 0):
        if max_checks < 1:
            raise ValueError(f"max_checks {max_checks!r} must be a positive number of collision checks")
        self.collision = collision
        self.ik = collision.ik
        self.max_step_rad = max_step_rad
        self.check_step_rad = check_step_rad
        self.max_checks = int(max_checks)
        self.last_checks = 0
        """Collision checks the last RRT-Connect search made (its share of :attr:`max_checks`)."""
        self.reseed(seed)

    def reseed(self, seed: int) -> None:
        """Make the searches from now on a function of ``seed`` (the executor reseeds with each episode's seed, so
        an attempt plans the same paths in any process, whatever ran before it)."""
        self.seed = int(seed)
        self._searches = 0

    def follow(self, other: ArmPlanner) -> None:
        """Go on with ``other``'s searches: the next search here is the one ``other`` would run next (a physics trial
        of what ``other``'s motion is about to do plans the same paths)."""
        self.seed, self._searches = other.seed, other._searches

    def segment_free(self, a: np.ndarray, b: np.ndarray, floor: float = 0.0) -> bool:
        """True when every configuration on the straight joint-space segment a→b (arm entries) is free (its
        clearance at least ``floor``, which a start already in collision lowers to its own)."""
        n = max(2, int(np.ceil(np.max(np.abs(b - a)) / self.check_step_rad)) + 1)
        return all(self._ok(a + (b - a) * t, floor) for t in np.linspace(0.0, 1.0, n))

    def _ok(self, q: np.ndarray, floor: float) -> bool:
        return self.collision.is_free(q) if floor >= 0.0 else self.collision.clearance(q) >= floor

    def plan(self, q_start: np.ndarray, q_goal: np.ndarray, max_step_rad: float | None = None) -> np.ndarray:
        """Waypoints [T, dof] from ``q_start`` (excluded) to ``q_goal`` (included); hand entries copy ``q_goal``.

        ``max_step_rad``: the densification's step for this path (default: the planner's).
        Raises :class:`PlanningError` when the goal is in collision or no path is found within the time limit.
        A start in collision (e.g. fingers already touching an object lifted a little into the margin, a hand that
        just pressed a door shut) is allowed: the path may not go deeper into collision than the start is, so it
        leaves along the straight segment toward the goal when that does not go deeper, else the search finds a way
        out (a straight segment from a hand resting on a door's front had taken the hand through the cabinet).
        """
        q_start = np.asarray(q_start, dtype=np.float64)
        q_goal = np.asarray(q_goal, dtype=np.float64)
        arm = self.ik.arm
        start = q_goal.copy()
        start[arm] = q_start[arm]
        if not self.collision.is_free(q_goal):
            raise PlanningError(f"goal configuration in collision (clearance "
                                f"{self.collision.clearance(q_goal):+.3f} m)")
        floor = min(0.0, self.collision.clearance(start) - START_SLACK_M)
        if self.segment_free(start, q_goal, floor):
            path = [start, q_goal]
        else:
            path = self._rrt(start, q_goal, floor)
        return self._densify(path, max_step_rad or self.max_step_rad)

    def _densify(self, path: list[np.ndarray], max_step_rad: float) -> np.ndarray:
        out = []
        for a, b in pairwise(path):
            n = max(1, int(np.ceil(np.max(np.abs(b - a)) / max_step_rad)))
            out.extend(a + (b - a) * k / n for k in range(1, n + 1))
        return np.asarray(out)

    def _rrt(self, start: np.ndarray, goal: np.ndarray, floor: float = 0.0) -> list[np.ndarray]:
        try:
            from ompl import base as ob
            from ompl import geometric as og
            from ompl import util as ou
        except ImportError as e:  # pragma: no cover - ompl is a dependency
            raise PlanningError("the straight motion is blocked and OMPL is not importable "
                                "(pip install ompl)") from e
        # OMPL seeds every RNG it creates from one global generator: reset it before each search, from the
        # planner's seed and the search's rank in the episode, so the search does not depend on earlier ones.
        # OMPL logs that reset as an error once any RNG exists ("changing seed now will not lead to deterministic
        # sampling"): true of RNGs made before it, but each search makes its own after it, so it is silenced
        ou.setLogLevel(ou.LOG_NONE)
        ou.RNG.setSeed((self.seed * 7919 + self._searches) % (2**31 - 1) + 1)
        ou.setLogLevel(ou.LOG_WARN)
        self._searches += 1
        arm = self.ik.arm
        lo, hi = self.ik.limits[arm, 0], self.ik.limits[arm, 1]
        space = ob.RealVectorStateSpace(len(arm))
        bounds = ob.RealVectorBounds(len(arm))
        for i in range(len(arm)):
            # the search stays within ±π of the straight path's span: no full wrist turns
            bounds.setLow(i, float(max(lo[i], min(start[arm[i]], goal[arm[i]]) - np.pi)))
            bounds.setHigh(i, float(min(hi[i], max(start[arm[i]], goal[arm[i]]) + np.pi)))
        space.setBounds(bounds)
        ss = og.SimpleSetup(space)
        template = goal.copy()

        def full(state) -> np.ndarray:
            q = template.copy()
            q[arm] = [state[i] for i in range(len(arm))]
            return q

        checks = [0]

        def valid(state) -> bool:
            checks[0] += 1
            return self._ok(full(state), floor)

        ss.setStateValidityChecker(valid)
        si = ss.getSpaceInformation()
        span = float(np.max(hi - lo))
        si.setStateValidityCheckingResolution(self.check_step_rad / span)
        s0, s1 = space.allocState(), space.allocState()
        for i in range(len(arm)):
            s0[i], s1[i] = float(start[arm[i]]), float(goal[arm[i]])
        ss.setStartAndGoalStates(s0, s1)
        ss.setPlanner(og.RRTConnect(si))
        guard = time.monotonic() + HANG_GUARD_S
        budget = self.max_checks

        def spent() -> bool:
            if checks[0] >= budget:
                return True
            if time.monotonic() > guard:  # pragma: no cover - a guard, not a budget
                log.warning("RRT-Connect stopped by its %.0f s guard after %d checks: this search's result depends "
                            "on the machine's speed", HANG_GUARD_S, checks[0])
                return True
            return False

        solved = ss.solve(ob.PlannerTerminationCondition(spent))
        self.last_checks = checks[0]
        if not solved or not ss.haveExactSolutionPath():
            raise PlanningError(f"RRT-Connect found no collision-free arm path in {self.max_checks} collision checks")
        ss.simplifySolution()
        states = ss.getSolutionPath().getStates()
        path = [full(s) for s in states]
        log.debug("RRT-Connect path with %d waypoints", len(path))
        return path
