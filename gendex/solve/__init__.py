"""Solving task versions: IK, motion planning, grasp synthesis, skill primitives, trained stage policies.

:data:`SOLVERS` names what ``gendex collect`` can run: ``stages`` (the stage executor,
:mod:`gendex.solve.executor`) and the ``hold`` and ``random`` baselines; :data:`SOLVER_ENV_KWARGS` the action space
each one's actions are for.
"""

from __future__ import annotations

from collections.abc import Callable

from gendex.solve.baselines import HoldSolver, RandomSolver, Solver


def make_stage_executor() -> Solver:
    """A fresh stage executor (the module is imported only when one is made: it loads the planner)."""
    from gendex.solve.executor import StageExecutor

    return StageExecutor()


SOLVERS: dict[str, Callable[[], Solver]] = {"stages": make_stage_executor, "hold": HoldSolver, "random": RandomSolver}
"""Solvers by name; each value makes a fresh solver (picklable, for worker processes)."""
SOLVER_ENV_KWARGS: dict[str, dict[str, str]] = {
    "stages": {"control_mode": "pd_joint_pos", "control_joint": "both"},
    "hold": {"control_mode": "pd_joint_delta_pos", "control_joint": "both"},
    "random": {"control_mode": "pd_joint_delta_pos", "control_joint": "both"},
}
"""The ``gym.make`` keyword arguments each solver's actions are for (the stage executor emits absolute targets)."""

__all__ = ["SOLVERS", "SOLVER_ENV_KWARGS", "HoldSolver", "RandomSolver", "Solver", "make_stage_executor"]
