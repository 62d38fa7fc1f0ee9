"""``gendex store``: keep a task root's store and registration index in order (:mod:`gendex_envs.task_store`,
:mod:`gendex_envs.task_index`).

After adding versions to ``generated_tasks/`` (generated, reworded, promoted): ``gendex store pack`` then commit the
folders, ``.objects/`` and ``index.json``; ``gendex store check`` (what CI runs) says whether both are in order."""

from __future__ import annotations

from pathlib import Path

import typer

from gendex.cli_common import die

store_app = typer.Typer(no_args_is_help=True, help="The task store: pack versions, renew the index, check both.")

_ROOT = typer.Argument(None, help="A task root (a folder of <Name>/v<N>/); default: the committed generated_tasks/.")


def _root(root: Path | None) -> Path:
    from gendex_envs.registry import REPO_TASKS_DIR

    root = REPO_TASKS_DIR if root is None else root
    if not root.is_dir():
        die(f"{root} is not a folder")
    return root


@store_app.command("pack")
def pack_command(root: Path = _ROOT,
                 prune: bool = typer.Option(False, "--prune", help="Also remove objects no version lists.")) -> None:
    """Move every version's data files (transcripts, renders, records, start states, policies) into the root's
    store, keeping spec, code and the version's own records in its folder; then renew the index. Digests do not
    change."""
    from gendex_envs.errors import GenDexError
    from gendex_envs.task_index import write_index
    from gendex_envs.task_store import pack, store_bytes
    from gendex_envs.task_store import prune as prune_store
    from gendex_envs.task_version import versions_in

    root = _root(root)
    moved = size = 0
    try:
        for version in versions_in(root):
            result = pack(version.root)
            moved, size = moved + result.moved, size + result.bytes_moved
        removed = prune_store(root) if prune else 0
        index = write_index(root)
    except GenDexError as exc:
        die(exc)
    typer.echo(f"{root}: {moved} files ({size / 1e6:.1f} MB) moved into the store; store {store_bytes(root) / 1e6:.1f}"
               f" MB{f', {removed} unused objects removed' if prune else ''}; {index} renewed")


@store_app.command("index")
def index_command(root: Path = _ROOT) -> None:
    """Renew the registration index (index.json) of a task root."""
    from gendex_envs.errors import GenDexError
    from gendex_envs.task_index import write_index

    try:
        typer.echo(f"wrote {write_index(_root(root))}")
    except GenDexError as exc:
        die(exc)


@store_app.command("unpack")
def unpack_command(folder: Path = typer.Argument(..., help="A version folder (<root>/<Name>/v<N>).")) -> None:
    """Copy a version's stored files back into its folder (a whole folder, to hand on without the store)."""
    from gendex_envs.errors import GenDexError
    from gendex_envs.task_store import unpack

    try:
        typer.echo(f"{folder}: {unpack(folder)} files copied back")
    except GenDexError as exc:
        die(exc)


@store_app.command("check")
def check_command(root: Path = _ROOT) -> None:
    """Exit 1 unless every version is packed, every object matches its name and is listed, and the index matches
    the folders."""
    from gendex_envs.errors import GenDexError
    from gendex_envs.task_index import stale_entries
    from gendex_envs.task_store import unpacked_files, verify

    root = _root(root)
    try:
        problems = verify(root)
        problems += [f"{rel}: data file not packed" for rel in unpacked_files(root)]
        problems += [f"index: {k}: {why}" for k, why in sorted(stale_entries(root).items())]
    except GenDexError as exc:  # a tree or spec that does not load: the refusal, not a traceback
        die(exc)
    for p in problems:
        typer.echo(p)
    if problems:
        typer.echo(f"{len(problems)} problem(s); `gendex store pack {root}` packs the versions and renews the index")
        raise typer.Exit(1)
    typer.echo(f"{root}: store and index in order")
