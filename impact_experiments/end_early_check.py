"""Is ``--end-early`` safe on a table? Its episodes against the same episodes run in full
(issue 56 item 1): every paired episode must end with the same outcome.

    impact-eval --env IMPACT/HammerBasket-v1 \\
        --method vanilla_dp_authors,augmented_dp_authors,dp.vanilla_authors+impact@keep_carried \\
        --mass-bins 0.1-0.3,0.3-0.5,0.5-1,1-2,2-4,4-6,6-8,8-10 --episodes 17 --end-early \\
        --workers 2 --out results/hammer_basket_diag/end_early
    python -m impact_experiments.end_early_check --full results/hammer_basket_authors \\
        --early results/hammer_basket_diag/end_early

Episodes pair on (method, parameter value, episode): the same paired seed (the early table is
run with the full one's ``--seed``; it may hold fewer episodes per cell). Prints, per method,
the pairs, the outcome flips (any flip fails the check: exit 1), how many episodes ended early
and the steps saved, and the largest change of each summed or peaked column, the columns that
cover only the steps run. ``--out FILE.json`` keeps it.

Both tables must have run on the same CPU model (run.json's ``host.cpu_model``): across CPU
families an outcome may flip with the flag off too (docs/results.md, "Reproducibility"), so a
flip there says nothing about the flag. Tables of two CPUs are refused in one line (exit 2)
naming how to rerun the full-length cells here; ``--across-cpus`` pairs them anyway.
``--twins-only`` pairs the early rows that have a twin and leaves out the others (a full
table rerun here for some cells only: ``results/hammer_basket_diag/end_early_full_here``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd

KEYS = ("method", "param_value", "episode")
"""What pairs an early episode with its full-length twin."""
COVERED = ("energy_j", "peak_torque_nm", "peak_contact_force_n", "peak_contact_sustained_n",
           "contact_p95_n", "contact_over_10n_s", "contact_over_20n_s", "mean_pose_error_m")
"""Columns over the steps an episode ran (docs/eval.md, "Ending an episode early")."""


def paired(full: pd.DataFrame, early: pd.DataFrame, twins_only: bool = False) -> pd.DataFrame:
    """The early rows joined to their full-length twins (suffixes ``_full``, ``_early``);
    with ``twins_only``, early rows without a twin are left out instead of refused.

    Raises:
        ValueError: an early row has no twin (without ``twins_only``), or the twins' seeds
            differ.
    """
    both = early.merge(full, on=list(KEYS), how="left", suffixes=("_early", "_full"),
                       validate="one_to_one")
    missing = both["seed_full"].isna()
    if twins_only:
        both, missing = both[~missing], missing[~missing]
    if missing.any():
        raise ValueError(f"{int(missing.sum())} early rows have no full-length twin "
                         f"(first: {both.loc[missing, list(KEYS)].iloc[0].to_dict()})")
    if (both["seed_full"].astype("int64") != both["seed_early"]).any():
        raise ValueError("paired rows have different seeds: not the same episodes")
    return both


def recorded_cpu(table: Path) -> str | None:
    """The CPU model a table's run.json records (``host.cpu_model``); None when unrecorded."""
    try:
        run = json.loads((table / "run.json").read_text())
    except (OSError, ValueError):
        return None
    host = run.get("host") if isinstance(run, dict) else None
    return host.get("cpu_model") if isinstance(host, dict) else None


def check_same_cpu(full: Path, early: Path) -> None:
    """Raise ``ValueError`` (one line) if the two tables record different CPU models."""
    cpus = recorded_cpu(full), recorded_cpu(early)
    if None not in cpus and cpus[0] != cpus[1]:
        raise ValueError(
            f"the tables ran on different CPUs ({cpus[0]}: {full}; {cpus[1]}: {early}), where "
            "outcomes may flip without the flag; rerun the full-length cells on this CPU "
            "(impact-eval reproduce --check TABLE --cells ... --out DIR) and pass --full DIR, "
            "or pass --across-cpus")


def summary(both: pd.DataFrame, full_length: int) -> dict[str, object]:
    """Per method and in total: pairs, outcome flips, early ends and steps saved, and the
    largest absolute change of each covered column."""
    out: dict[str, object] = {}
    for method, rows in [*both.groupby("method"), ("all", both)]:
        flips = rows[rows["success_full"] != rows["success_early"]]
        ended = rows["length_early"] < full_length
        out[str(method)] = {
            "pairs": len(rows),
            "flips": len(flips),
            "flipped": flips[list(KEYS)].to_dict("records"),
            "ended_early": int(ended.sum()),
            "steps_saved_fraction": float(1 - rows["length_early"].sum()
                                          / rows["length_full"].sum()),
            "largest_change": {c: float((rows[f"{c}_early"] - rows[f"{c}_full"]).abs().max())
                               for c in COVERED if f"{c}_full" in rows},
        }
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", type=Path, required=True, help="the full-length table")
    parser.add_argument("--early", type=Path, required=True, help="the --end-early table")
    parser.add_argument("--out", type=Path, help="write the summary as JSON")
    parser.add_argument("--across-cpus", action="store_true",
                        help="pair tables recorded on different CPU models anyway")
    parser.add_argument("--twins-only", action="store_true",
                        help="leave out early rows that have no full-length twin")
    args = parser.parse_args(argv)
    full = pd.read_csv(args.full / "episodes.csv", keep_default_na=False)
    early = pd.read_csv(args.early / "episodes.csv", keep_default_na=False)
    try:
        if not args.across_cpus:
            check_same_cpu(args.full, args.early)
        both = paired(full, early, args.twins_only)
    except ValueError as exc:
        parser.exit(2, f"end_early_check: error: {exc}\n")
    result = summary(both, int(full["length"].max()))
    for method, r in result.items():
        print(f"{method}: {r['pairs']} pairs, {r['flips']} outcome flips, {r['ended_early']} "
              f"ended early, {r['steps_saved_fraction']:.0%} of the steps saved")
    if args.out is not None:
        args.out.write_text(json.dumps(result, indent=1) + "\n")
    return 1 if result["all"]["flips"] else 0


if __name__ == "__main__":
    raise SystemExit(main())
