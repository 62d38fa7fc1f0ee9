"""Scenes in the env: appearance randomization never changes physics or a solver's actions; two seeds look
different and one seed looks the same byte for byte; structures collide and keep out of the objects' way; a task
without a scene keeps its plain look."""

import gymnasium as gym
import numpy as np
import pytest
import torch
from typer.testing import CliRunner

from gendex.cli import app
from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import parse_task_spec, spec_to_dict
from gendex_envs.task_env import VIEW_CAMERAS, TaskEnv

TASK = "GenDex/PutAppleBowl-v1"
NO_JITTER = {"position_m": 0.0, "rotation_deg": 0.0}
MAD_THRESHOLD = 15.0
"""Least mean absolute difference (0-255 levels) between two seeds' views over the pixels both show scenery (walls,
floor, table top, structures; the robot and the objects are masked out), camera jitter off (a camera shift alone
moves every textured pixel). Measured on PutAppleBowl-v1's kitchen (benchmarks/results/scenes.md): nothing drawn
(randomization off) gives 0.0 in 72 pairs; the lights alone 4.8-19.4 per view, typically 8; surface, floor and wall
changed with the lights 18.0-126. Seeds 2 and 3 give 67.8-84.9."""


def test_appearance_randomization_changes_neither_physics_nor_the_solvers_actions():
    """The stage executor solves one seed of a kitchen-scene task with appearance randomized and with it off
    (camera frames rendered at every step): the same actions, the same simulation state after reset and every step;
    only the look differs."""
    from gendex.episode_loop import Hooks
    from gendex.solve.attempt import run_attempt
    from gendex.solve.executor import StageExecutor

    runs = {}
    for randomize in (True, False):
        env = gym.make(TASK, control_mode="pd_joint_pos", control_joint="both", obs_mode="rgb", sensor_resolution=64,
                       scene="kitchen", randomize_appearance=randomize)
        actions, states = [], []

        def record(step, env=env, actions=actions, states=states):
            actions.append(np.asarray(step.action).copy())
            states.append(env.unwrapped.get_state()[0].cpu().numpy().copy())

        def at_reset(obs, info, env=env, states=states):
            states.append(env.unwrapped.get_state()[0].cpu().numpy().copy())

        try:
            out = run_attempt(env, StageExecutor(), 7, Hooks(on_reset=at_reset, on_step=record))
            runs[randomize] = (out, np.stack(actions), np.stack(states), env.unwrapped.appearance[0])
        finally:
            env.close()
    (out_on, act_on, st_on, look_on), (out_off, act_off, st_off, look_off) = runs[True], runs[False]
    assert out_on.succeeded and out_off.succeeded and out_on.steps == out_off.steps
    assert np.array_equal(act_on, act_off) and np.array_equal(st_on, st_off)
    assert look_off["randomized"] is False and look_on["randomized"] is True
    assert look_on["lights"] != look_off["lights"] and look_on["cameras"] != look_off["cameras"]


def _views(env, seed: int) -> tuple[dict, dict]:
    """(uint8 [H, W, 3] per view, bool [H, W] mask of the pixels showing scenery) after ``reset(seed)``."""
    env.reset(seed=seed)
    u = env.unwrapped
    rgb = u.render_views()
    look = {o.per_scene_id for o in u.scene.actors["scenery_0"]._objs}
    masks = {}
    for name in VIEW_CAMERAS:
        cam = u.scene.human_render_cameras[name]
        cam.capture()
        seg = cam.get_obs(rgb=False, depth=False, position=False, segmentation=True)["segmentation"]
        masks[name] = np.isin(seg[0, ..., 0].cpu().numpy(), list(look))
    return {n: rgb[n][0] for n in VIEW_CAMERAS}, masks


def test_two_seeds_look_different_and_one_seed_looks_the_same():
    env = gym.make(TASK, render_mode="rgb_array", scene={"style": "kitchen", "camera_jitter": NO_JITTER})
    try:
        a, mask_a = _views(env, 2)
        look_a = env.unwrapped.appearance[0]
        b, mask_b = _views(env, 3)
        look_b = env.unwrapped.appearance[0]
        again, _ = _views(env, 2)
    finally:
        env.close()
    for key in ("surface", "floor", "background", "lights", "ambient"):
        assert look_a[key] != look_b[key], key
    for name in VIEW_CAMERAS:
        both = mask_a[name] & mask_b[name]
        assert both.mean() > 0.5, f"{name}: scenery covers only {both.mean():.0%} of the view"
        mad = np.abs(a[name].astype(float) - b[name].astype(float))[both].mean()
        assert mad > MAD_THRESHOLD, f"{name}: seeds 2 and 3 differ by only {mad:.1f} levels over the scenery"
        assert again[name].tobytes() == a[name].tobytes(), f"{name}: seed 2 rendered twice differs"


def test_cli_renders_a_scene_the_same_for_a_seed_and_differently_for_another(tmp_path):
    runner = CliRunner()
    for out, seed in (("a", 3), ("b", 3), ("c", 4)):
        result = runner.invoke(app, ["render", TASK, "--seed", str(seed), "--scene", "kitchen", "--out",
                                     str(tmp_path / out)])
        assert result.exit_code == 0, result.output
    for name in VIEW_CAMERAS:
        png = f"PutAppleBowl-v1_{name}.png"
        first, second, other = ((tmp_path / d / png).read_bytes() for d in "abc")
        assert first == second and first != other, name
    refused = runner.invoke(app, ["render", TASK, "--scene", "kichen", "--out", str(tmp_path / "d")])
    assert refused.exit_code == 2 and "Did you mean: 'kitchen'" in refused.output


def _push_apple(scene) -> float:
    """x of the apple after it is shoved towards +x at 1.2 m/s and left alone for 1.5 s."""
    from gendex_envs.registry import resolve_task

    raw = spec_to_dict(resolve_task(TASK).spec)
    for obj in raw["objects"]:
        obj["randomize"] = {"xy_m": [0.0, 0.0], "yaw_deg": 0.0}
    raw["objects"][0]["pos_m"] = [0.25, 0.12, 0.0]
    raw["scene"] = scene
    env = TaskEnv(task_spec=parse_task_spec(raw), obs_mode="state", render_backend="none")
    try:
        env.reset(seed=0)
        apple = env.obj("apple")
        apple.set_linear_velocity(torch.tensor([[1.2, 0.0, 0.0]]))
        for _ in range(30):
            env.step(None)  # the arm holds its reset targets
        if scene is None:
            assert env.appearance == [{}] and "scenery_0" not in env.scene.actors
        return float(apple.pose.p[0, 0])
    finally:
        env.close()


def test_a_structure_stops_what_runs_into_it():
    """A backsplash standing across the table (its face at x = 0.39 m) stops the shoved apple (radius 4 cm); without
    it the apple rolls on to about 0.5 m."""
    wall = {"structures": [{"name": "wall", "kind": "backsplash", "pos_m": [0.40, 0.0, 0.0]}]}
    assert _push_apple(wall) < 0.39 - 0.03
    assert _push_apple(None) > 0.45


def test_a_structure_over_an_objects_start_region_is_refused():
    with pytest.raises(TaskSpecError, match=r"scene.structures\[0\] \(cutting_station 'board'\) .* overlaps object "
                                            r"'apple''s start region"):
        _push_apple({"structures": [{"name": "board", "kind": "cutting_station", "pos_m": [0.3, 0.12, 0.0]}]})


def test_the_planner_of_an_env_with_a_scene_avoids_its_structures():
    """ArmHandMotion of a kitchen env carries the kitchen's structures as static obstacles (the plain env none), and
    the robot at rest is clear of them."""
    from gendex.solve.motion import ArmHandMotion
    from gendex_envs.scene_styles import STYLES

    for scene, names in (("kitchen", {s.name for s in STYLES["kitchen"].structures}), (None, set())):
        env = gym.make(TASK, control_mode="pd_joint_pos", control_joint="both", obs_mode="state",
                       render_backend="none", scene=scene)
        try:
            env.reset(seed=0)
            motion = ArmHandMotion(env.unwrapped)
            assert {b.name.removeprefix("structure:") for b in motion.collision.static} == names
            assert motion.collision.is_free(motion.qpos())
        finally:
            env.close()


def test_a_dataset_records_what_each_episode_looked_like_and_a_plain_one_records_nothing(tmp_path):
    """The episodes parquet of a scene task's dataset holds each episode's drawn appearance (the env's, as JSON), also
    for episodes a killed writer journaled and a new writer appended again; a dataset of a task without a scene has
    no such column (its files are what they were before scenes)."""
    import json

    import pyarrow.parquet as pq

    from gendex.data.lerobot_v3 import APPEARANCE, LeRobotV3Writer
    from gendex.data.rollout import record_rollout

    def episodes(scene, seeds):
        env = gym.make(TASK, control_mode="pd_joint_delta_pos", **({"scene": scene} if scene else {}))
        try:
            out = []
            for seed in seeds:
                ep = record_rollout(env, seed, np.zeros((2, env.action_space.shape[0]), np.float32))
                out.append((ep, env.unwrapped.appearance[0]))
            return out
        finally:
            env.close()

    def writer(root, ep):
        return LeRobotV3Writer(root, fps=ep.fps, robot_type="ur10e_shadowhand",
                               state_names=[f"s{i}" for i in range(ep.state.shape[1])],
                               action_names=[f"a{i}" for i in range(ep.action.shape[1])])

    kitchen = episodes("kitchen", (4, 5))
    assert kitchen[0][1] and kitchen[0][1] != kitchen[1][1]  # drawn, and per seed
    root = tmp_path / "kitchen"
    with writer(root, kitchen[0][0]) as w:
        w.add_episode(kitchen[0][0])
    w = writer(root, kitchen[0][0])
    for ep, _ in kitchen[1:]:
        w.add_episode(ep)
    w._abandon()  # killed before closing: the second episode only journaled
    with writer(root, kitchen[0][0]):
        pass  # appends the journaled episodes again and publishes them
    rows = pq.read_table(next((root / "meta" / "episodes").rglob("*.parquet"))).to_pylist()
    assert [json.loads(r[APPEARANCE]) for r in rows] == [a for _, a in kitchen]

    (plain, drawn), = episodes(None, (4,))
    assert drawn == {} and plain.appearance == {}
    with writer(tmp_path / "plain", plain) as w:
        w.add_episode(plain)
    columns = pq.read_table(next((tmp_path / "plain" / "meta" / "episodes").rglob("*.parquet"))).column_names
    assert APPEARANCE not in columns
