"""The space a moving link holds things in: a drawer's bin (:attr:`~gendex_envs.assets.manifest.JointEntry.holds_m`).

*Put the can in the drawer* is an ``inside`` condition with a ``joint``: the can lies in the box the drawer's link
carries, wherever the drawer has slid to (it still counts once the drawer is shut on it). Batched over envs, like
:mod:`gendex_envs.success`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import torch

from gendex_envs.errors import TaskSpecError
from gendex_envs.geometry import quat_rotate, transform_points
from gendex_envs.physx import read_pose

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.task_env import TaskEnv

HOLDS_MARGIN_M = 0.01
"""An object counts as in a bin when its rest point is this far within the bin's walls (xy)."""
HOLDS_FLOOR_TOL_M = 0.01
"""... and from this far below the bin's floor (a seated object sinks a little into it) to its walls' top."""


def holds_box(env: TaskEnv, name: str, joint: str | None = None) -> tuple[torch.Tensor, torch.Tensor]:
    """([3], [3]) the low and high corners of the space ``name``'s joint's link holds things in, in that link's
    frame, scaled; :class:`~gendex_envs.errors.TaskSpecError` when the link holds nothing (a door, a lid)."""
    key = (name, joint)
    cache = env.__dict__.setdefault("_holds_boxes", {})
    if key not in cache:
        jr = env.joint_record(name, joint)
        if jr.holds_m is None:
            raise TaskSpecError(f"joint {jr.name!r} of {name!r} (asset {env.asset_record(name).id!r}) moves a link "
                                "that holds nothing; only a joint with holds_m (a drawer) can be put into")
        scale = env.task_spec.object(name).scale
        cache[key] = tuple(torch.tensor(c, dtype=torch.float32, device=env.device) * scale for c in jr.holds_m)
    return cache[key]


def holds_point(env: TaskEnv, name: str, joint: str | None = None) -> torch.Tensor:
    """[N, 3] world point at the middle of the floor of the part of the space ``name``'s joint's link holds things
    in that is out of the body now: a drawer slides out along -x of its frame (the asset convention), so after
    sliding q the part of its bin at link x < q is out; the whole bin's middle when it is shut."""
    lo, hi = holds_box(env, name, joint)
    pose = read_pose(env.handle_link(name, joint))
    n = pose.p.shape[0]
    x_hi = hi[0].expand(n)
    if env.joint_record(name, joint).type == "prismatic":
        out = env.joint_qpos(name, joint).to(lo.dtype) * env.task_spec.object(name).scale
        x_hi = torch.where(out > lo[0] + HOLDS_MARGIN_M, torch.minimum(x_hi, out), x_hi)
    middle = torch.stack([(lo[0] + x_hi) / 2, ((lo[1] + hi[1]) / 2).expand(n), lo[2].expand(n)], dim=-1)
    return transform_points(pose.p, pose.q, middle)


def holds_local(env: TaskEnv, name: str, joint: str | None, point: torch.Tensor) -> torch.Tensor:
    """[N, 3] world points ``point`` in the frame of ``name``'s joint's link."""
    pose = read_pose(env.handle_link(name, joint))
    conj = pose.q * torch.tensor([1.0, -1.0, -1.0, -1.0], dtype=pose.q.dtype, device=pose.q.device)
    return quat_rotate(conj, point - pose.p)


def in_holds(env: TaskEnv, name: str, joint: str | None, point: torch.Tensor) -> torch.Tensor:
    """[N] bool: world points ``point`` [N, 3] lie in the space ``name``'s joint's link holds things in
    (:data:`HOLDS_MARGIN_M` within its walls, from :data:`HOLDS_FLOOR_TOL_M` under its floor to its walls' top)."""
    lo, hi = holds_box(env, name, joint)
    local = holds_local(env, name, joint, point)
    xy = ((local[:, :2] >= lo[:2] + HOLDS_MARGIN_M) & (local[:, :2] <= hi[:2] - HOLDS_MARGIN_M)).all(dim=1)
    return xy & (local[:, 2] >= lo[2] - HOLDS_FLOOR_TOL_M) & (local[:, 2] <= hi[2])


__all__ = ["HOLDS_FLOOR_TOL_M", "HOLDS_MARGIN_M", "holds_box", "holds_local", "holds_point", "in_holds"]
