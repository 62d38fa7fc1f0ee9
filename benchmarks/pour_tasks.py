"""Write the three hand-written pour tasks the pour primitive was measured on before the offline author wrote any
(records: ``benchmarks/results/skills.md``): a tumbler, a beaker and a paper cup, each holding twelve beads, poured
into a bowl (the beaker into the large bowl). They are the spec of ``tests/sim/test_pour.py`` under three names, with
the reward module the generator writes for a pour (:mod:`generator.reward_library`); they are not library tasks.

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
from generator.reward_library import compose_task_module
from tests.sim.test_pour import _task  # the spec the tests check

TASKS = (("PourBeadsTumbler", "tumbler", "bowl"), ("PourBeadsBeaker", "beaker", "bowl_large"),
         ("PourBeadsPaperCup", "paper_cup", "bowl"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="folder to write <Name>/v0/ task folders into")
    out = ap.parse_args().out
    for name, vessel, bowl in TASKS:
        files = TaskLayout(out / name / "v0")
        files.spec.parent.mkdir(parents=True, exist_ok=True)
        spec = {**_task(vessel, bowl), "name": name}
        files.spec.write_text(yaml.safe_dump(spec, sort_keys=False))
        files.reward.write_text(compose_task_module(spec, {"glass": "graspable", "bowl": "container"}))


if __name__ == "__main__":
    main()
