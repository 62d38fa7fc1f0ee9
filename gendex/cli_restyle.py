"""``gendex restyle``: the next version of each task without a scene, in a place (:mod:`generator.restyle`)."""

from __future__ import annotations

import typer

from gendex.cli_common import die


def restyle_command(names: list[str] = typer.Argument(None, help="Task names to restyle (default: every task whose "
                                                                  "newest version has no scene)."),
                    dry_run: bool = typer.Option(False, "--dry-run", help="Print each task's style; publish nothing.")
                    ) -> None:
    """Publish the next version of each task without a scene with a scene style (the offline author's rotation
    over the sorted library, passing over styles whose structures leave the arm no room). Measure the new versions
    with `gendex gate --write`, then record their reward code with `gendex trust`."""
    from gendex_envs.errors import GenDexError
    from gendex_envs.registry import registered_tasks
    from generator.restyle import RESTYLE_SEED, plan_restyle, publish_restyled

    versions = registered_tasks()
    unknown = sorted(set(names or ()) - {v.name for v in versions.values()})
    if unknown:
        raise typer.BadParameter(f"no registered task named {', '.join(unknown)}", param_hint="NAMES")
    try:
        plan = plan_restyle(versions, names=names or None)
        for name in sorted(set(names or ()) - {c.source.name for c in plan}):
            typer.echo(f"{name}: its newest version already has a scene; left as it is")
        for change in plan:
            if dry_run:
                typer.echo(f"{change.env_id}: {change.style}")
                continue
            published = publish_restyled(change.source, change.style, {"rotation_seed": RESTYLE_SEED})
            typer.echo(f"{change.env_id} -> {published.env_id}: {change.style}")
    except GenDexError as exc:
        die(exc)
    typer.echo(f"{len(plan)} tasks {'to restyle (dry run)' if dry_run else 'restyled'}")
