"""The task env's cameras: three fixed views of the table (rendering, the critic's refinement, the docs, datasets)
and a camera on the palm, all sensors of the env; the three views are also its human-render cameras.

Every sensor a ManiSkill env declares is rendered at every step of an ``obs_mode="rgb"`` env, used or not; on a CPU
renderer that is most of a step's time (a dataset build's worker rendering four 96 px cameras spent 60 % of its time
in ``Camera.get_obs``, benchmarks/results/collect.md). ``sensors=`` declares only the cameras asked for.
"""

from __future__ import annotations

from collections.abc import Sequence

import sapien
from mani_skill.sensors.camera import CameraConfig
from mani_skill.utils import sapien_utils
from mani_skill.utils.structs import Pose

from gendex_envs.errors import RenderModeError, suggest

VIEW_CAMERAS = ("left_overhead", "right_overhead", "top_down")
"""The three scene views used by rendering, refinement and the docs."""
HAND_CAMERA = "hand_camera"
SENSOR_CAMERAS = (*VIEW_CAMERAS, HAND_CAMERA)
"""Every sensor camera of the env, in the order it declares them."""
WORKSPACE_TARGET = (0.1, 0.0, 0.08)
"""Where the overhead views look: the middle of the workspace in front of the robot."""


def look_at(eye, target, up=(0.0, 0.0, 1.0)) -> Pose:
    return sapien_utils.look_at(eye=list(eye), target=list(target), up=list(up))


def view_poses() -> dict[str, Pose]:
    """Each view's camera pose, by name (:data:`VIEW_CAMERAS`)."""
    return {
        "left_overhead": look_at([0.0, 1.0, 0.9], WORKSPACE_TARGET),
        "right_overhead": look_at([0.0, -1.0, 0.9], WORKSPACE_TARGET),
        "top_down": look_at([0.05, 0.0, 1.6], [0.05, 0.0, 0.0], up=[1.0, 0.0, 0.0]),
    }


def check_sensors(sensors: Sequence[str] | None) -> tuple[str, ...] | None:
    """``sensors`` as a tuple (None: every camera); :class:`RenderModeError` naming an unknown or repeated camera
    and the allowed ones, or saying that none was named."""
    if sensors is None:
        return None
    if isinstance(sensors, str):
        sensors = (sensors,)
    names = tuple(sensors)
    if not names:
        raise RenderModeError(f"sensors: name at least one camera of {list(SENSOR_CAMERAS)} (None: all of them)")
    for name in names:
        if name not in SENSOR_CAMERAS:
            raise RenderModeError(f"sensors: {name!r} is not a camera of the env; allowed: {list(SENSOR_CAMERAS)}."
                                  f"{suggest(str(name), SENSOR_CAMERAS)}")
    if len(set(names)) != len(names):
        raise RenderModeError(f"sensors: a camera is named twice in {list(names)}")
    return names


def sensor_configs(resolution: int, palm_link, sensors: tuple[str, ...] | None = None) -> list[CameraConfig]:
    """The env's sensor cameras at ``resolution`` px (only ``sensors`` when given): the views, then the hand camera
    on the palm, looking out of it (-y of the palm frame) towards the grasp."""
    views = [CameraConfig(uid=n, pose=p, width=resolution, height=resolution, fov=1.0, near=0.01, far=10.0)
             for n, p in view_poses().items()]
    mount = sapien.Pose(p=[0.0, -0.06, 0.03], q=[0.7071068, 0.0, 0.0, -0.7071068])
    hand = CameraConfig(uid=HAND_CAMERA, pose=mount, width=resolution, height=resolution, fov=1.4, near=0.01,
                        far=5.0, mount=palm_link)
    return [c for c in (*views, hand) if sensors is None or c.uid in sensors]


def human_camera_configs(resolution: int) -> list[CameraConfig]:
    """The three views at ``resolution`` px, as the env's human-render cameras."""
    return [CameraConfig(uid=n, pose=p, width=resolution, height=resolution, fov=1.0, near=0.01, far=10.0)
            for n, p in view_poses().items()]
