"""``impact-eval reproduce``: rerun a reference table of ``results/`` and compare it byte for byte.

``results/manifest.json`` holds, per reference table (a directory of ``results/``): the sweep's
arguments, the command that wrote it, the git SHA, the library versions and the sha256 of its
``episodes.csv``. ``reproduce TABLE`` reruns the whole table into a fresh directory;
``reproduce --check TABLE --cells method@value,...`` reruns only those cells: it copies the
committed rows of every other cell and the table's run.json into a scratch directory and
resumes the sweep there, so the finished file must equal the committed one byte for byte
(the resume path is exercised too). Every differing cell is printed; exit 1 if any differs.

The bytes hold per CPU instruction set (docs/results.md, "Reproducibility"): each entry records
the CPU model and widest SIMD of the machine that wrote it. On a machine whose CPU differs, a
byte difference is reported but not failed; the check there is that every episode's outcome
(``success``, ``success_once``) equals the committed one.
``reproduce --record TABLE ...`` (maintainers) writes the tables' manifest entries from their
current run.json and episodes.csv.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import shutil
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

from impact_envs.errors import InvalidArgumentError
from impact_eval.csvio import encode_rows, read_rows, row_key
from impact_eval.grid import format_value
from impact_eval.runinfo import IDENTITY_JSON, RUN_JSON, cpu_info, package_versions

RESULTS = Path(__file__).resolve().parent.parent / "results"
MANIFEST = "manifest.json"
MANIFEST_FORMAT = 1
PROG = "impact-eval reproduce"
OUTCOME_COLUMNS = ("success", "success_once")
"""Compared across CPUs (the other columns are compared byte for byte on the recording CPU)."""
Cell = tuple[str, str]
"""``(method, canonical value text)``."""


def sha256(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def sweep_argv(args: dict) -> list[str]:
    """The impact-eval arguments that define a table's rows (no output or executor options)."""
    argv = ["--env", args["env"], "--method", ",".join(args["methods"]),
            "--param-values", args["grid"], "--episodes", str(args["episodes"]),
            "--seed", str(args["seed"])]
    if args.get("param"):
        argv += ["--param", args["param"]]
    for override in args.get("controller_overrides") or ():
        argv += ["--controller-set", override]
    if args.get("beyond_hardware_limits"):
        argv.append("--beyond-hardware-limits")
    return argv


def load_manifest(results: Path) -> dict:
    """The manifest of ``results`` (an empty one if it does not exist yet)."""
    path = results / MANIFEST
    if not path.exists():
        return {"format": MANIFEST_FORMAT, "tables": {}}
    try:
        manifest = json.loads(path.read_text())
        if not isinstance(manifest.get("tables"), dict):
            raise ValueError("no 'tables' object")
    except (OSError, ValueError, AttributeError) as exc:
        raise InvalidArgumentError(f"cannot read {path}: {exc}") from None
    return manifest


def table_entry(manifest: dict, table: str) -> dict:
    """The manifest entry of ``table``, or a one-line error naming the tables it has."""
    tables = manifest["tables"]
    if table not in tables:
        raise InvalidArgumentError(
            f"unknown table {table!r}; valid choices: {', '.join(sorted(tables)) or '(none)'}")
    return tables[table]


def record(results: Path, tables: Sequence[str]) -> dict:
    """Write the manifest entries of ``tables`` from their run.json and episodes.csv."""
    manifest = load_manifest(results)
    for table in tables:
        directory = results / table
        run_path, csv_path = directory / RUN_JSON, directory / "episodes.csv"
        if not run_path.is_file() or not csv_path.is_file():
            raise InvalidArgumentError(f"{directory} has no run.json and episodes.csv")
        run = json.loads(run_path.read_text())
        manifest["tables"][table] = {
            "dir": table,
            "sweep_args": sweep_argv(run["args"]),
            "command": run.get("command"),
            "git": run.get("git"),
            "versions": run.get("versions"),
            "episodes_sha256": sha256(csv_path),
            "rows": len(read_rows(csv_path)),
            "cpu": {k: (run.get("host") or {}).get(k) for k in ("cpu_model", "simd")},
        }
    path = results / MANIFEST
    path.write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n")
    return manifest


def parse_cells(spec: str, args: dict) -> set[Cell]:
    """``method@value,...`` -> cells, each checked against the table's methods and grid."""
    methods = list(args["methods"])
    values = {format_value(float(v)) for v in args["values"]}
    cells = set()
    for item in spec.split(","):
        method, sep, value = item.strip().partition("@")
        try:
            text = format_value(float(value))
        except ValueError:
            text = None
        if not sep or method not in methods or text not in values:
            raise InvalidArgumentError(
                f"invalid cell {item!r}; valid: METHOD@VALUE with METHOD in {', '.join(methods)} "
                f"and VALUE in {', '.join(sorted(values, key=float))}")
        cells.add((method, text))
    return cells


def seed_scratch(table_dir: Path, scratch: Path, cells: set[Cell]) -> None:
    """Copy run.json and every committed row outside ``cells`` into ``scratch``."""
    scratch.mkdir(parents=True)
    for name in (RUN_JSON, IDENTITY_JSON):
        if (table_dir / name).exists():
            shutil.copy(table_dir / name, scratch / name)
    kept = [row for row in read_rows(table_dir / "episodes.csv") if row_key(row)[:2] not in cells]
    (scratch / "episodes.csv").write_text(encode_rows(kept))


class CellDiff(NamedTuple):
    """The episodes of one (method, value) cell that differ between two files."""

    cell: Cell
    differ: int
    episodes: int
    outcome: int
    columns: tuple[str, ...]

    def line(self) -> str:
        """One line: ``method @ value: k/n episodes differ (j in outcome; columns: ...)``."""
        named = ", ".join(self.columns) or "rows missing"
        return (f"{self.cell[0]} @ {float(self.cell[1]):g}: {self.differ}/{self.episodes} "
                f"episodes differ ({self.outcome} in outcome; columns: {named})")


def compare(committed: Path, rerun: Path) -> list[CellDiff]:
    """The (method, value) cells whose rows differ, with the differing columns; a missing row
    counts as a differing outcome."""
    def by_cell(path: Path) -> dict[Cell, dict[int, dict[str, str]]]:
        cells: dict[Cell, dict[int, dict[str, str]]] = {}
        for row in read_rows(path):
            method, value, episode = row_key(row)
            cells.setdefault((method, value), {})[episode] = row
        return cells

    old, new = by_cell(committed), by_cell(rerun)
    diffs = []
    for cell in sorted(set(old) | set(new), key=lambda c: (c[0], float(c[1]))):
        a, b = old.get(cell, {}), new.get(cell, {})
        episodes = sorted(set(a) | set(b))
        differ = [e for e in episodes if a.get(e) != b.get(e)]
        if differ:
            both = [e for e in differ if e in a and e in b]
            columns = tuple(sorted({k for e in both for k in a[e] if a[e][k] != b[e][k]}))
            outcome = sum(any(a[e][k] != b[e][k] for k in OUTCOME_COLUMNS) for e in both)
            diffs.append(CellDiff(cell, len(differ), len(episodes),
                                  outcome + len(differ) - len(both), columns))
    return diffs


def parser() -> argparse.ArgumentParser:
    """Parser of ``impact-eval reproduce``."""
    from impact_eval.cli import _Parser

    p = _Parser(prog=PROG, description=__doc__.splitlines()[0])
    p.add_argument("tables", nargs="*", metavar="TABLE", help="table name (a results/ directory)")
    p.add_argument("--check", action="store_true", help="rerun and compare with the committed rows")
    p.add_argument("--cells", help="with --check: only these cells, METHOD@VALUE,...")
    p.add_argument("--list", action="store_true", help="list the tables of the manifest")
    p.add_argument("--record", action="store_true",
                   help="write the tables' manifest entries from their current files")
    p.add_argument("--out", type=Path, help="rerun directory, kept (default: TABLE/tmp/rerun "
                   "without --check, a temporary directory removed afterwards with --check)")
    p.add_argument("--workers", type=int, help="worker processes of the rerun")
    p.add_argument("--envs-per-worker", type=int, help="lockstep envs per worker of the rerun")
    p.add_argument("--executor", default="local", help="local | ray")
    p.add_argument("--results", type=Path, default=RESULTS, help=argparse.SUPPRESS)
    return p


def rerun(results: Path, table: str, a: argparse.Namespace, out: Path) -> int:
    """Rerun ``table`` (or its ``--cells``) into ``out``; print the comparison; exit code."""
    from impact_eval.cli import run_sweep_command

    entry = table_entry(load_manifest(results), table)
    table_dir = results / entry["dir"]
    run = json.loads((table_dir / RUN_JSON).read_text())
    argv = [*entry["sweep_args"], "--out", str(out), "--executor", a.executor]
    if a.cells:
        seed_scratch(table_dir, out, parse_cells(a.cells, run["args"]))
        argv.append("--resume")
    for flag, value in (("--workers", a.workers), ("--envs-per-worker", a.envs_per_worker)):
        if value is not None:
            argv += [flag, str(value)]
    code = run_sweep_command(argv)
    if code not in (0, 1):
        return code
    diffs = compare(table_dir / "episodes.csv", out / "episodes.csv")
    digest = sha256(out / "episodes.csv")
    same = digest == entry["episodes_sha256"]
    for diff in diffs:
        print(f"{PROG}: differs: {table}: {diff.line()}")
    scope = f"cells {a.cells}" if a.cells else "the whole table"
    verdict = "identical" if same and not diffs else "DIFFERENT"
    print(f"{PROG}: {table} ({scope}): episodes.csv {verdict} to the committed bytes "
          f"(sha256 {entry['episodes_sha256'][:12]}, rerun {digest[:12]}; rerun in {out})")
    if same and not diffs:
        return 0
    recorded, here = entry.get("cpu") or {}, cpu_info()
    if recorded and recorded != here:
        flips = sum(diff.outcome for diff in diffs)
        print(f"{PROG}: {table}: recorded on {recorded.get('cpu_model')} "
              f"({recorded.get('simd')}), rerun on {here['cpu_model']} ({here['simd']}): bytes "
              f"are not comparable across CPUs; {flips} episode outcomes differ")
        return 1 if flips else 0
    return 1


def main(argv: Sequence[str]) -> int:
    """``impact-eval reproduce ...``; returns the exit code (bad input: InvalidArgumentError)."""
    a = parser().parse_args(argv)
    if a.list:
        for name, entry in sorted(load_manifest(a.results)["tables"].items()):
            print(f"{name}: {entry['rows']} episodes, sha256 {entry['episodes_sha256'][:12]}, "
                  f"{' '.join(entry['sweep_args'])}")
        return 0
    if not a.tables:
        raise InvalidArgumentError("name a TABLE (impact-eval reproduce --list shows them)")
    if a.record:
        record(a.results, a.tables)
        print(f"{PROG}: recorded {', '.join(a.tables)} in {a.results / MANIFEST}")
        return 0
    if a.cells and not a.check:
        raise InvalidArgumentError("--cells needs --check")
    if len(a.tables) > 1 and a.out is not None:
        raise InvalidArgumentError("--out takes one TABLE")
    print(f"{PROG}: library versions here: {package_versions()}")
    code = 0
    for table in a.tables:
        table_entry(load_manifest(a.results), table)  # unknown table: one line, nothing run
        out = a.out
        if out is None and not a.check:
            out = a.results / table / "tmp" / "rerun"  # ignored by git
            shutil.rmtree(out, ignore_errors=True)
        if out is not None:
            if out.exists():
                raise InvalidArgumentError(f"--out {out} exists; give a new directory")
            code = max(code, rerun(a.results, table, a, out))
            continue
        with tempfile.TemporaryDirectory(prefix=f"reproduce_{table}_") as tmp:
            code = max(code, rerun(a.results, table, a, Path(tmp) / table))
    return code
