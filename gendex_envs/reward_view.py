"""The read-only view of a task env that reward code receives: capabilities, not handles.

Reward modules (:mod:`gendex_envs.reward_module`) are written by a language model and shipped in task folders that
users download. They are handed a :class:`RewardView` in place of the env. The view offers exactly the members the
environment-API prompt (``prompts/env_api.txt``) documents, under the same names, so reward code reads
``env.obj_pose("apple").p`` as before; but

* every tensor it returns is a fresh copy: an in-place write (``add_``, ``x[:] = 0``, ``out=``) changes only the
  caller's copy, never the simulator, the env's recorded reset poses or the success it reports;
* it hands out no scene entity, articulation, agent, controller or env: ``env.obj(NAME)`` and
  ``env.handle_link(NAME)`` return an :class:`EntityView` (a name plus read-only velocity and pose), and
  ``env.agent`` is an :class:`AgentView` whose only members are the documented force and joint readings;
* the view stores no reference to the env at all. Which env a view reads is kept in this module's private
  registry (view -> weak reference to the env), so reaching the env from reward code would take either importing
  this module or a dunder (``__globals__``, ``__closure__``); the static check and the runtime guard refuse both
  (:mod:`gendex_envs.code_check`, :mod:`gendex_envs.guard`). Views have no ``__dict__``: attributes cannot
  be added or replaced.

``info``, ``obs`` and ``action`` passed to reward functions are copies as well (a read-only :class:`TensorsView`
that copies each entry read, or :func:`copy_tensors`), so writing into ``info["success"]`` cannot change what the
env reports. The ``info`` reward code receives also lacks the env's per-episode bookkeeping
(:data:`HIDDEN_INFO_KEYS`, :func:`reward_info`): a reward that knew the step count could behave during the reward
probe's first steps and misbehave after them without keeping any state of its own.
"""

from __future__ import annotations

import weakref
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import torch

from gendex_envs import pouring
from gendex_envs.holds import holds_point

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.task_env import TaskEnv

_SOURCES: weakref.WeakKeyDictionary[RewardView, weakref.ReferenceType] = weakref.WeakKeyDictionary()
"""view -> weak reference to the env it reads (the view itself holds none)."""
_VIEWS: weakref.WeakKeyDictionary[Any, RewardView] = weakref.WeakKeyDictionary()
"""env -> its one view (views are immutable, so one per env is shared by every call)."""


class ViewError(RuntimeError):
    """The env behind a view is gone (the view outlived it)."""


def _env(view: RewardView) -> TaskEnv:
    ref = _SOURCES.get(view)
    env = ref() if ref is not None else None
    if env is None:
        raise ViewError("this reward view's env has been closed; views are valid only while their env lives")
    return env


def _fresh(x: torch.Tensor) -> torch.Tensor:
    return x.clone()  # simulator state never requires grad: a clone shares nothing with it


def copy_tensors(value: Any) -> Any:
    """A deep copy of tensors inside dicts, lists and tuples (other leaves are returned as they are)."""
    if isinstance(value, torch.Tensor):
        return value.clone()
    if isinstance(value, dict):
        return {k: v.clone() if isinstance(v, torch.Tensor) else copy_tensors(v) for k, v in value.items()}
    if isinstance(value, Mapping):
        return {k: copy_tensors(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return type(value)(copy_tensors(v) for v in value)
    return value


HIDDEN_INFO_KEYS = frozenset({"elapsed_steps"})
"""Keys of the env's ``info`` that reward code does not see: ManiSkill's per-episode step count. ``evaluate`` may
not return them or any other bookkeeping key (:data:`gendex_envs.reward_checks.RESERVED_INFO_KEYS`), so the info
reward code reads holds ``success``, ``fail`` and the module's own diagnostics only."""


def reward_info(info: Any) -> Any:
    """``info`` as reward code may see it: without :data:`HIDDEN_INFO_KEYS` (a new dict, only when one is there)."""
    if isinstance(info, Mapping) and not HIDDEN_INFO_KEYS.isdisjoint(info.keys()):
        return {k: v for k, v in info.items() if k not in HIDDEN_INFO_KEYS}
    return info


class TensorsView(Mapping):
    """A read-only mapping over ``obs`` or ``info`` for reward code: reading an entry returns what
    :func:`copy_tensors` would have copied for it (a fresh tensor, nested dicts as further views), made only for the
    entries the code reads. Most reward modules read one or two entries of ``info`` and none of ``obs``; copying all
    of them cost about 15 us a step."""

    __slots__ = ("_data",)

    def __init__(self, data: Mapping):
        object.__setattr__(self, "_data", data)

    def __setattr__(self, key, value):
        raise AttributeError(f"reward views are read-only (cannot set {key!r})")

    def __getitem__(self, key):
        value = self._data[key]
        if isinstance(value, torch.Tensor):
            return value.clone()
        if isinstance(value, Mapping):
            return TensorsView(value)
        return copy_tensors(value)

    def __iter__(self):
        return iter(list(self._data))

    def __len__(self) -> int:
        return len(self._data)

    def __repr__(self) -> str:
        return f"TensorsView({list(self._data)})"


def view_args(value: Any) -> Any:
    """What a reward function receives for an ``obs``, ``action`` or ``info`` argument: a :class:`TensorsView` over
    a mapping, else a deep copy (:func:`copy_tensors`)."""
    return TensorsView(value) if isinstance(value, Mapping) else copy_tensors(value)


class PoseView:
    """A pose as reward code sees it: ``p`` [N, 3], ``q`` [N, 4] (wxyz) and ``raw_pose`` [N, 7], each a fresh copy
    made when it is read (reward code mostly reads ``p`` alone)."""

    __slots__ = ("_raw",)

    def __init__(self, raw_pose: torch.Tensor):
        object.__setattr__(self, "_raw", raw_pose)

    def __setattr__(self, key, value):
        raise AttributeError(f"reward views are read-only (cannot set {key!r})")

    @property
    def p(self) -> torch.Tensor:
        return self._raw[..., :3].clone()

    @property
    def q(self) -> torch.Tensor:
        return self._raw[..., 3:].clone()

    @property
    def raw_pose(self) -> torch.Tensor:
        """[N, 7]: p then q."""
        return self._raw.clone()

    def __repr__(self) -> str:
        return f"PoseView(p={self.p.tolist()}, q={self.q.tolist()})"


def _pose(pose) -> PoseView:
    return PoseView(pose.raw_pose)


class EntityView:
    """An object (or an articulated object's handle link) named for the force and velocity readings: no handle."""

    __slots__ = ("_view", "name", "part", "joint")

    def __init__(self, view: RewardView, name: str, part: str | None = None, joint: str | None = None):
        object.__setattr__(self, "_view", view)
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "part", part)
        object.__setattr__(self, "joint", joint)

    def __setattr__(self, key, value):
        raise AttributeError(f"reward views are read-only (cannot set {key!r})")

    def _entity(self):
        env = _env(self._view)
        return env.handle_link(self.name, self.joint) if self.part == "handle" else env.obj(self.name)

    @property
    def pose(self) -> PoseView:
        return _pose(self._entity().pose)

    @property
    def linear_velocity(self) -> torch.Tensor:
        """[N, 3] m/s."""
        return _fresh(self._entity().linear_velocity)

    @property
    def angular_velocity(self) -> torch.Tensor:
        """[N, 3] rad/s."""
        return _fresh(self._entity().angular_velocity)

    def __repr__(self) -> str:
        return f"EntityView({self.name!r}{', ' + self.part if self.part else ''})"


class RobotView:
    """``env.agent.robot``: joint readings only."""

    __slots__ = ("_view",)

    def __init__(self, view: RewardView):
        object.__setattr__(self, "_view", view)

    def __setattr__(self, key, value):
        raise AttributeError(f"reward views are read-only (cannot set {key!r})")

    def get_qpos(self) -> torch.Tensor:
        """[N, 30]: 6 arm joints, then the 24 hand joints."""
        return _fresh(_env(self._view).agent.robot.get_qpos())

    def get_qvel(self) -> torch.Tensor:
        return _fresh(_env(self._view).agent.robot.get_qvel())


class AgentView:
    """``env.agent``: the hand's contact forces and the robot's joints, nothing that acts."""

    __slots__ = ("_view", "robot")

    def __init__(self, view: RewardView):
        object.__setattr__(self, "_view", view)
        object.__setattr__(self, "robot", RobotView(view))

    def __setattr__(self, key, value):
        raise AttributeError(f"reward views are read-only (cannot set {key!r})")

    def get_hand_group_obj_mean_force(self, entity: EntityView) -> torch.Tensor:
        """[N, 6, 1] mean contact force (N) of each hand group (th, ff, mf, rf, lf, palm) on ``entity``."""
        if not isinstance(entity, EntityView):
            raise TypeError(f"get_hand_group_obj_mean_force takes env.obj(NAME) or env.handle_link(NAME), got "
                            f"{type(entity).__name__}")
        env = _env(self._view)
        return _fresh(env.hand_forces(entity.name, entity.part, entity.joint))[..., None]


class RewardView:
    """What ``evaluate``, ``compute_dense_reward`` and ``_get_obs_extra`` receive as ``env`` (see the module doc)."""

    __slots__ = ("__weakref__", "num_envs", "device", "table_height", "object_names", "stage_targets", "agent")

    def __init__(self, env: TaskEnv):
        _SOURCES[self] = weakref.ref(env)
        spec = env.task_spec
        for key, value in (("num_envs", int(env.num_envs)), ("device", torch.device(env.device)),
                           ("table_height", float(env.table_height)),
                           ("object_names", tuple(o.name for o in spec.objects)),
                           ("stage_targets", tuple(s.target for s in spec.stages)),
                           ("agent", AgentView(self))):
            object.__setattr__(self, key, value)

    def __setattr__(self, key, value):
        raise AttributeError(f"reward views are read-only (cannot set {key!r})")

    def __delattr__(self, key):
        raise AttributeError(f"reward views are read-only (cannot delete {key!r})")

    def __repr__(self) -> str:
        return f"RewardView({self.num_envs} envs, objects {list(self.object_names)})"

    # ---- objects
    def obj_pose(self, name: str) -> PoseView:
        """Pose of object ``name``: p [N, 3], q [N, 4]."""
        return _pose(_env(self).obj_pose(name))

    def obj(self, name: str) -> EntityView:
        _env(self).obj(name)  # an unknown name raises here, naming the objects
        return EntityView(self, name)

    def init_obj_pos(self, name: str) -> torch.Tensor:
        return _fresh(_env(self).init_obj_pos(name))

    def init_obj_quat(self, name: str) -> torch.Tensor:
        return _fresh(_env(self).init_obj_quat(name))

    def obj_height(self, name: str) -> torch.Tensor:
        return _fresh(_env(self).obj_height(name))

    def hand_forces(self, name: str, part: str | None = None, joint: str | None = None) -> torch.Tensor:
        return _fresh(_env(self).hand_forces(name, part, joint))

    # ---- the hand
    @property
    def palm_pose(self) -> PoseView:
        return _pose(_env(self).palm_pose)

    @property
    def tip_positions(self) -> torch.Tensor:
        return _fresh(_env(self).tip_positions)

    # ---- articulated objects
    def handle_link(self, name: str, joint: str | None = None) -> EntityView:
        _env(self).handle_link(name, joint)  # raises for rigid objects and unknown joints
        return EntityView(self, name, "handle", joint)

    def handle_pos(self, name: str, joint: str | None = None) -> torch.Tensor:
        return _fresh(_env(self).handle_pos(name, joint))

    def joint_qpos(self, name: str, joint: str | None = None) -> torch.Tensor:
        return _fresh(_env(self).joint_qpos(name, joint))

    def joint_open_fraction(self, name: str, joint: str | None = None) -> torch.Tensor:
        return _fresh(_env(self).joint_open_fraction(name, joint))

    def holds_point(self, name: str, joint: str | None = None) -> torch.Tensor:
        """[N, 3] the middle of the floor of the space the joint's link holds things in (a drawer's bin)."""
        return _fresh(holds_point(_env(self), name, joint))

    def poured_share(self, name: str, target: str) -> torch.Tensor:
        """[N] the share of the loose pieces (beads) that started in vessel ``name`` that now lie in container
        ``target`` (:mod:`gendex_envs.pouring`)."""
        return _fresh(pouring.share(_env(self), name, target))

    def wiped_share(self, name: str, target: str) -> torch.Tensor:
        """[N] the share of wipe area ``target``'s marks that ``name`` (a sponge) has wiped, pressed, this episode."""
        return _fresh(_env(self).wipes.share_of(name, target))

    # ---- goal and success
    @property
    def goal_pos(self) -> torch.Tensor:
        return _fresh(_env(self).goal_pos)

    def spec_success(self) -> torch.Tensor:
        """[N] bool: the task file's success conditions hold now."""
        return _fresh(_env(self).spec_success())


def view_of(env: TaskEnv) -> RewardView:
    """The (one, shared, immutable) reward view of ``env`` (a wrapped env is viewed through its ``unwrapped``)."""
    env = getattr(env, "unwrapped", env)
    view = _VIEWS.get(env)
    if view is None:
        view = _VIEWS[env] = RewardView(env)
    return view
