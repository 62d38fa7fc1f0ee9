"""The episode loop alone, on a scripted env: the order it calls agent and hooks in, when it stops, which errors it
keeps; and a guard that the applications run no episode loop of their own (tests/sim/test_episode_loop_users.py checks
that they really run this one)."""

from __future__ import annotations

import ast
import re

import numpy as np
import pytest

from gendex.episode_loop import Hooks, SolverAgent, run_episode


class ScriptedEnv:
    """Success after ``success_at`` steps (and from then on), termination after ``end_at``; reward = step count."""

    def __init__(self, success_at: int = 99, end_at: int = 99, calls: list | None = None):
        self.success_at, self.end_at, self.calls = success_at, end_at, [] if calls is None else calls

    def reset(self, *, seed=None):
        self.t = 0
        self.calls.append(("env.reset", seed))
        return "obs0", {"reconfigure": False}

    def step(self, action):
        self.t += 1
        self.calls.append(("env.step", action))
        info = {"success": np.array([self.t >= self.success_at]), "fail": False}
        return f"obs{self.t}", float(self.t), self.t >= self.end_at, False, info


class Counter:
    """Acts 0, 1, 2, ...; done after ``n`` actions; raises ``raise_at`` at that action."""

    def __init__(self, calls: list, n: int = 5, raise_at: int | None = None, error=ValueError):
        self.calls, self.n, self.raise_at, self.error = calls, n, raise_at, error

    def reset(self):
        self.k = 0
        self.calls.append(("agent.reset",))

    def act(self, obs):
        self.calls.append(("agent.act", obs))
        if self.k == self.raise_at:
            raise self.error("gave up")
        if self.k == self.n:
            return None
        self.k += 1
        return self.k - 1


def test_one_episode_calls_agent_and_hooks_in_order_and_sums_the_rewards():
    calls: list = []
    env = ScriptedEnv(success_at=2, calls=calls)
    hooks = Hooks(prepare=lambda a: a * 10, on_reset=lambda obs, info: calls.append(("on_reset", obs)),
                  on_step=lambda s: calls.append(("on_step", s.t, s.action, s.obs, s.success)))
    out = run_episode(env, Counter(calls, n=2), np.int64(7), hooks)
    assert calls == [("env.reset", 7), ("agent.reset",), ("on_reset", "obs0"),
                     ("agent.act", "obs0"), ("env.step", 0), ("on_step", 1, 0, "obs1", False),
                     ("agent.act", "obs1"), ("env.step", 10), ("on_step", 2, 10, "obs2", True),
                     ("agent.act", "obs2")]
    assert type(calls[0][1]) is int  # the seed is reset as a Python int
    assert (out.seed, out.steps, out.ended_by, out.error) == (7, 2, "agent", None)
    assert (out.success_once, out.success_at_end, out.sum_reward, out.max_reward) == (True, True, 3.0, 2.0)


def test_the_episode_ends_at_termination_at_a_stop_hook_or_steps_on_past_the_end():
    assert run_episode(ScriptedEnv(end_at=3), Counter([], n=9), 0).ended_by == "terminated"
    assert run_episode(ScriptedEnv(end_at=3), Counter([], n=9), 0).steps == 3
    at_success = run_episode(ScriptedEnv(success_at=2), Counter([], n=9), 0, Hooks(stop=lambda s: s.success))
    assert (at_success.steps, at_success.ended_by, at_success.success_at_end) == (2, "stop", True)
    past = run_episode(ScriptedEnv(end_at=3), Counter([], n=5), 0, Hooks(stop_at_end=False))
    assert (past.steps, past.ended_by, past.terminated) == (5, "agent", True)


def test_errors_in_catch_end_the_episode_and_others_propagate():
    out = run_episode(ScriptedEnv(success_at=1), Counter([], raise_at=2), 0, Hooks(catch=(ValueError,)))
    assert (out.steps, out.ended_by, str(out.error)) == (2, "error", "gave up")
    assert out.success_once and out.success_at_end  # the loop reports; what an error means is the caller's
    with pytest.raises(KeyError):
        run_episode(ScriptedEnv(), Counter([], raise_at=0, error=KeyError), 0, Hooks(catch=(ValueError,)))
    none = run_episode(ScriptedEnv(), Counter([], n=0), 0)
    assert (none.steps, none.max_reward, none.success_at_end, none.info) == (0, 0.0, False, {"reconfigure": False})


def test_a_solver_agent_reads_the_env_it_is_bound_to():
    seen = []

    class Solver:
        def reset(self, env, obs):
            seen.append(("reset", env, obs))

        def act(self, env, obs):
            seen.append(("act", env, obs))
            return None

    env = ScriptedEnv()
    run_episode(env, SolverAgent(Solver(), env), 3)
    assert seen == [("reset", env, None), ("act", env, "obs0")]


USERS = ("gendex/data/collector.py", "gendex/solve/attempt.py", "generator/steps/gate.py", "gendex/eval/runner.py",
         "gendex/eval/policies.py", "gendex/imitation/bc.py", "gendex/train/ablate.py", "gendex/train/evaluate.py",
         "gendex/train/start_states.py")
"""The modules that run episodes (collection and the gate, evaluation and BC checkpoints, the ablation, stage-policy
evaluation, start states): they go through :func:`gendex.episode_loop.run_episode`."""


@pytest.mark.parametrize("path", USERS)
def test_no_application_resets_or_steps_an_env_itself(repo_root, path):
    tree = ast.parse((repo_root / path).read_text())
    own = [f"{path}:{n.lineno}: {ast.unparse(n)}" for n in ast.walk(tree)
           if isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute) and n.func.attr in ("reset", "step")
           and re.search(r"(^|[._])env$", ast.unparse(n.func.value))]
    assert not own, "an episode loop of its own (use gendex.episode_loop.run_episode):\n" + "\n".join(own)


def test_the_guard_finds_an_own_loop():
    src = "def f(env, agent):\n    obs, _ = env.reset(seed=1)\n    while True:\n        self.env.step(agent.act(obs))\n"
    calls = [ast.unparse(n.func) for n in ast.walk(ast.parse(src)) if isinstance(n, ast.Call)
             and isinstance(n.func, ast.Attribute) and re.search(r"(^|[._])env$", ast.unparse(n.func.value))]
    assert calls == ["env.reset", "self.env.step"]
