"""Reward modules composed from vetted terms (:mod:`gendex_envs.reward_terms`): what the offline backend writes.

Each function returns the source of a complete reward module (``REWARD_MAX``, ``evaluate``,
``compute_dense_reward``, ``_get_obs_extra``), chosen by the stage's skill. ``evaluate`` returns ``fail`` and the
diagnostics the reward uses; success is the stage's declared conditions. The source still goes through the
validator like model-written code. Object names are inserted as string literals; they are snake_case by the task
schema.
"""

from __future__ import annotations

import math
import textwrap
from typing import Any

from gendex_envs.spec import JOINT_SKILLS
from gendex_envs.success import REGION_AHEAD_M, REGION_DEPTH_M, REGION_PARTS

_HEADER_TEMPLATE = '''"""{title}

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

'''

_FAIL_RIGID = '''    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in {rigid}:
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
'''

_FAIL_NONE = '''    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
'''



_PUSH = '''REWARD_MAX = 3.0


def evaluate(env):
{fail}    return {{"fail": fail}}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose({obj!r}).p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    reward = reach + 2.0 * rt.place(p, env.goal_pos)
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {{"obj_to_goal": env.goal_pos - env.obj_pose({obj!r}).p}}
'''
"""Reward of a push: the palm to the object, the object to the goal mark (format with ``fail`` and ``obj``)."""


_SHARE = '''REWARD_MAX = 5.0


def evaluate(env):
{{fail}}    force = env.agent.get_hand_group_obj_mean_force(env.obj({{obj!r}}))  # [N, 6, 1]
    return {{{{"fail": fail, "contact": rt.contact(force), "{key}": env.{key}_share({{obj!r}}, {{{to}!r}})}}}}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose({{obj!r}}).p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    {near} = rt.place(p, env.obj_pose({{{to}!r}}).p) * (info["contact"] > 0.2)
    reward = reach + info["contact"] + {near} + 2.0 * info["{key}"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {{{{"palm_to_obj": env.obj_pose({{obj!r}}).p - env.palm_pose.p,
            "obj_to_{to}": env.obj_pose({{{to}!r}}).p - env.obj_pose({{obj!r}}).p, "{key}": info["{key}"][:, None]}}}}
'''
"""A reward towards a share of things done with a held object (format with ``key``: ``wiped`` or ``poured``, whose
``env.<key>_share`` it reads, ``near``: the name of the term bringing the object to ``to``, the target's
placeholder): the palm to the object, holding it, the held object brought to the target, then the share."""
_WIPE = _SHARE.format(key="wiped", near="over", to="area")
"""Reward of a wipe (format with ``fail``, ``obj``: the sponge, ``area``: the spill): the palm to the sponge, holding
it, the held sponge over the spill, then the share of the spill's marks wiped."""


_HANG = '''REWARD_MAX = 5.0
UP_M = 0.15


def evaluate(env):
{fail}    force = env.agent.get_hand_group_obj_mean_force(env.obj({obj!r}))  # [N, 6, 1]
    return {{"fail": fail, "contact": rt.contact(force), "height": env.obj_height({obj!r})}}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose({obj!r}).p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    held = info["contact"] > 0.2
    up = rt.lift(info["height"], UP_M) * held
    near = rt.place(p, env.obj_pose({stand!r}).p) * held
    reward = reach + info["contact"] + up + near
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {{"palm_to_obj": env.obj_pose({obj!r}).p - env.palm_pose.p,
            "obj_to_stand": env.obj_pose({stand!r}).p - env.obj_pose({obj!r}).p}}
'''
"""Reward of a hang (format with ``fail``, ``obj``: the mug, ``stand``: what it hangs on): the palm to the mug,
holding it, the held mug raised and brought to the stand; success (hung on a peg, let go, still) pays the most."""


_FLIP = '''REWARD_MAX = 5.0
UP_M = 0.15


def _up(q):
    """[N, 3] the world direction of the object's own z axis for unit quaternions q [N, 4] (wxyz)."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return torch.stack([2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)], dim=-1)


def evaluate(env):
{fail}    force = env.agent.get_hand_group_obj_mean_force(env.obj({obj!r}))  # [N, 6, 1]
    turned = (1.0 - (_up(env.obj_pose({obj!r}).q) * _up(env.init_obj_quat({obj!r}))).sum(dim=-1)) / 2.0
    return {{"fail": fail, "contact": rt.contact(force), "height": env.obj_height({obj!r}), "turned": turned}}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose({obj!r}).p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    up = rt.lift(info["height"], UP_M) * (info["contact"] > 0.2)
    reward = reach + info["contact"] + up + 2.0 * info["turned"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {{"palm_to_obj": env.obj_pose({obj!r}).p - env.palm_pose.p, "turned": info["turned"][:, None]}}
'''
"""Reward of a flip (format with ``fail``, ``obj``): the palm to the object, holding it, the held object raised,
and how far it is turned over (0 as at reset, 1 upside down: half of one minus the cosine between its axis now and
then); success (upside down, let go, still) pays the most."""


_POUR = _SHARE.format(key="poured", near="near", to="into")
"""Reward of a pour (format with ``fail``, ``obj``: the vessel, ``into``: the container): the palm to the vessel,
holding it, the held vessel brought to the container, then the share of its pieces that lie in the container."""


def _header(title: str) -> str:
    """The module header, its title wrapped to docstring width (an instruction may be a long sentence)."""
    return _HEADER_TEMPLATE.format(title=textwrap.fill(title, width=100))


def _parts(spec: dict) -> list[dict]:
    """The task's success conditions, one per part, without the ``grasped`` that the scene step adds beside a
    ``lifted`` (:func:`generator.steps.scene.hold_lifted`) nor the ``released`` it adds beside a set-down
    (:func:`generator.steps.scene.let_go`), nor the ``at_rest`` and ``upright`` it adds to a hand-over
    (:func:`generator.steps.scene.hand_over_settles`): the lift's terms already reward the contact, and letting go
    and settling are rewarded by the success itself."""
    return [c for c in spec["success"]["conditions"] if c["type"] not in ("grasped", "released", "at_rest", "upright")]


def _success_condition(spec: dict, obj: str | None = None) -> dict:
    """The task's success condition on ``obj`` (the object a stage acts on, or carries to), else the first: a
    composed task has one condition per part."""
    conds = _parts(spec)
    return next((c for c in conds if obj is not None and obj in (c.get("object"), c.get("target"))), conds[0])


def _stage(spec: dict, name: str) -> dict:
    for s in spec["stages"]:
        if s["name"] == name:
            return s
    raise KeyError(f"no stage {name!r}; stages: {[s['name'] for s in spec['stages']]}")


def _rigid(spec: dict, roles: dict[str, str]) -> list[str]:
    """The objects whose fall off the table fails the task: the movable ones but the pieces a vessel pours (a bead
    bouncing off the table is a pour that spilled a little: the share poured says how much)."""
    from gendex_envs.assets.catalog import get_asset
    from gendex_envs.pouring import POURABLE_TAG

    return [o["name"] for o in spec["objects"] if roles.get(o["name"]) != "articulated" and not o.get("fixed")
            and POURABLE_TAG not in get_asset(o["asset"]).tags]


def compose_stage_module(spec: dict, stage_name: str, roles: dict[str, str]) -> str:
    """Reward module for one RL stage of ``spec`` (a task dict), by the stage's skill."""
    stage = _stage(spec, stage_name)
    kind, obj = stage["skill"], stage["target"]
    cond = _success_condition(spec, obj)
    rigid = _rigid(spec, roles)
    fail = _FAIL_RIGID.format(rigid=tuple(rigid)) if rigid else _FAIL_NONE
    title = f"{spec['name']}, stage {stage_name}: {stage['instruction']}"
    src = _header(title)
    if kind == "push" or (cond.get("target") == "goal" and kind not in JOINT_SKILLS):
        return src + _PUSH.format(fail=fail, obj=obj)
    if cond["type"] == "wiped" and kind in ("carry", "wipe"):
        return src + _WIPE.format(fail=fail, obj=cond["object"], area=cond["target"])
    if cond["type"] == "hung":
        return src + _HANG.format(fail=fail, obj=cond["object"], stand=cond["target"])
    if cond["type"] == "poured" and kind == "pour":
        return src + _POUR.format(fail=fail, obj=cond["object"], into=cond["target"])
    if cond["type"] == "flipped":
        return src + _FLIP.format(fail=fail, obj=cond["object"])
    if kind in JOINT_SKILLS:
        frac = float(cond.get("min_fraction") or 0.8) if cond["type"] == "joint_open" else 0.8
        # closing progresses from fully open (0) to the allowed fraction (1); -x / f clipped to [0, 1] was always 0
        progress = ('(1.0 - info["open_fraction"]) / (1.0 - OPEN_FRACTION)' if kind == "close" or cond.get("negate")
                    else 'info["open_fraction"] / OPEN_FRACTION')
        if cond["type"] == "joint_at":
            frac, progress = float(cond["fraction"]), _progress(cond)
        src += f'''REWARD_MAX = 4.0
OPEN_FRACTION = {frac}


def evaluate(env):
{fail}    return {{"fail": fail, "open_fraction": env.joint_open_fraction({obj!r})}}


def compute_dense_reward(env, obs, action, info):
    handle = env.handle_pos({obj!r})
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - handle, dim=-1))
    progress = rt.fraction({progress})
    reward = reach + 2.0 * progress
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {{"palm_to_handle": env.handle_pos({obj!r}) - env.palm_pose.p,
            "open_fraction": info["open_fraction"][:, None]}}
'''
        return src
    if kind == "grasp":
        src += f'''REWARD_MAX = 4.0


def evaluate(env):
{fail}    force = env.agent.get_hand_group_obj_mean_force(env.obj({obj!r}))  # [N, 6, 1]
    return {{"fail": fail, "contact": rt.contact(force)}}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose({obj!r}).p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    tips = rt.tips_reach(env.tip_positions, p, 0.05)
    reward = reach + tips + info["contact"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    pose = env.obj_pose({obj!r})
    return {{"palm_to_obj": pose.p - env.palm_pose.p, "obj_pose": torch.cat([pose.p, pose.q], dim=-1)}}
'''
        return src
    if kind == "lift":
        h = float(cond.get("min_height_m") or 0.1) if cond["type"] == "lifted" else 0.1
        src += f'''REWARD_MAX = 3.0
LIFT_M = {h}


def evaluate(env):
{fail}    force = env.agent.get_hand_group_obj_mean_force(env.obj({obj!r}))  # [N, 6, 1]
    return {{"fail": fail, "height": env.obj_height({obj!r}), "contact": rt.contact(force)}}


def compute_dense_reward(env, obs, action, info):
    reward = info["contact"] + rt.lift(info["height"], LIFT_M) * (info["contact"] > 0.2)
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {{"height": info["height"][:, None], "palm_to_obj": env.obj_pose({obj!r}).p - env.palm_pose.p}}
'''
        return src
    # carry / place / release: bring the held object to the success condition's target, then let go
    target = cond.get("target") or obj
    goal = placed_goal(cond, spec) or f"env.obj_pose({target!r}).p"
    release = kind == "release"
    src += f'''REWARD_MAX = 3.0


def evaluate(env):
{fail}    force = env.agent.get_hand_group_obj_mean_force(env.obj({obj!r}))  # [N, 6, 1]
    return {{"fail": fail, "contact": rt.contact(force)}}


def compute_dense_reward(env, obs, action, info):
    place = rt.place(env.obj_pose({obj!r}).p, {goal})
    reward = 2.0 * place {"+ (1.0 - info['contact']) * (place > 0.8)" if release else "+ info['contact']"}
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {{"obj_to_target": {goal} - env.obj_pose({obj!r}).p}}
'''
    return src




def _composed(spec: dict, conds: list[dict], fail: str) -> str:
    """Reward of a task of several parts done in turn (``conds``, one success condition each): each part's terms
    count once the parts before it are done, and a done part counts its whole weight. A joint part is done at its
    progress 0.99, a lift at its height; a part that sets an object down, once the object is over where it goes
    (:func:`rt.place` above :data:`PART_DONE_PLACE`) and back down (below half the lift; a stacked object, once over
    its base)."""
    keys, lines = [], []
    for k, c in enumerate(conds):
        obj = c["object"]
        if c["type"] in ("joint_open", "joint_at"):
            keys.append(f'"open_fraction_{k}": env.joint_open_fraction({obj!r})')
            lines.append(f"    d = rt.fraction({_progress(c, f'open_fraction_{k}')})\n"
                         f"    done = d > 0.99\n"
                         f"    reward = reward + gate * torch.where(done, torch.full_like(d, 2.0), 2.0 * d)\n"
                         f"    gate = gate * done\n")
            continue
        keys.append(f'"height_{k}": env.obj_height({obj!r})')
        carry = _carry_term(c.get("target"), placed_goal(c, spec)).strip()
        lines.append(f"    p = env.obj_pose({obj!r}).p\n"
                     f"    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))\n"
                     f"    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj({obj!r})))\n"
                     f"    lifted = rt.lift(info[\"height_{k}\"], LIFT_M)\n"
                     f"    {carry}\n"
                     + ("    done = lifted > 0.99\n" if c["type"] == "lifted" else
                        f"    over = rt.place(p, {_goal_point(c, spec)})\n"
                        # a stacked object stays risen by its base's height: over its base is done
                        + ("    done = over > PART_DONE_PLACE\n" if c["type"] == "over" else
                           f"    done = (over > PART_DONE_PLACE) & (info[\"height_{k}\"] < LIFT_M / 2)\n"))
                     +
                     "    reward = reward + gate * torch.where(done, torch.full_like(reach, 4.0), "
                     "reach + grasp + lifted + carry)\n"
                     "    gate = gate * done\n")
    weights = sum(2.0 if c["type"] in ("joint_open", "joint_at") else 4.0 for c in conds)
    return (f"REWARD_MAX = {weights + 1.0}\nLIFT_M = 0.1\nPART_DONE_PLACE = {PART_DONE_PLACE}\n\n\n"
            f"def evaluate(env):\n{fail}    return {{\"fail\": fail, {', '.join(keys)}}}\n\n\n"
            "def compute_dense_reward(env, obs, action, info):\n"
            "    reward = torch.zeros(env.num_envs, device=env.device)\n"
            "    gate = torch.ones(env.num_envs, device=env.device)\n"
            + "".join(lines)
            + "    return torch.where(info[\"success\"], torch.full_like(reward, REWARD_MAX), reward)\n")


def _goal_point(cond: dict, spec: dict) -> str:
    """Code for the [N, 3] point a part's object is set down at: its target's position, or a place's point."""
    return placed_goal(cond, spec) or f"env.obj_pose({cond['target']!r}).p"


def _progress(cond: dict, key: str = "open_fraction") -> str:
    """A joint condition's progress in [0, 1] as code, from ``info[key]`` (the joint's open fraction): a shut joint
    from open (0) to shut past the fraction (1); a joint set part way (``joint_at``) from the far end of its range
    (0) to the fraction (1)."""
    x = f'info["{key}"]'
    if cond["type"] == "joint_at":
        frac = float(cond["fraction"])
        return f'1.0 - ({x} - {frac!r}).abs() / {max(frac, 1.0 - frac)!r}'
    frac = float(cond.get("min_fraction") or 0.8)
    return f'(1.0 - {x}) / {1.0 - frac!r}' if cond.get("negate") else f'{x} / {frac!r}'


PART_DONE_PLACE = 0.8
"""A composed task's part that carries an object is done once :func:`rt.place` of the object and where it goes is
above this (within about 2 cm)."""


def _carry_term(target: str | None, goal: str | None = None) -> str:
    """The carry term's code: the object over ``target``, or at the point code ``goal`` computes."""
    if goal is not None:
        return f'    carry = rt.place(p, {goal}) * (lifted > 0.5)\n'
    return (f'    carry = rt.place(p, env.obj_pose({target!r}).p) * (lifted > 0.5)\n'
            if target else "    carry = torch.zeros_like(reach)\n")


def placed_goal(cond: dict, spec: dict) -> str | None:
    """Code for the [N, 3] point a ``placed`` condition sets its object down at (the solver's
    :func:`gendex.solve.set_down.set_down_point`, in the robot's frame from the spec's base yaw), or an ``inside``
    condition with a joint (a drawer's bin: the middle of its floor), else None."""
    if cond.get("type") == "inside" and cond.get("joint"):
        return f"env.holds_point({cond['target']!r}, {cond['joint']!r})"
    if cond.get("type") != "placed":
        return None
    yaw = math.radians(float(spec.get("robot", {}).get("base_yaw_deg", 0.0)))
    fwd, left = (math.cos(yaw), math.sin(yaw)), (-math.sin(yaw), math.cos(yaw))
    rel = cond["relation"]
    if rel == "in_region":
        base = spec.get("robot", {}).get("base_pos_m", [-0.8, 0.0, 0.0])
        x, y = base[0] + REGION_AHEAD_M * fwd[0], base[1] + REGION_AHEAD_M * fwd[1]
        for part in () if cond["region"] == "centre" else cond["region"].split("_"):
            axis, sign = REGION_PARTS[part]
            u = (fwd, left)[axis]
            x, y = x + sign * REGION_DEPTH_M * u[0], y + sign * REGION_DEPTH_M * u[1]
        return f"torch.tensor([[{x:.4f}, {y:.4f}, 0.0]], device=env.device)"
    t = f"env.obj_pose({cond['target']!r}).p"
    if rel == "between":
        return f"({t} + env.obj_pose({cond['other']!r}).p) / 2"
    gap = (float(cond.get("min_gap_m") or 0.05) + float(cond.get("max_gap_m") or 0.3)) / 2
    d = {"left_of": left, "right_of": (-left[0], -left[1]), "behind": fwd, "in_front_of": (-fwd[0], -fwd[1]),
         "next_to": (-fwd[0], -fwd[1])}[rel]
    return f"{t} + torch.tensor([[{gap * d[0]:.4f}, {gap * d[1]:.4f}, 0.0]], device=env.device)"


def compose_task_module(spec: dict, roles: dict[str, str]) -> str:
    """Reward module of the whole task: staged terms towards the task's success condition (for a composed task,
    the articulated part's condition first, then the rigid part's)."""
    conds = _parts(spec)
    if len(conds) > 1:
        rigid = _rigid(spec, roles)
        fail = _FAIL_RIGID.format(rigid=tuple(rigid)) if rigid else _FAIL_NONE
        return _header(f"{spec['name']}: {spec['instruction']}") + _composed(spec, conds, fail)
    cond = _success_condition(spec)
    rigid = _rigid(spec, roles)
    fail = _FAIL_RIGID.format(rigid=tuple(rigid)) if rigid else _FAIL_NONE
    src = _header(f"{spec['name']}: {spec['instruction']}")
    obj = cond["object"]
    if cond["type"] in ("joint_open", "joint_at"):
        # a shut joint (negated condition) progresses from open (0) to shut past the fraction (1); a joint set part
        # way, from the far end to its fraction
        frac = float(cond.get("min_fraction") or 0.8)
        progress = (f'(1.0 - info["open_fraction"]) / {1.0 - frac!r}' if cond.get("negate")
                    else _progress(cond) if cond["type"] == "joint_at" else 'info["open_fraction"]')
        src += f'''REWARD_MAX = 4.0


def evaluate(env):
{fail}    return {{"fail": fail, "open_fraction": env.joint_open_fraction({obj!r})}}


def compute_dense_reward(env, obs, action, info):
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - env.handle_pos({obj!r}), dim=-1))
    reward = reach + 2.0 * rt.fraction({progress})
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {{"palm_to_handle": env.handle_pos({obj!r}) - env.palm_pose.p}}
'''
        return src
    target = cond.get("target")
    if target == "goal":  # a push: the object towards the goal mark, never lifted
        return src + _PUSH.format(fail=fail, obj=obj)
    if cond["type"] == "wiped":
        return src + _WIPE.format(fail=fail, obj=obj, area=target)
    if cond["type"] == "hung":
        return src + _HANG.format(fail=fail, obj=obj, stand=target)
    if cond["type"] == "poured":
        return src + _POUR.format(fail=fail, obj=obj, into=target)
    if cond["type"] == "flipped":
        return src + _FLIP.format(fail=fail, obj=obj)
    carry = _carry_term(target, placed_goal(cond, spec))
    src += f'''REWARD_MAX = 5.0
LIFT_M = 0.1


def evaluate(env):
{fail}    return {{"fail": fail, "height": env.obj_height({obj!r})}}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose({obj!r}).p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj({obj!r})))
    lifted = rt.lift(info["height"], LIFT_M)
{carry}    reward = reach + grasp + lifted + carry
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {{"palm_to_obj": env.obj_pose({obj!r}).p - env.palm_pose.p}}
'''
    return src


def roles_of(proposal: dict[str, Any]) -> dict[str, str]:
    return {o["name"]: o["role"] for o in proposal["objects"]}
