"""Write the three hand-written pour tasks the pour primitive was measured on before the offline author wrote any
(records: ``benchmarks/results/skills.md``): a tumbler, a beaker and a paper cup, each holding twelve beads, poured
into a bowl (the beaker into the large bowl). They are the spec of ``tests/sim/test_pour.py`` under three names, with
a small reward module; they are not library tasks.

    .venv/bin/python benchmarks/pour_tasks.py /tmp/pourtasks
    GENDEX_TASKS_PATH=/tmp/pourtasks .venv/bin/python benchmarks/skill.py --tasks GenDex/PourBeadsTumbler-v0 \\
        GenDex/PourBeadsBeaker-v0 GenDex/PourBeadsPaperCup-v0 --seeds 20 --seed 75000 --workers 2
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from gendex_envs.task_version import TaskLayout
from tests.sim.test_pour import _task  # the spec the tests check

TASKS = (("PourBeadsTumbler", "tumbler", "bowl"), ("PourBeadsBeaker", "beaker", "bowl_large"),
         ("PourBeadsPaperCup", "paper_cup", "bowl"))
REWARD = '''"""A hand-written pour task for measuring the pour primitive (not a library task)."""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0


def evaluate(env):
    fail = env.obj_pose('glass').p[:, 2] < env.table_height - 0.05  # fell off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj('glass'))  # [N, 6, 1]
    return {"fail": fail, "contact": rt.contact(force), "poured": env.poured_share('glass', 'bowl')}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose('glass').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    held = info["contact"] > 0.2
    near = rt.place(p, env.obj_pose('bowl').p) * held
    reward = reach + info["contact"] + near + 2.0 * info["poured"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_obj": env.obj_pose('glass').p - env.palm_pose.p,
            "obj_to_bowl": env.obj_pose('bowl').p - env.obj_pose('glass').p, "poured": info["poured"][:, None]}
'''


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="folder to write <Name>/v0/ task folders into")
    out = ap.parse_args().out
    for name, vessel, bowl in TASKS:
        files = TaskLayout(out / name / "v0")
        files.spec.parent.mkdir(parents=True, exist_ok=True)
        files.spec.write_text(yaml.safe_dump({**_task(vessel, bowl), "name": name}, sort_keys=False))
        files.reward.write_text(REWARD)


if __name__ == "__main__":
    main()
