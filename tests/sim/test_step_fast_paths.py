"""The one-CPU-env shortcuts of ``env.step`` give exactly what ManiSkill's general code gives (issue: step overhead).

Each shortcut replaces a ManiSkill routine on the hot path of a single CPU env: contact queries, pose reads, the
observation flatten, the action scaling and the numpy conversion of the Gymnasium API. Each test runs both on the
same states and asserts equal values (and types, where the API returns them). The end-to-end guard is elsewhere:
``tests/sim/test_determinism.py`` and the smoke dataset's recorded checksums.
"""

import numpy as np
import pytest
import torch
from mani_skill.utils import common, gym_utils

import gendex_envs  # noqa: F401
from gendex_envs.physx import read_pose
from gendex_envs.wrappers import unbatched_numpy


def _random_steps(env, steps: int, seed: int = 0):
    """Yield after each of ``steps`` random delta-joint actions (resetting when an episode ends)."""
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    for i in range(steps):
        _, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
        yield i
        if terminated or truncated:
            env.reset(seed=seed + i + 1)


def test_contact_table_answers_what_maniskill_answers(make_env):
    """Net and pairwise impulses on every hand link, against ManiSkill's own per-query walks of the contact list,
    over random steps in which the hand hits the table and the objects."""
    env = make_env("GenDex/PutAppleBowl-v1", control_mode="pd_joint_delta_pos")
    base = env.unwrapped
    links = base.agent.robot.get_links()
    others = [base.table, *base.objects.values()]
    touching = 0
    for step in _random_steps(env, 330):
        if step < 200:  # the random walk reaches the table in the second episode (seed 0: from step 210)
            continue
        table = base.agent.contacts
        net = table.net_impulses(links)[0]
        expected = torch.stack([link.get_net_contact_impulses()[0] for link in links])
        torch.testing.assert_close(net, expected, rtol=1e-6, atol=1e-9)
        touching += int((net.abs().sum(dim=1) > 0).sum())
        for other in others:
            pair = table.pair_impulses(links, [other])[0]
            expected = torch.stack([base.scene.get_pairwise_contact_impulses(link, other)[0] for link in links])
            torch.testing.assert_close(pair, expected, rtol=1e-6, atol=1e-9)
    assert touching > 50, "the random actions never made the hand touch anything: the comparison proved nothing"


@pytest.mark.parametrize("task", ["GenDex/OpenCabinet-v1", "GenDex/PutAppleBowl-v1"])
def test_poses_read_from_physx_equal_maniskill_poses(make_env, task):
    env = make_env(task, control_mode="pd_joint_delta_pos")
    base = env.unwrapped
    structs = [base.agent.palm_link, *base.agent.tip_links, base.table, *base.objects.values(),
               *(link for art in base.articulations.values() for link in art.get_links())]
    for _ in _random_steps(env, 20):
        for struct in structs:
            fast, slow = read_pose(struct).raw_pose, struct.pose.raw_pose
            assert fast.dtype == slow.dtype and fast.shape == slow.shape == (1, 7)
            assert torch.equal(fast, slow), struct.name


@pytest.mark.parametrize("task", ["GenDex/OpenCabinet-v1", "GenDex/RotateTennisBall-v1"])
def test_flat_observation_equals_maniskills_flatten(make_env, task):
    env = make_env(task)
    base = env.unwrapped
    for _ in _random_steps(env, 10):
        raw = base.get_obs(base.get_info(), unflattened=True)
        fast = base._flatten_raw_obs(raw)
        slow = common.flatten_state_dict(raw, use_torch=True, device=base.device)
        assert fast.dtype == slow.dtype and torch.equal(fast, slow)


def test_a_state_dict_with_a_non_float_leaf_falls_back_to_maniskills_flatten(make_env):
    base = make_env("GenDex/PutAppleBowl-v1").unwrapped
    base.reset(seed=0)
    raw = {"agent": {"qpos": torch.rand(1, 3)}, "extra": {"flag": torch.tensor([True]), "x": torch.rand(1, 2)}}
    out = base._flatten_raw_obs(raw)
    assert torch.equal(out, common.flatten_state_dict(raw, use_torch=True, device=base.device))
    assert out.shape == (1, 6)


def test_scaled_actions_equal_maniskills_clip_and_scale(make_env):
    controller = make_env("GenDex/PutAppleBowl-v1", control_mode="pd_joint_delta_pos").unwrapped.agent.controller
    rng = np.random.default_rng(3)
    for _ in range(200):
        action = torch.as_tensor(rng.uniform(-1.6, 1.6, (1, controller.action_space.shape[0])), dtype=torch.float32)
        fast = controller._clip_and_scale_action(action)
        slow = gym_utils.clip_and_scale_action(action, controller.action_space_low, controller.action_space_high)
        assert torch.equal(fast, slow)


@pytest.mark.parametrize("value", [
    torch.tensor([[1.0, 2.0]]), torch.tensor([3.5]), torch.tensor([True]), torch.tensor([7], dtype=torch.int32),
    torch.zeros(2, 3), torch.tensor(4.0), np.ones((1, 4), dtype=np.float32), np.array([2]), np.array(5.0),
    np.float32(1.5), [1.0], [1, 2], True, 3, 2.5, "s", {"a": torch.tensor([[1.0]]), "b": {"c": torch.tensor([0])}},
])
def test_unbatched_numpy_equals_maniskills_unbatch_of_to_numpy(value):
    def same(x, y):
        assert type(x) is type(y), (type(x), type(y))
        if isinstance(x, dict):
            assert list(x) == list(y)
            for k in x:
                same(x[k], y[k])
        elif isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.shape == y.shape and np.array_equal(x, y)
        else:
            assert x == y

    same(unbatched_numpy(value), common.unbatch(common.to_numpy(value)))


def test_the_numpy_api_returns_python_scalars_and_unbatched_arrays(make_env):
    env = make_env("GenDex/PutAppleBowl-v1", max_episode_steps=3)
    obs, info = env.reset(seed=0)
    assert isinstance(obs, np.ndarray) and obs.ndim == 1
    flags = []
    for _ in range(3):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert isinstance(obs, np.ndarray) and obs.shape == env.observation_space.shape
        assert type(reward) is float and type(terminated) is bool and type(truncated) is bool
        assert isinstance(info["success"], bool) and isinstance(info["elapsed_steps"], int)
        flags.append(truncated)
    assert flags == [False, False, True]


def test_gym_make_env_matches_its_unwrapped_step(make_env):
    """The numpy API's step equals the batched step of an identical env, unbatched."""
    a = make_env("GenDex/OpenCabinet-v1")
    b = make_env("GenDex/OpenCabinet-v1", gym_api=False)
    a.reset(seed=4)
    b.reset(seed=4)
    rng = np.random.default_rng(4)
    for _ in range(15):
        action = rng.uniform(-1, 1, a.action_space.shape).astype(np.float32)
        obs, reward, terminated, truncated, info = a.step(action)
        obs_b, reward_b, terminated_b, truncated_b, info_b = b.step(torch.as_tensor(action)[None])
        assert np.array_equal(obs, obs_b[0].numpy()) and reward == float(reward_b[0])
        assert terminated == bool(terminated_b[0]) and truncated == bool(truncated_b[0])
        assert info["success"] == bool(info_b["success"][0])
