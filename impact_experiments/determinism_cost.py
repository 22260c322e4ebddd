"""Speed cost of batch-invariant diffusion-policy inference, measured on a real sweep.

Run ``python -m impact_experiments.determinism_cost --repeats 2 --out /tmp/det_cost``.

The sweep (default: the reproducibility acceptance sweep, Hammer, ``vanilla_dp, augmented_dp,
impact, impact_warm`` at 0.2, 5 and 10 kg, 5 episodes per cell) runs in this process on one
core, once with every env denoised alone (``DiffusionPolicy.batch_invariant = True``, what
impact-eval does) and once with one batched DDIM call per replanning step (the earlier
method), in the order invariant, batched, then batched, invariant in the next repeat, so that a
drift of the machine's speed cancels out. Each mode's rows must be identical across repeats
(checked). The wall times of the task loop (env stepping, controller, policy; process start
excluded), their ratios invariant / batched and the mean ratio are printed and written to
``OUT/determinism_cost.json``.
"""

from __future__ import annotations

import json
import statistics
import tempfile
import time
from pathlib import Path

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError
from impact_envs.parallel import single_threaded_torch
from impact_eval.grid import parse_grid
from impact_eval.spec import RunOptions, SweepSpec
from impact_eval.sweep import SweepConfig, Worker, plan_tasks

MODES = ("invariant", "batched")


def sweep_config(env_id: str, methods: tuple[str, ...], values: tuple[float, ...],
                 episodes: int, envs_per_worker: int) -> SweepConfig:
    """The in-process sweep to time (seed 0, one worker)."""
    import gymnasium as gym

    from impact_eval.envs import describe_env, import_env_module

    import_env_module(env_id)
    env = gym.make(env_id)
    try:
        info = describe_env(env)
    finally:
        env.close()
    spec = SweepSpec(env_id=env_id, methods=methods, values=values, episodes=episodes, seed=0)
    options = RunOptions(out=Path(tempfile.gettempdir()), envs_per_worker=envs_per_worker)
    return SweepConfig(spec, options, canonical_env_id=info.env_id, param_name=info.param_name,
                       policy_dt=info.policy_dt)


def run_mode(cfg: SweepConfig, batch_invariant: bool) -> tuple[float, list[dict[str, object]]]:
    """Wall time [s] of every task of ``cfg`` in one fresh worker, and the rows."""
    worker = Worker(cfg)
    rows: list[dict[str, object]] = []
    tasks = plan_tasks(cfg, set())
    for method in cfg.spec.methods:  # build policies (and envs) before the clock starts
        policy = worker._policy(method)
        if hasattr(policy, "batch_invariant"):
            policy.batch_invariant = batch_invariant  # type: ignore[attr-defined]
    t0 = time.perf_counter()
    try:
        for task in tasks:
            worker.run(task, rows.append)
    finally:
        worker.close()
    wall = time.perf_counter() - t0
    key = ("method", "param_value", "episode")
    return wall, sorted(rows, key=lambda r: tuple(str(r[k]) for k in key))


def measure(cfg: SweepConfig, repeats: int) -> dict[str, object]:
    """Alternate the two modes ``repeats`` times; walls, ratios and row identity."""
    walls: dict[str, list[float]] = {m: [] for m in MODES}
    rows: dict[str, list[str]] = {m: [] for m in MODES}
    for i in range(repeats):
        for mode in MODES if i % 2 == 0 else MODES[::-1]:
            wall, result = run_mode(cfg, mode == "invariant")
            walls[mode].append(wall)
            rows[mode].append(json.dumps(result, sort_keys=True, default=str))
            print(f"repeat {i} {mode}: {wall:.1f} s", flush=True)
    ratios = [a / b for a, b in zip(walls["invariant"], walls["batched"], strict=True)]
    return {"methods": list(cfg.spec.methods), "values": list(cfg.spec.values),
            "episodes": cfg.spec.episodes, "envs_per_worker": cfg.options.envs_per_worker,
            "walls_s": walls, "ratios_invariant_over_batched": ratios,
            "mean_ratio": statistics.fmean(ratios),
            "rows_identical_across_repeats": {m: len(set(rows[m])) == 1 for m in MODES}}


def main(argv: list[str] | None = None) -> int:
    """CLI entry point."""
    parser = OneLineParser(prog="determinism_cost", description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="IMPACT/Hammer-v1")
    parser.add_argument("--method", default="vanilla_dp,augmented_dp,impact,impact_warm")
    parser.add_argument("--masses", default="0.2,5,10")
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--envs-per-worker", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    if args.repeats < 1 or args.episodes < 1 or args.envs_per_worker < 1:
        parser.error("--repeats, --episodes and --envs-per-worker must be >= 1")
    try:
        single_threaded_torch()
        cfg = sweep_config(args.env, tuple(args.method.split(",")), tuple(parse_grid(args.masses)),
                           args.episodes, args.envs_per_worker)
        result = measure(cfg, args.repeats)
    except ImpactError as exc:
        parser.exit(2, f"determinism_cost: error: {exc}\n")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "determinism_cost.json").write_text(json.dumps(result, indent=2) + "\n")
    ratios = ", ".join(f"{r:.3f}" for r in result["ratios_invariant_over_batched"])
    print(f"invariant / batched wall: {ratios} (mean {result['mean_ratio']:.3f}); "
          f"rows identical across repeats: {result['rows_identical_across_repeats']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
