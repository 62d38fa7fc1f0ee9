"""Replays of recorded reward calls run in the parent (gendex_envs.sandbox.replay), so the recording is untrusted data
from the worker: every graph a compromised worker could send must be refused before anything runs, or be harmless.

Forged graphs are handed to ``compile_graph`` directly (each refusal next to a valid graph that compiles, so the
refusals are not vacuous), and once through the whole path: a module that, with the first wall down, replaces the
worker's recorder and sends forged graphs to the parent.
"""

from __future__ import annotations

import builtins
import resource
import time
from pathlib import Path

import pytest
import torch

from gendex_envs import guard
from gendex_envs.reward_module import load_reward_module
from gendex_envs.sandbox import host, replay

LEAF = ["L", ["m", "obj_pose", "apple"], "float32", [1, 7]]
SLICE_P = ["O", "Tensor.__getitem__", ["$u", ["$r", 0, None], ["$u", ["$e"], ["$s", None, 3, None]]], {},
           ["T", "float32", [1, 3]]]


def _compile(entries, out=("$r", 1, None), arity=0, num_envs=1):
    raw = {"entries": entries, "out": list(out) if isinstance(out, tuple) else out}
    return replay.compile_graph(raw, num_envs, torch.device("cpu"), lambda s: _read(s, arity))


def _read(source: list, arity: int):
    host._source_reader(source, arity)  # the parent's own check of a source
    return lambda view, args: view[tuple(source)]


class _Values(dict):
    """Stands for the view: leaf source -> tensor."""


def _reader(values: dict):
    return _Values(values)


def _run(graph, view):
    return graph.run(view, ())


def test_a_valid_graph_compiles_and_replays():
    pose = torch.arange(7, dtype=torch.float32)[None]
    graph = _compile([LEAF, SLICE_P])
    assert torch.equal(_run(graph, _reader({("m", "obj_pose", "apple"): pose})), pose[..., :3])


def _op(name, args=("$u", ["$r", 0, None]), kwargs=None, spec=("T", "float32", [1, 7])):
    return ["O", name, list(args), kwargs or {}, list(spec)]


@pytest.mark.parametrize("name", [
    "torch.save", "torch.load", "torch.from_file", "Tensor.numpy", "Tensor.data_ptr", "Tensor.storage",
    "Tensor.untyped_storage", "Tensor.share_memory_", "Tensor.set_", "Tensor.resize_", "torch.set_default_dtype",
    "torch.manual_seed", "torch.set_num_threads", "builtins.exec", "os.system", "__import__", "eval",
    "torch.nonzero", "torch.einsum", "Tensor.tolist", "torch.as_strided", "torch.empty", "torch.rand",
    "Tensor.__reduce_ex__", "Tensor.__setstate__", "Tensor.register_hook",
])
def test_an_operation_outside_the_table_is_refused(name):
    with pytest.raises(replay.GraphError, match="not one a replay may run"):
        _compile([LEAF, _op(name)])


@pytest.mark.parametrize("entries, out, match", [
    ([LEAF, _op("Tensor.add", ("$u", ["$r", 0, None], ["$r", 0, None]), {"out": ["$r", 0, None]})], ("$r", 1, None),
     "keywords"),
    ([LEAF, _op("Tensor.add", ("$u", ["$r", 2, None], 1.0))], ("$r", 1, None), "reference"),  # a later entry
    ([LEAF, _op("Tensor.__bool__", spec=("V", True)), _op("Tensor.add", ("$u", ["$r", 1, None], 1.0))],
     ("$r", 2, None), "not a tensor"),  # a guard's value is not a tensor to use
    ([LEAF, SLICE_P], ("$r", 1, 0), "not a tensor"),  # an element of a single result
    ([LEAF, _op("torch.split", ("$u", ["$r", 0, None], 3), spec=("S", [["T", "float32", [1, 7]]]))],
     ("$r", 1, 5), "not a tensor"),  # an element past the sequence's end
    ([["L", ["m", "__class__"], "float32", [1]]], ("$r", 0, None), "unknown env member"),
    ([["L", ["m", "obj_pose"], "float32", [1]]], ("$r", 0, None), "unknown env member"),  # missing argument
    ([["L", ["m", "obj_pose", 7], "float32", [1]]], ("$r", 0, None), "strings"),
    ([["L", ["a", 5, "success"], "bool", [1]]], ("$r", 0, None), "not a member or argument"),
    ([["L", ["x", "success"], "bool", [1]]], ("$r", 0, None), "not a member or argument"),
    ([["L", ["m", "obj_pose", "apple"], "object", [1, 7]]], ("$r", 0, None), "dtype"),
    ([["L", ["m", "obj_pose", "apple"], "float32", [1, -7]]], ("$r", 0, None), "shape"),
    ([LEAF, _op("Tensor.add", ("$u", ["$r", 0, None], ["$x", 1]))], ("$r", 1, None), "unknown value tag"),
    ([LEAF, _op("Tensor.add", ("$u", ["$r", 0, None], [1, 2]))], ("$r", 1, None), "untagged"),
    ([LEAF, _op("Tensor.add", ("$u", ["$r", 0, None], ["$dt", "object"]))], ("$r", 1, None), "dtype"),
    ([LEAF], ("$r", 9, None), "bad reference"),
])
def test_a_malformed_graph_is_refused(entries, out, match):
    with pytest.raises(replay.GraphError, match=match):
        _compile(entries, out=out)


def test_constant_tensors_are_bounded():
    big = ["$c", torch.zeros(replay.MAX_CONST_BYTES // 4 + 1)]
    with pytest.raises(replay.GraphError, match="constant tensors"):
        _compile([_op("Tensor.clone", ("$u", big), spec=("T", "float32", [replay.MAX_CONST_BYTES // 4 + 1]))],
                 out=("$r", 0, None))


def test_deep_nesting_is_refused():
    value = 1.0
    for _ in range(40):
        value = ["$l", value]
    with pytest.raises(replay.GraphError, match="deeper"):
        _compile([LEAF, _op("Tensor.add", ("$u", ["$r", 0, None], value))])


def test_too_many_entries_are_refused():
    entries = [LEAF] + [_op("Tensor.clone", ("$u", ["$r", i, None])) for i in range(replay.MAX_ENTRIES)]
    with pytest.raises(replay.GraphError, match="entries"):
        _compile(entries, out=("$r", 5, None))


def _rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def test_a_size_the_graph_hides_is_found_before_anything_is_allocated():
    """``torch.zeros(200000, 200000)`` (160 GB) stated as one element: the meta run finds the lie."""
    before, start = _rss_mb(), time.monotonic()
    lie = _op("torch.zeros", ("$u", 200_000, 200_000), spec=("T", "float32", [1]))
    with pytest.raises(replay.GraphError, match="states a result it does not give"):
        _compile([lie], out=("$r", 0, None))
    assert time.monotonic() - start < 5 and _rss_mb() - before < 100


def test_a_size_the_graph_states_is_bounded():
    honest = _op("torch.zeros", ("$u", 200_000, 200_000), spec=("T", "float32", [200_000, 200_000]))
    with pytest.raises(replay.GraphError, match="elements"):
        _compile([honest], out=("$r", 0, None))
    many = [_op("torch.zeros", ("$u", 60_000), spec=("T", "float32", [60_000])) for _ in range(80)]
    with pytest.raises(replay.GraphError, match="elements"):
        _compile(many, out=("$r", 0, None))


@pytest.mark.parametrize("op", [
    _op("Tensor.expand", ("$u", ["$r", 0, None], ["$r", 0, None]), spec=("T", "float32", [1, 7])),
    _op("Tensor.repeat", ("$u", ["$r", 0, None], ["$r", 0, None], 1), spec=("T", "float32", [1, 7])),
    _op("torch.zeros", ("$u", ["$r", 0, None]), spec=("T", "float32", [1])),
    _op("torch.arange", ("$u", ["$r", 0, None]), spec=("T", "float32", [1])),
    _op("torch.nn.functional.pad", ("$u", ["$r", 0, None], ["$u", 0, ["$r", 0, None]]), spec=("T", "float32", [1, 7])),
])
def test_sizes_taken_from_tensor_values_are_refused(op):
    with pytest.raises(replay.GraphError, match="sizes must be constants|cannot be checked"):
        _compile([LEAF, op], out=("$r", 1, None))


MASK = _op("Tensor.__gt__", ("$u", ["$r", 0, None], 0.5), spec=("T", "bool", [1, 7]))


def test_a_result_whose_size_depends_on_data_is_refused():
    by_mask = _op("Tensor.__getitem__", ("$u", ["$r", 0, None], ["$r", 1, None]), spec=("T", "float32", [1]))
    with pytest.raises(replay.GraphError, match="cannot be checked"):
        _compile([LEAF, MASK, by_mask], out=("$r", 2, None))


# ---------------------------------------------------------------------------------------------- what a replay touches
def test_in_place_operations_change_only_the_replays_own_copies():
    pose = torch.arange(7, dtype=torch.float32)[None]
    success = torch.tensor([True])
    keep_pose, keep_success = pose.clone(), success.clone()
    entries = [LEAF, _op("Tensor.add_", ("$u", ["$r", 0, None], 100.0)),
               ["L", ["a", 0, "success"], "bool", [1]],
               _op("Tensor.__setitem__", ("$u", ["$r", 2, None], 0, False), spec=("N",)),
               _op("Tensor.zero_", ("$u", ["$r", 0, None]))]
    graph = _compile(entries, out={"pose": ["$r", 4, None], "success": ["$r", 2, None]}, arity=1)
    out = _run(graph, _reader({("m", "obj_pose", "apple"): pose, ("a", 0, "success"): success}))
    assert not out["success"].any() and not out["pose"].any()
    assert torch.equal(pose, keep_pose) and torch.equal(success, keep_success)


def test_a_constant_changed_in_place_is_fresh_in_the_next_replay():
    entries = [_op("Tensor.add_", ("$u", ["$c", torch.ones(3)], 1.0), spec=("T", "float32", [3]))]
    graph = _compile(entries, out=("$r", 0, None))
    first, second = _run(graph, _reader({})), _run(graph, _reader({}))
    assert torch.equal(first, torch.full((3,), 2.0)) and torch.equal(second, first)


def test_a_guard_or_leaf_that_comes_out_otherwise_is_a_miss():
    pose = torch.zeros(1, 7)
    entries = [LEAF, _op("Tensor.any", ("$u", ["$r", 0, None]), spec=("T", "bool", [])),
               _op("Tensor.__bool__", ("$u", ["$r", 1, None]), spec=("V", True))]
    graph = _compile(entries, out=("$r", 0, None))
    with pytest.raises(replay.Miss, match="guard"):
        _run(graph, _reader({("m", "obj_pose", "apple"): pose}))
    assert torch.equal(_run(graph, _reader({("m", "obj_pose", "apple"): pose + 1})), pose + 1)
    with pytest.raises(replay.Miss, match="leaf"):
        _run(graph, _reader({("m", "obj_pose", "apple"): torch.zeros(2, 7)}))


# ---------------------------------------------------------------------------------------------- the whole path
FORGING = '''
import sys
import torch

trace = sys.modules["gendex_envs.sandbox.trace"]
trace.Tracer.finish = lambda self, value: FORGED


def evaluate(env):
    return {{"fail": env.obj_pose("apple").p[:, 2] < -10.0}}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs)
'''


@pytest.fixture(scope="module")
def env(reward_env):
    return reward_env


@pytest.fixture
def fresh_worker():
    """The module below rewrites the worker's recorder: later tests get a new worker."""
    host.shutdown()
    yield
    host.shutdown()


@pytest.mark.parametrize("forged", [
    None,  # the control: the worker's own recording is kept and replayed
    '{"entries": [["O", "torch.save", ["$u", ["$c", torch.zeros(1)], "MARKER"], {}, ["N"]]], "out": {}}',
    '{"entries": [["O", "Tensor.add", ["$u", ["$c", torch.zeros(1)], 1.0], {"out": ["$c", torch.zeros(1)]}, '
    '["T", "float32", [1]]]], "out": {"fail": ["$r", 0, None]}}',
    '{"entries": [["L", ["m", "obj_pose", "apple"], "float32", [1, 7]], ["O", "Tensor.zero_", ["$u", ["$r", 0, '
    'None]], {}, ["T", "float32", [1, 7]]]], "out": {"fail": ["$r", 1, None]}}',
    '{"entries": [["O", "torch.ones", ["$u", 100000, 100000], {}, ["T", "float32", [1]]]], "out": {"fail": '
    '["$r", 0, None]}}',
])
def test_forged_recordings_from_a_compromised_worker_are_refused_or_harmless(env, tmp_path, monkeypatch, forged,
                                                                            fresh_worker):
    monkeypatch.setattr(guard, "restricted_builtins", lambda: dict(vars(builtins)))
    monkeypatch.setattr(guard, "untrust", lambda folder: None)
    monkeypatch.setattr(host, "FULL_BUILTINS_FOR_TESTS", True)
    marker = tmp_path / "marker"
    path = tmp_path / "tasks" / "Forged" / "v0" / "reward.py"
    path.parent.mkdir(parents=True)
    source = FORGING.format()
    if forged is None:
        source = source.replace("trace.Tracer.finish = lambda self, value: FORGED", "")
    path.write_text(source.replace("FORGED", str(forged)).replace("MARKER", str(marker)))
    pose = env.unwrapped.obj_pose("apple").raw_pose.clone()
    module = load_reward_module(path, trusted=False, static_check=False)
    remote = next(c.cell_contents for c in module.evaluate.__closure__
                  if isinstance(c.cell_contents, host.RemoteModule))
    for _ in range(3):
        info = module.evaluate(env)
        assert info["fail"].dtype == torch.bool and not info["fail"].any()
    if forged is None:
        assert remote.replays == {"evaluate": 2} and remote.worker_calls == {"evaluate": 1}
    else:
        assert remote.graphs == {} and remote.replays == {}  # nothing replayed: every call went to the worker
        assert remote.worker_calls["evaluate"] == 3
    assert not marker.exists() and not Path(str(marker)).exists()
    assert torch.equal(env.unwrapped.obj_pose("apple").raw_pose, pose)
