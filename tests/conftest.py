"""Shared fixtures. Sim tests run ManiSkill on the CPU (physx_cpu, num_envs=1).

Tests reach committed tasks only through :func:`task_version` (a registered version by name) or :func:`task_copy`
(a private copy under a scratch task root, registered for the test and unregistered after it).
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # first: it pins OpenBLAS's kernels before numpy loads; gendex_envs.blas
# isort: on

import logging
import os
from pathlib import Path

import gymnasium as gym
import pytest

import gendex_envs  # noqa: F401  (registers the GenDex tasks)
from gendex_envs.registry import register_tasks, resolve_task, unregister_tasks
from gendex_envs.task_version import NAMESPACE, TaskLayout, TaskVersion

logging.getLogger("gymnasium_robotics").setLevel(logging.ERROR)

# Tests start processes beside this one (probe and gate children, worker pools, Ray actors). With more busy processes
# than cores, OpenBLAS's spinning threads make the solver's small matrix inverses hundreds of times slower; one BLAS
# thread per process (here, and inherited by every child) keeps them fast and changes no result.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
from threadpoolctl import threadpool_limits  # noqa: E402

threadpool_limits(1)


@pytest.fixture(scope="session")
def task_version():
    """``task_version("PutAppleBowl")`` (highest version) or ``task_version("PutAppleBowl", 0)``: a committed task."""

    def get(name: str, version: int | None = None) -> TaskVersion:
        return resolve_task(name if version is None else f"{NAMESPACE}/{name}-v{version}")

    return get


@pytest.fixture
def task_copy(tmp_path):
    """``task_copy("PutAppleBowl", as_name="ScratchApple", version=3)``: a copy of a committed task version under a
    scratch task root (``tmp_path/tasks``), registered with Gymnasium; its ids are removed afterwards."""
    made: list[str] = []

    def copy(name: str, as_name: str | None = None, version: int = 0, register: bool = True) -> TaskVersion:
        source = resolve_task(name)
        new_name = as_name or name
        folder = tmp_path / "tasks" / new_name / f"v{version}"
        source.copy_to(folder)
        if new_name != source.name:
            spec = TaskLayout(folder).spec
            spec.write_text(spec.read_text().replace(f"name: {source.name}\n", f"name: {new_name}\n"))
        copied = TaskVersion.at(folder)
        if register:
            made.extend(register_tasks([folder.parent.parent], override=True))
        return copied

    yield copy
    unregister_tasks(made)


@pytest.fixture
def stage_run():
    """``stage_run(version, "lift_bottle", tmp_path / "run")``: a training run folder of ``version`` already holding
    four start states of the stage, which ``train_stage`` then uses instead of collecting the 64 ``gendex train``
    collects (40 s of a one-rollout test run; collecting them is tested on its own)."""

    def make(version: TaskVersion, stage: str, run_dir: Path, n: int = 4) -> Path:
        from gendex.train.start_states import collect_executor_states
        from gendex.train.train import open_run

        run = open_run(run_dir, version)
        collect_executor_states(version, stage, n, seed=0).states.save(run.start_states(stage))
        return run_dir

    return make


@pytest.fixture
def solved():
    """``solved(spec, seed)``: the stage executor on a task env of ``spec`` (a TaskSpec) from ``reset(seed=seed)``
    until the task succeeds, the solver stops or the episode ends; returns (succeeded, env, solver), the env closed
    when the test ends."""
    from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
    from gendex_envs.registry import HISTORY_FREE
    from gendex_envs.task_env import TaskEnv

    made = []

    def run(spec, seed: int):
        env = TaskEnv(task_spec=spec, render_backend="none", **SOLVER_ENV_KWARGS["stages"], **HISTORY_FREE)
        made.append(env)
        solver = SOLVERS["stages"]()
        obs, info = env.reset(seed=seed)
        solver.reset(env, obs)
        success = False
        while not success and (action := solver.act(env, obs)) is not None:
            obs, _, _, truncated, info = env.step(action)
            success = bool(info["success"][0])
            if bool(truncated):
                break
        return success, env, solver

    yield run
    for env in made:
        env.close()


@pytest.fixture
def make_env():
    """Factory for GenDex envs that closes every env it made when the test ends."""
    made = []

    def _make(env_id: str, **kwargs):
        env = gym.make(env_id, **kwargs)
        made.append(env)
        return env

    yield _make
    for env in made:
        env.close()


@pytest.fixture(scope="module")
def reward_env():
    """A bare PutAppleBowl env (state observations, no renderer) reset with seed 0, shared by a test file's tests
    that call reward modules against it."""
    from gendex_envs.registry import resolve_task
    from gendex_envs.task_env import TaskEnv

    e = TaskEnv(task=resolve_task("PutAppleBowl"), obs_mode="state", control_mode="pd_joint_delta_pos",
                render_backend="none")
    e.reset(seed=0)
    yield e
    e.close()


@pytest.fixture(scope="session")
def library_sample() -> list[str]:
    """The versions a default-suite test of an every-version property checks (:func:`gendex.check.ci_selection`:
    the changed ones, the newest reference ones and a fixed sample), so its cost does not grow with the library;
    its slow-marked variant checks them all."""
    from gendex.check import ci_selection

    return ci_selection()


@pytest.fixture
def no_renders(monkeypatch):
    """Renders stand-in for generation tests that do not look at the renders (a third of a task's generation time
    goes to rendering; ``tests/sim/test_generate.py``'s offline run and its critic test check the real renders)."""
    from generator.render import VIEWS

    def views(spec, *, seed=0, resolution=None):
        return {view: f"{spec.name}:{view}:{seed}".encode() for view in VIEWS}

    monkeypatch.setattr("generator.pipeline.render_spec", views)
    monkeypatch.setattr("generator.steps.refine.render_spec", views)


@pytest.fixture(scope="session")
def committed_tasks() -> dict[str, TaskVersion]:
    """The committed library (``discover_tasks`` of ``generated_tasks/``, whatever else this process registered),
    found once a process so that each spec is parsed once however many tests read it. Read it; do not change it."""
    from gendex_envs.registry import REPO_TASKS_DIR, discover_tasks

    return discover_tasks([REPO_TASKS_DIR])


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """The repository (for tests of its own files: docs, benchmarks, the source tree)."""
    return Path(__file__).resolve().parent.parent
