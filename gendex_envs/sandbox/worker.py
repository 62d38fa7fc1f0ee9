"""The reward worker: a confined child process that runs untrusted reward modules (:mod:`gendex_envs.sandbox`).

Started by the parent as ``python -I <this file> PARENT_PID MEMORY_BYTES CPU_S`` (not ``-m``, which would run
``gendex_envs/__init__.py`` and register every task: 0.7 s and SAPIEN for nothing). It registers empty
``gendex_envs`` and ``gendex_envs.sandbox`` packages whose ``__path__`` points at the package folders, so the few
trusted files it needs (the guard's restricted builtins, the reward view's ``TensorsView``/``PoseView``, the wire
format, the confinement, ``reward_terms``) load from there without the package's ``__init__``. Then it imports
torch (one thread), prepares the module copies reward code may import, confines itself
(:func:`gendex_envs.sandbox.confine.confine`), reports ``ready`` with the walls it raised, and only then receives
source text. It serves ``load`` and ``call`` requests on stdin/stdout (:mod:`gendex_envs.sandbox.protocol`); a
reward function's read of an env member missing from the call's snapshot becomes a nested ``get`` request.
"""

from __future__ import annotations

import os
import sys
import time
import types


def _bootstrap() -> None:
    here = os.path.dirname(os.path.abspath(__file__))
    for name, path in (("gendex_envs", os.path.dirname(here)), ("gendex_envs.sandbox", here)):
        if name not in sys.modules:
            package = types.ModuleType(name)
            package.__path__ = [path]
            sys.modules[name] = package


if __name__ == "__main__":
    _bootstrap()

import builtins  # noqa: E402
import dis  # noqa: E402
import importlib  # noqa: E402
import inspect  # noqa: E402

import torch  # noqa: E402

from gendex_envs import errors, guard  # noqa: E402
from gendex_envs.reward_view import PoseView, view_args  # noqa: E402
from gendex_envs.sandbox import confine, protocol, trace  # noqa: E402

FUNCTIONS = ("evaluate", "compute_dense_reward", "_get_obs_extra")


class Channel:
    def __init__(self, rfd: int, wfd: int):
        self.rfd, self.wfd = rfd, wfd
        self.remote_errors: set[int] = set()
        self.tracer: trace.Tracer | None = None  # recording the current call (gendex_envs.sandbox.trace)
        self.running = ""  # the function being called: the parent files what it asks for under it

    def send(self, header: dict, value=None) -> None:
        tensors: list = []
        if value is not None or "value" in header:
            header = dict(header, value=protocol.encode(value, tensors))
        protocol.write_frame(self.wfd, header, tensors)

    def get(self, key: tuple):
        """The parent's answer for an env member missing from the snapshot (its error, raised here as it was)."""
        tracer = self.tracer
        if tracer is not None:
            tracer.paused = True  # the frame's own tensor building is not the reward call's
        try:
            self.send({"op": "get", "key": list(key), "fn": self.running})
            reply = protocol.read_frame(self.rfd)
        finally:
            if tracer is not None:
                tracer.paused = False
        if reply.get("op") == "val":
            return reply.get("value")
        exc = _rebuild(reply.get("type"), str(reply.get("msg", "")))
        self.remote_errors.add(id(exc))
        raise exc


def _rebuild(name, message: str) -> BaseException:
    cls = getattr(errors, str(name), None) or getattr(builtins, str(name), None)
    if not (isinstance(cls, type) and issubclass(cls, Exception)):
        cls = RuntimeError
    try:
        return cls(message)
    except Exception:  # an error type with another signature
        return RuntimeError(message)


# ---------------------------------------------------------------------------------------------- the remote view
def _ro(self, key, value):
    raise AttributeError(f"reward views are read-only (cannot set {key!r})")


class EntityView:
    __slots__ = ("_view", "name", "part", "joint")
    __setattr__ = _ro

    def __init__(self, view, name, part=None, joint=None):
        for k, v in (("_view", view), ("name", name), ("part", part), ("joint", joint)):
            object.__setattr__(self, k, v)

    @property
    def pose(self) -> PoseView:
        return PoseView(self._view._get("entity.pose", self.name, self.part, self.joint))  # noqa: SLF001 (the view's own helper)

    @property
    def linear_velocity(self) -> torch.Tensor:
        return self._view._get("entity.linear_velocity", self.name, self.part, self.joint).clone()  # noqa: SLF001 (the view's own helper)

    @property
    def angular_velocity(self) -> torch.Tensor:
        return self._view._get("entity.angular_velocity", self.name, self.part, self.joint).clone()  # noqa: SLF001 (the view's own helper)

    def __repr__(self) -> str:
        return f"EntityView({self.name!r}{', ' + self.part if self.part else ''})"


class RobotView:
    __slots__ = ("_view",)
    __setattr__ = _ro

    def __init__(self, view):
        object.__setattr__(self, "_view", view)

    def get_qpos(self) -> torch.Tensor:
        return self._view._get("qpos").clone()  # noqa: SLF001 (the view's own helper)

    def get_qvel(self) -> torch.Tensor:
        return self._view._get("qvel").clone()  # noqa: SLF001 (the view's own helper)


class AgentView:
    __slots__ = ("_view", "robot")
    __setattr__ = _ro

    def __init__(self, view):
        object.__setattr__(self, "_view", view)
        object.__setattr__(self, "robot", RobotView(view))

    def get_hand_group_obj_mean_force(self, entity: EntityView) -> torch.Tensor:
        if not isinstance(entity, EntityView):
            raise TypeError(f"get_hand_group_obj_mean_force takes env.obj(NAME) or env.handle_link(NAME), got "
                            f"{type(entity).__name__}")
        return self._view._get("hand_forces", entity.name, entity.part, entity.joint).clone()[..., None]  # noqa: SLF001 (the view's own helper)


class RemoteView:
    """The worker's twin of :class:`gendex_envs.reward_view.RewardView`: the same members, read from the call's
    snapshot (each a fresh copy), a miss asked of the parent."""

    __slots__ = ("_snapshot", "_channel", "num_envs", "device", "table_height", "object_names", "stage_targets",
                 "agent")
    __setattr__ = _ro

    def __init__(self, snapshot: dict, channel: Channel, static: dict):
        for k, v in (("_snapshot", snapshot), ("_channel", channel), ("num_envs", int(static["num_envs"])),
                     ("device", torch.device("cpu")), ("table_height", float(static["table_height"])),
                     ("object_names", tuple(static["object_names"])),
                     ("stage_targets", tuple(static["stage_targets"])), ("agent", AgentView(self))):
            object.__setattr__(self, k, v)

    def __delattr__(self, key):
        raise AttributeError(f"reward views are read-only (cannot delete {key!r})")

    def __repr__(self) -> str:
        return f"RewardView({self.num_envs} envs, objects {list(self.object_names)})"

    def _get(self, *key):
        if key in self._snapshot:
            return self._snapshot[key]
        value = self._snapshot[key] = self._channel.get(key)
        if self._channel.tracer is not None:
            self._channel.tracer.source(value, ("m", *key))
        return value

    def obj_pose(self, name: str) -> PoseView:
        return PoseView(self._get("obj_pose", name))

    def obj(self, name: str) -> EntityView:
        self._get("obj", name)
        return EntityView(self, name)

    def init_obj_pos(self, name: str) -> torch.Tensor:
        return self._get("init_obj_pos", name).clone()

    def init_obj_quat(self, name: str) -> torch.Tensor:
        return self._get("init_obj_quat", name).clone()

    def obj_height(self, name: str) -> torch.Tensor:
        return self._get("obj_height", name).clone()

    def hand_forces(self, name: str, part: str | None = None, joint: str | None = None) -> torch.Tensor:
        return self._get("hand_forces", name, part, joint).clone()

    @property
    def palm_pose(self) -> PoseView:
        return PoseView(self._get("palm_pose"))

    @property
    def tip_positions(self) -> torch.Tensor:
        return self._get("tip_positions").clone()

    def handle_link(self, name: str, joint: str | None = None) -> EntityView:
        self._get("handle_link", name, joint)
        return EntityView(self, name, "handle", joint)

    def handle_pos(self, name: str, joint: str | None = None) -> torch.Tensor:
        return self._get("handle_pos", name, joint).clone()

    def joint_qpos(self, name: str, joint: str | None = None) -> torch.Tensor:
        return self._get("joint_qpos", name, joint).clone()

    def joint_open_fraction(self, name: str, joint: str | None = None) -> torch.Tensor:
        return self._get("joint_open_fraction", name, joint).clone()

    def holds_point(self, name: str, joint: str | None = None) -> torch.Tensor:
        return self._get("holds_point", name, joint).clone()

    def poured_share(self, name: str, target: str) -> torch.Tensor:
        return self._get("poured_share", name, target).clone()

    def wiped_share(self, name: str, target: str) -> torch.Tensor:
        return self._get("wiped_share", name, target).clone()

    @property
    def goal_pos(self) -> torch.Tensor:
        return self._get("goal_pos").clone()

    def spec_success(self) -> torch.Tensor:
        return self._get("spec_success").clone()


# ---------------------------------------------------------------------------------------------- serving
def _prepare() -> None:
    """Everything reward code may import, loaded before the walls go up (after them, nothing new can be read)."""
    for name in guard.ALLOWED_IMPORTS:
        importlib.import_module(name)  # the real modules first: a package's copy reads its submodules
    importer = guard.restricted_builtins()["__import__"]
    for name in guard.ALLOWED_IMPORTS:
        importer(name, None, None, (), 0)
    # torch's C++ side imports torch.storage through the calling frame's __import__ the first time a tensor is
    # built from Python data with a device; the restricted builtins refuse it (an INTERNAL ASSERT), so do it here
    torch.tensor([0.0, 0.08], device=torch.device("cpu"), dtype=torch.float32).tolist()
    torch.as_tensor([1, 2], device="cpu")
    torch.full((2,), 1.0, device="cpu").sum().item()
    x = torch.linspace(0.0, 1.0, 12).reshape(3, 4)
    (torch.linalg.norm(x, dim=-1) + torch.tanh(x).sum(-1) + torch.where(x > 0.5, x, -x).amax(-1)).clamp(0, 1)
    torch.nn.functional.normalize(x, dim=-1)


def _load(msg: dict, modules: dict) -> dict:
    table = dict(vars(builtins)) if msg.get("full_builtins") else guard.restricted_builtins()
    scope = {"__name__": str(msg["name"]), "__builtins__": table}
    exec(compile(str(msg["source"]), str(msg["filename"]), "exec", dont_inherit=True), scope)
    fns = {f: scope[f] for f in FUNCTIONS if callable(scope.get(f))}
    modules[msg["id"]] = fns
    reward_max = scope.get("REWARD_MAX", 1.0)
    reward = fns.get("compute_dense_reward")
    return {"op": "loaded", "functions": sorted(fns), "early_reward": reward is not None and _ignores(reward, (1, 2)),
            "reward_max": float(reward_max) if isinstance(reward_max, int | float) else str(reward_max)[:100]}


def _ignores(fn, positions: tuple[int, ...]) -> bool:
    """Whether ``fn``'s code never reads its parameters at ``positions`` (nor hands them to a nested function)."""
    code = getattr(fn, "__code__", None)
    if code is None or code.co_argcount <= max(positions):
        return False
    if code.co_flags & (inspect.CO_VARARGS | inspect.CO_VARKEYWORDS):
        return False
    names = {code.co_varnames[i] for i in positions}
    if names & set(code.co_cellvars):
        return False
    return not any(ins.argval in names for ins in dis.get_instructions(code) if ins.opname.startswith("LOAD_"))


def _call(msg: dict, modules: dict, channel: Channel):
    """The function's value; with ``then`` the reward of the same state and info computed right after it (for a
    reward function that reads neither ``obs`` nor ``action``; see :mod:`gendex_envs.sandbox.host`); with ``trace``
    the call recorded as a graph the parent may replay (:mod:`gendex_envs.sandbox.trace`)."""
    fns = modules[msg["id"]]
    snapshot = {tuple(k): v for k, v in msg["snapshot"]}
    view = RemoteView(snapshot, channel, msg["static"])
    channel.running = msg["fn"]
    args = msg["args"]
    if msg.get("trace"):
        sources: dict[int, tuple] = {}
        keep: list = []
        for key, v in snapshot.items():
            trace.sources_of(v, ("m", *key), sources, keep)
        trace.sources_of(list(args), ("a",), sources, keep)
        channel.tracer = tracer = trace.Tracer(sources, keep)
        try:
            with tracer:
                value = fns[msg["fn"]](view, *(view_args(a) for a in args))
        finally:
            channel.tracer = None
        return value, None, tracer.finish(value)
    value = fns[msg["fn"]](view, *(view_args(a) for a in args))
    if not msg.get("then"):
        return value, None, None
    channel.running = "compute_dense_reward"
    try:  # any failure here is the real call's to report, when the env makes it
        early = fns["compute_dense_reward"](view, None, None, view_args(args[-1]))
    except Exception:
        return value, None, None
    return value, [early], None


def _line(exc: BaseException) -> int | None:
    """The line of the deepest frame of a reward module in ``exc``'s traceback (the parent names it)."""
    line, tb = None, exc.__traceback__
    while tb is not None:
        if tb.tb_frame.f_globals.get("__name__", "").startswith("gendex_reward_"):
            line = tb.tb_lineno
        tb = tb.tb_next
    return line


def serve(rfd: int, wfd: int) -> None:
    channel, modules = Channel(rfd, wfd), {}
    while True:
        try:
            msg = protocol.read_frame(rfd)
        except EOFError:
            return
        op = msg.get("op")
        channel.remote_errors.clear()
        try:
            if op == "load":
                channel.send(_load(msg, modules))
            elif op == "call":
                start = time.perf_counter()
                value, early, graph = _call(msg, modules, channel)
                tensors: list = []
                header = {"op": "ret", "value": protocol.encode(value, tensors),
                          "then": protocol.encode(early, tensors), "busy_s": time.perf_counter() - start}
                if graph is not None:
                    try:
                        header["graph"] = protocol.encode(graph, tensors)
                    except protocol.ProtocolError as exc:
                        header["graph"] = {"$d": [["failed", f"not sent: {exc}"[:500]]]}
                protocol.write_frame(channel.wfd, header, tensors)
            elif op == "exit":
                return
            else:
                channel.send({"op": "exc", "type": "ProtocolError", "msg": f"unknown request {str(op)[:50]}"})
        except BaseException as exc:
            try:
                channel.send({"op": "exc", "type": type(exc).__name__, "msg": str(exc)[:4000], "line": _line(exc),
                              "args": [str(a)[:4000] if isinstance(a, str) else a for a in exc.args[:4]]
                              if all(a is None or isinstance(a, str | int | float) for a in exc.args) else None,
                              "remote": id(exc) in channel.remote_errors,
                              "memory": isinstance(exc, MemoryError) or "can't allocate memory" in str(exc)})
            except BaseException:
                return


def main() -> None:
    parent, memory, cpu = (int(a) for a in sys.argv[1:4])
    rfd, wfd = os.dup(0), os.dup(1)
    null = os.open(os.devnull, os.O_RDWR)
    os.dup2(null, 0)
    os.dup2(null, 1)
    os.close(null)
    torch.set_num_threads(1)
    _prepare()
    try:
        walls = confine.confine(parent, memory, cpu)
    except confine.ConfinementError as exc:
        protocol.write_frame(wfd, {"op": "unconfined", "msg": str(exc)}, [])
        os._exit(3)
    protocol.write_frame(wfd, {"op": "ready", "walls": walls, "pid": os.getpid()}, [])
    serve(rfd, wfd)


if __name__ == "__main__":
    main()
