"""The task language's pose-and-motion conditions (``upright``, ``flipped``, ``at_rest``): their tolerances, what
counts as the object's up axis, and what the spec refuses."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest
import torch

from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import CONDITION_DEFAULTS, ConditionSpec, parse_task_spec
from gendex_envs.success import condition_holds

EPS_DEG = 0.1


def _quat(axis, deg: float) -> list[float]:
    a = torch.tensor(axis, dtype=torch.float64)
    a = a / a.norm()
    h = math.radians(deg) / 2
    return [math.cos(h), *(math.sin(h) * a).tolist()]


def _mul(a, b) -> list[float]:
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return [aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw]


class _Env:
    """Poses now and at reset, and velocities, one env per row."""

    def __init__(self, q, q0=None, lin=None, ang=None):
        n = len(q)
        self.num_envs, self.device, self.articulations = n, torch.device("cpu"), set()
        self.q = torch.tensor(q, dtype=torch.float32)
        self.q0 = torch.tensor(q0 if q0 is not None else [[1.0, 0, 0, 0]] * n, dtype=torch.float32)
        self.actor = SimpleNamespace(linear_velocity=torch.tensor(lin or [[0.0] * 3] * n),
                                     angular_velocity=torch.tensor(ang or [[0.0] * 3] * n))

    def obj_pose(self, name):
        return SimpleNamespace(p=torch.zeros(self.num_envs, 3), q=self.q)

    def init_obj_quat(self, name):
        return self.q0

    def obj(self, name):
        return self.actor


def holds(env, kind: str, **kw) -> list[bool]:
    return condition_holds(env, ConditionSpec(type=kind, object="bottle", **kw)).tolist()


def test_upright_is_a_lean_within_its_tolerance_whichever_way_and_however_turned_about_the_vertical():
    tol = CONDITION_DEFAULTS["max_tilt_deg"]
    rows = [_quat((1, 0, 0), tol - EPS_DEG), _quat((0, 1, 0), -(tol - EPS_DEG)), _quat((1, 1, 0), tol + EPS_DEG),
            _quat((0, 0, 1), 170.0), _mul(_quat((0, 0, 1), 90), _quat((1, 0, 0), tol - EPS_DEG)),
            _quat((1, 0, 0), 90.0)]
    assert holds(_Env(rows), "upright") == [True, True, False, True, True, False]
    assert holds(_Env(rows[:3]), "upright", max_tilt_deg=5.0) == [False, False, False]


def test_up_is_the_axis_that_pointed_up_at_reset():
    """An object that started lying on its side (turned 90 deg about x) is upright while it still lies so, and flipped
    once that axis points down."""
    side = _quat((1, 0, 0), 90)
    env = _Env([side, _mul(_quat((0, 0, 1), 45), side), _quat((1, 0, 0), -90), [1.0, 0, 0, 0]], q0=[side] * 4)
    assert holds(env, "upright") == [True, True, False, False]
    assert holds(env, "flipped") == [False, False, True, False]


def test_flipped_needs_the_up_axis_turned_past_its_tolerance():
    tol = CONDITION_DEFAULTS["min_tilt_deg"]
    rows = [_quat((1, 0, 0), 180), _quat((0, 1, 0), tol + EPS_DEG), _quat((1, -1, 0), tol - EPS_DEG),
            _quat((1, 0, 0), 90), [1.0, 0, 0, 0], _mul(_quat((0, 0, 1), 30), _quat((0, 1, 0), 180))]
    assert holds(_Env(rows), "flipped") == [True, True, False, False, False, True]
    assert holds(_Env(rows), "flipped", min_tilt_deg=80.0) == [True, True, True, True, False, True]
    assert holds(_Env(rows[:1]), "flipped", negate=True) == [False]


def test_at_rest_bounds_both_speed_and_spin():
    v, w = CONDITION_DEFAULTS["max_speed_m_s"], CONDITION_DEFAULTS["max_spin_rad_s"]
    lin = [[v * 0.99, 0, 0], [0, 0, -v * 1.01], [0, 0, 0], [0, 0, 0], [v * 0.6, v * 0.6, 0]]
    ang = [[0, 0, 0], [0, 0, 0], [0, w * 0.99, 0], [w * 1.01, 0, 0], [0, 0, 0]]
    env = _Env([[1.0, 0, 0, 0]] * 5, lin=lin, ang=ang)
    assert holds(env, "at_rest") == [True, False, True, False, True]
    assert holds(env, "at_rest", max_speed_m_s=v * 0.5, max_spin_rad_s=w * 2) == [False, False, True, True, False]


def _spec(cond: dict) -> dict:
    return {"name": "T", "instruction": "Do it.",
            "objects": [{"name": "bottle", "asset": "bottle", "pos_m": [0.1, 0.0, 0.0]}],
            "stages": [{"name": "s", "instruction": "Do it.", "skill": "reach", "method": "motion_planning",
                        "control_joint": "arm"}],
            "success": {"description": "Done.", "conditions": [cond]}}


@pytest.mark.parametrize("cond, words", [
    ({"type": "upright", "object": "bottle", "max_tilt_deg": 0}, "max_tilt_deg"),
    ({"type": "upright", "object": "bottle", "max_tilt_deg": 180}, "(0, 180)"),
    ({"type": "flipped", "object": "bottle", "min_tilt_deg": 181}, "(0, 180]"),
    ({"type": "at_rest", "object": "bottle", "max_speed_m_s": 0}, "> 0"),
    ({"type": "at_rest", "object": "bottle", "max_spin_rad_s": -1}, "> 0"),
    ({"type": "upright", "object": "bottle", "min_tilt_deg": 10}, "does not apply to type 'upright'"),
    ({"type": "at_rest"}, "object is required"),
    ({"type": "flipped", "object": "cup"}, "cup"),
])
def test_the_spec_refuses_bad_values_naming_the_field(cond, words):
    with pytest.raises(TaskSpecError, match=words.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[")
                       .replace("]", r"\]")):
        parse_task_spec(_spec(cond), source="test")
