"""The generator pipeline end to end: offline generation, replay, human-guided tasks, and adversarial answers."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import pytest
from gymnasium.utils.env_checker import check_env

from gendex_envs.registry import register_tasks
from gendex_envs.task_version import DRAFTS, TaskLayout
from generator.backends.base import ModelResponse
from generator.backends.offline import OfflineBackend
from generator.backends.transcript import ReplayBackend
from generator.errors import RetriesExhaustedError
from generator.pipeline import generate
from generator.steps.gate import gate_seeds


def _offline(seed: int = 0):
    return lambda: OfflineBackend(seed=seed)


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _task_folders(root: Path) -> list[Path]:
    return sorted(p for p in root.glob("*/v*") if p.is_dir())


GATE_SEEDS = 5
"""The offline run's gate measures 5 of the pipeline's 10 seeds (the gate's own rules: tests/sim/test_gate.py)."""


@pytest.fixture(scope="module")
def offline_run(tmp_path_factory):
    """One autonomous lift through the whole pipeline with its gate. A lift, because the replay below skips the gate:
    a run whose first proposal the gate drops (the take-out after a two-in-the-bowl task, in the library of session
    45) commits another task than its replay does."""
    root = tmp_path_factory.mktemp("gen")
    summaries = generate(lambda: OfflineBackend(seed=0, kinds=("lift",)), root, n=1, seed=0, command="test",
                         gate_attempts=GATE_SEEDS)
    assert summaries[0].dropped == (), summaries[0].dropped
    return root, summaries


def test_offline_task_is_committed_complete_and_passes_check_env(offline_run):
    root, summaries = offline_run
    [folder] = _task_folders(root)
    version = summaries[0].committed
    assert folder == version.root
    for f in version.files.generated:
        assert f.is_file(), f
    for when in ("before", "after"):
        for view in ("left_overhead", "right_overhead", "top_down"):
            assert version.files.render(f"{when}_{view}").read_bytes()[:4] == b"\x89PNG"
    info = version.provenance()["generation"]
    assert info["backend"] == "offline" and info["is_language_model"] is False and info["seed"] == 0
    # it passed the solvability gate: the solver's attempts on the task's own unseen seeds, stored with it
    gate = version.provenance()["solvability"]
    assert gate["passed"] and gate["planned_attempts"] == GATE_SEEDS and gate["successes"] >= 0.8 * GATE_SEEDS
    assert gate["seeds"] == gate_seeds(version.name)[:gate["attempts"]] and "stage executor" in gate["solver_version"]
    assert summaries[0].gate is not None and summaries[0].gate.successes == gate["successes"]
    assert not (root / DRAFTS).exists()  # nothing left half-written, not even an empty draft folder
    # every RL stage declares its goal (the skill's standard one), and its module does not decide success
    for stage in version.spec.stages:
        assert stage.method != "RL" or stage.success, stage
    rl = [s for s in version.spec.stages if s.method == "RL"]
    assert rl and version.judge(rl[0].name).conditions[0].type == rl[0].success[0].type
    env_id = summaries[0].committed.env_id
    assert env_id in register_tasks([root], override=True)
    env = gym.make(env_id)
    try:
        check_env(env, skip_render_check=True)
    finally:
        env.close()


def test_replayed_transcript_reproduces_the_task_files(offline_run, tmp_path):
    root, summaries = offline_run
    src = summaries[0].committed
    replay = generate(lambda: ReplayBackend(src.files.transcript), tmp_path, n=1, seed=0, command="test",
                      gate_attempts=0)
    # every file the transcript decides is byte-identical; the gate's measurement is not replayed (the replay is
    # told to skip it: the offline run above measured it, tests/sim/test_gate.py measures the gate itself)
    gate = TaskLayout(".").record("solvability").name
    a, b = _tree(replay[0].committed.root), _tree(src.root)
    assert gate not in a and json.loads(b[gate])["passed"]
    assert a == {k: v for k, v in b.items() if k != gate}


def test_human_instruction_grab_the_apple_gives_an_apple_grasp_task(tmp_path, no_renders):
    [s] = generate(_offline(0), tmp_path, n=1, seed=0, instruction="grab the apple", command="test", gate_attempts=0)
    spec = s.committed.provenance()["proposal"]
    assert [o["asset"] for o in spec["objects"]] == ["apple"]
    assert any(st["skill"] == "grasp" for st in spec["steps"])
    assert spec["success"]["type"] == "lifted"
    text = s.committed.files.spec.read_text()
    assert "asset: apple" in text and "control_joint: hand" in text and "skill: grasp" in text


# ---------------------------------------------------------------- adversarial answers (nothing is committed)
class Scripted:
    """A fake language model answering each stage from a list or a function; falls back to the offline author."""

    name = "scripted"
    model = "scripted-1"
    sees_images = False
    is_language_model = True

    def __init__(self, **answers):
        self.answers = answers
        self.offline = OfflineBackend(seed=0)
        self.seen: list[str] = []

    def complete(self, request):
        self.seen.append(request.step)
        a = self.answers.get(request.step)
        if a is None:
            return self.offline.complete(request)
        text = a(request) if callable(a) else a
        return ModelResponse(text=text, backend=self.name, model=self.model)


_LEMON = ('```json\n{"name": "LiftTheLemon", "description": "Lift the lemon.", '
          '"objects": [{"name": "lemon", "asset": "%s", "role": "graspable"}], '
          '"steps": [{"skill": "reach", "target": "lemon", "control_joint": "arm", "instruction": "Reach."}, '
          '{"skill": "grasp", "target": "lemon", "control_joint": "hand", "instruction": "Grasp."}], '
          '"success": {"type": "lifted", "object": "lemon", "target": null, "min_height_m": 0.1}, '
          '"success_text": "The lemon is lifted."}\n```')


UNLIFTED = "peach"
"""An object no library task lifts: a lemon is now a near-duplicate of LiftLemon, and the proposal would be refused
before the step a test aims at."""


def _assert_nothing_committed(root: Path) -> None:
    assert _task_folders(root) == []
    assert not (root / DRAFTS).exists() or not list((root / DRAFTS).iterdir())


def test_hallucinated_asset_is_rejected_with_its_name_and_nothing_is_committed(tmp_path):
    b = Scripted(propose=_LEMON % "golden_apple_9000")
    with pytest.raises(RetriesExhaustedError, match="golden_apple_9000.*not in the catalog"):
        generate(lambda: b, tmp_path, n=1, command="test", gate_attempts=0)
    assert b.seen == ["propose"] * 3  # bounded retries
    _assert_nothing_committed(tmp_path)


def test_malformed_scene_yaml_is_rejected_and_nothing_is_committed(tmp_path, no_renders):
    b = Scripted(propose=_LEMON % UNLIFTED, scene="```yaml\nname: LiftTheLemon\nobjects: [\n  - {name: lemon\n```")
    with pytest.raises(RetriesExhaustedError, match="not valid YAML"):
        generate(lambda: b, tmp_path, n=1, command="test", gate_attempts=0)
    _assert_nothing_committed(tmp_path)


def test_reward_code_importing_os_is_rejected_and_nothing_is_committed(tmp_path, no_renders):
    bad = ("```python\nimport os\n\ndef evaluate(env):\n    os.remove('x')\n\n"
           "def compute_dense_reward(env, obs, action, info):\n    return 0\n```")
    b = Scripted(propose=_LEMON % UNLIFTED, reward=bad)
    with pytest.raises(RetriesExhaustedError, match="os"):
        generate(lambda: b, tmp_path, n=1, command="test", gate_attempts=0)
    _assert_nothing_committed(tmp_path)


def test_reward_code_returning_nan_is_fed_back_and_the_fix_is_committed(tmp_path, no_renders):
    nan = ("```python\nimport torch\n\ndef evaluate(env):\n    z = torch.zeros(env.num_envs, dtype=torch.bool, "
           "device=env.device)\n    return {'fail': z}\n\n"
           "def compute_dense_reward(env, obs, action, info):\n"
           "    return torch.full((env.num_envs,), float('nan'), device=env.device)\n```")
    offline = OfflineBackend(seed=0)
    calls = []

    def reward(request):
        calls.append(request.prompt)
        if len(calls) == 1:
            return nan
        return offline.complete(request).text

    b = Scripted(propose=_LEMON % UNLIFTED, reward=reward)
    [s] = generate(lambda: b, tmp_path, n=1, command="test", gate_attempts=0)
    attempts = s.committed.provenance()["reward_attempts"]["attempts"]
    assert not attempts[0]["ok"] and "nan" in attempts[0]["feedback"].lower()
    assert "rejected" in calls[-1] or any("nan" in c.lower() for c in calls[1:])


def test_killed_run_leaves_no_partial_task_folder(tmp_path, repo_root):
    env = {**os.environ, "PYTHONPATH": str(repo_root)}
    proc = subprocess.Popen([sys.executable, "-m", "gendex.cli", "generate", "--backend", "offline", "--n", "3",
                             "--out", str(tmp_path)], env=env, cwd=repo_root, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)

    def drafts_with_a_spec():
        return [d for d in (tmp_path / DRAFTS).glob("*") if TaskLayout(d).spec.is_file()]

    try:
        deadline = time.time() + 120
        while time.time() < deadline and not drafts_with_a_spec():
            time.sleep(0.2)
        assert drafts_with_a_spec(), "the run never reached the reward step"
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    for folder in _task_folders(tmp_path):  # tasks committed before the kill are complete
        assert all(f.is_file() for f in TaskLayout(folder).generated), folder
    names = {p.name for p in tmp_path.iterdir()} - {DRAFTS}
    assert all(list((tmp_path / n).glob("v*/" + TaskLayout(".").spec.name)) for n in names)
    assert register_tasks([tmp_path], override=True) == [f"GenDex/{f.parent.name}-{f.name}"
                                                         for f in _task_folders(tmp_path)]


@pytest.mark.slow
def test_five_offline_tasks_are_distinct_reproducible_and_pass_check_env(tmp_path):
    runs = []
    for k in range(2):
        root = tmp_path / f"run{k}"
        runs.append((root, generate(_offline(0), root, n=5, seed=0, command="test", gate_attempts=0)))
    (root_a, a), (root_b, b) = runs
    assert len({s.committed.name for s in a}) == 5
    assert [s.committed.name for s in a] == [s.committed.name for s in b]
    for sa, sb in zip(a, b, strict=True):
        assert _tree(sa.committed.root) == _tree(sb.committed.root), sa.committed.name
    ids = register_tasks([root_a], override=True)
    assert sorted(ids) == sorted(s.committed.env_id for s in a)
    history_dependent = []
    for env_id in ids:
        env = gym.make(env_id)
        env.action_space.seed(1)
        try:
            check_env(env, skip_render_check=True)
        except AssertionError as exc:  # only the known defect is tolerated, and reported below
            if "Deterministic step observations are not equivalent" not in str(exc):
                raise
            history_dependent.append(env_id)
        finally:
            env.close()
    if history_dependent:
        pytest.xfail(f"known defect on {history_dependent}: after check_env's random full-body step the same seed and "
                     "action step differently (PhysX state outside get_state() survives a reset); history-"
                     "independent stepping is item 2 of the datasets issue")


# ---------------------------------------------------------------- the anthropic backend through the whole pipeline
_SCENE = """```yaml
name: LiftTheLemon
instruction: Lift the lemon.
objects:
  - {name: lemon, asset: peach, pos_m: [0.1, 0.0, 0.0]}
stages:
  - {name: approach_lemon, instruction: Reach., skill: reach, method: motion_planning, control_joint: arm,
     target: lemon}
  - {name: grasp_lemon, instruction: Grasp., skill: grasp, method: RL, control_joint: hand, target: lemon}
success:
  description: The lemon is lifted.
  conditions: [{type: lifted, object: lemon, min_height_m: 0.1}]
```"""
_PLAN = """```yaml
- {name: approach_lemon, instruction: Reach the lemon., skill: reach, method: motion_planning, control_joint: arm,
   target: lemon}
- {name: grasp_lemon, instruction: Grasp the lemon., skill: grasp, method: RL, control_joint: hand, horizon: 40,
   target: lemon, success: [{type: grasped, object: lemon, min_fingers: 3}]}
```"""
_REWARD = """```python
import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 1.0


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return rt.reach(torch.linalg.norm(env.palm_pose.p - env.obj_pose("lemon").p, dim=-1))


def _get_obs_extra(env, info):
    return {"lemon": env.obj_pose("lemon").p}
```"""


def test_anthropic_backend_runs_the_pipeline_with_images_and_its_directives_are_applied(tmp_path, monkeypatch):
    import httpx2

    from generator.backends.anthropic_backend import AnthropicBackend

    bodies: list[dict] = []
    analyses = iter(["Scene looks fine but the lemon could sit a bit to the left.\nDirectives:\n"
                     "Position_Action: lemon - move_y 0.05", "All good.\nDirectives: none"])

    def api(request):
        body = json.loads(request.content)
        bodies.append(body)
        prompt = body["messages"][0]["content"][-1]["text"]
        if "Propose ONE" in prompt:
            text = _LEMON % UNLIFTED
        elif "Write the scene file" in prompt:
            text = _SCENE
        elif "renders of a robot task scene" in prompt:
            text = next(analyses)
        elif "Split this task into sub-stages" in prompt:
            text = _PLAN
        elif "Write the Python module" in prompt:
            text = _REWARD
        else:
            raise AssertionError(f"unexpected prompt: {prompt[:80]}")
        return httpx2.Response(200, json={
            "id": "msg", "type": "message", "role": "assistant", "model": body["model"],
            "content": [{"type": "text", "text": text}], "stop_reason": "end_turn", "stop_sequence": None,
            "usage": {"input_tokens": 10, "output_tokens": 10}})

    monkeypatch.setenv("ANTHROPIC_API_KEY", "sk-ant-test")
    factory = lambda: AnthropicBackend(model="claude-test", http_client=httpx2.Client(  # noqa: E731
        transport=httpx2.MockTransport(api)), sleep=lambda s: None)
    [s] = generate(factory, tmp_path, n=1, command="test", candidates=1, gate_attempts=0)
    version = s.committed
    folder = version.root
    vision = [b for b in bodies if any(c["type"] == "image" for c in b["messages"][0]["content"])]
    assert len(vision) == 2  # one analysis per refinement round, until the critic asked for nothing
    images = [c for c in vision[0]["messages"][0]["content"] if c["type"] == "image"]
    assert len(images) == 3 and all(i["source"]["media_type"] == "image/png" for i in images)
    critique = version.provenance()["critique"]
    assert "Position_Action: lemon - move_y 0.05" in critique["rounds"][0]["directives"]
    assert "pos_m: [0.1, 0.05, 0.0]" in version.files.spec.read_text()
    # the model's own stage goal is kept (a stage without one would get the skill's standard goal)
    assert version.spec.stages[1].success[0].min_fingers == 3
    info = version.provenance()["generation"]
    assert info["backend"] == "anthropic" and info["model"] == "claude-test" and info["is_language_model"]
    # the recorded transcript replays to the same files without the API
    again = generate(lambda: ReplayBackend(version.files.transcript), tmp_path / "replay", n=1, command="test",
                     candidates=1, gate_attempts=0)
    assert _tree(again[0].committed.root) == _tree(folder)


@pytest.mark.slow
@pytest.mark.parametrize("request_text, name, conditions", [
    ("put the lemon and the plum in the bowl", "PutLemonInBowlThenPutPlumInBowl", ["inside", "inside"]),
    ("take the can out of the bowl", "TakeCanOutOfBowl", ["placed"]),
    ("stack the three blocks into a tower", "StackBlockMediumOnBlockLargeThenStackBlockSmallOnBlockMedium",
     ["over", "over"]),
])
def test_a_sample_of_the_dev_set_is_generated_and_solved(tmp_path, no_renders, request_text, name, conditions):
    """Issue 45's slow check: requests of the dev set (tests/data/instructions/dev.yaml) in the new constructs go
    through the whole pipeline, the solvability gate included (5 seeds, >= 80 %), and are committed as asked."""
    [s] = generate(_offline(0), tmp_path, n=1, seed=0, instruction=request_text, command="test",
                   gate_attempts=GATE_SEEDS)
    assert s.gate is not None and s.gate.passed, s.gate
    assert s.committed.name.removeprefix(name) in ("", "2")  # '2': the library holds a task of that name
    spec = s.committed.spec
    assert [c.type for c in spec.success.conditions if c.type not in ("released", "grasped")] == conditions
