"""The import-time heap is frozen before the first scene (``gendex_envs.heap``), and scenes built after it are still
reclaimed when torn down."""

from __future__ import annotations

import gc
import weakref


def test_scenes_torn_down_after_the_freeze_are_still_reclaimed(make_env):
    env = make_env("GenDex/PickUpBottle-v0")
    u = env.unwrapped
    assert gc.get_freeze_count() > 100_000  # modules, classes and import-time tables, walked by no later collection
    first = weakref.ref(u.scene.sub_scenes[0])
    env.reset(seed=0, options={"reconfigure": True})  # what a grasp trial does for each candidate
    gc.collect()
    assert first() is None and u.scene.sub_scenes[0] is not None
