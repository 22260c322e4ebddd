"""``python -m impact_experiments.failed_contact``: how long and how hard each method's
episodes press, from a table's ``episodes.csv`` (the results pages' safety numbers).

    python -m impact_experiments.failed_contact results/hammer_presets_v2 [results/hammer_presets]

Per method: its failed episodes' count, the 90th percentile of their time above 20 N
(``contact_over_20n_s``) and of their sustained contact peak (``peak_contact_sustained_n``,
≥ 50 ms), and over **all** its episodes how many spent more than ``--long-s`` (1 s) above
20 N. The percentile describes a method's failures, so it moves with where they lie (a method
that fails only at the heaviest masses has heavy failures); the count per episode does not,
and two tables' counts are compared with a two-sided Fisher test when a second table is given
(the same method on each side). Bad input (a folder without ``episodes.csv``, a table without
the contact columns) is one line, exit 2.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from impact_eval.metrics import fisher_two_sided

COLUMNS = ("method", "success", "contact_over_20n_s", "peak_contact_sustained_n")
"""The ``episodes.csv`` columns read."""


def contact_summary(episodes: pd.DataFrame, long_s: float = 1.0) -> pd.DataFrame:
    """Per method (rows, sorted): ``failed``, ``over_20n_p90_s`` and ``sustained_p90_n`` over
    its failed episodes (NaN without one), ``long`` (episodes above 20 N for more than
    ``long_s``, of all) and ``episodes``."""
    rows = {}
    for method, frame in episodes.groupby("method"):
        failed = frame[frame["success"] == 0]
        rows[method] = {"failed": len(failed),
                        "over_20n_p90_s": failed["contact_over_20n_s"].quantile(0.9),
                        "sustained_p90_n": failed["peak_contact_sustained_n"].quantile(0.9),
                        "long": int((frame["contact_over_20n_s"] > long_s).sum()),
                        "episodes": len(frame)}
    return pd.DataFrame.from_dict(rows, orient="index").sort_index()


def markdown(new: pd.DataFrame, old: pd.DataFrame | None, long_s: float) -> str:
    """The summary as a markdown table; with ``old``, its long count and the Fisher p."""
    head = ["method", "failed", "failed: time > 20 N, p90 [s]", "failed: sustained peak, p90 [N]",
            f"episodes > {long_s:g} s above 20 N"]
    if old is not None:
        head += ["the other table", "Fisher p"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for method, r in new.iterrows():
        k, n = int(r["long"]), int(r["episodes"])
        cells = [f"`{method}`", str(int(r["failed"])), _number(r["over_20n_p90_s"], 2),
                 _number(r["sustained_p90_n"], 1), f"{k}/{n}"]
        if old is not None:
            if method in old.index:
                k_old, n_old = int(old.loc[method, "long"]), int(old.loc[method, "episodes"])
                cells += [f"{k_old}/{n_old}", f"{fisher_two_sided(k, n, k_old, n_old):.3g}"]
            else:
                cells += ["–", "–"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _number(value: float, digits: int) -> str:
    """A percentile to ``digits`` decimals; – where it is undefined (no failed episode)."""
    return "–" if pd.isna(value) else f"{value:.{digits}f}"


def _read(parser: argparse.ArgumentParser, folder: Path) -> pd.DataFrame:
    csv = folder / "episodes.csv"
    if not csv.is_file():
        parser.error(f"no {csv}; valid: a sweep's output folder")
    frame = pd.read_csv(csv)
    missing = [c for c in COLUMNS if c not in frame]
    if missing:
        parser.error(f"{csv} lacks {', '.join(missing)}; valid: a table with the contact "
                     f"columns ({', '.join(COLUMNS)})")
    return frame


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("table", type=Path, help="a sweep's folder (its episodes.csv)")
    parser.add_argument("other", type=Path, nargs="?", help="a second table to compare with")
    parser.add_argument("--long-s", type=float, default=1.0,
                        help="count episodes above 20 N for longer than this [s]")
    args = parser.parse_args(argv)
    if not args.long_s > 0:
        parser.error(f"invalid --long-s {args.long_s}; valid: > 0")
    new = contact_summary(_read(parser, args.table), args.long_s)
    old = contact_summary(_read(parser, args.other), args.long_s) if args.other else None
    print(markdown(new, old, args.long_s), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
