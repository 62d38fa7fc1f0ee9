"""An allow-list, not a deny-list, of what reward code may call (issue 43, "torch's public surface is wider than the
deny-list").

Every payload in ``tests/data/hostile_r2/allow_list`` is a complete reward module whose ``compute_dense_reward``
reaches for something outside the allow-list (``gendex_envs.code_check.rules``): a file reader or writer torch
re-exports, a tensor over an interpreter buffer, uninitialised or arbitrary memory, the global generator. Its
first line ``# expect: <text>`` is a substring of the static check's refusal; its second, ``# runtime: <text>``,
a substring of the ``UntrustedCodeError`` the runtime guard raises when the module is loaded without the static
check and run (``static only`` for tensor methods: they cannot be withheld in-process, so the static check holds
them and the confined worker process is the wall behind it).
"""

from __future__ import annotations

import inspect
import types
from pathlib import Path

import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from gendex_envs import guard, reward_terms, reward_view
from gendex_envs.code_check.rules import (
    MODULE_MEMBERS,
    REWARD_TERMS_FUNCTIONS,
    TENSOR_METHODS,
    VALUE_ATTRIBUTES,
    VIEW_MEMBERS,
)
from gendex_envs.errors import RewardModuleError, UnsafeCodeError
from gendex_envs.guard import UntrustedCodeError
from gendex_envs.reward_module import load_reward_module
from generator.steps.static_check import check_reward_file

REPO = Path(__file__).resolve().parents[2]
CORPUS = sorted((REPO / "tests" / "data" / "hostile_r2" / "allow_list").glob("*.py"))


def _header(path: Path) -> tuple[str, str]:
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("# expect: ") and lines[1].startswith("# runtime: "), path.name
    return lines[0].removeprefix("# expect: "), lines[1].removeprefix("# runtime: ")


def _fake_env() -> types.SimpleNamespace:
    return types.SimpleNamespace(num_envs=2, device=torch.device("cpu"), tip_positions=torch.zeros(2, 5, 3))


def _copy(path: Path, tmp_path: Path) -> tuple[Path, Path]:
    folder = tmp_path / "tasks" / path.stem / "v1"
    folder.mkdir(parents=True)
    marker = tmp_path / "marker"
    (folder / "reward.py").write_text(path.read_text(encoding="utf-8").replace("MARKER", repr(str(marker))))
    return folder / "reward.py", marker


def test_corpus_is_large():
    assert len(CORPUS) >= 20


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.stem)
def test_hostile_call_is_refused_statically(path, tmp_path):
    expect, _ = _header(path)
    copy, marker = _copy(path, tmp_path)
    with pytest.raises(UnsafeCodeError) as info:
        check_reward_file(copy)
    assert expect in str(info.value), str(info.value)
    with pytest.raises(RewardModuleError, match="static check rejected it"):
        load_reward_module(copy, trusted=False)
    assert not marker.exists()


@pytest.mark.parametrize("path", [p for p in CORPUS if _header(p)[1] != "static only"], ids=lambda p: p.stem)
def test_hostile_call_is_refused_at_run_time_without_the_static_check(path, tmp_path, monkeypatch):
    """As if the static check had been bypassed: the module copies lack the name, and the refusal is a GenDex
    error naming the module and the attribute, not a bare AttributeError; no marker file appears."""
    monkeypatch.setenv("GENDEX_IN_PROCESS_GUARD", "1")  # this process's guard, not the worker's
    _, runtime = _header(path)
    copy, marker = _copy(path, tmp_path)
    try:
        module = load_reward_module(copy, trusted=False, static_check=False)
    except RewardModuleError as exc:  # refused while the module ran its imports
        assert isinstance(exc.__cause__, UntrustedCodeError) and runtime in str(exc), str(exc)
    else:
        raw = getattr(module.compute_dense_reward, "__wrapped__", module.compute_dense_reward)
        with pytest.raises(UntrustedCodeError) as info:
            raw(_fake_env(), {}, torch.zeros(2, 30), {})
        assert runtime in str(info.value), str(info.value)
    assert not marker.exists()


def test_refusals_name_what_is_allowed(tmp_path):
    copy, _ = _copy(REPO / "tests/data/hostile_r2/allow_list/torch_empty.py", tmp_path)
    with pytest.raises(UnsafeCodeError, match=r"nearest allowed in `torch`: .*`zeros`"):
        check_reward_file(copy)
    with pytest.raises(UntrustedCodeError, match=r"torch\.empty.*nearest allowed: .*zeros"):
        guard._proxy("torch").empty  # noqa: B018 - the attribute access is the test


# ---------------------------------------------------------------------------------------------- the lists
def test_every_allowed_name_exists_in_its_module():
    import importlib

    for module, names in MODULE_MEMBERS.items():
        real = importlib.import_module(module)
        assert not [n for n in names if not hasattr(real, n)], module
    assert not [n for n in TENSOR_METHODS if not hasattr(torch.Tensor, n)]


def test_no_allowed_name_writes_in_place_reads_memory_or_files():
    everything = VALUE_ATTRIBUTES.union(*MODULE_MEMBERS.values())
    assert not [n for n in everything if n.endswith("_") or n.startswith("_")]
    for bad in ("empty", "empty_like", "new_empty", "as_strided", "frombuffer", "asarray", "from_file", "from_numpy",
                "from_dlpack", "numpy", "storage", "untyped_storage", "data_ptr", "tofile", "save", "load",
                "pin_memory", "PyTorchFileWriter", "PyTorchFileReader", "UntypedStorage", "rand", "manual_seed",
                "get_file_path", "set_default_dtype", "factorial", "dropout", "Generator"):
        assert bad not in everything, bad


def test_reward_terms_and_view_lists_match_the_code():
    public = {k for k, v in vars(reward_terms).items() if inspect.isfunction(v) and not k.startswith("_")
              and v.__module__ == reward_terms.__name__}
    assert public == REWARD_TERMS_FUNCTIONS
    members = set()
    for cls in (reward_view.RewardView, reward_view.PoseView, reward_view.EntityView, reward_view.AgentView,
                reward_view.RobotView):
        members |= {k for k in dir(cls) if not k.startswith("_")}
    assert members == VIEW_MEMBERS


def test_the_module_copies_hold_exactly_the_allow_list():
    for module, names in MODULE_MEMBERS.items():
        copy = guard._proxy(module)
        assert {k for k in vars(copy) if not k.startswith("__")} == set(names), module
    assert isinstance(guard._proxy("torch").linalg, guard.ModuleView)
    with pytest.raises(UntrustedCodeError, match="may not change the module torch"):
        guard._proxy("torch").zeros = None


@settings(max_examples=300, deadline=None)
@given(module=st.sampled_from(sorted(MODULE_MEMBERS)),
       name=st.one_of(st.text(alphabet="abcdefghijklmnopqrstuvwxyz_ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789", min_size=1,
                              max_size=20),
                      st.sampled_from(sorted({n for m in ("torch", "torch.nn.functional", "math")
                                              for n in dir(__import__("importlib").import_module(m))}))))
def test_any_name_on_a_module_copy_is_allowed_or_refused_with_a_gendex_error(module, name):
    copy = guard._proxy(module)
    if name.startswith("__"):
        return  # Python's own protocol probes: plain AttributeError (the static check refuses every dunder)
    if name in MODULE_MEMBERS[module]:
        assert getattr(copy, name) is not None
    else:
        with pytest.raises(UntrustedCodeError, match=f"may not use {module}"):
            getattr(copy, name)


def test_reward_codes_torch_tensor_is_a_type_to_name_not_to_call():
    """The runtime wall behind the static check: torch.Tensor(n) is torch.empty(n) (uninitialised memory, which
    could carry state from call to call); reward code's torch.Tensor answers isinstance but refuses to build."""
    import torch

    from gendex_envs import guard
    from gendex_envs.guard import UntrustedCodeError

    copy = guard._proxy("torch")
    assert isinstance(torch.zeros(2), copy.Tensor) and not isinstance([1.0], copy.Tensor)
    for args in ((4,), (torch.Size([2, 2]),), (2, 3)):
        with pytest.raises(UntrustedCodeError, match="torch.zeros"):
            copy.Tensor(*args)
