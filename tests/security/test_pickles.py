"""No pickles from untrusted places (issue 43, deliverable 5).

A stage policy zip from a task folder and a BC checkpoint from anywhere are read as tensors plus a known
architecture: a pickle payload in the zip's ``data`` entry, in its ``policy.pth`` or in a checkpoint never runs.
Each payload, when unpickled, writes a marker file; the tests assert that the marker never appears and that the
refusal is a typed GenDex error naming the file. The hostile files are built at test time from the committed
RotateTennisBall policy, so the marker lives in the test's own folder.
"""

from __future__ import annotations

import base64
import io
import json
import pickle
import shutil
import zipfile
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch

from gendex.imitation.bc import BCPolicy, load_checkpoint, resave_trusted_checkpoint, save_checkpoint
from gendex.solve.policy import StagePolicy, load_policy_network, read_policy_weights
from gendex_envs.errors import GenDexError, PolicyError
from gendex_envs.task_version import PolicyFiles, TaskVersion

COMMITTED = Path(__file__).resolve().parents[2] / "generated_tasks" / "RotateTennisBall"


class _WritesMarker:
    """Unpickling this runs ``eval``: it writes ``path``, then gives what the loader expected (``then``, an
    expression), so that a vulnerable loader goes on as if nothing happened. What an attacker's file would do."""

    def __init__(self, path: Path, then: str = "None"):
        self.path, self.then = str(path), then

    def __reduce__(self):
        return (eval, (f"(open({self.path!r}, 'w').write('pickle payload ran'), {self.then})[1]",))


def _committed(version: str) -> PolicyFiles:
    files = TaskVersion.at(COMMITTED / version).policy("rotate_ball")  # the model and record lie in the task store
    assert files is not None
    return files


def _hostile_zip(tmp_path: Path, marker: Path, *, data: bool = False, weights: bool = False) -> PolicyFiles:
    """A copy of the committed v0 policy with a payload in its ``data`` entry (cloudpickle, as stable-baselines3
    stores ``policy_class``) and/or in its ``policy.pth`` (a pickle REDUCE)."""
    src = _committed("v0")
    out = tmp_path / "policies"
    out.mkdir()
    files = PolicyFiles("rotate_ball", out / "rotate_ball.zip", out / "rotate_ball.json")
    shutil.copy(src.record, files.record)
    payload = base64.b64encode(pickle.dumps(_WritesMarker(
        marker, "__import__('stable_baselines3.common.policies').common.policies.ActorCriticPolicy"))).decode()
    with zipfile.ZipFile(src.model) as zin, zipfile.ZipFile(files.model, "w") as zout:
        for item in zin.infolist():
            raw = zin.read(item)
            if data and item.filename == "data":
                record = json.loads(raw)
                record["policy_class"][":serialized:"] = payload
                raw = json.dumps(record).encode()
            if weights and item.filename == "policy.pth":
                buf = io.BytesIO()
                torch.save({"action_net.weight": _WritesMarker(marker)}, buf)
                raw = buf.getvalue()
            zout.writestr(item.filename, raw)
    return files


def test_a_policy_zip_whose_data_holds_a_pickle_payload_loads_without_running_it(task_version, tmp_path):
    """``gendex collect`` (the executor's StagePolicy.load): the pickled ``data`` entry is never read."""
    marker = tmp_path / "marker"
    files = _hostile_zip(tmp_path, marker, data=True)
    policy = StagePolicy.load(task_version("RotateTennisBall", 0), files)
    assert not marker.exists(), "the policy zip's pickled data ran"
    good, _ = load_policy_network(_committed("v0"))
    obs = np.random.default_rng(0).normal(size=(4, 136)).astype(np.float32)
    np.testing.assert_array_equal(policy.model.predict(obs, deterministic=True)[0],
                                  good.predict(obs, deterministic=True)[0])


def test_a_policy_pth_with_a_pickle_payload_is_refused_with_a_typed_error(task_version, tmp_path):
    marker = tmp_path / "marker"
    files = _hostile_zip(tmp_path, marker, weights=True)
    with pytest.raises(PolicyError, match=r"rotate_ball\.zip.*policy\.pth holds more than tensors"):
        StagePolicy.load(task_version("RotateTennisBall", 0), files)
    assert not marker.exists()


class _Box(gym.Env):
    observation_space = gym.spaces.Box(-np.inf, np.inf, (136,), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (20,), np.float32)

    def reset(self, *, seed=None, options=None):
        return np.zeros(136, np.float32), {}

    def step(self, action):
        return np.zeros(136, np.float32), 0.0, False, False, {}


def test_training_from_a_hostile_policy_zip_runs_no_pickle(tmp_path):
    """``gendex train --init-from``: the fine-tune starts from the zip's tensors only."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from gendex.train.presets import PRESETS
    from gendex.train.train import warm_start

    marker = tmp_path / "marker"
    files = _hostile_zip(tmp_path, marker, data=True)
    venv = VecNormalize(DummyVecEnv([_Box]), clip_obs=10.0)
    model = PPO("MlpPolicy", venv, device="cpu", **PRESETS["cpu"].ppo_kwargs())
    warm_start(model, venv, files, "hand", -1.2)
    assert not marker.exists(), "the policy zip's pickled data ran"
    want = read_policy_weights(_committed("v0").model)
    got = model.policy.state_dict()
    assert all(torch.equal(got[k], want[k]) for k in want if k != "log_std")

    marker2 = tmp_path / "marker2"
    (tmp_path / "policies").rename(tmp_path / "first")
    files = _hostile_zip(tmp_path, marker2, weights=True)
    with pytest.raises(GenDexError, match="policy.pth holds more than tensors"):
        warm_start(model, venv, files, "hand", -1.2)
    assert not marker2.exists()


@pytest.mark.parametrize("version", ["v0", "v1"])
def test_the_safe_loader_gives_what_ppo_load_gave_for_the_committed_policies(version):
    """Equivalence, with stable-baselines3's own loader run on the committed (trusted) files: same class, same
    weights, identical actions."""
    from stable_baselines3 import PPO

    files = _committed(version)
    net, meta = load_policy_network(files)
    old = PPO.load(str(files.model), device="cpu").policy
    assert type(net) is type(old)
    a, b = net.state_dict(), old.state_dict()
    assert a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)
    obs = np.random.default_rng(1).normal(scale=3.0, size=(16, meta["obs_dim"])).astype(np.float32)
    np.testing.assert_array_equal(net.predict(obs, deterministic=True)[0], old.predict(obs, deterministic=True)[0])


def test_a_record_whose_architecture_does_not_fit_its_weights_is_refused(tmp_path):
    src = _committed("v0")
    d = tmp_path / "p"
    d.mkdir()
    files = PolicyFiles("rotate_ball", d / "rotate_ball.zip", d / "rotate_ball.json")
    shutil.copy(src.model, files.model)
    meta = json.loads(src.record.read_text())
    meta["architecture"] = dict(kind="sb3-mlp-actor-critic", net_arch=[64], activation="relu", obs_dim=136,
                                action_dim=20)
    files.record.write_text(json.dumps(meta))
    with pytest.raises(PolicyError, match="do not fit the recorded architecture"):
        load_policy_network(files)
    meta["architecture"]["net_arch"] = [10**9]
    files.record.write_text(json.dumps(meta))
    with pytest.raises(PolicyError, match="MAX_LAYER_WIDTH"):
        load_policy_network(files)
    meta["architecture"] = dict(meta["architecture"], net_arch=[256, 256], obs_dim=135)
    files.record.write_text(json.dumps(meta))
    with pytest.raises(PolicyError, match="obs_dim 135 differs from the 136 values of obs_norm"):
        load_policy_network(files)
    meta["architecture"]["obs_dim"] = 136
    files.record.write_text(json.dumps(meta))
    assert load_policy_network(files)[0].action_net.out_features == 20  # the recorded architecture loads


# --------------------------------------------------------------------------------------------- BC checkpoints
def test_a_bc_checkpoint_with_a_pickle_payload_is_refused_with_a_typed_error(tmp_path):
    """``gendex eval --policy bc:PATH``."""
    marker = tmp_path / "marker"
    path = tmp_path / "bc.pt"
    weights, norm, info = _toy_parts()
    torch.save({"format": 2, "model": weights, **{k: torch.as_tensor(v, dtype=torch.float32) for k, v in norm.items()},
                **info, "config": _WritesMarker(marker, repr(info["config"]))}, path)
    try:
        BCPolicy(path)
        refused = None
    except PolicyError as exc:
        refused = str(exc)
    assert not marker.exists(), "the checkpoint's pickle payload ran"
    assert refused is not None and "bc.pt: it holds objects that only pickle can load" in refused


def _toy_parts() -> tuple[dict, dict, dict]:
    """(weights, normalization, metadata) of a tiny BC checkpoint: 2 state + 2 world features, 2 actions."""
    from gendex.imitation.bc import _mlp

    torch.manual_seed(0)
    model = _mlp(5, 4, 8, 2)
    info = {"config": {"chunk": 2, "hidden": 8, "layers": 2, "steps": 1, "batch": 1, "lr": 1e-3,
                       "weight_decay": 0.0, "obs_noise": 0.0, "ensemble_decay": 0.1, "seed": 0},
            "names": {"observation.state": ["s0"]}, "task_id": "GenDex/Toy-v0",
            "env_kwargs": {"control_mode": "pd_joint_pos"}, "training_seeds": [1, 2], "demos": 2, "frames": 10,
            "dataset": "toy", "final_loss": 0.5, "seconds": 1.0}
    norm = {"x_mean": np.zeros(5), "x_std": np.ones(5), "a_mean": np.zeros(2), "a_std": np.ones(2)}
    return model.state_dict(), norm, info


def _toy_checkpoint(path: Path) -> Path:
    return save_checkpoint(path, *_toy_parts())


def test_bc_checkpoints_load_with_weights_only_and_old_pickled_ones_are_refused_until_resaved(tmp_path):
    path = _toy_checkpoint(tmp_path / "bc.pt")
    torch.load(path, weights_only=True)  # nothing in it needs pickle
    policy = BCPolicy(path)
    policy.reset()
    action = policy.act({"observation.state": np.zeros(2, np.float32),
                         "observation.environment_state": np.zeros(2, np.float32)})
    assert action.shape == (2,) and np.isfinite(action).all()

    ckpt = load_checkpoint(path)  # the format before: numpy arrays, which only pickle can load
    old = {k: v for k, v in ckpt.items() if k != "format"}
    legacy = tmp_path / "legacy.pt"
    torch.save(old, legacy)
    with pytest.raises(PolicyError, match="resave_trusted_checkpoint"):
        BCPolicy(legacy)
    resave_trusted_checkpoint(legacy)  # the user's explicit word that they trust the file
    again = BCPolicy(legacy)
    np.testing.assert_array_equal(again.ckpt["x_std"], policy.ckpt["x_std"])


def test_a_bc_checkpoint_with_non_finite_or_out_of_bounds_values_is_refused(tmp_path):
    path = _toy_checkpoint(tmp_path / "bc.pt")
    ckpt = torch.load(path, weights_only=True)
    bad = dict(ckpt, x_std=torch.tensor([1.0, float("nan"), 1, 1, 1]))
    torch.save(bad, path)
    with pytest.raises(PolicyError, match="x_std must be a 1-D finite float tensor"):
        BCPolicy(path)
    bad = dict(ckpt, config=dict(ckpt["config"], hidden=10**9))
    torch.save(bad, path)
    with pytest.raises(PolicyError, match="config.hidden"):
        BCPolicy(path)


# --------------------------------------------------------------------------------------------- committed corpus
HOSTILE = Path(__file__).resolve().parents[1] / "data" / "hostile_r2" / "files"


@pytest.mark.parametrize("folder, refused", [("policy_data_pickle", None),
                                             ("policy_pth_pickle", "policy.pth holds more than tensors")])
def test_the_committed_hostile_policies_run_no_payload(tmp_path, monkeypatch, folder, refused):
    """``tests/data/hostile_r2/files/`` (``make_files.py`` rebuilds them): payloads write $GENDEX_HOSTILE_MARKER."""
    marker = tmp_path / "marker"
    monkeypatch.setenv("GENDEX_HOSTILE_MARKER", str(marker))
    files = PolicyFiles("rotate_ball", HOSTILE / folder / "rotate_ball.zip", HOSTILE / folder / "rotate_ball.json")
    if refused is None:
        net, _ = load_policy_network(files)  # the data entry is never read; the weights are fine
        assert net.predict(np.zeros((2, 4), np.float32), deterministic=True)[0].shape == (2, 20)
    else:
        with pytest.raises(PolicyError, match=refused):
            load_policy_network(files)
    assert not marker.exists()


def test_the_committed_hostile_bc_checkpoint_runs_no_payload(tmp_path, monkeypatch):
    marker = tmp_path / "marker"
    monkeypatch.setenv("GENDEX_HOSTILE_MARKER", str(marker))
    with pytest.raises(PolicyError, match="only pickle can load"):
        BCPolicy(HOSTILE / "bc_pickle.pt")
    assert not marker.exists()


def _deflated(raw: bytes) -> bytes:
    """The torch archive ``raw`` with every record deflated (torch's reader inflates them to their declared size)."""
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(raw)) as zin, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            zout.writestr(item.filename, zin.read(item))
    return out.getvalue()


def test_a_compressed_torch_archive_is_refused_before_it_is_inflated(tmp_path):
    """64 MB of weights in 70 kB: torch.load would inflate them; the archive's directory refuses them first."""
    buf = io.BytesIO()
    torch.save({"action_net.weight": torch.zeros(16_000_000)}, buf)
    bomb = _deflated(buf.getvalue())
    assert len(bomb) < 200_000
    src = _committed("v0")
    files = PolicyFiles("rotate_ball", tmp_path / "rotate_ball.zip", tmp_path / "rotate_ball.json")
    shutil.copy(src.record, files.record)
    with zipfile.ZipFile(src.model) as zin, zipfile.ZipFile(files.model, "w") as zout:
        for item in zin.infolist():
            zout.writestr(item.filename, bomb if item.filename == "policy.pth" else zin.read(item))
    with pytest.raises(PolicyError, match="compressed or oversized records"):
        read_policy_weights(files.model)
    path = tmp_path / "bc.pt"
    path.write_bytes(bomb)
    with pytest.raises(PolicyError, match=r"bc\.pt: compressed or oversized records"):
        load_checkpoint(path)


@pytest.mark.parametrize("key, value", [("trust_remote_code", True), ("start_states", "/etc/passwd"),
                                        ("control_mode", 3)])
def test_a_bc_checkpoint_cannot_choose_gym_make_arguments_beyond_what_a_dataset_records(tmp_path, key, value):
    """``gendex bc eval`` builds the env with the checkpoint's env_kwargs: a checkpoint must not turn on
    trust_remote_code for the task it is evaluated on, nor hand the env a file."""
    path = _toy_checkpoint(tmp_path / "bc.pt")
    ckpt = torch.load(path, weights_only=True)
    torch.save(dict(ckpt, env_kwargs={"control_mode": "pd_joint_pos", key: value}), path)
    with pytest.raises(PolicyError, match=f"env_kwargs {key}="):
        BCPolicy(path)



@pytest.mark.parametrize("sensors", [["/etc/passwd"], ["left_overhead"] * 9, [{"uid": "top_down"}], [3], []])
def test_a_bc_checkpoint_names_only_the_envs_own_cameras(tmp_path, sensors):
    """A dataset records ``sensors`` (the cameras it rendered); a checkpoint's list holds only the env's camera
    names, few, once each."""
    path = _toy_checkpoint(tmp_path / "bc.pt")
    ckpt = torch.load(path, weights_only=True)
    torch.save(dict(ckpt, env_kwargs={"control_mode": "pd_joint_pos", "sensors": sensors}), path)
    with pytest.raises(PolicyError, match="env_kwargs sensors"):
        BCPolicy(path)


_PEAK_SCRIPT = """
import resource, sys
from gendex.imitation.bc import BCPolicy
from gendex_envs.errors import PolicyError
try:
    BCPolicy(sys.argv[1])
    print("loaded")
except PolicyError as exc:
    print("refused:", exc)
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024)
"""


def test_a_small_checkpoint_whose_config_asks_for_a_huge_network_is_refused_before_it_is_built(tmp_path):
    """Its config sizes the network the loader builds before loading the weights: 16 layers of 8192 units (4.3 GB of
    float32) within the config's bounds, with the toy's few hundred weights. The shape is compared on the meta device
    first, so the loader refuses it naming the first mismatch, and its process never holds the network."""
    import subprocess
    import sys

    path = _toy_checkpoint(tmp_path / "bc.pt")
    ckpt = torch.load(path, weights_only=True)
    torch.save(dict(ckpt, config=dict(ckpt["config"], hidden=8192)), path)
    with pytest.raises(PolicyError, match=r"0.weight is \(8, 5\) in the file, \(8192, 5\) by the config"):
        BCPolicy(path)
    torch.save(dict(ckpt, config=dict(ckpt["config"], hidden=8192, layers=16)), path)
    assert path.stat().st_size < 100_000
    out = subprocess.run([sys.executable, "-c", _PEAK_SCRIPT, str(path)], capture_output=True, text=True,
                         timeout=300, check=True).stdout.split("\n")
    assert out[0].startswith("refused:") and "do not fit the network its config describes" in out[0], out
    assert "10.bias is missing in the file, (8192,) by the config" in out[0], out  # 16 layers asked, 2 given
    assert int(out[1]) < 2048, f"the refused load peaked at {out[1]} MiB"  # the network alone would be 4 300
