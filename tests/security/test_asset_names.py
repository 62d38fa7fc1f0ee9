"""An untrusted task folder names its assets by catalog id, never by path (issue 43, untrusted task folders).

``task.yaml``'s ``objects[i].asset`` is looked up in the asset catalog (``gendex_envs.assets.catalog``); it is never
joined to a folder. A hostile copy of a committed task whose asset is a path (``..`` out of the task folder or out of
the catalog's data folder, an absolute path, ``~``, a ``file://`` URL, a Windows path, a name with a NUL byte or a
newline) must be refused when the env is made, by ``gym.make`` of its registered id and by ``TaskEnv(task=folder)``,
with a :class:`TaskSpecError` naming the field and the bad value; nothing outside the copy may be opened or written
while it is refused (an audit hook records every path Python opens or lists during ``make``, and a sentinel file the
traversals aim at must stay as it was).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import gymnasium as gym
import pytest

import gendex_envs.assets.catalog as catalog
from gendex_envs.errors import TaskSpecError
from gendex_envs.registry import register_tasks, resolve_task, unregister_tasks
from gendex_envs.task_env import TaskEnv
from gendex_envs.task_version import NAMESPACE, TaskLayout, TaskVersion
from gendex_envs.typed_yaml import quote

SOURCE = "PutAppleBowl"
"""A committed task with two objects: ``apple`` (``objects[0]``) and ``bowl`` (``objects[1]``)."""
SECRET = "gendex-secret-asset.obj"
"""The sentinel file the traversals aim at; no path holding this name may be opened."""
MARKERS = (SECRET, "passwd", "id_rsa", "evil.obj")
"""Parts of the paths the payloads name: a path Python opens or lists during ``make`` must hold none of them."""

_SEEN: list[str] | None = None
"""Paths opened or listed while a test watches (None: not watching); filled by :func:`_audit`."""


def _audit(event: str, args: tuple) -> None:
    if _SEEN is None or event not in ("open", "os.listdir", "os.scandir", "os.mkdir", "os.rename", "os.remove",
                                      "shutil.copyfile", "shutil.rmtree"):
        return
    for arg in args[:2]:
        if isinstance(arg, (str, bytes, os.PathLike)):
            _SEEN.append(os.fsdecode(arg))


_HOOKED = False


def _watch() -> list[str]:
    """Start recording paths; the hook (audit hooks cannot be removed) costs one comparison when nothing watches."""
    global _HOOKED, _SEEN
    if not _HOOKED:
        sys.addaudithook(_audit)
        _HOOKED = True
    _SEEN = []
    return _SEEN


def _stop() -> None:
    global _SEEN
    _SEEN = None


def _payloads(sentinel: Path, folder: Path) -> dict[str, str]:
    """Bad asset names by id; the relative ones lead from the task folder or the catalog's data folder to the
    sentinel."""
    data = Path(catalog.__file__).parent / "data"
    return {
        "dotdot_etc_passwd": "../../../etc/passwd",
        "dotdot_from_task_folder": os.path.relpath(sentinel, folder),
        "dotdot_from_catalog_data": os.path.relpath(sentinel, data),
        "dotdot_from_a_catalog_group": os.path.relpath(sentinel, data / "objects"),
        "id_then_dotdot": "apple/../../../../../etc/passwd",
        "absolute_etc_passwd": "/etc/passwd",
        "absolute_sentinel": str(sentinel),
        "home": "~/.ssh/id_rsa",
        "file_url": f"file://{sentinel}",
        "backslash": "..\\..\\..\\etc\\passwd",
        "windows_absolute": "C:\\Windows\\evil.obj",
        "nul_after_id": "apple\x00../../../etc/passwd",
        "nul_before_path": "\x00/etc/passwd",
        "newline_then_path": "apple\n/etc/passwd",
        "dotdot_alone": "..",
        "mesh_file_name": "evil.obj",
    }


def _hostile_copy(root: Path, name: str, assets: dict[str, str]) -> Path:
    """A copy of :data:`SOURCE` as ``root/<name>/v0`` whose objects' assets are replaced (catalog id -> new name,
    written as a YAML double-quoted string so NUL and newline survive the file)."""
    folder = root / name / "v0"
    resolve_task(SOURCE).copy_to(folder)
    spec = TaskLayout(folder).spec
    text = spec.read_text().replace(f"name: {SOURCE}\n", f"name: {name}\n")
    for old, new in assets.items():
        assert f"    asset: {old}\n" in text
        text = text.replace(f"    asset: {old}\n", f"    asset: {json.dumps(new)}\n")
    spec.write_text(text)
    return folder


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.fixture
def places(tmp_path):
    """(tasks root, sentinel file): the root holds only the hostile copies; the sentinel is beside it."""
    sentinel = tmp_path / "outside" / SECRET
    sentinel.parent.mkdir()
    sentinel.write_text("v 0 0 0\n")
    return tmp_path / "tasks", sentinel


def _refused(make, folder: Path, sentinel: Path, fields: dict[str, str]) -> None:
    """``make()`` raises a TaskSpecError naming ``fields`` (path -> bad asset) and the file; nothing is read or
    written outside the copy."""
    before_copy, before_outside = _snapshot(folder), _snapshot(sentinel.parent)
    seen = _watch()
    try:
        with pytest.raises(TaskSpecError) as err:
            make()
    finally:
        _stop()
    text = str(err.value)
    assert str(TaskLayout(folder).spec) in text, text
    assert any(p.endswith(str(TaskLayout(folder).spec)) for p in seen), "the audit hook saw no read of the spec"
    for field, bad in fields.items():
        assert f"{field} = {quote(bad)} is not a known asset" in text, text
    leaked = [p for p in seen if any(m in p for m in MARKERS) or "\x00" in p]
    assert leaked == [], f"paths the spec names were opened or listed: {leaked}"
    assert _snapshot(sentinel.parent) == before_outside, "a refused make changed files outside the task folder"
    assert _snapshot(folder) == before_copy, "a refused make changed the task folder"


PAYLOADS = tuple(_payloads(Path("/"), Path("/")))
"""The payloads' ids (their values depend on the test's folders)."""


@pytest.mark.parametrize("payload", PAYLOADS)
def test_gym_make_refuses_an_asset_named_by_path(places, payload):
    root, sentinel = places
    name = "HostileAsset" + "".join(w.capitalize() for w in payload.split("_"))
    folder = root / name / "v0"
    bad = _payloads(sentinel, folder)[payload]
    _hostile_copy(root, name, {"apple": bad})
    env_id = f"{NAMESPACE}/{name}-v0"
    made = register_tasks([root])
    try:
        assert made == [env_id], made  # registration reads the spec without the catalog: make refuses it
        _refused(lambda: gym.make(env_id, render_backend="none"), folder, sentinel, {"objects[0].asset": bad})
    finally:
        unregister_tasks(made)


def test_task_env_refuses_every_bad_asset_of_a_folder_at_once(places):
    """Made from the folder (no registry), with both objects' assets bad: one error names both fields."""
    root, sentinel = places
    folder = root / "HostileAssetBoth" / "v0"
    bad = {"apple": "../../../etc/passwd", "bowl": str(sentinel)}
    _hostile_copy(root, "HostileAssetBoth", bad)
    _refused(lambda: TaskEnv(task=folder, obs_mode="state", render_backend="none"), folder, sentinel,
             {"objects[0].asset": bad["apple"], "objects[1].asset": bad["bowl"]})


def test_a_known_asset_id_still_loads(places):
    """The same kind of copy with catalog ids (swapped, so they differ from the committed task's) passes the
    catalog check that refuses the payloads above."""
    root, _ = places
    folder = _hostile_copy(root, "HonestAssetSwap", {"apple": "bowl", "bowl": "apple"})
    assert [o.asset for o in TaskVersion.at(folder).spec.objects] == ["bowl", "apple"]
