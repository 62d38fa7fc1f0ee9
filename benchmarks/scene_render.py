"""What a scene costs to render, and how different two seeds of it look (issue 49's render-time and pixel checks).

**Render time.** In one process, a task's env without a scene (its plain look) and the same task in each scene
style (``gym.make(task, scene=style)``), all with ``render_mode="rgb_array"``, each warmed up first (the first
frame of a process compiles shaders). Then ``--repeats`` rounds, the envs' order turning each round so load on the
machine falls on all alike; each round resets every env to a new seed (timed: the reset draws and applies the
appearance) and times ``--frames`` calls of ``render_views()`` (the three 512 px views ``gendex render`` writes)
and as many sensor captures (``get_obs()`` of ``obs_mode="rgb"``: the three views and the hand camera at
``--sensor-px``, what a pixel policy sees). Reported: the median seconds per frame (a view, or one sensor
observation of four cameras) and the ratio to the plain env. The issue's target: at most 1.5 times the plain look.

**Background difference.** For each style, ``--pairs`` pairs of seeds (0 and 1, 2 and 3, ...) with appearance
randomization on and off: the mean absolute difference (0-255 levels) of each view over the pixels both seeds show
scenery (the scenery's segmentation ids; robot and objects masked out). With ``--components``, the kitchen style
again without camera jitter, and with only the camera jitter, only the lights, or only the textures left to vary.
The test's threshold
(``tests/sim/test_scenes.py``) comes from these figures.

``--sheet PATH`` also writes the picture of ``docs/scenes.md``: each style at two seeds, left-overhead view.

Usage (the record in ``benchmarks/results/scenes.md``)::

    .venv/bin/python benchmarks/scene_render.py --repeats 7 --frames 5 --pairs 6 --components \\
        --json benchmarks/results/scenes.json
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # first: it pins OpenBLAS's kernels before numpy loads
# isort: on

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import gendex_envs  # noqa: F401 - registers the tasks
from gendex_envs.scene_styles import STYLES
from gendex_envs.task_env import VIEW_CAMERAS

ROOT = Path(__file__).resolve().parent.parent
FIXED = {"surface": {"materials": ["oak"]}, "floor": {"materials": ["tile_checker"]},
         "background": {"images": ["kitchen_subway_white"]}}
STEADY_LIGHT = {"ambient": [0.3, 0.3], "lights": [{"direction": [0.5, -1, -1]}, {"direction": [0, 0, -1]}]}
STILL = {"position_m": 0.0, "rotation_deg": 0.0}
COMPONENTS = {"no camera jitter": {"style": "kitchen", "camera_jitter": STILL},  # the test's setting
              "camera jitter only": {"style": "kitchen", **FIXED, "lighting": STEADY_LIGHT},
              "lights only": {"style": "kitchen", **FIXED, "camera_jitter": STILL},
              "textures only": {"style": "kitchen", "lighting": STEADY_LIGHT, "camera_jitter": STILL}}


def _make(task: str, scene, sensor_px: int, randomize: bool = True, obs_mode: str = "none"):
    kwargs = {} if scene is None else {"scene": scene, "randomize_appearance": randomize}
    return gym.make(task, render_mode="rgb_array", obs_mode=obs_mode, sensor_resolution=sensor_px, **kwargs)


def render_time(task: str, styles: list[str], repeats: int, frames: int, sensor_px: int) -> dict:
    names = ["none", *styles]
    envs = {n: _make(task, None if n == "none" else n, sensor_px, obs_mode="rgb") for n in names}
    per_view: dict[str, list[float]] = {n: [] for n in names}
    per_obs: dict[str, list[float]] = {n: [] for n in names}
    reset: dict[str, list[float]] = {n: [] for n in names}
    try:
        for env in envs.values():  # warm-up: shader compilation, first textures
            env.reset(seed=0)
            env.unwrapped.render_views()
            env.unwrapped.get_obs()
        for r in range(repeats):
            order = names[r % len(names):] + names[:r % len(names)]
            for n in order:
                u = envs[n].unwrapped
                t = time.perf_counter()
                envs[n].reset(seed=1000 + r)
                reset[n].append(time.perf_counter() - t)
                t = time.perf_counter()
                for _ in range(frames):
                    u.render_views()
                per_view[n].append((time.perf_counter() - t) / (frames * len(VIEW_CAMERAS)))
                t = time.perf_counter()
                for _ in range(frames):
                    u.get_obs()
                per_obs[n].append((time.perf_counter() - t) / frames)
    finally:
        for env in envs.values():
            env.close()
    med = {k: {n: statistics.median(v) for n, v in d.items()} for k, d in
           (("view_s", per_view), ("sensor_obs_s", per_obs), ("reset_s", reset))}
    return {"task": task, "repeats": repeats, "frames": frames, "sensor_px": sensor_px, "median": med,
            "ratio_to_none": {k: {n: med[k][n] / med[k]["none"] for n in names} for k in med},
            "all": {"view_s": per_view, "sensor_obs_s": per_obs, "reset_s": reset}}


def _views(env, seed: int) -> tuple[dict, dict, dict]:
    env.reset(seed=seed)
    u = env.unwrapped
    rgb = u.render_views()
    look = {o.per_scene_id for o in u.scene.actors["scenery_0"]._objs}  # noqa: SLF001 - its segmentation ids
    masks = {}
    for name in VIEW_CAMERAS:
        cam = u.scene.human_render_cameras[name]
        cam.capture()
        seg = cam.get_obs(rgb=False, depth=False, position=False, segmentation=True)["segmentation"]
        masks[name] = np.isin(seg[0, ..., 0].cpu().numpy(), list(look))
    return {n: rgb[n][0] for n in VIEW_CAMERAS}, masks, u.appearance[0]


def background_difference(task: str, scene, pairs: int, randomize: bool) -> list[dict]:
    env = _make(task, scene, 64, randomize)
    rows = []
    try:
        for k in range(pairs):
            (a, ma, la), (b, mb, lb) = _views(env, 2 * k), _views(env, 2 * k + 1)
            mad = {}
            for n in VIEW_CAMERAS:
                both = ma[n] & mb[n]
                mad[n] = round(float(np.abs(a[n].astype(float) - b[n].astype(float))[both].mean()), 2)
            differ = [f for f in ("surface", "floor", "background") if la[f] != lb[f]]
            rows.append({"seeds": [2 * k, 2 * k + 1], "mad": mad, "differ": differ,
                         "scenery_share": {n: round(float((ma[n] & mb[n]).mean()), 3) for n in VIEW_CAMERAS}})
    finally:
        env.close()
    return rows


def contact_sheet(task: str, styles: list[str], path: Path, seeds: tuple[int, ...] = (0, 1), px: int = 256) -> None:
    """One row per style, one column per seed: the left-overhead view at ``px`` pixels, the style's name on it."""
    from PIL import Image, ImageDraw

    rows = []
    for style in styles:
        env = _make(task, style, 64)
        try:
            tiles = []
            for seed in seeds:
                env.reset(seed=seed)
                img = Image.fromarray(env.unwrapped.render_views(("left_overhead",))["left_overhead"][0])
                img = img.resize((px, px), Image.LANCZOS)
                ImageDraw.Draw(img).text((6, 4), f"{style}, seed {seed}", fill=(255, 255, 255))
                tiles.append(np.asarray(img))
            rows.append(np.concatenate(tiles, axis=1))
        finally:
            env.close()
    Image.fromarray(np.concatenate(rows, axis=0)).quantize(256).save(path, optimize=True)  # 256 colours: small


def run(args) -> dict:
    styles = [s for s in STYLES if s != "plain"] if args.styles == ["all"] else args.styles
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    record: dict = {"command": "benchmarks/scene_render.py " + " ".join(args.argv), "commit": commit,
                    "machine": f"{platform.machine()}, {os.cpu_count()} CPUs",
                    "date": time.strftime("%Y-%m-%d"), "load_avg": os.getloadavg()}
    if args.repeats:
        record["render_time"] = render_time(args.task, styles, args.repeats, args.frames, args.sensor_px)
    if args.pairs:
        record["difference"] = {f"{s}/{'on' if r else 'off'}": background_difference(args.task, s, args.pairs, r)
                                for s in styles for r in (True, False)}
        if args.components:
            record["components"] = {k: background_difference(args.task, sc, args.pairs, True)
                                    for k, sc in COMPONENTS.items()}
    return record


def _print(record: dict) -> None:
    rt = record.get("render_time")
    if rt:
        print(f"render time, {rt['task']}, medians of {rt['repeats']} rounds x {rt['frames']} frames:")
        print("| scene | s / 512 px view | x none | s / sensor obs (4 x "
              f"{rt['sensor_px']} px) | x none | s / reset | x none |\n|---|---|---|---|---|---|---|")
        med, ratio = rt["median"], rt["ratio_to_none"]
        for n in med["view_s"]:
            print(f"| {n} | {med['view_s'][n]:.4f} | {ratio['view_s'][n]:.2f} | {med['sensor_obs_s'][n]:.4f} | "
                  f"{ratio['sensor_obs_s'][n]:.2f} | {med['reset_s'][n]:.3f} | {ratio['reset_s'][n]:.2f} |")
    for title, rows in (*record.get("difference", {}).items(), *record.get("components", {}).items()):
        side = [np.mean([r["mad"]["left_overhead"], r["mad"]["right_overhead"]]) for r in rows]
        per_view = {n: min(r["mad"][n] for r in rows) for n in VIEW_CAMERAS}
        print(f"{title}: side-view MAD per pair {[round(float(s), 1) for s in side]}; least per view {per_view}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", default="GenDex/PutAppleBowl-v1")
    ap.add_argument("--styles", nargs="*", default=["all"])
    ap.add_argument("--repeats", type=int, default=5, help="render-time rounds (0: skip)")
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--sensor-px", type=int, default=128)
    ap.add_argument("--pairs", type=int, default=6, help="seed pairs per style (0: skip the difference check)")
    ap.add_argument("--components", action="store_true", help="also vary the kitchen's jitter, lights, textures alone")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--sheet", type=Path, help="also write the styles' contact sheet (docs/images/scenes.png)")
    args = ap.parse_args()
    args.argv = sys.argv[1:]
    record = run(args)
    _print(record)
    if args.json:
        args.json.write_text(json.dumps(record, indent=1) + "\n")
    if args.sheet:
        contact_sheet(args.task, [s for s in STYLES if s != "plain"] if args.styles == ["all"] else args.styles,
                      args.sheet)


if __name__ == "__main__":
    main()
