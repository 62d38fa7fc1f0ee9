"""Benchmarks must keep running as the package changes (their numbers are printed, not asserted)."""

import re
import subprocess
import sys

import pytest


@pytest.mark.parametrize("task", ["GenDex/PutAppleBowl-v0", "GenDex/OpenCabinet-v0"])
def test_step_rate_benchmark_runs_and_builds_an_equivalent_scene(repo_root, task):
    script = repo_root / "benchmarks" / "step_rate.py"
    out = subprocess.run([sys.executable, str(script), "--task", task, "--steps", "20", "--warmup", "5", "--repeats",
                          "1"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    bodies = re.search(r"bodies \(dynamic, static, links\): env (\(.*?\))\s+raw (\(.*?\))", out.stdout)
    assert bodies and bodies.group(1) == bodies.group(2), out.stdout
    assert re.search(r"ratio env / raw\s+\d+\.\d+", out.stdout), out.stdout


def test_collect_benchmark_reports_success_rate_and_steps_per_success(repo_root):
    script = repo_root / "benchmarks" / "collect.py"
    out = subprocess.run([sys.executable, str(script), "--tasks", "GenDex/PutAppleBowl-v0", "--episodes", "3",
                          "--workers-trial", "0"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    m = re.search(r"PutAppleBowl-v0: (\d+)/3 succeeded .*?([\d.]+) env steps per success", out.stdout)
    assert m, out.stdout
    assert int(m.group(1)) == 3 and 0 < float(m.group(2)) < 200, out.stdout


def test_collect_benchmark_defaults_to_the_newest_reference_versions(repo_root):
    import importlib.util

    from gendex_envs.registry import registered_tasks

    spec = importlib.util.spec_from_file_location("collect_bench", repo_root / "benchmarks" / "collect.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    ids = bench.newest_reference_ids()
    versions = registered_tasks()
    assert [versions[i].name for i in ids] == list(bench.REFERENCE_TASKS)
    for env_id in ids:
        mine = versions[env_id]
        assert all(v.version <= mine.version for v in versions.values() if v.name == mine.name), env_id
    assert "GenDex/PickUpBottle-v0" not in ids  # v1 and v2 exist


def test_blind_replay_benchmark_replays_a_recorded_success_open_loop(repo_root):
    """On the seed it was recorded on, a replayed success succeeds again: the replay is exact, so what the benchmark
    reports on new seeds is the randomization's doing."""
    script = repo_root / "benchmarks" / "blind_replay.py"
    out = subprocess.run([sys.executable, str(script), "--tasks", "GenDex/PickUpBottle-v1", "--seed", "0", "--seeds",
                          "1"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    m = re.search(r"PickUpBottle-v1: blind replay of seed (\d+)'s success \((\d+) actions\): (\d+)/1", out.stdout)
    assert m, out.stdout
    assert m.group(1) == "0" and int(m.group(2)) > 0 and m.group(3) == "1", out.stdout


def test_scene_render_benchmark_times_both_looks_and_sees_appearance_only_when_drawn(repo_root):
    """One round of the scene benchmark: both envs are timed, and over the scenery two seeds differ with
    randomization on and not at all with it off."""
    import argparse
    import importlib.util

    spec = importlib.util.spec_from_file_location("scene_bench", repo_root / "benchmarks" / "scene_render.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    args = argparse.Namespace(task="GenDex/PutAppleBowl-v1", styles=["kitchen"], repeats=1, frames=1, sensor_px=32,
                              pairs=1, components=False, argv=[])
    record = bench.run(args)
    times = record["render_time"]["median"]["view_s"]
    assert set(times) == {"none", "kitchen"} and all(t > 0 for t in times.values())
    on, off = record["difference"]["kitchen/on"][0], record["difference"]["kitchen/off"][0]
    assert all(v == 0.0 for v in off["mad"].values()) and all(v > 5.0 for v in on["mad"].values()), record
