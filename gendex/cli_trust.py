"""``gendex trust``: the deliberate step that makes reviewed reward code of ``generated_tasks/`` trusted
(:mod:`gendex_envs.trust_record`), and the check that lists what is not."""

from __future__ import annotations

from pathlib import Path

import typer

from gendex.cli_common import die


def trust_command(paths: list[Path] = typer.Argument(None, help="Task version folders (generated_tasks/<Name>/v<N>), "
                                                                  "task folders or .py files you reviewed."),
                  check: bool = typer.Option(False, "--check", help="Only list the code files of generated_tasks/ "
                                                                    "that differ from the record (exit 1 if any).")
                  ) -> None:
    """Record the reward code of reviewed tasks in generated_tasks/TRUSTED.sha256, so it runs as trusted code (in
    this process, without the static check and the sandbox). Code written by a model is untrusted until a person
    reviews it: `gendex generate` never records anything. Without PATHS (or with --check): list what differs."""
    from gendex_envs.trust_record import TrustRecordError, record_trusted, trust_status

    try:
        if check or not paths:
            if check and paths:
                raise TrustRecordError("--check takes no paths: it compares every code file of generated_tasks/")
            status = trust_status()
            for line in status.lines():
                typer.echo(line)
            typer.echo("the trust record matches every code file of generated_tasks/" if status.clean else
                       "untrusted files run through the static check and the sandbox; review them, then record them "
                       "with: gendex trust generated_tasks/<Name>/v<N>")
            raise typer.Exit(0 if status.clean else 1)
        update = record_trusted(paths)
    except TrustRecordError as exc:
        die(exc)
    for kind, rels in (("recorded", update.added), ("re-recorded (changed)", update.changed),
                       ("dropped (file gone)", update.dropped)):
        for rel in rels:
            typer.echo(f"{kind}: {rel}")
    typer.echo(f"{update.record}: {len(update.added)} added, {len(update.changed)} changed, "
               f"{len(update.unchanged)} already recorded, {len(update.dropped)} dropped; commit it with the tasks")
