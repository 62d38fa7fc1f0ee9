"""The task store (data files kept once by content) and the registration index: every reader still sees a whole
version, digests do not change, hostile trees and indexes are refused, and the committed library is packed and
indexed."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import gymnasium as gym
import pytest

from gendex_envs import task_index, task_store
from gendex_envs.registry import REPO_TASKS_DIR, register_tasks, unregister_tasks
from gendex_envs.task_store import OBJECTS, TREE_NAME, StoreError
from gendex_envs.task_version import TaskVersion, versions_in

REWORDED = ("CloseBoxWithLidLarge", 1)
"""A rewording (v1) whose source (v0) is a generated task with transcript, renders and generation records."""


def _whole_root(tmp_path: Path, *versions: tuple[str, int]) -> Path:
    root = tmp_path / "tasks"
    for name, v in versions:
        TaskVersion.at(REPO_TASKS_DIR / name / f"v{v}").copy_to(root / name / f"v{v}")
    return root


def _plain_files(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and "__pycache__" not in p.parts}


def test_a_committed_version_copies_out_whole_and_digests_as_the_committed_one(tmp_path):
    name, v = REWORDED
    committed = TaskVersion.at(REPO_TASKS_DIR / name / f"v{v}")
    copy = TaskVersion.at(committed.copy_to(tmp_path / "t" / name / f"v{v}"))
    assert not (copy.root / TREE_NAME).exists()
    assert (copy.root / "transcript.jsonl").is_file() and len(copy.renders()) == 6
    assert copy.file_digest() == committed.file_digest()


def test_packing_moves_data_out_keeps_digests_and_stores_a_rewordings_copies_once(tmp_path):
    name, v = REWORDED
    root = _whole_root(tmp_path, (name, v - 1), (name, v))
    versions = versions_in(root)
    whole = {ver.env_id: _plain_files(ver.root) for ver in versions}
    before = {ver.env_id: ver.file_digest() for ver in versions}
    results = [task_store.pack(ver.root) for ver in versions]
    assert all(r.moved > 0 for r in results)
    after = {ver.env_id: TaskVersion.at(ver.root).file_digest() for ver in versions}
    assert after == before
    for ver in versions:
        left = sorted(p.relative_to(ver.root).as_posix() for p in ver.root.rglob("*") if p.is_file())
        assert all(task_store.is_inline(rel) for rel in left), left
        assert "task.yaml" in left and "reward.py" in left and TREE_NAME in left
    # the rewording's transcript, renders and generation records are its source's: stored once
    trees = [task_store.load_tree(ver.root) for ver in versions]
    shared = {rel for rel in trees[0] if rel in trees[1] and trees[0][rel] == trees[1][rel]}
    assert {"transcript.jsonl", "generation.json", "renders/after_top_down.png"} <= shared
    objects = list((root / OBJECTS).glob("*/*"))
    assert len(objects) == len({e.sha256 for t in trees for e in t.values()}) < sum(len(t) for t in trees)
    # every reader sees the whole version
    ver = TaskVersion.at(versions[1].root)
    assert ver.renders().keys() == {p[len("renders/"):-4] for p in whole[ver.env_id] if p.startswith("renders/")}
    assert ver.renders()["after_top_down"].read_bytes() == whole[ver.env_id]["renders/after_top_down.png"]
    assert ver.provenance()["generation"] == json.loads(whole[ver.env_id]["generation.json"])
    assert ver.files.resolve(ver.files.transcript).read_bytes() == whole[ver.env_id]["transcript.jsonl"]
    # write paths stay in the folder: nothing written through a layout can change a shared object
    assert ver.files.transcript == ver.root / "transcript.jsonl" and not ver.files.transcript.exists()
    assert task_store.verify(root) == [] and task_store.unpacked_files(root) == []
    # unpacking gives the whole folder back, byte for byte
    task_store.unpack(ver.root)
    assert _plain_files(ver.root) == whole[ver.env_id]
    assert task_store.pack(ver.root).moved > 0 and TaskVersion.at(ver.root).file_digest() == before[ver.env_id]


def test_a_packed_policy_and_start_states_load_from_the_store(tmp_path):
    root = _whole_root(tmp_path, ("RotateTennisBall", 1))
    ver = versions_in(root)[0]
    stages = ver.artifacts.policy_stages()
    assert stages
    model = ver.policy(stages[0]).model.read_bytes()
    task_store.pack(ver.root)
    packed = TaskVersion.at(ver.root)
    assert packed.artifacts.policy_stages() == stages
    files = packed.policy(stages[0])
    assert files.model.parent.parent.name == OBJECTS and files.model.read_bytes() == model
    assert files.meta() == ver.policy(stages[0]).meta()


def test_a_changed_or_missing_object_fails_the_digest_by_name(tmp_path):
    name, v = REWORDED
    root = _whole_root(tmp_path, (name, v))
    ver = versions_in(root)[0]
    task_store.pack(ver.root)
    entry = task_store.load_tree(ver.root)["transcript.jsonl"]
    obj = task_store.object_path(root, entry.sha256)
    obj.write_bytes(obj.read_bytes() + b" ")
    with pytest.raises(StoreError, match="does not match its SHA-256 name"):
        TaskVersion.at(ver.root).file_digest()
    assert any("do not match its name" in p for p in task_store.verify(root))
    obj.unlink()
    with pytest.raises(StoreError, match="cannot be read"):
        TaskVersion.at(ver.root).file_digest()
    assert any("which is missing" in p for p in task_store.verify(root))


@pytest.mark.parametrize("rel, why", [
    ("../../../etc/passwd", "plain relative path"),
    ("/etc/passwd", "plain relative path"),
    ("renders/../reward.py", "plain relative path"),
    (".hidden", "plain relative path"),
    ("reward.py", "may not come from the store"),
    ("stage_rewards/lift.py", "may not come from the store"),
    ("task.yaml", "may not come from the store"),
    ("solvability.json", "may not come from the store"),
])
def test_a_tree_cannot_name_a_path_outside_or_code(tmp_path, rel, why):
    folder = tmp_path / "tasks" / "Hostile" / "v0"
    folder.mkdir(parents=True)
    (folder / TREE_NAME).write_text(json.dumps({"format": 1, "files": {rel: {"sha256": "0" * 64, "bytes": 1}}}))
    with pytest.raises(StoreError, match=why):
        task_store.load_tree(folder)


@pytest.mark.parametrize("entry, why", [
    ({"sha256": "0" * 63, "bytes": 1}, "64 lower-case hex"),
    ({"sha256": "A" * 64, "bytes": 1}, "64 lower-case hex"),
    ({"sha256": "0" * 64, "bytes": -1}, "bytes"),
    ({"sha256": "0" * 64, "bytes": True}, "bytes"),
    ({"sha256": "0" * 64}, "exactly sha256 and bytes"),
])
def test_a_tree_entry_is_checked(tmp_path, entry, why):
    folder = tmp_path / "Hostile" / "v0"
    folder.mkdir(parents=True)
    (folder / TREE_NAME).write_text(json.dumps({"format": 1, "files": {"transcript.jsonl": entry}}))
    with pytest.raises(StoreError, match=why):
        task_store.load_tree(folder)


# ------------------------------------------------------------------------------------------------ the index
def _synthetic(root: Path, n: int) -> list[str]:
    source = REPO_TASKS_DIR / "PutAppleBowl" / "v0"
    names = []
    for k in range(n):
        name = f"IndexedTask{k}"
        TaskVersion.at(source).copy_to(root / name / "v0")
        spec = root / name / "v0" / "task.yaml"
        spec.write_text(spec.read_text().replace("name: PutAppleBowl\n", f"name: {name}\n"))
        names.append(name)
    return names


def test_registration_reads_the_index_and_parses_only_what_changed(tmp_path, monkeypatch, caplog):
    root = tmp_path / "tasks"
    names = _synthetic(root, 3)
    spec = root / names[0] / "v0" / "task.yaml"
    spec.write_text(spec.read_text().replace("max_episode_steps: 200", "max_episode_steps: 150")
                    if "max_episode_steps: 200" in spec.read_text() else spec.read_text() + "max_episode_steps: 150\n")
    task_index.write_index(root)
    assert json.loads((root / "index.json").read_text())["versions"][f"{names[0]}/v0"]["max_episode_steps"] == 150
    # change one spec after indexing: only that one is parsed, and the stale index is reported
    spec.write_text(spec.read_text().replace("max_episode_steps: 150", "max_episode_steps: 170"))
    parsed: list[str] = []
    original = TaskVersion.load_spec_unchecked

    def counting(self):
        parsed.append(self.name)
        return original(self)

    monkeypatch.setattr(TaskVersion, "load_spec_unchecked", counting)
    ids = []
    try:
        with caplog.at_level(logging.WARNING, logger="gendex_envs.registry"):
            ids = register_tasks([root], override=True)
        assert sorted(ids) == sorted(f"GenDex/{n}-v0" for n in names)
        assert parsed == [names[0]]
        assert gym.spec(f"GenDex/{names[0]}-v0").max_episode_steps == 170
        assert gym.spec(f"GenDex/{names[1]}-v0").max_episode_steps == TaskVersion.at(
            root / names[1] / "v0").spec.max_episode_steps
        assert "gendex store index" in caplog.text and "1 version(s)" in caplog.text
        assert set(task_index.stale_entries(root)) == {f"{names[0]}/v0"}
    finally:
        unregister_tasks(ids)


@pytest.mark.parametrize("body, why", [
    ('{"format": 2, "versions": {}}', "format-1 index"),
    ('{"format": 1, "versions": {"../x/v0": {"spec_sha256": "' + "0" * 64 + '", "max_episode_steps": 5}}}',
     "is not '<Name>/v<N>'"),
    ('{"format": 1, "versions": {"Ok/v0": {"spec_sha256": "' + "0" * 64 + '", "max_episode_steps": 0}}}',
     "max_episode_steps 0"),
    ('{"format": 1, "versions": {"Ok/v0": {"spec_sha256": "zz", "max_episode_steps": 5}}}', "spec_sha256"),
    ("[1, 2", "Expecting"),
])
def test_an_invalid_index_is_ignored_with_the_reason_and_every_spec_is_parsed(tmp_path, caplog, body, why):
    root = tmp_path / "tasks"
    names = _synthetic(root, 1)
    (root / "index.json").write_text(body)
    with caplog.at_level(logging.WARNING, logger="gendex_envs.task_index"):
        assert task_index.load_index(root) is None
    assert why in caplog.text and "gendex store index" in caplog.text
    ids = register_tasks([root], override=True)
    try:
        assert ids == [f"GenDex/{names[0]}-v0"]
    finally:
        unregister_tasks(ids)


def test_the_committed_library_is_packed_indexed_and_its_store_complete():
    """What `gendex store check` checks (the message says how to fix it)."""
    fix = "run: gendex store pack generated_tasks"
    assert task_store.unpacked_files(REPO_TASKS_DIR) == [], fix
    assert task_store.verify(REPO_TASKS_DIR) == [], fix
    assert task_index.stale_entries(REPO_TASKS_DIR) == {}, fix


def test_the_store_keeps_committed_folders_small():
    """Data (transcripts, renders, records, policies) lies in the store; version folders keep spec and code."""
    in_folders = sum(p.stat().st_size for v in versions_in(REPO_TASKS_DIR) for p in v.root.rglob("*")
                     if p.is_file() and "__pycache__" not in p.parts)
    stored = task_store.store_bytes(REPO_TASKS_DIR)
    assert stored > 2 * in_folders


def test_a_derived_version_published_into_a_packed_root_adds_only_what_changed(tmp_path):
    from gendex_envs.task_version import publish_derived

    name, v = REWORDED
    root = _whole_root(tmp_path, (name, v))
    source = versions_in(root)[0]
    task_store.pack(source.root)
    task_index.write_index(root)
    objects = sorted((root / OBJECTS).glob("*/*"))

    def edit(out):
        out.spec.write_text(out.spec.read_text() + "# a changed spec\n")
        return {"reason": "test"}

    new = publish_derived(TaskVersion.at(source.root), "reword", edit)
    assert new.version == v + 1
    assert sorted((root / OBJECTS).glob("*/*")) == objects  # nothing new to store: the data is the source's
    assert task_store.unpacked_files(root) == [] and task_store.verify(root) == []
    assert sorted(p.name for p in new.root.iterdir()) == ["reward.py", "reword.json", "solvability.json",
                                                          "stage_rewards", "task.yaml", TREE_NAME]
    assert new.renders().keys() == source.renders().keys() and new.provenance()["reword"]["reason"] == "test"
    assert task_index.stale_entries(root) == {}  # publishing recorded it in the index


def test_store_check_refuses_a_hostile_tree_by_name_without_a_traceback(tmp_path):
    from typer.testing import CliRunner

    from gendex.cli import app

    root = _whole_root(tmp_path, ("PutAppleBowl", 1))
    tree = root / "PutAppleBowl" / "v1" / TREE_NAME
    tree.write_text(json.dumps({"format": 1, "files": {"renders/../../x.png": {"sha256": "0" * 64, "bytes": 1}}}))
    out = CliRunner().invoke(app, ["store", "check", str(root)])
    assert out.exit_code != 0 and "not a plain relative path" in out.output and "Traceback" not in out.output
