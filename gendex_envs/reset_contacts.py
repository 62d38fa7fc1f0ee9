"""What the robot touches at a reset: robot-object interpenetrations in PhysX's contact list.

A start state whose resting hand overlaps an object (a mug rack's peg swung into the fingers by its yaw draw, an
oven's body at the arm's elbow) is not a state the simulator can hold: the first physics step pushes the two apart,
and how it does so depends on contact data PhysX keeps from the step before the reset. The same seed and actions
then step differently after another episode, which Gymnasium's ``check_env`` reports as non-determinism and which a
recorded dataset cannot rebuild from. The generator's critic measures the nominal layout and the extremes of its
randomization with :func:`robot_penetrations`; ``gendex check`` measures every version's first :data:`START_SEEDS`
resets.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

START_SEEDS = 20
"""Resets (seeds 0 .. START_SEEDS - 1) whose start states ``gendex check`` measures."""


def entity_ids(entity: Any) -> list[int]:
    """The per-scene entity ids of an actor, or of every link of an articulation (first sub-scene)."""
    from mani_skill.utils.structs import Articulation

    from gendex_envs.physx import px_objects

    if isinstance(entity, Articulation):
        return [px_objects(link)[0].entity.per_scene_id for link in entity.get_links()]
    return [obj.per_scene_id for obj in px_objects(entity)]


@dataclass(frozen=True)
class Penetration:
    """A robot link inside an object: ``depth`` (m, > 0) at its deepest contact point, and ``push``, the unit
    direction that moves the object out of the link there (PhysX's contact normal, which points from a contact's
    second body to its first, turned to point away from the link)."""

    link: str
    depth: float
    push: tuple[float, float, float]


def robot_penetrations(env: Any) -> dict[str, dict[str, Penetration]]:
    """``{object: {robot link: Penetration}}`` of the task's objects in the first sub-scene, from the contacts
    PhysX listed at its last physics step (step the scene once after a reset: the contact list is filled by a step).
    Touching without interpenetration is left out."""
    from gendex_envs.physx import px_objects

    owner = {i: name for name, entity in env.objects.items() for i in entity_ids(entity)}
    links = {px_objects(link)[0].entity.per_scene_id: link.name for link in env.agent.robot.get_links()}
    found: dict[str, dict[str, Penetration]] = {}
    for contact in env.scene.px.get_contacts():
        ids = [b.entity.per_scene_id for b in contact.bodies]
        sign = 1.0  # the object is the first body: the normal already points towards it
        if ids[0] in links:
            ids.reverse()
            sign = -1.0
        name, link = owner.get(ids[0]), links.get(ids[1])
        if name is None or link is None or not contact.points:
            continue
        point = min(contact.points, key=lambda p: p.separation)
        depth = -float(point.separation)
        if depth > getattr(found.get(name, {}).get(link), "depth", 0.0):
            push = tuple(float(sign * x) for x in point.normal)
            found.setdefault(name, {})[link] = Penetration(link, depth, push)
    return found
