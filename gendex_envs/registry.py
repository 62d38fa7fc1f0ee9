"""Task registry: ``generated_tasks/<Name>/v<N>/`` folders become Gymnasium IDs ``GenDex/<Name>-v<N>``.

:func:`register_tasks` is called once when :mod:`gendex_envs` is imported. Task folders are searched in the roots
listed in ``$GENDEX_TASKS_PATH`` (``os.pathsep``-separated) and then in the repository's ``generated_tasks/``.

``gym.make("GenDex/PutAppleBowl-v0")`` with one CPU env returns a standard Gymnasium env (numpy arrays, no batch
dimension: ManiSkill's ``CPUGymWrapper``). With ``num_envs > 1`` (or the GPU backend) it returns the batched
ManiSkill env (torch tensors ``[num_envs, ...]``). ``env.unwrapped`` is the :class:`~gendex_envs.task_env.TaskEnv`
either way.
"""

from __future__ import annotations

import logging
import os
import re
from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym

from gendex_envs.errors import DuplicateTaskError, TaskNotFoundError, TaskSpecError, suggest

log = logging.getLogger(__name__)

NAMESPACE = "GenDex"
TASKS_PATH_ENV = "GENDEX_TASKS_PATH"
REPO_TASKS_DIR = Path(__file__).resolve().parent.parent / "generated_tasks"
_VERSION_DIR = re.compile(r"^v(\d+)$")


@dataclass(frozen=True)
class TaskEntry:
    """One registered task version."""

    env_id: str
    name: str
    version: int
    task_dir: Path


def task_roots() -> list[Path]:
    """Folders searched for tasks, in priority order."""
    roots = [Path(p) for p in os.environ.get(TASKS_PATH_ENV, "").split(os.pathsep) if p]
    if REPO_TASKS_DIR.is_dir():
        roots.append(REPO_TASKS_DIR)
    return roots


def discover_tasks(roots: list[Path] | None = None) -> dict[str, TaskEntry]:
    """Find every ``<root>/<Name>/v<N>/task.yaml``; returns env id -> entry (first root wins on duplicates)."""
    found: dict[str, TaskEntry] = {}
    for root in task_roots() if roots is None else roots:
        if not root.is_dir():
            raise TaskNotFoundError(f"task root {root} is not a folder (from ${TASKS_PATH_ENV} or the repository)")
        for task_yaml in sorted(root.glob("*/v*/task.yaml")):
            version_dir = task_yaml.parent
            m = _VERSION_DIR.match(version_dir.name)
            if m is None:
                log.warning("ignoring %s: version folders are named v<N>", version_dir)
                continue
            name = version_dir.parent.name
            env_id = f"{NAMESPACE}/{name}-v{int(m.group(1))}"
            if env_id in found:
                log.info("%s in %s is shadowed by %s", env_id, version_dir, found[env_id].task_dir)
                continue
            found[env_id] = TaskEntry(env_id, name, int(m.group(1)), version_dir)
    return found


_REGISTERED: dict[str, TaskEntry] = {}


def register_tasks(roots: list[Path] | None = None, override: bool = False) -> list[str]:
    """Register every discovered task with Gymnasium; returns the new IDs.

    Re-registering an ID that points at the same folder is a no-op; a different folder raises
    :class:`DuplicateTaskError` unless ``override``.
    """
    new = []
    for env_id, entry in discover_tasks(roots).items():
        if env_id in gym.registry:
            previous = _REGISTERED.get(env_id)
            if previous is not None and previous.task_dir == entry.task_dir:
                continue
            if not override:
                where = previous.task_dir if previous else "another package"
                raise DuplicateTaskError(f"{env_id} from {entry.task_dir} is already registered by {where}; "
                                         "pass override=True to replace it")
            del gym.registry[env_id]
        gym.register(id=env_id, entry_point="gendex_envs.registry:make_task_env",
                     kwargs={"task_dir": str(entry.task_dir)}, disable_env_checker=True)
        _REGISTERED[env_id] = entry
        new.append(env_id)
    return new


def registered_tasks() -> dict[str, TaskEntry]:
    """Env id -> entry of every task registered by GenDex in this process."""
    return dict(_REGISTERED)


def task_entry(env_id: str) -> TaskEntry:
    """Look up a registered task by id; :class:`TaskNotFoundError` with suggestions."""
    try:
        return _REGISTERED[env_id]
    except KeyError:
        raise TaskNotFoundError(f"no GenDex task {env_id!r}.{suggest(env_id, _REGISTERED)} "
                                f"Registered: {', '.join(sorted(_REGISTERED)) or 'none'}") from None


def make_task_env(task_dir: str, num_envs: int = 1, max_episode_steps: int | None = None,
                  gym_api: bool | None = None, **kwargs) -> gym.Env:
    """Build a task env. ``gym_api`` (default: one CPU env) wraps it as a plain numpy Gymnasium env."""
    from mani_skill.utils.registration import TimeLimitWrapper  # noqa: PLC0415
    from mani_skill.utils.wrappers.gymnasium import CPUGymWrapper  # noqa: PLC0415

    from gendex_envs.task_env import TaskEnv  # noqa: PLC0415  (heavy: sapien + torch)

    if not (Path(task_dir) / "task.yaml").is_file():
        raise TaskNotFoundError(f"{task_dir} holds no task.yaml")
    if "render_backend" not in kwargs:
        import torch  # noqa: PLC0415

        # without CUDA, render on the Vulkan CPU device directly (ManiSkill would warn, then do the same)
        kwargs["render_backend"] = "gpu" if torch.cuda.is_available() else "cpu"
    env = TaskEnv(task_dir=task_dir, num_envs=num_envs, **kwargs)
    if max_episode_steps is not None:
        steps = max_episode_steps
    else:  # a stage env lasts the stage's horizon
        steps = env.stage_spec.horizon if env.stage_spec is not None else env.task_spec.max_episode_steps
    if steps < 1:
        raise TaskSpecError(f"max_episode_steps={steps} must be >= 1")
    wrapped: gym.Env = TimeLimitWrapper(env, max_episode_steps=steps)
    if gym_api is None:
        gym_api = num_envs == 1 and not env.gpu_sim_enabled
    if gym_api:
        wrapped = CPUGymWrapper(wrapped)
    return wrapped
