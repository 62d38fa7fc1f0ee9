"""Hostile task specs of round two: names that only look valid, and finite positions far outside any scene.

Each payload in ``tests/data/hostile_r2/identity/`` declares on its first line the message it must be refused with
(``# expect: REGEX``); all are refused by :func:`load_task_spec` with a :class:`TaskSpecError`.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from gendex_envs.errors import TaskSpecError
from gendex_envs.registry import REPO_TASKS_DIR
from gendex_envs.spec import (
    MAX_ANGLE_DEG,
    MAX_JOINT_POSITION,
    MAX_POSITION_M,
    MAX_RANDOMIZE_M,
    SNAKE_NAME_RE,
    TASK_NAME_RE,
    load_task_spec,
)
from gendex_envs.task_version import VERSION_DIR

PAYLOADS = Path(__file__).resolve().parents[1] / "data" / "hostile_r2" / "identity"
SPECS = sorted(PAYLOADS.glob("*.yaml"))


def _expect(path: Path) -> str:
    first = path.read_text(encoding="utf-8").splitlines()[0]
    assert first.startswith("# expect: "), f"{path.name} must declare its expected reason on its first line"
    return first.removeprefix("# expect: ")


def test_there_are_payloads():
    assert len(SPECS) >= 15


@pytest.mark.parametrize("path", SPECS, ids=lambda p: p.stem)
def test_hostile_spec_is_refused_with_its_reason(path):
    with pytest.raises(TaskSpecError) as err:
        load_task_spec(path)
    assert re.search(_expect(path), str(err.value)), str(err.value)
    assert str(path) in str(err.value)


@pytest.mark.parametrize("bad", ["Name\n", "Name\r", "Name\r\n", "Na\x00me", "Name\x00", "N\u0430me", "Name\u200b",
                                 "Ｎame", "Name\u0661", "\nName", "Name "])
def test_name_patterns_match_whole_ascii_names_only(bad):
    assert TASK_NAME_RE.match(bad) is None and TASK_NAME_RE.fullmatch(bad) is None
    snake = bad.lower()
    assert SNAKE_NAME_RE.match(snake) is None and SNAKE_NAME_RE.fullmatch(snake) is None
    assert TASK_NAME_RE.match("Name") and SNAKE_NAME_RE.match("name_2")


@pytest.mark.parametrize("bad", ["v1\n", "v1\r", "v\u0661", "v01", "v1 ", "v-1", "v", "v1234567890"])
def test_version_folder_pattern_refuses_lookalikes(bad):
    assert VERSION_DIR.match(bad) is None
    assert VERSION_DIR.match("v0") and VERSION_DIR.match("v12")


def test_bounds_are_far_above_every_committed_task():
    """The bounds leave a wide margin over the committed library (largest values: |pos| 0.8 m, randomization
    0.13 m, yaw range 180 deg, joint state 6.28: a cap a full turn off). The committed files are read with libyaml
    (trusted, and ~20x faster than the bounded loader, so the test stays cheap as the library grows); that every
    version still loads through the bounded loader is ``gendex check``'s (``tests/sim/test_check.py``: the sample
    and the changed versions by default, every version under ``--slow``)."""
    import yaml

    specs = sorted(REPO_TASKS_DIR.glob("*/v*/task.yaml"))
    assert len(specs) >= 190
    pos, rand, yaw, joint = 0.0, 0.0, 0.0, 0.0
    for path in specs:
        raw = yaml.load(path.read_bytes(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
        pos = max([pos, *map(abs, raw.get("robot", {}).get("base_pos_m", [0])),
                   *map(abs, (raw.get("goal") or {}).get("pos_m", [0]))])
        for o in raw["objects"]:
            pos = max([pos, *map(abs, o["pos_m"])])
            rand = max([rand, *o.get("randomize", {}).get("xy_m", [0])])
            yaw = max(yaw, o.get("randomize", {}).get("yaw_deg", 0))
            joint = max([joint, *map(abs, (o.get("joint_state") or {0: 0}).values())])
    assert pos * 4 <= MAX_POSITION_M and rand * 4 <= MAX_RANDOMIZE_M and yaw <= MAX_ANGLE_DEG
    assert joint * 4 <= MAX_JOINT_POSITION
