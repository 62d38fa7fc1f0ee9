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
        # PhysX component -> entity id of the tracked bodies, looked up by the component object itself: SAPIEN's
        # pybind11 bindings hand out the one live Python object of a component (ManiSkill's structs and this dict
        # keep them alive), so a dict lookup replaces two attribute reads per body of every contact
        self._tracked = {px_bodies(b)[0]: self._id(b) for b in bodies}
        self._ids = frozenset(self._tracked.values())
        self._kept: list[tuple[int, int, np.ndarray]] | None = None  # (body 0, body 1, impulse on body 0)
        self._net: dict[int, np.ndarray] | None = None
        self._pair: dict[tuple[int, int], np.ndarray] = {}

    def invalidate(self) -> None:
        """Forget the cached contacts (call after every physics step or state change)."""
        self._kept = None
        self._net = None

    def _refresh(self) -> None:
        kept: list[tuple[int, int, np.ndarray]] = []
        pair: dict[tuple[int, int], np.ndarray] = {}
        tracked = self._tracked
        for contact in self.scene.px.get_contacts():
            body0, body1 = contact.bodies
            a, b = tracked.get(body0), tracked.get(body1)
            if a is None:
                if b is None:  # neither body is tracked
                    continue
                a = body0.entity.per_scene_id
            elif b is None:
                b = body1.entity.per_scene_id
            points = contact.points
            if not points:
                impulse = np.float64(0.0)  # what np.sum([], axis=0) gave
                points = ()
            else:
                impulse = points[0].impulse
            for point in points[1:]:  # row by row, as np.sum(..., axis=0) adds them: the same float32 result
                impulse = impulse + point.impulse
            # the impulse acts on body 0; body 1 receives the opposite (same convention as ManiSkill)
            kept.append((a, b, impulse))
            pair[(a, b)] = pair.get((a, b), 0.0) + impulse
            pair[(b, a)] = pair.get((b, a), 0.0) - impulse
        self._kept, self._pair = kept, pair

    def _net_sums(self) -> dict[int, np.ndarray]:
        """Net impulse per body, summed in contact order (only on request: most steps ask only pairwise)."""
        if self._kept is None:
            self._refresh()
        if self._net is None:
            net: dict[int, np.ndarray] = {}
            for a, b, impulse in self._kept:
                net[a] = net.get(a, 0.0) + impulse
                net[b] = net.get(b, 0.0) - impulse
            self._net = net
        return self._net

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

    def _tracked_ids(self, bodies: list[Actor | Link]) -> list[int]:
        """The entity ids of ``bodies``; ValueError naming any the table does not track."""
        ids = [self._id(b) for b in bodies]
        if not self._ids.issuperset(ids):
            outside = [b.name for b, i in zip(bodies, ids, strict=True) if i not in self._ids]
            raise ValueError(f"contact table does not track {outside}")
        return ids

    def net_impulses(self, bodies: list[Actor | Link]) -> torch.Tensor:
        """[N, B, 3] total contact impulse on each body during the last physics step."""
        if self.scene.gpu_sim_enabled:
            return torch.stack([b.get_net_contact_impulses() for b in bodies], dim=1)
        ids = self._tracked_ids(bodies)
        net = self._net_sums()
        return self._rows([net.get(i) for i in ids])

    def pair_impulses(self, bodies: list[Actor | Link], others: list[Actor | Link]) -> torch.Tensor:
        """[N, B, 3] contact impulse on each body from all of ``others`` during the last physics step."""
        if self.scene.gpu_sim_enabled:
            return torch.stack([sum(self.scene.get_pairwise_contact_impulses(b, o) for o in others)
                                for b in bodies], dim=1)
        ids = self._tracked_ids(bodies)
        if self._kept is None:
            self._refresh()
        pair = self._pair
        if not pair:  # nothing touches the tracked bodies (most steps of a reach)
            return self._rows([None] * len(ids))
        other_ids = [self._id(o) for o in others]
        rows = []
        for bid in ids:
            hits = [pair[(bid, o)] for o in other_ids if (bid, o) in pair]
            rows.append(np.sum(hits, axis=0) if hits else None)
        return self._rows(rows)
