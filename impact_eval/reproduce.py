"""``impact-eval reproduce``: rerun a reference table of ``results/`` and compare it with its rows.

``results/manifest.json`` holds, per reference table (a directory of ``results/``): the sweep's
arguments, the command that wrote it, the git SHA, the library versions, the CPU and the sha256
and row count of its ``episodes.csv``. Every named table's entry, directory, run.json and
episodes.csv are checked first (a missing or damaged one: one line, exit 2, nothing written),
then each committed episodes.csv is compared with the manifest's sha256 and row count (an
edited one: exit 1, nothing rerun, on any CPU).

``reproduce TABLE`` reruns the whole table into ``results/TABLE/tmp/rerun`` (kept);
``reproduce --check TABLE --cells method@value,...`` reruns only those cells: it copies the
committed rows of every other cell and the table's run.json into a scratch directory and
resumes the sweep there. Every differing row (method, value, episode and columns) and cell is
printed. On the CPU that recorded the table (model and SIMD width, in the manifest) the rerun
must equal the committed file byte for byte. On another CPU (docs/results.md,
"Reproducibility") the rows outside the rerun cells must still be equal, no row may be missing
or extra, and at most ``K = max_outcome_flips(n)`` of the ``n`` rerun episodes may flip
``success`` or ``success_once`` (``impact_eval.reproduce_compare``); the output says so.
``reproduce --record TABLE ...`` (maintainers) writes the tables' manifest entries from their
current run.json and episodes.csv.
"""

from __future__ import annotations

import argparse
import shutil
import signal
import sys
import tempfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from impact_control.cli import signal_handler
from impact_control.errors import InvalidArgumentError
from impact_control.runinfo import cpu_info
from impact_eval.csvio import encode_rows, file_columns, older_columns_missing, read_rows, row_key
from impact_eval.grid import format_value
from impact_eval.report import FLOAT_COLUMNS
from impact_eval.reproduce_compare import (
    Cell,
    RowDiff,
    cell_diffs,
    cell_sizes,
    compare_rows,
    max_outcome_flips,
    row_lines,
)
from impact_eval.reproduce_manifest import (
    EPISODES_CSV,
    MANIFEST,
    Table,
    committed_problem,
    load_manifest,
    open_table,
    positive_int,
    record,
    sha256,
    table_entry,
)
from impact_eval.run_migration import spec_json_of
from impact_eval.runinfo import IDENTITY_JSON, RUN_JSON, package_versions
from impact_eval.sweep_command import _Parser, run_sweep_command

RESULTS = Path(__file__).resolve().parent.parent / "results"
PROG = "impact-eval reproduce"


def parse_cells(spec: str, sweep: dict) -> set[Cell]:
    """``method@value,...`` -> cells, each checked against the table's methods and grid
    (``sweep``: its spec, ``SweepSpec.to_json``'s keys); an empty spec or item is refused (it
    would otherwise rerun the whole table)."""
    methods = list(sweep["methods"])
    values = {format_value(float(v)) for v in sweep["values"]}
    valid = (f"METHOD@VALUE,... with METHOD in {', '.join(methods)} and VALUE in "
             f"{', '.join(sorted(values, key=float))}")
    items = [item.strip() for item in spec.split(",")]
    if not any(items):
        raise InvalidArgumentError(f"--cells {spec!r} names no cell; valid: {valid}")
    cells = set()
    for item in items:
        method, sep, value = item.rpartition("@")  # a composed method may hold an @
        try:
            text = format_value(float(value))
        except ValueError:
            text = None
        if not sep or method not in methods or text not in values:
            raise InvalidArgumentError(f"invalid cell {item!r} in --cells {spec!r}; valid: {valid}")
        cells.add((method, text))
    return cells


def seed_scratch(table: Table, scratch: Path, cells: set[Cell]) -> None:
    """Copy run.json and every committed row outside ``cells`` into ``scratch``."""
    scratch.mkdir(parents=True, exist_ok=True)
    for name in (RUN_JSON, IDENTITY_JSON):
        if (table.dir / name).exists():
            shutil.copy(table.dir / name, scratch / name)
    kept = [row for row in read_rows(table.dir / EPISODES_CSV, older=True)
            if row_key(row)[:2] not in cells]
    missing = older_columns_missing(file_columns(table.dir / EPISODES_CSV)) or ()
    # a table recorded before columns were added: its rows get them as "not measured" (nan for
    # a number, empty for text), so the sweep can resume into the scratch folder and its report
    # reads them; the comparison reads only the table's own columns
    filler = {c: "nan" if c in FLOAT_COLUMNS else "" for c in missing}
    (scratch / EPISODES_CSV).write_text(encode_rows({**row, **filler} for row in kept))


def parser() -> argparse.ArgumentParser:
    """Parser of ``impact-eval reproduce``."""
    p = _Parser(prog=PROG, description=__doc__.splitlines()[0])
    p.add_argument("tables", nargs="*", metavar="TABLE", help="table name (a results/ directory)")
    p.add_argument("--check", action="store_true", help="rerun and compare with the committed rows")
    p.add_argument("--cells", help="with --check: only these cells, METHOD@VALUE,...")
    p.add_argument("--list", action="store_true", help="list the tables of the manifest")
    p.add_argument("--record", action="store_true",
                   help="write the tables' manifest entries from their current files")
    p.add_argument("--out", type=Path, help="rerun directory, kept (default: TABLE/tmp/rerun "
                   "without --check, a temporary directory removed afterwards with --check)")
    p.add_argument("--workers", type=positive_int, help="worker processes of the rerun")
    p.add_argument("--envs-per-worker", type=positive_int,
                   help="lockstep envs per worker of the rerun")
    p.add_argument("--executor", default="local", choices=("local", "ray"),
                   help="local | ray")
    p.add_argument("--results", type=Path, default=RESULTS, help=argparse.SUPPRESS)
    return p


def _first_missing(path: Path) -> Path | None:
    """The topmost ancestor of ``path`` (or itself) that does not exist yet."""
    missing = None
    for candidate in (path, *path.parents):
        if candidate.exists() or candidate.is_symlink():
            break
        missing = candidate
    return missing


def rerun(table: Table, cells: set[Cell] | None, a: argparse.Namespace, out: Path,
          kept: bool) -> int:
    """Rerun ``table`` (or its ``cells``) into ``out``; print the comparison; exit code. On an
    error, whatever this call created is removed."""
    from impact_eval.prepare import check_out_dir

    check_out_dir(out)
    created = _first_missing(out)
    argv = [*table.entry["sweep_args"], "--out", str(out), "--executor", a.executor]
    for flag, value in (("--workers", a.workers), ("--envs-per-worker", a.envs_per_worker)):
        if value is not None:
            argv += [flag, str(value)]
    try:
        if cells is not None:
            seed_scratch(table, out, cells)
            argv += ["--resume", "--allow-code-change"]  # committed rows, checked byte by byte
        run_sweep_command(argv)
    except BaseException:  # an error, Ctrl-C or SIGTERM: no partial rerun is left
        if created is not None:
            shutil.rmtree(created, ignore_errors=True)
        raise
    return judge(table, cells, out, kept)


def judge(table: Table, cells: set[Cell] | None, out: Path, kept: bool) -> int:
    """Print every differing row and cell and the verdict; 0 if the rerun passes."""
    committed, fresh = table.dir / EPISODES_CSV, out / EPISODES_CSV
    rows = compare_rows(committed, fresh)
    for diff in cell_diffs(rows, cell_sizes(committed, fresh)):
        print(f"{PROG}: differs: {table.name}: {diff.line()}")
    for line in row_lines(rows):
        print(f"{PROG}: differs: {table.name}: {line}")
    digest, recorded = sha256(fresh), table.entry["episodes_sha256"]
    missing = older_columns_missing(file_columns(committed))
    same = (digest == recorded or missing is not None) and not rows
    if missing is not None:
        print(f"{PROG}: {table.name}: the committed table predates the columns "
              f"{', '.join(missing)}: compared value for value on its own columns, not as bytes")
    scope = ("cells " + ",".join(f"{m}@{float(v):g}" for m, v in sorted(cells))) if cells \
        else "the whole table"
    what = "values" if missing is not None else "bytes"
    print(f"{PROG}: {table.name} ({scope}): episodes.csv "
          f"{'identical' if same else 'DIFFERENT'} to the committed {what} "
          f"(sha256 {recorded[:12]}, rerun {digest[:12]}; {len(rows)} rows differ)"
          + (f"; rerun kept in {out}" if kept else ""))
    if same:
        return 0
    cpu, here = table.entry["cpu"], cpu_info()
    if (cpu["cpu_model"], cpu["simd"]) == (here["cpu_model"], here["simd"]):
        print(f"{PROG}: {table.name}: FAIL: rerun on the recording CPU ({here['cpu_model']}, "
              f"{here['simd']}), where the bytes must be identical")
        return 1
    return other_cpu_verdict(table, cells, rows, here)


def other_cpu_verdict(table: Table, cells: set[Cell] | None, rows: list[RowDiff],
                      here: dict[str, str]) -> int:
    """On another CPU: rows outside the rerun cells equal, none missing or extra, at most K of
    the n rerun episodes with a flipped outcome."""
    committed = [row_key(r) for r in read_rows(table.dir / EPISODES_CSV, older=True)]
    n = sum(cells is None or key[:2] in cells for key in committed)
    outside = sum(cells is not None and r.key[:2] not in cells for r in rows)
    presence = sum(bool(r.presence) for r in rows)
    flips = sum(bool(r.outcome) for r in rows if cells is None or r.key[:2] in cells)
    k = max_outcome_flips(n)
    ok = flips <= k and not presence and not outside
    cpu = table.entry["cpu"]
    print(f"{PROG}: {table.name}: recorded on {cpu['cpu_model']} ({cpu['simd']}), rerun on "
          f"{here['cpu_model']} ({here['simd']}): another CPU, so bytes are compared only on the "
          f"recording CPU; here {flips} of {n} rerun episodes flipped outcome (success, "
          f"success_once), at most K={k} allowed (docs/results.md, \"Reproducibility\"); "
          f"{presence} rows missing or extra; {outside} rows differ outside the rerun cells: "
          f"{'PASS' if ok else 'FAIL'}")
    return 0 if ok else 1


def list_tables(results: Path) -> int:
    """``--list``: one line per table (a damaged entry: one-line error)."""
    manifest = load_manifest(results)
    for name in sorted(manifest["tables"]):
        entry = table_entry(manifest, name, results)
        print(f"{name}: {entry['rows']} episodes, sha256 {entry['episodes_sha256'][:12]}, "
              f"{' '.join(entry['sweep_args'])}")
    return 0


def _open_all(a: argparse.Namespace) -> list[tuple[Table, set[Cell] | None]]:
    """Every named table, checked (and its --cells parsed) before anything runs."""
    if a.cells is not None and not a.check:
        raise InvalidArgumentError("--cells needs --check")
    tables = list(dict.fromkeys(a.tables))
    if len(tables) > 1 and a.out is not None:
        raise InvalidArgumentError("--out takes one TABLE")
    if a.out is not None:
        if a.out.exists() or a.out.is_symlink():
            raise InvalidArgumentError(f"--out {a.out} exists; give a new directory")
        from impact_eval.prepare import check_out_dir

        check_out_dir(a.out)  # creatable and writable, probed without residue
    manifest = load_manifest(a.results)
    opened = [open_table(a.results, manifest, name) for name in tables]
    return [(t, None if a.cells is None else parse_cells(a.cells, spec_json_of(t.run)))
            for t in opened]


def _run_one(table: Table, cells: set[Cell] | None, a: argparse.Namespace) -> int:
    """Rerun one table into --out, its tmp/rerun (kept) or a temporary directory (removed).
    Ctrl-C or SIGTERM: one stderr line saying what is left of the rerun, exit 130 or 128 + N."""
    out = a.out
    try:
        if a.out is not None:
            return rerun(table, cells, a, a.out, kept=True)
        if not a.check:
            out = table.dir / "tmp" / "rerun"  # ignored by git; the previous rerun is replaced
            shutil.rmtree(out, ignore_errors=True)
            return rerun(table, cells, a, out, kept=True)
        with tempfile.TemporaryDirectory(prefix=f"reproduce_{table.dir.name}_") as tmp:
            return rerun(table, cells, a, Path(tmp) / table.dir.name, kept=False)
    except (KeyboardInterrupt, Terminated) as exc:
        code = exc.code if isinstance(exc, Terminated) else 130
        what = f"terminated (signal {code - 128})" if isinstance(exc, Terminated) \
            else "interrupted"
        print(f"{PROG}: {table.name}: {what}; {_left_behind(out)}", file=sys.stderr, flush=True)
        raise SystemExit(code) from None


def _left_behind(out: Path | None) -> str:
    """What an interrupted rerun leaves: nothing (a sweep stopped midway is removed, and
    reproduce does not resume one), or a rerun that had finished, in its kept folder."""
    if out is not None and (out / EPISODES_CSV).is_file():
        return f"the finished rerun is kept in {out}, not compared"
    return ("the rerun folder was removed and nothing is kept (reproduce does not resume a "
            "rerun); run the same command again to start it over")


class Terminated(SystemExit):
    """SIGTERM during a rerun (exit code 128 + the signal)."""


def _terminated(signum: int, frame: object) -> None:
    raise Terminated(128 + signum)


@contextmanager
def sigterm_unwinds() -> Iterator[None]:
    """SIGTERM (``timeout``, CI) raises ``Terminated`` (a SystemExit), so the rerun's folders
    are removed."""
    with signal_handler(signal.SIGTERM, _terminated):
        yield


def main(argv: Sequence[str]) -> int:
    """``impact-eval reproduce ...``; returns the exit code (bad input: InvalidArgumentError).
    Ctrl-C outside a rerun: one line, exit 130 (no "--resume": there is nothing to
    resume; during a rerun ``_run_one`` says what is left)."""
    try:
        return _main(argv)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted; no rerun was under way, nothing to resume",
              file=sys.stderr, flush=True)
        return 130


def _main(argv: Sequence[str]) -> int:
    a = parser().parse_args(argv)
    if a.list:
        return list_tables(a.results)
    if not a.tables:
        raise InvalidArgumentError("name a TABLE (impact-eval reproduce --list shows them)")
    if a.record:
        record(a.results, a.tables)
        print(f"{PROG}: recorded {', '.join(a.tables)} in {a.results / MANIFEST}")
        return 0
    opened = _open_all(a)
    problems = [(t.name, p) for t, _ in opened if (p := committed_problem(t))]
    for name, problem in problems:
        print(f"{PROG}: {name}: FAIL before any rerun: {problem}")
    if problems:
        return 1
    print(f"{PROG}: library versions here: {package_versions()}")
    with sigterm_unwinds():
        return max(_run_one(table, cells, a) for table, cells in opened)
