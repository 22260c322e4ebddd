"""What the full rerun on ``-v1`` changed in each reference table: its rows against the same
table's ``-v0`` rows at an earlier commit, outcome by outcome (issue 41).

    python -m impact_experiments.version_flips --before REV [--out results/rerun_v1.md]
    python -m impact_experiments.version_flips --before REV --cells   # cells that moved

For every manifest table whose entry names the current env version, the committed
``episodes.csv`` at ``REV`` (the last commit before the rerun) and the current one are paired
by (method, value, episode): rows missing on either side, episodes whose ``success`` or
``success_once`` differ, and each method's successes before and after. ``-v1`` is the last
``-v0``'s behaviour, so flips come only from the CPU: the report's last column names the CPU
each side was recorded on (the manifest's ``cpu``; docs/results.md, "Reproducibility").
The title names the env versions compared (each side's manifest ``env_version``, the
version of its ``--env`` id for a table recorded before versions were, else its rows'
``env_id``); a ``--before`` whose rows of a table ran the version that table runs now is not a
version change and is refused (one line, exit 2), as is a ``--before`` git cannot read (naming
the file), a bad ``--results`` or an ``--out`` that cannot be written (nothing is written).
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import subprocess
from collections import Counter
from pathlib import Path

from impact_control.cli import OneLineParser
from impact_control.errors import InvalidArgumentError
from impact_envs.versions import version_of
from impact_eval.reproduce_manifest import load_manifest
from impact_experiments.rerun_tables import RESULTS, is_current

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
    try:
        done = subprocess.run(["git", "show", f"{rev}:{path}"], capture_output=True, text=True,
                              cwd=results.parent)
    except OSError as exc:
        raise InvalidArgumentError(f"cannot run git in {results.parent}: "
                                   f"{exc.strerror or exc}") from None
    if done.returncode != 0:
        reason = (done.stderr.strip().splitlines() or ["git show failed"])[-1]
        raise InvalidArgumentError(f"cannot read {path} at --before {rev}: {reason}")
    return done.stdout


def _old_tables(results: Path, rev: str) -> dict:
    """The ``tables`` of results/manifest.json at ``rev`` (one line if it is damaged)."""
    text = _git_show(results, rev, "results/manifest.json")
    try:
        tables = json.loads(text)["tables"]
        if not isinstance(tables, dict):
            raise TypeError("'tables' is not an object")
    except (ValueError, KeyError, TypeError) as exc:
        raise InvalidArgumentError(f"cannot read results/manifest.json at --before {rev}: "
                                   f"{' '.join(str(exc).split())}") from None
    return tables


def _cpu(entry: dict) -> str:
    cpu = entry.get("cpu") or {}
    return f"{cpu.get('cpu_model', '?')} {cpu.get('simd', '?')}"


def _version_before(entry: object, episodes: str) -> int | None:
    """The env version a table's rows at the earlier revision ran: its manifest entry's
    ``env_version`` (run.json's), else the version of its ``--env`` id, else of its rows'
    ``env_id`` (all rows must agree)."""
    entry = entry if isinstance(entry, dict) else {}
    if isinstance(entry.get("env_version"), int):
        return entry["env_version"]
    args = entry.get("sweep_args")
    if isinstance(args, list) and "--env" in args[:-1]:
        return version_of(str(args[args.index("--env") + 1]))
    ids = {r.get("env_id") for r in csv.DictReader(io.StringIO(episodes))}
    return version_of(ids.pop()) if len(ids) == 1 and None not in ids else None


def _current_tables(results: Path, rev: str):
    """(table, pairing) for every manifest table rerun on the current version; the pairing
    also names the CPU and env version each side was recorded on (``cpu_before``,
    ``cpu_after``, ``versions``). A table whose rows at ``rev`` ran the version it runs now
    (or one that cannot be told) is refused: the comparison would not be a version change."""
    entries = load_manifest(results)["tables"]
    old = _old_tables(results, rev)
    for table, entry in entries.items():
        if not isinstance(entry, dict) or not is_current(entry) or "env_version" not in entry:
            continue
        before = _git_show(results, rev, f"results/{table}/episodes.csv")
        was, now = _version_before(old.get(table), before), entry["env_version"]
        if was is None or was >= now:
            ran = "an env version that cannot be told" if was is None else f"-v{was}"
            raise InvalidArgumentError(
                f"--before {rev} is not a version change for {table}: its rows there ran {ran}, "
                f"now -v{now}; give a revision whose {table} ran an earlier version")
        r = table_flips(before, (results / table / "episodes.csv").read_text())
        yield table, {**r, "cpu_before": _cpu(old.get(table) or {}), "cpu_after": _cpu(entry),
                      "versions": (was, now)}


def _versions(pairs: list[tuple[str, dict]]) -> tuple[str, str]:
    """The env versions compared, before and after, as the report names them ("-v0", "-v1";
    tables that compare other versions add theirs: "-v0/-v1"). No table: one line."""
    if not pairs:
        raise InvalidArgumentError("no table of the manifest is recorded on its env's current "
                                   "version (env_version); nothing to compare")

    def names(side: int) -> str:
        return "/".join(f"-v{v}" for v in sorted({r["versions"][side] for _, r in pairs}))
    return names(0), names(1)


def cells_report(results: Path, rev: str) -> str:
    """Every (table, method, value) cell whose successes moved: the lines docs are checked
    against."""
    pairs = list(_current_tables(results, rev))
    was, now = _versions(pairs)
    lines = [f"Cells whose successes moved from the {was} rows at {rev} to the {now} rerun:", ""]
    for table, r in pairs:
        for (method, value), (x, y, n) in r["cells"].items():
            lines.append(f"{table}: {method} @ {value}: {x}/{n} -> {y}/{n}")
    return "\n".join(lines) + "\n"


def report(results: Path, rev: str) -> str:
    """The markdown table of every table rerun on the current version."""
    pairs = list(_current_tables(results, rev))
    was, now = _versions(pairs)
    short = f"{was} -> {now}".replace("-v", "v")
    lines = [f"Rows of each table rerun on {now} against its {was} rows at {rev} "
             "(`python -m impact_experiments.version_flips`).", "",
             f"| table | rows | missing | outcome flips | successes per method, {short} "
             f"| recorded on, {short} |",
             "|---|---|---|---|---|---|"]
    total = Counter()
    for table, r in pairs:
        methods = ", ".join(f"{m} {x}->{y}" for m, (x, y) in r["methods"].items())
        lines.append(f"| {table} | {r['rows']} | {r['missing']} | {r['flips']} | {methods} "
                     f"| {r['cpu_before']} -> {r['cpu_after']} |")
        total.update(rows=r["rows"], missing=r["missing"], flips=r["flips"])
    lines.append(f"| all | {total['rows']} | {total['missing']} | {total['flips']} | | |")
    return "\n".join(lines) + "\n"


def _write(out: Path, text: str) -> None:
    """Write ``out`` whole or not at all (temp file + rename; one line if it cannot)."""
    tmp = out.with_name(out.name + ".tmp")
    try:
        tmp.write_text(text)
        os.replace(tmp, out)
    except OSError as exc:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise InvalidArgumentError(f"cannot write --out {out}: {exc.strerror or exc}") from None


def main(argv: list[str] | None = None) -> int:
    p = OneLineParser(prog="version_flips", description=__doc__.splitlines()[0])
    p.add_argument("--before", required=True,
                   help="a commit whose tables ran an earlier env version (e.g. -v0)")
    p.add_argument("--results", type=Path, default=RESULTS)
    p.add_argument("--out", type=Path, help="also write the table here")
    p.add_argument("--cells", action="store_true",
                   help="list the cells whose successes moved instead")
    a = p.parse_args(argv)
    try:
        text = (cells_report if a.cells else report)(a.results, a.before)
        if a.out:
            _write(a.out, text)
    except InvalidArgumentError as exc:
        p.fail(exc)
    print(text, end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
