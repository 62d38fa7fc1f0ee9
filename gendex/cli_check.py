"""``gendex check``: the per-version checks of the task library (:mod:`gendex.check`), in parallel, with a JSON
report. CI runs it on the versions a change touches plus a fixed sample; ``gendex check`` alone checks them all."""

from __future__ import annotations

import time
from pathlib import Path

import typer

from gendex.cli_common import die


def check_command(ids: list[str] = typer.Argument(None, help="Task versions: registered ids, names (the highest "
                                                              "version) or version folders. None and no selection "
                                                              "option: every registered version."),
                  workers: int = typer.Option(1, "--workers", "-j", min=1, help="Local worker processes."),
                  report: Path = typer.Option(None, "--report", help="Write a JSON report here: per id its status "
                                                                     "(passed, failed, xfail), message and seconds."),
                  changed_since: str = typer.Option(None, "--changed-since", help="Also the versions whose folders "
                                                                                  "differ from this git revision."),
                  reference: bool = typer.Option(False, "--reference", help="Also the newest version of each "
                                                                            "reference task."),
                  sample: int = typer.Option(0, "--sample", min=0, help="Also N more versions drawn at random."),
                  seed: int = typer.Option(0, "--seed", help="The seed of --sample's draw."),
                  list_only: bool = typer.Option(False, "--list", help="Print the selected ids and exit.")) -> None:
    """Check task versions: the static check of their reward code, the registered time limit, Gymnasium's
    check_env, and reset plus a few random steps with finite observations and rewards. Exit 1 if any fails."""
    from gendex.check import CheckSelectionError, run_checks, select, write_report

    try:
        chosen = select(ids or (), changed_since_rev=changed_since, reference=reference, sample=sample, seed=seed)
    except CheckSelectionError as exc:
        die(exc)
    if list_only:
        for env_id in chosen:
            typer.echo(env_id)
        return
    start = time.perf_counter()
    results = []
    for r in run_checks(chosen, workers):
        results.append(r)
        typer.echo(f"{r.status:<6} {r.id} ({r.seconds:.1f} s){': ' + r.message if r.message else ''}")
    seconds = time.perf_counter() - start
    if report is not None:
        write_report(report, results, workers, seconds)
    failed = [r for r in results if not r.ok]
    known = sum(r.status == "xfail" for r in results)
    typer.echo(f"{len(results) - len(failed)}/{len(results)} versions passed ({known} known defects) "
               f"in {seconds:.1f} s on {workers} worker{'s' if workers > 1 else ''}")
    raise typer.Exit(1 if failed else 0)
