"""Rebuild the hostile non-code files of this folder (issue 43): ``python tests/data/hostile_r2/files/make_files.py``.

Pickle payloads write the file named by the environment variable ``GENDEX_HOSTILE_MARKER`` when they are
unpickled, then hand the loader what it expected, so a vulnerable loader carries on as if nothing happened.
``tests/security/test_pickles.py`` and ``test_hostile_start_states.py`` load every file here and assert that no
marker appears and that the error is a typed GenDex error.

- ``policy_data_pickle/``: a stage policy (zip + record) whose zip's ``data`` entry holds a cloudpickle payload.
- ``policy_pth_pickle/``: the same policy with a REDUCE payload in ``policy.pth``.
- ``bc_pickle.pt``: a BC checkpoint with a REDUCE payload in its ``config``.
- ``start_states_<case>.npz``: start states with NaN, inf, 1e30, a far position, a non-unit quaternion, integers.
"""

from __future__ import annotations

import base64
import io
import json
import pickle
import shutil
import zipfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
MARKER_ENV = "GENDEX_HOSTILE_MARKER"


class Payload:
    def __init__(self, then: str = "None"):
        self.then = then

    def __reduce__(self):
        return (eval, (f"(open(__import__('os').environ[{MARKER_ENV!r}], 'w').write('payload ran'), {self.then})[1]",))


def _policy(folder: Path, *, data: bool, weights: bool) -> None:
    import gymnasium as gym
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    class Box(gym.Env):
        observation_space = gym.spaces.Box(-np.inf, np.inf, (4,), np.float32)
        action_space = gym.spaces.Box(-1.0, 1.0, (20,), np.float32)

        def reset(self, *, seed=None, options=None):
            return np.zeros(4, np.float32), {}

        def step(self, action):
            return np.zeros(4, np.float32), 0.0, False, False, {}

    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    model = PPO("MlpPolicy", DummyVecEnv([Box]), device="cpu", seed=0,
                policy_kwargs=dict(net_arch=[8], activation_fn=torch.nn.ReLU))
    model.save(folder / "plain.zip")
    with zipfile.ZipFile(folder / "plain.zip") as zin, zipfile.ZipFile(folder / "rotate_ball.zip", "w") as zout:
        for item in zin.infolist():
            raw = zin.read(item)
            if data and item.filename == "data":
                record = json.loads(raw)
                record["policy_class"][":serialized:"] = base64.b64encode(pickle.dumps(Payload(
                    "__import__('stable_baselines3.common.policies').common.policies.ActorCriticPolicy"))).decode()
                raw = json.dumps(record).encode()
            if weights and item.filename == "policy.pth":
                buf = io.BytesIO()
                torch.save({"action_net.weight": Payload()}, buf)
                raw = buf.getvalue()
            zout.writestr(item.filename, raw)
    (folder / "plain.zip").unlink()
    meta = dict(format=1, stage="rotate_ball", control_joint="hand", control_mode="pd_joint_delta_pos",
                obs_dim=4, obs_norm=dict(mean=[0.0] * 4, var=[1.0] * 4, clip=10.0),
                architecture=dict(kind="sb3-mlp-actor-critic", net_arch=[8], activation="relu", obs_dim=4,
                                  action_dim=20))
    (folder / "rotate_ball.json").write_text(json.dumps(meta, indent=1) + "\n")


def _bc(path: Path) -> None:
    import torch

    config = {"chunk": 1, "hidden": 4, "layers": 1, "steps": 1, "batch": 1, "lr": 0.001, "weight_decay": 0.0,
              "obs_noise": 0.0, "ensemble_decay": 0.1, "seed": 0}
    torch.save({"format": 2, "model": {}, "config": Payload(repr(config)), "x_mean": torch.zeros(3),
                "x_std": torch.ones(3), "a_mean": torch.zeros(1), "a_std": torch.ones(1), "names": {},
                "task_id": "GenDex/Toy-v0", "env_kwargs": {}, "training_seeds": [], "demos": 0, "frames": 0,
                "dataset": "", "final_loss": None, "seconds": 0.0}, path)


START_STATES = {
    "nan": dict(state=np.float32([[0.0, np.nan]])),
    "inf": dict(state=np.float32([[-np.inf, 0.0]])),
    "huge": dict(state=np.float32([[1e30, 0.0]])),
    "far_position": dict(pos=np.float32([[0.0, 0.0, 5e3]])),
    "quaternion": dict(quat=np.float32([[0.1, 0.0, 0.0, 0.0]])),
    "integers": dict(state=np.int64([[1, 2]])),
}


def _start_states(path: Path, state=None, pos=None, quat=None) -> None:
    arrays = {"state": np.zeros((1, 2), np.float32) if state is None else state,
              "meta": np.array(json.dumps({"stage": "s", "source": "hostile", "objects": ["box"]})),
              "pos/box": np.zeros((1, 3), np.float32) if pos is None else pos,
              "quat/box": np.float32([[1, 0, 0, 0]]) if quat is None else quat}
    with path.open("wb") as f:
        np.savez_compressed(f, **arrays)


def main() -> None:
    _policy(HERE / "policy_data_pickle", data=True, weights=False)
    _policy(HERE / "policy_pth_pickle", data=False, weights=True)
    _bc(HERE / "bc_pickle.pt")
    for case, arrays in START_STATES.items():
        _start_states(HERE / f"start_states_{case}.npz", **arrays)


if __name__ == "__main__":
    main()
