"""Every member the environment-API prompt names exists on the view reward code receives, with the documented shape,
and the view offers nothing the prompt does not document."""

from __future__ import annotations

import re

import pytest
import torch

from gendex_envs.pouring import spec_fills
from gendex_envs.reward_view import RewardView, view_of
from generator.prompts import render

_LINE = re.compile(r"^- `(?P<expr>[^`]+)` : (?P<shape>[^:]+?) : ", re.M)


def _members() -> list[tuple[str, str]]:
    found = [(m["expr"], m["shape"].strip()) for m in _LINE.finditer(render("env_api"))]
    assert len(found) >= 15, "the env-API prompt lists its members as '- `expr` : shape : meaning'"
    return found


def _check(value, shape: str, n: int, expr: str) -> None:
    if shape == "int":
        assert isinstance(value, int), expr
    elif shape == "tuple":
        assert isinstance(value, tuple), expr
    elif shape == "float":
        assert isinstance(value, float), expr
    elif shape == "torch.device":
        assert isinstance(value, torch.device), expr
    else:
        m = re.fullmatch(r"\[(?P<dims>[^\]]+)\](?: (?P<dtype>bool))?", shape)
        assert m, f"unparsed shape {shape!r} for {expr}"
        dims = [n if d.strip() == "N" else int(d) for d in m["dims"].split(",")]
        assert isinstance(value, torch.Tensor), expr
        assert list(value.shape) == dims, f"{expr}: documented {shape}, got {list(value.shape)}"
        if m["dtype"] == "bool":
            assert value.dtype == torch.bool, expr
        else:
            assert value.dtype.is_floating_point, f"{expr}: {value.dtype}"


@pytest.mark.parametrize("env_id, placeholder, name, joint", [
    ("GenDex/PutAppleBowl-v0", "NAME", "apple", None),
    ("GenDex/OpenCabinet-v0", "ARTICULATED", "cabinet", None),
    ("GenDex/PushBlockToGoal-v0", "NAME", "block", None),
    ("GenDex/OpenDrawer-v1", "ARTICULATED", "drawer_chest", "drawer_0_slide"),
    ("GenDex/WipeSpillRound-v1", "NAME", "sponge", None),
    ("GenDex/PourBeadsFromTumblerIntoBowl-v0", "NAME", "tumbler", None),
])
def test_env_api_prompt_matches_the_reward_view(make_env, env_id, placeholder, name, joint):
    """Each documented member, evaluated on a task's objects (JOINT: a drawer's, on a task that has one; AREA: its
    spill; VESSEL and CONTAINER: the vessel it pours from and the bowl), has the documented shape and dtype."""
    env = make_env(env_id, control_mode="pd_joint_delta_pos")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    u = env.unwrapped
    view = view_of(u)
    checked = 0
    vessels = spec_fills(u.task_spec)
    for expr, shape in _members():
        other = "ARTICULATED" if placeholder == "NAME" else "NAME"
        if other in expr or ("goal_pos" in expr and u.goal_site is None) or ("JOINT" in expr and joint is None) \
                or ("AREA" in expr and "spill" not in u.objects) or ("VESSEL" in expr and name not in vessels):
            continue
        code = (expr.replace(placeholder, repr(name)).replace("JOINT", repr(joint)).replace("AREA", repr("spill"))
                .replace("VESSEL", repr(name)).replace("CONTAINER", repr("bowl")))
        value = eval(code, {"torch": torch}, {"env": view})
        _check(value, shape, u.num_envs, expr)
        checked += 1
    assert checked >= 12


def test_the_view_offers_exactly_what_the_prompt_documents():
    documented = {m for expr, _ in _members() for m in re.findall(r"\benv\.(\w+)", expr)}
    offered = {n for n in dir(RewardView) if not n.startswith("_")}
    assert offered == documented, (f"undocumented: {sorted(offered - documented)}; "
                                   f"documented but missing: {sorted(documented - offered)}")
