"""Run INSIDE the lerobot side venv (scripts/lerobot_venv.sh), not the project's: load GenDex datasets with lerobot's
own LeRobotDataset, decode a frame of each video feature, ask lerobot's ACT config whether it accepts the
dataset's features, and normalise a frame's state and action as pi0.5 does (lerobot's NormalizerProcessorStep in
QUANTILES mode, from the dataset's stats: it needs q01 and q99; a value beyond 100 is reported as degenerate stats).
Prints one JSON object per dataset; exits 0 unless a dataset fails to load.

    .venv-lerobot/bin/python scripts/lerobot_check.py DATASET_ROOT [DATASET_ROOT ...]
"""

from __future__ import annotations

import json
import os
import sys

LARGEST_SANE = 100.0
"""A normalised value beyond this is a stats defect, not data: quantile normalisation maps q01..q99 to [-1, 1]."""


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
    out["pi05_norm"] = _pi05_normalisation(ds, features, item)
    out["quantiles_flat_across_episodes"] = _flat_quantiles(ds)
    return out


def _pi05_normalisation(ds, features, item) -> str:
    """What pi0.5's normalisation says to the dataset's stats: its own mapping (``PI05Config.normalization_mapping``:
    state and action by quantiles, images as they are, the environment state not at all, since pi0.5 does not read
    it): ``accepted (...)`` with the range of the normalised values, or ``refused: <lerobot's error>``."""
    import torch
    from lerobot.configs.types import FeatureType
    from lerobot.policies.pi05.configuration_pi05 import PI05Config
    from lerobot.processor.converters import create_transition
    from lerobot.processor.core import TransitionKey
    from lerobot.processor.normalize_processor import NormalizerProcessorStep

    norm_map = {FeatureType[k]: v for k, v in PI05Config().normalization_mapping.items()}
    step = NormalizerProcessorStep.from_lerobot_dataset(ds, features, norm_map)
    obs = {k: item[k][None] for k, f in features.items() if f.type is FeatureType.STATE}
    try:
        out = step(create_transition(observation=obs, action=item["action"][None]))
    except ValueError as exc:
        return f"refused: {exc}"
    values = torch.cat([v.flatten() for v in [*out[TransitionKey.OBSERVATION].values(), out[TransitionKey.ACTION]]])
    if not bool(torch.isfinite(values).all()):
        return "refused: non-finite normalised values"
    span = f"[{float(values.min()):.2f}, {float(values.max()):.2f}]"
    if float(values.abs().max()) > LARGEST_SANE:
        return f"degenerate (normalised values in {span}: a q01 == q99 where the frames differ)"
    return f"accepted (normalised values in {span})"


def _flat_quantiles(ds) -> dict[str, int]:
    """Per feature, the dimensions whose q01..q99 span under a thousandth of their min..max: a value constant
    within each episode (an articulated object's pose) that varies between episodes.
    lerobot 0.4 aggregates quantiles as the
    count-weighted mean of the episodes' (``aggregate_feature_stats``), so these collapse; normalise them by
    mean/std, not by quantiles."""
    import numpy as np

    out = {}
    for key, s in ds.meta.stats.items():
        if "q01" in s and "q99" in s:
            span = np.asarray(s["max"], np.float64) - np.asarray(s["min"], np.float64)
            flat = (np.asarray(s["q99"], np.float64) - np.asarray(s["q01"], np.float64) < 1e-3 * span) & (span > 0)
            if flat.any():
                out[key] = int(flat.sum())
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
