"""Setting an object down at a place (gendex.solve.set_down): beside, between, in a region of the table, on tasks the
offline author wrote for requests of the task language (tests/data/tasks)."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from gendex.solve.attempt import run_attempt
from gendex.solve.executor import StageExecutor
from gendex.solve.set_down import placed_condition, set_down_point
from gendex_envs.spec import parse_task_spec
from gendex_envs.success import rest_point, robot_axes
from gendex_envs.task_env import TaskEnv

DATA = Path(__file__).parents[1] / "data" / "tasks"


def _env(name: str) -> TaskEnv:
    spec = parse_task_spec(yaml.safe_load((DATA / f"{name}.yaml").read_text()), source=name)
    return TaskEnv(task_spec=spec, control_mode="pd_joint_pos", control_joint="both", obs_mode="none",
                   render_backend="none")


def test_the_set_down_point_is_the_middle_of_what_the_condition_accepts():
    """Left of the bowl: the middle of the gap band, straight out on the robot's left (+y at base yaw 0); between:
    the midpoint; a region: 18 cm into it from the table's middle."""
    for name, check in [
        ("SetAppleLeftOfBowl", lambda env, c, p: np.allclose(
            p - rest_point(env, c.target)[0, :2].double().numpy(), [0.0, (c.min_gap_m + c.max_gap_m) / 2])),
        ("SetPeachBetweenBowlMug", lambda env, c, p: np.allclose(
            p, (rest_point(env, c.target)[0, :2] + rest_point(env, c.other)[0, :2]).double().numpy() / 2)),
        ("SetOrangeFarRight", lambda env, c, p: np.allclose(p, [0.1 + 0.18, -0.18])),
    ]:
        env = _env(name)
        try:
            env.reset(seed=3)
            c = placed_condition(env, env.task_spec.success.conditions[0].object)
            assert c is not None and c.type == "placed"
            base, fwd, left = robot_axes(env, rest_point(env, c.object))
            assert np.allclose(fwd.numpy(), [1.0, 0.0]) and np.allclose(left.numpy(), [0.0, 1.0])
            assert check(env, c, set_down_point(env, c)), name
        finally:
            env.close()


@pytest.mark.parametrize(("name", "seed"), [
    ("SetAppleLeftOfBowl", 7100), ("SetPeachBetweenBowlMug", 7101),
    pytest.param("SetOrangeFarRight", 7102, marks=pytest.mark.slow),
    pytest.param("SetLemonInFrontOfPlate", 7103, marks=pytest.mark.slow),
])
def test_the_executor_sets_the_object_down_where_the_place_says_and_lets_go(name, seed):
    env = _env(name)
    try:
        executor = StageExecutor()
        out = run_attempt(env, executor, seed)
        assert out.succeeded, out.failure
        held = env.task_spec.success.conditions[0].object
        point = executor._points[held]
        assert float(np.linalg.norm(rest_point(env, held)[0, :2].double().numpy() - point)) < 0.05
        assert executor.rigid.held is None
    finally:
        env.close()
