"""``impact-eval``'s sweep command: its parser, its defaults and its run (``impact-eval
--env ... --method ...``); ``reproduce`` reruns a recorded table through it."""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from impact_control.errors import ImpactError, InvalidArgumentError
from impact_envs.cli import add_robot_set

PROG = "impact-eval"

QUICK_DEFAULTS = {
    "env": "IMPACT/Hammer-v1",
    "grid": "0.2,2.5,5,7.5,10",
    "episodes": 4,
    "out": Path("results/quickstart"),
}
"""The embedded defaults of ``--quick`` (the README's main job); methods: see quick_methods."""


def _method_choices() -> list[str]:
    """Every registered method (the registry, imported only when a parser is built)."""
    from impact_eval.methods import method_choices

    return method_choices()


def quick_methods(env_id: str) -> str:
    """The learned methods when their checkpoints ship with the package, else scripted ones;
    IMPACT with both controller presets (``default`` and the paper-literal ``paper``)."""
    from impact_eval.methods import checkpoint_dir

    try:
        for variant in ("vanilla", "augmented"):
            checkpoint_dir(env_id, variant)
    except ImpactError:
        return "scripted,scripted_impact,scripted_impact_paper"
    return "vanilla_dp,augmented_dp,impact,impact_paper"


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one-line ``InvalidArgumentError``s (exit code 2)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise InvalidArgumentError(f"{message} (see {self.prog} --help)")


def sweep_parser() -> argparse.ArgumentParser:
    """Parser of the sweep command."""
    p = _Parser(
        prog=PROG,
        description="Sweep methods over an env parameter (e.g. object mass); "
        "writes episodes.csv, summary.csv, run.json and plots/. "
        f"'{PROG} report DIR' redraws a finished sweep from its CSV; "
        f"'{PROG} reproduce --check TABLE' reruns a reference table of results/ and compares "
        "it with the committed rows (bytes on the recording CPU, outcomes on another).",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="the main job on embedded defaults: Hammer, masses 0.2,2.5,5,7.5,10 kg, "
        "4 episodes, the shipped DP checkpoints (scripted methods if none ship), "
        "out results/quickstart; explicit options override",
    )
    p.add_argument("--env", help="env id, e.g. IMPACT/Hammer-v1")
    p.add_argument(
        "--method",
        help="comma list of: " + ", ".join(_method_choices()),
    )
    grid = p.add_mutually_exclusive_group()
    grid.add_argument(
        "--masses",
        dest="grid",
        metavar="GRID",
        help="values of the env's parameter (alias of --param-values): "
        "start:stop:step (stop included when on the grid) or a comma list",
    )
    grid.add_argument("--param-values", dest="grid", metavar="GRID", help="same as --masses")
    grid.add_argument(
        "--mass-bins",
        metavar="BINS",
        help="bins [LO, HI) in kg of the env's mass instead of fixed values, e.g. "
        "0.1-0.3,0.3-0.5,0.5-1: each episode draws its mass uniformly in its bin from its "
        "seed (episodes.csv: drawn_mass_kg; param_value is the bin's LO). The mass is "
        "object_mass (Calligraphy: tool_mass; Disturbance, whose first parameter is a push: "
        "give --param object_mass); any other parameter is refused: sweep it as a grid",
    )
    _add_spec_options(p)
    _add_output_options(p)
    _add_executor_options(p)
    return p


def _add_spec_options(p: argparse.ArgumentParser) -> None:
    """What defines the rows beyond env, methods and grid: parameter, episodes, seed and the
    controller and robot changes (``SweepSpec``)."""
    p.add_argument(
        "--param",
        default=None,
        help="parameter to sweep: any the env declares (default: its first, e.g. object_mass)",
    )
    p.add_argument("--episodes", type=int, default=None,
                   help="episodes per (method, value) (default 20)")
    p.add_argument("--seed", type=int, default=0, help="base seed of the paired episode seeds")
    p.add_argument(
        "--controller-set",
        action="append",
        default=[],
        metavar="SECTION.FIELD=VALUE",
        help="change one field of the controller config on top of each method's preset "
        "(its @PRESET, docs/eval.md 'Methods'; repeatable; ablations), e.g. "
        "internal_model.slow_rate_max=1.5; recorded in run.json",
    )
    add_robot_set(p, "run.json, checked on --resume; for every method")
    p.add_argument(
        "--beyond-hardware-limits",
        action="store_true",
        help="allow --controller-set limits above the FR3's (87/12 Nm, 1000 Nm/s); recorded "
        "in run.json",
    )


def _add_output_options(p: argparse.ArgumentParser) -> None:
    """Where and how the rows are written, none of which changes a row (``RunOptions``)."""
    p.add_argument("--out", type=Path, help="output directory")
    p.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="worker processes (default: CPU count; 1 runs in-process); --executor local only",
    )
    p.add_argument(
        "--envs-per-worker",
        type=int,
        default=20,
        help="envs each worker steps in lockstep with one batched policy call (default 20)",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue OUT with the same methods, grid and episodes: skip (method, value, "
        "episode) rows already written",
    )
    p.add_argument(
        "--allow-code-change",
        action="store_true",
        help="with --resume/--extend: continue even if another commit or other uncommitted "
        "changes wrote the earlier rows (recorded in run.json)",
    )
    p.add_argument(
        "--extend",
        action="store_true",
        help="continue OUT adding methods or grid values (every earlier one kept, same "
        "--episodes): each new cell gets the same episode count",
    )
    p.add_argument(
        "--video",
        type=int,
        default=0,
        metavar="K",
        help="write the first K episodes of every cell as MP4 to OUT/videos (imageio-ffmpeg; "
        "rendering is checked before anything is written; no display: MUJOCO_GL=egl is "
        "picked when unset)",
    )
    p.add_argument(
        "--trust-sb3",
        action="store_true",
        help="allow sb3:<zip> methods: SB3 zips are loaded with cloudpickle and CAN EXECUTE "
        "ARBITRARY CODE from the file; pass only for files you trust (same as "
        "IMPACT_TRUST_SB3=1)",
    )


def _add_executor_options(p: argparse.ArgumentParser) -> None:
    """Where the sweep's tasks run: this machine's processes or a Ray cluster."""
    p.add_argument(
        "--executor",
        default="local",
        help="local (worker processes on this machine) | ray (Ray tasks on a cluster, local "
        "or remote: docs/scale.md; needs pip install -e '.[ray]')",
    )
    p.add_argument("--ray-address", default=None, metavar="ADDR",
                   help="Ray cluster to join, e.g. 10.0.0.1:6379 (default: $RAY_ADDRESS, else "
                   "a new local Ray instance)")


def print_outputs(out: Path, summary: Path, plots: list[Path]) -> None:
    """Tell where the results went."""
    print(f"  episodes: {out / 'episodes.csv'}")
    print(f"  summary:  {summary}")
    pngs = ", ".join(p.name for p in plots if p.suffix == ".png")
    print(f"  plots:    {plots[0].parent}/ ({pngs}; PDFs beside them)" if plots else "")


def _with_defaults(a: argparse.Namespace) -> argparse.Namespace:
    """Fill ``--quick`` defaults, or insist on the options a sweep needs."""
    if a.quick:
        for key, value in QUICK_DEFAULTS.items():
            if getattr(a, key) is None and not (key == "grid" and a.mass_bins is not None):
                setattr(a, key, value)
        if a.method is None:
            a.method = quick_methods(a.env)
    missing = [f"--{k}" for k in ("env", "method", "out") if getattr(a, k) is None]
    if a.grid is None and a.mass_bins is None:
        missing.append("--masses/--param-values/--mass-bins")
    if missing:
        raise InvalidArgumentError(
            f"missing {', '.join(missing)}; give them or use --quick (see {PROG} --help)"
        )
    if a.episodes is None:
        a.episodes = 20
    return a


def run_sweep_command(argv: Sequence[str]) -> int:
    """The sweep: validate, then run, then write the summary and plots."""
    a = _with_defaults(sweep_parser().parse_args(argv))
    if not a.trust_sb3:
        return _run_sweep(a, argv)
    from impact_eval.sb3 import TRUST_SB3_ENV_VAR

    before = os.environ.get(TRUST_SB3_ENV_VAR)
    os.environ[TRUST_SB3_ENV_VAR] = "1"  # the workers inherit it
    try:
        return _run_sweep(a, argv)
    finally:
        if before is None:
            del os.environ[TRUST_SB3_ENV_VAR]
        else:
            os.environ[TRUST_SB3_ENV_VAR] = before


def _run_sweep(a: argparse.Namespace, argv: Sequence[str]) -> int:
    """Run a parsed sweep command."""
    from impact_eval.execute import execute
    from impact_eval.prepare import prepare
    from impact_eval.spec import RunOptions, SweepSpec

    spec = SweepSpec.from_cli(a)
    options = RunOptions(out=a.out, workers=a.workers, envs_per_worker=a.envs_per_worker,
                         resume=a.resume, extend=a.extend, video_episodes=a.video,
                         executor=a.executor, ray_address=a.ray_address,
                         allow_code_change=a.allow_code_change)
    plan = prepare(spec, options)
    t0 = time.perf_counter()
    result = execute(plan, command=[PROG, *argv], args=vars(a))
    wall = time.perf_counter() - t0
    print(
        f"{PROG}: {result.episodes_run} episodes run ({len(plan.done)} already done, "
        f"{result.rows} in total) in {wall:.1f} s wall"
    )
    print_outputs(plan.out, result.summary, result.plots)
    crashed = crashed_cells(plan.out)
    if crashed:
        print(f"{PROG}: error: every episode raised in {len(crashed)} cell(s): "
              f"{'; '.join(crashed[:3])}{' ...' if len(crashed) > 3 else ''} "
              "(failure_reason in episodes.csv, n_exception in summary.csv)", file=sys.stderr)
        return 1
    return 0


def crashed_cells(out: Path) -> list[str]:
    """``"method @ value: reason"`` of each (method, value) cell of ``out/episodes.csv`` whose
    every episode ended in an exception (a broken policy or env, not a hard task)."""
    import pandas as pd

    episodes = pd.read_csv(out / "episodes.csv", keep_default_na=False)
    cells = []
    for (method, value), group in episodes.groupby(["method", "param_value"], sort=True):
        reasons = group["failure_reason"].astype(str)
        if len(group) and reasons.str.startswith("exception").all():
            cells.append(f"{method} @ {value:g}: {reasons.iloc[0]}")
    return cells
