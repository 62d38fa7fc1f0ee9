"""Small text helpers the offline author's task builders share: object names as words, proposal steps, fenced
answers and CamelCase task names."""

from __future__ import annotations

import re


def word(name: str) -> str:
    """An object name as a word in a sentence (``tuna_can`` -> ``tuna can``)."""
    return name.replace("_", " ")


def step(skill: str, target: str, control_joint: str, instruction: str) -> dict:
    return {"skill": skill, "target": target, "control_joint": control_joint, "instruction": instruction}


def carry_steps(n: str, t: str, where: str) -> list[dict]:
    """The steps that pick up object ``n`` and take it ``where`` (above, over) object ``t``, then let go."""
    return [
        step("reach", n, "arm", f"Bring the open hand to the {word(n)}."),
        step("grasp", n, "hand", f"Close the fingers around the {word(n)}."),
        step("carry", t, "arm", f"Carry the {word(n)} {where} the {word(t)}."),
        step("release", n, "hand", f"Open the hand to let go of the {word(n)}."),
    ]


def fence(lang: str, body: str) -> str:
    return f"```{lang}\n{body.rstrip()}\n```\n"


def camel(*words: str) -> str:
    return "".join(w[:1].upper() + w[1:] for part in words for w in re.split(r"[_\s]+", part) if w)
