"""Rigid skills beyond pick-and-carry: ``place`` (a held object is centred over its destination and let down until it
rests there) and ``push`` (an object slid across the table with the flat hand, closed loop on its measured pose)."""

import logging

import gymnasium as gym
import numpy as np
import pytest
import torch

from gendex.solve.executor import StageExecutor
from gendex_envs.spec import parse_task_spec
from gendex_envs.success import conditions_hold
from gendex_envs.task_env import TaskEnv


def _stage(name, skill, target):
    return {"name": name, "instruction": f"{skill} {target}", "skill": skill, "method": "motion_planning",
            "control_joint": "arm", "target": target}


def test_place_sets_a_block_down_on_a_plate_from_wide_random_layouts():
    spec = parse_task_spec({
        "name": "PlaceBlockOnPlate", "instruction": "Put the block on the plate.",
        "objects": [{"name": "block", "asset": "block_medium", "pos_m": [0.1, 0.12, 0.0],
                     "randomize": {"xy_m": [0.08, 0.08], "yaw_deg": 45}},
                    {"name": "plate", "asset": "plate", "pos_m": [0.12, -0.14, 0.0],
                     "randomize": {"xy_m": [0.08, 0.08], "yaw_deg": 45}}],
        "stages": [_stage("reach", "reach", "block"), _stage("grasp", "grasp", "block"),
                   _stage("carry", "carry", "plate"), _stage("place", "place", "plate"),
                   _stage("release", "release", "block")],
        "success": {"description": "The block rests on the plate.",
                    "conditions": [{"type": "over", "object": "block", "target": "plate", "max_xy_m": 0.08,
                                    "min_dz_m": 0.0, "max_dz_m": 0.04},
                                   {"type": "released", "object": "block"}]},
        "max_episode_steps": 300}, source="<test>")
    env = TaskEnv(task_spec=spec, control_mode="pd_joint_pos", control_joint="both", obs_mode="none",
                  reward_mode="none", render_backend="none")
    executor = StageExecutor()
    try:
        for seed in (501, 502):
            env.reset(seed=seed)
            executor.reset(env, None)
            lowest = []
            while (action := executor.act(env, None)) is not None:
                env.step(torch.as_tensor(action[None]))
                if executor.current_stage is not None and executor.current_stage.skill == "release":
                    lowest.append(float(env.obj("block").pose.p[0, 2]))
            assert bool(conditions_hold(env, spec.success.conditions)[0]), f"seed {seed}"
            # let down, not dropped: when the hand opened, the block was already within 2 cm of the plate's top
            assert lowest and lowest[0] < 0.045, (seed, lowest[:3])
            assert float(env.obj("block").linear_velocity[0].norm()) < 0.05
    finally:
        executor.rigid.close()
        env.close()


def test_push_slides_the_block_onto_the_goal_without_grasping_it(task_version):
    version = task_version("PushBlockToGoal")
    env = gym.make(version.env_id, control_mode="pd_joint_pos", control_joint="both")
    u = env.unwrapped
    executor = StageExecutor()
    try:
        for seed in (901, 902):
            obs, _ = env.reset(seed=seed)
            start = u.obj("block").pose.p[0, :2].numpy().copy()
            executor.reset(env, obs)
            lifted, info = 0.0, {}
            while (action := executor.act(env, obs)) is not None:
                obs, _, terminated, truncated, info = env.step(action)
                lifted = max(lifted, float(u.obj("block").pose.p[0, 2]))
                if terminated or truncated:
                    break
            end = u.obj("block").pose.p[0, :2].numpy()
            goal = u.goal_pos[0, :2].numpy()
            assert bool(info["success"]), (seed, start, end, goal)
            assert np.linalg.norm(end - start) > 0.15  # it travelled the table...
            assert lifted < 0.005  # ...on the table, never picked up
    finally:
        executor.rigid.close()
        env.close()


def test_a_tall_box_going_into_a_bowl_is_grasped_so_that_it_stays_upright():
    """On this seed the first grasps of the sugar box that hold let it swing over (its footprint about doubles, and
    a swung box catches the bowl's rim). The executor keeps trying and takes one that holds it upright."""
    from gendex.solve.attempt import run_attempt
    from gendex.solve.grasp_trial import UPRIGHT_SPREAD

    env = gym.make("GenDex/PutSugarBoxInBowl-v0", control_mode="pd_joint_pos", control_joint="both")
    executor = StageExecutor()
    try:
        out = run_attempt(env, executor, 1)
        held = [r for r in executor.rigid.trial_log if r.held]
        assert held[0].spread > 1.8  # the first grasp that held swung the box over
        assert executor.grasp_plan is held[-1].plan and held[-1].spread <= UPRIGHT_SPREAD
        assert all(r.spread > UPRIGHT_SPREAD for r in held[:-1])
        assert out.succeeded, out.failure
    finally:
        env.close()


def test_an_object_flung_onto_something_higher_is_grasped_again(caplog):
    """On this seed the lemon squirts out of the pinch as the hand lifts and lands on the cutting board, 5 cm above
    the table: it rose, but nothing of the hand touches it. That is a slip (grasped again), not a grasp that held
    (which failed the carry that followed, generated batch 52817)."""
    from pathlib import Path

    import yaml

    from gendex.solve.attempt import run_attempt
    from gendex_envs.spec import parse_task_spec

    path = Path(__file__).parents[1] / "data" / "tasks" / "SetLemonOnCuttingBoard.yaml"
    spec = parse_task_spec(yaml.safe_load(path.read_text()), source=str(path))
    env = TaskEnv(task_spec=spec, control_mode="pd_joint_pos", control_joint="both", obs_mode="none",
                  reward_mode="none", render_backend="none")
    try:
        with caplog.at_level(logging.INFO, logger="gendex.solve.rigid"):
            out = run_attempt(env, StageExecutor(), 800)
        slips = [r.getMessage() for r in caplog.records if "slipped (" in r.getMessage()]
        assert len(slips) == 1 and "touched by 0 part(s)" in slips[0], slips
        rose = float(slips[0].split("rose ")[1].split(" m")[0])
        assert rose > 0.04  # it did rise, onto the board
        assert out.succeeded, out.failure
    finally:
        env.close()


def _data_task_env(name: str) -> TaskEnv:
    from pathlib import Path

    import yaml

    path = Path(__file__).parents[1] / "data" / "tasks" / f"{name}.yaml"
    spec = parse_task_spec(yaml.safe_load(path.read_text()), source=str(path))
    return TaskEnv(task_spec=spec, control_mode="pd_joint_pos", control_joint="both", obs_mode="none",
                   reward_mode="none", render_backend="none")


def test_a_bottle_caged_a_little_over_still_goes_into_a_large_bowl():
    """The side cage holds the bottle tilted 25 degrees (its footprint spreads about 1.5x). It still fits the
    22 cm bowl, so it is taken; passed over as 'not upright', a pinch was taken instead and the bottle slipped out
    of it in the carry (this seed, before fits_on)."""
    from gendex.solve.attempt import run_attempt
    from gendex.solve.grasp_trial import UPRIGHT_SPREAD

    env = _data_task_env("PutBottleInBowlLarge")
    executor = StageExecutor()
    try:
        out = run_attempt(env, executor, 779002)
        first = executor.rigid.trial_log[0]
        assert first.held and first.plan.kind == "side" and first.spread > UPRIGHT_SPREAD
        assert executor.grasp_plan is first.plan
        assert out.succeeded, out.failure
    finally:
        executor.rigid.close()
        env.close()


def test_a_tall_box_held_high_is_carried_from_as_high_as_the_arm_reaches(caplog):
    """On this seed the first grasp that holds the sugar box is a side grasp that swings it over too far to fit the
    20 cm board (taken before fits_on: the box toppled off the board). The pinch taken instead holds the box low in
    the hand, so the carry first lifts it off the table, and the arm reaches only part of the 10 cm (the attempt
    stopped there with no_ik). It lifts as far as it reaches and the carry plans from there."""

    from gendex.solve.attempt import run_attempt

    env = _data_task_env("SetSugarBoxOnCuttingBoard")
    executor = StageExecutor()
    try:
        with caplog.at_level(logging.INFO, logger="gendex.solve.motion"):
            out = run_attempt(env, executor, 779001)
        assert any("reaches no further" in r.getMessage() for r in caplog.records)
        held = [r for r in executor.rigid.trial_log if r.held]
        assert held[0].plan.kind == "side" and held[0].spread > 2.0  # swung: does not fit the 20 cm board
        assert executor.grasp_plan is held[-1].plan and held[-1].plan.kind == "pinch"
        assert out.succeeded, out.failure
    finally:
        executor.rigid.close()
        env.close()


@pytest.mark.parametrize("seed", [779603, pytest.param(779604, marks=pytest.mark.slow)])
def test_a_ball_to_lie_on_a_board_is_set_down_on_it_not_dropped(seed):
    """A release whose ``near`` names a board first lowers the ball onto it. Dropped from the carry's height, a
    tennis ball bounced off the cutting board on these seeds; set down, it rests on the board, let go, and stays."""
    from gendex.solve.attempt import run_attempt
    from gendex_envs.geometry import transform_points
    from gendex_envs.success import rest_point

    env = _data_task_env("SetTennisBallOnCuttingBoard")
    executor = StageExecutor()
    try:
        out = run_attempt(env, executor, seed)
        assert out.succeeded, out.failure
        assert executor.rigid.placed_on == "cutting_board"
        board_top = float(env.obj("cutting_board").pose.p[0, 2]) + env.asset_record("cutting_board").size_m[2]
        ball = env.obj("tennis_ball").pose
        radius = env.asset_record("tennis_ball").size_m[2] / 2
        centre = transform_points(ball.p, ball.q, torch.tensor([0.0, 0.0, radius]))
        assert abs(float(centre[0, 2]) - radius - board_top) < 0.01  # on it, not in the air
        assert float(torch.linalg.norm(rest_point(env, "tennis_ball")[0, :2] - centre[0, :2])) < 1e-5
    finally:
        executor.rigid.close()
        env.close()


@pytest.mark.parametrize("seed", [52666200, pytest.param(52666201, marks=pytest.mark.slow)])
def test_a_bottle_the_grasp_tilted_is_stood_back_up_before_it_is_set_down(seed, caplog):
    """Batch 109453's SetBottleOnTray: the side grasp lifts the bottle 24° askew, more than it stands at. Set down so,
    it leaned on the opened thumb (0.35 N, so never ``released``) or, the hand backed away, fell over and lay off the
    tray's middle. Turned back upright in the hand first, it stands on the tray and the hand leaves it untouched."""
    from gendex.solve.attempt import run_attempt
    from gendex_envs.geometry import quat_rotate

    env = _data_task_env("SetBottleOnTray")
    executor = StageExecutor()
    try:
        with caplog.at_level(logging.INFO, logger="gendex.solve.rigid"):
            out = run_attempt(env, executor, seed)
        assert any("back up before setting it down" in r.getMessage() for r in caplog.records)
        assert out.succeeded, out.failure
        up = quat_rotate(env.obj("bottle").pose.q, torch.tensor([[0.0, 0.0, 1.0]]))
        assert float(up[0, 2]) > np.cos(np.radians(10))  # standing
        assert float(env.hand_forces("bottle").max()) < 0.05  # the hand left it (the release backs off past 0.05 N)
    finally:
        executor.rigid.close()
        env.close()


def test_a_grip_pressing_the_palm_too_hard_is_eased_in_the_physics_trials_as_in_the_grasp():
    """PutAppleBowl-v1's grasp stage allows the palm 10 N. On this seed every top grasp lifted the apple with the
    thumb and four fingers but pressed the palm at 12-14 N, and all ten trials were rejected (``grasp_failed``): the
    executor's grasp eased such a grip after its lift, the trials did not. Eased in the trials too, a top grasp holds
    within the ceiling and the task is solved."""
    from gendex.solve.attempt import run_attempt

    env = gym.make("GenDex/PutAppleBowl-v1", control_mode="pd_joint_pos", control_joint="both")
    executor = StageExecutor()
    try:
        out = run_attempt(env, executor, 261016)
        held = [r for r in executor.rigid.trial_log if r.held]
        assert held and held[0].plan.kind == "top", executor.rigid.trial_log
        assert out.succeeded, out.failure
    finally:
        env.close()
