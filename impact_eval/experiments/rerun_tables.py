"""Rerun the reference tables of ``results/manifest.json`` on the current env versions
(issue 41's single full rerun), resumably, one table after another.

    python -m impact_eval.experiments.rerun_tables [TABLE ...] [--workers 2] [--python PY]

For each table (default: every one in the manifest, in its order): the manifest's
``sweep_args`` with a retired env id replaced by its current one (``impact_envs/versions.py``)
run as ``impact-eval ... --out results/.rerun/TABLE`` (``--resume`` when that directory
already holds rows: a killed rerun continues). When the sweep completes, its directory
replaces ``results/TABLE`` and ``impact-eval reproduce --record TABLE`` writes the manifest
entry (with ``env_version``). A table whose entry already names its env's current version is
skipped, so calling the script again goes on where it stopped. Files of the old directory
that the sweep does not write (e.g. ``hammer_basket/authors_figure.md``) are listed for
regeneration. ``--python`` runs the sweeps with another interpreter (the LeRobot table needs
the venv of tests/learn/lerobot_venv.sh).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

from impact_control.cli import OneLineParser
from impact_envs.versions import current_version, parse, retired

RESULTS = Path(__file__).resolve().parents[2] / "results"
SCRATCH = ".rerun"


def current_args(sweep_args: list[str]) -> list[str]:
    """``sweep_args`` with a retired ``--env`` id replaced by the current one."""
    args = list(sweep_args)
    i = args.index("--env") + 1
    parsed = parse(args[i])
    if parsed is not None and retired(args[i]):
        family, version = parsed
        args[i] = args[i].replace(f"{family}-v{version}",
                                  f"{family}-v{current_version(family)}")
    return args


def is_current(entry: dict) -> bool:
    """Whether a manifest entry was recorded on its env's current version."""
    env = entry["sweep_args"][entry["sweep_args"].index("--env") + 1]
    parsed = parse(env)
    return parsed is None or entry.get("env_version") == current_version(parsed[0])


def rerun(table: str, entry: dict, results: Path, workers: int, python: str) -> None:
    """Run one table into its scratch directory, then swap it in and record it."""
    scratch = results / SCRATCH / table
    argv = [python, "-m", "impact_eval", *current_args(entry["sweep_args"]),
            "--out", str(scratch), "--workers", str(workers)]
    if (scratch / "episodes.csv").is_file():
        argv.append("--resume")
    print(f"[{time.strftime('%H:%M:%S')}] {table}: {' '.join(argv[2:])}", flush=True)
    t0 = time.perf_counter()
    subprocess.run(argv, check=True)
    target = results / table
    written = {p.relative_to(scratch) for p in scratch.rglob("*") if p.is_file()}
    stale = sorted(str(p.relative_to(target)) for p in target.rglob("*")
                   if p.is_file() and p.relative_to(target) not in written)
    shutil.rmtree(target)
    shutil.move(str(scratch), str(target))
    subprocess.run([python, "-m", "impact_eval", "reproduce", "--record", table,
                    *(["--results", str(results)] if results != RESULTS else [])], check=True)
    print(f"[{time.strftime('%H:%M:%S')}] {table}: recorded ({time.perf_counter() - t0:.0f} s)"
          + (f"; regenerate: {', '.join(stale)}" if stale else ""), flush=True)


def main(argv: list[str] | None = None) -> int:
    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("tables", nargs="*", help="tables to rerun (default: all, manifest order)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--python", default=sys.executable, help="interpreter of the sweeps")
    p.add_argument("--results", type=Path, default=RESULTS)
    a = p.parse_args(argv)
    entries = json.loads((a.results / "manifest.json").read_text())["tables"]
    unknown = sorted(set(a.tables) - set(entries))
    if unknown:
        p.error(f"unknown table(s) {unknown}; valid: {', '.join(entries)}")
    for table in a.tables or list(entries):
        entry = json.loads((a.results / "manifest.json").read_text())["tables"][table]
        if is_current(entry):
            print(f"{table}: already on the current version, skipped", flush=True)
            continue
        rerun(table, entry, a.results, a.workers, a.python)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
