"""`gendex dataset build` + `verify` reproduce a published dataset byte for byte."""

from typer.testing import CliRunner

from gendex.cli import app
from gendex.data.datasets import load_manifest


def test_building_the_smoke_manifest_reproduces_its_recorded_checksums(tmp_path):
    """datasets/gendex-smoke.yaml (three PutAppleBowl-v1 episodes with 64 px AV1 video) was built and recorded on
    this project's machine; a fresh build with two workers gives the same files, byte for byte (about 1 min on 2
    cores, in the default suite: a published dataset that no longer rebuilds must fail CI). A changed byte is
    caught by verify."""
    out = tmp_path / "smoke"
    built = CliRunner().invoke(app, ["dataset", "build", "gendex-smoke", "--out", str(out), "--workers", "2"])
    assert built.exit_code == 0, built.output
    recorded = load_manifest("gendex-smoke").checksums
    assert len(recorded) >= 8 and f"{len(recorded)} files match the manifest" in built.output
    video = next(out.rglob("*.mp4"))
    video.write_bytes(video.read_bytes()[:-1] + b"\x00")
    checked = CliRunner().invoke(app, ["dataset", "verify", str(out)])
    assert checked.exit_code == 1 and "1 different" in checked.output and video.name in checked.output
