"""`gendex tasks-doc`: a gallery row and a picture for every task, with what the solvability gate measured."""

import json
import shutil

from PIL import Image

from gendex_envs.registry import registered_tasks
from gendex_envs.task_version import TaskLayout, TaskVersion
from generator.task_gallery import write_task_gallery


def test_gallery_has_a_row_and_a_real_picture_per_task_and_shows_gate_results(tmp_path, repo_root):
    # two copies of a library task: one without a solvability record, one with a given one
    src = next(v for v in registered_tasks().values() if v.name == "LiftApple")
    plain = tmp_path / "tasks" / "LiftApple" / "v0"
    src.copy_to(plain)
    TaskLayout(plain).record("solvability").unlink(missing_ok=True)
    folder = tmp_path / "tasks" / "LiftAppleGated" / "v0"
    shutil.copytree(plain, folder)
    spec = TaskLayout(folder).spec
    spec.write_text(spec.read_text().replace("name: LiftApple", "name: LiftAppleGated"))
    TaskLayout(folder).record("solvability").write_text(json.dumps(
        {"attempts": 10, "successes": 9, "env_steps_per_success": 123.4, "planned_attempts": 10}))
    versions = {"GenDex/LiftApple-v0": TaskVersion.at(plain), "GenDex/LiftAppleGated-v0": TaskVersion.at(folder)}
    out = write_task_gallery(versions, tmp_path / "docs" / "tasks.md", size=96)
    text = out.read_text()
    rows = [ln for ln in text.splitlines() if ln.startswith("| ![")]
    assert len(rows) == 2
    gated = next(r for r in rows if "LiftAppleGated" in r)
    assert "| 9/10 | 123 |" in gated and "lift" in gated and "`apple`" in gated
    assert "| — | — |" in next(r for r in rows if "LiftAppleGated" not in r)
    pic = tmp_path / "docs" / "tasks" / "LiftApple-v0.png"
    assert f"](tasks/{pic.name})" in text
    img = Image.open(pic)
    assert img.size == (96, 96) and len(set(img.getdata())) > 50  # a rendered scene, not a blank frame


def test_a_published_versions_picture_is_kept_unless_asked_to_draw_it_again(tmp_path):
    """A version's folder never changes once published: tasks-doc keeps its picture (a library of hundreds would
    otherwise be drawn again for one new task), and --rerender draws it again."""
    src = next(v for v in registered_tasks().values() if v.name == "LiftApple")
    versions = {src.env_id: src}
    out = tmp_path / "docs" / "tasks.md"
    pic = tmp_path / "docs" / "tasks" / f"LiftApple-v{src.version}.png"
    pic.parent.mkdir(parents=True)
    Image.new("RGB", (96, 96), (255, 0, 0)).save(pic)
    write_task_gallery(versions, out, size=96)
    assert set(Image.open(pic).getdata()) == {(255, 0, 0)}  # kept
    write_task_gallery(versions, out, size=128)
    assert Image.open(pic).size == (128, 128)  # another size: drawn again
    Image.new("RGB", (128, 128), (255, 0, 0)).save(pic)
    write_task_gallery(versions, out, size=128, rerender=True)
    assert len(set(Image.open(pic).getdata())) > 50


def test_a_reworded_version_takes_its_sources_picture_and_stale_pictures_go(tmp_path, task_copy):
    """A rewording changes the instruction only: its picture is its source's, not drawn again; a picture of a
    version the gallery no longer shows is removed (the gallery of a reworded library held both)."""
    from generator.reword import publish_reworded

    src = task_copy("LiftApple", as_name="ScratchApple")
    new = publish_reworded(src, "Raise the apple off the counter.", {"reason": "test"})
    out = tmp_path / "docs" / "tasks.md"
    pictures = tmp_path / "docs" / "tasks"
    pictures.mkdir(parents=True)
    Image.new("RGB", (96, 96), (0, 0, 255)).save(pictures / f"ScratchApple-v{src.version}.png")
    Image.new("RGB", (96, 96), (0, 255, 0)).save(pictures / "GoneTask-v3.png")
    (pictures / "notes.txt").write_text("not a picture of a version")
    write_task_gallery({src.env_id: src, new.env_id: new}, out, size=96)
    pic = pictures / f"ScratchApple-v{new.version}.png"
    assert set(Image.open(pic).getdata()) == {(0, 0, 255)}  # the source's, copied
    assert sorted(p.name for p in pictures.iterdir()) == [pic.name, "notes.txt"]
    assert f"tasks/{pic.name}" in out.read_text()


def test_a_rewording_record_naming_no_task_id_gets_its_picture_drawn(tmp_path, task_copy):
    """A task folder is untrusted: a reword record whose source is a path, a malformed id or no string at all is
    no source picture, and the gallery draws the version's own (it crashed on a malformed id)."""
    from gendex_envs.task_version import TaskLayout

    src = task_copy("LiftApple", as_name="ScratchApple")
    out = tmp_path / "docs" / "tasks.md"
    for source in ("../../../etc/passwd", 42, "GenDex/ScratchApple"):
        TaskLayout(src.root).record("reword").write_text(json.dumps({"source": source, "old": "a", "new": "b"}))
        write_task_gallery({src.env_id: TaskVersion.at(src.root)}, out, size=64, rerender=True)
        pic = tmp_path / "docs" / "tasks" / f"ScratchApple-v{src.version}.png"
        assert len(set(Image.open(pic).getdata())) > 50, source  # drawn, not copied from anywhere

