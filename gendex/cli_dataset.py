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
    """Collect every task of a dataset manifest, then check the result against the manifest's checksums. Before it
    collects, one attempt tells whether this code collects as the code that built the manifest did."""
    from gendex.data.datasets import build, load_manifest, manifest_path, record_checksums, save_manifest, verify
    from gendex.data.numerics import NUMERICS
    from gendex.data.provenance import BuiltWith, canary, check_code, current_commit
    from gendex_envs.errors import GenDexError

    try:
        m = load_manifest(name)
        target = out or Path("out/datasets") / m.name
        code = check_code(m)
        if not record or code.status != "same":
            typer.echo(("note: " if code.status != "same" else "") + code.message, err=True)
        sums = build(m, target, backend=backend_of(workers, ray, ray_address),
                     progress=lambda task, ok, n: typer.echo(f"  {task}: {ok} episodes after {n} attempts", err=True))
        if record:
            built = BuiltWith(canary=code.canary or canary(m), commit=current_commit(), numerics=NUMERICS)
            save_manifest(record_checksums(m, sums, built), manifest_path(name))
            typer.echo(f"built {target}: {len(sums)} files; checksums and the code that built them recorded in "
                       f"{manifest_path(name)}")
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


@dataset_app.command("check")
def dataset_check(names: list[str] = typer.Argument(None, help="Manifests in datasets/ (default: all).")) -> None:
    """Does this code collect each manifest as the code that built it did? One attempt per manifest (its first
    task's first seed); exits 1 when one differs and is not marked as built by older code (`gendex dataset stale`)."""
    from gendex.data.datasets import load_manifest
    from gendex.data.provenance import check_code
    from gendex_envs.errors import GenDexError
    from gendex_envs.library import library_dir

    try:
        manifests = [load_manifest(n) for n in (names or sorted(p.stem for p in
                                                                 library_dir("datasets").glob("*.yaml")))]
        checks = [check_code(m) for m in manifests]
    except GenDexError as exc:
        die(exc)
    for c in checks:
        typer.echo(f"{c.status:8s} {c.message}")
    if not all(c.ok for c in checks):
        raise typer.Exit(1)


@dataset_app.command("stale")
def dataset_stale(name: str = typer.Argument(..., help="A manifest in datasets/.")) -> None:
    """Mark a manifest as built by older code: its checksums stay as the record of what was published, `gendex
    dataset check` accepts it, and a build says that it will give other files."""
    from gendex.data.datasets import load_manifest, manifest_path, mark_stale, save_manifest
    from gendex_envs.errors import GenDexError

    try:
        m = load_manifest(name)
        path = manifest_path(name)  # the file named, when a path was given
        save_manifest(mark_stale(m), path)
    except GenDexError as exc:
        die(exc)
    typer.echo(f"{path}: marked as built by older code; `gendex dataset build {m.name} --record` rebuilds it and "
               f"records the new checksums")


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
