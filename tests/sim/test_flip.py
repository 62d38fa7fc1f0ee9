"""Flipping: a glass or cup turned upside down on the table counts as flipped only once it has been let go and lies
still (``flipped``, ``released``, ``at_rest``), holding still flips nothing, the reward the generator writes for a flip
grows as the object turns over, and the stage executor turns a glass it grasped by its side over and lets it go on
its top (:mod:`gendex.solve.flip`)."""

from __future__ import annotations

import numpy as np
import pytest
import sapien
import torch

from gendex_envs.geometry import tilt
from gendex_envs.spec import parse_task_spec
from gendex_envs.task_env import TaskEnv
from generator.reward_library import compose_task_module
from generator.steps.validate import check_reward_source

FLIPPED = {"type": "flipped", "object": "glass", "min_tilt_deg": 150.0}


def _task(vessel: str = "tumbler") -> dict:
    return {
        "name": "FlipCheck", "instruction": "Turn the glass upside down.",
        "objects": [{"name": "glass", "asset": vessel, "pos_m": [0.04, 0.0, 0.0],
                     "randomize": {"xy_m": [0.12, 0.2], "yaw_deg": 180.0}}],
        "stages": [
            {"name": "reach_glass", "instruction": "Reach the glass.", "skill": "reach", "method": "motion_planning",
             "control_joint": "arm", "horizon": 60, "target": "glass"},
            {"name": "grasp_glass", "instruction": "Grasp the glass.", "skill": "grasp", "method": "RL",
             "control_joint": "hand", "horizon": 40, "target": "glass",
             "success": [{"type": "grasped", "object": "glass", "min_fingers": 1}]},
            {"name": "flip_glass", "instruction": "Turn the glass over.", "skill": "flip", "method": "RL",
             "control_joint": "arm", "horizon": 200, "target": "glass", "success": [FLIPPED]},
            {"name": "release_glass", "instruction": "Let go of the glass.", "skill": "release", "method": "RL",
             "control_joint": "hand", "horizon": 30, "target": "glass"}],
        "success": {"description": "The glass stands upside down on the table, let go and still.",
                    "conditions": [FLIPPED, {"type": "released", "object": "glass"},
                                   {"type": "at_rest", "object": "glass"}],
                    "hold_steps": 10},
        "max_episode_steps": 500,
    }


def _still(env: TaskEnv, steps: int) -> dict:
    info = {}
    for _ in range(steps):
        _, _, _, _, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    return info


def test_flipped_holds_only_for_a_glass_left_upside_down_and_the_reward_follows_the_turn():
    source = compose_task_module(_task(), {"glass": "graspable"})
    check_reward_source(source)
    module: dict = {}
    exec(compile(source, "flip_reward", "exec"), module)  # the generator's own template, validated above
    env = TaskEnv(task_spec=parse_task_spec(_task()), render_backend="none", control_mode="pd_joint_delta_pos")
    try:
        env.reset(seed=0)
        info = _still(env, 30)  # holding still turns nothing over
        mine = module["evaluate"](env)
        assert not bool(info["success"][0]) and float(mine["turned"][0]) < 0.01
        glass = env.obj("glass")
        p = glass.pose.p[0].numpy()
        glass.set_pose(sapien.Pose(p + [0.0, 0.0, 0.14], [0.0, 1.0, 0.0, 0.0]))  # upside down, on its rim
        info = _still(env, 40)
        assert float(np.degrees(tilt(env.obj_pose("glass").q, env.init_obj_quat("glass"))[0])) > 175.0
        assert bool(info["success"][0])
        upside_down = module["evaluate"](env)
        assert float(upside_down["turned"][0]) == pytest.approx(1.0, abs=0.01)
        glass.set_pose(sapien.Pose(p + [0.0, 0.0, 0.04], [np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0]))
        info = _still(env, 40)  # on its side: a quarter turn is no flip, and half the reward's turn
        side = module["evaluate"](env)
        assert not bool(info["success"][0]) and float(side["turned"][0]) == pytest.approx(0.5, abs=0.05)
        side["success"] = info["success"]
        upside_down["success"] = torch.zeros(1, dtype=torch.bool)
        assert float(module["compute_dense_reward"](env, None, None, side)[0]) < float(
            module["compute_dense_reward"](env, None, None, upside_down)[0])
    finally:
        env.close()


@pytest.mark.parametrize("vessel, seed", [("tumbler", 3), ("paper_cup", 5)])
def test_the_executor_turns_a_glass_over_and_leaves_it_on_its_top(solved, vessel, seed):
    ok, env, solver = solved(parse_task_spec(_task(vessel)), seed)
    assert ok
    assert [log.primitive for log in solver.logs[:4]] == ["approach", "grasp", "flip", "release"]
    assert float(np.degrees(tilt(env.obj_pose("glass").q, env.init_obj_quat("glass"))[0])) > 170.0
    assert float(env.obj_pose("glass").p[0, 2]) > 0.1  # standing on its rim: its origin (the base) is up
