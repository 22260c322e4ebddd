"""Rerun the reference tables of ``results/manifest.json`` recorded on a retired env version
on the version that pins its behaviour (issue 41's single full rerun: ``-v0`` onto ``-v1``),
resumably, one table after another.

    python -m impact_experiments.rerun_tables [TABLE ...] [--workers 2] [--python PY]

For each table (default: every one in the manifest, in its order): the manifest's
``sweep_args`` with a retired env id replaced by the next registered one
(``impact_envs/versions.py``)
run as ``impact-eval ... --out results/.rerun/TABLE`` (``--resume`` when that directory
already holds rows: a killed rerun continues). When the sweep completes, its directory
replaces ``results/TABLE`` and ``impact-eval reproduce --record TABLE`` writes the manifest
entry (with ``env_version``). A table whose entry already names a registered version (``-v1``
or ``-v2``) is skipped, so calling the script again goes on where it stopped. Files of the old
directory that the sweep does not write (e.g. ``hammer_basket/authors_figure.md``) are listed for
regeneration. ``--python`` runs the sweeps with another interpreter (the LeRobot table needs
the venv of tests/learn/lerobot_venv.sh).

``--to-version N`` (issue 59's single rerun) instead runs each named table on version ``N`` of
its env into a twin, ``results/TABLE_vN``, recorded in the manifest beside the table it was
rerun from, which stays as it is (``-v1`` stays registered and keeps reproducing); a twin
already in the manifest is skipped.

    python -m impact_experiments.rerun_tables --to-version 2 hammer_presets dumbbell_presets

Bad input (an unknown table, ``--workers`` below 1, a ``--python`` that cannot import
``impact_eval``, a missing or damaged manifest) is one line, exit 2, before anything runs. A
sweep or record that fails has printed its own line; the script exits with its exit code and
adds nothing (calling it again resumes the sweep).
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import time
from pathlib import Path

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError
from impact_envs.versions import parse, pinned_by, registered, retired
from impact_eval.reproduce_manifest import load_manifest, positive_int

RESULTS = Path(__file__).resolve().parents[1] / "results"
SCRATCH = ".rerun"


def current_args(sweep_args: list[str]) -> list[str]:
    """``sweep_args`` with a retired ``--env`` id replaced by the next registered version's
    (the one that pinned its behaviour: ``-v0`` -> ``-v1``)."""
    args = list(sweep_args)
    i = args.index("--env") + 1
    parsed = parse(args[i])
    if parsed is not None and retired(args[i]):
        family, version = parsed
        args[i] = args[i].replace(f"{family}-v{version}",
                                  f"{family}-v{pinned_by(family, version)}")
    return args


def version_args(sweep_args: list[str], version: int) -> list[str]:
    """``sweep_args`` with the ``--env`` id of a built-in env at ``version`` (one line for
    another env or a version that is not registered)."""
    args = list(sweep_args)
    i = args.index("--env") + 1
    parsed = parse(args[i])
    if parsed is None or version not in {v.version for v in registered(parsed[0])}:
        raise InvalidArgumentError(f"--to-version {version}: {args[i]} has no registered "
                                   f"version {version}")
    args[i] = args[i].replace(f"{parsed[0]}-v{parsed[1]}", f"{parsed[0]}-v{version}")
    return args


def is_current(entry: dict) -> bool:
    """Whether a manifest entry was recorded on a registered (not retired) env version."""
    env = entry["sweep_args"][entry["sweep_args"].index("--env") + 1]
    parsed = parse(env)
    return parsed is None or entry.get("env_version") in {
        v.version for v in registered(parsed[0])}


def check_python(python: str) -> None:
    """``--python`` must be an interpreter that imports this package (probed, one line if not:
    a sweep it cannot run would otherwise fail, or a program that is not Python exit 0 and
    have its table replaced by nothing)."""
    where = shutil.which(python)
    if where is None:
        raise InvalidArgumentError(f"--python {python}: no such executable")
    try:
        done = subprocess.run([where, "-c", "import impact_eval; print('impact_eval')"],
                              capture_output=True, text=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise InvalidArgumentError(f"--python {python} cannot be run: {exc}") from None
    if done.returncode != 0 or done.stdout.strip() != "impact_eval":
        reason = (done.stderr.strip().splitlines() or [f"exit {done.returncode}"])[-1]
        raise InvalidArgumentError(f"--python {python} cannot import impact_eval: {reason}")


class ChildError(ImpactError):
    """A sweep or record child exited non-zero; it has printed its own line (its exit code)."""

    def __init__(self, code: int) -> None:
        super().__init__(f"exit {code}")
        self.code = code


def _child(argv: list[str]) -> None:
    """Run a child ``impact-eval``; its failure is ``ChildError`` with its exit code."""
    code = subprocess.run(argv).returncode
    if code != 0:
        raise ChildError(code if code > 0 else 128 - code)  # killed by a signal: 128 + it


def rerun(table: str, entry: dict, results: Path, workers: int, python: str,
          to_version: int | None = None) -> None:
    """Run one table into its scratch directory, then swap it in and record it (with
    ``to_version``: its twin ``TABLE_vN`` on that version, the table left as it is)."""
    sweep_args = current_args(entry["sweep_args"])
    if to_version is not None:
        sweep_args, table = version_args(sweep_args, to_version), f"{table}_v{to_version}"
    scratch = results / SCRATCH / table
    argv = [python, "-m", "impact_eval", *sweep_args,
            "--out", str(scratch), "--workers", str(workers)]
    if (scratch / "episodes.csv").is_file():
        argv.append("--resume")
    print(f"[{time.strftime('%H:%M:%S')}] {table}: {' '.join(argv[2:])}", flush=True)
    t0 = time.perf_counter()
    _child(argv)
    if not (scratch / "episodes.csv").is_file():
        raise InvalidArgumentError(f"the sweep of {table} wrote no {scratch / 'episodes.csv'}; "
                                   f"{results / table} is kept")
    target = results / table
    written = {p.relative_to(scratch) for p in scratch.rglob("*") if p.is_file()}
    stale = sorted(str(p.relative_to(target)) for p in target.rglob("*")  # none for a twin
                   if p.is_file() and p.relative_to(target) not in written)
    if target.exists():
        shutil.rmtree(target)
    shutil.move(str(scratch), str(target))
    _child([python, "-m", "impact_eval", "reproduce", "--record", table,
            *(["--results", str(results)] if results != RESULTS else [])])
    print(f"[{time.strftime('%H:%M:%S')}] {table}: recorded ({time.perf_counter() - t0:.0f} s)"
          + (f"; regenerate: {', '.join(stale)}" if stale else ""), flush=True)


def _tables(p: OneLineParser, a: argparse.Namespace) -> list[str]:
    """The tables to rerun, checked with --python before anything runs."""
    entries = load_manifest(a.results)["tables"]
    unknown = sorted(set(a.tables) - set(entries))
    if unknown:
        p.error(f"unknown table(s) {unknown}; valid: {', '.join(entries)}")
    check_python(a.python)
    return a.tables or list(entries)


def main(argv: list[str] | None = None) -> int:
    """Exit 0 when every table is on its current version; 2 for bad input (one line); a
    child's own exit code (after its own line) when a sweep or record fails."""
    p = OneLineParser(prog="rerun_tables", description=__doc__.splitlines()[0])
    p.add_argument("tables", nargs="*", help="tables to rerun (default: all, manifest order)")
    p.add_argument("--workers", type=positive_int, default=2)
    p.add_argument("--python", default=sys.executable, help="interpreter of the sweeps")
    p.add_argument("--results", type=Path, default=RESULTS)
    p.add_argument("--to-version", type=positive_int, default=None,
                   help="rerun the tables on this env version into twins TABLE_vN")
    a = p.parse_args(argv)
    try:
        for table in _tables(p, a):
            tables = load_manifest(a.results)["tables"]
            entry = tables[table]
            if a.to_version is not None:
                version_args(entry["sweep_args"], a.to_version)  # one line before it runs
                if f"{table}_v{a.to_version}" in tables:
                    print(f"{table}_v{a.to_version}: already recorded, skipped", flush=True)
                    continue
            elif is_current(entry):
                print(f"{table}: already on a registered version, skipped", flush=True)
                continue
            rerun(table, entry, a.results, a.workers, a.python, a.to_version)
    except ChildError as exc:
        return exc.code
    except KeyboardInterrupt:
        print(f"{p.prog}: interrupted; run the same command again to continue (a table's sweep "
              f"resumes from {a.results / SCRATCH})", file=sys.stderr)
        return 130
    except InvalidArgumentError as exc:
        p.fail(exc)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
