"""``RigidPrimitives.grasp`` takes an object for slipped when it rose less than half as far as the hand did: an edge
grasp's lift, cut short where the arm's reach ends, is judged by the part the hand made, not the whole offset.

The motion, the object's height and the hand's contacts are stand-ins: the lift raises the hand by the fraction of
the offset the "arm" reaches, and the object by a given share of what the hand rose.
"""

from __future__ import annotations

import numpy as np
import pytest
import sapien
import torch

import gendex.solve.rigid as rigid
from gendex.solve.grasp import GraspPlan
from gendex.solve.grasp_trial import rose_with_hand
from gendex.solve.rigid import MIN_LIFT_M, RigidConfig, RigidPrimitives
from gendex_envs.errors import ExecutionError


class _Pose:
    def __init__(self, z: float):
        self.p = torch.tensor([[0.0, 0.0, z]])


class _Env:
    def __init__(self):
        self.z = 0.0

    def obj(self, name):
        return type("Obj", (), {"pose": _Pose(self.z)})()

    def hand_forces(self, name):
        return torch.tensor([[2.0, 2.0, 0.0, 0.0, 0.0, 0.0]])  # thumb and index on it


class _Motion:
    def __init__(self, env: _Env, reach: float, follows: float):
        self.env, self.reach, self.follows = env, reach, follows

    def cartesian(self, offset, m_per_step, guard=False, paced=False, after=0, partial=False):
        done = min(1.0, self.reach / float(offset[2]))
        if done < 1.0 and not partial:
            raise ExecutionError("no IK", cause="no_ik")
        self.env.z += self.follows * done * float(offset[2])
        yield np.zeros(3)
        return done


def _grasp(monkeypatch, lift_m: float | None, reach: float, follows: float) -> RigidPrimitives:
    env = _Env()
    prims = RigidPrimitives.__new__(RigidPrimitives)
    prims.m, prims.env, prims.config = _Motion(env, reach, follows), env, RigidConfig(regrasps=0)
    prims.held, prims._require = None, ()

    def lift(m_per_step: float):  # an edge grasp's own lift: straight up, as far as the arm reaches
        done = yield from prims.m.cartesian(np.array([0.0, 0.0, lift_m]), m_per_step, True, partial=True)
        return done * lift_m

    prims.plan = GraspPlan("edge", sapien.Pose(), np.array([0.0, 0.0, -1.0]), lift=None if lift_m is None else lift)
    monkeypatch.setattr(rigid, "close_hand", lambda m, plan, motion: iter(()))
    monkeypatch.setattr(rigid, "ease_grip", lambda m, require: iter(()))
    list(prims.grasp("tool"))
    return prims


def test_an_edge_lift_cut_short_by_the_arm_holds_when_the_object_rose_with_the_hand(monkeypatch):
    # the hand rises 11 cm of the 24 asked, the hanging tool 9 of them: under half of 24 cm, most of what the hand did
    prims = _grasp(monkeypatch, lift_m=0.24, reach=0.11, follows=0.8)
    assert prims.held == "tool"


def test_an_object_that_stayed_behind_the_hand_slipped(monkeypatch):
    with pytest.raises(ExecutionError) as err:
        _grasp(monkeypatch, lift_m=0.24, reach=0.11, follows=0.3)
    assert err.value.cause == "slipped"
    assert "of 0.110 m" in str(err.value)  # judged against the hand's 11 cm


def test_a_lift_the_arm_barely_starts_is_judged_against_the_least_lift(monkeypatch):
    # the hand rose 2 cm: an object that rose with it has still not come up MIN_LIFT_M / 2
    with pytest.raises(ExecutionError) as err:
        _grasp(monkeypatch, lift_m=0.24, reach=0.02, follows=1.0)
    assert f"of {MIN_LIFT_M:.3f} m" in str(err.value)


def test_a_full_lift_is_judged_as_before(monkeypatch):
    config_lift = RigidConfig().motion.lift_m
    assert _grasp(monkeypatch, lift_m=None, reach=1.0, follows=0.55).held == "tool"
    with pytest.raises(ExecutionError) as err:
        _grasp(monkeypatch, lift_m=None, reach=1.0, follows=0.45)
    assert f"of {config_lift:.3f} m" in str(err.value)


def test_a_rehearsed_edge_grasp_is_judged_as_the_executor_judges_it():
    # the physics trials' rehearsal of an edge grasp and the executor share one judgement, floor included: a tool
    # that stayed on the table while the arm barely rose did not come up with the hand
    assert rose_with_hand(0.045, 0.09) and not rose_with_hand(0.04, 0.09)
    assert not rose_with_hand(0.015, 0.02)  # with the palm: 1.5 of 2 cm; but not half of MIN_LIFT_M
    assert rose_with_hand(0.5 * MIN_LIFT_M, 0.0)
