"""An adversarial corpus of reward modules: each is rejected by the static check with its named reason (issue 17).

Every file in ``tests/data/hostile_rewards`` is a complete reward module (``evaluate(env)`` and
``compute_dense_reward(env, obs, action, info)``) whose only fault is the hostile part. Its first line,
``# expect: <text>``, holds a substring the rejection message must contain; its second, ``# class: <name>``,
the class of attack it stands for.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import gendex_envs
from gendex_envs.code_check.rules import MAX_SOURCE_CHARS
from generator.errors import RewardCodeError, UnsafeCodeError
from generator.steps.static_check import check_reward_file, check_reward_source

ROOT = Path(__file__).resolve().parents[2]
CORPUS = sorted((ROOT / "tests" / "data" / "hostile_rewards").glob("*.py"))
PREVIEW = Path(gendex_envs.__file__).parent / "preview_rewards.py"
CLASSES = {"match", "scope", "dunder", "names", "mutation", "simulator", "modules", "state", "syntax", "resources"}


def _header(path: Path) -> tuple[str, str]:
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("# expect: ") and lines[1].startswith("# class: "), path.name
    return lines[0].removeprefix("# expect: "), lines[1].removeprefix("# class: ")


def test_corpus_is_large_and_covers_every_class():
    assert len(CORPUS) >= 40
    classes = {_header(p)[1] for p in CORPUS}
    assert classes == CLASSES, classes


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.stem)
def test_hostile_module_is_rejected_with_its_reason(path):
    expect, _ = _header(path)
    with pytest.raises(UnsafeCodeError) as info:
        check_reward_file(path)
    message = str(info.value)
    assert expect in message, message
    assert message.startswith(path.name)


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.stem)
def test_hostile_module_has_the_full_interface(path):
    """Only the hostile part may fail: both required functions exist with their exact parameters."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    defs = {s.name: [a.arg for a in s.args.args] for s in tree.body if isinstance(s, ast.FunctionDef)}
    assert defs.get("evaluate") == ["env"]
    assert defs.get("compute_dense_reward") == ["env", "obs", "action", "info"]


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.stem)
def test_checker_raises_only_typed_errors_on_mangled_sources(path):
    """Truncated and spliced variants of hostile code: the check returns or raises RewardCodeError, nothing else."""
    source = path.read_text(encoding="utf-8")
    variants = [source[: len(source) * k // 7] for k in range(1, 7)]
    variants += [source.replace("    ", "\t", 3), source.replace("(", "[", 2), source[::-1][:300], "\x00" + source]
    for variant in variants:
        try:
            check_reward_source(variant, path.name)
        except RewardCodeError:
            pass


def test_oversized_source_is_rejected_unparsed():
    source = CORPUS[0].read_text(encoding="utf-8")
    padded = source + "#" * (MAX_SOURCE_CHARS + 1 - len(source)) + "\n"
    with pytest.raises(RewardCodeError, match="too long for a reward module"):
        check_reward_source(padded, "big.py")


def test_the_preview_reward_module_still_passes():
    """The committed tasks' modules are checked per version by `gendex check` (tests/sim/test_check.py)."""
    check_reward_file(PREVIEW)
