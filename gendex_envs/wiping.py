"""Wiping: which marks of a wipe area an object pressed on it has passed over, per env, over an episode.

A wipe area (a spill: an asset whose params give its marks, :func:`spill_marks`, on its top at
``params["top_z_m"]``) is wiped by an object (a sponge) that slides over it pressed down. After each control step,
for every ``wiped`` condition of the task (its success, its sequence's steps, its stages'), a mark becomes wiped in
an env when, at that step,

- the object and the area touch with a net contact force of at least the condition's ``min_press_n`` (the simulator's
  contact forces between the two bodies: a sponge lying on the stain under its own weight, 0.25 N, presses too little),
- and the mark lies within :data:`MARK_PAD_M` of the object's box (its bounding box, at its pose): under the face that
  presses, whichever face that is.

A wiped mark stays wiped until the episode ends. The state is per env ([N, M] booleans), batched, and reset with each
episode, so the GPU backend keeps working. :func:`gendex_envs.success.condition_holds` reads the share wiped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import torch

from gendex_envs.errors import TaskSpecError
from gendex_envs.geometry import quat_conj, quat_rotate

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.conditions import ConditionSpec
    from gendex_envs.task_env import TaskEnv

MARK_PAD_M = 0.008
"""A mark counts as under the pressing object within this distance of the object's box: a sponge's edges round off
3-5 mm, and a mark is a point where a stain is a few centimetres across."""


def press_of(c: ConditionSpec) -> float:
    from gendex_envs.conditions import CONDITION_DEFAULTS

    return CONDITION_DEFAULTS["min_press_n"] if c.min_press_n is None else c.min_press_n


@dataclass
class _Wipe:
    wiper: str
    area: str
    press_n: float
    marks: torch.Tensor
    """[M, 3] the area's marks in its frame (at the object's scale), on its top."""
    lo: torch.Tensor
    hi: torch.Tensor
    """[3] the wiper's box in its frame (scaled)."""
    done: torch.Tensor
    """[N, M] marks wiped so far this episode."""
    force: torch.Tensor
    """[N] the net contact force between the wiper and the area at the last update (N)."""


def spill_marks(params: dict) -> list[tuple[float, float]]:
    """The marks (x, y in metres, the area's frame, centred) of a wipe area with these catalog params: a grid of
    ``marks_pitch_m`` centred on it, at least ``marks_inset_m`` inside its edge: a disc ``size_x_m`` across
    (``shape: round``) or a ``size_x_m`` x ``size_y_m`` rectangle. No marks without ``marks_pitch_m``."""
    pitch = params.get("marks_pitch_m")
    if not pitch:
        return []
    inset, sx = float(params["marks_inset_m"]), float(params["size_x_m"])
    sy = sx if params.get("shape") == "round" else float(params["size_y_m"])
    nx, ny = (int((s - 2 * inset) / pitch + 1e-9) + 1 for s in (sx, sy))
    out = []
    for i in range(nx):
        for j in range(ny):
            x, y = (i - (nx - 1) / 2) * pitch, (j - (ny - 1) / 2) * pitch
            if params.get("shape") != "round" or math.hypot(x, y) <= sx / 2 - inset + 1e-9:
                out.append((round(x, 4), round(y, 4)))
    return out


def area_marks(env: TaskEnv, name: str) -> torch.Tensor:
    """[M, 3] the marks of wipe area ``name`` in its frame (scaled); TaskSpecError if its asset has none."""
    rec = env.asset_record(name)
    marks = spill_marks(rec.entry.params) if not rec.articulated else None
    if not marks:
        raise TaskSpecError(f"object {name!r} (asset {rec.id!r}) has no marks to wipe: the target of a 'wiped' "
                            "condition is a wipe area (an asset tagged wipe_area, e.g. spill_round)")
    scale = env.task_spec.object(name).scale
    top = float(rec.entry.params.get("top_z_m", 0.0))
    return torch.tensor([[x, y, top] for x, y in marks], dtype=torch.float32, device=env.device) * scale


class Wipes:
    """The ``wiped`` conditions' marks of one env's scene (module docstring); :meth:`update` after each control
    step, :meth:`reset` with each episode."""

    def __init__(self, env: TaskEnv):
        self.env = env
        self.items: dict[tuple[str, str, float], _Wipe] = {}
        spec = env.task_spec
        conds = [*spec.success.conditions, *(c for s in spec.success.sequence or () for c in s.conditions),
                 *(c for s in spec.stages for c in s.success or ())]
        for c in conds:
            if c.type != "wiped" or self.key(c) in self.items:
                continue
            rec = env.asset_record(c.object)
            scale = spec.object(c.object).scale
            box = [torch.tensor(b, dtype=torch.float32, device=env.device) * scale
                   for b in (rec.bbox_min_m, rec.bbox_max_m)]
            marks = area_marks(env, c.target)
            done = torch.zeros(env.num_envs, marks.shape[0], dtype=torch.bool, device=env.device)
            self.items[self.key(c)] = _Wipe(c.object, c.target, press_of(c), marks, box[0], box[1], done,
                                            torch.zeros(env.num_envs, device=env.device))

    @staticmethod
    def key(c: ConditionSpec) -> tuple[str, str, float]:
        return c.object, c.target, press_of(c)

    def reset(self, env_idx: torch.Tensor) -> None:
        for w in self.items.values():
            w.done[env_idx] = False
            w.force[env_idx] = 0.0

    def update(self) -> None:
        env = self.env
        for w in self.items.values():
            force = env.scene.get_pairwise_contact_forces(env.obj(w.wiper), env.obj(w.area))  # [N, 3]
            w.force = torch.linalg.norm(force, dim=-1)
            pressed = w.force >= w.press_n
            if not bool(pressed.any()):
                continue
            area, wiper = env.obj_pose(w.area), env.obj_pose(w.wiper)
            n, m = pressed.shape[0], w.marks.shape[0]
            world = area.p[:, None, :] + quat_rotate(area.q[:, None, :].expand(n, m, 4), w.marks[None].expand(n, m, 3))
            local = quat_rotate(quat_conj(wiper.q)[:, None, :].expand(n, m, 4), world - wiper.p[:, None, :])
            gap = torch.linalg.norm(local - local.clamp(w.lo, w.hi), dim=-1)  # [N, M] distance to the box
            w.done |= pressed[:, None] & (gap <= MARK_PAD_M)

    def wiped(self, c: ConditionSpec) -> torch.Tensor:
        """[N, M] the marks condition ``c`` has wiped so far."""
        return self.items[self.key(c)].done

    def force(self, c: ConditionSpec) -> torch.Tensor:
        """[N] how hard condition ``c``'s object pressed on its target at the last update (N)."""
        return self.items[self.key(c)].force

    def share_of(self, wiper: str, area: str) -> torch.Tensor:
        """[N] the share of ``area``'s marks ``wiper`` has wiped so far (the most of its ``wiped`` conditions);
        TaskSpecError when no condition of the task wipes ``area`` with ``wiper``."""
        done = [w.done for w in self.items.values() if (w.wiper, w.area) == (wiper, area)]
        if not done:
            pairs = sorted({(w.wiper, w.area) for w in self.items.values()})
            raise TaskSpecError(f"no 'wiped' condition of the task wipes {area!r} with {wiper!r}; it wipes: "
                                f"{pairs or 'nothing'}")
        return torch.stack([d.float().mean(dim=1) for d in done]).amax(dim=0)

    def share(self, c: ConditionSpec) -> torch.Tensor:
        """[N] the share of the target's marks condition ``c``'s object has wiped so far this episode."""
        return self.wiped(c).float().mean(dim=1)

