"""RotateTennisBall: roll the ball resting in the upturned palm a quarter turn about world z, keeping it in the palm.

Sense: counter-clockwise seen from above (positive rotation about world +z). The rotation is the twist about z of
the ball's rotation since reset, q * conj(q0), wrapped to (-pi, pi].
"""

import math

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0
TARGET_RAD = math.pi / 2
BALL_RADIUS_M = 0.0335 * 0.97
"""Catalog radius of tennis_ball times the task's scale; the asset's origin is its lowest point at rest, not its
centre, so the centre is found by rotating (0, 0, radius) with the ball."""
PALM_CENTRE_LOCAL = (0.021, -0.043, 0.077)
"""Where the ball's centre rests, in the palm link's frame (z along the fingers, -y out of the palm): measured by
letting the ball settle in the palm_up keyframe."""
DROP_DIST_M = 0.06
"""Ball centre further than this from the palm centre counts as dropped."""
MAX_SPIN_RAD_S = 3.0
"""Angular speed about z beyond which spinning earns nothing more (flicking the ball is not the goal)."""


def quat_rotate(q, v):
    """Rotate vectors v [N, 3] by unit quaternions q [N, 4] (wxyz)."""
    w = q[:, :1]
    u = q[:, 1:]
    t = 2.0 * torch.linalg.cross(u, v, dim=-1)
    return v + w * t + torch.linalg.cross(u, t, dim=-1)


def ball_centre(env):
    """[N, 3] world position of the ball's centre."""
    pose = env.obj_pose("ball")
    up = torch.zeros_like(pose.p)
    up[:, 2] = BALL_RADIUS_M
    return pose.p + quat_rotate(pose.q, up)


def palm_centre(env):
    """[N, 3] world position where the ball's centre rests in the palm, and [N, 3] the palm's outward normal."""
    palm = env.palm_pose
    local = torch.tensor(PALM_CENTRE_LOCAL, dtype=palm.p.dtype, device=palm.p.device).expand_as(palm.p)
    normal = torch.zeros_like(palm.p)
    normal[:, 1] = -1.0
    return palm.p + quat_rotate(palm.q, local), quat_rotate(palm.q, normal)


def z_twist(q, q0):
    """[N] signed angle (rad, wrapped to (-pi, pi]) of the twist about world z of the rotation q * conj(q0)."""
    w0, x0, y0, z0 = q0[:, 0], -q0[:, 1], -q0[:, 2], -q0[:, 3]
    w1, x1, y1, z1 = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    dw = w1 * w0 - x1 * x0 - y1 * y0 - z1 * z0
    dz = w1 * z0 + x1 * y0 - y1 * x0 + z1 * w0
    angle = 2.0 * torch.atan2(dz, dw)
    return torch.remainder(angle + math.pi, 2.0 * math.pi) - math.pi


def evaluate(env):
    centre = ball_centre(env)
    palm_c, normal = palm_centre(env)
    offset = centre - palm_c
    dist = torch.linalg.norm(offset, dim=-1)
    # below the palm: the centre has sunk under the palm surface (about one radius below its resting height)
    below = (offset * normal).sum(dim=-1) < -BALL_RADIUS_M
    dropped = (dist > DROP_DIST_M) | below
    rotation = z_twist(env.obj_pose("ball").q, env.init_obj_quat("ball"))
    return {"fail": dropped, "rotation": rotation, "palm_dist": dist}


def compute_dense_reward(env, obs, action, info):
    spin = env.obj("ball").angular_velocity[:, 2].clamp(-MAX_SPIN_RAD_S, MAX_SPIN_RAD_S) / MAX_SPIN_RAD_S
    progress = rt.fraction(info["rotation"] / TARGET_RAD)
    in_hand = rt.reach(info["palm_dist"], 0.03)
    tips = rt.tips_reach(env.tip_positions, ball_centre(env), 0.05)
    effort = (action.float() ** 2).mean(dim=-1).clamp(max=1.0)
    kept = (~info["fail"]).float()
    # spin and progress count only while the ball is held; staying in hand and touching it shape the exploration
    reward = kept * (2.0 * progress + spin + in_hand + 0.5 * tips) - 0.1 * effort
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    pose = env.obj_pose("ball")
    palm_c, normal = palm_centre(env)
    ball = env.obj("ball")
    return {"ball_in_palm": ball_centre(env) - palm_c, "ball_quat": pose.q,
            "ball_ang_vel": ball.angular_velocity, "ball_lin_vel": ball.linear_velocity,
            "ball_rotation": info["rotation"][:, None]}
