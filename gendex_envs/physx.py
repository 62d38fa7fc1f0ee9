"""The PhysX objects behind ManiSkill's batched structs, for the CPU code paths that need them directly.

ManiSkill's ``Actor``, ``Link``, ``Articulation`` and joint structs wrap one PhysX/SAPIEN object per sub-scene and
expose them only as private lists; this is the one place GenDex reaches into them (per-joint drive targets,
contact bodies, tight bounding boxes, pinocchio models), so a ManiSkill upgrade that renames them breaks one file.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from mani_skill.utils.structs.pose import Pose
from sapien import physx


def px_objects(struct: Any) -> list:
    """The per-sub-scene PhysX/SAPIEN objects of a ManiSkill struct (an actor's entities, a link's or joint's
    PhysX components, an articulation's PhysX articulations)."""
    return struct._objs  # noqa: SLF001


def px_bodies(struct: Any) -> list:
    """The per-sub-scene PhysX rigid-body components of a ManiSkill actor or link."""
    return struct._bodies  # noqa: SLF001


def read_pose(struct: Any) -> Pose:
    """``struct.pose`` (an actor, link or articulation root) with the same values, read straight from PhysX when the
    scene is one CPU sub-scene. ManiSkill's CPU getter converts each sapien.Pose through lists and ``to_tensor``
    (about 9 us); this concatenates the float32 ``p`` and ``q`` arrays SAPIEN returns (about 3 us)."""
    objs = struct._objs  # noqa: SLF001
    if struct.scene.gpu_sim_enabled or len(objs) != 1:
        return struct.pose
    obj = objs[0]
    if isinstance(obj, physx.PhysxArticulation):
        pose = obj.root_pose
    elif isinstance(obj, physx.PhysxArticulationLinkComponent):
        pose = obj.entity_pose
    else:  # sapien.Entity (an actor)
        pose = obj.pose
    return Pose(raw_pose=torch.from_numpy(np.concatenate([pose.p, pose.q]))[None].to(struct.device))
