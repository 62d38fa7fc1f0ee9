"""The multi-task, language-conditioned BC baseline on synthetic LeRobot datasets (no simulator): one policy learns
two tasks whose observations look alike and whose experts act oppositely, so it must read the instruction."""

from __future__ import annotations

import json
from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest

from gendex.data.episode import Episode
from gendex.data.lerobot_v3 import LeRobotV3Writer
from gendex.imitation.bc import PolicyError, load_policy
from gendex.imitation.frames import DatasetReadError
from gendex.imitation.multitask import (
    FrameSampler,
    MultiTaskConfig,
    MultiTaskPolicy,
    PolicyTaskError,
    state_columns,
    train,
)
from gendex_envs.observation import ENVIRONMENT_STATE, STATE

S, A = 4, 2
TASKS = {"GenDex/ToyToward-v0": ("move toward the block", 1.0, 3), "GenDex/ToyAway-v0": ("move away from the block",
                                                                                           -1.0, 5)}


def fake_embed(texts: list[str]) -> np.ndarray:
    """A stand-in sentence encoder: a fixed unit vector per text (no language model in unit tests)."""
    out = []
    for text in texts:
        v = np.random.default_rng(sum(map(ord, text))).normal(size=16)
        out.append(v / np.linalg.norm(v))
    return np.asarray(out, np.float32)


def _episode(task: str, seed: int, t: int = 12) -> Episode:
    text, sign, k = TASKS[task]
    rng = np.random.default_rng(seed)
    world = np.repeat(rng.uniform(-1, 1, (1, k)), t + 1, 0).astype(np.float32)
    steps = np.arange(t, dtype=np.float32)[:, None]
    return Episode(task_id=task, instruction=text, seed=seed, control_mode="pd_joint_pos", control_joint="both",
                   fps=20, state=rng.normal(size=(t + 1, S)).astype(np.float32) * 0.01,
                   action=(sign * (world[:t, :A] + 0.1 * steps)).astype(np.float32), reward=np.zeros(t, np.float32),
                   success=np.r_[np.zeros(t - 1, bool), True], fail=np.zeros(t, bool),
                   env_states=np.zeros((t + 1, 2), np.float32), environment_state=world,
                   environment_state_names=tuple(f"w{i}" for i in range(k)))


def _dataset(root, task: str, action_names=None, state_names=None) -> None:
    k = TASKS[task][2]
    with LeRobotV3Writer(root, fps=20, robot_type="toy", state_names=state_names or [f"s{i}" for i in range(S)],
                         action_names=action_names or [f"a{i}" for i in range(A)],
                         environment_state_names=[f"w{i}" for i in range(k)]) as w:
        for seed in range(30):
            w.add_episode(_episode(task, seed))
    (root / "meta" / "gendex.json").write_text(json.dumps({"task_id": task, "env_kwargs": {
        "control_mode": "pd_joint_pos", "reconfiguration_freq": 1}, "episode_seeds": list(range(30))}))


@pytest.fixture
def datasets(tmp_path):
    paths = []
    for i, task in enumerate(TASKS):
        _dataset(tmp_path / f"d{i}" / "lerobot", task)
        paths.append(tmp_path / f"d{i}")
    return paths


def _env(instruction: str):
    return SimpleNamespace(unwrapped=SimpleNamespace(task_spec=SimpleNamespace(instruction=instruction)),
                           action_space=gym.spaces.Box(-10, 10, (A,), np.float32))


def _error(policy, task: str, instruction: str | None = None) -> float:
    policy.bind(_env(instruction or TASKS[task][0]))
    errs = []
    for seed in range(100, 106):  # episodes it never saw
        ep = _episode(task, seed)
        policy.reset()
        for t in range(ep.length):
            a = policy.act({STATE: ep.state[t], ENVIRONMENT_STATE: ep.environment_state[t]})
            errs.append(np.abs(a - ep.action[t]).max())
    return float(np.mean(errs))


def test_one_policy_learns_both_tasks_by_their_instructions(datasets, tmp_path):
    path = train(datasets, tmp_path / "mt", fake_embed, config=MultiTaskConfig(chunk=4, steps=800, hidden=128,
                                                                               layers=2, obs_noise=0.0, batch=128))
    policy = load_policy(str(path))
    assert isinstance(policy, MultiTaskPolicy) and policy.world_dim == 5
    assert policy.tasks == {t: v[0] for t, v in TASKS.items()} and policy.training_seeds == list(range(30))
    record = json.loads((tmp_path / "mt" / "bc.json").read_text())
    steps = [s for s, _ in record["curve"]]
    assert steps == list(range(16, 801, 16)) and record["curve"][-1][1] == record["final_loss"]  # 50 even points
    assert record["curve"][-1][1] < record["curve"][0][1]  # the smoothed loss falls
    for task in TASKS:
        assert _error(policy, task) < 0.3, task  # the actions span about 3 units
    # told the other task's instruction, it does the other task: the instruction is what it acts on
    assert _error(policy, "GenDex/ToyToward-v0", TASKS["GenDex/ToyAway-v0"][0]) > 1.0


def test_an_instruction_it_did_not_learn_needs_an_encoder(datasets, tmp_path):
    path = train(datasets, tmp_path / "mt", fake_embed, config=MultiTaskConfig(chunk=2, steps=5, hidden=16,
                                                                               layers=1))
    with pytest.raises(PolicyTaskError, match="did not learn 'push the block'"):
        MultiTaskPolicy(path).bind(_env("push the block"))
    policy = MultiTaskPolicy(path, fake_embed)
    policy.bind(_env("push the block"))
    policy.reset()
    assert policy.act({STATE: np.zeros(S, np.float32), ENVIRONMENT_STATE: np.zeros(3, np.float32)}).shape == (A,)
    with pytest.raises(PolicyTaskError, match="environment state has 6 values; the policy learned at most 5"):
        policy.act({STATE: np.zeros(S, np.float32), ENVIRONMENT_STATE: np.zeros(6, np.float32)})


def test_datasets_of_other_robots_or_the_same_task_twice_are_refused(datasets, tmp_path):
    other = tmp_path / "other" / "lerobot"
    _dataset(other, "GenDex/ToyAway-v0", action_names=["b0", "b1"])
    with pytest.raises(DatasetReadError, match="differ in action names"):
        train([datasets[0], other.parent], tmp_path / "x", fake_embed, config=MultiTaskConfig(steps=1))
    with pytest.raises(DatasetReadError, match="given twice"):
        train([datasets[0], datasets[0]], tmp_path / "x", fake_embed, config=MultiTaskConfig(steps=1))
    assert not (tmp_path / "x").exists()  # nothing written for a refused training


@pytest.mark.parametrize("balance, want", [(0.0, [0.01, 0.09, 0.90]), (1.0, [1 / 3, 1 / 3, 1 / 3])])
def test_task_balance_shares_batches_out_over_tasks(balance, want):
    counts = [10, 90, 900]
    draws = FrameSampler(counts, balance, np.random.default_rng(3))(60_000)
    assert draws.min() >= 0 and draws.max() < sum(counts)
    share = np.bincount(np.searchsorted(np.cumsum(counts), draws, side="right"), minlength=3) / len(draws)
    assert np.allclose(share, want, atol=0.01)
    first = np.bincount(draws[draws < 10], minlength=10) / (draws < 10).sum()
    assert np.allclose(first, 0.1, atol=0.03)  # uniform within a task


def test_task_balance_out_of_range_is_refused():
    with pytest.raises(ValueError, match="task_balance 1.5 must be from 0"):
        MultiTaskConfig(task_balance=1.5)
    with pytest.raises(ValueError, match="at least one frame"):
        FrameSampler([5, 0], 0.5, np.random.default_rng(0))


def test_the_fit_runs_on_the_threads_asked_and_gives_them_back(datasets, tmp_path):
    import torch

    before = torch.get_num_threads()
    train(datasets, tmp_path / "mt", fake_embed, config=MultiTaskConfig(chunk=2, steps=3, hidden=16, layers=1),
          threads=2)
    assert json.loads((tmp_path / "mt" / "bc.json").read_text())["threads"] == 2
    assert torch.get_num_threads() == before
    with pytest.raises(ValueError, match="threads 0 must be at least 1"):
        train(datasets, tmp_path / "none", fake_embed, config=MultiTaskConfig(steps=1), threads=0)
    assert not (tmp_path / "none").exists()


JOINT_STATE = ["j0.pos", "j1.pos", "j0.vel", "j1.vel"]


def _acts(policy, state: np.ndarray) -> np.ndarray:
    policy.reset()
    return policy.act({STATE: state, ENVIRONMENT_STATE: np.full(3, 0.5, np.float32)})


@pytest.mark.parametrize("velocity", [False, True])
def test_joint_velocities_are_read_only_when_asked(tmp_path, velocity):
    _dataset(tmp_path / "d" / "lerobot", "GenDex/ToyToward-v0", state_names=JOINT_STATE)
    path = train([tmp_path / "d"], tmp_path / "mt", fake_embed,
                 config=MultiTaskConfig(chunk=2, steps=30, hidden=32, layers=1, joint_velocity=velocity))
    policy = MultiTaskPolicy(path)
    policy.bind(_env(TASKS["GenDex/ToyToward-v0"][0]))
    # inputs: the state entries read, the 3 world values, the step and the 16-value embedding
    assert len(policy.ckpt["x_mean"]) == (4 if velocity else 2) + 3 + 1 + 16
    still, moving = np.zeros(4, np.float32), np.array([0, 0, 5, -5], np.float32)
    assert np.array_equal(_acts(policy, still), _acts(policy, moving)) is not velocity
    with pytest.raises(PolicyTaskError, match="state has 3 values; the policy learned 4 \\(j0.pos ... j1.vel\\)"):
        _acts(policy, np.zeros(3, np.float32))


def test_checkpoints_from_before_the_switch_read_velocities_and_a_bad_switch_is_refused(tmp_path):
    import torch

    _dataset(tmp_path / "d" / "lerobot", "GenDex/ToyToward-v0", state_names=JOINT_STATE)
    path = train([tmp_path / "d"], tmp_path / "mt", fake_embed,
                 config=MultiTaskConfig(chunk=2, steps=3, hidden=16, layers=1, joint_velocity=True))
    ckpt = torch.load(path, weights_only=True)
    del ckpt["config"]["joint_velocity"]  # what a checkpoint written before the field holds
    torch.save(ckpt, path)
    assert MultiTaskPolicy(path).keep.tolist() == [0, 1, 2, 3]
    ckpt["config"]["joint_velocity"] = "no"
    torch.save(ckpt, path)
    with pytest.raises(PolicyError, match="config.joint_velocity 'no' must be true or false"):
        MultiTaskPolicy(path)
    ckpt["config"]["joint_velocity"], ckpt["names"][STATE] = False, []
    torch.save(ckpt, path)
    with pytest.raises(PolicyError, match="must be the \\(non-empty\\) list of the state's entry names"):
        MultiTaskPolicy(path)
    with pytest.raises(ValueError, match="joint_velocity 1 must be True or False"):
        MultiTaskConfig(joint_velocity=1)
    assert state_columns(JOINT_STATE, False).tolist() == [0, 1]
