import math

import numpy as np
import pytest
import torch
from scipy.spatial.transform import Rotation

from gendex_envs.geometry import box_rest_point, quat_mul, quat_rotate, transform_points, xy_distance, yaw_quat


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


def test_box_rest_point_is_the_origin_of_a_standing_box_and_the_middle_of_a_lying_one():
    """A 0.22 m bottle-like box, origin at its bottom centre: standing (turned about z, anywhere) it lies at its
    origin; laid on its side, at the middle of its length seen from above, at its origin's height. A ball turned
    any way lies under its centre, no higher than its centre."""
    lo, hi = torch.tensor([-0.03, -0.03, 0.0]), torch.tensor([0.03, 0.03, 0.22])
    p = torch.tensor([[0.1, -0.2, 0.76], [0.1, -0.2, 0.76]])
    standing = yaw_quat(torch.tensor([0.0, 1.1]))
    torch.testing.assert_close(box_rest_point(p, standing, lo, hi), p)
    # about world y by +90 deg: the body's +z (base -> cap) points along world +x; its side lies on the table
    lying = torch.tensor([[math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0]]).expand(2, 4)
    p_lying = torch.tensor([[0.1, -0.2, 0.79], [0.0, 0.0, 0.79]])  # the origin 3 cm up: the radius
    torch.testing.assert_close(box_rest_point(p_lying, lying, lo, hi), p_lying + torch.tensor([0.11, 0.0, 0.0]))
    ball_lo, ball_hi = torch.tensor([-0.033, -0.033, 0.0]), torch.tensor([0.033, 0.033, 0.066])
    turned = torch.tensor(Rotation.random(8, random_state=4).as_quat()[:, [3, 0, 1, 2]], dtype=torch.float32)
    origin = torch.rand(8, 3)
    centre = origin + quat_rotate(turned, torch.tensor([[0.0, 0.0, 0.033]]).expand(8, 3))
    expected = torch.cat([centre[:, :2], torch.minimum(origin[:, 2:], centre[:, 2:])], dim=-1)
    torch.testing.assert_close(box_rest_point(origin, turned, ball_lo, ball_hi), expected)
    # upside down (half a turn about x) the origin is on top of the ball: it lies at its centre's height
    flipped = torch.tensor([[0.0, 1.0, 0.0, 0.0]])
    top = torch.tensor([[0.2, 0.1, 0.766 + 0.066]])
    torch.testing.assert_close(box_rest_point(top, flipped, ball_lo, ball_hi), torch.tensor([[0.2, 0.1, 0.799]]))
