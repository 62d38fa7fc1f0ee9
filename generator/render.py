"""Render a scene spec from the three critic views (left-overhead, right-overhead, top-down) as PNG bytes."""

from __future__ import annotations

import io
import logging

import numpy as np

from gendex_envs.spec import TaskSpec

log = logging.getLogger(__name__)

VIEWS = ("left_overhead", "right_overhead", "top_down")
RESOLUTION = 384


def png_bytes(rgb: np.ndarray) -> bytes:
    """Encode an [H, W, 3] uint8 image as PNG with no metadata (same pixels, same bytes)."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="PNG", optimize=False)
    return buf.getvalue()


def render_spec(spec: TaskSpec, *, seed: int = 0, resolution: int = RESOLUTION) -> dict[str, bytes]:
    """PNG bytes of each view of ``spec`` after a reset with ``seed`` (object pose noise included)."""
    import torch

    from gendex_envs.task_env import TaskEnv

    env = TaskEnv(task_spec=spec, num_envs=1, render_mode="rgb_array", view_resolution=resolution,
                  render_backend="gpu" if torch.cuda.is_available() else "cpu")
    try:
        env.reset(seed=seed)
        views = env.render_views(VIEWS)
    finally:
        env.close()
    return {name: png_bytes(rgb[0]) for name, rgb in views.items()}
