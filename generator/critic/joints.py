"""Edits of an articulated object's joint state that the critic's ``joint_state`` check asks for
(:func:`apply_joint_fix`): the directive grammar moves and scales objects, these set where a joint starts."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from gendex_envs.assets.catalog import get_asset
from gendex_envs.spec import TaskSpec, parse_task_spec, spec_to_dict
from generator.errors import DirectiveError


def apply_joint_fix(spec: TaskSpec, fixes: Mapping | Iterable[Mapping]) -> TaskSpec:
    """A new TaskSpec with each ``{"object", "joint", "value"}`` written into that object's ``joint_state``.

    DirectiveError for an unknown object or joint, or a value outside the joint's limits.
    """
    fixes = [fixes] if isinstance(fixes, Mapping) else list(fixes)
    raw = spec_to_dict(spec)
    by_name = {o["name"]: o for o in raw["objects"]}
    for fx in fixes:
        name, joint, value = fx.get("object"), fx.get("joint"), fx.get("value")
        if name not in by_name:
            raise DirectiveError(f"joint fix {dict(fx)} names object {name!r}, which is not in the scene; "
                                 f"objects: {', '.join(by_name)}")
        rec = get_asset(by_name[name]["asset"])
        joints = [j.name for j in rec.joints]
        if joint not in joints:
            raise DirectiveError(f"joint fix {dict(fx)}: {name!r} (asset {rec.id!r}) has no joint {joint!r}; "
                                 f"joints: {', '.join(joints) or 'none'}")
        jlo, jhi = rec.joint(joint).limits
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not jlo <= value <= jhi:
            raise DirectiveError(f"joint fix {dict(fx)}: value {value!r} is outside {joint}'s limits [{jlo}, {jhi}]")
        by_name[name]["joint_state"] = {**by_name[name]["joint_state"], joint: float(value)}
    return parse_task_spec(raw, source=f"<{spec.name} after {len(fixes)} joint fixes>")
