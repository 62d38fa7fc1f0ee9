"""``gendex dataset ...``: the published datasets of ``datasets/`` (build, verify, push, pull); see
:mod:`gendex.data.datasets` and docs/datasets.md."""

from __future__ import annotations

from pathlib import Path

import typer

from gendex.cli_common import backend_of, die, ray_address_option, ray_option

dataset_app = typer.Typer(no_args_is_help=True, help="Published datasets: build, verify, push and pull the "
                                                       "manifests in datasets/ (docs/datasets.md).")
def _remote(remote: Path | None, endpoint: str | None):
    from gendex.data.datasets import FolderRemote, HubRemote

    return FolderRemote(remote) if remote is not None else HubRemote(endpoint=endpoint)


@dataset_app.command("build")
def dataset_build(name: str = typer.Argument(..., help="A manifest in datasets/ (e.g. gendex-putapplebowl-v1)."),
                  out: Path = typer.Option(None, "--out", help="Where to build (default out/datasets/NAME); "
                                                              "resumes a build that was stopped."),
                  workers: int = typer.Option(1, "--workers", min=1, help="Worker processes per task."),
                  ray: bool = ray_option(), ray_address: str = ray_address_option(),
                  record: bool = typer.Option(False, "--record", help="Write the built files' checksums into the "
                                                                     "manifest (the expected ones).")) -> None:
    """Collect every task of a dataset manifest, then check the result against the manifest's checksums."""
    from gendex.data.datasets import build, load_manifest, manifest_path, record_checksums, save_manifest, verify
    from gendex_envs.errors import GenDexError

    try:
        m = load_manifest(name)
        target = out or Path("out/datasets") / m.name
        sums = build(m, target, backend=backend_of(workers, ray, ray_address),
                     progress=lambda task, ok, n: typer.echo(f"  {task}: {ok} episodes after {n} attempts", err=True))
        if record:
            save_manifest(record_checksums(m, sums), manifest_path(m.name))
            typer.echo(f"built {target}: {len(sums)} files; checksums recorded in {manifest_path(m.name)}")
            return
        if m.checksums:
            v = verify(target, m)
            typer.echo(f"built {target}: {v.summary()}")
            if not v.ok:
                raise typer.Exit(1)
        else:
            typer.echo(f"built {target}: {len(sums)} files (the manifest records no checksums: --record)")
    except GenDexError as exc:
        die(exc)


@dataset_app.command("verify")
def dataset_verify(path: Path = typer.Argument(..., help="A built or downloaded dataset folder."),
                   manifest: str = typer.Option(None, "--manifest",
                                                help="Manifest name (default: the one the folder's "
                                                     "gendex_dataset.json names).")) -> None:
    """Check a dataset folder file by file against its manifest; exits 1 on any missing, extra or changed file."""
    import json

    from gendex.data.datasets import BUILD_RECORD, DatasetError, load_manifest, verify
    from gendex_envs.errors import GenDexError

    try:
        if manifest is None:
            rec = path / BUILD_RECORD
            if not rec.is_file():
                raise DatasetError(f"{path} holds no {BUILD_RECORD}; name the manifest with --manifest")
            manifest = json.loads(rec.read_text())["manifest"]
        v = verify(path, load_manifest(manifest))
    except GenDexError as exc:
        die(exc)
    typer.echo(f"{path}: {v.summary()}")
    if not v.ok:
        raise typer.Exit(1)


@dataset_app.command("push")
def dataset_push(name: str = typer.Argument(..., help="The manifest of the built dataset."),
                 repo_id: str = typer.Option(..., "--repo-id", help="ORG/NAME of the dataset repo."),
                 path: Path = typer.Option(None, "--path", help="The built dataset (default out/datasets/NAME)."),
                 remote: Path = typer.Option(None, "--remote", help="A folder standing in for the Hub."),
                 endpoint: str = typer.Option(None, "--endpoint", help="Hub endpoint (default: huggingface_hub's).")
                 ) -> None:
    """Publish a built dataset (verified against its manifest first) as a LeRobot-tagged dataset repo."""
    from gendex.data.datasets import load_manifest, push
    from gendex_envs.errors import GenDexError

    try:
        m = load_manifest(name)
        where = push(path or Path("out/datasets") / m.name, repo_id, _remote(remote, endpoint), m)
    except GenDexError as exc:
        die(exc)
    typer.echo(f"pushed {m.name} to {where}")


@dataset_app.command("pull")
def dataset_pull(repo_id: str = typer.Argument(..., help="ORG/NAME of the dataset repo."),
                 out: Path = typer.Option(..., "--out", help="Where to put it."),
                 manifest: str = typer.Option(None, "--manifest", help="Verify against this manifest."),
                 remote: Path = typer.Option(None, "--remote", help="A folder standing in for the Hub."),
                 endpoint: str = typer.Option(None, "--endpoint", help="Hub endpoint (default: huggingface_hub's).")
                 ) -> None:
    """Download a dataset repo and verify it against its manifest."""
    from gendex.data.datasets import load_manifest, pull
    from gendex_envs.errors import GenDexError

    try:
        v = pull(repo_id, out, _remote(remote, endpoint), load_manifest(manifest) if manifest else None)
    except GenDexError as exc:
        die(exc)
    typer.echo(f"pulled {repo_id} into {out}" + (f": {v.summary()}" if v is not None else ""))
    if v is not None and not v.ok:
        raise typer.Exit(1)
