"""What every ``gendex`` command shares."""

from __future__ import annotations

import typer


def die(exc: Exception) -> None:
    """Print ``exc`` as the command's error and exit with code 2 (bad input or a request that cannot be met)."""
    typer.secho(f"error: {exc}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code=2)


def refuse_request(exc: Exception, instruction: str | None, out) -> None:
    """:func:`die` with ``exc``; a request ``gendex generate`` refused (an ``InstructionError``) first names the
    library tasks (and those in ``out``) whose commands read most like it."""
    from generator.errors import InstructionError

    if instruction is not None and isinstance(exc, InstructionError):
        from generator.novelty import closest_tasks, existing_tasks
        from generator.pipeline import task_roots

        close = closest_tasks(instruction, existing_tasks(task_roots(out)))
        if close:
            typer.secho("Library tasks that read like your request (MiniLM cosine of their commands):", err=True)
            for env_id, command, cosine in close:
                typer.secho(f"  {env_id}: {command!r} ({cosine:.2f}); gym.make({env_id!r})", err=True)
    die(exc)


def ray_option():
    return typer.Option(False, "--ray", help="Run the workers as Ray actors on a local Ray instance started for "
                                             "this command (a killed worker's jobs are re-run by another).")


def ray_address_option():
    return typer.Option(None, "--ray-address", help="Join a running Ray cluster (e.g. auto, or ray://HEAD:10001) "
                                                    "instead of starting one; implies --ray.")


def backend_of(workers: int, ray: bool, ray_address: str | None):
    """The :class:`gendex.fanout.Backend` the ``--workers/--ray/--ray-address`` options ask for (exit 2 if bad)."""
    from gendex.fanout import Backend, FanOutError

    try:
        return Backend.from_options(workers, ray, ray_address)
    except FanOutError as exc:
        die(exc)
