"""Detents: springs that hold a button or switch in its rest positions.

A joint whose catalog entry lists ``detents`` (fractions from closed to open) and a ``spring`` stiffness gets a
PhysX joint drive of that stiffness; before each control step its target is the rest position nearest to where the
joint is now. A momentary button (one detent, up) springs back when let go; a switch or a latching button (detents
at both ends) snaps to whichever end it was pushed past the middle and stays there, so a press has to carry the
part past the middle: pushing it a little and letting go undoes nothing and does nothing. The drive is a real force
in the simulation (the hand feels it), set per env from batched joint positions, so the GPU backend keeps working.

A joint with a ``friction_limit`` (a screw cap's thread) gets dry friction the same way: a stiff drive whose force
is capped at that limit, anchored where the joint stuck. While the joint stays within :data:`FRICTION_SLIP` of its
anchor it sticks (no creep under a steady push below the limit); pushed further, it slips and drags the anchor along,
resisting with the limit; at reset the anchor is where the joint starts. So the joint stays where the hand left it,
moves only while pushed harder than the limit, and cannot coast: a finger brushing past a cap turns it no further
than the finger carries it. (SAPIEN's URDF loader drops the URDF's joint friction.)
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
FRICTION_SLIP = 0.005
"""Deflection (rad or m) at which a friction drive reaches its force limit: how far a joint held by dry friction
gives before it slips."""


@dataclass
class _Detent:
    name: str
    joint: object
    """The ManiSkill ``ArticulationJoint``."""
    index: int
    rests: torch.Tensor | None
    """[K] the rest joint positions (at the object's scale); None: dry friction, held at :attr:`anchor`."""
    anchor: torch.Tensor | None = None
    """[N] where a joint held by dry friction stuck (set at its first update)."""


class Detents:
    """The detented joints of one env's scene; :meth:`update` before each control step."""

    def __init__(self, env: TaskEnv):
        self.env = env
        self.items: list[_Detent] = []
        for name, art in env.articulations.items():
            for j in env.asset_record(name).joints:
                joint = art.joints_map[j.name]
                if j.detents and j.spring:
                    lo, hi = env.closed_qpos(name, j.name), env.open_qpos(name, j.name)
                    rests = torch.tensor([lo + f * (hi - lo) for f in j.detents], dtype=torch.float32,
                                         device=env.device)
                    joint.set_drive_properties(stiffness=j.spring, damping=DAMPING_RATIO * j.spring, mode="force")
                elif j.friction_limit:
                    rests = None
                    damping = float(joint.damping.reshape(-1)[0])  # the URDF's, which the loader set on the drive
                    joint.set_drive_properties(stiffness=j.friction_limit / FRICTION_SLIP, damping=damping,
                                               force_limit=j.friction_limit, mode="force")
                else:
                    continue
                self.items.append(_Detent(name, joint, env.joint_index(name, j.name), rests))

    def __bool__(self) -> bool:
        return bool(self.items)

    def targets(self) -> dict[str, torch.Tensor]:
        """[N] the rest position each detented joint is pulled towards now (a joint held by dry friction: its anchor,
        dragged along first if the joint has slipped past :data:`FRICTION_SLIP`), by ``object/joint``."""
        out = {}
        for d in self.items:
            q = self.env.articulations[d.name].get_qpos()[:, d.index]
            if d.rests is None:
                fresh = self.env.elapsed_steps.to(q.device) == 0  # the episode's first step: stuck where it starts
                anchor = q if d.anchor is None else torch.where(fresh, q, d.anchor)
                dev = q - anchor
                d.anchor = torch.where(dev.abs() > FRICTION_SLIP, q - torch.sign(dev) * FRICTION_SLIP, anchor)
                out[f"{d.name}/{d.joint.name}"] = d.anchor
            else:
                out[f"{d.name}/{d.joint.name}"] = d.rests[torch.argmin((q[:, None] - d.rests[None, :]).abs(), dim=1)]
        return out

    def update(self) -> None:
        for d, target in zip(self.items, self.targets().values(), strict=True):
            d.joint.set_drive_target(target)
        if self.items and self.env.gpu_sim_enabled:  # ManiSkill applied the robot's targets before this call
            self.env.scene.px.gpu_apply_articulation_target_position()


__all__ = ["DAMPING_RATIO", "FRICTION_SLIP", "Detents"]
