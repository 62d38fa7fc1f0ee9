"""Red-team round on the parent-side replay of recorded reward calls (gendex_envs.sandbox.trace / replay / ops, and
host.RemoteModule.call/_keep/_audit/_source_reader).

The recording is attacker-controlled data: a compromised worker (a module loaded with the first wall down) can
send any graph, and ``replay.compile_graph`` can be handed forged graphs directly. Every test asserts the SAFE
outcome, so a FAILING test is an escape; the docstring of each says what it tries and which documented guarantee
it holds the code to (docs/security.md, "Isolation" -> "Replays in the parent"). Honest-module tests compare an
untrusted (sandboxed, replayed) load of a module that passes the static check against a trusted in-process load
of the same file on a real env.

Payload modules: tests/data/hostile_r3/replay/.
"""

from __future__ import annotations

import builtins
import os
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import sapien
import torch

from gendex_envs import guard
from gendex_envs.reward_module import load_reward_module
from gendex_envs.sandbox import host, replay

REPO = Path(__file__).resolve().parents[2]
PAYLOADS = REPO / "tests" / "data" / "hostile_r3" / "replay"
LEAF = ["L", ["m", "obj_pose", "apple"], "float32", [1, 7]]


# ---------------------------------------------------------------------------------------------- helpers
def _read(source: list, arity: int):
    host._source_reader(source, arity)  # the parent's own check of a source
    return lambda view, args: view[tuple(source)]


def _compile(entries, out=("$r", 0, None), arity=0, num_envs=1, reader=None):
    raw = {"entries": entries, "out": list(out) if isinstance(out, tuple) else out}
    return replay.compile_graph(raw, num_envs, torch.device("cpu"), reader or (lambda s: _read(s, arity)))


def _op(name, args=(), kwargs=None, spec=("T", "float32", [1])):
    return ["O", name, ["$u", *args], kwargs or {}, list(spec)]


def _zeros(*shape, dtype="float32"):
    return _op("torch.zeros", shape, {"dtype": ["$dt", dtype]}, spec=("T", dtype, list(shape)))


def _ref(i, j=None):
    return ["$r", i, j]


@pytest.fixture(scope="module", autouse=True)
def _fake_mode_imported():
    """The first compile imports torch's fake-tensor machinery (about 2 s): not part of any measurement."""
    _compile([_zeros(1)])


class _PeakRss:
    """Peak resident memory above the start, sampled every millisecond by a thread (torch's kernels release the
    GIL), so that a transient allocation freed before the block ends is still seen."""

    _PAGE = os.sysconf("SC_PAGE_SIZE")

    def __enter__(self):
        self.base = self.peak = self._rss()
        self._stop = False
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        return self

    def _rss(self) -> int:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * self._PAGE

    def _run(self):
        while not self._stop:
            self.peak = max(self.peak, self._rss())
            time.sleep(0.001)

    def __exit__(self, *exc):
        self._stop = True
        self._thread.join()
        self.peak = max(self.peak, self._rss())

    @property
    def mb(self) -> float:
        return (self.peak - self.base) / 2**20


def _compile_and_run(entries, out=("$r", 0, None), view=None, args=()):
    """(compiled or the GraphError, replay value or the Miss, seconds, peak MB above the start)."""
    start = time.perf_counter()
    with _PeakRss() as mem:
        try:
            graph = _compile(entries, out)
        except replay.GraphError as exc:
            graph = exc
        value = None
        if isinstance(graph, replay.Graph):
            try:
                value = graph.run(view if view is not None else {}, args)
            except replay.Miss as miss:
                value = miss
    return graph, value, time.perf_counter() - start, mb(mem)


def mb(mem: _PeakRss) -> float:
    return round(mem.mb, 1)


# ---------------------------------------------------------------------------------------------- (4) memory and work
def test_a_guard_stated_for_a_tensor_result_does_not_escape_the_size_bounds():
    """A result stated as a guard ("V") is not counted in the element or work bounds, and _shape_check skips its
    check when the fake run succeeds: ``torch.ones(12000, 12000)`` stated as the guard ``1`` compiles, and every
    replay allocates and fills 576 MB before the guard check misses (the Miss message then formats the tensor)."""
    graph, value, seconds, peak = _compile_and_run([_op("torch.ones", (12000, 12000), spec=("V", 1))], out={})
    assert isinstance(graph, replay.GraphError) or peak < 200, (
        f"ESCAPE: a 'guard' over a 144M-element tensor compiled and its replay took {peak} MB and {seconds:.2f} s "
        f"({str(value)[:80]})")


def test_a_real_guard_that_broadcasts_its_inputs_is_bounded():
    """``torch.allclose`` really is a guard (it returns a bool), but it broadcasts its inputs: [8192, 1] against
    [1, 8192] is 67M elements of intermediates while _work counts 16 385. The fake run cannot decide it (data) and
    keeps the stated value, so it compiles."""
    entries = [_zeros(8192, 1), _zeros(1, 8192), _op("torch.allclose", (_ref(0), _ref(1)), spec=("V", True))]
    graph, value, seconds, peak = _compile_and_run(entries, out={})
    assert isinstance(graph, replay.GraphError) or (seconds < 0.5 and peak < 200), (
        f"ESCAPE: allclose over broadcast inputs replayed in {seconds:.2f} s and {peak} MB (32768x32768 would be "
        f"16x that)")


def test_an_operation_whose_internal_size_comes_from_a_scalar_argument_is_bounded():
    """``torch.mvlgamma(x, p)``: an honest stated result ([1] float32) and a work of 2 elements, but ATen builds
    ``arange(p)`` and ``x.unsqueeze(-1) + arange(p)`` and takes p lgammas: p = 2**26 is 512 MB and a second of
    CPU (p is not a SHAPE_ARGUMENTS size, so it is a constant nobody bounds)."""
    entries = [_op("torch.mvlgamma", (["$c", torch.tensor([1e9])], 1 << 26), spec=("T", "float32", [1]))]
    graph, value, seconds, peak = _compile_and_run(entries)
    assert isinstance(graph, replay.GraphError) or peak < 200, (
        f"ESCAPE: mvlgamma(p=2**26) replayed in {seconds:.2f} s and {peak} MB (p=2**30 would be 8 GB)")


def test_a_loss_that_broadcasts_its_inputs_is_bounded():
    """``F.mse_loss(a [16384, 1], b [1, 16384])`` states an honest scalar result; _work counts 32 769 elements,
    but the loss materialises the 268M-element broadcast difference (1 GB; at the node cap, [65536, 1] against
    [1, 65536], 16 GB)."""
    entries = [_zeros(16384, 1), _zeros(1, 16384),
               _op("torch.nn.functional.mse_loss", (_ref(0), _ref(1)), spec=("T", "float32", []))]
    graph, value, seconds, peak = _compile_and_run(entries, out=("$r", 2, None))
    assert isinstance(graph, replay.GraphError) or peak < 200, (
        f"ESCAPE: mse_loss over broadcast inputs replayed in {seconds:.2f} s and {peak} MB")


def test_an_assignment_through_broadcast_indices_is_bounded():
    """``x[i, j] = 1.0`` with index tensors [N, 1] and [1, N] writes N*N elements; _work counts the inputs and a
    None result (its stated spec "N"), about 3*N. N = 16384 is 268M writes; at the node cap (N = 65536) 4.3G, and
    85 such assignments fit the work bound."""
    n = 16384
    entries = [_zeros(256, 256), _zeros(n, 1, dtype="int64"), _zeros(1, n, dtype="int64"),
               _op("Tensor.__setitem__", (_ref(0), ["$u", _ref(1), _ref(2)], 1.0), spec=("N",))]
    graph, value, seconds, peak = _compile_and_run(entries)
    assert isinstance(graph, replay.GraphError) or seconds < 1.0, (
        f"ESCAPE: one broadcast-index assignment replayed in {seconds:.2f} s")


def test_compile_time_is_bounded():
    """The fake-tensor shape check runs every entry through FakeTensorMode; ``torch.gradient`` of a [4, 4] tensor
    costs 3.5-10 ms there (10-40 times an ordinary op). 512 entries are far inside every bound (under 1% of the
    work bound, 2% of the element bound); 4096 of them take 15-40 s of the parent's CPU per recording (up to 8
    recordings per function), and compile time is not counted by REPLAY_SLOW_S."""
    grad = _op("torch.gradient", (_ref(0),), spec=("S", [["T", "float32", [4, 4]], ["T", "float32", [4, 4]]]))
    entries = [_zeros(4, 4)] + [grad] * 512
    start = time.perf_counter()
    try:
        _compile(entries)
        outcome = "compiled"
    except replay.GraphError as exc:
        outcome = f"refused: {exc}"
    seconds = time.perf_counter() - start
    assert seconds < 1.0, (f"ESCAPE: compile_graph of 513 entries took {seconds:.2f} s ({outcome[:80]}); a full "
                           f"graph of {replay.MAX_ENTRIES} would take about {seconds * replay.MAX_ENTRIES / 513:.0f} s")


def test_a_graph_does_not_flood_the_parents_log():
    """A guard ("V") whose fake run fails is accepted with its stated value. When the failure happens inside a
    meta kernel, torch's fake-tensor module logs the whole traceback at ERROR level (about 1.4 KB, 22 lines on
    torch's stderr handler) for every such entry: 4096 entries are megabytes written to the user's stderr or log
    file per recording, and seconds of CPU."""
    import logging

    bmm = _op("torch.bmm", (_ref(0), _ref(0)), spec=("V", 1))  # 2-D inputs: meta_bmm raises
    records: list[logging.LogRecord] = []
    counter = logging.Handler()
    counter.emit = records.append
    logger = logging.getLogger("torch._subclasses.fake_tensor")  # its own stderr handler: counted, kept quiet
    handlers, propagate = logger.handlers[:], logger.propagate
    logger.handlers, logger.propagate = [counter], False
    try:
        _compile([_zeros(2, 2)] + [bmm] * 64)
    except replay.GraphError:
        pass
    finally:
        logger.handlers, logger.propagate = handlers, propagate
    text = logging.Formatter()
    logged = sum(len(text.format(r)) for r in records)
    assert logged < 8192, f"ESCAPE: compiling 65 entries logged {len(records)} ERROR records, {logged} bytes with " \
                          f"tracebacks (x64 for a full graph)"


def test_many_member_leaves_stay_cheap(env):
    """Leaves are read from the real env on every replay and not counted as work: 4096 leaves of the costliest
    member on PutAppleBowl (``spec_success``, which evaluates the task's success conditions). Held if a replay
    stays under 2 s (REPLAY_SLOW_S ends replays of the module after the first such replay)."""
    from gendex_envs.reward_view import view_of

    leaf = ["L", ["m", "spec_success"], "bool", [1]]
    try:
        graph = replay.compile_graph({"entries": [leaf] * 4096, "out": ["$r", 0, None]}, 1, torch.device("cpu"),
                                     lambda s: host._source_reader(s, 0))
    except replay.GraphError:
        return  # held: refused (more entries than a graph may have)
    view = view_of(env)
    start = time.perf_counter()
    graph.run(view, ())
    seconds = time.perf_counter() - start
    assert seconds < 2.0, f"ESCAPE: 4096 member leaves took {seconds:.2f} s in one replay"


# ---------------------------------------------------------------------------------------------- (5) crashes
CRASH = r"""
import sys, types
for name, path in (("gendex_envs", "gendex_envs"), ("gendex_envs.sandbox", "gendex_envs/sandbox")):
    package = types.ModuleType(name)
    package.__path__ = [path]
    sys.modules[name] = package
import torch
from gendex_envs.sandbox import replay

raw = {"entries": [["O", "torch.div", ["$u", ["$c", torch.tensor([-2**63])], -1], {"rounding_mode": "trunc"},
                    ["T", "int64", [1]]]], "out": ["$r", 0, None]}
try:
    graph = replay.compile_graph(raw, 1, torch.device("cpu"), lambda source: None)
    print("compiled", flush=True)
    graph.run(None, ())
except (replay.GraphError, replay.Miss) as exc:
    print("refused:", exc, flush=True)
print("survived", flush=True)
"""


def test_integer_overflow_in_a_division_does_not_kill_the_parent():
    """``torch.div(INT64_MIN, -1, rounding_mode="trunc")`` executes x86 ``idiv`` on INT64_MIN / -1: SIGFPE, the
    process dies. Every name and argument is allowed (torch.div, a constant tensor, an int, a string keyword).
    With the dividend built by ``torch.tensor([-2**63])`` inside the graph, fake-tensor constant propagation runs
    the real kernel already in compile_graph."""
    proc = subprocess.run([sys.executable, "-c", CRASH], cwd=REPO, capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONPATH": str(REPO)})
    assert proc.returncode == 0 and "survived" in proc.stdout, (
        f"ESCAPE: the replaying process died with status {proc.returncode} (SIGFPE is -8); stdout: "
        f"{proc.stdout.strip()[-200:]!r}")


# ---------------------------------------------------------------------------------------------- (2)/(8) arguments
@pytest.mark.parametrize("entry", [
    _op("torch.zeros", (1,), {"device": "meta"}),
    _op("torch.zeros", (1,), {"device": "cuda:1"}),  # on a CUDA build: CUDA initialised on any GPU, in the parent
    _op("torch.zeros", (1,), {"pin_memory": True}),  # on a CUDA build: a CUDA context for pinned host memory
    _op("Tensor.to", (["$c", torch.zeros(1)], "meta")),
    _op("torch.zeros", (1,), {"requires_grad": True}),  # an autograd leaf handed to the env as a reward
], ids=["zeros-meta", "zeros-cuda1", "pin-memory", "to-meta", "requires-grad"])
def test_a_graph_cannot_choose_the_device_or_autograd(entry):
    """The docs list "the env's device" as the only device constant; ``$dev`` is resolved to it. But any string is
    a constant, and keywords other than ``out``/``inplace`` pass, so a graph names any device or backend, pinned
    memory or ``requires_grad``; results are checked for dtype and shape only. Safe outcome: refused at compile."""
    graph, value, seconds, peak = _compile_and_run([entry])
    assert isinstance(graph, replay.GraphError), (
        f"ESCAPE: compiled; its replay gave {value if isinstance(value, replay.Miss) else _describe(value)}")


def _describe(t) -> str:
    return f"a tensor on {t.device} (requires_grad={t.requires_grad})" if isinstance(t, torch.Tensor) else repr(t)


@pytest.mark.parametrize("name, args", [
    ("Tensor.type", ("antigravity",)), ("Tensor.type", ("os.system",)), ("Tensor.type", ("torch.cuda.FloatTensor",)),
    ("Tensor.to", ("xla",)), ("Tensor.to", ("hpu",)), ("Tensor.to", ("privateuseone",)),
])
def test_strings_handed_to_operations_import_or_run_nothing(name, args):
    """Held: strings reach C++ parsers (``Tensor.type``, device names), never an import of a module they name."""
    before = set(sys.modules)
    entry = _op(name, (["$c", torch.zeros(1)], *args), spec=("V", 1))
    graph, value, seconds, peak = _compile_and_run([entry], out={})
    assert set(sys.modules) - before == set() and "antigravity" not in sys.modules


def test_argument_leaves_are_copies_even_when_reached_by_index():
    """Held: an argument leaf reached through an int path part (a view of the caller's tensor) is copied before
    in-place operations run on it."""
    success = torch.tensor([[True, True]])
    info = {"success": success}
    entries = [["L", ["a", 0, "success", 0], "bool", [2]],
               _op("Tensor.__setitem__", (_ref(0), 0, False), spec=("N",)),
               _op("Tensor.fill_", (_ref(0), False), spec=("T", "bool", [2]))]
    graph = replay.compile_graph({"entries": entries, "out": ["$r", 0, None]}, 1, torch.device("cpu"),
                                 lambda s: host._source_reader(s, 1))
    out = graph.run(None, (info,))
    assert not out.any() and bool(success.all()) and info["success"] is success


# ---------------------------------------------------------------------------------------------- the whole path
@pytest.fixture(scope="module")
def env(reward_env):
    return reward_env


def _put_apple(env, x=None, y=None) -> None:
    pose = env.obj_pose("apple")
    p = pose.p[0].tolist()
    p = [p[0] if x is None else x, p[1] if y is None else y, p[2]]
    env.obj("apple").set_pose(sapien.Pose(p, pose.q[0].tolist()))


@pytest.fixture
def apple_back(env):
    p = env.obj_pose("apple").p[0].tolist()
    yield
    _put_apple(env, p[0], p[1])


@pytest.fixture
def fresh_worker():
    host.shutdown()
    yield
    host.shutdown()


@pytest.fixture
def wall_down(monkeypatch):
    """Modules load as if the first wall had a hole (the way tests/security/test_replay.py gets a compromised
    worker)."""
    monkeypatch.setattr(guard, "restricted_builtins", lambda: dict(vars(builtins)))
    monkeypatch.setattr(guard, "untrust", lambda folder: None)
    monkeypatch.setattr(host, "FULL_BUILTINS_FOR_TESTS", True)


def _task(tmp_path: Path, payload: str, name: str) -> Path:
    path = tmp_path / "tasks" / name / "v0" / "reward.py"
    path.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(PAYLOADS / payload, path)
    return path


def _remote(module) -> host.RemoteModule:
    return next(c.cell_contents for c in module.evaluate.__closure__ if isinstance(c.cell_contents, host.RemoteModule))


def test_a_recording_cannot_hang_the_parent(env, tmp_path, wall_down, fresh_worker):
    """A compromised worker answers one evaluate call with a graph of one ``torch.special.zeta`` on one element
    (stated shape true, work 3). zeta(2, q) loops about -q times for a negative non-integer q: q = -1e8 + 0.5 is
    about 3 s of the parent's CPU inside the env's step (the first replay runs in _keep, before any timing can
    stop it); q = -1e13 + 0.5 never returns in practice. The worker's own call took milliseconds."""
    module = load_reward_module(_task(tmp_path, "zeta_hang.py", "ZetaHang"), trusted=False, static_check=False)
    start = time.perf_counter()
    info = module.evaluate(env)
    seconds = time.perf_counter() - start
    assert not info["fail"].any()
    assert seconds < 1.0, f"ESCAPE: one evaluate call took {seconds:.2f} s in the parent (a forged zeta graph)"


def test_in_place_operations_on_every_member_leave_the_env_alone(env):
    """Held: a graph that reads every member the worker may ask for on PutAppleBowl, and an entry of ``info``, and
    zeroes each in place (``zero_``, ``fill_``, ``__setitem__``), changes none of them in the env or the caller's
    info dict (leaves are copies); read through the real view and the parent's own source reader."""
    from gendex_envs.reward_view import view_of

    view = view_of(env)
    keys = [("obj_pose", "apple"), ("entity.pose", "apple", None, None),
            ("entity.linear_velocity", "apple", None, None), ("entity.angular_velocity", "apple", None, None),
            ("init_obj_pos", "apple"), ("init_obj_quat", "apple"), ("obj_height", "apple"),
            ("hand_forces", "apple", None, None), ("palm_pose",), ("tip_positions",), ("qpos",), ("qvel",),
            ("spec_success",)]
    before = {k: host.MEMBERS[k[0]][1](view, *k[1:]).clone() for k in keys}
    info = {"success": torch.tensor([True]), "fail": torch.tensor([False])}
    kept = {k: v.clone() for k, v in info.items()}
    entries, out = [], {}
    for k in [*keys, ("a", 2, "success")]:
        value = before[k] if k[0] != "a" else info["success"]
        i = len(entries)
        source = ["m", *k] if k[0] != "a" else list(k)
        entries.append(["L", source, str(value.dtype).removeprefix("torch."), list(value.shape)])
        spec = ["T", str(value.dtype).removeprefix("torch."), list(value.shape)]
        entries.append(_op("Tensor.zero_", (_ref(i),), spec=spec))
        entries.append(_op("Tensor.fill_", (_ref(i), 1), spec=spec))
        entries.append(_op("Tensor.__setitem__", (_ref(i), ["$e"], 0), spec=("N",)))
        out[str(len(out))] = _ref(i)
    graph = replay.compile_graph({"entries": entries, "out": out}, 1, torch.device("cpu"),
                                 lambda source: host._source_reader(source, 3))
    got = graph.run(view, (None, None, info))
    assert all(not v.any() for v in got.values())  # the replay's own copies were zeroed
    for k in keys:
        assert torch.equal(host.MEMBERS[k[0]][1](view, *k[1:]), before[k]), k
    assert all(torch.equal(info[k], kept[k]) for k in info)


def _rss_mb() -> float:
    import gc

    gc.collect()
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def test_a_kept_graph_holds_only_what_it_states(env, tmp_path, wall_down, fresh_worker, monkeypatch):
    """A compromised worker sends an honest-valued recording of evaluate (one 1-element constant) in a frame that
    also carries 200 MB under a key compile_graph ignores. protocol._tensors decodes every tensor of a frame as a
    view into one payload buffer (torch.frombuffer), and the kept constant is used as it is (``t.to(cpu)`` is
    ``t``): the constant pins the whole payload. MAX_CONST_BYTES counts 1 byte."""
    # what is checked is memory, not time: building and sending the 200 MB frame overran the 5 s per-call limit
    # once on a 2-core machine running the suite beside a benchmark (a clean-clone run, 2026-12-01)
    monkeypatch.setenv("GENDEX_SANDBOX_TIMEOUT_S", "60")
    module = load_reward_module(_task(tmp_path, "payload_anchor.py", "Anchor"), trusted=False, static_check=False)
    before = _rss_mb()
    info = module.evaluate(env)
    del info
    retained = _rss_mb() - before
    remote = _remote(module)
    kept = sum(len(g) for g in remote.graphs.values())
    assert kept == 0 or retained < 100, (
        f"ESCAPE: {kept} kept graph(s) with a 1-byte constant hold {retained:.0f} MB of the parent's memory "
        f"(up to 4 graphs per function and signature, each frame up to 256 MB)")


def test_the_replay_opt_out_stops_a_forged_recording(env, tmp_path, wall_down, fresh_worker, monkeypatch):
    """Held (the mitigation today): with GENDEX_SANDBOX_REPLAY=0 the parent asks for no recording, so the zeta
    graph of the previous test never reaches compile_graph."""
    monkeypatch.setenv(host.REPLAY_ENV, "0")
    module = load_reward_module(_task(tmp_path, "zeta_hang.py", "ZetaOff"), trusted=False, static_check=False)
    start = time.perf_counter()
    for _ in range(3):
        module.evaluate(env)
    assert time.perf_counter() - start < 1.0 and _remote(module).graphs == {}


def test_a_compromised_worker_cannot_leave_forged_graphs_behind(env, tmp_path, wall_down, fresh_worker, apple_back):
    """(7) A compromised module shares the worker with an honest one and rewrites the worker's recorder: the honest
    module's recording becomes "return this constant". _keep replays it on the recorded state, where it agrees, and
    keeps it. After the compromised worker is gone (host.shutdown(): a fresh worker would be honest), the honest
    module's replays still return the frozen value, until an audit (the 16th, 64th, 256th replay, then every
    1024th)."""
    load_reward_module(_task(tmp_path, "freeze_others.py", "Freezer"), trusted=False, static_check=False)
    path = _task(tmp_path, "victim.py", "Victim")
    victim = load_reward_module(path, trusted=False)  # static check on: the victim is honest
    trusted = load_reward_module(path, trusted=True)
    _put_apple(env, x=0.05)
    first = victim.compute_dense_reward(env, None, None, {})
    assert torch.equal(first, trusted.compute_dense_reward(env, None, None, {}))
    host.shutdown()  # the compromised worker is gone
    _put_apple(env, x=-0.05)
    later = [victim.compute_dense_reward(env, None, None, {}) for _ in range(3)]
    honest = trusted.compute_dense_reward(env, None, None, {})
    assert all(torch.equal(v, honest) for v in later), (
        f"ESCAPE: after the compromised worker stopped, the honest module replayed {later[0].tolist()} (the value "
        f"frozen by the other module) where it computes {honest.tolist()}; replays "
        f"{_remote(victim).replays}, worker calls {_remote(victim).worker_calls}")


def _modules(tmp_path: Path, payload: str, name: str):
    path = _task(tmp_path, payload, name)
    return load_reward_module(path, trusted=False), load_reward_module(path, trusted=True)


def _same(a, b) -> bool:
    if isinstance(a, torch.Tensor):
        return isinstance(b, torch.Tensor) and a.dtype == b.dtype and bool(torch.equal(a, b))
    if isinstance(a, dict):
        return isinstance(b, dict) and list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    return a == b


def test_an_honest_module_replays_what_it_computes(env, tmp_path, apple_back):
    """Held (control): views changed through in-place updates of their base, iteration over tensors, info keys,
    branches on data, Python floats from data, reward_terms, the view's static members and tensor metadata all
    replay bit for bit, on both sides of the branch."""
    untrusted, trusted = _modules(tmp_path, "kitchen_sink.py", "KitchenSink")
    for x in [0.07, 0.02, 0.09, -0.03, 0.08, 0.01, 0.1, -0.01]:
        _put_apple(env, x=x)
        info_u, info_t = untrusted.evaluate(env), trusted.evaluate(env)
        assert _same(info_u, info_t)
        assert _same(untrusted.compute_dense_reward(env, None, None, info_t),
                     trusted.compute_dense_reward(env, None, None, info_t)), x
    remote = _remote(untrusted)
    assert sum(remote.replays.values()) >= 8, (remote.replays, remote.worker_calls)  # it did replay


def test_a_guard_tells_minus_zero_from_zero(env, tmp_path, apple_back):
    """(6) The honest module signed_zero.py rounds the apple's coordinates to table cells and takes
    ``math.atan2`` of them. Recorded with the apple at y = +1 mm (row 0.0), replayed with it at y = -1 mm (row -0.0):
    the guard ``float(...) == 0.0`` holds for -0.0, so the replay returns the bearing pi (reward 1.0) where the
    module computes -pi (reward 0.0). The argument signature (replay.signature) has the same blind spot for a
    Python float -0.0 in an argument."""
    untrusted, trusted = _modules(tmp_path, "signed_zero.py", "SignedZero")
    _put_apple(env, x=0.079, y=0.001)
    assert _same(untrusted.compute_dense_reward(env, None, None, {}), trusted.compute_dense_reward(env, None, None, {}))
    _put_apple(env, x=0.079, y=-0.001)
    got, want = untrusted.compute_dense_reward(env, None, None, {}), trusted.compute_dense_reward(env, None, None, {})
    assert _same(got, want), (
        f"ESCAPE: the untrusted copy gave {got.tolist()}, the module computes {want.tolist()} (replays "
        f"{_remote(untrusted).replays})")


def test_iteration_order_of_a_set_is_the_users(env, tmp_path, apple_back):
    """(6, sandbox-wide) The honest module set_order.py enumerates ``set(STAGES)``: string hashing is seeded per
    process, the worker's seed (``python -I``, no PYTHONHASHSEED) is not the user's, so the worker records and the
    parent replays a different order than the trusted in-process run takes. (The worker-served path has the same
    difference; the documented claim is bit-for-bit equality with the trusted run.) Fails unless both processes'
    seeds happen to order the eight names alike (about 1 in 40 000)."""
    from gendex_envs.code_check import check_reward_source
    from gendex_envs.errors import RewardCodeError

    # held since the fix: reward code may not build sets at all (the static check names the reason)
    source = (PAYLOADS / "set_order.py").read_text()
    with pytest.raises(RewardCodeError, match="order that changes"):
        check_reward_source(source, "set_order.py")
