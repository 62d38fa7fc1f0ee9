"""Which primitive runs a stage (gendex.solve.executor.StageExecutor.primitive): by the stage's skill and what its
target is."""

from types import SimpleNamespace as NS

import pytest

from gendex.solve.executor import StageExecutor
from gendex_envs.errors import ExecutionError


def _executor(stages) -> StageExecutor:
    ex = StageExecutor()
    ex._env = NS(articulations={"box": object(), "cabinet": object()}, task_spec=NS(stages=stages))
    return ex


def test_a_carry_to_an_articulated_box_is_the_rigid_carry_and_its_lid_is_pressed():
    """*Put the lemon in the box and shut the lid*: the carry's target is where the lemon goes (the box's body), so
    the rigid carry runs; the box's lid is pushed by the open hand (no stage grasps it)."""
    stages = [NS(name=n, skill=k, target=t) for n, k, t in (
        ("reach_lemon", "reach", "lemon"), ("grasp_lemon", "grasp", "lemon"), ("carry_box", "carry", "box"),
        ("release_lemon", "release", "lemon"), ("reach_box", "reach", "box"), ("close_box", "close", "box"))]
    ex = _executor(stages)
    assert [ex.primitive(s) for s in stages] == ["approach", "grasp", "carry", "release", "approach_press", "press"]
    grasped = [NS(name="grasp_cabinet", skill="grasp", target="cabinet"), NS(name="o", skill="open", target="cabinet")]
    assert [_executor(grasped).primitive(s) for s in grasped] == ["hook", "pull"]
    with pytest.raises(ExecutionError, match="no primitive for skill 'lift' on an ungrasped articulated target"):
        ex.primitive(NS(name="lift_box", skill="lift", target="box"))


def test_a_second_object_put_in_a_container_goes_beside_the_first(monkeypatch):
    import numpy as np
    import torch

    from gendex.solve.set_down import free_spot

    poses = {"bowl": (0.1, 0.0), "lemon": (0.13, 0.0), "plum": (0.3, 0.3), "apple": (0.5, 0.5)}

    class Env:
        objects = {n: None for n in poses}
        articulations: dict = {}
        task_spec = NS(object=lambda n: NS(scale=1.0), success=NS(conditions=()),
                       robot=NS(base_yaw_deg=0.0, base_pos_m=(-0.6, 0.0, 0.0)))

        @staticmethod
        def container_extent(name):
            return (0.08, 0.06)

        @staticmethod
        def asset_record(name):
            return NS(size_m=(0.2, 0.2, 0.08) if name == "bowl" else (0.05, 0.05, 0.05))

    from gendex.solve import set_down

    monkeypatch.setattr(set_down, "rest_point", lambda env, n: torch.tensor([[*poses[n], 0.0]]))
    spot = free_spot(Env, "bowl", "plum")  # the lemon lies 3 cm beyond the middle: the plum goes to the near side
    assert np.allclose(spot, (0.1 - (0.08 - 0.025), 0.0))  # as far as it stays within the checked space
    del poses["lemon"]
    Env.objects = {n: None for n in poses}
    assert free_spot(Env, "bowl", "plum") is None  # nothing in it yet: its middle
    # a bowl that is to hold three (every 'inside' condition on it): the first goes to the robot's left, as far out
    # as it stays within the checked space, so the next have room; each next one where it is farthest from what
    # lies there (where it came to rest)
    inside = lambda o: NS(type="inside", object=o, target="bowl", joint=None, negate=False)  # noqa: E731
    Env.task_spec.success.conditions = (inside("lemon"), inside("plum"), inside("apple"))
    room = 0.08 - 0.025
    assert np.allclose(free_spot(Env, "bowl", "lemon"), (0.1, room))  # nothing in it yet
    poses["lemon"] = (0.1, 0.02)  # it rolled towards the middle
    Env.objects = {n: None for n in poses}

    def turned(spot):  # degrees from the lemon's direction, seen from the bowl's middle
        a, b = np.asarray(spot) - (0.1, 0.0), np.asarray(poses["lemon"]) - (0.1, 0.0)
        return np.degrees(np.arccos(a @ b / np.linalg.norm(a) / np.linalg.norm(b)))

    spot = free_spot(Env, "bowl", "plum")  # three to hold: 120 degrees on from where the lemon lies
    assert np.isclose(np.linalg.norm(spot - (0.1, 0.0)), room) and np.isclose(turned(spot), 120.0)
    Env.task_spec.success.conditions = (inside("lemon"), inside("plum"))
    assert np.isclose(turned(free_spot(Env, "bowl", "plum")), 180.0)  # two: across the middle from it
    poses["lemon"] = (0.1, 0.085)  # rolled to the rim, beyond the slots: it still counts
    assert np.isclose(turned(free_spot(Env, "bowl", "plum")), 180.0)
