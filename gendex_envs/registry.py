"""Task registry: every task version ``<Name>/v<N>/`` under the task roots is the Gymnasium id ``GenDex/<Name>-v<N>``.

:func:`register_tasks` runs once when :mod:`gendex_envs` is imported. Task roots are the folders listed in
``$GENDEX_TASKS_PATH`` (``os.pathsep``-separated), then the repository's ``generated_tasks/``; the first root that
has a version wins, except that a committed id (a version in ``generated_tasks/``) keeps its committed folder: a
folder elsewhere that would replace it is refused with a warning unless ``GENDEX_ALLOW_OVERRIDE=1`` (or, from code,
``register_tasks(roots, override=True)``). A folder that cannot be registered (a missing root, a spec file that is
not a file, a spec that does not load) is reported and skipped; the others register, so one bad folder never hides
the library. Every version is registered, and an unversioned name resolves as Gymnasium resolves it:
``gym.make("GenDex/PutAppleBowl")`` makes the highest version (with Gymnasium's warning), and
:func:`resolve_task` does the same for GenDex's own commands.

Each registered spec carries the task's ``max_episode_steps`` (``gym.spec(id).max_episode_steps``), so Gymnasium
applies the time limit and ``gym.make(id, max_episode_steps=N)`` changes it. The entry point builds the bare
:class:`~gendex_envs.task_env.TaskEnv`; :class:`~gendex_envs.wrappers.GymApi` is applied last: the plain numpy
Gymnasium API for one CPU env, ManiSkill's batched torch API otherwise. ``env.unwrapped`` is the ``TaskEnv`` (a
ManiSkill env: torch tensors ``[num_envs, ...]`` even for one env). By default actions drive the whole arm and hand
with absolute joint targets (``control_mode="pd_joint_pos"``, ``control_joint="both"``), which is what
``gendex collect`` records.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import gymnasium as gym
from gymnasium.envs.registration import EnvSpec, WrapperSpec, find_highest_version, parse_env_id

from gendex_envs.errors import DuplicateTaskError, TaskNotFoundError, TaskSpecError, suggest
from gendex_envs.library import library_dir
from gendex_envs.spec import TASK_NAME_RE
from gendex_envs.task_index import INDEX_NAME, load_index, spec_digest
from gendex_envs.task_version import NAMESPACE, TaskVersion, versions_in

log = logging.getLogger(__name__)

TASKS_PATH_ENV = "GENDEX_TASKS_PATH"
ALLOW_OVERRIDE_ENV = "GENDEX_ALLOW_OVERRIDE"
"""``GENDEX_ALLOW_OVERRIDE=1``: folders on ``$GENDEX_TASKS_PATH`` may replace committed task ids (read as
``GENDEX_TRUST_REMOTE_CODE`` is: 1, true or yes)."""
REPO_TASKS_DIR = library_dir("generated_tasks")
"""The committed library: the checkout's ``generated_tasks/``, or the one an installed wheel ships
(:mod:`gendex_envs.library`)."""
GYM_API_WRAPPER = WrapperSpec(name="GymApi", entry_point="gendex_envs.wrappers:GymApi", kwargs={})


def override_allowed() -> bool:
    """``GENDEX_ALLOW_OVERRIDE=1``: the user lets task folders replace committed ids."""
    return os.environ.get(ALLOW_OVERRIDE_ENV, "").strip().lower() in ("1", "true", "yes")


def _env_roots() -> list[Path]:
    return [Path(p) for p in os.environ.get(TASKS_PATH_ENV, "").split(os.pathsep) if p]


def task_roots() -> list[Path]:
    """Folders searched for tasks, in priority order (``$GENDEX_TASKS_PATH`` entries that are not folders left out,
    with a warning)."""
    roots = []
    for root in _env_roots():
        if root.is_dir():
            roots.append(root)
        else:
            log.warning("ignoring %s=%s entry %s: not a folder", TASKS_PATH_ENV, os.environ.get(TASKS_PATH_ENV), root)
    if REPO_TASKS_DIR.is_dir():
        roots.append(REPO_TASKS_DIR)
    return roots


def _is_committed_root(root: Path) -> bool:
    try:
        return root.resolve() == REPO_TASKS_DIR.resolve()
    except OSError:
        return False


def committed_ids() -> set[str]:
    """Ids of the committed task versions (``generated_tasks/<Name>/v<N>/`` holding a spec), by folder
    names only."""
    if not REPO_TASKS_DIR.is_dir():
        return set()
    return {v.env_id for v in versions_in(REPO_TASKS_DIR)}


def committed_version(env_id: str) -> TaskVersion | None:
    """The committed version (``generated_tasks/<Name>/v<N>``) of ``env_id``, whatever is registered under that id
    in this process; None when the repository holds no such version."""
    try:
        ns, name, version = parse_env_id(env_id)
    except gym.error.Error:
        return None
    if ns != NAMESPACE or version is None or not TASK_NAME_RE.fullmatch(name or ""):
        return None
    folder = REPO_TASKS_DIR / name / f"v{version}"
    try:
        return TaskVersion.at(folder)
    except TaskNotFoundError:
        return None


def discover_tasks(roots: list[Path] | None = None, override: bool | None = None) -> dict[str, TaskVersion]:
    """Every task version in ``roots`` (default :func:`task_roots`): env id -> version; the first root wins.

    A version outside ``generated_tasks/`` whose id, or whose task name, is a committed one is refused (logged,
    skipped: the committed versions keep the id and the unversioned name) unless ``override`` (None:
    ``GENDEX_ALLOW_OVERRIDE``). Roots given explicitly must be
    folders (:class:`TaskNotFoundError`)."""
    override = override_allowed() if override is None else override
    committed: set[str] | None = None
    committed_names: set[str] = set()
    found: dict[str, TaskVersion] = {}
    for root in task_roots() if roots is None else roots:
        if not root.is_dir():
            raise TaskNotFoundError(f"task root {root} is not a folder (from ${TASKS_PATH_ENV} or the repository)")
        own = _is_committed_root(root)
        for version in versions_in(root):
            if version.env_id in found:
                log.info("%s in %s is shadowed by %s", version.env_id, version.root, found[version.env_id].root)
                continue
            if not own and not override:
                if committed is None:
                    committed = committed_ids()
                    committed_names = {i.split("/", 1)[1].rsplit("-v", 1)[0] for i in committed}
                if version.env_id in committed:
                    log.warning("refusing %s from %s: it would replace the committed task %s; set %s=1 (or call "
                                "register_tasks(roots, override=True)) to use it instead", version.env_id,
                                version.root, REPO_TASKS_DIR / version.name / f"v{version.version}",
                                ALLOW_OVERRIDE_ENV)
                    continue
                if version.name in committed_names:
                    # a new version of a committed name would become what GenDex/<Name> and resolve_task pick
                    log.warning("refusing %s from %s: %s is a committed task's name, whose versions are the "
                                "repository's; set %s=1 (or call register_tasks(roots, override=True)) to add one",
                                version.env_id, version.root, version.name, ALLOW_OVERRIDE_ENV)
                    continue
            found[version.env_id] = version
    return found


_REGISTERED: dict[str, TaskVersion] = {}


def env_spec(version: TaskVersion, max_episode_steps: int | None = None) -> EnvSpec:
    """The Gymnasium spec ``version`` is registered under (``max_episode_steps``: the spec's own when None);
    ``gym.make`` takes it directly, so a folder that is not registered (or one whose id the library holds) can be
    made without replacing anything in the registry."""
    steps = version.load_spec_unchecked().max_episode_steps if max_episode_steps is None else max_episode_steps
    return EnvSpec(id=version.env_id, entry_point="gendex_envs.registry:make_task_env", max_episode_steps=steps,
                   kwargs={"task": str(version.root)}, disable_env_checker=True,
                   additional_wrappers=(GYM_API_WRAPPER,))


def register_tasks(roots: list[Path] | None = None, override: bool = False) -> list[str]:
    """Register every discovered task version with Gymnasium; returns the new ids.

    Re-registering an id that points at the same folder is a no-op; a different folder raises
    :class:`DuplicateTaskError` unless ``override``. A folder that would replace a committed id is refused (logged,
    skipped) unless ``override`` or ``GENDEX_ALLOW_OVERRIDE=1``. A version that cannot be registered (its spec does
    not load, whatever the error) is logged and skipped (one broken folder must not hide every other task); making it
    names the problem.
    """
    new = []
    indexes: dict[Path, list] = {}
    unversioned = {s.name for s in gym.registry.values() if s.namespace == NAMESPACE and s.version is None}
    for env_id, version in discover_tasks(roots, override=True if override else None).items():
        if env_id in gym.registry:
            previous = _REGISTERED.get(env_id)
            if previous is not None and previous.root == version.root:
                continue
            if not override:
                where = previous.root if previous else "another package"
                raise DuplicateTaskError(f"{env_id} from {version.root} is already registered by {where}; "
                                         "pass override=True to replace it")
            del gym.registry[env_id]
        try:
            steps = _time_limit(version, indexes)
            if version.name in unversioned:
                raise gym.error.RegistrationError(f"can't register {env_id}: the unversioned {NAMESPACE}/"
                                                  f"{version.name} is registered")
            # what gym.register does for a versioned id, without its scan of the whole registry per call (quadratic
            # in the library: 1.5 s of registering 2 000 versions); the one conflict it checks is checked above
            gym.registry[env_id] = env_spec(version, steps)
        except TaskSpecError as exc:
            log.error("not registering %s: %s", env_id, exc)
            continue
        except Exception as exc:  # any failure of one untrusted folder: report it, register the rest
            log.error("not registering %s from %s: %s: %s", env_id, version.root, type(exc).__name__,
                      str(exc)[:500])
            continue
        _REGISTERED[env_id] = version
        new.append(env_id)
    stale = {root: n for root, (_, n) in indexes.items() if n}
    for root, n in stale.items():
        log.warning("%d version(s) in %s are not in its %s or changed since; their specs were parsed: run "
                    "`gendex store index %s` to renew it", n, root, INDEX_NAME, root)
    return new


def _time_limit(version: TaskVersion, indexes: dict[Path, list]) -> int:
    """``max_episode_steps`` of ``version``: from its root's index (:mod:`gendex_envs.task_index`) when the spec's
    digest matches the indexed one, else from the parsed spec (counted as stale when the root has an index)."""
    root = version.tasks_root
    if root not in indexes:
        indexes[root] = [load_index(root), 0]
    index = indexes[root][0]
    if index is not None:
        entry = index.get(f"{version.name}/v{version.version}")
        if entry is not None and spec_digest(version.files.spec) == entry.spec_sha256:
            return entry.max_episode_steps
        indexes[root][1] += 1
    return version.load_spec_unchecked().max_episode_steps


def unregister_tasks(env_ids: list[str]) -> None:
    """Remove GenDex task ids from Gymnasium's registry (tasks registered for a while, e.g. a scratch root)."""
    for env_id in env_ids:
        if env_id in _REGISTERED:
            del _REGISTERED[env_id]
            gym.registry.pop(env_id, None)


def registered_tasks() -> dict[str, TaskVersion]:
    """Env id -> version of every task registered by GenDex in this process."""
    return dict(_REGISTERED)


REFERENCE_TASKS = ("OpenCabinet", "PickUpBottle", "PutAppleBowl")
"""The GenDexHand paper's three reference tasks, by name: :func:`resolve_task` gives each one's highest version."""


def resolve_task(task: str | Path) -> TaskVersion:
    """The task version named by ``task``: a registered id (``GenDex/PutAppleBowl-v0``), an unversioned name
    (``GenDex/PutAppleBowl`` or ``PutAppleBowl``: the highest registered version, as ``gym.make`` picks it), or a
    version folder. :class:`TaskNotFoundError` with suggestions otherwise."""
    text = str(task)
    if text in _REGISTERED:
        return _REGISTERED[text]
    if Path(text).is_dir():
        return TaskVersion.at(text)
    ns, name, version = parse_env_id(text if "/" in text else f"{NAMESPACE}/{text}")
    if ns == NAMESPACE and version is None:
        latest = find_highest_version(ns, name)
        if latest is not None and f"{ns}/{name}-v{latest}" in _REGISTERED:
            return _REGISTERED[f"{ns}/{name}-v{latest}"]
    raise TaskNotFoundError(f"no GenDex task {text!r}.{suggest(text, _REGISTERED)} "
                            f"Registered: {', '.join(sorted(_REGISTERED)) or 'none'}")


HISTORY_FREE = {"reconfiguration_freq": 1}
"""``gym.make`` keyword arguments under which an episode depends only on (task version, seed, actions): every
reset rebuilds the physics scene. PhysX keeps contact caches and solver warm starts of a scene across resets, so in
a reused scene an episode differs slightly (up to 2e-4 in the flat state after 60 steps, measured) with what ran
before it; a rebuilt scene is the same in any process, whatever ran there (about 0.4-1 s per reset). Collections,
datasets, the solvability gate and evaluation make their envs with these; training keeps the faster default."""


def make_task_env(task: str | Path | TaskVersion, num_envs: int = 1, **kwargs):
    """Gymnasium entry point: the bare :class:`~gendex_envs.task_env.TaskEnv` of ``task`` (a version or its folder).

    Without CUDA the renderer runs on the Vulkan CPU device directly (ManiSkill would warn, then do the same)."""
    from gendex_envs.task_env import TaskEnv

    if "render_backend" not in kwargs:
        import torch

        kwargs["render_backend"] = "gpu" if torch.cuda.is_available() else "cpu"
    return TaskEnv(task=task, num_envs=num_envs, **kwargs)


def make_env(task: str | Path | TaskVersion, *, max_episode_steps: int | None = None, **kwargs) -> gym.Env:
    """``gym.make`` for a task version that need not be registered: the same wrappers, the same defaults.

    ``max_episode_steps``: None for the task's own limit, -1 for none."""
    from gendex_envs.wrappers import GymApi

    version = task if isinstance(task, TaskVersion) else TaskVersion.at(task)
    env = make_task_env(version, **kwargs)
    steps = version.spec.max_episode_steps if max_episode_steps is None else max_episode_steps
    if steps != -1:
        if steps < 1:
            raise TaskSpecError(f"max_episode_steps={steps} must be >= 1 (or -1 for no limit)")
        env = gym.wrappers.TimeLimit(env, steps)
    return GymApi(env)
