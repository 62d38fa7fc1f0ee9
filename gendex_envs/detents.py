"""Detents: springs that hold a button or switch in its rest positions.

A joint whose catalog entry lists ``detents`` (fractions from closed to open) and a ``spring`` stiffness gets a
PhysX joint drive of that stiffness; before each control step its target is the rest position nearest to where the
joint is now. A momentary button (one detent, up) springs back when let go; a switch or a latching button (detents
at both ends) snaps to whichever end it was pushed past the middle and stays there, so a press has to carry the
part past the middle: pushing it a little and letting go undoes nothing and does nothing. The drive is a real force
in the simulation (the hand feels it), set per env from batched joint positions, so the GPU backend keeps working.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import torch

if TYPE_CHECKING:
    from gendex_envs.task_env import TaskEnv

DAMPING_RATIO = 0.05
"""Drive damping as a share of the spring's stiffness (N·s/m per N/m, or N·m·s/rad per N·m/rad): enough to stop
a released switch ringing, little enough that it still snaps within a control step or two."""


@dataclass
class _Detent:
    name: str
    joint: object
    """The ManiSkill ``ArticulationJoint``."""
    index: int
    rests: torch.Tensor
    """[K] the rest joint positions (at the object's scale)."""


class Detents:
    """The detented joints of one env's scene; :meth:`update` before each control step."""

    def __init__(self, env: TaskEnv):
        self.env = env
        self.items: list[_Detent] = []
        for name, art in env.articulations.items():
            for j in env.asset_record(name).joints:
                if not j.detents or not j.spring:
                    continue
                lo, hi = env.closed_qpos(name, j.name), env.open_qpos(name, j.name)
                rests = torch.tensor([lo + f * (hi - lo) for f in j.detents], dtype=torch.float32, device=env.device)
                joint = art.joints_map[j.name]
                joint.set_drive_properties(stiffness=j.spring, damping=DAMPING_RATIO * j.spring, mode="force")
                self.items.append(_Detent(name, joint, env.joint_index(name, j.name), rests))

    def __bool__(self) -> bool:
        return bool(self.items)

    def targets(self) -> dict[str, torch.Tensor]:
        """[N] the rest position each detented joint is pulled towards now, by ``object/joint``."""
        out = {}
        for d in self.items:
            q = self.env.articulations[d.name].get_qpos()[:, d.index]
            out[f"{d.name}/{d.joint.name}"] = d.rests[torch.argmin((q[:, None] - d.rests[None, :]).abs(), dim=1)]
        return out

    def update(self) -> None:
        for d, target in zip(self.items, self.targets().values(), strict=True):
            d.joint.set_drive_target(target)
        if self.items and self.env.gpu_sim_enabled:  # ManiSkill applied the robot's targets before this call
            self.env.scene.px.gpu_apply_articulation_target_position()


__all__ = ["DAMPING_RATIO", "Detents"]
