"""``gendex eval``: a policy on a benchmark suite (:mod:`gendex.eval.suite_run`); the policy specs the command
line adds to the built-in ones (``bc:PATH``)."""

from __future__ import annotations

from pathlib import Path

import typer

from gendex.cli_common import backend_of, die, ray_address_option, ray_option


def policy_factory(spec: str):
    """What ``--policy SPEC`` builds: ``bc:PATH`` (a behaviour-cloning checkpoint) or a built-in / module policy
    (:func:`gendex.eval.policies.resolve_policy`). Top-level, so worker processes can resolve the spec themselves."""
    if spec.startswith("bc:"):
        from gendex.cli_bc import embed_instructions
        from gendex.imitation.bc import load_policy

        paths = spec.removeprefix("bc:")
        return lambda: load_policy(paths, embed_instructions)
    from gendex.eval.policies import resolve_policy

    return resolve_policy(spec)


def eval_command(suite: str = typer.Option(..., "--suite", help="A suite in suites/ (e.g. gendex-ref-v1)."),
                 policy: str = typer.Option(..., "--policy", help="random | hold | oracle | bc:PATH[,PATH...] "
                                                                  "(one per task) | module:factory"),
                 out: Path = typer.Option(..., "--out", help="Result folder (resumes a stopped run)."),
                 episodes: int = typer.Option(None, "--episodes", min=1, help="Episodes per task (default: the "
                                                                               "suite's; fewer marks it incomplete)."),
                 workers: int = typer.Option(1, "--workers", min=1, help="Processes sharing the tasks."),
                 ray: bool = ray_option(), ray_address: str = ray_address_option(),
                 tasks: str = typer.Option(None, "--tasks", help="Comma-separated subset of the suite's tasks."),
                 videos: int = typer.Option(0, "--videos", min=0, help="Record the first K episodes of each task."),
                 allow_changed_tasks: bool = typer.Option(
                     False, "--allow-changed-tasks",
                     help="Run even when a task's files differ from the suite's (the committed version, by digest), "
                          "e.g. a folder registered over its id with GENDEX_ALLOW_OVERRIDE=1; the leaderboard "
                          "refuses such a result.")
                 ) -> None:
    """Evaluate a policy on a suite: eval_info.json (LeRobot's fields, per-task success with 95 % Wilson
    intervals, suite hash, GenDex version); episodes whose policy raises or gives a bad action fail with the
    reason."""
    import dataclasses

    from gendex.eval.eval_info import summary
    from gendex.eval.suite import load_suite
    from gendex.eval.suite_run import EvalError, run_suite
    from gendex_envs.errors import GenDexError

    try:
        s = load_suite(suite)
        if tasks:
            chosen = [t for t in tasks.split(",") if t]
            unknown = sorted(set(chosen) - set(s.tasks))
            if unknown:
                raise EvalError(f"--tasks {unknown} are not in suite {s.name} ({', '.join(s.tasks)})")
            s = dataclasses.replace(s, tasks=tuple(t for t in s.tasks if t in chosen))
        factory = policy_factory(policy)
        trained_on = getattr(factory(), "training_seeds", None) if policy.startswith("bc:") else None

        def show(row) -> None:
            ok = "success" if row[s.metric] else "fail"
            typer.echo(f"  {row['task']} seed {row['seed']}: {ok}" + (f" ({row['failure']})" if row["failure"]
                                                                         else ""), err=True)

        info = run_suite(s, policy, policy_factory, out, episodes=episodes,
                         backend=backend_of(workers, ray, ray_address),
                         training_seeds=trained_on, videos=videos, progress=show,
                         allow_changed_tasks=allow_changed_tasks, groups=skill_groups(s.tasks))
    except (GenDexError, ValueError) as exc:
        die(exc)
    result = summary(info)
    for task, t in result.per_task.items():
        lo, hi = t["wilson95"]
        typer.echo(f"{task} ({t['group']}): {t['successes']}/{t['episodes']} = {t['pc_success']:.0f} % (95 % CI "
                   f"{lo:.0f}-{hi:.0f}), success once {t['pc_success_once']:.0f} %, mean length {t['mean_length']:.0f}")
    for group, g in info["per_group"].items():
        typer.echo(f"  group {group}: {g['pc_success']:.0f} % of {g['n_episodes']} episodes")
    a = result.overall
    typer.echo(f"{s.name} / {policy}: {a['pc_success']:.1f} % of {a['episodes']} episodes (95 % CI "
               f"{a['wilson95'][0]:.1f}-{a['wilson95'][1]:.1f}), mean over tasks {a['mean_task_pc_success']:.1f} %; "
               f"{out / 'eval_info.json'}")


def skill_groups(tasks) -> dict[str, str]:
    """Task id -> its group in an eval result: the skills it exercises, joined by ``+`` (``close_door+put_in``), as
    ``gendex stats`` counts them (:func:`generator.stats.task_skills`)."""
    from gendex_envs.registry import resolve_task
    from generator.stats import task_skills

    return {t: "+".join(task_skills(resolve_task(t).spec)) or "other" for t in tasks}


leaderboard_app = typer.Typer(no_args_is_help=True, help="The leaderboard: result files in leaderboard/<suite>/, "
                                                         "a static site and docs/leaderboard.md.")


@leaderboard_app.command("add")
def leaderboard_add(result: Path = typer.Argument(..., help="A gendex eval result folder (or its eval_info.json)."),
                    method: str = typer.Option(..., "--method"), authors: str = typer.Option(..., "--authors"),
                    code: str = typer.Option(..., "--code", help="Link to the method's code."),
                    kind: str = typer.Option(..., "--kind", help="baseline | oracle | imitation | reinforcement | "
                                                                 "other"),
                    sees_state: bool = typer.Option(..., "--sees-simulator-state/--no-simulator-state",
                                                    help="Whether the policy reads the simulator's object state "
                                                         "(poses, the planner's world) besides cameras and joints."),
                    training_data: str = typer.Option("none", "--training-data"),
                    notes: str = typer.Option("", "--notes"),
                    date: str = typer.Option(None, "--date", help="YYYY-MM-DD (default: today)")) -> None:
    """File an evaluation as a leaderboard result (leaderboard/<suite>/<method>.json), validated."""
    import datetime
    import json
    import re

    from gendex.eval.leaderboard import LEADERBOARD_DIR, load_entries
    from gendex.eval.suite import SUITES_DIR
    from gendex_envs.atomic_io import write_json
    from gendex_envs.errors import GenDexError

    path = result / "eval_info.json" if result.is_dir() else result
    try:
        info = json.loads(path.read_text())
        suite = info["suite"]["name"]
        if not isinstance(suite, str) or not re.fullmatch(r"[a-z0-9][a-z0-9.-]*", suite) or ".." in suite \
                or not (SUITES_DIR / f"{suite}.yaml").is_file():
            raise ValueError(f"{path}: suite {str(suite)[:80]!r} is not a suite in {SUITES_DIR}")
        entry = {"method": method, "authors": authors, "code": code, "policy_kind": kind,
                 "training_data": training_data, "date": date or datetime.date.today().isoformat(),
                 "policy": info["policy"], "sees_simulator_state": sees_state, "notes": notes, "eval_info": info}
        dest = LEADERBOARD_DIR / suite / (re.sub(r"[^a-z0-9]+", "-", method.lower()).strip("-") + ".json")
        before = dest.read_bytes() if dest.is_file() else None
        write_json(dest, entry, indent=1)
        try:
            load_entries(suite)
        except GenDexError:  # the board is left as it was: the earlier result of this name, or none
            if before is None:
                dest.unlink()
            else:
                dest.write_bytes(before)
            raise
    except (GenDexError, OSError, KeyError, ValueError) as exc:
        die(exc)
    typer.echo(f"wrote {dest}")


@leaderboard_app.command("build")
def leaderboard_build(out: Path = typer.Option(Path("out/leaderboard"), "--out", help="Folder for the site."),
                      docs: Path = typer.Option(Path("docs/leaderboard.md"), "--docs",
                                                help="Where to write the Markdown tables.")) -> None:
    """Render the leaderboard: a static site (sortable tables, per-task breakdowns) and docs/leaderboard.md."""
    from gendex.eval.leaderboard import build_site, markdown
    from gendex_envs.errors import GenDexError

    try:
        pages = build_site(out)
        docs.write_text(markdown())
    except GenDexError as exc:
        die(exc)
    typer.echo(f"wrote {len(pages)} pages to {out} and {docs}")
