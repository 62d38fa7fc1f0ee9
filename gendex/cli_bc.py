"""``gendex bc ...``: the behaviour-cloning baseline (train on a dataset, evaluate on the env); see
:mod:`gendex.imitation.bc` and docs/results.md."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from gendex.cli_common import die

bc_app = typer.Typer(no_args_is_help=True, help="Behaviour cloning on GenDex datasets: train, evaluate.")

EVAL_SEED = 1_000_000
"""Default first evaluation seed: far from every dataset's seeds (0..) and the gate's (50 000 000+)."""


def run_eval(ckpt: Path, episodes: int, seed: int, out: Path | None = None) -> dict:
    """Evaluate a BC checkpoint on its dataset's task; prints and returns the summary (written to ``out``)."""
    from gendex.eval.metrics import wilson
    from gendex.eval.runner import evaluate_task
    from gendex.imitation.bc import BCPolicy

    policy = BCPolicy(ckpt)
    seeds = list(range(seed, seed + episodes))
    leaked = sorted(set(seeds) & set(policy.training_seeds))
    if leaked:
        raise ValueError(f"evaluation seeds {leaked[:5]}... were training seeds of {ckpt}; pick --seed elsewhere")
    def show(r) -> None:
        typer.echo(f"  seed {r.seed}: {'success' if r.success_at_end else 'fail'}"
                   + (f" ({r.failure})" if r.failure else ""), err=True)

    results = evaluate_task(policy.task_id, lambda: policy, seeds, env_kwargs=policy.env_kwargs, progress=show)
    k = sum(r.success_at_end for r in results)
    lo, hi = wilson(k, len(results))
    summary = {"checkpoint": str(ckpt), "task": policy.task_id, "demos": policy.ckpt["demos"], "episodes":
               len(results), "success_at_end": k, "success_once": sum(r.success_once for r in results),
               "rate": k / len(results), "wilson95": [lo, hi], "seeds": [seeds[0], seeds[-1]],
               "mean_length": sum(r.length for r in results) / len(results),
               "per_episode": [r.to_dict() for r in results]}
    typer.echo(f"{policy.task_id}: {k}/{len(results)} successes ({k / len(results):.0%}, 95 % CI {lo:.2f}-{hi:.2f}) "
               f"from {policy.ckpt['demos']} demos")
    if out is not None:
        out.write_text(json.dumps(summary, indent=1) + "\n")
    return summary


@bc_app.command("train")
def bc_train(dataset: Path = typer.Argument(..., help="A LeRobot dataset folder (or a dataset build of one task)."),
             out: Path = typer.Option(..., "--out", help="Folder for bc.pt and its record."),
             demos: int = typer.Option(None, "--demos", min=1, help="Use the first N episodes (default: all)."),
             steps: int = typer.Option(20_000, "--steps", min=1, help="Gradient steps."),
             chunk: int = typer.Option(10, "--chunk", min=1, help="Actions predicted per step."),
             seed: int = typer.Option(0, "--seed"),
             eval_episodes: int = typer.Option(0, "--eval-episodes", min=0,
                                               help="Then evaluate on this many unseen seeds (0: do not)."),
             eval_seed: int = typer.Option(EVAL_SEED, "--eval-seed")) -> None:
    """Train the BC baseline on state + environment state; optionally evaluate it on the env."""
    from gendex.imitation.bc import BCConfig, train
    from gendex_envs.errors import GenDexError

    try:
        path = train(dataset, out, demos, BCConfig(chunk=chunk, steps=steps, seed=seed),
                     progress=lambda s, loss: typer.echo(f"  step {s}: loss {loss:.4f}", err=True))
        typer.echo(f"wrote {path}")
        if eval_episodes:
            run_eval(path, eval_episodes, eval_seed, out / "eval.json")
    except (GenDexError, ValueError) as exc:
        die(exc)


def embed_instructions(texts: list[str]):
    """all-MiniLM-L6-v2 embeddings of ``texts`` (the model the generator measures instruction diversity with)."""
    from generator.embedding import embed

    return embed(texts)[0]


def dataset_folders(paths: list[Path]) -> list[Path]:
    """Each path as given, or, for a dataset build (``gendex_dataset.json`` in it), every task folder of it."""
    out = []
    for p in paths:
        if (p / "gendex_dataset.json").is_file():
            out += sorted(d for d in p.iterdir() if (d / "lerobot" / "meta" / "info.json").is_file())
        else:
            out.append(p)
    return out


@bc_app.command("train-multitask")
def bc_train_multitask(datasets: list[Path] = typer.Argument(..., help="LeRobot datasets of one task each, or "
                                                                        "dataset builds (every task in them)."),
                       out: Path = typer.Option(..., "--out", help="Folder for bc.pt and its record."),
                       demos: int = typer.Option(None, "--demos", min=1, help="First N episodes of each task."),
                       steps: int = typer.Option(40_000, "--steps", min=1, help="Gradient steps."),
                       chunk: int = typer.Option(10, "--chunk", min=1, help="Actions predicted per step."),
                       camera: str = typer.Option(None, "--camera", help="Learn from this camera's frames and the "
                                                                         "joint state instead of the object poses."),
                       image_size: int = typer.Option(64, "--image-size", min=8, max=512,
                                                      help="With --camera: frames resized to this size."),
                       task_balance: float = typer.Option(
                           0.0, "--task-balance", min=0.0, max=1.0,
                           help="How batches share out over tasks: 0 frames uniform (long demonstrations dominate), "
                                "1 every task equally often."),
                       joint_velocity: bool = typer.Option(
                           False, "--joint-velocity/--no-joint-velocity",
                           help="State policy: read the joint velocities as well as the positions (off: the fit "
                                "leans on them and drifts in closed loop)."),
                       seed: int = typer.Option(0, "--seed"),
                       threads: int = typer.Option(1, "--threads", min=1,
                                                   help="Torch threads for the fit (state policy); more help only "
                                                        "on cores nothing else uses.")) -> None:
    """Train one language-conditioned policy on many tasks (state + environment state, or with --camera the
    camera's frames + joint state, and the instruction's MiniLM embedding); evaluate it with gendex eval --policy
    bc:OUT/bc.pt."""
    from gendex.imitation import multitask, pixels
    from gendex_envs.errors import GenDexError

    try:
        folders = dataset_folders(datasets)
        typer.echo(f"training on {len(folders)} datasets", err=True)
        show = lambda s, loss: typer.echo(f"  step {s}: loss {loss:.4f}", err=True)  # noqa: E731
        if camera is None:
            config = multitask.MultiTaskConfig(chunk=chunk, steps=steps, task_balance=task_balance,
                                               joint_velocity=joint_velocity, seed=seed)
            path = multitask.train(folders, out, embed_instructions, demos, config, progress=show, threads=threads)
        else:
            path = pixels.train(folders, out, embed_instructions, demos,
                                pixels.PixelConfig(camera=camera, image_size=image_size, chunk=chunk, steps=steps,
                                                   task_balance=task_balance, seed=seed), progress=show)
        typer.echo(f"wrote {path}")
    except (GenDexError, ValueError, OSError) as exc:
        die(exc)


@bc_app.command("eval")
def bc_eval(ckpt: Path = typer.Argument(..., help="A bc.pt checkpoint."),
            episodes: int = typer.Option(50, "--episodes", min=1),
            seed: int = typer.Option(EVAL_SEED, "--seed", help="First evaluation seed (disjoint from training)."),
            out: Path = typer.Option(None, "--out", help="Write the results JSON here.")) -> None:
    """Evaluate a BC checkpoint on its task (success at the end of each episode, with a 95 % Wilson interval)."""
    from gendex_envs.errors import GenDexError

    try:
        run_eval(ckpt, episodes, seed, out)
    except (GenDexError, ValueError) as exc:
        die(exc)
