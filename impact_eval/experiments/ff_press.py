"""``python -m impact_eval.experiments.ff_press``: the controller-attributed press (issue 54)
on given episodes, paired with a table's rows.

For each method and each episode it runs one rollout (as ``experiments.trace`` does: the
episode's seed, its parameter value, the DP's sampling noise from the seed) and writes a row
with the outcome, ``contact_over_20n_s`` and ``peak_contact_sustained_n`` (as in
``episodes.csv``) and the two diagnostic columns of ``safety.FF_PRESS_COLUMNS``: the time
during which the robot-environment normal force exceeds 20 N **and** the force feedforward
pushes more than 2 N toward the environment along that contact's normal, and the mean robot
contact over that time. They are not ``episodes.csv`` columns: they are computed only on the
cells issue 54's acceptance reads, from the env's ``info["ff_into_contact_trace_n"]``.

Episodes come either from a table's rows (``--pairs-from DIR/episodes.csv --pairs-method M
--values-from LO --values-to HI``: each row's value, seed, episode and drawn mass, so the
rows pair with the table's) or from a grid (``--values 9,10 --episodes 10 --seed 101``, the
paired seeds of ``impact-eval`` for those values in that order). Rows are appended to
``--out`` as they finish; a rerun skips the (method, value, episode) rows already there.

    python -m impact_eval.experiments.ff_press --env IMPACT/Hammer-v1 \\
        --methods impact,dp.vanilla+impact@lift_watch \\
        --pairs-from results/hammer_presets/episodes.csv --pairs-method impact \\
        --values-from 7 --values-to 10 --out results/ff_press/hammer.csv --workers 2
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from impact_control.errors import ImpactError, InvalidArgumentError
from impact_control.policy import stack_obs
from impact_eval.grid import episode_seed, parse_grid
from impact_eval.metrics import EpisodeTracker
from impact_eval.safety import FF_PRESS_COLUMNS

COLUMNS: tuple[str, ...] = ("method", "env_id", "param_value", "reset_value", "seed",
                            "episode", "success", "length", "contact_over_20n_s",
                            "peak_contact_sustained_n", *FF_PRESS_COLUMNS)


@dataclass(frozen=True)
class Job:
    """One rollout: method, env, the row's value, the value the env is reset with (a bin's
    drawn mass), seed, episode and ``--controller-set`` overrides."""

    method: str
    env_id: str
    value: float
    reset_value: float
    seed: int
    episode: int
    overrides: tuple[str, ...] = ()


def run_job(job: Job) -> dict[str, object]:
    """One episode of ``job``; its row (``COLUMNS``)."""
    from impact_eval.envs import describe_env, make_env
    from impact_eval.methods import resolve_method

    spec = resolve_method(job.method)
    env = make_env(job.env_id, spec.controller, job.overrides, spec.preset, robot=spec.robot)
    policy = spec.build(job.env_id, env)
    obs, info = env.reset(seed=job.seed, options={describe_env(env).param_name: job.reset_value})
    policy.reset(1)
    if hasattr(policy, "seed_envs"):
        policy.seed_envs([job.seed])
    tracker = EpisodeTracker(policy_dt=float(env.unwrapped.policy_dt))
    tracker.start(info)
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(np.asarray(policy.act(stack_obs([obs]))[0]))
        tracker.update(info)
        done = terminated or truncated
    tracker.finish("terminated" if terminated else "timeout")
    env.close()
    row = tracker.row()
    return {"method": job.method, "env_id": job.env_id, "param_value": job.value,
            "reset_value": job.reset_value, "seed": job.seed, "episode": job.episode,
            "success": row["success"], "length": row["length"],
            "contact_over_20n_s": row["contact_over_20n_s"],
            "peak_contact_sustained_n": row["peak_contact_sustained_n"], **tracker.ff_press()}


def pairs_from(path: Path, method: str, lo: float, hi: float) -> list[tuple[float, float, int, int]]:
    """(value, reset value, seed, episode) of ``method``'s rows of a table with ``lo <=
    value <= hi`` (the reset value is the drawn mass of a bin row, else the value)."""
    try:
        with path.open(newline="") as f:
            rows = [r for r in csv.DictReader(f) if r.get("method") == method]
    except OSError as exc:
        raise InvalidArgumentError(f"cannot read --pairs-from {str(path)!r}: {exc.strerror}") from None
    out = []
    for r in rows:
        value = float(r["param_value"])
        if lo <= value <= hi:
            drawn = float(r.get("drawn_mass_kg") or "nan")
            reset = drawn if r["param_name"].endswith("_bin") and math.isfinite(drawn) else value
            out.append((value, reset, int(r["seed"]), int(r["episode"])))
    if not out:
        raise InvalidArgumentError(f"no rows of method {method!r} with a value in [{lo:g}, "
                                   f"{hi:g}] in {str(path)!r}")
    return out


def grid_pairs(values: Sequence[float], episodes: int, seed: int
               ) -> list[tuple[float, float, int, int]]:
    """impact-eval's paired episodes of a grid (``grid.episode_seed``)."""
    return [(v, v, episode_seed(seed, i, e), e) for i, v in enumerate(values)
            for e in range(episodes)]


def _done(out: Path) -> set[tuple[str, float, int]]:
    if not out.exists():
        return set()
    with out.open(newline="") as f:
        return {(r["method"], float(r["param_value"]), int(r["episode"]))
                for r in csv.DictReader(f)}


def run(jobs: Sequence[Job], out: Path, workers: int) -> None:
    """Run the jobs not yet in ``out``, appending each row as it finishes."""
    done = _done(out)
    todo = [j for j in jobs if (j.method, j.value, j.episode) not in done]
    out.parent.mkdir(parents=True, exist_ok=True)
    new = not out.exists()
    with out.open("a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        if new:
            writer.writeheader()
        if workers == 1:
            results = map(run_job, todo)
        else:
            pool = ProcessPoolExecutor(workers)
            results = pool.map(run_job, todo)
        for row in results:
            writer.writerow(row)
            f.flush()
            print(f"{row['method']} {row['param_value']} ep {row['episode']}: success "
                  f"{row['success']}, >20 N {row['contact_over_20n_s']:.2f} s, ff press "
                  f"{row['ff_press_over_20n_s']:.2f} s", flush=True)


def main(argv: list[str] | None = None) -> None:
    """Entry point."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--env", default="IMPACT/Hammer-v1")
    p.add_argument("--methods", required=True, help="comma list of impact-eval methods")
    p.add_argument("--pairs-from", type=Path, help="a table's episodes.csv")
    p.add_argument("--pairs-method", help="whose rows of --pairs-from give the episodes")
    p.add_argument("--values-from", type=float, default=-math.inf)
    p.add_argument("--values-to", type=float, default=math.inf)
    p.add_argument("--values", help="a grid (instead of --pairs-from)")
    p.add_argument("--episodes", type=int, default=10)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--controller-set", action="append", default=[],
                   metavar="SECTION.FIELD=VALUE")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args(argv)
    try:
        if args.workers < 1 or args.episodes < 1:
            raise InvalidArgumentError("--workers and --episodes must be >= 1")
        if (args.pairs_from is None) == (args.values is None):
            raise InvalidArgumentError("give either --pairs-from (with --pairs-method) or "
                                       "--values (exactly one)")
        if args.pairs_from is not None:
            pairs = pairs_from(args.pairs_from, args.pairs_method or "", args.values_from,
                               args.values_to)
        else:
            pairs = grid_pairs(parse_grid(args.values), args.episodes, args.seed)
        jobs = [Job(m, args.env, v, r, s, e, tuple(args.controller_set))
                for m in args.methods.split(",") for v, r, s, e in pairs]
        run(jobs, args.out, args.workers)
    except ImpactError as exc:
        print(f"{p.prog}: error: {' '.join(str(exc).split())}", file=sys.stderr)
        raise SystemExit(2) from None


if __name__ == "__main__":
    main()
