"""Contact impulses for many (body, body) queries per step, at the cost of one pass over the contact list.

ManiSkill answers each CPU query (``get_pairwise_contact_forces``, ``get_net_contact_forces``) by walking PhysX's
whole contact list in Python; the hand's force API asks ~25 such questions per step. On the CPU backend this table
walks the list once after each physics step and answers every query from it. On the GPU backend ManiSkill's batched
contact queries are used unchanged.

Contacts only change when physics steps, so the table stays valid until the owner calls :meth:`invalidate` after
``scene.step()`` (:class:`~gendex_envs.task_env.TaskEnv` does, in ``_after_simulation_step`` and on reset).
"""

from __future__ import annotations

import numpy as np
import torch
from mani_skill.utils.structs import Actor, Link

from gendex_envs.physx import px_bodies


class ContactTable:
    """Net and pairwise contact impulses [N, 3] (N·s) on a fixed set of bodies (e.g. a robot's links).

    Only contacts that involve one of ``bodies`` are kept, and queries must ask about those bodies.
    """

    def __init__(self, scene, bodies: list[Actor | Link]):
        self.scene = scene
        self._keys: dict[int, tuple[Actor | Link, int]] = {}  # id(wrapper) -> (wrapper, kept alive; entity id)
        self._ids = frozenset(self._id(b) for b in bodies)
        self._net: dict[int, np.ndarray] | None = None
        self._pair: dict[tuple[int, int], np.ndarray] = {}

    def invalidate(self) -> None:
        """Forget the cached contacts (call after every physics step or state change)."""
        self._net = None

    def _refresh(self) -> None:
        net: dict[int, np.ndarray] = {}
        pair: dict[tuple[int, int], np.ndarray] = {}
        ids = self._ids
        for contact in self.scene.px.get_contacts():
            a, b = contact.bodies[0].entity.per_scene_id, contact.bodies[1].entity.per_scene_id
            if a not in ids and b not in ids:
                continue
            impulse = np.sum([point.impulse for point in contact.points], axis=0)
            # the impulse acts on body 0; body 1 receives the opposite (same convention as ManiSkill)
            net[a] = net.get(a, 0.0) + impulse
            net[b] = net.get(b, 0.0) - impulse
            pair[(a, b)] = pair.get((a, b), 0.0) + impulse
            pair[(b, a)] = pair.get((b, a), 0.0) - impulse
        self._net, self._pair = net, pair

    def _rows(self, values: list) -> torch.Tensor:
        """[1, len(values), 3] from cached impulses (0.0 where there was no contact)."""
        out = np.zeros((1, len(values), 3), dtype=np.float32)
        for i, v in enumerate(values):
            if v is not None:
                out[0, i] = v
        return torch.from_numpy(out).to(self.scene.device)

    def _id(self, body: Actor | Link) -> int:
        """PhysX entity id of a (CPU, single-env) body, memoised per wrapper object."""
        hit = self._keys.get(id(body))
        if hit is None:
            hit = self._keys[id(body)] = (body, px_bodies(body)[0].entity.per_scene_id)
        return hit[1]

    def _check(self, bodies: list[Actor | Link]) -> None:
        outside = [b.name for b in bodies if self._id(b) not in self._ids]
        if outside:
            raise ValueError(f"contact table does not track {outside}")

    def net_impulses(self, bodies: list[Actor | Link]) -> torch.Tensor:
        """[N, B, 3] total contact impulse on each body during the last physics step."""
        if self.scene.gpu_sim_enabled:
            return torch.stack([b.get_net_contact_impulses() for b in bodies], dim=1)
        self._check(bodies)
        if self._net is None:
            self._refresh()
        return self._rows([self._net.get(self._id(b)) for b in bodies])

    def pair_impulses(self, bodies: list[Actor | Link], others: list[Actor | Link]) -> torch.Tensor:
        """[N, B, 3] contact impulse on each body from all of ``others`` during the last physics step."""
        if self.scene.gpu_sim_enabled:
            return torch.stack([sum(self.scene.get_pairwise_contact_impulses(b, o) for o in others)
                                for b in bodies], dim=1)
        self._check(bodies)
        if self._net is None:
            self._refresh()
        other_ids = [self._id(o) for o in others]
        rows = []
        for b in bodies:
            bid = self._id(b)
            hits = [self._pair[(bid, o)] for o in other_ids if (bid, o) in self._pair]
            rows.append(np.sum(hits, axis=0) if hits else None)
        return self._rows(rows)
