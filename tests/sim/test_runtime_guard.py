"""The runtime guard (gendex_envs.guard): reward code from a folder that is not the repository's cannot spawn
processes, reach the network, write or read files or load ctypes, even long after the probe window; the user's
own code in the same process keeps its rights; ``trust_remote_code`` lifts the hook; restricted builtins apply
to every module.

Audit hooks cannot be removed, so each case runs in a fresh interpreter."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

# The hostile part runs only when the first action component is exactly 1.0, which the script sends from step 30
# on (after any probe's 20 steps): reward code cannot read the step count (info has no elapsed_steps) and keeps no
# state, so the test chooses the step.
HOSTILE = '''
import torch
from gendex_envs import reward_terms as rt


def evaluate(env):
    return {{"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device),
             "h": env.obj_height("apple")}}


def compute_dense_reward(env, obs, action, info):
    if bool((action[:, 0] == 1.0).any()):
{attack}
    return rt.reach(torch.linalg.norm(env.palm_pose.p - env.obj_pose("apple").p, dim=-1))
'''

ATTACKS = {
    # builtins the module never had: fails in restricted builtins, trusted or not
    "open": ("open('{marker}', 'w').write('x')", "NameError"),
    "import_os": ("import os\nos.system('touch {marker}')", "may not import 'os'"),
    "getattr_dunder": ("getattr(env, '__class__')", "public attributes only"),
    # reward code's torch is a copy without what saves, loads or downloads
    "torch_save": ("torch.save(env.palm_pose.p, '{marker}')", "may not use torch.save"),
    "torch_load": ("torch.load('/etc/hostname')", "may not use torch.load"),
    # what reaches a file through a library call the copy keeps: the audit hook
    "numpy_dump": ("env.palm_pose.p.numpy().dump('{marker}')", "may not import 'numpy"),
    "torch_hub": ("torch.hub.list('pytorch/vision')", "may not use torch.hub"),
    "rt_torch": ("rt.torch.save(env.palm_pose.p, '{marker}')", "may not use gendex_envs.reward_terms.torch"),
}

SCRIPT = '''
import json, sys, numpy as np, torch
import gendex_envs.reward_module
from gendex_envs.task_env import TaskEnv
from gendex_envs import guard
if sys.argv[4] == "skip-static-check":  # to reach the runtime fences, as code that got past the check would
    gendex_envs.reward_module.check_reward_source = lambda *args: None
out = {"steps": 0, "error": None}
try:
    env = TaskEnv(task=sys.argv[1], obs_mode="state", control_mode="pd_joint_delta_pos", render_backend="none",
              trust_remote_code=sys.argv[2] == "trust")
    env.reset(seed=0)
    out["made"] = True
    for step in range(1, 41):
        action = torch.zeros(env.action_space.shape)
        action[..., 0] = 1.0 if step >= 30 else 0.0
        env.step(action)
        out["steps"] += 1
except Exception as e:
    out["error"] = type(e).__name__ + ": " + str(e)
out["untrusted"] = list(guard.untrusted_folders())
# the user's own code keeps its rights in the same process
with open(sys.argv[3], "w") as f:
    f.write("user")
out["user_wrote"] = True
print("RESULT " + json.dumps(out))
'''


def _task(task_copy, tmp_path: Path, name: str, attack: str) -> Path:
    version = task_copy("PutAppleBowl", as_name=name, register=False)
    body = textwrap.indent(attack, " " * 8)
    version.files.reward.write_text(HOSTILE.format(attack=body))
    for module in version.files.stage_rewards.glob("*.py"):
        module.unlink()  # the task's module judges every stage
    return version.root


def _result(proc: subprocess.CompletedProcess) -> dict:
    """The JSON a child script printed after ``RESULT ``."""
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT ")), None)
    assert line, proc.stdout[-2000:] + proc.stderr[-3000:]
    return json.loads(line[7:])


def _run(folder: Path, tmp_path: Path, trust: bool = False, static_check: bool = False) -> dict:
    user_file = tmp_path / "user.txt"
    proc = subprocess.run([sys.executable, "-c", SCRIPT, str(folder), "trust" if trust else "no", str(user_file),
                           "static-check" if static_check else "skip-static-check"],
                          capture_output=True, text=True, timeout=600, cwd=REPO)
    out = _result(proc)
    assert user_file.read_text() == "user" and out["user_wrote"]
    return out


DEFAULT_CASES = ("open", "torch_save", "numpy_dump", "rt_torch")
"""One deferred case per fence in the default suite (restricted builtins, reward code's torch copy, the audit hook,
a module's torch reached through another); every case under --slow (each is an interpreter of its own)."""


@pytest.mark.parametrize("case", [c if c in DEFAULT_CASES else pytest.param(c, marks=pytest.mark.slow)
                                  for c in sorted(ATTACKS)])
def test_deferred_hostile_reward_code_is_stopped_when_it_acts(task_copy, tmp_path, case):
    attack, reason = ATTACKS[case]
    marker = tmp_path / "pwned"
    folder = _task(task_copy, tmp_path, f"Guard{case.title().replace('_', '')}", attack.format(marker=marker))
    out = _run(folder, tmp_path)  # as if the static check had been bypassed
    assert out["steps"] == 29, out  # 29 normal steps; the 30th (elapsed_steps 30) attacked and was stopped
    assert out["error"] and any(r in out["error"] for r in reason.split("|")), out["error"]
    assert not marker.exists()
    assert any(str(folder) in f for f in out["untrusted"])


STATIC_SCRIPT = '''
import json, sys
from gendex_envs.task_env import TaskEnv
out = {}
for folder in json.loads(sys.argv[1]):
    try:
        TaskEnv(task=folder, obs_mode="state", control_mode="pd_joint_delta_pos", render_backend="none")
        out[folder] = "made"
    except Exception as e:
        out[folder] = type(e).__name__ + ": " + str(e)
print("RESULT " + json.dumps(out))
'''


def test_untrusted_hostile_modules_are_rejected_when_the_env_is_made(task_copy, tmp_path):
    """With the static check in place (the default), none of them gets to run a step: the env is not made. (Nothing
    of theirs runs, so one interpreter tries them all.)"""
    folders = {}
    for case, (attack, _) in sorted(ATTACKS.items()):
        marker = tmp_path / f"pwned_{case}"
        folders[case] = (str(_task(task_copy, tmp_path, f"Static{case.title().replace('_', '')}",
                                   attack.format(marker=marker))), marker)
    proc = subprocess.run([sys.executable, "-c", STATIC_SCRIPT, json.dumps([f for f, _ in folders.values()])],
                          capture_output=True, text=True, timeout=600, cwd=REPO)
    out = _result(proc)
    for case, (folder, marker) in folders.items():
        error = out[folder]
        assert error.startswith("RewardModuleError") and "static check rejected" in error and "was rejected" in \
            error, (case, error)
        assert not marker.exists()


def test_trust_remote_code_runs_the_folder_as_written(task_copy, tmp_path):
    marker = tmp_path / "saved.pt"
    folder = _task(task_copy, tmp_path, "GuardTrusted", f"torch.save(env.palm_pose.p, '{marker}')")
    out = _run(folder, tmp_path, trust=True)
    assert out["error"] is None and out["steps"] == 40 and marker.exists() and out["untrusted"] == []


def test_committed_tasks_are_trusted_and_other_folders_are_not(tmp_path, monkeypatch):
    from gendex_envs import guard
    from gendex_envs.registry import REPO_TASKS_DIR

    monkeypatch.delenv(guard.TRUST_ENV, raising=False)
    assert guard.is_trusted(REPO_TASKS_DIR / "PutAppleBowl" / "v1" / "reward.py")
    assert not guard.is_trusted(tmp_path / "PutAppleBowl" / "v1" / "reward.py")
    monkeypatch.setenv(guard.TRUST_ENV, "1")
    assert guard.is_trusted(tmp_path / "PutAppleBowl" / "v1" / "reward.py")


HOOK_MODULE = '''
import os, socket, subprocess, ctypes


def write(path):
    with open(path, "w") as f:
        f.write("x")


def read(path):
    with open(path) as f:
        return f.read()


def spawn():
    subprocess.run(["true"])


def shell():
    os.system("true")


def connect():
    socket.socket()


def load_c():
    ctypes.CDLL(None)


def listdir(path):
    return os.listdir(path)


def call(fn, *args):  # untrusted code calling trusted code: still judged
    return fn(*args)
'''

HOOK_SCRIPT = '''
import importlib.util, json, os, sys
from pathlib import Path
from gendex_envs import guard
folder = Path(sys.argv[1])
guard.untrust(folder)
spec = importlib.util.spec_from_file_location("hostile_lib", folder / "hostile_lib.py")
mod = importlib.util.module_from_spec(spec)
spec.loader.exec_module(mod)   # ordinary builtins: as if the restricted ones had been escaped
target = sys.argv[2]
cases = {"write": (mod.write, target + ".w"), "read": (mod.read, "/etc/hostname"), "spawn": (mod.spawn,),
         "shell": (mod.shell,), "connect": (mod.connect,), "load_c": (mod.load_c,),
         "listdir": (mod.listdir, "/"), "write_via_trusted": (mod.call, Path.write_text, Path(target + ".t"), "x")}
out = {}
for name, (fn, *args) in cases.items():
    try:
        fn(*args)
        out[name] = "allowed"
    except guard.UntrustedCodeError as e:
        out[name] = str(e)
# the same things from the user's own code
Path(target + ".user").write_text("user")
out["user_read"] = len(Path("/etc/hostname").read_text()) > 0
out["user_listdir"] = len(os.listdir("/")) > 0
print("RESULT " + json.dumps(out))
'''


def test_the_audit_hook_refuses_what_untrusted_code_does_and_allows_the_rest_of_the_process(tmp_path):
    folder = tmp_path / "lib"
    folder.mkdir()
    (folder / "hostile_lib.py").write_text(HOOK_MODULE)
    target = str(tmp_path / "out")
    proc = subprocess.run([sys.executable, "-c", HOOK_SCRIPT, str(folder), target], capture_output=True, text=True,
                          timeout=300, cwd=REPO)
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT ")), None)
    assert line, proc.stdout[-2000:] + proc.stderr[-3000:]
    out = json.loads(line[7:])
    reasons = {"write": "writing files", "read": "reading files", "spawn": "starting processes",
               "shell": "starting processes", "connect": "network access", "load_c": "ctypes",
               "write_via_trusted": "writing files", "listdir": "listing folders"}
    for case, why in reasons.items():
        assert why in out[case] and "hostile_lib.py" in out[case], (case, out[case])
    assert not any(Path(target + s).exists() for s in (".w", ".t"))
    assert Path(target + ".user").read_text() == "user" and out["user_read"] and out["user_listdir"]


@pytest.mark.parametrize("name", ["PutAppleBowl", "OpenCabinet", "RotateTennisBall", "PushBlockToGoal"])
def test_a_committed_task_copied_elsewhere_runs_guarded_with_the_same_rewards(task_copy, task_version, name):
    """Untrusted (a copy outside the repository: static check, restricted builtins, module copies, audit hook) and
    trusted runs of the same modules give the same rewards and success, step for step."""
    import numpy as np
    import torch

    from gendex_envs.task_env import TaskEnv

    def rollout(version):
        env = TaskEnv(task=version, obs_mode="state", control_mode="pd_joint_delta_pos", render_backend="none")
        try:
            env.reset(seed=5)
            rng = np.random.default_rng(1)
            out = []
            for _ in range(15):
                _, reward, _, _, info = env.step(torch.as_tensor(rng.uniform(-1, 1, env.action_space.shape),
                                                                 dtype=torch.float32))
                out.append((reward.clone(), info["success"].clone()))
            return out
        finally:
            env.close()

    from gendex_envs import guard

    original = task_version(name)
    copy = task_copy(name, as_name=f"Guarded{name}", register=False)
    assert guard.is_trusted(original.files.reward) and not guard.is_trusted(copy.files.reward)
    for (r1, s1), (r2, s2) in zip(rollout(original), rollout(copy), strict=True):
        assert torch.equal(r1, r2) and torch.equal(s1, s2)
    assert any(str(copy.root) in f for f in guard.untrusted_folders())


def _load_untrusted_in_a_child(paths: list[str]) -> int:
    script = textwrap.dedent('''
        import json, sys
        from gendex_envs.reward_module import load_reward_module
        paths = json.loads(sys.stdin.read())
        for p in paths:
            load_reward_module(p, trusted=False)
        print("LOADED", len(paths))
    ''')
    proc = subprocess.run([sys.executable, "-c", script], input=json.dumps(paths), capture_output=True, text=True,
                          timeout=600, cwd=REPO)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return int(proc.stdout.split("LOADED")[1])


def test_the_sampled_versions_reward_modules_load_as_untrusted_code(library_sample):
    """Each passes the static check and imports with the restricted builtins and module copies: the versions
    :func:`gendex.check.ci_selection` picks (changed, newest reference, a fixed sample), so the default suite's cost
    does not grow with the library."""
    from gendex_envs.registry import registered_tasks

    versions = registered_tasks()
    paths = [str(p) for i in library_sample for p in versions[i].files.reward_modules()]
    assert len(paths) >= len(library_sample)
    assert _load_untrusted_in_a_child(paths) == len(paths)


@pytest.mark.slow
def test_every_committed_reward_module_loads_as_untrusted_code():
    from gendex_envs.registry import REPO_TASKS_DIR
    from gendex_envs.task_version import versions_in

    paths = [str(p) for v in versions_in(REPO_TASKS_DIR) for p in v.files.reward_modules()]
    assert _load_untrusted_in_a_child(paths) == len(paths) >= 300
