"""The behaviour-cloning baseline on a synthetic LeRobot dataset (no simulator): it reads the dataset's features,
learns a mapping from them, and runs as a policy with temporal ensembling (one check makes a real env: a policy
bound to the wrong task)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gendex.data.episode import Episode
from gendex.data.lerobot_v3 import LeRobotV3Writer
from gendex.imitation.bc import BCConfig, BCPolicy, _chunk_targets, curve_due, train
from gendex.imitation.frames import DatasetReadError, load_frames
from gendex_envs.observation import ENVIRONMENT_STATE, STATE

S, K, A = 4, 3, 2


def _episode(seed: int, t: int = 12) -> Episode:
    """The 'expert' moves its two targets towards the object's x, y: action = world[:2] + 0.1 * step."""
    rng = np.random.default_rng(seed)
    world = np.repeat(rng.uniform(-1, 1, (1, K)), t + 1, 0).astype(np.float32)
    steps = np.arange(t, dtype=np.float32)[:, None]
    return Episode(task_id="GenDex/Toy-v0", instruction="toy", seed=seed, control_mode="pd_joint_pos",
                   control_joint="both", fps=20, state=rng.normal(size=(t + 1, S)).astype(np.float32) * 0.01,
                   action=(world[:t, :A] + 0.1 * steps).astype(np.float32), reward=np.zeros(t, np.float32),
                   success=np.r_[np.zeros(t - 1, bool), True], fail=np.zeros(t, bool),
                   env_states=np.zeros((t + 1, 2), np.float32), environment_state=world,
                   environment_state_names=tuple(f"w{i}" for i in range(K)))


@pytest.fixture
def toy_dataset(tmp_path):
    root = tmp_path / "lerobot"
    with LeRobotV3Writer(root, fps=20, robot_type="toy", state_names=[f"s{i}" for i in range(S)],
                         action_names=[f"a{i}" for i in range(A)],
                         environment_state_names=[f"w{i}" for i in range(K)]) as w:
        for seed in range(40):
            w.add_episode(_episode(seed))
    (root / "meta" / "gendex.json").write_text(json.dumps({"task_id": "GenDex/Toy-v0", "env_kwargs": {
        "control_mode": "pd_joint_pos", "reconfiguration_freq": 1}, "episode_seeds": list(range(100, 140))}))
    return root


def test_frames_and_chunk_targets(toy_dataset):
    f = load_frames(toy_dataset, episodes=5)
    assert f.episodes == 5 and f.state.shape == (60, S) and f.environment_state.shape == (60, K)
    assert f.names[ENVIRONMENT_STATE] == ["w0", "w1", "w2"] and f.names[STATE][0] == "s0"
    y = _chunk_targets(f, 4)
    assert y.shape == (60, 4, A)
    np.testing.assert_array_equal(y[0], f.action[0:4])
    np.testing.assert_array_equal(y[11], np.repeat(f.action[11:12], 4, 0))  # the episode's last action repeated
    with pytest.raises(DatasetReadError, match="holds 40 episodes; asked for 41"):
        load_frames(toy_dataset, episodes=41)


def test_bc_learns_the_expert_and_records_what_it_learned_from(toy_dataset, tmp_path):
    path = train(toy_dataset, tmp_path / "bc", demos=30, config=BCConfig(chunk=4, steps=500, hidden=64, layers=2,
                                                                          obs_noise=0.0))
    policy = BCPolicy(path)
    assert policy.task_id == "GenDex/Toy-v0" and policy.training_seeds == list(range(100, 130))
    assert policy.env_kwargs == {"control_mode": "pd_joint_pos"}  # the determinism flag is the evaluator's
    errs = []
    for seed in range(30, 40):  # episodes it never saw
        ep = _episode(seed)
        policy.reset()
        for t in range(ep.length):
            a = policy.act({STATE: ep.state[t], ENVIRONMENT_STATE: ep.environment_state[t]})
            errs.append(np.abs(a - ep.action[t]).max())
    assert np.mean(errs) < 0.15, np.mean(errs)  # the actions span about 3 units


def test_a_dataset_without_environment_state_is_refused(tmp_path):
    root = tmp_path / "old"
    with LeRobotV3Writer(root, fps=20, robot_type="toy", state_names=["s"], action_names=["a"]) as w:
        ep = _episode(0)
        w.add_episode(Episode(**{**ep.__dict__, "state": ep.state[:, :1], "action": ep.action[:, :1],
                                 "environment_state": None, "environment_state_names": ()}))
    with pytest.raises(DatasetReadError, match="no 'observation.environment_state' feature"):
        load_frames(root)


def test_a_checkpoint_acts_only_in_the_task_it_learned_and_several_cover_a_suite(toy_dataset, tmp_path):
    """``bc:PATH`` in another task's env fails naming both tasks (another version of its own task is allowed);
    ``bc:A,B`` binds each env to its own task's checkpoint and refuses a task it has none for (the evaluation then
    fails that task's episodes with the reason)."""
    import shutil
    from types import SimpleNamespace

    from gendex.eval.runner import evaluate_task
    from gendex.imitation.bc import BCPolicies, PolicyTaskError, load_policy

    cfg = BCConfig(chunk=4, steps=20, hidden=16, layers=1)
    toy = train(toy_dataset, tmp_path / "toy", config=cfg)
    other_root = tmp_path / "other" / "lerobot"
    shutil.copytree(toy_dataset, other_root)
    meta = json.loads((other_root / "meta" / "gendex.json").read_text())
    (other_root / "meta" / "gendex.json").write_text(json.dumps({**meta, "task_id": "GenDex/Other-v0"}))
    other = train(other_root, tmp_path / "other_bc", config=cfg)

    def env(task):
        return SimpleNamespace(spec=SimpleNamespace(id=task),
                               action_space=SimpleNamespace(low=-np.ones(A), high=np.ones(A)))

    with pytest.raises(PolicyTaskError, match="learned GenDex/Toy-v0, not GenDex/Other-v0"):
        BCPolicy(toy).bind(env("GenDex/Other-v0"))
    BCPolicy(toy).bind(env("GenDex/Toy-v3"))  # another version of its task: allowed
    both = load_policy(f"{toy},{other}")
    assert isinstance(both, BCPolicies) and sorted(both.by_task) == ["GenDex/Other-v0", "GenDex/Toy-v0"]
    both.bind(env("GenDex/Other-v0"))
    assert both.active.task_id == "GenDex/Other-v0"
    both.bind(env("GenDex/Toy-v1"))
    assert both.active.task_id == "GenDex/Toy-v0"
    both.bind(env("GenDex/Other-v0"))
    both.reset()
    assert both.act({STATE: np.zeros(S, np.float32), ENVIRONMENT_STATE: np.zeros(K, np.float32)}).shape == (A,)
    with pytest.raises(PolicyTaskError, match=r"no BC checkpoint for GenDex/Third-v0; checkpoints: \['GenDex/Other"):
        both.bind(env("GenDex/Third-v0"))
    with pytest.raises(PolicyTaskError, match="two BC checkpoints for GenDex/Toy-v0"):
        load_policy(f"{toy},{toy}")
    rows = evaluate_task("GenDex/PutAppleBowl-v1", lambda: load_policy(str(toy)), [7, 8])
    assert [(r.seed, r.success_at_end, r.length) for r in rows] == [(7, False, 0), (8, False, 0)]
    assert all("learned GenDex/Toy-v0, not GenDex/PutAppleBowl-v1" in r.failure for r in rows)


@pytest.mark.parametrize(("steps", "points", "first"), [(3, 3, 1), (50, 50, 1), (800, 50, 16), (6000, 50, 120),
                                                         (100_000, 100, 1000), (101, 51, 2)])
def test_a_learning_curve_has_evenly_spaced_points_and_the_last_step(steps, points, first):
    due = [s for s in range(1, steps + 1) if curve_due(s, steps)]
    assert len(due) == points and due[0] == first and due[-1] == steps
