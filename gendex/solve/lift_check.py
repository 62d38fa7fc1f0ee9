"""Lift-and-hold: can the solver pick up a given catalog object? (The measure behind ``benchmarks/grasp.py``.)

:func:`lift_spec` is a one-object task: the object at a random pose (anywhere in :data:`REGION_XY_M` around
:data:`CENTER_XY_M`, any yaw), a ``reach`` and a ``grasp`` stage. :func:`lift_and_hold` runs the stage executor on it
(grasp synthesis, physics-trial ranking, the grasp primitive's 15 cm lift and its regrasp after a slip), then holds
for :data:`HOLD_STEPS` control steps. It succeeds when the object ends at least :data:`MIN_RISE_M` above where it
lay, touched by the thumb and at least one finger.

The object is at the size a task holds it: an object wider than the hand across its narrow side (a 22 cm plate, a
large bowl) is scaled down to :data:`~gendex.solve.grasp.HAND_SPAN_M` by :func:`~gendex.solve.grasp.hand_fit_scale`,
exactly as the generator's size step fits every grasped object before a task is written. Pass ``scale`` to measure
another size (``benchmarks/grasp.py --catalog-scale`` measures every object at scale 1).
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from gendex.solve.executor import StageExecutor
from gendex.solve.failure import Failure
from gendex.solve.grasp import hand_fit_scale
from gendex_envs.errors import ExecutionError
from gendex_envs.registry import HISTORY_FREE
from gendex_envs.spec import TaskSpec, parse_task_spec

CENTER_XY_M = (0.10, 0.0)
REGION_XY_M = (0.12, 0.22)
"""Half-ranges of the object's position around :data:`CENTER_XY_M` (in front of the robot, within its reach)."""
MEASURED_FILE = Path(__file__).with_name("grasp_measured.json")
"""The lift-and-hold rates last measured by ``benchmarks/grasp.py --record`` (per asset: held, attempts, seeds)."""
MIN_RISE_M = 0.10
HOLD_STEPS = 20
"""1 s at 20 Hz."""


def lift_spec(asset: str, scale: float = 1.0) -> TaskSpec:
    """The one-object lift task of ``asset`` (see the module docstring)."""
    stage = {"method": "motion_planning", "target": "obj"}
    return parse_task_spec({
        "name": "LiftAndHold", "instruction": f"Pick up the {asset} and hold it.",
        "objects": [{"name": "obj", "asset": asset, "scale": scale, "pos_m": [*CENTER_XY_M, 0.0],
                     "randomize": {"xy_m": list(REGION_XY_M), "yaw_deg": 180.0}}],
        "stages": [{"name": "reach", "instruction": "Bring the open hand to the object.", "skill": "reach",
                    "control_joint": "arm", **stage},
                   {"name": "grasp", "instruction": "Close the hand on the object and lift it.", "skill": "grasp",
                    "control_joint": "hand", **stage}],
        "success": {"description": "The object is held 10 cm above where it lay.",
                    "conditions": [{"type": "lifted", "object": "obj", "min_height_m": MIN_RISE_M}]},
        "max_episode_steps": 400,
    }, source=f"<lift check of {asset}>")


@dataclass(frozen=True)
class LiftResult:
    asset: str
    seed: int
    held: bool
    rise_m: float
    grasp: str
    """The grasp executed last (family and parameters), or '' when none was."""
    trials: int
    """Physics trials the grasp choice ran."""
    steps: int
    """Env steps of the episode (trials excluded)."""
    seconds: float
    failure: Failure | None = None
    forecast: bool = False
    """The last physics trial before the robot's grasp held: the grasp it did held in its trial (how often a forecast
    came true is the benchmark's ``forecast_missed``)."""

    def to_dict(self) -> dict:
        d = asdict(self)
        d["failure"] = self.failure.to_dict() if self.failure else None
        return d


def fitted_scale(asset: str) -> float:
    """The scale a task grasps ``asset`` at: 1, or smaller where the object is wider than the hand (rounded to
    three decimals, as the generator's size step writes it)."""
    from gendex_envs.assets.catalog import catalog

    e = catalog()[asset].entry
    size = np.subtract(e.bbox_max_m, e.bbox_min_m)
    return round(hand_fit_scale((float(size[0]), float(size[1]))), 3)


class LiftChecker:
    """Runs lift-and-hold attempts of one asset, keeping its env and executor between seeds; the asset at
    ``scale`` (default: :func:`fitted_scale`).

    Each attempt runs in a rebuilt scene (:data:`~gendex_envs.registry.HISTORY_FREE`, as collection and evaluation
    run): a PhysX scene keeps contact caches and solver warm starts across resets, so an attempt in a scene that ran
    others first depended on them (by 0.1 mm for a mug; for the wrench on seed 10311, a physics trial of its edge grasp
    held and the robot, doing the same in a scene that had run eight attempts, let it slip), and a benchmark's rows
    on how its seeds were split among workers. In a scene of its own an attempt depends on its seed alone, and the
    executor's physics trials, which run in rebuilt scenes too, forecast what the robot then does
    (:mod:`gendex.solve.edge_trial`)."""

    def __init__(self, asset: str, scale: float | None = None):
        from gendex_envs.task_env import TaskEnv

        self.asset = asset
        self.scale = fitted_scale(asset) if scale is None else scale
        self.env = TaskEnv(task_spec=lift_spec(asset, self.scale), control_mode="pd_joint_pos", control_joint="both",
                           obs_mode="none", reward_mode="none", render_backend="none", **HISTORY_FREE)
        self.executor = StageExecutor()

    def close(self) -> None:
        if hasattr(self.executor, "rigid"):
            self.executor.rigid.close()
        self.env.close()

    def __call__(self, seed: int) -> LiftResult:
        env, ex = self.env, self.executor
        t0 = time.perf_counter()
        env.reset(seed=seed)
        ex.reset(env, None)
        steps, failure = 0, None
        try:
            while not ex.finished:
                action = ex.act(env, None)
                if action is None:
                    break
                env.step(torch.as_tensor(action[None]))
                steps += 1
            hold = ex.motion.target()
            for _ in range(HOLD_STEPS):
                env.step(torch.as_tensor(ex.motion.emit(hold)[None]))
                steps += 1
        except ExecutionError as exc:
            failure = Failure.of_error(exc)
        rise = float(env.obj_height("obj")[0])
        forces = env.hand_forces("obj")[0].cpu().numpy()
        touched = bool(forces[0] > 0.3 and np.any(forces[1:5] > 0.3))
        held = failure is None and rise >= MIN_RISE_M and touched
        if failure is None and not held:
            failure = Failure("slipped", "grasp", "grasp", f"rose {rise:.3f} m, thumb/finger contact {touched} after "
                                                           f"the {HOLD_STEPS}-step hold")
        plan = ex.grasp_plan
        log = ex.rigid.trial_log
        return LiftResult(self.asset, seed, held, rise, str(plan) if plan else "", len(log), steps,
                          time.perf_counter() - t0, failure, bool(log) and log[-1].held)


def measured_rates(path: Path = MEASURED_FILE) -> dict[str, float]:
    """Asset id -> lift-and-hold success rate of the last recorded ``benchmarks/grasp.py`` run (empty if none)."""
    if not path.is_file():
        return {}
    rows = json.loads(path.read_text())["assets"]
    return {a: r["held"] / r["attempts"] for a, r in rows.items() if r["attempts"]}


def measured_graspable(min_rate: float = 0.9, path: Path = MEASURED_FILE) -> frozenset[str]:
    """Assets the solver picked up and held in at least ``min_rate`` of the recorded attempts."""
    return frozenset(a for a, rate in measured_rates(path).items() if rate >= min_rate)


def held_summary(min_rate: float = 0.9, path: Path = MEASURED_FILE) -> dict[str, str]:
    """Each graspable-tagged rigid catalog object -> how the record says the solver holds it: ``"19/20"``,
    ``"**not graspable** (12/20)"`` below ``min_rate``, or ``"not measured"`` (what the asset gallery shows)."""
    from gendex_envs.assets.catalog import catalog

    rows = json.loads(path.read_text())["assets"] if path.is_file() else {}
    out = {}
    for asset_id, record in catalog().items():
        if "graspable" not in record.tags or record.articulated:
            continue
        row = rows.get(asset_id)
        if not row:
            out[asset_id] = "not measured"
            continue
        rate = f"{row['held']}/{row['attempts']}"
        out[asset_id] = rate if row["held"] / row["attempts"] >= min_rate else f"**not graspable** ({rate})"
    return out


def write_record(rows: list[dict], seeds: list[int], path: Path = MEASURED_FILE, merge: bool = False) -> None:
    """Record a ``benchmarks/grasp.py`` run (what :func:`measured_graspable` reads). ``merge``: keep the record's other
    assets and replace only those of ``rows`` (a run over some objects), each that was measured on other seeds than
    the record's with its own."""
    old = json.loads(path.read_text()) if merge and path.is_file() else {"seeds": seeds, "assets": {}}
    assets = dict(old["assets"])
    for r in rows:
        assets[r["asset"]] = {"held": r["held"], "attempts": r["attempts"], "scale": r["scale"],
                              **({"seeds": seeds} if seeds != old["seeds"] else {})}
    record = {"what": "lift-and-hold per graspable catalog asset at the scale a task holds it "
                      "(gendex.solve.lift_check), benchmarks/grasp.py",
              "seeds": old["seeds"], "assets": assets}
    path.write_text(json.dumps(record, indent=1, sort_keys=True) + "\n")
