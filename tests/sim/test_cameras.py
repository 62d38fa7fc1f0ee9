"""sensors=: an env declares only the cameras asked for, and each renders exactly what it renders beside the
others (a dataset build renders only its recorded camera)."""

import gymnasium as gym
import numpy as np
import pytest

from gendex_envs.cameras import SENSOR_CAMERAS
from gendex_envs.errors import RenderModeError

TASK = "GenDex/PutAppleBowl-v1"


def _frames(sensors, seed=4, steps=3):
    env = gym.make(TASK, obs_mode="rgb", sensor_resolution=48, sensors=sensors, scene="kitchen")
    try:
        obs, _ = env.reset(seed=seed)
        out = [obs["sensor_data"]]
        rng = np.random.default_rng(0)
        for _ in range(steps):
            obs, *_ = env.step(rng.uniform(env.action_space.low, env.action_space.high).astype(np.float32))
            out.append(obs["sensor_data"])
        return out
    finally:
        env.close()


def test_only_the_cameras_asked_for_render_and_they_render_the_same_pixels():
    every = _frames(None)
    one = _frames(["left_overhead"])
    assert sorted(every[0]) == sorted(SENSOR_CAMERAS) and list(one[0]) == ["left_overhead"]
    for a, b in zip(every, one, strict=True):
        rgb_all, rgb_one = (np.asarray(x["left_overhead"]["rgb"]) for x in (a, b))
        assert rgb_all.std() > 5  # a picture, not a blank frame
        np.testing.assert_array_equal(rgb_one, rgb_all)


@pytest.mark.parametrize("sensors, message", [(["wrist_cam"], "not a camera of the env; allowed"),
                                              (["top_down", "top_down"], "named twice"),
                                              ([], "name at least one camera")])
def test_an_unknown_or_repeated_camera_is_refused(sensors, message):
    with pytest.raises(RenderModeError, match=message):
        gym.make(TASK, obs_mode="rgb", sensors=sensors)
