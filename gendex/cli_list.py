"""``gendex list``: the registered task versions, with what each asks, holds and was measured to do."""

from __future__ import annotations

import typer


def list_command(pattern: str = typer.Argument("", help="Only the IDs that contain this text (any case), e.g. "
                                                        "'Drawer' or 'PutAppleBowl-v1'."),
                 latest: bool = typer.Option(False, "--latest", help="Only the latest version of each task.")) -> None:
    """List the registered task versions (Gymnasium IDs): instruction, objects, stages, policies, origin."""
    from gendex_envs.errors import GenDexError
    from gendex_envs.registry import registered_tasks
    from generator.stats import latest_versions

    tasks = registered_tasks()
    if not tasks:
        typer.echo("no tasks registered (looked in generated_tasks/ and $GENDEX_TASKS_PATH)")
        return
    if latest:
        tasks = latest_versions(tasks)
    tasks = {env_id: v for env_id, v in tasks.items() if pattern.lower() in env_id.lower()}
    if not tasks:
        typer.echo(f"no registered task ID contains {pattern!r}", err=True)
        raise typer.Exit(2)
    for env_id, version in sorted(tasks.items()):
        try:
            spec = version.spec
        except GenDexError as exc:
            typer.echo(f"{env_id}\n    INVALID: {exc}")
            continue
        stages = " -> ".join(f"{s.name}[{s.skill}, {s.method}:{s.control_joint}]" for s in spec.stages)
        objects = ", ".join(f"{o.name}({o.asset})" for o in spec.objects)
        policies = ", ".join(version.artifacts.policy_stages()) or "none"
        origin = version.provenance()
        made = ("reworded from " + origin["reword"]["source"] if "reword" in origin
                else "promoted from " + origin["promotion"]["source"] if "promotion" in origin
                else "revised from " + origin["revision"]["source"] if "revision" in origin
                else f"generated ({origin['generation']['backend']})" if "generation" in origin else "hand-written")
        gate = origin.get("solvability")
        solved = ("not measured by the solvability gate" if gate is None else
                  f"{gate['successes']}/{gate['attempts']} solved by the {gate['solver_version']} on seeds "
                  f"{gate['seeds'][0]}..{gate['seeds'][-1]}"
                  + (f", {gate['env_steps_per_success']:.0f} env steps per success"
                     if gate.get("env_steps_per_success") else ""))
        typer.echo(f"{env_id}\n    {spec.instruction}\n    objects:  {objects}\n    stages:   {stages}\n"
                   f"    policies: {policies}; {made}\n    solved:   {solved}\n    folder:   {version.root}")
