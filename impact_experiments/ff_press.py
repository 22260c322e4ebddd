"""``python -m impact_experiments.ff_press``: the controller-attributed press (issue 54)
on given episodes, paired with a table's rows.

For each method it runs each cell's episodes in lockstep, as one ``impact-eval`` worker task
does (``rollout.LockstepBatch``: the same seeds, batch and DP noise, so on the same CPU the
rows equal ``impact-eval``'s) and writes a row per episode
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
``--out`` cell by cell; a rerun skips the (method, value, episode) rows already there.

    python -m impact_experiments.ff_press --env IMPACT/Hammer-v1 \\
        --methods impact,dp.vanilla+impact@lift_watch \\
        --pairs-from results/hammer_presets/episodes.csv --pairs-method impact \\
        --values-from 7 --values-to 10 --out results/ff_press/hammer.csv --workers 2
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError
from impact_eval.grid import episode_seed, parse_grid
from impact_eval.safety import FF_PRESS_COLUMNS, NET_CONTACT_COLUMNS

COLUMNS: tuple[str, ...] = ("method", "env_id", "param_value", "reset_value", "seed",
                            "episode", "success", "length", "contact_over_20n_s",
                            "peak_contact_sustained_n", *FF_PRESS_COLUMNS,
                            *NET_CONTACT_COLUMNS)


Episode = tuple[float, float, int, int]
"""(value, reset value, seed, episode index)."""


@dataclass(frozen=True)
class Cell:
    """One cell's episodes, run in lockstep as one ``impact-eval`` worker task runs them (one
    batch, so the batched policy's numerics match the table's rows on the same CPU): method,
    env, ``--controller-set`` overrides, and per episode (value, reset value, seed, index)."""

    method: str
    env_id: str
    overrides: tuple[str, ...]
    episodes: tuple[Episode, ...]


def run_cell(cell: Cell) -> list[dict[str, object]]:
    """The rows (``COLUMNS``) of ``cell``'s episodes."""
    from impact_eval.envs import describe_env, method_env
    from impact_eval.methods import resolve_method
    from impact_eval.rollout import EpisodeJob, LockstepBatch

    spec = resolve_method(cell.method)
    envs = [method_env(cell.env_id, spec, cell.overrides) for _ in cell.episodes]
    for env in envs:  # the loop records the feedforward's push only when asked
        env.unwrapped.loop.record_press_diagnostics = True
    described = describe_env(envs[0])
    batch = LockstepBatch(envs, spec.build(cell.env_id, envs[0]), described.param_name,
                          described.policy_dt)
    batch.with_press_diagnostics = True
    jobs = [EpisodeJob(value, seed, episode, reset) for value, reset, seed, episode
            in cell.episodes]
    rows: list[dict[str, object]] = []

    def on_finish(i: int, columns: dict[str, object]) -> None:
        job = jobs[i]
        rows.append({"method": cell.method, "env_id": cell.env_id, "param_value": job.value,
                     "reset_value": job.reset_value, "seed": job.seed,
                     "episode": job.episode, **{c: columns[c] for c in COLUMNS[6:]}})

    batch.run(jobs, on_finish)
    for env in envs:
        env.close()
    return sorted(rows, key=lambda r: r["episode"])  # type: ignore[arg-type, return-value]


def pairs_from(path: Path, method: str, lo: float, hi: float) -> list[Episode]:
    """(value, reset value, seed, episode) of ``method``'s rows of a table with ``lo <=
    value <= hi`` (the reset value is the drawn mass of a bin row, else the value)."""
    try:
        with path.open(newline="") as f:
            rows = [r for r in csv.DictReader(f) if r.get("method") == method]
    except OSError as exc:
        raise InvalidArgumentError(
            f"cannot read --pairs-from {str(path)!r}: {exc.strerror}") from None
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


def grid_pairs(values: Sequence[float], episodes: int, seed: int) -> list[Episode]:
    """impact-eval's paired episodes of a grid (``grid.episode_seed``)."""
    return [(v, v, episode_seed(seed, i, e), e) for i, v in enumerate(values)
            for e in range(episodes)]


def _done(out: Path) -> set[tuple[str, float, int]]:
    if not out.exists():
        return set()
    with out.open(newline="") as f:
        return {(r["method"], float(r["param_value"]), int(r["episode"]))
                for r in csv.DictReader(f)}


def run(cells: Sequence[Cell], out: Path, workers: int) -> None:
    """Run the episodes not yet in ``out``, cell by cell, appending each cell's rows as it
    finishes."""
    done = _done(out)
    todo = [Cell(c.method, c.env_id, c.overrides,
                 tuple(e for e in c.episodes if (c.method, e[0], e[3]) not in done))
            for c in cells]
    todo = [c for c in todo if c.episodes]
    out.parent.mkdir(parents=True, exist_ok=True)
    new = not out.exists()
    with out.open("a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        if new:
            writer.writeheader()
        pool = ProcessPoolExecutor(workers) if workers > 1 else None
        results = pool.map(run_cell, todo) if pool is not None else map(run_cell, todo)
        for rows in results:
            writer.writerows(rows)
            f.flush()
            first = rows[0]
            print(f"{first['method']} {first['param_value']}: {len(rows)} episodes, "
                  f"{sum(int(r['success']) for r in rows)} successes, ff press above 0.5 s in "
                  f"{sum(r['ff_press_over_20n_s'] > 0.5 for r in rows)}", flush=True)


def mcnemar_p(b: int, c: int) -> float:
    """Two-sided exact McNemar p-value of ``b`` and ``c`` discordant pairs (binomial, 1/2)."""
    n, k = b + c, min(b, c)
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, i) for i in range(k + 1)) / 2.0**n
    return min(1.0, 2.0 * tail)


def summary(path: Path, baseline: str, candidate: str) -> list[str]:
    """Per value: successes of ``baseline`` and ``candidate`` on the same episodes, the pairs
    only one of them won, the failed episodes' longest time above 20 N and the longest ff
    press; then the pooled counts with the exact McNemar p-value."""
    try:
        with path.open(newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as exc:
        raise InvalidArgumentError(f"cannot read {str(path)!r}: {exc.strerror}") from None
    names = sorted({r.get("method", "") for r in rows})
    if baseline not in names or candidate not in names:
        raise InvalidArgumentError(f"--summary {baseline},{candidate}: {str(path)!r} holds "
                                   f"rows of {', '.join(names) or 'no method'}")
    by = {(r["method"], float(r["param_value"]), int(r["episode"])): r for r in rows}
    lines = [f"value | {baseline} | {candidate} | only {baseline} | only {candidate} | "
             "failed > 20 N, longest [s] (each) | ff press, longest [s] (each)"]
    pooled = [0, 0, 0, 0]
    for value in sorted({k[1] for k in by}):
        pairs = [(by[k], by.get((candidate, value, k[2]))) for k in sorted(by)
                 if k[0] == baseline and k[1] == value]
        pairs = [(a, b) for a, b in pairs if b is not None]
        wins = [(int(a["success"]), int(b["success"])) for a, b in pairs]
        counts = [sum(x for x, _ in wins), sum(y for _, y in wins),
                  sum(x > y for x, y in wins), sum(y > x for x, y in wins)]
        pooled = [p + c for p, c in zip(pooled, counts, strict=True)]

        def longest(column: str, failed: bool, side: int, chosen=pairs) -> str:
            vals = [float(pair[side][column]) for pair in chosen
                    if not failed or pair[side]["success"] == "0"]
            return f"{max(vals):.2f}" if vals else "-"

        lines.append(f"{value:g} | {counts[0]}/{len(pairs)} | {counts[1]}/{len(pairs)} | "
                     f"{counts[2]} | {counts[3]} | {longest('contact_over_20n_s', True, 0)} / "
                     f"{longest('contact_over_20n_s', True, 1)} | "
                     f"{longest('ff_press_over_20n_s', False, 0)} / "
                     f"{longest('ff_press_over_20n_s', False, 1)}")
    lines.append(f"pooled: {pooled[0]} vs {pooled[1]}; only {baseline} {pooled[2]}, only "
                 f"{candidate} {pooled[3]}; exact McNemar p = {mcnemar_p(*pooled[2:]):.3g}")
    return lines


def check_out(out: Path, env_id: str, overrides: Sequence[str]) -> None:
    """``out`` may be written and, if it exists, holds this runner's rows of the same env and
    ``--controller-set`` (kept beside it in ``OUT.json``); else a one-line
    ``InvalidArgumentError``, nothing written."""
    setup = {"env": env_id, "controller_set": list(overrides)}
    record = out.with_suffix(".json")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        if out.exists():
            with out.open(newline="") as f:
                header = next(csv.reader(f), [])
            had = json.loads(record.read_text()) if record.exists() else None
            if tuple(header) != COLUMNS or had != setup:
                raise InvalidArgumentError(
                    f"--out {str(out)!r} holds other rows (columns or {record.name}: "
                    f"{had}); valid: a new file, or this run's own to resume")
        else:
            record.write_text(json.dumps(setup) + "\n")
    except (OSError, json.JSONDecodeError) as exc:
        raise InvalidArgumentError(f"cannot use --out {str(out)!r}: {exc}") from None


def _cells(args: argparse.Namespace) -> list[Cell]:
    """The run's cells from the command line, every input checked first (one line each)."""
    from impact_control.config import ControllerConfig
    from impact_control.overrides import apply_overrides
    from impact_eval.envs import check_env_id
    from impact_eval.methods import resolve_method

    if args.workers < 1 or args.episodes < 1:
        raise InvalidArgumentError("--workers and --episodes must be >= 1")
    methods = [m for m in args.methods.split(",") if m]
    if not methods:
        raise InvalidArgumentError("--methods names no method; valid: a comma list of "
                                   "impact-eval methods")
    for method in methods:
        resolve_method(method)
    check_env_id(args.env)
    apply_overrides(ControllerConfig(), args.controller_set)
    if (args.pairs_from is None) == (args.values is None):
        raise InvalidArgumentError("give either --pairs-from (with --pairs-method) or "
                                   "--values (exactly one)")
    if args.pairs_from is not None:
        pairs = pairs_from(args.pairs_from, args.pairs_method or "", args.values_from,
                           args.values_to)
    else:
        pairs = grid_pairs(parse_grid(args.values), args.episodes, args.seed)
    return [Cell(m, args.env, tuple(args.controller_set),
                 tuple(p for p in pairs if p[0] == v))
            for m in methods for v in sorted({p[0] for p in pairs})]


def main(argv: list[str] | None = None) -> None:
    """Entry point."""
    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("--env", default="IMPACT/Hammer-v1")
    p.add_argument("--methods", default="", help="comma list of impact-eval methods")
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
    p.add_argument("--summary", metavar="BASELINE,CANDIDATE",
                   help="print the paired summary of --out's rows for two methods and exit")
    args = p.parse_args(argv)
    try:
        if args.summary:
            baseline, _, candidate = args.summary.partition(",")
            print("\n".join(summary(args.out, baseline, candidate)))
            return
        cells = _cells(args)
        check_out(args.out, args.env, args.controller_set)
    except ImpactError as exc:
        p.fail(" ".join(str(exc).split()))
    run(cells, args.out, args.workers)


if __name__ == "__main__":
    main()
