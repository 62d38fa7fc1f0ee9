"""Grasps that meet the grasp stage's own conditions: when a pinch holds its object in a physics trial but the stage
asks for more fingers than the pinch closes, the same pinch with the middle finger closing beside the index.

A task's grasp stage may declare ``grasped`` conditions (the thumb and ``min_fingers`` fingers touching, default 2).
A pinch closes the thumb and the index, and the middle finger beside the index only where finger inverse
kinematics puts its pad on the object; across the 84 mm tuna can it does not, so the middle finger is tucked away
and the pinch, which lifts the can, fails the stage's condition. :func:`with_middle_finger` gives the pinch whose
middle finger takes the index's pre-shape and closing targets (it closes beside the index, on the same side of the
object, and the guarded closing stops it on the surface). The executor's grasp selection
(:meth:`gendex.solve.rigid.RigidPrimitives.choose_grasp`) trials it after a pinch that held but missed the stage's
conditions (:func:`missed_only_conditions`) when the stage asks for two fingers besides the thumb (the most a
pinch with the middle finger can give), so a chosen grasp still meets them in physics.
"""

from __future__ import annotations

from dataclasses import replace

from gendex.solve.grasp import GraspPlan
from gendex.solve.grasp_trial import HELD_FRACTION, STILL_M_PER_S, TrialResult
from gendex.solve.hand import actuated
from gendex_envs.spec import CONDITION_DEFAULTS, ConditionSpec

INDEX, MIDDLE = actuated("ff"), actuated("mf")
"""Actuated joints of the index and the middle finger, in the same order (J3, J2, J1, ...)."""


def missed_only_conditions(result: TrialResult, lift_m: float) -> bool:
    """Whether the trial's grasp held its object (rose, touched by the thumb and a finger, still) and failed only
    the grasp stage's own conditions."""
    return (not result.held and result.rise_m >= HELD_FRACTION * lift_m and result.touching
            and result.speed_m_s < STILL_M_PER_S)


def fingers_wanted(require: tuple[ConditionSpec, ...]) -> int:
    """Fingers besides the thumb the ``grasped`` conditions ``require`` want on the object (0: none asked)."""
    return max((CONDITION_DEFAULTS["min_fingers"] if c.min_fingers is None else c.min_fingers
                for c in require if c.type == "grasped"), default=0)


def with_middle_finger(plan: GraspPlan, require: tuple[ConditionSpec, ...]) -> GraspPlan | None:
    """``plan`` (a pinch) with the middle finger moving as the index does: its pre-shape and closing targets;
    None when ``plan`` is not a pinch, its middle finger already does, or ``require`` does not ask for exactly two
    fingers besides the thumb."""
    if plan.kind != "pinch" or fingers_wanted(require) != 2:
        return None

    def twin(targets: dict[str, float]) -> dict[str, float]:
        return {m: targets[f] for f, m in zip(INDEX, MIDDLE, strict=True) if f in targets}

    open_mid = twin(plan.open_hand)
    if all(plan.open_hand.get(j) == v for j, v in open_mid.items()):
        return None
    closing = tuple((targets | twin(targets), steps) for targets, steps in plan.closing)
    return replace(plan, open_hand=plan.open_hand | open_mid, closing=closing,
                   note=f"{plan.note}, middle finger beside the index")


__all__ = ["fingers_wanted", "missed_only_conditions", "with_middle_finger"]
