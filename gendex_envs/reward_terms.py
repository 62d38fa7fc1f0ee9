"""Vetted, batched reward terms that task reward modules compose. Every function returns [N] tensors in [0, 1].

The reward modules of task versions may import this module; the generator's validator
allows it alongside ``torch`` and ``math``.
"""

from __future__ import annotations

import torch

from gendex_envs.geometry import xy_distance


def reach(dist_m: torch.Tensor, scale_m: float = 0.1) -> torch.Tensor:
    """[N] 1 at distance 0, falling smoothly: 1 - tanh(dist / scale)."""
    return 1.0 - torch.tanh(dist_m / scale_m)


def tips_reach(tip_pos: torch.Tensor, target_p: torch.Tensor, scale_m: float = 0.1) -> torch.Tensor:
    """[N] mean :func:`reach` of the five fingertips ``tip_pos`` [N, 5, 3] to ``target_p`` [N, 3]."""
    d = torch.linalg.norm(tip_pos - target_p[:, None, :], dim=-1)  # [N, 5]
    return reach(d, scale_m).mean(dim=1)


def contact(group_force: torch.Tensor, min_force_n: float = 0.3) -> torch.Tensor:
    """[N] fraction of hand groups touching, from ``get_hand_group_obj_mean_force`` [N, 6, 1].

    The thumb (group 0) counts double: opposition is what makes a grasp.
    """
    touching = (group_force[..., 0] > min_force_n).float()  # [N, 6]
    return (touching[:, 0] * 2 + touching[:, 1:].sum(dim=1)) / 7.0


def lift(height_m: torch.Tensor, target_m: float) -> torch.Tensor:
    """[N] linear progress of a lift towards ``target_m``, clipped to [0, 1]."""
    return (height_m / target_m).clamp(0.0, 1.0)


def place(obj_p: torch.Tensor, target_p: torch.Tensor, scale_m: float = 0.1) -> torch.Tensor:
    """[N] horizontal closeness of an object to a target position."""
    return reach(xy_distance(obj_p, target_p), scale_m)


def fraction(value: torch.Tensor) -> torch.Tensor:
    """[N] a progress fraction clipped to [0, 1]."""
    return value.clamp(0.0, 1.0)
