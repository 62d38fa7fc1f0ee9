"""What every ``gendex`` command shares."""

from __future__ import annotations

import typer


def die(exc: Exception) -> None:
    """Print ``exc`` as the command's error and exit with code 2 (bad input or a request that cannot be met)."""
    typer.secho(f"error: {exc}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code=2)
