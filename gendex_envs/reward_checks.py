"""What a reward module's functions may return, checked on every call: one set of rules, one place.

The reward probe (:mod:`generator.steps.probe_child`) runs a candidate module for its first 20 steps; code that
behaves for 20 steps and then returns NaN, replaces the env's observations or adds a key that other tools read as
success would pass it. So the env and the judge check every output on every call, at the three places where a
reward module's output enters GenDex:

* :meth:`gendex_envs.success.Judge.evaluate` takes ``evaluate``'s output (:func:`check_evaluate`);
* :meth:`gendex_envs.task_env.TaskEnv.compute_dense_reward` takes the reward (:func:`check_reward`);
* :meth:`gendex_envs.task_env.TaskEnv._get_obs_extra` takes the task observations (:func:`check_obs_extra`).

The checks sit at these call sites, not inside the module's functions, so that they hold for every
:class:`~gendex_envs.reward_module.RewardModule`, whoever built it: one from
:func:`~gendex_envs.reward_module.load_reward_module`, one whose functions run in another process and send their
outputs back, or the probe's own wrapper. Committed (trusted) modules are checked too; every committed module
passes, and the checks cost a few microseconds per step (docs/security.md, "Per-step checks").

The rules:

``evaluate(env)``
    a mapping of at most :data:`MAX_KEYS` entries; each key a lower-case name (``[a-z][a-z0-9_]*``, at most
    :data:`MAX_KEY_CHARS` characters) that is not ``success`` (the spec decides it) nor one of
    :data:`RESERVED_INFO_KEYS` (keys that Gymnasium, ManiSkill, Stable-Baselines3 or GenDex's own tools read as
    success or as episode bookkeeping); each value a tensor ``[num_envs, ...]`` on the env's device of at most
    :data:`MAX_VALUES_PER_ENV` values per env; ``fail``, if present, a bool tensor ``[num_envs]``; floating values
    finite and within ``±``:data:`MAX_ABS_VALUE`.
``compute_dense_reward(env, obs, action, info)``
    a floating tensor ``[num_envs]`` on the env's device, finite and within ``±``:data:`MAX_ABS_VALUE`.
``_get_obs_extra(env, info)``
    a mapping of at most :data:`MAX_KEYS` entries, keys as for ``evaluate`` and none of the env's own observation
    names (``palm_pose``, ``tip_pos``, ``<object>_pose``, ``<object>_qpos``, ``goal_pos``) nor the agent's
    (``qpos``, ``qvel``, ``controller``) nor the observation's top-level names (:data:`RESERVED_OBS_KEYS`); each
    value a float, bool or integer tensor ``[num_envs]`` or ``[num_envs, k]`` on the env's device, ``k`` at most
    :data:`MAX_VALUES_PER_ENV`; floating and integer values finite and within ``±``:data:`MAX_ABS_VALUE`.

A broken rule raises :class:`RewardOutputError`, naming the module, the function, the step, what was returned and
what is allowed. The checks run only on what the functions return; the ``info`` reward code receives is filtered
separately (:func:`gendex_envs.reward_view.reward_info` hides ``elapsed_steps``).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

import torch

from gendex_envs.errors import RewardModuleError

MAX_KEYS = 64
"""Entries ``evaluate`` or ``_get_obs_extra`` may return (committed modules return at most 6)."""
MAX_KEY_CHARS = 64
MAX_VALUES_PER_ENV = 1024
"""Values per env in one returned tensor (committed modules' largest is 15: five fingertips' positions)."""
MAX_ABS_VALUE = 1e9
"""Bound on every floating value returned. Committed rewards lie in [-5, 5] and observations are metres, radians,
newtons or fractions; 1e9 leaves room for any unit while keeping sums of rewards and normalised observations far
from float32's overflow."""
KEY_PATTERN = re.compile(r"[a-z][a-z0-9_]*")
RESERVED_INFO_KEYS = frozenset({
    # success, decided by the spec (gendex_envs.success), and what other tools read as success or failure
    "success", "is_success", "success_once", "success_at_end", "fail_once", "fail_at_end",
    # per-episode bookkeeping of ManiSkill (elapsed_steps, reconfigure), Gymnasium's wrappers and vector envs
    # (episode, final_info, final_obs, final_observation, TimeLimit.truncated), SB3 (terminal_observation, and
    # episode's r/l/t) and ManiSkill's recording and evaluation wrappers (return, reward, episode_len)
    "elapsed_steps", "reconfigure", "episode", "episodes", "final_info", "final_obs", "final_observation",
    "terminal_observation", "terminated", "truncated", "return", "reward", "episode_len", "r", "l", "t",
})
"""Keys ``evaluate`` may not return. Names with capitals, dots or a leading underscore (``TimeLimit.truncated``,
``_final_info``) are refused by :data:`KEY_PATTERN` already."""
AGENT_OBS_KEYS = frozenset({"qpos", "qvel", "controller"})
"""The agent's proprioception (ManiSkill ``BaseAgent.get_proprioception``)."""
RESERVED_OBS_KEYS = AGENT_OBS_KEYS | frozenset({"agent", "extra", "sensor_data", "sensor_param", "state"})
"""Observation names a task observation may not take besides the env's own extras (ManiSkill's top-level names)."""


class RewardOutputError(RewardModuleError):
    """A reward module's function returned something outside the interface (:mod:`gendex_envs.reward_checks`)."""

    def __init__(self, path: Path | str | None, fn: str, step: int | None, problem: str):
        self.path, self.fn, self.step, self.problem = path, fn, step, problem
        super().__init__(f"reward module {path}: {when(step)}, {fn} {problem}")

    def __reduce__(self):  # keep the fields through pickling (worker processes)
        return (type(self), (self.path, self.fn, self.step, self.problem))


def when(step: int | None) -> str:
    """``right after reset (step 0)``, ``at step N`` (the probe's wording)."""
    if step is None:
        return "outside a step"
    return "right after reset (step 0)" if step == 0 else f"at step {step}"


def describe(value) -> str:
    """A returned value for messages: type, dtype, shape, device (never its contents)."""
    if isinstance(value, torch.Tensor):
        return f"a {value.dtype} tensor of shape {tuple(value.shape)} on {value.device}"
    if isinstance(value, bool | int | float):
        return f"a Python {type(value).__name__} ({value!r})"
    if value is None:
        return "None"
    return f"a {type(value).__module__}.{type(value).__qualname__}"


class _Problem(Exception):
    """Raised inside the checks; the public functions add the module, function and step."""


def _step_of(step) -> int | None:
    if isinstance(step, torch.Tensor):
        return int(step.max()) if step.numel() else None
    return None if step is None else int(step)


def _raise(path, fn: str, step, problem: str):
    raise RewardOutputError(path, fn, _step_of(step), problem) from None


def _device_code(device: torch.device) -> int:
    """What ``Tensor.get_device()`` returns on ``device`` (-1 for the CPU; -2: any CUDA device)."""
    return -1 if device.type == "cpu" else (-2 if device.index is None else device.index)


def _same_device(value: torch.Tensor, want: int) -> bool:
    got = value.get_device()  # an int, cheaper than building value.device
    return got == want or (want == -2 and got >= 0)


def _check_key(key, what: str) -> None:
    if not isinstance(key, str):
        raise _Problem(f"returned the non-string key {describe(key)}; {what} keys are names matching "
                       f"[a-z][a-z0-9_]* of at most {MAX_KEY_CHARS} characters")
    if len(key) > MAX_KEY_CHARS or not KEY_PATTERN.fullmatch(key):
        raise _Problem(f"returned the key {key[:MAX_KEY_CHARS]!r}{'...' if len(key) > MAX_KEY_CHARS else ''}; "
                       f"{what} keys are names matching [a-z][a-z0-9_]* of at most {MAX_KEY_CHARS} characters")


def _check_count(out, kind: str, what: str) -> None:
    if not isinstance(out, Mapping):
        raise _Problem(f"returned {describe(out)}; expected {kind}")
    if len(out) > MAX_KEYS:
        raise _Problem(f"returned {len(out)} {what} entries; at most {MAX_KEYS} are allowed")


def _check_leading(key: str, value, n: int, device: torch.device, want: int, what: str) -> None:
    if not isinstance(value, torch.Tensor) or value.dim() == 0 or value.shape[0] != n:
        raise _Problem(f"returned {key!r} as {describe(value)}; every {what} entry must be a tensor with leading "
                       f"dimension num_envs={n} ([num_envs, ...])")
    if value.numel() > n * MAX_VALUES_PER_ENV:
        raise _Problem(f"returned {key!r} as {describe(value)}; at most {MAX_VALUES_PER_ENV} values per env are "
                       "allowed")
    if value.is_complex():
        raise _Problem(f"returned {key!r} as {describe(value)}; complex tensors are not allowed (float, bool or "
                       "integer)")
    if not _same_device(value, want):
        raise _Problem(f"returned {key!r} on {value.device}; expected the env's device {device} (create tensors "
                       "with device=env.device)")


def _bad_values(value: torch.Tensor, what: str) -> str:
    """Why ``value`` (floating) breaks the value bound: which kinds, in which envs."""
    kinds = [k for k, bad in (("NaN", torch.isnan(value)), ("inf", torch.isinf(value))) if bool(bad.any())]
    finite = torch.isfinite(value)
    big = finite & (value.abs() > MAX_ABS_VALUE)
    bad = ~finite | big
    envs = bad.reshape(bad.shape[0], -1).any(dim=1).nonzero().flatten()[:8].tolist() if bad.dim() else []
    parts = []
    if kinds:
        parts.append(f"non-finite values ({'/'.join(kinds)})")
    if bool(big.any()):
        parts.append(f"values beyond ±{MAX_ABS_VALUE:g}")
    return (f"returned {' and '.join(parts)} in {what} for env(s) {envs}; values must be finite and within "
            f"±{MAX_ABS_VALUE:g} (guard divisions, logs and square roots, e.g. clamp denominators with "
            ".clamp(min=1e-6))")


SMALL_CPU_TENSOR = 256
"""Up to this many values, a CPU tensor is checked in Python (``tolist``: about 1 us) rather than by torch
reductions (about 5 us each)."""


def _within(value: torch.Tensor) -> bool:
    """Every value of ``value`` (floating) finite and within the bound. NaN fails every comparison."""
    if value.numel() <= SMALL_CPU_TENSOR and value.get_device() == -1:
        return all(-MAX_ABS_VALUE <= x <= MAX_ABS_VALUE for x in value.detach().reshape(-1).tolist())
    if not value.is_floating_point():  # integers: abs() of the most negative one is itself, so compare both ends
        return bool(value.min() >= -MAX_ABS_VALUE) and bool(value.max() <= MAX_ABS_VALUE)
    return bool(value.detach().abs().max() <= MAX_ABS_VALUE)


def _is_integer(value: torch.Tensor) -> bool:
    return not value.is_floating_point() and not value.is_complex() and value.dtype != torch.bool


def _check_values(entries: list[tuple[str | None, torch.Tensor]]) -> None:
    """Every floating or integer tensor of ``entries`` finite and within the bound (on an accelerator: one
    reduction, one synchronisation, when they all are)."""
    floats = [(k, v) for k, v in entries if (v.is_floating_point() or _is_integer(v)) and v.numel()]
    if not floats:
        return
    if floats[0][1].get_device() != -1 and len(floats) > 1:
        flat = torch.cat([v.detach().reshape(-1).float() for _, v in floats])
        if bool(flat.abs().max() <= MAX_ABS_VALUE):
            return
    for key, value in floats:
        if not _within(value):
            raise _Problem(_bad_values(value.detach(), "the reward" if key is None else repr(key)))


def check_evaluate(info, n: int, device: torch.device | str, *, path=None, step=None) -> dict:
    """``evaluate``'s output checked (module doc); returns it as a new dict. ``step`` may be the env's
    ``elapsed_steps`` tensor: it is read only to name the step in an error."""
    device = torch.device(device)
    want = _device_code(device)
    try:
        _check_count(info, "a dict with 'fail' ([num_envs] bool tensor) and [num_envs, ...] diagnostics", "info")
        info = dict(info)
        for key in info:
            _check_key(key, "info")
            if key == "success":
                raise _Problem("returned 'success', but success is declared in the task spec (success.conditions, "
                               "stages[].success) and decided by the env; return 'fail' and diagnostics only")
            if key in RESERVED_INFO_KEYS:
                raise _Problem(f"returned the key {key!r}, which Gymnasium, ManiSkill or GenDex's tools read as "
                               f"success or episode bookkeeping; rename it (reserved: {sorted(RESERVED_INFO_KEYS)})")
        fail = info.get("fail")
        if fail is not None and not (isinstance(fail, torch.Tensor) and fail.dtype == torch.bool
                                     and tuple(fail.shape) == (n,)):
            expected = f"a torch.bool tensor of shape ({n},) on {device}"
            if not isinstance(fail, torch.Tensor):
                raise _Problem(f"returned 'fail' as {describe(fail)}; expected {expected}")
            if fail.dtype != torch.bool:
                raise _Problem(f"returned 'fail' as {describe(fail)}; expected {expected} (use a comparison such as "
                               "`dist < 0.05`, or `.bool()`)")
            raise _Problem(f"returned 'fail' as {describe(fail)}; expected shape ({n},), one flag per env "
                           "([num_envs])")
        for key, value in info.items():
            _check_leading(key, value, n, device, want, "info")
        _check_values(list(info.items()))
    except _Problem as p:
        _raise(path, "evaluate", step, str(p))
    return info


def check_reward(reward, n: int, device: torch.device | str, *, path=None, step=None) -> torch.Tensor:
    """``compute_dense_reward``'s output checked (module doc); returns it."""
    device = torch.device(device)
    try:
        expected = f"a float tensor of shape ({n},) on {device}"  # for the messages
        if not isinstance(reward, torch.Tensor):
            raise _Problem(f"returned {describe(reward)}; expected {expected}, one reward per env")
        if not reward.is_floating_point():
            raise _Problem(f"returned {describe(reward)}; expected {expected} (convert with `.float()`)")
        if tuple(reward.shape) != (n,):
            hint = " (drop the trailing dimension, e.g. `.squeeze(-1)`)" if reward.dim() == 2 and \
                reward.shape[0] == n and reward.shape[1] == 1 else ""
            raise _Problem(f"returned {describe(reward)}; expected shape ({n},) ([num_envs]){hint}")
        if not _same_device(reward, _device_code(device)):
            raise _Problem(f"returned the reward on {reward.device}; expected the env's device {device} (create "
                           "tensors with device=env.device)")
        _check_values([(None, reward)])
    except _Problem as p:
        _raise(path, "compute_dense_reward", step, str(p))
    return reward


def check_obs_extra(extra, n: int, device: torch.device | str, taken, *, path=None, step=None) -> dict:
    """``_get_obs_extra``'s output checked (module doc); ``taken``: the env's own observation names (its extras;
    :data:`RESERVED_OBS_KEYS` are added here). Returns it as a new dict."""
    device = torch.device(device)
    want = _device_code(device)
    fn = "_get_obs_extra"
    try:
        _check_count(extra, "a dict of [num_envs, ...] tensors", "observation")
        extra = dict(extra)
        for key, value in extra.items():
            _check_key(key, "observation")
            if key in taken or key in RESERVED_OBS_KEYS:
                own = sorted({*taken, *RESERVED_OBS_KEYS})
                raise _Problem(f"returned the key {key!r}, which would replace the env's own observation of that "
                               f"name (taken: {own}); rename it")
            _check_leading(key, value, n, device, want, "observation")
            if value.dim() > 2:
                raise _Problem(f"returned {key!r} as {describe(value)}; state observations are flattened per env, "
                               "so use at most 2 dimensions (e.g. `.flatten(1)`)")
            if not (value.is_floating_point() or value.dtype in (torch.bool, torch.int32, torch.int64)):
                raise _Problem(f"returned {key!r} as {describe(value)}; expected a float tensor")
        _check_values(list(extra.items()))
    except _Problem as p:
        _raise(path, fn, step, str(p))
    return extra
