"""robosuite Lift / Stack with a heavier cube: OSC vs our impedance vs IMPACT.

Run ``python -m impact_robosuite.experiment --out results/robosuite`` (defaults: Lift and
Stack, masses 0.5, 2, 4 kg, 20 episodes per cell, seeds 0..19). Every episode is a fresh
``robosuite.make`` seeded with the episode's seed (cube placement and size), the picked cube's
mass and inertia scaled to the cell's mass after reset, the scripted ``PickLift`` policy
(the same actions for every controller), and success = robosuite's own ``_check_success()``
at the last step. Rows are appended to ``OUT/episodes.csv`` as they finish; ``--resume``
skips the rows already there. Then ``OUT/summary.md`` and ``OUT/success.png``.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError

COLUMNS = ("task", "method", "mass_kg", "seed", "success", "max_lift_m", "final_lift_m", "steps")


@dataclass(frozen=True)
class TaskSpec:
    """A robosuite task as run here: env name, picked body, scripted policy settings."""

    env_name: str
    body: str
    object_key: str
    place_on: str | None
    horizon: int


TASKS = {
    "lift": TaskSpec("Lift", "cube_main", "cube_pos", None, 160),
    "stack": TaskSpec("Stack", "cubeA_main", "cubeA_pos", "cubeB_pos", 300),
}


def make_env(task: TaskSpec, method: str, seed: int, goal_update_mode: str = "achieved") -> object:
    """A seeded robosuite env of ``task`` driven by ``method`` (no rendering);
    ``goal_update_mode`` applies to our controllers (OSC keeps robosuite's "achieved")."""
    import robosuite

    from impact_robosuite import controller_config

    options = {} if method == "osc" else {"goal_update_mode": goal_update_mode}
    config = controller_config(method, **options)
    return robosuite.make(task.env_name, robots="Panda", controller_configs=config,
                          has_renderer=False, has_offscreen_renderer=False, use_camera_obs=False,
                          control_freq=20, horizon=task.horizon, seed=seed)


def set_mass(env: object, body: str, mass_kg: float) -> None:
    """Scale ``body``'s mass and rotational inertia to ``mass_kg``."""
    model = env.sim.model._model
    i = model.body(body).id
    model.body_inertia[i] *= mass_kg / model.body_mass[i]
    model.body_mass[i] = mass_kg
    env.sim.forward()


def run_episode(task: TaskSpec, method: str, mass_kg: float, seed: int,
                goal_update_mode: str = "achieved") -> dict[str, object]:
    """One episode; its CSV row."""
    from impact_robosuite.scripted import PickLift

    env = make_env(task, method, seed, goal_update_mode)
    try:
        obs = env.reset()
        set_mass(env, task.body, mass_kg)
        arm = env.robots[0].composite_controller.part_controllers["right"]
        if hasattr(arm, "sensors"):
            arm.sensors.reseed(seed)
        policy = PickLift(task.object_key, task.place_on)
        policy.reset(obs)
        z0, top, steps = obs[task.object_key][2], 0.0, 0
        while steps < task.horizon:
            obs, _, done, _ = env.step(policy.act(obs))
            steps += 1
            top = max(top, float(obs[task.object_key][2] - z0))
            if done:
                break
        success = bool(env._check_success())
    finally:
        env.close()
    return {"task": task.env_name, "method": method, "mass_kg": mass_kg, "seed": seed,
            "success": int(success), "max_lift_m": round(top, 4),
            "final_lift_m": round(float(obs[task.object_key][2] - z0), 4), "steps": steps}


def cells(tasks: list[str], methods: list[str], masses: list[float],
          seeds: list[int]) -> Iterator[tuple[TaskSpec, str, float, int]]:
    """Every episode, task-major, then mass, seed and method (paired seeds)."""
    for name in tasks:
        for mass in masses:
            for seed in seeds:
                for method in methods:
                    yield TASKS[name], method, mass, seed


def _done(path: Path) -> set[tuple[str, str, float, int]]:
    if not path.exists():
        return set()
    with path.open() as f:
        return {(r["task"], r["method"], float(r["mass_kg"]), int(r["seed"]))
                for r in csv.DictReader(f)}


def run(out: Path, tasks: list[str], methods: list[str], masses: list[float], seeds: list[int],
        resume: bool, goal_update_mode: str = "achieved") -> Path:
    """Run every missing episode, appending rows; returns the CSV path."""
    path = out / "episodes.csv"
    if path.exists() and not resume:
        raise InvalidArgumentError(f"{path} exists; pass --resume to continue it")
    out.mkdir(parents=True, exist_ok=True)
    done = _done(path)
    with path.open("a", newline="") as f:
        writer = csv.DictWriter(f, COLUMNS)
        if not done:
            writer.writeheader()
        for task, method, mass, seed in cells(tasks, methods, masses, seeds):
            if (task.env_name, method, mass, seed) in done:
                continue
            writer.writerow(run_episode(task, method, mass, seed, goal_update_mode))
            f.flush()
            os.fsync(f.fileno())
    return path


def main(argv: list[str] | None = None) -> None:
    """Entry point (``python -m impact_robosuite.experiment``)."""
    from impact_robosuite.registry import METHODS
    from impact_robosuite.report import write_report

    p = OneLineParser(prog="impact_robosuite.experiment", description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--tasks", default="lift,stack", help=f"comma list of {', '.join(TASKS)}")
    p.add_argument("--methods", default=",".join(METHODS),
                   help="comma list of osc, impedance, impact, impact_paper")
    p.add_argument("--masses", default="0.5,2,4", help="comma list of cube masses [kg]")
    p.add_argument("--episodes", type=int, default=20, help="episodes per cell (seeds 0..N-1)")
    p.add_argument("--seed-offset", type=int, default=0, help="first seed")
    p.add_argument("--goal-update-mode", default="achieved",
                   help="our controllers' delta reference: achieved (robosuite's default) | "
                   "desired (OSC stays at achieved)")
    p.add_argument("--resume", action="store_true")
    a = p.parse_args(argv)
    try:
        tasks, methods = a.tasks.split(","), a.methods.split(",")
        for name in tasks:
            if name not in TASKS:
                raise InvalidArgumentError(f"unknown task {name!r}; valid: {', '.join(TASKS)}")
        for name in methods:
            if name not in METHODS:
                raise InvalidArgumentError(f"unknown method {name!r}; valid: {', '.join(METHODS)}")
        try:
            masses = [float(m) for m in a.masses.split(",")]
        except ValueError:
            raise InvalidArgumentError(f"--masses must be numbers, got {a.masses!r}") from None
        if a.episodes < 1 or min(masses) <= 0:
            raise InvalidArgumentError("--episodes must be >= 1 and masses > 0")
        seeds = list(range(a.seed_offset, a.seed_offset + a.episodes))
        if a.goal_update_mode not in ("achieved", "desired"):
            raise InvalidArgumentError(f"invalid --goal-update-mode {a.goal_update_mode!r}; "
                                       "valid: achieved, desired")
        path = run(a.out, tasks, methods, masses, seeds, a.resume, a.goal_update_mode)
    except ImpactError as exc:
        p.exit(2, f"impact_robosuite.experiment: error: {exc}\n")
    print(f"episodes: {path}; report: {', '.join(str(x) for x in write_report(a.out))}")


if __name__ == "__main__":
    main()
