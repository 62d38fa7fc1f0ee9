"""Buttons and switches hold their rest positions by a spring in the simulation (gendex_envs.detents): a latching
button or a switch pushed past the middle snaps to its other end and stays, pushed less it springs back; a momentary
button always springs back."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from gendex_envs.registry import resolve_task
from gendex_envs.spec import parse_task_spec, spec_to_dict
from gendex_envs.task_env import TaskEnv

CONTROLS = {"estop": ("button_estop", (0.42, -0.25)), "arcade": ("button_arcade", (0.42, 0.0)),
            "lever": ("switch_lever", (0.42, 0.25))}


@pytest.fixture(scope="module")
def env():
    raw = spec_to_dict(resolve_task("TurnValveLeverOff").spec)
    base = raw["objects"][0]
    raw["objects"] = [dict(base, name=n, asset=a, pos_m=[x, y, 0.0], joint_state=None, randomize=None)
                      for n, (a, (x, y)) in CONTROLS.items()]
    for o in raw["objects"]:
        o.pop("joint_state"), o.pop("randomize")
    for s in raw["stages"]:
        s["target"] = "lever"
    cond = {"type": "joint_open", "object": "lever", "min_fraction": 0.9}
    raw["stages"][1].update(skill="press", success=[cond])
    raw["success"]["conditions"] = [cond]
    e = TaskEnv(task_spec=parse_task_spec(raw), control_mode="pd_joint_delta_pos", render_backend="none")
    e.reset(seed=0)
    yield e
    e.close()


def _settle(env, fractions: dict[str, float] | None = None, steps: int = 12) -> dict[str, float]:
    """Put each control at ``fractions`` of the way from off to on (at rest), hold the robot still for ``steps``
    control steps, and return where each control came to rest."""
    for name, f in (fractions or {}).items():
        art, idx = env.articulations[name], env.joint_index(name)
        lo, hi = env.closed_qpos(name), env.open_qpos(name)
        q = art.get_qpos().clone()
        q[:, idx] = lo + f * (hi - lo)
        art.set_qpos(q)
        art.set_qvel(torch.zeros_like(q))
    hold = np.zeros(env.action_space.shape, dtype=np.float32)
    for _ in range(steps):
        env.step(hold)
    return {name: float(env.joint_open_fraction(name)[0]) for name in CONTROLS}


def test_controls_rest_off_and_are_pulled_to_their_nearest_rest_position(env):
    rest = _settle(env)
    assert all(abs(v) < 0.05 for v in rest.values()), rest  # a button sags under its own weight by under 0.5 mm
    past = _settle(env, {"estop": 0.6, "arcade": 0.6, "lever": 0.6})
    assert past["estop"] > 0.95 and past["lever"] > 0.95  # latched / snapped on, and they stay there
    assert abs(past["arcade"]) < 0.05  # a momentary button springs back up
    assert _settle(env, steps=20)["estop"] > 0.95
    short = _settle(env, {"estop": 0.4, "lever": 0.4, "arcade": 0.9})
    assert all(abs(v) < 0.05 for v in short.values()), short  # short of the middle: back to off


def test_the_pull_is_a_joint_drive_whose_target_is_the_nearest_rest(env):
    _settle(env, {"estop": 0.7, "lever": 0.2}, steps=1)
    targets = env.detents.targets()
    estop_on = env.open_qpos("estop")
    assert torch.allclose(targets["estop/button_slide"], torch.tensor([estop_on]))
    assert torch.allclose(targets["lever/lever_hinge"], torch.tensor([env.closed_qpos("lever")]))
    assert len(env.detents.items) == 3


@pytest.fixture(scope="module")
def jar():
    raw = spec_to_dict(resolve_task("GenDex/UnscrewJar-v0").spec)
    raw["objects"][0].pop("randomize")
    e = TaskEnv(task_spec=parse_task_spec(raw), control_mode="pd_joint_delta_pos", render_backend="none")
    e.reset(seed=0)
    e.step(np.zeros(e.action_space.shape, dtype=np.float32))  # past the first step, where the thread's anchor is set
    yield e
    e.close()


def _twist(env, torque_nm: float, steps: int = 10) -> float:
    """Push the jar's cap counter-clockwise with ``torque_nm`` about its axis at every simulation step of ``steps``
    control steps (the robot held still, out of reach) and return how far it turned (rad)."""
    cap = env.handle_link("jar")._objs[0]
    start = float(env.joint_qpos("jar")[0])
    for _ in range(steps):
        env.detents.update()
        for _ in range(env.sim_freq // env.control_freq):
            cap.add_force_torque(np.zeros(3), np.array([0.0, 0.0, torque_nm]))
            env.scene.step()
    return float(env.joint_qpos("jar")[0]) - start


def test_a_screw_cap_holds_below_its_thread_friction_and_turns_above_it(jar):
    from gendex_envs.assets.articulated import SCREW_RIM_FRICTION_N

    limit = jar.asset_record("jar").joints[0].friction_limit
    assert limit == pytest.approx(SCREW_RIM_FRICTION_N * jar.asset_record("jar").entry.params["cap_radius"], rel=1e-3)
    assert abs(_twist(jar, 0.6 * limit)) < 0.01  # held by the thread (it gives FRICTION_SLIP at most)
    turned = _twist(jar, 2.0 * limit)
    assert turned > 0.3
    assert abs(_twist(jar, 0.0)) < 0.01  # let go, it stays where it was turned to: it neither coasts nor springs back
