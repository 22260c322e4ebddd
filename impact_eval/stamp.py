"""``python -m impact_eval.stamp CHECKPOINT RESULTS --method NAME``: record a checkpoint's
evaluation in its ``meta.json``.

Reads ``RESULTS/episodes.csv`` and ``RESULTS/run.json`` (written by ``impact-eval``) and stores,
under the key ``"evaluation"`` of ``CHECKPOINT/meta.json``, the env, the method, the results
directory, the sweep's git commit and, per parameter value, successes and episodes. Any earlier
``"evaluation"`` entry for the same results directory and method is replaced; others are kept.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pandas as pd

from impact_control.errors import ImpactError, InvalidArgumentError


def evaluation_entry(results: Path, method: str) -> dict:
    """Successes per parameter value of ``method`` in a sweep's ``episodes.csv``."""
    episodes = pd.read_csv(results / "episodes.csv")
    rows = episodes[episodes["method"] == method]
    if rows.empty:
        methods = ", ".join(sorted(episodes["method"].unique()))
        raise InvalidArgumentError(f"method {method!r} not in {results}; valid: {methods}")
    run = json.loads((results / "run.json").read_text())
    cells = {
        f"{value:g}": [int(group["success"].sum()), int(len(group))]
        for value, group in rows.groupby("param_value")
    }
    return {
        "env_id": str(rows["env_id"].iloc[0]),
        "param_name": str(rows["param_name"].iloc[0]),
        "method": method,
        "results": str(results),
        "git": run.get("git", {}).get("sha"),
        "success_episodes": cells,
    }


def stamp(checkpoint: Path, results: Path, method: str) -> dict:
    """Add (or replace) the evaluation entry of ``results``/``method`` in ``meta.json``."""
    meta_path = checkpoint / "meta.json"
    if not meta_path.is_file():
        raise InvalidArgumentError(f"{meta_path} does not exist")
    meta = json.loads(meta_path.read_text())
    entry = evaluation_entry(results, method)
    kept = [e for e in meta.get("evaluation", [])
            if (e.get("results"), e.get("method")) != (entry["results"], method)]
    meta["evaluation"] = [*kept, entry]
    meta_path.write_text(json.dumps(meta, indent=2) + "\n")
    return entry


def main(argv: list[str] | None = None) -> None:
    """Command line: bad input exits 2 with one line."""
    parser = argparse.ArgumentParser(prog="python -m impact_eval.stamp", description=__doc__)
    parser.add_argument("checkpoint", type=Path, help="checkpoint directory (has meta.json)")
    parser.add_argument("results", type=Path, help="impact-eval output directory")
    parser.add_argument("--method", required=True, help="method whose rows to record")
    args = parser.parse_args(argv)
    try:
        entry = stamp(args.checkpoint, args.results, args.method)
    except (ImpactError, OSError, KeyError, ValueError) as exc:
        parser.exit(2, f"stamp: error: {exc}\n")
    cells = ", ".join(f"{k}: {s}/{n}" for k, (s, n) in entry["success_episodes"].items())
    print(f"{args.checkpoint}/meta.json: {args.method} on {entry['env_id']} ({cells})")


if __name__ == "__main__":
    main()
