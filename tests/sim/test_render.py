"""The three scene views show the robot, the table and every object; the CLI writes them as PNGs."""

import numpy as np
import pytest
from mani_skill.utils.structs import Articulation
from PIL import Image
from typer.testing import CliRunner

from gendex.cli import app
from gendex_envs.registry import REFERENCE_TASKS as REFERENCE_NAMES
from gendex_envs.task_env import VIEW_CAMERAS

REFERENCE_TASKS = tuple(f"GenDex/{name}-v0" for name in REFERENCE_NAMES)  # version 0 of each reference task


def _seg_ids(entity) -> set[int]:
    """Segmentation ids of an Actor or of every link of an Articulation."""
    if isinstance(entity, Articulation):
        return {link._objs[0].entity.per_scene_id for link in entity.get_links()}
    return {obj.per_scene_id for obj in entity._objs}


@pytest.mark.parametrize("env_id", REFERENCE_TASKS)
def test_views_show_robot_table_and_objects(make_env, env_id):
    env = make_env(env_id, obs_mode="rgb+segmentation", gym_api=False, sensor_resolution=160)
    u = env.unwrapped
    obs, _ = env.reset(seed=0)
    id_map = u.segmentation_id_map
    robot_ids = _seg_ids(u.agent.robot)
    object_ids = {name: _seg_ids(entity) for name, entity in u.objects.items()}
    for cam in VIEW_CAMERAS:
        seg = obs["sensor_data"][cam]["segmentation"][0, ..., 0].cpu().numpy()
        ids, counts = np.unique(seg, return_counts=True)
        visible = dict(zip(ids.tolist(), counts.tolist(), strict=True))
        names = {id_map[i].name if i in id_map else None for i in visible}
        assert "table" in names, f"{cam}: table not visible ({names})"
        assert sum(visible.get(i, 0) for i in robot_ids) > 200, f"{cam}: robot barely visible"
        for obj, ids in object_ids.items():
            pixels = sum(visible.get(i, 0) for i in ids)
            assert pixels > 30, f"{cam}: object {obj!r} covers only {pixels} px"
        rgb = obs["sensor_data"][cam]["rgb"][0].cpu().numpy()
        assert rgb.std() > 10, f"{cam}: image is flat"


def test_cli_render_writes_three_pngs(tmp_path):
    result = CliRunner().invoke(app, ["render", "GenDex/PutAppleBowl-v0", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    pngs = sorted(tmp_path.glob("*.png"))
    assert [p.name for p in pngs] == [f"PutAppleBowl-v0_{c}.png" for c in sorted(VIEW_CAMERAS)]
    for p in pngs:
        img = np.asarray(Image.open(p))
        assert img.shape == (512, 512, 3) and img.std() > 10


def test_cli_render_unknown_task_is_a_clear_error(tmp_path):
    result = CliRunner().invoke(app, ["render", "GenDex/PutAppleBowel-v0", "--out", str(tmp_path)])
    assert result.exit_code == 2
    assert "PutAppleBowl-v0" in result.output  # suggestion
    assert not list(tmp_path.iterdir())


def test_cli_list_shows_the_tasks_asked_for():
    """``gendex list PATTERN`` lists the IDs containing PATTERN (any case), ``--latest`` the newest of each task;
    a pattern no ID contains exits 2 saying so (every version is listed without a pattern: ``test_promote``)."""
    def ids(output: str) -> list[str]:  # a listed task starts its line with its ID; its details may name others
        return [line.split()[0] for line in output.splitlines() if line.startswith("GenDex/")]

    for env_id in REFERENCE_TASKS:
        result = CliRunner().invoke(app, ["list", env_id.split("/")[1].lower()])
        assert result.exit_code == 0 and ids(result.output) == [env_id], result.output  # no other ID has it inside
    name = REFERENCE_TASKS[0].split("/")[1].rsplit("-v", 1)[0]
    every = ids(CliRunner().invoke(app, ["list", name + "-v"]).output)
    newest = ids(CliRunner().invoke(app, ["list", name + "-v", "--latest"]).output)
    assert len(every) > 1 and newest == [max(every, key=lambda i: int(i.rsplit("-v", 1)[1]))]
    missing = CliRunner().invoke(app, ["list", "NoSuchTaskAnywhere"])
    assert missing.exit_code == 2 and "no registered task ID contains 'NoSuchTaskAnywhere'" in missing.output


def test_named_colours_show_in_the_views(task_version):
    """objects[i].color paints the object: the apple (red in the catalog) painted blue and the bowl (white) painted
    green show as blue- and green-dominated pixels in every view."""
    from gendex_envs.spec import parse_task_spec, spec_to_dict
    from gendex_envs.task_env import TaskEnv

    raw = spec_to_dict(task_version("PutAppleBowl", 0).spec)
    paint = {"apple": ("blue", 2), "bowl": ("green", 1)}  # colour, the channel that must dominate
    for obj in raw["objects"]:
        obj["color"], obj["color_rgba"] = paint[obj["name"]][0], None
    env = TaskEnv(task_spec=parse_task_spec(raw), obs_mode="rgb+segmentation", sensor_resolution=128)
    try:
        obs, _ = env.reset(seed=0)
        for cam in VIEW_CAMERAS:
            seg = obs["sensor_data"][cam]["segmentation"][0, ..., 0].cpu().numpy()
            rgb = obs["sensor_data"][cam]["rgb"][0].cpu().numpy().astype(float)
            for name, (colour, channel) in paint.items():
                mask = np.isin(seg, list(_seg_ids(env.objects[name])))
                assert mask.sum() > 20, f"{cam}: {name} covers {mask.sum()} px"
                mean = rgb[mask].mean(axis=0)
                assert mean.argmax() == channel, f"{cam}: {name} painted {colour} looks {mean.round()}"
    finally:
        env.close()
