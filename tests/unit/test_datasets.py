"""Dataset manifests (datasets/*.yaml) and what checks a copy against them: verify, push and pull through a
file-backed stand-in of the Hub, and the Hub remote's calls (no network: huggingface_hub's API object is faked)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from gendex.data.datasets import (
    BUILD_RECORD,
    DATASETS_DIR,
    DatasetError,
    FolderRemote,
    HubRemote,
    checksums,
    load_manifest,
    pull,
    push,
    record_checksums,
    save_manifest,
    verify,
)


def test_the_shipped_manifests_load_and_cover_what_the_issue_asks(committed_tasks):
    names = sorted(p.stem for p in DATASETS_DIR.glob("*.yaml"))
    assert {"gendex-putapplebowl-v1", "gendex-pickupbottle-v1", "gendex-opencabinet-v1", "gendex-lib-v1",
            "gendex-smoke"} <= set(names)
    for name in names:
        m = load_manifest(name)
        assert m.name == name and m.tasks and m.gendex_version
    for ref in ("putapplebowl", "pickupbottle", "opencabinet"):
        assert load_manifest(f"gendex-{ref}-v1").tasks[0].episodes >= 200
    from generator.stats import latest_versions

    # the repository's committed tasks, not this process's registry: other tests register tasks they generate
    lib = load_manifest("gendex-lib-v1")
    assert {t.task for t in lib.tasks} == set(latest_versions(committed_tasks))
    assert min(t.episodes for t in lib.tasks) >= 50
    assert load_manifest("gendex-smoke").checksums  # built and recorded: the tests rebuild it byte for byte


def _manifest_file(tmp_path: Path, **changes) -> Path:
    raw = yaml.safe_load((DATASETS_DIR / "gendex-smoke.yaml").read_text())
    raw.update(changes)
    path = tmp_path / f"{raw['name']}.yaml"
    path.write_text(yaml.safe_dump(raw))
    return path


@pytest.mark.parametrize("changes, message", [
    ({"solver": "magic"}, "solver 'magic' is not one of"),
    ({"video_codec": "mjpeg"}, "video_codec 'mjpeg' is not one of"),
    ({"tasks": [{"task": "PutAppleBowl", "episodes": 3}]}, "not a versioned GenDex id"),
    ({"tasks": [{"task": "GenDex/PutAppleBowl-v1", "episodes": 5, "max_attempts": 2}]}, "must be >= 1 and <="),
    ({"tasks": [{"task": "GenDex/PutAppleBowl-v1", "episodes": 3, "colour": "red"}]}, "colour"),
])
def test_a_bad_manifest_is_refused_with_what_is_wrong(tmp_path, changes, message):
    with pytest.raises(DatasetError, match=message):
        load_manifest(_manifest_file(tmp_path, **changes))
    with pytest.raises(DatasetError, match="no dataset manifest 'nosuch'; known: .*gendex-smoke"):
        load_manifest("nosuch")


def _fake_build(root: Path) -> Path:
    (root / "PutAppleBowl-v1" / "lerobot" / "meta").mkdir(parents=True)
    (root / "PutAppleBowl-v1" / "lerobot" / "meta" / "info.json").write_text('{"total_episodes": 3}\n')
    (root / "PutAppleBowl-v1" / "lerobot" / "data.parquet").write_bytes(b"\x00" * 100)
    (root / "PutAppleBowl-v1" / "collect_state.json").write_text('{"seconds": 12.3}')  # bookkeeping: not checked
    (root / BUILD_RECORD).write_text(json.dumps({"manifest": "gendex-smoke",
                                                 "tasks": [{"task": "GenDex/PutAppleBowl-v1"}]}))
    return root


def test_verify_names_every_missing_extra_and_changed_file(tmp_path):
    root = _fake_build(tmp_path / "built")
    m = record_checksums(load_manifest("gendex-smoke"), checksums(root))
    assert "PutAppleBowl-v1/collect_state.json" not in m.checksums and verify(root, m).ok
    (root / "PutAppleBowl-v1" / "collect_state.json").write_text('{"seconds": 99}')  # wall time: still the same
    assert verify(root, m).ok
    (root / "PutAppleBowl-v1" / "lerobot" / "data.parquet").write_bytes(b"\x01" * 100)
    (root / "PutAppleBowl-v1" / "lerobot" / "meta" / "info.json").unlink()
    (root / "stray.txt").write_text("x")
    v = verify(root, m)
    assert not v.ok
    assert v.different == ("PutAppleBowl-v1/lerobot/data.parquet",)
    assert v.missing == ("PutAppleBowl-v1/lerobot/meta/info.json",) and v.extra == ("stray.txt",)
    assert "1 missing" in v.summary() and "1 different" in v.summary()
    with pytest.raises(DatasetError, match="holds no checksums yet"):
        verify(root, record_checksums(m, {}))


def test_save_and_load_round_trip(tmp_path):
    m = record_checksums(load_manifest("gendex-smoke"), {"b": "2" * 64, "a": "1" * 64})
    path = tmp_path / "gendex-smoke.yaml"
    save_manifest(m, path)
    assert load_manifest(path) == m and list(yaml.safe_load(path.read_text())["checksums"]) == ["a", "b"]


def test_push_and_pull_through_a_folder_remote_keep_every_byte(tmp_path):
    root = _fake_build(tmp_path / "built")
    m = record_checksums(load_manifest("gendex-smoke"), checksums(root))
    remote = FolderRemote(tmp_path / "hub")
    where = Path(push(root, "gendex/smoke", remote, m))
    assert (where / ".tags").read_text().split() == ["v3.0"]  # the format version lerobot looks for
    # one task: its LeRobot dataset at the repo's root, the build record beside it, no bookkeeping
    assert sorted(str(p.relative_to(where)) for p in where.rglob("*") if p.is_file()) == [
        ".tags", "data.parquet", BUILD_RECORD, "meta/info.json"]
    v = pull("gendex/smoke", tmp_path / "copy", remote, m)
    assert v is not None and v.ok and v.checked == len(m.checksums)
    (root / "PutAppleBowl-v1" / "lerobot" / "data.parquet").write_bytes(b"tampered")
    with pytest.raises(DatasetError, match="does not match manifest 'gendex-smoke'.*not pushed"):
        push(root, "gendex/smoke", remote, m)
    with pytest.raises(DatasetError, match="must be ORG/NAME"):
        remote.pull("smoke", tmp_path / "x")
    with pytest.raises(DatasetError, match="not on the remote"):
        remote.pull("gendex/other", tmp_path / "y")


def test_the_hub_remote_makes_a_tagged_dataset_repo_of_the_whole_folder(tmp_path):
    calls = []

    class FakeApi:
        def create_repo(self, repo_id, **kw):
            calls.append(("create_repo", repo_id, kw))

        def upload_folder(self, **kw):
            calls.append(("upload_folder", kw))
            return type("Info", (), {"commit_url": f"hub/{kw['repo_id']}/commit/1"})()

        def create_tag(self, repo_id, **kw):
            calls.append(("create_tag", repo_id, kw["tag"]))

        def dataset_info(self, repo_id, **kw):
            calls.append(("dataset_info", repo_id, kw))
            return type("Info", (), {"sha": "c0ffee", "siblings": [
                type("Sibling", (), {"rfilename": "gendex_dataset.json", "size": 469})()]})()

        def snapshot_download(self, **kw):
            calls.append(("snapshot_download", kw))
            return kw["local_dir"]

    root = _fake_build(tmp_path / "built")
    hub = HubRemote(api=FakeApi())
    assert push(root, "org/ds", hub) == "hub/org/ds/commit/1"
    assert calls[0] == ("create_repo", "org/ds", {"repo_type": "dataset", "exist_ok": True})
    assert calls[1][1]["repo_type"] == "dataset"
    assert [c[2] for c in calls if c[0] == "create_tag"] == ["v3.0"]
    hub.pull("org/ds", tmp_path / "dl")  # the listing (sizes included) first, then that revision's files
    assert calls[-2] == ("dataset_info", "org/ds", {"files_metadata": True})
    assert calls[-1][1] == {"repo_id": "org/ds", "repo_type": "dataset", "revision": "c0ffee",
                            "local_dir": str(tmp_path / "dl")}
