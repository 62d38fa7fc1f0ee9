"""Pure, batched geometry on torch tensors. Quaternions are (w, x, y, z); every function keeps the batch dim."""

from __future__ import annotations

import math

import torch


def quat_rotate(q_wxyz: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """Rotate vectors ``v`` [N, 3] by unit quaternions ``q_wxyz`` [N, 4] -> [N, 3]."""
    w, xyz = q_wxyz[..., :1], q_wxyz[..., 1:]
    t = 2.0 * torch.linalg.cross(xyz, v, dim=-1)
    return v + w * t + torch.linalg.cross(xyz, t, dim=-1)


def quat_conj(q_wxyz: torch.Tensor) -> torch.Tensor:
    """The conjugate (the inverse of a unit quaternion) of quaternions [..., 4]."""
    return q_wxyz * torch.tensor([1.0, -1.0, -1.0, -1.0], dtype=q_wxyz.dtype, device=q_wxyz.device)


def quat_mul(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product a * b of quaternions [N, 4] -> [N, 4] (apply b, then a)."""
    aw, ax, ay, az = a.unbind(-1)
    bw, bx, by, bz = b.unbind(-1)
    return torch.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        dim=-1,
    )


def yaw_quat(yaw_rad: torch.Tensor) -> torch.Tensor:
    """Rotation about world z by ``yaw_rad`` [N] -> quaternions [N, 4]."""
    half = 0.5 * yaw_rad
    zeros = torch.zeros_like(half)
    return torch.stack([torch.cos(half), zeros, zeros, torch.sin(half)], dim=-1)


def transform_points(p: torch.Tensor, q_wxyz: torch.Tensor, local: torch.Tensor) -> torch.Tensor:
    """World position [N, 3] of a point ``local`` ([3] or [N, 3]) given frame position p [N, 3] and rotation [N, 4]."""
    return p + quat_rotate(q_wxyz, local.expand_as(p))


def box_rest_point(p: torch.Tensor, q_wxyz: torch.Tensor, lo: torch.Tensor, hi: torch.Tensor) -> torch.Tensor:
    """[N, 3] where an object with the box ``[lo, hi]`` (its frame, [3] each) posed at ``p`` [N, 3], ``q_wxyz``
    [N, 4] lies: the centre of the box seen from above, at the height of the frame's origin or of the box's centre,
    whichever is lower. For an object standing as built (the origin at the centre of its box's bottom face) that is
    its origin, however it is turned about the vertical; a bottle lying on its side lies at its middle, not at its
    base; a ball rolled upside down, its origin now on top, at its centre's height, not 6.6 cm over its bottom. Both
    heights are points of the object's own box that the object sits around: an estimate of the lowest point from the
    box (its lowest corner, or its inscribed ellipsoid's lowest point) put an apple scan rolled over in a bowl 1.9 cm
    under its collision shape's lowest point, and under the bowl."""
    center = transform_points(p, q_wxyz, (lo + hi) / 2)
    return torch.cat([center[:, :2], torch.minimum(p[:, 2:], center[:, 2:])], dim=-1)


def xy_distance(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Horizontal distance between positions a, b [N, 3] -> [N], metres."""
    return torch.linalg.norm(a[..., :2] - b[..., :2], dim=-1)


def z_twist(q_wxyz: torch.Tensor, q0_wxyz: torch.Tensor) -> torch.Tensor:
    """[N] signed angle (rad, wrapped to (-pi, pi]) of the twist about world z of the rotation from ``q0`` to ``q``
    (that is, of ``q * conj(q0)``); positive is counter-clockwise seen from above."""
    w0, x0, y0, z0 = q0_wxyz[:, 0], -q0_wxyz[:, 1], -q0_wxyz[:, 2], -q0_wxyz[:, 3]
    w1, x1, y1, z1 = q_wxyz[:, 0], q_wxyz[:, 1], q_wxyz[:, 2], q_wxyz[:, 3]
    dw = w1 * w0 - x1 * x0 - y1 * y0 - z1 * z0
    dz = w1 * z0 + x1 * y0 - y1 * x0 + z1 * w0
    angle = 2.0 * torch.atan2(dz, dw)
    return torch.remainder(angle + math.pi, 2.0 * math.pi) - math.pi


def tilt(q_wxyz: torch.Tensor, q0_wxyz: torch.Tensor) -> torch.Tensor:
    """[N] angle (rad, in [0, pi]) between world up and the object axis that pointed up at ``q0``, now at ``q``: 0
    for an object standing as it stood at ``q0`` (turned about the vertical or not), pi for one turned upside down."""
    up = torch.zeros_like(q_wxyz[:, 1:])
    up[:, 2] = 1.0
    axis = quat_rotate(q_wxyz, quat_rotate(quat_conj(q0_wxyz), up))
    return torch.acos(axis[:, 2].clamp(-1.0, 1.0))
