"""Stage success conditions and reward modules of the reference tasks agree with the stage executor, which solves
each task.

Every stage's declared success must hold where the executor ends that stage (the state the next stage starts from)
and not where the stage starts; every stage module must pass the generator's validator and be the module a stage
env loads.
"""

import gymnasium as gym
import pytest
import torch

from gendex.solve.executor import StageExecutor
from gendex_envs.registry import REFERENCE_TASKS, resolve_task
from gendex_envs.start_states import StartStates
from generator.steps.validate import check_reward_source

SEEDS = (0, 1)
# stages whose start state, as the executor leaves it, already meets the goal: its grasp lifts the bottle
ALREADY_DONE_AT_START = {("PickUpBottle", "lift_bottle")}
TASKS = REFERENCE_TASKS


def version(task):
    return resolve_task(f"GenDex/{task}-v0")


def stage_names(task):
    return [s.name for s in version(task).spec.stages]


def executor_boundaries(env, seed, judges):
    """Run the executor; at each stage boundary (start of stage k; the last: end of the last stage) the
    evaluation of every stage's judge, the env state and each stage module's dense reward: a list of
    ({stage: info}, state, {stage: reward}), one entry more than stages."""
    obs, _ = env.reset(seed=seed)
    u = env.unwrapped
    ex = StageExecutor()
    ex.reset(env, obs)
    seen, marks = 0, []
    while True:
        action = ex.act(env, obs)
        if len(ex.logs) > seen:  # stages [seen, len) start now; a stage that emitted no step starts and ends here
            infos = {n: j.evaluate(u) for n, j in judges.items()}
            rewards = {n: float(j.module.compute_dense_reward(u, None, None, infos[n])[0]) for n, j in judges.items()}
            snap = (infos, u.get_state(), rewards)
            marks += [snap] * (len(ex.logs) - seen)
            seen = len(ex.logs)
        if action is None:
            break
        obs, *_ = env.step(action)
    names = list(judges)
    assert [log.stage for log in ex.logs[:len(names)]] == names
    return marks[:len(names) + 1]


@pytest.fixture(scope="module", params=TASKS)
def task_run(request):
    task = request.param
    env = gym.make(f"GenDex/{task}-v0", control_mode="pd_joint_pos", control_joint="both")
    judges = {s: version(task).judge(s) for s in stage_names(task)}
    runs = {seed: executor_boundaries(env, seed, judges) for seed in SEEDS}
    yield task, env, judges, runs
    env.close()


def test_every_stage_module_passes_the_validator():
    for task in TASKS:
        for stage in stage_names(task):
            path = version(task).files.stage_reward(stage)
            check_reward_source(path.read_text(), f"{stage}.py")
            assert version(task).spec.stages[stage_names(task).index(stage)].success, f"{task}/{stage} declares none"


def test_stage_success_at_the_executors_stage_end_not_at_its_start(task_run):
    task, env, judges, runs = task_run
    for seed, marks in runs.items():
        for k, stage in enumerate(judges):
            start, end = marks[k][0][stage], marks[k + 1][0][stage]
            assert bool(end["success"][0]), f"{task}/{stage} seed {seed}: no success at the stage's end: {end}"
            assert "fail" not in end or not bool(end["fail"][0])
            if (task, stage) not in ALREADY_DONE_AT_START:
                assert not bool(start["success"][0]), f"{task}/{stage} seed {seed}: success already at the start"
            top = judges[stage].module.reward_max
            assert 0.0 <= marks[k][2][stage] < top or (task, stage) in ALREADY_DONE_AT_START
            assert marks[k + 1][2][stage] == top
        if task == "PickUpBottle":  # its start already lifts (see ALREADY_DONE_AT_START), so: not before the grasp
            assert not bool(marks[1][0]["lift_bottle"]["success"][0])


def test_stage_envs_load_their_own_module_and_start_where_the_previous_stage_ended(task_run):
    task, env, judges, runs = task_run
    names = list(judges)
    first = gym.make(f"GenDex/{task}-v0", stage=0)
    try:
        assert first.unwrapped.reward.path == version(task).files.stage_reward(names[0]).resolve()
        assert first.unwrapped.judge.conditions == version(task).spec.stages[0].success
    finally:
        first.close()
    # the last stage, started from the executor's states at the end of the one before, sees what the executor saw
    u = env.unwrapped
    seed = SEEDS[-1]  # the env's last episode, whose reset poses init_obj_pos still holds
    state = runs[seed][len(names) - 1][1].cpu().numpy()
    starts = StartStates(stage=names[-1], state=state, source="test",
                         obj_reset_pos={n: u.init_obj_pos(n)[:1].cpu().numpy() for n in u.objects})
    last = gym.make(f"GenDex/{task}-v0", stage=names[-1], start_states=starts)
    try:
        v = last.unwrapped
        assert v.reward.path == version(task).files.stage_reward(names[-1]).resolve()
        last.reset(seed=0)
        # contact forces read zero until the first physics step after a restore: hold the targets for one step
        joints = [j.name for j in v.agent.robot.get_active_joints()]
        hold = v.agent.controller.target_qpos[:, [joints.index(n) for n in v.agent.controller.free_joint_names]]
        _, _, _, _, info = last.step(hold.cpu().numpy()[0])
        expected = bool(runs[seed][len(names) - 1][0][names[-1]]["success"][0])
        assert bool(torch.as_tensor(info["success"]).reshape(-1)[0]) == expected
    finally:
        last.close()
