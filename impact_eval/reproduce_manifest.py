"""``results/manifest.json`` of ``impact-eval reproduce``: read and checked at the boundary.

Every entry, every table directory, its ``run.json`` and its ``episodes.csv`` are checked
before anything is rerun: a missing or damaged one is a one-line ``InvalidArgumentError``
(exit 2). ``committed_problem`` compares the committed ``episodes.csv`` with the manifest's
sha256 and row count (an edited file fails the check on any CPU, before any rerun).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
from collections.abc import Sequence
from pathlib import Path, PurePosixPath
from typing import NamedTuple

from impact_control.errors import InvalidArgumentError
from impact_eval.csvio import read_rows
from impact_eval.run_migration import spec_json_of
from impact_eval.runinfo import RUN_JSON, read_run_json
from impact_eval.spec import SweepSpec

MANIFEST = "manifest.json"
MANIFEST_FORMAT = 1
EPISODES_CSV = "episodes.csv"
SWEEP_ONLY = ("--out", "--resume", "--extend", "--quick")
"""Options a manifest's ``sweep_args`` may not hold (the rerun chooses its own output)."""
_HEX64 = re.compile(r"[0-9a-f]{64}")


class Table(NamedTuple):
    """A reference table whose entry, directory, run.json and episodes.csv were checked."""

    name: str
    entry: dict
    dir: Path
    run: dict


def positive_int(text: str) -> int:
    """argparse ``type`` of a count such as ``--workers``: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer >= 1")
    return value


def sha256(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def sweep_argv(run: dict) -> list[str]:
    """The impact-eval arguments that define a table's rows (no output or executor options):
    ``SweepSpec.to_argv`` of the spec its run.json recorded, in any layout (``run_migration``)."""
    return SweepSpec.from_json(spec_json_of(run)).to_argv()


def load_manifest(results: Path, must_exist: bool = True) -> dict:
    """The manifest of ``results`` (an empty one if it does not exist and not ``must_exist``)."""
    path = results / MANIFEST
    if not path.exists():
        if must_exist:
            raise InvalidArgumentError(f"no {MANIFEST} in {results}")
        return {"format": MANIFEST_FORMAT, "tables": {}}
    try:
        manifest = json.loads(path.read_text())
        if not isinstance(manifest, dict) or not isinstance(manifest.get("tables"), dict):
            raise ValueError("no 'tables' object")
    except (OSError, ValueError) as exc:
        raise InvalidArgumentError(f"cannot read {path}: {' '.join(str(exc).split())}") from None
    return manifest


def _entry_problem(entry: object) -> str | None:
    """What is wrong with a manifest entry, or ``None``."""
    if not isinstance(entry, dict):
        return "not a JSON object"
    checks = (
        ("dir", lambda v: isinstance(v, str) and _relative_name(v), "a relative directory name"),
        ("sweep_args", lambda v: isinstance(v, list) and v and all(isinstance(s, str) for s in v)
         and not set(v) & set(SWEEP_ONLY), f"a list of strings without {', '.join(SWEEP_ONLY)}"),
        ("episodes_sha256", lambda v: isinstance(v, str) and _HEX64.fullmatch(v), "64 hex digits"),
        ("rows", lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0,
         "a count >= 0"),
        ("cpu", lambda v: isinstance(v, dict) and all(isinstance(v.get(k), str)
                                                      for k in ("cpu_model", "simd")),
         "an object with cpu_model and simd"),
    )
    for key, ok, wanted in checks:
        if key not in entry:
            return f"no {key!r}"
        if not ok(entry[key]):
            return f"{key!r} is not {wanted}"
    return None


def _relative_name(name: str) -> bool:
    """True for a non-empty relative path without ``..`` (stays inside results/)."""
    path = PurePosixPath(name)
    return bool(name.strip()) and not path.is_absolute() and ".." not in path.parts


def table_entry(manifest: dict, table: str, results: Path) -> dict:
    """The checked manifest entry of ``table``; a one-line error naming the tables it has, or
    saying what is wrong with the entry."""
    tables = manifest["tables"]
    if table not in tables:
        raise InvalidArgumentError(
            f"unknown table {table!r}; valid choices: {', '.join(sorted(tables)) or '(none)'}")
    problem = _entry_problem(tables[table])
    if problem:
        raise InvalidArgumentError(
            f"{results / MANIFEST}: the entry of table {table!r} is damaged ({problem}); restore "
            f"the file (git checkout -- {MANIFEST}) or write it with reproduce --record {table}")
    return tables[table]


def read_table_run(directory: Path) -> dict:
    """The table's ``run.json``, its spec checked for what ``--cells`` and ``--record`` read
    (the methods and values)."""
    if not directory.is_dir():
        raise InvalidArgumentError(f"the table directory {directory} does not exist; restore it "
                                   "(git checkout) or choose another table (--list)")
    run = read_run_json(directory)  # a corrupt or truncated one: one-line error
    if run is None:
        raise InvalidArgumentError(f"{directory} has no {RUN_JSON}; restore it (git checkout)")
    try:
        spec = spec_json_of(run, str(directory / RUN_JSON))
    except (KeyError, TypeError) as exc:
        raise InvalidArgumentError(f"{directory / RUN_JSON} is damaged (spec: {exc}); "
                                   "restore it") from None
    problem = ("'methods' is not a list of names" if not (
                   isinstance(spec.get("methods"), list)
                   and all(isinstance(m, str) for m in spec["methods"])) else
               "'values' is not a list of numbers" if not (
                   isinstance(spec.get("values"), list) and all(
                       isinstance(v, int | float) and not isinstance(v, bool)
                       for v in spec["values"])) else None)
    if problem:
        raise InvalidArgumentError(f"{directory / RUN_JSON} is damaged ({problem}); restore it")
    return run


def open_table(results: Path, manifest: dict, table: str) -> Table:
    """Check ``table``'s entry, directory, run.json and that its episodes.csv exists."""
    entry = table_entry(manifest, table, results)
    directory = results / entry["dir"]
    run = read_table_run(directory)
    if not (directory / EPISODES_CSV).is_file():
        raise InvalidArgumentError(f"{directory} has no {EPISODES_CSV}; restore it (git checkout)")
    return Table(table, entry, directory, run)


def committed_problem(table: Table) -> str | None:
    """Why the committed episodes.csv is not the one the manifest recorded, or ``None``."""
    path = table.dir / EPISODES_CSV
    try:
        digest = sha256(path)
        recorded = digest == table.entry["episodes_sha256"]
        rows = len(read_rows(path, older=True)) if recorded else None
    except (OSError, InvalidArgumentError) as exc:
        raise InvalidArgumentError(f"cannot read {path}: {' '.join(str(exc).split())}") from None
    if digest != table.entry["episodes_sha256"]:
        return (f"the committed {path} is not the recorded one (sha256 {digest[:12]}, manifest "
                f"{table.entry['episodes_sha256'][:12]}): it was edited or damaged; restore it "
                f"(git checkout -- {path}) or re-record the table")
    if rows != table.entry["rows"]:
        return (f"the committed {path} has {rows} rows, the manifest {table.entry['rows']} "
                "(its sha256 matches): the manifest entry is damaged")
    return None


def record(results: Path, tables: Sequence[str]) -> dict:
    """Write the tables' manifest entries from their run.json and episodes.csv (atomically)."""
    manifest = load_manifest(results, must_exist=False)
    for table in tables:
        if not _relative_name(table):
            raise InvalidArgumentError(f"invalid table name {table!r}: a directory of {results}")
        directory = results / table
        run = read_table_run(directory)
        csv_path = directory / EPISODES_CSV
        if not csv_path.is_file():
            raise InvalidArgumentError(f"{directory} has no {EPISODES_CSV}")
        try:
            sweep_args = sweep_argv(run)
        except (KeyError, TypeError) as exc:
            raise InvalidArgumentError(f"{directory / RUN_JSON} is damaged (spec: {exc})") from None
        host = run.get("host") if isinstance(run.get("host"), dict) else {}
        manifest["tables"][table] = {
            "dir": table, "sweep_args": sweep_args, "command": run.get("command"),
            "env_version": (run["env"].get("version") if isinstance(run.get("env"), dict)
                            else None),
            "git": run.get("git"), "versions": run.get("versions"),
            "episodes_sha256": sha256(csv_path), "rows": len(read_rows(csv_path)),
            "cpu": {k: str(host.get(k) or "unknown") for k in ("cpu_model", "simd")},
        }
    path = results / MANIFEST
    tmp = path.with_name(MANIFEST + ".tmp")
    try:
        tmp.write_text(json.dumps(manifest, indent=2, sort_keys=True) + "\n")
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise InvalidArgumentError(f"cannot write {path}: {exc.strerror or exc}") from None
    return manifest
