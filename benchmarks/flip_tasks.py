"""Write the three hand-written flip tasks the flip primitive was measured on before the offline author wrote any
(records: ``benchmarks/results/skills.md``): a tumbler, a paper cup and a beaker, each turned upside down on the
table and let go there. They are the spec of ``tests/sim/test_flip.py`` under three names, with the reward module
the generator writes for a flip (:mod:`generator.reward_library`); they are not library tasks.

    .venv/bin/python benchmarks/flip_tasks.py /tmp/fliptasks
    GENDEX_TASKS_PATH=/tmp/fliptasks .venv/bin/python benchmarks/skill.py --tasks GenDex/FlipHandTumbler-v0 \\
        GenDex/FlipHandPaperCup-v0 GenDex/FlipHandBeaker-v0 --seeds 50 --seed 77000 --workers 2
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from gendex_envs.task_version import TaskLayout
from generator.reward_library import compose_task_module
from tests.sim.test_flip import _task  # the spec the tests check

TASKS = (("FlipHandTumbler", "tumbler"), ("FlipHandPaperCup", "paper_cup"), ("FlipHandBeaker", "beaker"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="folder to write <Name>/v0/ task folders into")
    out = ap.parse_args().out
    for name, vessel in TASKS:
        files = TaskLayout(out / name / "v0")
        files.spec.parent.mkdir(parents=True, exist_ok=True)
        spec = {**_task(vessel), "name": name}
        files.spec.write_text(yaml.safe_dump(spec, sort_keys=False))
        files.reward.write_text(compose_task_module(spec, {"glass": "graspable"}))


if __name__ == "__main__":
    main()
