"""Dataset manifests (datasets/*.yaml) and what checks a copy against them: verify, push and pull through a
file-backed stand-in of the Hub, and the Hub remote's calls (no network: huggingface_hub's API object is faked)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml

from gendex.data.datasets import (
    BUILD_RECORD,
    DATASETS_DIR,
    DatasetError,
    FolderRemote,
    HubRemote,
    build,
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
    # the repository's committed tasks, not this process's registry: other tests register tasks they generate.
    # The manifest is frozen (as the v1 suites): one committed version of every task of the library, the newest
    # when it was written; versions landed since (e.g. the scene versions) do not change it.
    lib = load_manifest("gendex-lib-v1")
    assert {t.task for t in lib.tasks} <= set(committed_tasks)
    names = [committed_tasks[t.task].name for t in lib.tasks]
    assert len(names) == len(set(names)) and set(names) == {v.name for v in committed_tasks.values()}
    assert min(t.episodes for t in lib.tasks) >= 50
    assert load_manifest("gendex-smoke").checksums  # built and recorded: the tests rebuild it byte for byte


def test_the_library_dataset_v2_is_every_task_of_the_v2_suites_with_a_camera_and_pooled_quantile_stats():
    from gendex.eval.suite import load_suite, suite_task_digests

    m = load_manifest("gendex-lib-v2")
    suite_tasks = {t for name in ("gendex-ref-v2", "gendex-skills-v2", "gendex-lib-v2")
                   for t in load_suite(name).tasks}
    assert {t.task for t in m.tasks} == suite_tasks == set(load_suite("gendex-lib-v2").tasks)
    assert suite_task_digests(load_suite("gendex-lib-v2"))  # each a committed task version
    assert min(t.episodes for t in m.tasks) >= 50 and m.cameras and m.conventions == 3 and m.video_codec


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
    ({"conventions": 4}, r"conventions 4 is not one of \[1, 2, 3\]"),
    ({"conventions": True}, r"conventions True is not one of \[1, 2, 3\]"),
    ({"conventions": "2"}, "wrong value type for field \"conventions\""),
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
    two = replace(m, conventions=2)
    save_manifest(two, path)
    assert yaml.safe_load(path.read_text())["conventions"] == 2 and load_manifest(path) == two


def test_the_published_manifests_are_conventions_1_and_save_as_the_same_bytes(tmp_path):
    """``conventions`` defaults to 1 and is written only when it is not: re-recording a published manifest leaves
    its file as it is."""
    for name in ("gendex-putapplebowl-v1", "gendex-pickupbottle-v1", "gendex-opencabinet-v1", "gendex-lib-v1",
                 "gendex-smoke"):
        m = load_manifest(name)
        assert m.conventions == 1 and "conventions" not in yaml.safe_load((DATASETS_DIR / f"{name}.yaml").read_text())
        save_manifest(m, tmp_path / f"{name}.yaml")
        assert (tmp_path / f"{name}.yaml").read_bytes() == (DATASETS_DIR / f"{name}.yaml").read_bytes(), name


@pytest.mark.parametrize("conventions", [1, 2, 3])
def test_build_hands_the_manifests_conventions_to_the_collector(tmp_path, monkeypatch, conventions):
    """No simulation: the collector is replaced by one that records its config. A conventions-1 build record has
    exactly the keys published records have."""
    from gendex.data import collector

    seen = []

    def fake_collect(cfg, make_solver, progress=None, backend=None):
        seen.append(cfg)
        return collector.CollectState(task_id=cfg.task_id, seed=cfg.seed, attempts=3, kept_seeds=[0, 1, 2])

    monkeypatch.setattr(collector, "collect", fake_collect)
    monkeypatch.setattr(collector, "write_card", lambda *a, **kw: None)
    m = replace(load_manifest("gendex-smoke"), conventions=conventions)
    build(m, tmp_path / "out")
    assert [c.conventions for c in seen] == [conventions]
    record = json.loads((tmp_path / "out" / BUILD_RECORD).read_text())
    keys = ["manifest", "description", "gendex_version", "solver", "tasks"]
    assert list(record) == (keys if conventions == 1 else [*keys, "conventions"])
    assert record.get("conventions", 1) == conventions


def test_the_collectors_lerobot_writer_gets_the_conventions(tmp_path, monkeypatch):
    from gendex.data import collector

    env = SimpleNamespace(unwrapped=SimpleNamespace(agent=SimpleNamespace(controller=SimpleNamespace(
        free_joint_names=["a0", "a1"])), sensor_resolution=64, control_freq=20))
    monkeypatch.setattr(collector.observation, "robot_state_names", lambda e: ["q0.pos", "q0.vel"])
    monkeypatch.setattr(collector.observation, "environment_state_names", lambda e: ["apple.pos.x"])
    for conventions, quantiles in [(1, False), (2, True)]:
        cfg = collector.CollectConfig(task_id="GenDex/PutAppleBowl-v1", num_success=1, out=tmp_path / str(conventions),
                                      conventions=conventions)
        w = collector._open_exporters(cfg, env)["lerobot"]
        assert w.conventions == conventions and ("q99" in w.stat_names) == quantiles
        w.close()


def test_push_and_pull_through_a_folder_remote_keep_every_byte(tmp_path):
    root = _fake_build(tmp_path / "built")
    m = record_checksums(load_manifest("gendex-smoke"), checksums(root))
    remote = FolderRemote(tmp_path / "hub")
    where = Path(push(root, "gendex/smoke", remote, m))
    assert remote.tags("gendex/smoke") == {"v3.0": remote.revision("gendex/smoke")}  # the version lerobot looks for
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


class FakeHubRepo:
    """A stand-in of ``huggingface_hub.HfApi`` for one dataset repo, as the Hub treats commits and tags: each upload of
    changed files is a new commit (an upload of the same files makes none and answers the head), a tag names one
    commit, ``create_tag`` refuses a tag that exists and ``delete_tag`` one that does not."""

    def __init__(self):
        self.commits: list[dict[str, bytes]] = []  # commit k's files; its id is "c<k+1>"
        self.tags: dict[str, str] = {}
        self.log: list[tuple] = []

    def create_repo(self, repo_id, **kw):
        pass

    def upload_folder(self, *, repo_id, folder_path, **kw):
        root = Path(folder_path)
        files = {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}
        if not self.commits or self.commits[-1] != files:
            self.commits.append(files)
        oid = f"c{len(self.commits)}"
        self.log.append(("upload_folder", oid))
        return SimpleNamespace(oid=oid, commit_url=f"hub/{repo_id}/commit/{len(self.commits)}")

    def list_repo_refs(self, repo_id, repo_type=None):
        return SimpleNamespace(branches=[], converts=[], tags=[
            SimpleNamespace(name=t, ref=f"refs/tags/{t}", target_commit=c) for t, c in self.tags.items()])

    def delete_tag(self, repo_id, *, tag, repo_type=None):
        if tag not in self.tags:
            raise LookupError(f"404: tag {tag} does not exist")
        self.log.append(("delete_tag", tag))
        del self.tags[tag]

    def create_tag(self, repo_id, *, tag, revision=None, repo_type=None, exist_ok=False, **kw):
        if tag in self.tags:
            if exist_ok:
                return
            raise LookupError(f"409: tag {tag} exists")
        self.log.append(("create_tag", tag, revision))
        self.tags[tag] = revision or f"c{len(self.commits)}"

    def files_at(self, tag: str) -> dict[str, bytes]:
        """What ``LeRobotDataset("ORG/NAME")`` downloads: the files of the commit the version tag names."""
        return self.commits[int(self.tags[tag][1:]) - 1]


def test_a_second_push_moves_the_version_tag_to_the_new_commit(tmp_path):
    """lerobot loads a dataset at its ``v3.0`` tag: a tag left on the first commit would serve the first push's
    files after the second."""
    root = _fake_build(tmp_path / "built")
    hub = HubRemote(api=FakeHubRepo())
    push(root, "org/ds", hub)
    assert hub.api.tags == {"v3.0": "c1"}
    (root / "PutAppleBowl-v1" / "lerobot" / "data.parquet").write_bytes(b"\x02" * 50)
    hub.api.log.clear()
    assert push(root, "org/ds", hub) == "hub/org/ds/commit/2"
    assert hub.api.tags == {"v3.0": "c2"}
    assert hub.api.log == [("upload_folder", "c2"), ("delete_tag", "v3.0"), ("create_tag", "v3.0", "c2")]
    assert hub.api.files_at("v3.0")["data.parquet"] == b"\x02" * 50
    hub.api.log.clear()
    push(root, "org/ds", hub)  # the same files: no commit, and the tag is where it should be
    assert hub.api.log == [("upload_folder", "c2")] and hub.api.tags == {"v3.0": "c2"}


def test_a_second_push_to_a_folder_remote_moves_the_tag_too(tmp_path):
    root = _fake_build(tmp_path / "built")
    remote = FolderRemote(tmp_path / "hub")
    push(root, "org/ds", remote)
    first = remote.revision("org/ds")
    assert remote.tags("org/ds") == {"v3.0": first}
    (root / "PutAppleBowl-v1" / "lerobot" / "data.parquet").write_bytes(b"\x02" * 50)
    push(root, "org/ds", remote)
    second = remote.revision("org/ds")
    assert second != first and remote.tags("org/ds") == {"v3.0": second}
    push(root, "org/ds", remote)
    assert remote.tags("org/ds") == {"v3.0": second}
    (tmp_path / "hub" / "org" / "ds" / ".tags").write_text("v3.0\nold\n")  # a remote pushed before revisions
    assert remote.tags("org/ds") == {"v3.0": "", "old": ""}
    push(root, "org/ds", remote)
    assert remote.tags("org/ds") == {"v3.0": second, "old": ""}


def test_the_hub_remote_makes_a_tagged_dataset_repo_of_the_whole_folder(tmp_path):
    calls = []

    class FakeApi(FakeHubRepo):
        def create_repo(self, repo_id, **kw):
            calls.append(("create_repo", repo_id, kw))

        def upload_folder(self, **kw):
            calls.append(("upload_folder", kw))
            return super().upload_folder(**kw)

        def create_tag(self, repo_id, **kw):
            calls.append(("create_tag", repo_id, kw["tag"]))
            super().create_tag(repo_id, **kw)

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
    assert hub.api.tags == {"v3.0": "c1"}
    hub.pull("org/ds", tmp_path / "dl")  # the listing (sizes included) first, then that revision's files
    assert calls[-2] == ("dataset_info", "org/ds", {"files_metadata": True})
    assert calls[-1][1] == {"repo_id": "org/ds", "repo_type": "dataset", "revision": "c0ffee",
                            "local_dir": str(tmp_path / "dl")}
