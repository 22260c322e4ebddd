"""Wall time of the same sweep through ``--executor local`` and ``--executor ray``, in one run.

Run ``python -m impact_experiments.executor_cost --repeats 2 --out /tmp/executor_cost``.
Each repeat runs the README's main job (``impact-eval --quick``, or the sweep given after
``--``) once per executor as a fresh process, in the order local, ray, then ray, local in the
next repeat (so a drift of the machine's speed cancels out). The wall time covers the whole
command as a user types it: Python start, pre-flight, a new local Ray instance, the sweep,
the report. Every run's ``episodes.csv`` must be byte-identical (checked); the ratio
ray / local of each pair and their mean are printed and written to ``OUT/executor_cost.json``.

``--estimate EPISODES_CSV --cpus N`` instead predicts a sweep's wall time on N CPUs from a
finished sweep's episode lengths: its tasks are rebuilt as the sweep builds them (cells cut
into ``--envs-per-worker`` blocks), each costs its episodes' steps times a measured cost per
env step and controller (``--step-ms``), and they are handed out in plan order to the CPU that
is free first, as Ray does. Startup (Ray, workers, kernels) is not included.
"""

from __future__ import annotations

import argparse
import heapq
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError


def run_once(out: Path, executor: str, sweep: list[str]) -> float:
    """Wall time [s] of one ``impact-eval`` process writing to ``out``."""
    cmd = [sys.executable, "-m", "impact_eval", *sweep, "--out", str(out), "--executor", executor]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        tail = " ".join(proc.stderr.split())[-300:]
        raise ImpactError(f"{' '.join(cmd)} exited {proc.returncode}: {tail}")
    return wall


def measure(out: Path, repeats: int, sweep: list[str]) -> dict[str, object]:
    """Run the pairs; returns the walls, the ratios and whether the CSVs are identical."""
    walls: dict[str, list[float]] = {"local": [], "ray": []}
    csvs = set()
    for i in range(repeats):
        order = ("local", "ray") if i % 2 == 0 else ("ray", "local")
        for executor in order:
            run_dir = out / f"{executor}_{i}"
            walls[executor].append(run_once(run_dir, executor, sweep))
            csvs.add((run_dir / "episodes.csv").read_bytes())
            print(f"repeat {i} {executor}: {walls[executor][-1]:.1f} s", flush=True)
    ratios = [r / loc for r, loc in zip(walls["ray"], walls["local"], strict=True)]
    return {"sweep": sweep, "walls_s": walls, "ratios_ray_over_local": ratios,
            "mean_ratio": statistics.fmean(ratios), "csv_identical": len(csvs) == 1}


def task_costs(episodes_csv: Path, envs_per_worker: int, step_s: dict[str, float],
               methods: tuple[str, ...] = ()) -> list[float]:
    """Cost [s] of each task of the sweep that wrote ``episodes_csv``, in plan order
    (value-major, then episode block, then method); ``methods`` restricts it."""
    from impact_eval.csvio import read_rows
    from impact_eval.methods import resolve_method

    cost: dict[tuple[float, int, str], float] = {}
    for row in read_rows(episodes_csv, older=True):
        if methods and row["method"] not in methods:
            continue
        controller = resolve_method(row["method"]).controller
        key = (float(row["param_value"]), int(row["episode"]) // envs_per_worker, row["method"])
        cost[key] = cost.get(key, 0.0) + int(row["length"]) * step_s[controller]
    return [cost[k] for k in sorted(cost)]


def schedule_wall(costs: list[float], cpus: int) -> float:
    """Finish time of ``costs`` handed out in order, each to the CPU that is free first."""
    free = [0.0] * cpus
    for c in costs:
        heapq.heappush(free, heapq.heappop(free) + c)
    return max(free)


def estimate(args: argparse.Namespace) -> dict[str, object]:
    """The ``--estimate`` mode's numbers (bad input: ``InvalidArgumentError``)."""
    step_s = {}
    for item in args.step_ms.split(","):
        name, _, ms = item.partition("=")
        try:
            step_s[name.strip()] = float(ms) / 1e3
        except ValueError:
            raise InvalidArgumentError(
                f"--step-ms must be CONTROLLER=MS,..., got {args.step_ms!r}") from None
    if args.cpus < 1 or args.envs_per_worker < 1:
        raise InvalidArgumentError("--cpus and --envs-per-worker must be >= 1")
    if not args.estimate.is_file():
        raise InvalidArgumentError(f"--estimate {args.estimate} is not a file")
    methods = tuple(m for m in (args.methods or "").split(",") if m)
    try:
        costs = task_costs(args.estimate, args.envs_per_worker, step_s, methods)
    except KeyError as exc:
        raise InvalidArgumentError(f"no --step-ms for controller {exc}") from None
    if not costs:
        raise InvalidArgumentError(f"no episodes of {methods or 'any method'} in {args.estimate}")
    return {"tasks": len(costs), "cpu_s": sum(costs), "longest_task_s": max(costs),
            "cpus": args.cpus, "wall_s": schedule_wall(costs, args.cpus)}


def main(argv: list[str] | None = None) -> None:
    """Entry point (``python -m impact_experiments.executor_cost``)."""
    parser = OneLineParser(prog="executor_cost", description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2, help="pairs of runs (default 2)")
    parser.add_argument("--out", type=Path, help="directory for the runs")
    parser.add_argument("--estimate", type=Path, metavar="EPISODES_CSV",
                        help="predict that sweep's wall time on --cpus CPUs instead")
    parser.add_argument("--cpus", type=int, default=160, help="--estimate: CPUs (default 160)")
    parser.add_argument("--envs-per-worker", type=int, default=20, help="--estimate: batch size")
    parser.add_argument("--step-ms", default="impact=3.44,impedance=2.38",
                        help="--estimate: cost of one env step per controller [ms], measured")
    parser.add_argument("--methods", help="--estimate: only these methods (comma list)")
    parser.add_argument("sweep", nargs="*", help="impact-eval arguments after -- "
                        "(default: --quick); --out and --executor are added")
    args = parser.parse_args(argv)
    try:
        if args.estimate is not None:
            print(json.dumps(estimate(args), indent=2))
            return
        if args.out is None:
            raise InvalidArgumentError("give --out (or --estimate)")
        if args.repeats < 1:
            raise InvalidArgumentError(f"--repeats must be >= 1, got {args.repeats}")
        if args.out.exists():
            raise InvalidArgumentError(f"--out {args.out} exists; choose a new directory")
        result = measure(args.out, args.repeats, args.sweep or ["--quick"])
    except ImpactError as exc:
        parser.exit(2, f"executor_cost: error: {exc}\n")
    (args.out / "executor_cost.json").write_text(json.dumps(result, indent=2) + "\n")
    print(f"ray / local wall: {' '.join(f'{r:.3f}' for r in result['ratios_ray_over_local'])} "
          f"(mean {result['mean_ratio']:.3f}); episodes.csv identical: {result['csv_identical']}")


if __name__ == "__main__":
    main()
