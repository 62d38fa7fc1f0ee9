"""The multi-task pixel policy on synthetic LeRobot datasets with camera video (no simulator): the world is shown
only in the camera's frames (a solid colour per episode), so the policy must read them, and the two tasks' experts
act oppositely, so it must read the instruction too."""

from __future__ import annotations

import json
from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest

from gendex.data.episode import Episode
from gendex.data.lerobot_v3 import LeRobotV3Writer
from gendex.eval.runner import observation_kwargs
from gendex.imitation.bc import load_policy
from gendex.imitation.frames import DatasetReadError, load_frames, load_images
from gendex.imitation.pixels import PixelConfig, PixelPolicy, train
from gendex_envs.observation import IMAGES, STATE

S, A, RES = 4, 2, 32
TASKS = {"GenDex/ToyToward-v0": ("move toward the block", 1.0), "GenDex/ToyAway-v0": ("move away from it", -1.0)}


def fake_embed(texts: list[str]) -> np.ndarray:
    out = []
    for text in texts:
        v = np.random.default_rng(sum(map(ord, text))).normal(size=8)
        out.append(v / np.linalg.norm(v))
    return np.asarray(out, np.float32)


def _episode(task: str, seed: int, t: int = 6) -> Episode:
    text, sign = TASKS[task]
    rng = np.random.default_rng(seed)
    world = rng.uniform(-1, 1, 2).astype(np.float32)
    colour = np.array([(world[0] + 1) * 120, (world[1] + 1) * 120, 60], np.uint8)
    frames = np.broadcast_to(colour, (t + 1, RES, RES, 3)).copy()
    return Episode(task_id=task, instruction=text, seed=seed, control_mode="pd_joint_pos", control_joint="both",
                   fps=20, state=np.zeros((t + 1, S), np.float32), action=np.repeat(sign * world[None], t, 0),
                   reward=np.zeros(t, np.float32), success=np.r_[np.zeros(t - 1, bool), True],
                   fail=np.zeros(t, bool), env_states=np.zeros((t + 1, 2), np.float32),
                   images={"left_overhead": frames},
                   environment_state=np.zeros((t + 1, 1), np.float32), environment_state_names=("w",))


@pytest.fixture
def datasets(tmp_path):
    paths = []
    for i, task in enumerate(TASKS):
        root = tmp_path / f"d{i}" / "lerobot"
        with LeRobotV3Writer(root, fps=20, robot_type="toy", state_names=[f"s{k}" for k in range(S)],
                             action_names=[f"a{k}" for k in range(A)], cameras={"left_overhead": (RES, RES)},
                             environment_state_names=["w"], video_codec="libx264") as w:
            for seed in range(30):
                w.add_episode(_episode(task, seed))
        (root / "meta" / "gendex.json").write_text(json.dumps({"task_id": task, "env_kwargs": {
            "control_mode": "pd_joint_pos", "obs_mode": "rgb", "sensor_resolution": RES},
            "episode_seeds": list(range(30))}))
        paths.append(root.parent)
    return paths


def test_frames_are_decoded_in_the_rows_order_and_resized(datasets):
    rows = load_frames(datasets[0], episodes=3)
    images = load_images(datasets[0], "left_overhead", episodes=3)
    assert images.shape == (len(rows.action), RES, RES, 3)
    for e in range(3):  # each episode's frames show its own colour (lossy video: within a few levels)
        want = _episode("GenDex/ToyToward-v0", e).images["left_overhead"][:-1]
        np.testing.assert_allclose(images[rows.episode == e].mean((1, 2)), want.mean((1, 2)), atol=6)
    assert load_images(datasets[0], "left_overhead", episodes=1, size=16).shape[1:] == (16, 16, 3)
    with pytest.raises(DatasetReadError, match="no video of camera 'wrist'.*cameras: \\['left_overhead'\\]"):
        load_images(datasets[0], "wrist")


def _env(instruction: str):
    return SimpleNamespace(unwrapped=SimpleNamespace(task_spec=SimpleNamespace(instruction=instruction)),
                           action_space=gym.spaces.Box(-10, 10, (A,), np.float32))


def _error(policy, task: str, instruction: str | None = None) -> float:
    policy.bind(_env(instruction or TASKS[task][0]))
    errs = []
    for seed in range(100, 110):
        ep = _episode(task, seed)
        policy.reset()
        for t in range(ep.length):
            errs.append(np.abs(policy.act({STATE: ep.state[t], IMAGES + "left_overhead": ep.images["left_overhead"][t]})
                               - ep.action[t]).max())
    return float(np.mean(errs))


def test_the_pixel_policy_reads_the_camera_and_the_instruction(datasets, tmp_path):
    cfg = PixelConfig(camera="left_overhead", image_size=16, channels=(8, 16), embed=32, hidden=64, layers=2, chunk=2,
                      steps=600, batch=64, lr=2e-3, shift=1, obs_noise=0.0)
    path = train(datasets, tmp_path / "px", fake_embed, config=cfg)
    policy = load_policy(str(path))
    assert isinstance(policy, PixelPolicy) and policy.training_seeds == list(range(30))
    assert observation_kwargs(policy) == {"obs_mode": "rgb", "sensor_resolution": 16, "sensors": ["left_overhead"]}
    assert "obs_mode" not in policy.env_kwargs  # what it observes is the runner's business, not a task argument
    for task in TASKS:
        assert _error(policy, task) < 0.35, task  # actions span 2 units; the mean guess errs by about 0.5
    assert _error(policy, "GenDex/ToyToward-v0", TASKS["GenDex/ToyAway-v0"][0]) > 0.6
    curve = json.loads((tmp_path / "px" / "bc.json").read_text())["curve"]
    assert [s for s, _ in curve] == list(range(12, 601, 12))  # 50 evenly spaced points
    assert curve[-1][1] == pytest.approx(policy.ckpt["final_loss"]) and curve[-1][1] < curve[0][1]


def test_a_policy_may_only_ask_the_env_for_cameras():
    assert observation_kwargs(SimpleNamespace()) == {}
    with pytest.raises(ValueError, match="may only set obs_mode"):
        observation_kwargs(SimpleNamespace(observation_kwargs={"obs_mode": "rgb", "robot_init_qpos_noise": 1.0}))
    with pytest.raises(ValueError, match="sensor_resolution"):
        observation_kwargs(SimpleNamespace(observation_kwargs={"sensor_resolution": 4096}))
    for sensors in (["wrist"], "left_overhead", ["top_down", "top_down"], []):
        with pytest.raises(ValueError, match="sensors"):
            observation_kwargs(SimpleNamespace(observation_kwargs={"sensors": sensors}))
