"""``gendex`` command line: thin commands (parse, call, print) over the runtime (:mod:`gendex_envs`), the
application packages (:mod:`gendex.solve`, :mod:`gendex.data`, :mod:`gendex.train`) and the generator.

A task argument is a registered id (``GenDex/PutAppleBowl-v0``), an unversioned name (``PutAppleBowl``: its highest
version, as ``gym.make`` resolves it) or a version folder."""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # noqa: F401  (first: it pins OpenBLAS's kernels before anything loads numpy)
# isort: on

import functools
import logging
from pathlib import Path

import typer

from gendex.cli_bc import bc_app
from gendex.cli_check import check_command
from gendex.cli_common import backend_of, ray_address_option, ray_option
from gendex.cli_common import die as _die
from gendex.cli_common import refuse_request as _refuse
from gendex.cli_dataset import dataset_app
from gendex.cli_eval import eval_command, leaderboard_app
from gendex.cli_list import list_command
from gendex.cli_restyle import restyle_command
from gendex.cli_store import store_app
from gendex.cli_trust import trust_command
from gendex_envs.registry import REFERENCE_TASKS

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="GenDex: generative simulation for dexterous hands (ShadowHand on UR10e, SAPIEN/ManiSkill3).")
app.add_typer(dataset_app, name="dataset")
app.add_typer(bc_app, name="bc")
app.command("eval")(eval_command)
app.command("list")(list_command)
app.add_typer(leaderboard_app, name="leaderboard")
app.command("trust")(trust_command)
app.command("restyle")(restyle_command)
app.command("check")(check_command)
app.add_typer(store_app, name="store")
log = logging.getLogger("gendex")


@app.callback()
def _main(verbose: bool = typer.Option(False, "--verbose", "-v", help="Log debug messages.")) -> None:
    logging.basicConfig(level=logging.DEBUG if verbose else logging.INFO,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s", datefmt="%H:%M:%S")
    # gymnasium-robotics prints a deprecation notice for unrelated Adroit envs on import; ManiSkill logs on its own
    logging.getLogger("gymnasium_robotics").setLevel(logging.ERROR)


@app.command()
def stats(as_json: bool = typer.Option(False, "--json", help="Print the numbers as JSON."),
          all_versions: bool = typer.Option(False, "--all-versions", help="Count every version, not only the "
                                                                           "latest of each task."),
          diversity: bool = typer.Option(True, "--diversity/--no-diversity",
                                         help="Embed the instructions with all-MiniLM-L6-v2 (the 'stats' extra).")
          ) -> None:
    """What the task library holds: tasks per skill, assets, stages, articulated vs rigid, instruction and scene
    diversity."""
    import json

    from gendex_envs.registry import registered_tasks
    from generator.stats import format_stats, library_stats

    numbers = library_stats(registered_tasks(), all_versions=all_versions, diversity=diversity)
    typer.echo(json.dumps(numbers, indent=1) if as_json else format_stats(numbers))


@app.command()
def reword(keep: list[str] = typer.Option([], "--keep", help="Task names whose instruction stays (repeatable)."),
           dry_run: bool = typer.Option(False, "--dry-run", help="Print the new wordings; publish nothing."),
           commands: bool = typer.Option(False, "--commands",
                                         help="Also reword the commands: each one the wording least like the other "
                                              "tasks' commands of those the reader reads as the same task.")) -> None:
    """Reword the library: each task's command framed by the situation and purpose least like the other tasks'
    instructions (all-MiniLM-L6-v2, the 'stats' extra), each change published as the task's next version."""
    from gendex_envs.registry import registered_tasks
    from generator.reword import plan_rewording, publish_reworded

    versions = registered_tasks()
    unknown = sorted(set(keep) - {v.name for v in versions.values()})
    if unknown:
        raise typer.BadParameter(f"no registered task named {', '.join(unknown)}", param_hint="--keep")
    changes, numbers = plan_rewording(versions, keep=keep, commands=commands)
    for c in changes:
        typer.echo(f"{c.env_id}\n    was: {c.old}\n    now: {c.new}")
        if not dry_run:
            record = {"reason": "gendex reword" + (" --commands" if commands else "") + ": the library's wording",
                      "library": numbers}
            published = publish_reworded(versions[c.env_id], c.new, record)
            typer.echo(f"    published {published.env_id}")
    typer.echo(f"{numbers['reworded']} of {numbers['tasks']} tasks reworded{' (dry run)' if dry_run else ''}; "
               f"mean pairwise MiniLM cosine {numbers['mean_pairwise_cosine_before']:.3f} -> "
               f"{numbers['mean_pairwise_cosine_after']:.3f}; commands alone "
               f"{numbers['commands_mean_pairwise_cosine_before']:.3f} -> "
               f"{numbers['commands_mean_pairwise_cosine_after']:.3f} ({numbers['commands_reworded']} reworded)")


@app.command()
def gate(task_ids: list[str] = typer.Argument(..., help="Tasks to measure, e.g. GenDex/PutAppleBowl-v1."),
         attempts: int = typer.Option(10, "--attempts", min=1, help="Solver attempts (the task's gate seeds)."),
         write: bool = typer.Option(False, "--write", help="Store each measurement as the version's solvability "
                                                          "record (shown by list, stats and tasks-doc).")) -> None:
    """Run the solvability gate on committed task versions: the stage executor on the task's own unseen seeds, in
    a child process; exits 1 when any task is below 80 %."""

    from gendex_envs.atomic_io import write_json
    from gendex_envs.errors import GenDexError
    from gendex_envs.registry import resolve_task
    from generator.steps.gate import GATE_MIN_RATE, run_gate

    failed = []
    for task_id in task_ids:
        try:
            version = resolve_task(task_id)
            result = run_gate(version.root, version.name, attempts)
        except GenDexError as exc:
            _die(exc)
        typer.echo(f"{version.env_id}: {result.summary()}"
                   + (f", {result.env_steps_per_success:.0f} env steps per success"
                      if result.env_steps_per_success else ""))
        if write:
            write_json(version.files.record("solvability"), result.to_dict(), indent=2, sort_keys=True)
        if not result.passed:
            failed.append(version.env_id)
    if failed:
        typer.secho(f"below {GATE_MIN_RATE:.0%}: {', '.join(failed)}", fg=typer.colors.RED, err=True)
        raise typer.Exit(code=1)


@app.command("tasks-doc")
def tasks_doc(out: Path = typer.Option(Path("docs/tasks.md"), "--out", help="The gallery Markdown file."),
              all_versions: bool = typer.Option(False, "--all-versions", help="A row per version, not per task."),
              size: int = typer.Option(192, "--size", min=64, help="Thumbnail size (px)."),
              rerender: bool = typer.Option(False, "--rerender", help="Draw every picture again (default: keep a "
                                                                      "version's picture already there).")) -> None:
    """Write the task gallery (picture, instruction, skills, objects, stages, measured success) to docs/tasks.md,
    with a thumbnail of every task beside it."""
    from gendex_envs.errors import GenDexError
    from gendex_envs.registry import registered_tasks
    from generator.task_gallery import write_task_gallery

    try:
        path = write_task_gallery(registered_tasks(), out, all_versions=all_versions, size=size, rerender=rerender)
    except GenDexError as exc:
        _die(exc)
    typer.echo(f"wrote {path}")


def _save_png(rgb, path: Path) -> Path:
    from PIL import Image

    from gendex_envs.atomic_io import atomic_path

    with atomic_path(path) as tmp:  # never leave a half-written PNG behind
        Image.fromarray(rgb).save(tmp)
    return path


def _render_views(env_id: str, out: Path, seed: int, montage: bool = False, scene: str | None = None
                  ) -> dict[str, Path]:
    import gymnasium as gym
    import numpy as np

    from gendex_envs.registry import resolve_task

    env_id = resolve_task(env_id).env_id
    env = gym.make(env_id, render_mode="rgb_array", **({"scene": scene} if scene else {}))
    try:
        env.reset(seed=seed)
        views = env.unwrapped.render_views()
    finally:
        env.close()
    out.mkdir(parents=True, exist_ok=True)
    stem = env_id.split("/")[-1]
    paths = {name: _save_png(rgb[0], out / f"{stem}_{name}.png") for name, rgb in views.items()}
    if montage:
        paths["montage"] = _save_png(np.concatenate([rgb[0] for rgb in views.values()], axis=1),
                                     out / f"{stem}_views.png")
    return paths


@app.command()
def scenes() -> None:
    """List what a task's scene section can name: styles, surface materials, backgrounds, structures, paints."""
    from gendex_envs.assets.scenery_catalog import guide

    typer.echo(guide())


@app.command()
def render(task_id: str = typer.Argument(..., help="e.g. GenDex/PutAppleBowl-v0"),
           out: Path = typer.Option(Path("out/render"), "--out", help="Folder for the PNGs."),
           seed: int = typer.Option(0, help="Reset seed (object placement; the scene's appearance draw)."),
           montage: bool = typer.Option(False, help="Also write the three views side by side."),
           scene: str = typer.Option("", "--scene", help="Show the task in this scene style (kitchen, lab, ...: "
                                     "`gendex scenes`) instead of its own scene.")) -> None:
    """Render a task's three views (left-overhead, right-overhead, top-down) to PNG."""
    import gendex_envs  # noqa: F401
    from gendex_envs.errors import GenDexError

    try:
        paths = _render_views(task_id, out, seed, montage, scene or None)
    except GenDexError as exc:
        _die(exc)
    for name, path in paths.items():
        typer.echo(f"{name}: {path}")


@app.command()
def assets(as_json: bool = typer.Option(False, "--json", help="Machine-readable catalog."),
           guidance: bool = typer.Option(False, "--guidance", help="The text block proposal prompts consume.")) -> None:
    """List the asset catalog (shipped objects, articulated models and user datasets found on disk)."""
    import json

    from gendex_envs.assets.guidance import catalog_json, guidance_text

    if as_json:
        typer.echo(json.dumps(catalog_json(), indent=1))
    elif guidance:
        typer.echo(guidance_text())
    else:
        data = catalog_json()
        for a in data["assets"]:
            size = " x ".join(f"{100 * v:.1f}" for v in a["size_m"])
            typer.echo(f"{a['id']:28s} {a['category']:18s} {a['kind']:11s} {size:>22s} cm  {a['mass_kg']:7.3f} kg  "
                       f"{a['licence']}")
        c = data["counts"]
        typer.echo(f"\n{c['rigid']} rigid assets, {c['articulated']} articulated in "
                   f"{len(c['articulated_categories'])} categories")


@app.command()
def gallery(out: Path = typer.Option(Path("docs/assets"), "--out", help="Folder for thumbnails and index."),
            size: int = typer.Option(256, help="Thumbnail size in pixels."),
            rerender: bool = typer.Option(True, help="Render every thumbnail again (--no-rerender: only the "
                                                     "assets that have none yet).")) -> None:
    """Render a thumbnail of every asset (on the task table, next to the hand) and write ``<out>.md``."""
    from gendex.gallery import render_gallery
    from gendex.solve.lift_check import held_summary
    from generator.backends.roles import MIN_GRASP_RATE

    index = render_gallery(out, size, rerender, held_summary(MIN_GRASP_RATE))
    typer.echo(f"wrote {index}")


@app.command()
def collect(task_id: str = typer.Argument(..., help="e.g. GenDex/PutAppleBowl-v0"),
            num_success: int = typer.Option(..., "--num-success", min=1, help="Successful episodes to keep."),
            out: Path = typer.Option(..., "--out", help="Dataset folder (resumes if it holds a collection)."),
            fmt: str = typer.Option("lerobot", "--format", help="lerobot | h5 | both"),
            cameras: str = typer.Option("", help="Comma-separated camera names to record (e.g. left_overhead)."),
            resolution: int = typer.Option(128, min=16, help="Camera images are RESOLUTION x RESOLUTION pixels."),
            video: str = typer.Option("libsvtav1", help="Camera images as MP4 video with this encoder (libsvtav1: "
                                                        "AV1, lerobot's default; libx264: H.264) or 'png' (PNG "
                                                        "inside the parquet files)."),
            workers: int = typer.Option(1, min=1, help="Worker processes running attempts (one env each)."),
            ray: bool = ray_option(), ray_address: str = ray_address_option(),
            seed: int = typer.Option(0, help="Attempt k resets with seed + k."),
            solver: str = typer.Option("stages", help="Solver: stages (planned + scripted task stages), hold, random."),
            max_attempts: int = typer.Option(None, help="Give up after this many attempts.")) -> None:
    """Collect successful episodes into a LeRobot v3.0 dataset and/or HDF5 trajectories (resumable)."""
    from tqdm import tqdm

    from gendex.data.collector import CollectConfig, write_card
    from gendex.data.collector import collect as run_collect
    from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
    from gendex_envs.errors import GenDexError, suggest
    from gendex_envs.registry import resolve_task

    formats = {"lerobot": ("lerobot",), "h5": ("h5",), "both": ("lerobot", "h5")}
    if fmt not in formats:
        _die(ValueError(f"--format {fmt!r} is not one of {sorted(formats)}.{suggest(fmt, formats)}"))
    if solver not in SOLVERS:
        _die(ValueError(f"--solver {solver!r} is not one of {sorted(SOLVERS)}.{suggest(solver, SOLVERS)}"))
    from gendex_envs.video import CODECS

    if video != "png" and video not in CODECS:
        _die(ValueError(f"--video {video!r} is not one of {[*sorted(CODECS), 'png']}"))
    try:
        version = resolve_task(task_id)
        cfg = CollectConfig(task_id=version.env_id, num_success=num_success, out=out, formats=formats[fmt],
                            cameras=tuple(c for c in cameras.split(",") if c), seed=seed, max_attempts=max_attempts,
                            resolution=resolution, video_codec=None if video == "png" else video,
                            **SOLVER_ENV_KWARGS[solver])
        spec = version.spec
        with tqdm(total=num_success, desc="successes", unit="ep") as bar:
            def progress(state):
                bar.n = state.successes
                bar.set_postfix(attempts=state.attempts, steps=state.env_steps)
                bar.refresh()
            state = run_collect(cfg, SOLVERS[solver], progress, backend=backend_of(workers, ray, ray_address))
        if "lerobot" in cfg.formats and state.successes:
            write_card(cfg, spec.instruction, solver, state)
    except GenDexError as exc:
        _die(exc)
    typer.echo(f"{state.successes}/{state.attempts} attempts succeeded; {state.env_steps} env steps "
               f"({state.env_steps_per_success:.0f} per success); output in {out}")
    _echo_failures(state.failures)


def _echo_failures(failures: dict[str, int]) -> None:
    """The failed attempts per stage, skill and cause (also in the collection's state file)."""
    from gendex.solve.failure import breakdown, by_cause

    if not failures:
        return
    causes = ", ".join(f"{cause} {n}" for cause, n in sorted(by_cause(failures).items(), key=lambda kv: -kv[1]))
    typer.echo(f"failed attempts by cause: {causes}")
    for key, n in breakdown(failures):
        stage, skill, cause = key.split("/")
        typer.echo(f"  {n:4d}  {cause:20s} stage {stage} ({skill})")


@app.command()
def replay(file: Path = typer.Argument(..., help="A trajectories .h5 file written by gendex collect.")) -> None:
    """Re-simulate every episode of an HDF5 trajectory file and confirm its end state and success."""
    from gendex.data.trajectory_h5 import replay_file
    from gendex_envs.errors import GenDexError

    try:
        results = replay_file(file)
    except GenDexError as exc:
        _die(exc)
    bad = 0
    for r in results:
        ok = r.reproduced()
        bad += not ok
        typer.echo(f"episode {r.episode_id}: {r.steps} steps, success {r.success_recorded} -> {r.success_replayed}, "
                   f"max object error {1000 * r.max_object_pos_err_m:.3f} mm: {'OK' if ok else 'DIFFERS'}")
    raise typer.Exit(code=1 if bad else 0)


def _command(name: str) -> str:
    import shlex
    import sys

    return f"gendex {name} " + " ".join(shlex.quote(a) for a in sys.argv[2:])


@app.command()
def generate(n: int = typer.Option(1, "--n", min=1, help="Number of tasks to generate."),
             instruction: str = typer.Option(None, "--instruction", help='Human request, e.g. "grab the apple".'),
             backend: str = typer.Option(None, "--backend",
                                         help="anthropic | offline | replay (default: anthropic when "
                                              "ANTHROPIC_API_KEY is set, else offline)."),
             seed: int = typer.Option(0, "--seed", help="Seed of the offline author and of scene resets."),
             out: Path = typer.Option(Path("generated_tasks"), "--out", help="Task root to commit into."),
             model: str = typer.Option(None, "--model", help="Model id for the anthropic backend."),
             candidates: int = typer.Option(3, "--candidates", min=1, help="Scene candidates per task; the best "
                                                                           "one is refined."),
             gate_attempts: int = typer.Option(10, "--gate-attempts", min=0,
                                               help="Solver attempts (unseen seeds) a drafted task must pass at >= "
                                                    "80 % before it is committed; 0 skips the solvability gate."),
             workers: int = typer.Option(1, "--workers", min=1,
                                         help="Workers: with --n above 1, tasks are generated in parallel (the "
                                              "committed tasks equal one process's); with one task, its gate "
                                              "attempts run in parallel."),
             ray: bool = ray_option(), ray_address: str = ray_address_option(),
             transcript: list[Path] = typer.Option(None, "--transcript",
                                                   help="replay: a recorded transcript (or a task folder holding "
                                                        "one); repeat for several tasks."),
             kind: list[str] = typer.Option(None, "--kind",
                                            help="offline, without --instruction: draw only tasks of this kind "
                                                 "(repeat for several), e.g. place_at, open_part, composed; "
                                                 "generator.backends.offline.TASK_KINDS lists them.")) -> None:
    """Generate new tasks: propose, scene, render, critique/refine, plan, reward code, validate, commit."""
    from tqdm import tqdm

    from gendex_envs.errors import GenDexError
    from generator.backends.registry import BACKEND_NAMES, default_backend_name, make_backend
    from generator.backends.transcript import ReplayBackend
    from generator.pipeline import generate as run_generate

    name = backend or default_backend_name()
    if name not in BACKEND_NAMES:
        _die(ValueError(f"--backend {name!r} is not one of {list(BACKEND_NAMES)}"))
    from gendex_envs.task_version import TaskLayout

    files = [TaskLayout(t).resolve(TaskLayout(t).transcript) if t.is_dir() else t for t in (transcript or [])]
    if name == "replay":
        if not files:
            _die(ValueError("--backend replay needs --transcript PATH (a recorded transcript or a task folder)"))
        n = len(files)
    elif files:
        _die(ValueError("--transcript is only used with --backend replay"))
    if name == "offline":
        typer.secho("Backend: offline — a deterministic, seeded task author built from a task grammar, a layout "
                    "sampler and a library of reward terms. It is NOT a language model; set ANTHROPIC_API_KEY or "
                    "pass --backend anthropic for Claude.", fg=typer.colors.YELLOW, err=True)
    pending = list(files)
    kinds = {"kinds": tuple(kind)} if kind else {}
    if kind and (name != "offline" or instruction is not None):
        _die(ValueError("--kind chooses among the offline author's own proposals: it needs --backend offline and "
                        "no --instruction"))
    if kind:
        try:
            make_backend(name, seed=seed, **kinds)  # unknown kinds fail here, before anything runs
        except GenDexError as exc:
            _die(exc)

    def factory():
        if name == "replay":
            return ReplayBackend(pending.pop(0))
        return make_backend(name, seed=seed, model=model, **kinds)

    # several tasks on several workers (or Ray): the offline author's tasks in parallel. A parallel batch guesses
    # each task's proposal ahead of time, which needs an author that answers the same question the same way; a
    # language model does not, and a replay reads its transcripts in order, so their tasks run one after another
    # (each task's gate attempts still fan out)
    fan_out = workers > 1 or ray or ray_address is not None
    tasks_on = backend_of(workers, ray, ray_address) if n > 1 and fan_out and name == "offline" else None
    picklable = functools.partial(make_backend, name, seed=seed, model=model, **kinds)
    if n > 1 and fan_out and tasks_on is None:
        typer.secho(f"{name}: tasks are generated one after another (only the offline author's tasks run in "
                    "parallel); --workers runs each task's gate attempts", fg=typer.colors.YELLOW, err=True)
    reading = None
    if instruction is not None:  # how the request was read, before anything runs: substitutions are never silent
        from generator.catalog_view import asset_dicts
        from generator.instruction import read_instruction

        try:
            reading = read_instruction(instruction, asset_dicts())
        except GenDexError as exc:
            _refuse(exc, instruction, out)
        for line in reading.lines():
            typer.secho(line, fg=typer.colors.YELLOW if "SUBSTITUTED" in line or " chose " in line else None,
                        err=True)
    command = _command("generate")
    rows: list = []
    failed: list[str] = []
    try:
        with tqdm(total=n, desc="tasks", unit="task") as bar:
            def progress(summary) -> None:
                rows.append(summary)
                bar.update(1)
                bar.set_postfix(last=summary.committed.name)
            run_generate(factory if tasks_on is None else picklable, out, n=n, seed=seed, instruction=instruction,
                         command=command, progress=progress, candidates=candidates, gate_attempts=gate_attempts,
                         reading=reading, failed=failed, gate_workers=workers if tasks_on is None else 1,
                         tasks_on=tasks_on)
    except GenDexError as exc:
        _refuse(exc, instruction, out)
    typer.echo("\nGenerated tasks (physical-check violations before -> after refinement)")
    for s in rows:
        dropped = f" ({s.proposals_tried - 1} earlier proposal(s) dropped)" if s.proposals_tried > 1 else ""
        typer.echo(f"  {s.committed.env_id}: {s.violations_before} -> {s.violations_after} violations in "
                   f"{s.refine_rounds} round(s){dropped}, {s.seconds:.1f} s; folder {s.committed.root}")
        if s.gate is not None:
            typer.echo(f"    solvability gate: {s.gate.summary()}, "
                       f"{s.gate.env_steps_per_success or 0:.0f} env steps per success")
        for reason in s.dropped:
            typer.secho(f"    rejected before it: {reason}", fg=typer.colors.YELLOW)
        for phrase, asset in s.substitutions.items():
            typer.secho(f"    substituted: {phrase!r} -> {asset} (recorded in the task's proposal record)",
                        fg=typer.colors.YELLOW)
    for reason in failed:
        typer.secho(f"  no task: {reason}", fg=typer.colors.RED, err=True)
    if rows:  # model-written code stays untrusted until a person reviews it (gendex_envs.trust_record)
        typer.echo("The new reward code runs as untrusted code (static check, sandbox); once you have reviewed a task, "
                   "`gendex trust FOLDER` records it as trusted (generated_tasks/ only).")
    gated = sum(1 for s in rows for r in s.dropped if "solvability gate" in r)
    typer.echo(f"\n{len(rows)} of {n} task(s) committed; {sum(len(s.dropped) for s in rows)} proposal(s) rejected on "
               f"the way ({gated} by the solvability gate); {len(failed)} task slot(s) without a task")
    if failed:
        raise typer.Exit(1)


@app.command()
def train(task_id: str = typer.Argument(..., help="e.g. GenDex/PickUpBottle-v0, PickUpBottle, or a version folder."),
          stage: str = typer.Option(..., "--stage", help="Stage index or name; 'task' trains the whole task as one "
                                                         "stage with every joint."),
          steps: int = typer.Option(200_000, "--steps", min=1, help="Env steps of PPO training."),
          envs: int = typer.Option(None, "--envs", min=1, help="Parallel envs (default: the preset's)."),
          preset: str = typer.Option("cpu", "--preset", help="cpu (2-core machine) | paper (the seed paper's "
                                                              "hyperparameters, GPU backend)."),
          seed: int = typer.Option(0, "--seed"),
          out: Path = typer.Option(None, "--out", help="Run folder (default: out/train/<Name>-v<N>); train more "
                                                       "stages into the same folder to chain them."),
          eval_episodes: int = typer.Option(20, "--eval-episodes", min=1),
          init_from: str = typer.Option(None, "--init-from", help="Start from the stage's policy in this task "
                                                                  "version (id or folder) or training run folder."),
          ppo: list[str] = typer.Option(None, "--ppo", help="Override a preset setting, KEY=VALUE (repeatable), "
                                                            "e.g. --ppo log_std_init=-1.5 --ppo ent_coef=0.001.")
          ) -> None:
    """Train PPO on one stage of a task version into a run folder (the version is never changed); publish the
    result as a new version with ``gendex promote``."""
    from gendex.train.presets import get_preset, parse_overrides
    from gendex.train.train import default_run_dir, policy_to_start_from, train_stage
    from gendex_envs.errors import GenDexError
    from gendex_envs.registry import resolve_task

    try:
        version = resolve_task(task_id)
        run = out or default_run_dir(version)
        chosen = get_preset(preset).with_overrides(**parse_overrides(ppo or []))
        init = policy_to_start_from(version, stage, init_from) if init_from else None
        r = train_stage(version, stage, steps=steps, run_dir=run, preset=chosen, n_envs=envs, seed=seed,
                        eval_episodes=eval_episodes, command=_command("train"), init=init)
    except GenDexError as exc:
        _die(exc)
    typer.echo(f"{r.stage}: {r.steps} env steps in {r.wall_s:.0f} s -> {r.policy.model}\n"
               f"  trained:   success {r.trained.successes}/{r.trained.episodes}, mean return "
               f"{r.trained.mean_return:.2f}\n"
               f"  untrained: success {r.untrained.successes}/{r.untrained.episodes}, mean return "
               f"{r.untrained.mean_return:.2f}\n"
               f"publish it as the next version of {version.env_id} with: gendex promote {run}")


@app.command()
def promote(runs: list[Path] = typer.Argument(..., help="Training run folders (gendex train --out) of one version.")
            ) -> None:
    """Publish the runs' task version plus their trained policies and start states as its next version."""
    from gendex.train.train import promote as run_promote
    from gendex_envs.errors import GenDexError

    try:
        new = run_promote(runs, command=_command("promote"))
    except GenDexError as exc:
        _die(exc)
    typer.echo(f"published {new.env_id} ({', '.join(new.artifacts.policy_stages()) or 'no'} policies) in {new.root}")


@app.command()
def ablate(tasks: list[str] = typer.Option(list(REFERENCE_TASKS), "--tasks",
                                           help="Task names (latest version) or env ids (default: reference tasks)."),
           budget: int = typer.Option(100_000, "--budget", min=1, help="PPO env steps per task and variant."),
           variants: list[str] = typer.Option(None, "--variant", help="Run only these (repeatable): no_subgoals, "
                                                                      "subgoals, frozen_dofs, mp_rl."),
           eval_episodes: int = typer.Option(20, "--eval-episodes", min=1),
           seed: int = typer.Option(0, "--seed"),
           out: Path = typer.Option(Path("out/ablate"), "--out", help="Run folder (policies, curves, cells)."),
           results: Path = typer.Option(Path("docs/results.md"), "--results", help="Markdown file for the table."),
           fresh: bool = typer.Option(False, "--fresh", help="Re-run cells already saved in --out."),
           workers: int = typer.Option(1, "--workers", min=1, help="Cells trained at once (processes)."),
           ray: bool = ray_option(), ray_address: str = ray_address_option()) -> None:
    """The paper's four-variant comparison: success and env steps to 1000 successes per task and variant."""
    from gendex.train.ablate import VARIANTS, run_ablation, write_results
    from gendex_envs.errors import GenDexError
    from gendex_envs.registry import resolve_task

    try:
        versions = [resolve_task(t) for t in tasks]
        chosen = tuple(variants) if variants else tuple(VARIANTS)
        bad = [v for v in chosen if v not in VARIANTS]
        if bad:
            raise ValueError(f"unknown variants {bad}; variants: {list(VARIANTS)}")
        command = _command("ablate")
        cells = run_ablation(versions, budget, out, variants=chosen, seed=seed, eval_episodes=eval_episodes,
                             backend=backend_of(workers, ray, ray_address),
                             resume=not fresh,
                             progress=lambda c: typer.echo(f"{c.task} {VARIANTS[c.variant]}: {c.successes}/"
                                                           f"{c.eval_episodes}, {c.train_steps:,} PPO steps"))
        path = write_results(cells, results, results.parent / "images" / f"ablation_{budget}.png", command, budget)
    except (GenDexError, ValueError) as exc:
        _die(exc)
    typer.echo(f"wrote {path}")


@app.command()
def demo(out: Path = typer.Option(Path("out/demo"), "--out", help="Folder for renders."),
         steps: int = typer.Option(50, help="Control steps of the random rollout per task."),
         seed: int = typer.Option(0, help="Seed of resets and random actions."),
         collect_n: int = typer.Option(3, "--collect", min=0,
                                       help="Successful PutAppleBowl episodes to collect into a LeRobot dataset."),
         generate_n: int = typer.Option(1, "--generate", min=0,
                                        help="New tasks to generate with the offline author into OUT/generated_tasks.")
         ) -> None:
    """The main job on embedded defaults: build the newest version of every task, render its views, roll out random
    actions, lay the views out as one contact sheet (OUT/contact_sheet.png) and print a table; then generate a new
    task with the offline author and collect a few successful PutAppleBowl episodes with the stage executor into a
    LeRobot v3.0 dataset."""
    from gendex.demo import format_table, run_demo
    from gendex_envs.registry import registered_tasks

    rows, sheet = run_demo(registered_tasks(), out, steps=steps, seed=seed)
    typer.echo(f"\nGenDex demo: the newest version of {len(rows)} tasks, {steps} random steps each; "
               f"views in {out}/<Task>-v<N>_<view>.png, contact sheet {sheet}")
    for line in format_table(rows):
        typer.echo(line)
    if generate_n:
        _demo_generate(out / "generated_tasks", generate_n, seed)
    if collect_n:
        _demo_collect(out / "PutAppleBowl_dataset", collect_n, seed)
    if not all(r.rewards_finite for r in rows):
        raise typer.Exit(code=1)


def _demo_generate(out: Path, n: int, seed: int) -> None:
    from generator.backends.offline import OfflineBackend
    from generator.pipeline import generate as run_generate

    typer.echo(f"\nGenerating {n} new task(s) with the offline author (a seeded task grammar, not a language model)")
    rows = run_generate(lambda: OfflineBackend(seed=seed), out, n=n, seed=seed,
                        command=f"gendex generate --backend offline --n {n} --seed {seed} --out {out}")
    for s in rows:
        typer.echo(f"  {s.committed.env_id}: violations {s.violations_before} -> {s.violations_after}, "
                   f"{s.seconds:.1f} s; folder {s.committed.root}")


def _demo_collect(out: Path, n: int, seed: int) -> None:
    from gendex.data.collector import CollectConfig, write_card
    from gendex.data.collector import collect as run_collect
    from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
    from gendex_envs.registry import resolve_task

    version = resolve_task("GenDex/PutAppleBowl-v0")
    task_id = version.env_id
    cfg = CollectConfig(task_id=task_id, num_success=n, out=out, formats=("lerobot",), seed=seed,
                        max_attempts=5 * n, **SOLVER_ENV_KWARGS["stages"])
    state = run_collect(cfg, SOLVERS["stages"])
    if state.successes:
        write_card(cfg, version.spec.instruction, "stages", state)
    typer.echo(f"\nCollected {state.successes}/{state.attempts} successful {task_id} episodes "
               f"({state.env_steps_per_success:.0f} env steps per success) into the LeRobot dataset {out / 'lerobot'}")
    if state.successes < n:
        raise typer.Exit(code=1)


def main() -> None:
    app()


if __name__ == "__main__":
    main()
