"""The PhysX objects behind ManiSkill's batched structs, for the CPU code paths that need them directly.

ManiSkill's ``Actor``, ``Link``, ``Articulation`` and joint structs wrap one PhysX/SAPIEN object per sub-scene and
expose them only as private lists; this is the one place GenDex reaches into them (per-joint drive targets,
contact bodies, tight bounding boxes, pinocchio models), so a ManiSkill upgrade that renames them breaks one file.
"""

from __future__ import annotations

from typing import Any


def px_objects(struct: Any) -> list:
    """The per-sub-scene PhysX/SAPIEN objects of a ManiSkill struct (an actor's entities, a link's or joint's
    PhysX components, an articulation's PhysX articulations)."""
    return struct._objs  # noqa: SLF001


def px_bodies(struct: Any) -> list:
    """The per-sub-scene PhysX rigid-body components of a ManiSkill actor or link."""
    return struct._bodies  # noqa: SLF001
