"""Run INSIDE the lerobot side venv (scripts/lerobot_venv.sh), not the project's: load GenDex datasets with lerobot's
own LeRobotDataset, decode a frame of each video feature, and ask lerobot's ACT config whether it accepts the
dataset's features. Prints one JSON object per dataset; exits 0 unless a dataset fails to load.

    .venv-lerobot/bin/python scripts/lerobot_check.py DATASET_ROOT [DATASET_ROOT ...]
"""

from __future__ import annotations

import json
import os
import sys


def check(root: str) -> dict:
    os.environ["HF_HUB_OFFLINE"] = "1"
    from lerobot.configs.types import FeatureType
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from lerobot.datasets.utils import dataset_to_policy_features
    from lerobot.policies.act.configuration_act import ACTConfig

    ds = LeRobotDataset("local/gendex-check", root=root, video_backend="torchcodec")
    item = ds[len(ds) // 2]
    out = {"root": root, "frames": len(ds), "episodes": ds.num_episodes, "task": item["task"],
           "features": sorted(ds.meta.features), "decoded": {}}
    for key in ds.meta.video_keys:
        out["decoded"][key] = list(item[key].shape)  # C, H, W float in [0, 1]
    features = dataset_to_policy_features(ds.meta.features)
    outputs = {k: f for k, f in features.items() if f.type is FeatureType.ACTION}
    inputs = {k: f for k, f in features.items() if k not in outputs}
    try:
        cfg = ACTConfig(input_features=inputs, output_features=outputs)
        cfg.validate_features()
        out["act"] = "accepted"
    except ValueError as exc:
        out["act"] = f"refused: {exc}"
    return out


def main() -> int:
    ok = True
    for root in sys.argv[1:]:
        try:
            print(json.dumps(check(root)), flush=True)
        except Exception as exc:  # report it and go on: the caller decides
            ok = False
            print(json.dumps({"root": root, "error": f"{type(exc).__name__}: {exc}"}), flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
