"""Which code built a published dataset (gendex.data.provenance): the canary recorded in a manifest, what
`gendex dataset check` and `build` say about it, and `gendex dataset stale`."""

from __future__ import annotations

from dataclasses import replace

import pytest
from typer.testing import CliRunner

from gendex.cli import app
from gendex.data import provenance
from gendex.data.datasets import load_manifest, mark_stale, save_manifest
from gendex.data.provenance import BuiltWith, check_code


@pytest.fixture
def smoke():
    return load_manifest("gendex-smoke")


def test_each_status_and_what_ci_accepts(smoke):
    recorded = replace(smoke, built_with=BuiltWith(canary="a" * 64, commit="c0ffee"))
    assert check_code(recorded, current="a" * 64).status == "same"
    differs = check_code(recorded, current="b" * 64)
    assert differs.status == "differs" and not differs.ok
    assert "c0ffee" in differs.message and "--record" in differs.message and "dataset stale" in differs.message
    assert check_code(replace(smoke, built_with=None), current="a" * 64).status == "unknown"
    stale = check_code(mark_stale(recorded), current="b" * 64)
    assert stale.status == "stale" and stale.ok and "older code" in stale.message
    unbuilt = check_code(replace(smoke, checksums={}, built_with=None))
    assert unbuilt.status == "unbuilt" and unbuilt.ok
    assert [check_code(recorded, current=c).ok for c in ("a" * 64, "b" * 64)] == [True, False]


def test_stale_is_kept_through_a_save_and_cleared_by_a_new_record(smoke, tmp_path):
    path = tmp_path / "gendex-smoke.yaml"
    save_manifest(mark_stale(smoke), path)
    again = load_manifest(path)
    assert again.built_with.stale and again.built_with.canary == smoke.built_with.canary
    assert again.checksums == smoke.checksums
    save_manifest(replace(again, built_with=BuiltWith(canary="c" * 64)), path)
    assert not load_manifest(path).built_with.stale


def test_the_stale_command_marks_a_manifest(smoke, tmp_path):
    path = tmp_path / "gendex-smoke.yaml"
    save_manifest(smoke, path)
    result = CliRunner().invoke(app, ["dataset", "stale", str(path)])
    assert result.exit_code == 0, result.output
    assert load_manifest(path).built_with.stale and "built by older code" in result.output


def test_a_build_by_other_code_says_so_before_it_collects(smoke, tmp_path, monkeypatch):
    """The note comes from the canary, before any episode is collected (build is stopped at its start here)."""
    path = tmp_path / "gendex-smoke.yaml"
    save_manifest(replace(smoke, built_with=BuiltWith(canary="a" * 64, commit="c0ffee")), path)
    monkeypatch.setattr(provenance, "canary", lambda m: "b" * 64)

    def no_build(*args, **kwargs):
        raise KeyboardInterrupt("stopped before collecting")

    monkeypatch.setattr("gendex.data.datasets.build", no_build)
    result = CliRunner().invoke(app, ["dataset", "build", str(path), "--out", str(tmp_path / "out")])
    assert "note: gendex-smoke was built by other code (commit c0ffee)" in result.output
    assert not (tmp_path / "out").exists()


def test_every_committed_manifest_is_built_by_this_code_or_says_it_is_not():
    """CI's check of the published datasets: each committed manifest's canary (one attempt of its first task)
    equals what this code collects, or the manifest is marked as built by older code, or it records no checksums
    yet. After a change that alters collection: `gendex dataset build NAME --record`, or `gendex dataset stale
    NAME`. gendex-smoke is left to tests/sim/test_dataset_build.py, which rebuilds it byte for byte (a stronger
    check than its canary, the same first attempt as gendex-putapplebowl-v1's)."""
    from gendex_envs.library import library_dir

    checks = {p.stem: check_code(load_manifest(p.stem)) for p in sorted(library_dir("datasets").glob("*.yaml"))
              if p.stem != "gendex-smoke"}
    assert checks and all(c.ok for c in checks.values()), "\n".join(c.message for c in checks.values() if not c.ok)
    assert checks["gendex-putapplebowl-v1"].status == "same"
