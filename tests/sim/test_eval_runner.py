"""The evaluation runner: a policy's bad action fails its episode with the reason and the evaluation goes on;
every episode is reset with its own seed and judged at its end and at any step."""

import numpy as np

from gendex.eval.runner import evaluate_task

TASK = "GenDex/PutAppleBowl-v1"


class Scripted:
    """Acts by episode: hold the current targets, then NaN, then raise, then a joint far beyond its limit."""

    def __init__(self):
        self.episode = -1

    def bind(self, env):
        self.env = env

    def reset(self):
        self.episode += 1

    def act(self, obs):
        assert set(obs) == {"observation.state", "observation.environment_state"}
        hold = self.env.unwrapped.agent.controller.free_targets()[0].cpu().numpy()
        if self.episode == 1:
            return hold * np.nan
        if self.episode == 2:
            raise RuntimeError("policy crashed")
        if self.episode == 3:
            hold = hold.copy()
            hold[0] += 100.0
        return hold


def test_bad_actions_fail_their_episode_with_a_reason_and_the_run_goes_on():
    results = evaluate_task(TASK, Scripted, [11, 12, 13, 14], max_episode_steps=3)
    assert [r.seed for r in results] == [11, 12, 13, 14]
    hold, nan, crash, far = results
    assert hold.failure is None and hold.length == 3 and np.isfinite(hold.sum_reward)
    assert not hold.success_at_end  # holding still does not put the apple in the bowl
    assert nan.failure == "the action holds NaN or inf" and nan.length == 0
    assert crash.failure == "the policy's act() raised RuntimeError: policy crashed"
    assert far.failure.startswith("action[0] = ") and "outside the action space" in far.failure
    assert not any(r.success_at_end or r.success_once for r in (nan, crash, far))


def _tiny_suite(tmp_path):
    from gendex.eval.suite import load_suite

    path = tmp_path / "tiny.yaml"
    path.write_text("name: tiny\ndescription: two short episodes of PutAppleBowl\ntasks: [GenDex/PutAppleBowl-v1]\n"
                    "seed: 3000000\nepisodes: 2\nmax_episode_steps: 4\n")
    return load_suite(path)


def test_a_suite_run_resumes_where_it_stopped_and_refuses_seeds_a_policy_learned_from(tmp_path):
    import json

    import pytest

    from gendex.eval.policies import resolve_policy
    from gendex.eval.suite_run import EPISODES_FILE, EvalError, run_suite

    suite = _tiny_suite(tmp_path)
    out = tmp_path / "run"
    first = run_suite(suite, "hold", resolve_policy, out)
    [task] = first["per_task"]
    assert task["task_id"] == "GenDex/PutAppleBowl-v1" and task["metrics"]["seeds"] == [3_000_000, 3_000_001]
    assert first["suite"]["complete"] and task["episodes"] == 2 and first["overall"]["n_episodes"] == 2
    from gendex_envs.registry import committed_version

    digest = committed_version("GenDex/PutAppleBowl-v1").file_digest()
    assert first["task_digests"] == {"GenDex/PutAppleBowl-v1": digest}
    assert json.loads((out / "eval_run.json").read_text())["task_digests"] == first["task_digests"]
    lines = (out / EPISODES_FILE).read_text().splitlines()
    (out / EPISODES_FILE).write_text(lines[0] + "\n")  # as if stopped after the first episode
    seen = []
    again = run_suite(suite, "hold", resolve_policy, out, progress=seen.append)
    assert [r["seed"] for r in seen] == [3_000_001]  # only the missing episode ran
    assert again["per_task"] == first["per_task"]  # and it came out the same
    with pytest.raises(EvalError, match="holds an evaluation of hold"):
        run_suite(suite, "random", resolve_policy, out)
    with pytest.raises(EvalError, match="trained on seeds \\[3000001\\]"):
        run_suite(suite, "hold", resolve_policy, tmp_path / "other", training_seeds=[3_000_001, 7])
    assert json.loads((out / "eval_info.json").read_text())["policy"] == "hold"
