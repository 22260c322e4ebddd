"""What the full rerun on ``-v1`` changed in each reference table: its rows against the same
table's ``-v0`` rows at an earlier commit, outcome by outcome (issue 41).

    python -m impact_eval.experiments.version_flips --before REV [--out results/rerun_v1.md]
    python -m impact_eval.experiments.version_flips --before REV --cells   # cells that moved

For every manifest table whose entry names the current env version, the committed
``episodes.csv`` at ``REV`` (the last commit before the rerun) and the current one are paired
by (method, value, episode): rows missing on either side, episodes whose ``success`` or
``success_once`` differ, and each method's successes before and after. ``-v1`` is the last
``-v0``'s behaviour, so flips come only from the CPU: the report's last column names the CPU
each side was recorded on (the manifest's ``cpu``; docs/results.md, "Reproducibility").
A ``--before`` git cannot read is one line naming the file it could not read there.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import subprocess
from collections import Counter
from pathlib import Path

from impact_control.errors import InvalidArgumentError
from impact_eval.experiments.rerun_tables import RESULTS, is_current

OUTCOMES = ("success", "success_once")
KEY = ("method", "param_value", "episode")


def _rows(text: str) -> dict[tuple[str, ...], dict[str, str]]:
    return {tuple(r[k] for k in KEY): r for r in csv.DictReader(io.StringIO(text))}


def _won(row: dict[str, str]) -> bool:
    return row["success"] in ("True", "1", "true")


def table_flips(before: str, after: str) -> dict:
    """Pairing of two episodes.csv texts: counts of rows, missing, flips and successes."""
    a, b = _rows(before), _rows(after)
    common = a.keys() & b.keys()
    flips = sum(any(a[k][o] != b[k][o] for o in OUTCOMES) for k in common)
    won_a, won_b, cell_a, cell_b, cell_n = (Counter() for _ in range(5))
    for k in common:
        won_a[k[0]] += _won(a[k])
        won_b[k[0]] += _won(b[k])
        cell_a[k[:2]] += _won(a[k])
        cell_b[k[:2]] += _won(b[k])
        cell_n[k[:2]] += 1
    moved = {c: (cell_a[c], cell_b[c], cell_n[c]) for c in sorted(cell_n)
             if cell_a[c] != cell_b[c]}
    return {"rows": len(b), "missing": len(a.keys() ^ b.keys()), "flips": flips,
            "methods": {m: (won_a[m], won_b[m]) for m in sorted(won_a.keys() | won_b.keys())},
            "cells": moved}


def _git_show(results: Path, rev: str, path: str) -> str:
    """``path`` at ``rev`` in the repository holding ``results``.

    Raises:
        InvalidArgumentError: git cannot read it (unknown revision, no such file there).
    """
    done = subprocess.run(["git", "show", f"{rev}:{path}"], capture_output=True, text=True,
                          cwd=results.parent)
    if done.returncode != 0:
        reason = (done.stderr.strip().splitlines() or ["git show failed"])[-1]
        raise InvalidArgumentError(f"cannot read {path} at --before {rev}: {reason}")
    return done.stdout


def _cpu(entry: dict) -> str:
    cpu = entry.get("cpu") or {}
    return f"{cpu.get('cpu_model', '?')} {cpu.get('simd', '?')}"


def _current_tables(results: Path, rev: str):
    """(table, pairing) for every manifest table rerun on the current version; the pairing
    also names the CPU each side was recorded on (``cpu_before``, ``cpu_after``)."""
    entries = json.loads((results / "manifest.json").read_text())["tables"]
    old = json.loads(_git_show(results, rev, "results/manifest.json"))["tables"]
    for table, entry in entries.items():
        if not is_current(entry) or "env_version" not in entry:
            continue
        before = _git_show(results, rev, f"results/{table}/episodes.csv")
        r = table_flips(before, (results / table / "episodes.csv").read_text())
        yield table, {**r, "cpu_before": _cpu(old.get(table, {})), "cpu_after": _cpu(entry)}


def cells_report(results: Path, rev: str) -> str:
    """Every (table, method, value) cell whose successes moved: the lines docs are checked
    against."""
    lines = [f"Cells whose successes moved from the -v0 rows at {rev} to the -v1 rerun:", ""]
    for table, r in _current_tables(results, rev):
        for (method, value), (x, y, n) in r["cells"].items():
            lines.append(f"{table}: {method} @ {value}: {x}/{n} -> {y}/{n}")
    return "\n".join(lines) + "\n"


def report(results: Path, rev: str) -> str:
    """The markdown table of every table rerun on the current version."""
    lines = [f"Rows of each table rerun on -v1 against its -v0 rows at {rev} "
             "(`python -m impact_eval.experiments.version_flips`).", "",
             "| table | rows | missing | outcome flips | successes per method, v0 -> v1 "
             "| recorded on, v0 -> v1 |",
             "|---|---|---|---|---|---|"]
    total = Counter()
    for table, r in _current_tables(results, rev):
        methods = ", ".join(f"{m} {x}->{y}" for m, (x, y) in r["methods"].items())
        lines.append(f"| {table} | {r['rows']} | {r['missing']} | {r['flips']} | {methods} "
                     f"| {r['cpu_before']} -> {r['cpu_after']} |")
        total.update(rows=r["rows"], missing=r["missing"], flips=r["flips"])
    lines.append(f"| all | {total['rows']} | {total['missing']} | {total['flips']} | | |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--before", required=True, help="the commit holding the -v0 tables")
    p.add_argument("--results", type=Path, default=RESULTS)
    p.add_argument("--out", type=Path, help="also write the table here")
    p.add_argument("--cells", action="store_true",
                   help="list the cells whose successes moved instead")
    a = p.parse_args(argv)
    try:
        text = (cells_report if a.cells else report)(a.results, a.before)
    except InvalidArgumentError as exc:
        p.error(str(exc))
    print(text, end="")
    if a.out:
        a.out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
