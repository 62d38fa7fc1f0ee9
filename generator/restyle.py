"""Give the library's tasks a place: each committed task whose newest version has no ``scene`` section gets its next
version with ``scene: {style: <style>}`` (``gendex restyle``).

The styles are dealt as the offline author deals them to a batch (:func:`generator.backends.offline_style.style_for`):
the tasks, sorted by name, take :data:`~generator.backends.offline_style.STYLE_ROTATION` in turn from the offset
:data:`RESTYLE_SEED` sets, and a style whose fixed structures would leave the arm too little room in that task's
layout (the critic's ``structure_room`` check) is passed over for the next. So any six tasks in a row of the sorted
library show six places, and the styles are spread evenly over it.

Only the ``scene`` section changes. Its light and paint never touch physics (``docs/scenes.md``); its structures do
(static boxes beside the table that the planner routes round), so a restyled version drops the solvability record
it was copied with, for ``gendex gate --write`` to measure again.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import yaml

from gendex_envs.errors import TaskSpecError
from gendex_envs.scene_spec import SceneSpec
from gendex_envs.spec import load_task_spec
from gendex_envs.task_version import TaskLayout, TaskVersion, publish_derived

log = logging.getLogger(__name__)

RESTYLE_SEED = 0
"""The offset of the style rotation over the sorted library (the first task takes ``STYLE_ROTATION[0]``)."""


class RestyleError(TaskSpecError):
    """A task cannot be restyled: it already has a scene, or its rewritten spec does not read back as written."""


@dataclass(frozen=True)
class Restyle:
    """One planned change: ``source`` (a task's newest version) republished in ``style``."""

    source: TaskVersion
    style: str

    @property
    def env_id(self) -> str:
        return self.source.env_id


def _newest(versions: Iterable[TaskVersion]) -> list[TaskVersion]:
    """The newest version of each task (:func:`generator.stats.latest_versions`), sorted by task name."""
    from generator.stats import latest_versions

    return sorted(latest_versions({v.env_id: v for v in versions}).values(), key=lambda v: v.name)


def newest_without_scene(versions: Iterable[TaskVersion]) -> list[TaskVersion]:
    """The newest version of each task, for the tasks whose newest version has no ``scene`` section, by name."""
    return [v for v in _newest(versions) if v.spec.scene is None]


def plan_restyle(versions: Mapping[str, TaskVersion] | Iterable[TaskVersion], seed: int = RESTYLE_SEED,
                 names: Iterable[str] | None = None) -> list[Restyle]:
    """The style each task without a scene gets (module docstring); ``names`` keeps only those tasks. The rotation
    is dealt over every task of the library, those with a scene included, so a task's style depends neither on
    which others are asked for nor on which were restyled before it."""
    from generator.backends.offline_style import style_for

    items = versions.values() if isinstance(versions, Mapping) else versions
    wanted = None if names is None else set(names)
    plan = []
    for index, source in enumerate(_newest(items)):
        if (wanted is not None and source.name not in wanted) or source.spec.scene is not None:
            continue
        raw = yaml.safe_load(source.files.spec.read_text())
        plan.append(Restyle(source, style_for(raw, seed, index)))
    return plan


def add_scene(text: str, style: str) -> str:
    """``text`` (a task spec's YAML without a top-level ``scene``) with ``scene: {style: <style>}`` appended; every
    other byte is kept."""
    root = yaml.compose(text)
    if isinstance(root, yaml.MappingNode) and any(k.value == "scene" for k, _ in root.value):
        raise RestyleError("the spec already has a top-level 'scene' entry")
    return text.rstrip("\n") + "\n" + yaml.safe_dump({"scene": {"style": style}}, sort_keys=False)


def publish_restyled(source: TaskVersion, style: str, record: Mapping | None = None) -> TaskVersion:
    """Publish ``v<N+1>`` of ``source``'s task with ``scene: {style: <style>}`` (every other file copied, the
    solvability record dropped). Raises :class:`RestyleError` when ``source`` already has a scene."""
    if source.spec.scene is not None:
        raise RestyleError(f"{source.env_id} already has a scene ({source.spec.scene.style or 'custom'})")
    expected = dataclasses.replace(source.spec, scene=SceneSpec(style=style))

    def edit(out: TaskLayout) -> dict:
        out.spec.write_text(add_scene(out.spec.read_text(), style))
        if load_task_spec(out.spec) != expected:
            raise RestyleError(f"{source.env_id}: the restyled spec does not read back as written")
        out.record("solvability").unlink(missing_ok=True)
        return dict(record or {}, style=style, changed=[f"{out.spec.name}: scene: {{style: {style}}}"],
                    reason="The task had no scene: a plain table before a grey void, one look for every episode. "
                           "Its next version happens in a place whose look each episode draws from its seed.")

    published = publish_derived(source, "revision", edit)
    log.info("published %s in the %s style", published.env_id, style)
    return published


__all__ = ["RESTYLE_SEED", "Restyle", "RestyleError", "add_scene", "newest_without_scene", "plan_restyle",
           "publish_restyled"]
