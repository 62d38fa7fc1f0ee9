"""Build the gendex wheel from this checkout, install it into a fresh venv and use it from another folder.

    .venv/bin/python scripts/check_wheel.py [--ids N] [--seed S] [--keep]

What it proves (issue 44, "installable tasks"): with no checkout on the path, ``import gendex_envs`` registers as
many ``GenDex/`` ids as the checkout does, from the library shipped in the wheel; ``gym.make`` + reset + 10 steps
works on N random ids; ``gendex list`` lists them all; suites, dataset manifests and prompts load; the shipped trust
record trusts the shipped reward modules, while a folder on ``$GENDEX_TASKS_PATH`` registers, is untrusted, and
cannot take a shipped id. It also reports how many task versions' file digests (what suites and leaderboard results
pin) differ from the checkout's (none should: ``TaskVersion.file_digest`` leaves out the ``__pycache__`` folders
that ``pip install`` writes beside every shipped ``.py`` file, and stored files, :mod:`gendex_envs.task_store`, ship
in the library's store).

How, without downloading torch and ManiSkill again: the wheel is built (``pip wheel --no-deps
--no-build-isolation``) from an export of the work tree (the files git tracks, as they are now, plus new files git
does not ignore outside the library folders), so no stale ``build/`` folder and no untracked draft leaks into it.
The fresh venv (``python -m venv --without-pip``, no ``--system-site-packages``) sees the dependencies through a
folder of links to every entry of this interpreter's site-packages except gendex's own (its dist-info and the
editable install's finder and ``.pth``), added with ``site.addsitedir``; ``pip install --no-index`` of the wheel (pip
itself from those links) then resolves every declared dependency from it, and downloads nothing. The checks run
with the venv's interpreter in an empty folder, without ``PYTHONPATH`` or ``GENDEX_*`` variables, and fail unless
``gendex_envs``, ``gendex``, ``generator`` and the library resolve inside the venv.

Prints a JSON summary (counts, wheel size, timings) as its last line; exit status 1 when a check fails.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
LIBRARY_FOLDERS = ("generated_tasks", "suites", "datasets", "prompts")
OWN_ENTRIES = ("gendex", "gendex_envs", "generator", "gendex_data")

CHECKOUT = ("import json, gymnasium as gym, gendex_envs\n"
            "from gendex_envs.registry import REPO_TASKS_DIR, discover_tasks\n"
            "print(json.dumps({'count': len([i for i in gym.registry if i.startswith('GenDex/')]),\n"
            "  'digests': {i: v.file_digest() for i, v in discover_tasks([REPO_TASKS_DIR]).items()}}))\n")

INSTALLED_CHECK = r'''
import json, os, random, shutil, sys, sysconfig, tempfile, time
from pathlib import Path

t0 = time.perf_counter()
import gymnasium as gym
import gendex_envs
import_s = time.perf_counter() - t0
import gendex, generator
from gendex_envs import guard, library, registry, trust_record
from gendex_envs.task_version import TaskLayout
from gendex.data.datasets import DATASETS_DIR, load_manifest
from gendex.eval.suite import SUITES_DIR, load_suite
from generator.prompts import PROMPTS_DIR, load_manifest as load_prompts

site = Path(sysconfig.get_paths()["purelib"]).resolve()
where = {m.__name__: str(Path(m.__file__).resolve()) for m in (gendex_envs, gendex, generator)}
assert all(Path(p).is_relative_to(site) for p in where.values()), where
assert library.installed() and library.library_root() == site / "gendex_data", library.library_root()
for d in (registry.REPO_TASKS_DIR, SUITES_DIR, DATASETS_DIR, PROMPTS_DIR):
    assert d.is_dir() and d.resolve().is_relative_to(site), d
ids = sorted(i for i in gym.registry if i.startswith("GenDex/"))
suites = sorted(p.stem for p in SUITES_DIR.glob("*.yaml"))
for s in suites:
    load_suite(s)
manifests = sorted(p.stem for p in DATASETS_DIR.glob("*.yaml"))
for m in manifests:
    load_manifest(m)
prompts = sorted(load_prompts())

# trust: the shipped record trusts the shipped reward modules (and nothing is trusted wholesale)
status = trust_record.trust_status()
assert status.clean, status
rewards = [TaskLayout(v.root).reward for v in registry.discover_tasks([registry.REPO_TASKS_DIR]).values()]
assert rewards and all(guard.is_trusted(p) for p in rewards)
assert not guard.trusts_everything()

# a user's folder on GENDEX_TASKS_PATH: registers, is untrusted, and cannot take a shipped id or name
user = Path(tempfile.mkdtemp())
src = registry.REPO_TASKS_DIR / "PutAppleBowl" / "v1"
mine = user / "MyAppleBowl" / "v0"
shutil.copytree(src, mine, ignore=shutil.ignore_patterns("__pycache__"))
spec = TaskLayout(mine).spec
spec.write_text(spec.read_text().replace("name: PutAppleBowl\n", "name: MyAppleBowl\n"))
shutil.copytree(src, user / "PutAppleBowl" / "v1", ignore=shutil.ignore_patterns("__pycache__"))
found = registry.discover_tasks([user, registry.REPO_TASKS_DIR])
assert found["GenDex/MyAppleBowl-v0"].root == mine, found["GenDex/MyAppleBowl-v0"].root
assert found["GenDex/PutAppleBowl-v1"].root == src, "a user folder took a shipped id"
assert not guard.is_trusted(TaskLayout(mine).reward)
assert not guard.is_trusted(TaskLayout(user / "PutAppleBowl" / "v1").reward)
shutil.rmtree(user)

digests = {i: v.file_digest() for i, v in registry.discover_tasks([registry.REPO_TASKS_DIR]).items()}
pycache = sum(1 for _ in registry.REPO_TASKS_DIR.rglob("__pycache__"))  # pip compiled the shipped .py files

rng = random.Random(int(sys.argv[2]))
picked = rng.sample(ids, int(sys.argv[1]))
steps = {}
for env_id in picked:
    t = time.perf_counter()
    env = gym.make(env_id)
    env.reset(seed=0)
    for _ in range(10):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    env.close()
    steps[env_id] = round(time.perf_counter() - t, 2)
print(json.dumps({"count": len(ids), "import_s": round(import_s, 2), "modules": where,
                  "library": str(library.library_root()), "suites": len(suites), "manifests": len(manifests),
                  "prompts": len(prompts), "trusted_rewards": len(rewards), "pycache_folders": pycache,
                  "make_and_10_steps_s": steps, "digests": digests}))
'''


def export_tree(dst: Path, repo: Path = REPO) -> list[str]:
    """Copy the work tree's files a build should see into ``dst``: what git tracks (as it is now, deleted files
    left out) and new files git does not ignore, except new files in the library folders (a wheel ships only the
    tracked library). Returns their paths, relative, with ``/``."""
    def ls(*args: str) -> list[str]:
        out = subprocess.run(["git", "ls-files", "-z", *args], cwd=repo, capture_output=True, check=True).stdout
        return [f for f in out.decode("utf-8").split("\0") if f]

    new = [f for f in ls("--others", "--exclude-standard") if f.split("/", 1)[0] not in LIBRARY_FOLDERS]
    files = sorted({f for f in ls("--cached") + new if (repo / f).is_file() and not (repo / f).is_symlink()})
    for rel in files:
        (dst / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(repo / rel, dst / rel)
    return files


def build_wheel(src: Path, out: Path, python: str = sys.executable) -> Path:
    """``pip wheel --no-deps --no-build-isolation`` of ``src`` into ``out`` (offline: the build backend is this
    interpreter's setuptools)."""
    subprocess.run([python, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index", "-q",
                    "-w", str(out), str(src)], check=True, capture_output=True)
    (wheel,) = out.glob("gendex-*.whl")
    return wheel


def _deps_farm(dst: Path) -> None:
    """Links to every entry of this interpreter's site-packages but gendex's own."""
    site = Path(sysconfig.get_paths()["purelib"])
    dst.mkdir()
    for entry in sorted(site.iterdir()):
        name = entry.name
        if name in OWN_ENTRIES or name.startswith(("gendex-", "__editable__", "__pycache__")):
            continue
        (dst / name).symlink_to(entry)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ids", type=int, default=5, help="random ids to make and step (default 5)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random pick")
    ap.add_argument("--keep", action="store_true", help="keep the temporary folder (printed)")
    args = ap.parse_args()

    tmp = Path(tempfile.mkdtemp(prefix="gendex-wheel-"))
    summary: dict = {"tmp": str(tmp)}
    try:
        t = time.perf_counter()
        summary["exported_files"] = len(export_tree(tmp / "src"))
        wheel = build_wheel(tmp / "src", tmp / "dist")
        import zipfile

        with zipfile.ZipFile(wheel) as z:
            names = z.namelist()
        summary.update(wheel=wheel.name, wheel_files=len(names), wheel_mb=round(wheel.stat().st_size / 2**20, 1),
                       library_files=sum(n.startswith("gendex_data/") for n in names),
                       build_s=round(time.perf_counter() - t, 1))
        print(f"built {wheel.name}: {len(names)} files, {summary['wheel_mb']} MiB", flush=True)

        t = time.perf_counter()
        _deps_farm(tmp / "deps")
        venv = tmp / "venv"
        subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)  # pip: the linked one
        py = str(venv / "bin" / "python")
        purelib = subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                                 capture_output=True, text=True, check=True).stdout.strip()
        Path(purelib, "_gendex_check_deps.pth").write_text(f"import site; site.addsitedir({str(tmp / 'deps')!r})\n")
        done = subprocess.run([py, "-m", "pip", "install", "--no-index", "--no-cache-dir", "-q", str(wheel)],
                              capture_output=True, text=True)
        if done.returncode:
            print(done.stdout[-3000:], done.stderr[-3000:], file=sys.stderr)
            raise SystemExit("pip install of the wheel failed")
        summary["venv_install_s"] = round(time.perf_counter() - t, 1)
        print(f"installed into {venv} (dependencies from links to {sysconfig.get_paths()['purelib']})", flush=True)

        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH" and not k.startswith("GENDEX_")}
        elsewhere = tmp / "elsewhere"
        elsewhere.mkdir()
        t = time.perf_counter()
        done = subprocess.run([py, "-c", INSTALLED_CHECK, str(args.ids), str(args.seed)], cwd=elsewhere, env=env,
                              capture_output=True, text=True)
        if done.returncode:
            print(done.stdout[-3000:], done.stderr[-5000:], file=sys.stderr)
            raise SystemExit("the installed wheel failed its checks")
        summary["installed"] = json.loads(done.stdout.strip().splitlines()[-1])
        summary["installed_check_s"] = round(time.perf_counter() - t, 1)
        done = subprocess.run([str(venv / "bin" / "gendex"), "list"], cwd=elsewhere, env=env, capture_output=True,
                              text=True)  # the console script, with every subpackage of gendex it imports
        if done.returncode:
            print(done.stderr[-3000:], file=sys.stderr)
            raise SystemExit("`gendex list` failed in the venv")
        summary["gendex_list_ids"] = sum(line.startswith("GenDex/") for line in done.stdout.splitlines())

        done = subprocess.run([sys.executable, "-c", CHECKOUT], cwd=REPO, env=env, capture_output=True, text=True,
                              check=True)
        checkout = json.loads(done.stdout.strip().splitlines()[-1])
        summary["checkout_count"] = checkout["count"]
        installed_digests = summary["installed"].pop("digests")
        summary["digests_differ"] = sorted(i for i in checkout["digests"] | installed_digests
                                           if checkout["digests"].get(i) != installed_digests.get(i))
        summary["digests_differ"] = len(summary["digests_differ"])  # reported, not failed: see the docstring
        ok = summary["installed"]["count"] == summary["checkout_count"] == summary["gendex_list_ids"]
        summary["ok"] = ok
        print(json.dumps(summary))
        return 0 if ok else 1
    finally:
        if not args.keep:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
