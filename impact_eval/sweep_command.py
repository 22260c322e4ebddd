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
from impact_envs.versions import current_id

PROG = "impact-eval"

QUICK_DEFAULTS = {
    "env": current_id("Hammer"),
    "grid": "0.2,2.5,5,7.5,10",
    "episodes": 4,
    "out": Path("results/quickstart"),
}
"""The embedded defaults of ``--quick`` (the README's main job); methods: see quick_methods."""


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
    from impact_eval.spec import RunOptions, SweepSpec

    SweepSpec.add_arguments(p)  # what defines the rows, declared with SweepSpec's fields
    RunOptions.add_arguments(p)  # where and how they are written, with RunOptions'
    p.add_argument(
        "--trust-sb3",
        action="store_true",
        help="allow sb3:<zip> methods: SB3 zips are loaded with cloudpickle and CAN EXECUTE "
        "ARBITRARY CODE from the file; pass only for files you trust (same as "
        "IMPACT_TRUST_SB3=1)",
    )
    return p


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
    plan = prepare(spec, RunOptions.from_cli(a))
    t0 = time.perf_counter()
    result = execute(plan, command=[PROG, *argv])
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
