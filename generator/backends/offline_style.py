"""The offline author's choice of a scene style (:mod:`gendex_envs.scene_styles`) for each task it lays out.

Every scene file it writes ends with ``scene: {style: <style>}``. The style is a function of the author's seed and
the task's index in the batch (the request's ``index``: the same for every candidate and round of one task, another
for each retry of it): the tasks of a batch take :data:`STYLE_ROTATION` in turn from an offset the seed sets, so any
six tasks in a row show six places and a batch of 20 at least five. Nothing is drawn from the scene's random
generator: the objects' places are what they were before scenes existed.

A style whose structures the critic would reject for the layout (:mod:`generator.critic.room`: the arm's room,
the robot base, the objects' start regions) is passed over for the next one in the rotation; ``studio`` stands no
structures, so one always fits.
"""

from __future__ import annotations

import dataclasses
import logging

from generator.errors import BackendError

log = logging.getLogger(__name__)

STYLE_ROTATION = ("kitchen", "workshop", "lab", "dining", "office", "studio")
"""The styles the offline author gives its tasks, in turn (``plain``, the look of a task without a scene, is not
among them)."""
FALLBACK_STYLE = "studio"
"""A style without structures: it always leaves the arm room."""


def style_for(spec: dict, seed: int, index: int) -> str:
    """The style of the scene file ``spec`` (a raw task mapping) that task ``index`` of a batch by an author of
    ``seed`` gets (module docstring)."""
    from gendex_envs.errors import TaskSpecError
    from gendex_envs.scene_spec import SceneSpec
    from gendex_envs.spec import parse_task_spec
    from generator.catalog_view import asset_dicts
    from generator.critic.physical import check_scene_static

    start = (int(seed) + int(index)) % len(STYLE_ROTATION)
    order = STYLE_ROTATION[start:] + STYLE_ROTATION[:start]
    try:
        parsed = parse_task_spec({k: v for k, v in spec.items() if k != "scene"}, source="offline scene",
                                 known_assets=[a["id"] for a in asset_dicts()])
    except TaskSpecError as exc:  # the scene step rejects it anyway; a style without structures cannot be wrong
        log.debug("offline scene of %s does not parse (%s): style %s", spec.get("name"), exc, FALLBACK_STYLE)
        return FALLBACK_STYLE
    for style in order:
        report = check_scene_static(dataclasses.replace(parsed, scene=SceneSpec(style=style)))
        found = report.by_check("structure_room")
        if not found:
            return style
        log.debug("offline scene of %s: style %s passed over (%s)", spec.get("name"), style, found[0].message)
    raise BackendError(f"no scene style leaves the arm room in {spec.get('name')!r}, not even {FALLBACK_STYLE!r}")
