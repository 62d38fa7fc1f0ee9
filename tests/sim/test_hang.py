"""Hanging: a mug threaded onto a peg and let go hangs there (the ``hung`` condition: the stand bears its weight and
it has risen min_height_m), a mug on the table does not, and the stage executor
hangs a mug it grasped on a peg of a stand (:mod:`gendex.solve.hang`)."""

from __future__ import annotations

import dataclasses

import numpy as np
import sapien
import yaml

from gendex.solve.hang import hole_local, pegs_world, thread_poses
from gendex_envs.spec import parse_task_spec
from gendex_envs.success import condition_holds
from gendex_envs.task_env import TaskEnv

TASK = yaml.safe_load("""
name: HangCheck
instruction: Hang the mug on the mug tree.
objects:
- {name: mug, asset: mug, pos_m: [-0.05, 0.2, 0.0], randomize: {xy_m: [0.08, 0.08], yaw_deg: 90.0}}
- {name: stand, asset: mug_tree, pos_m: [0.15, 0.0, 0.0], fixed: true, randomize: {xy_m: [0.03, 0.03], yaw_deg: 30.0}}
stages:
- {name: reach_mug, instruction: Reach the mug., skill: reach, method: motion_planning, control_joint: arm,
   horizon: 60, target: mug}
- {name: grasp_mug, instruction: Grasp the mug., skill: grasp, method: RL, control_joint: hand, horizon: 40,
   target: mug, success: [{type: grasped, object: mug, min_fingers: 1}]}
- {name: hang_mug, instruction: Hang it on a peg., skill: hang, method: motion_planning, control_joint: arm,
   horizon: 250, target: stand}
- {name: release_mug, instruction: Let go of it., skill: release, method: RL, control_joint: hand, horizon: 30,
   target: mug}
success:
  description: The mug hangs by its handle on the mug tree, let go and still.
  conditions: [{type: hung, object: mug, target: stand}, {type: released, object: mug}, {type: at_rest, object: mug}]
max_episode_steps: 580
""")


def _still(env: TaskEnv, steps: int) -> None:
    for _ in range(steps):
        env.step(np.zeros(env.action_space.shape, dtype=np.float32))


def _holds(env: TaskEnv) -> list[bool]:
    return [bool(condition_holds(env, c)[0]) for c in env.task_spec.success.conditions]


def test_a_mug_threaded_on_a_peg_hangs_there_and_one_on_the_table_does_not():
    env = TaskEnv(task_spec=parse_task_spec(TASK), render_backend="none", control_mode="pd_joint_delta_pos")
    try:
        env.reset(seed=0)
        assert _holds(env)[0] is False  # on the table
        mug = env.obj("mug")
        palm = sapien.Pose([0.0, 0.0, 1.0])  # any palm pose: the mug's pose in the hand is what thread_poses keeps
        now = sapien.Pose(mug.pose.p[0].numpy(), mug.pose.q[0].numpy())
        ways = thread_poses(env, "mug", "stand", palm, now)
        assert len(ways) == 2 * len(pegs_world(env, "stand")) == 6  # every peg, either way round
        t = next(w for w in ways if w.peg == 0)
        goal = t.on * palm.inv() * now  # the mug where that way puts it: its opening on the peg's axis
        assert np.linalg.norm((goal * sapien.Pose(hole_local(env, "mug"))).p - t.hole_on) < 1e-6
        mug.set_pose(sapien.Pose(goal.p - [0.0, 0.0, 0.01], goal.q))  # the peg just under the opening's top
        _still(env, 100)
        assert _holds(env) == [True, True, True]
        assert float(env.obj_height("mug")[0]) > 0.1
        risen = float(env.obj_height("mug")[0])
        hung = env.task_spec.success.conditions[0]
        assert bool(condition_holds(env, dataclasses.replace(hung, min_height_m=risen - 0.01))[0])
        assert not bool(condition_holds(env, dataclasses.replace(hung, min_height_m=risen + 0.01))[0])
        mug.set_pose(sapien.Pose(goal.p + [0.0, 0.0, 0.2], goal.q))  # lifted off the peg: falls to the table
        _still(env, 60)
        assert _holds(env)[0] is False
    finally:
        env.close()


def test_the_executor_hangs_a_mug_it_grasped_on_a_peg(solved):
    """One seed, stand and mug moved and turned at reset (rates over 50 unseen seeds: benchmarks/results/skills.md)."""
    success, env, solver = solved(parse_task_spec(TASK), seed=4)
    assert success
    assert [log.primitive for log in solver.logs[:4]] == ["approach", "grasp", "hang", "release"]
    assert float(env.obj_height("mug")[0]) > 0.1
