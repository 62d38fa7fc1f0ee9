import math

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation

from gendex_envs.geometry import quat_mul, quat_rotate, transform_points, xy_distance, yaw_quat


def _to_scipy(q_wxyz: torch.Tensor) -> Rotation:
    return Rotation.from_quat(q_wxyz[:, [1, 2, 3, 0]].numpy())


def test_quat_rotate_matches_scipy():
    rng = np.random.default_rng(0)
    q = torch.tensor(Rotation.random(16, random_state=1).as_quat()[:, [3, 0, 1, 2]], dtype=torch.float64)
    v = torch.tensor(rng.normal(size=(16, 3)))
    expected = _to_scipy(q).apply(v.numpy())
    np.testing.assert_allclose(quat_rotate(q, v).numpy(), expected, atol=1e-12)


def test_quat_mul_composes_like_rotation_product():
    a = torch.tensor(Rotation.random(8, random_state=2).as_quat()[:, [3, 0, 1, 2]], dtype=torch.float64)
    b = torch.tensor(Rotation.random(8, random_state=3).as_quat()[:, [3, 0, 1, 2]], dtype=torch.float64)
    expected = (_to_scipy(a) * _to_scipy(b)).as_matrix()
    np.testing.assert_allclose(_to_scipy(quat_mul(a, b)).as_matrix(), expected, atol=1e-12)


def test_yaw_quat_rotates_x_axis_in_the_plane():
    yaw = torch.tensor([0.0, math.pi / 2, math.pi, -math.pi / 2], dtype=torch.float64)
    x = torch.tensor([[1.0, 0.0, 0.0]], dtype=torch.float64).expand(4, 3)
    out = quat_rotate(yaw_quat(yaw), x)
    expected = torch.stack([torch.cos(yaw), torch.sin(yaw), torch.zeros(4, dtype=torch.float64)], dim=-1)
    torch.testing.assert_close(out, expected)


def test_transform_points_and_xy_distance():
    p = torch.tensor([[1.0, 2.0, 3.0]])
    q = yaw_quat(torch.tensor([math.pi / 2]))
    out = transform_points(p, q, torch.tensor([1.0, 0.0, 0.5]))
    torch.testing.assert_close(out, torch.tensor([[1.0, 3.0, 3.5]]))
    assert xy_distance(out, torch.tensor([[4.0, 7.0, -9.0]])).item() == pytest.approx(5.0)
