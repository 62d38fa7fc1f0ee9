"""PD joint-position controller with frozen joints and coupled (mimic) joints, batched over envs.

One controller drives *every* joint of the robot so that frozen joints keep a drive target: the action only writes
the free joints; frozen joints hold the target they had (the measured pose at reset); follower joints copy their
leader's target (the ShadowHand's distal joints J0 follow the middle joints J1, as MuJoCo's tendons couple them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import torch
from gymnasium import spaces
from mani_skill.agents.controllers.pd_joint_pos import PDJointPosController, PDJointPosControllerConfig
from mani_skill.utils.structs.types import Array

from gendex_envs.errors import ControlModeError
from gendex_envs.physx import px_objects


class FreezingJointPosController(PDJointPosController):
    """Absolute or delta joint-position targets for the free joints; frozen joints hold, followers mimic."""

    config: FreezingJointPosControllerConfig

    def _initialize_joints(self):
        super()._initialize_joints()
        names = list(self.config.joint_names)
        unknown = [n for n in (*self.config.free_joint_names, *self.config.mimic, *self.config.mimic.values())
                   if n not in names]
        if unknown:
            raise ControlModeError(f"joints {unknown} are not driven by this controller; known joints: {names}")
        followers = set(self.config.mimic)
        free = [n for n in self.config.free_joint_names if n not in followers]
        if not free:
            raise ControlModeError("a controller needs at least one free joint")
        device = self.device
        self.free_idx = torch.tensor([names.index(n) for n in free], dtype=torch.long, device=device)
        """[F] positions (in ``joint_names``) of the joints the action drives."""
        self.follower_idx = torch.tensor([names.index(n) for n in self.config.mimic], dtype=torch.long, device=device)
        self.leader_idx = torch.tensor([names.index(n) for n in self.config.mimic.values()], dtype=torch.long,
                                       device=device)
        self.free_joint_names = tuple(free)
        self._qlimits = self.articulation.get_qlimits()[0, self.active_joint_indices].to(device)
        """[J, 2] limits of every driven joint."""
        free_limits = self._qlimits[self.free_idx]
        self._free_lo, self._free_hi = free_limits[:, 0].contiguous(), free_limits[:, 1].contiguous()
        """[F] the free joints' limits, indexed once (an action moves them every step)."""
        self._px_joints = [px_objects(joint)[0] for joint in self.joints]

    def set_drive_targets(self, targets: torch.Tensor):
        if self.scene.gpu_sim_enabled:
            return super().set_drive_targets(targets)
        # CPU (one env): straight to the PhysX joints; ManiSkill's per-joint wrapper costs ~5 us a joint
        for joint, target in zip(self._px_joints, targets[0].tolist(), strict=True):
            joint.set_drive_target(target)

    def _get_joint_limits(self) -> np.ndarray:
        free = self.free_idx.cpu().numpy()
        if self.config.use_delta:
            lo = np.broadcast_to(np.asarray(self.config.lower, dtype=np.float32), (len(free),))
            hi = np.broadcast_to(np.asarray(self.config.upper, dtype=np.float32), (len(free),))
            return np.stack([lo, hi], axis=1)
        qlimits = self.articulation.get_qlimits()[0, self.active_joint_indices].cpu().numpy()
        return qlimits[free]

    def _initialize_action_space(self):
        limits = self._get_joint_limits()
        self.single_action_space = spaces.Box(limits[:, 0], limits[:, 1], dtype=np.float32)

    def _clip_and_scale_action_space(self):
        super()._clip_and_scale_action_space()
        # ManiSkill scales an action by mid + half * clip(action) with both halves recomputed every step; they are
        # constants, computed here once by the same float32 operations, so the scaled actions are the same values
        self._action_mid = 0.5 * (self.action_space_high + self.action_space_low)
        self._action_half = 0.5 * (self.action_space_high - self.action_space_low)

    def _clip_and_scale_action(self, action):
        return self._action_mid + self._action_half * torch.clip(action, -1, 1)

    def set_action(self, action: Array):
        action = self._preprocess_action(action)  # [N, F]
        self._step = 0
        if self.config.interpolate:  # the measured start is needed only to interpolate towards the target
            self._start_qpos = self.qpos
        if self.config.use_delta:
            target = self.moved_targets(self.free_idx, action, from_qpos=not self.config.use_target)
        else:
            target = self._target_qpos.clone()  # [N, J]
            target[:, self.free_idx] = action
            self._mimic(target)
        self._target_qpos = target
        if self.config.interpolate:
            self._step_size = (self._target_qpos - self._start_qpos) / self._sim_steps
        else:
            self.set_drive_targets(self._target_qpos)

    @property
    def target_qpos(self) -> torch.Tensor:
        """[N, J] a copy of the current drive targets of every joint (free, frozen and coupled), in
        ``config.joint_names`` order."""
        return self._target_qpos.clone()

    def free_targets(self) -> torch.Tensor:
        """[N, F] a copy of the current drive targets of the joints the action drives."""
        return self._target_qpos[:, self.free_idx].clone()

    def joint_indices(self, names: Sequence[str]) -> torch.Tensor:
        """[K] positions of joints ``names`` in this controller's ``joint_names``."""
        order = list(self.config.joint_names)
        unknown = [n for n in names if n not in order]
        if unknown:
            raise ControlModeError(f"joints {unknown} are not driven by this controller; known joints: {order}")
        return torch.tensor([order.index(n) for n in names], dtype=torch.long, device=self.device)

    def moved_targets(self, idx: torch.Tensor, delta: torch.Tensor, from_qpos: bool = False) -> torch.Tensor:
        """[N, J] targets after moving joints ``idx`` by ``delta`` [N, K] from their current targets (or measured
        positions), clipped to the joint limits (no wind-up past a limit: the targets an absolute controller would
        get), followers copying their leaders. The rule of a delta action, for any subset of joints: a stage
        policy's deltas run through the stage executor's absolute controller with it."""
        target = self._target_qpos.clone()
        base = (self.qpos if from_qpos else target)[:, idx]
        if idx is self.free_idx:
            lo, hi = self._free_lo, self._free_hi
        else:
            lim = self._qlimits[idx]
            lo, hi = lim[:, 0], lim[:, 1]
        target[:, idx] = torch.clamp(base + torch.as_tensor(delta, dtype=target.dtype, device=target.device), lo, hi)
        self._mimic(target)
        return target

    def _mimic(self, target: torch.Tensor) -> None:
        if len(self.follower_idx):
            target[:, self.follower_idx] = target[:, self.leader_idx]

    def reset(self):
        super().reset()
        # followers start on their leader's target so the first action does not jerk them
        if len(self.follower_idx) and self._target_qpos is not None:
            self._target_qpos[:, self.follower_idx] = self._target_qpos[:, self.leader_idx]
            self.set_drive_targets(self._target_qpos)

    def get_state(self) -> dict:
        # always save the targets: frozen joints' targets are part of the state
        return {"target_qpos": self._target_qpos}

    def set_state(self, state: dict):
        self._target_qpos = state["target_qpos"]
        self.set_drive_targets(self._target_qpos)


@dataclass
class FreezingJointPosControllerConfig(PDJointPosControllerConfig):
    """Config of :class:`FreezingJointPosController`. ``joint_names`` lists every driven joint."""

    free_joint_names: Sequence[str] = ()
    """Joints the action drives (a subset of ``joint_names``); the rest are frozen at their current target."""
    mimic: dict[str, str] = field(default_factory=dict)
    """follower joint -> leader joint; the follower's target is the leader's target."""
    controller_cls = FreezingJointPosController
