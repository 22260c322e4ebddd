"""impact-eval reproduce on bad or damaged input: one stderr line naming what is wrong, exit 2,
nothing rerun, and the results directory, the temporary directory and ``--out`` exactly as
before (nothing written, nothing deleted)."""

from __future__ import annotations

import json
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

import pytest
from fixtures.reproduce_fake import TABLE, record_fake_table, reproduce, set_entry, snapshot

Setup = Callable[[Path, Path], list[str]]
"""(results, tmp_path) -> the arguments; may damage ``results`` first."""


def _args(*args: str) -> Setup:
    return lambda results, tmp: [a.replace("{tmp}", str(tmp)) for a in args]


def _entry(**values: object) -> Setup:
    def setup(results: Path, tmp: Path) -> list[str]:
        set_entry(results, **values)
        return ["--check", TABLE]
    return setup


def _write(name: str, text: str | None, *args: str) -> Setup:
    """Replace (``None``: delete) ``results/<name>``, then run ``args`` (default --check)."""
    def setup(results: Path, tmp: Path) -> list[str]:
        path = results / name
        if text is None:
            shutil.rmtree(path) if path.is_dir() else path.unlink()
        else:
            path.write_text(text)
        return list(args) or ["--check", TABLE]
    return setup


def _truncate_run_json(results: Path, tmp: Path) -> list[str]:
    path = results / TABLE / "run.json"
    path.write_bytes(path.read_bytes()[:200])
    return ["--check", TABLE, "--cells", "fake_fast@1"]


def _out_under_a_file(results: Path, tmp: Path) -> list[str]:
    (tmp.parent / "a_file").write_text("mine\n")
    return ["--check", TABLE, "--cells", "fake_fast@1", "--out", str(tmp.parent / "a_file" / "x")]


def _unknown_env(*extra: str) -> Setup:
    """A manifest whose sweep fails inside the rerun (after --out or the scratch was made)."""
    def setup(results: Path, tmp: Path) -> list[str]:
        entry = json.loads((results / "manifest.json").read_text())["tables"][TABLE]
        args = entry["sweep_args"]
        args[args.index("--env") + 1] = "IMPACT/Nope-v0"
        set_entry(results, sweep_args=args)
        return ["--check", TABLE, "--out", str(tmp / "deep" / "rerun"), *extra]
    return setup


CELLS = "valid: METHOD@VALUE,... with METHOD in fake_fast, fake_slow and VALUE in 0.5, 1.0, 3.0"
C = ("--check", TABLE)
CASES: dict[str, tuple[Setup, str]] = {
    "empty cells": (_args(*C, "--cells", ""), f"--cells '' names no cell; {CELLS}"),
    "blank cells": (_args(*C, "--cells", " , "), "names no cell"),
    "trailing comma": (_args(*C, "--cells", "fake_fast@1,"), "invalid cell ''"),
    "unknown value": (_args(*C, "--cells", "fake_fast@7"), "invalid cell 'fake_fast@7'"),
    "unknown method": (_args(*C, "--cells", "scripted@1"), "invalid cell 'scripted@1'"),
    "no @": (_args(*C, "--cells", "fake_fast"), "invalid cell 'fake_fast'"),
    "cells without check": (_args(TABLE, "--cells", "fake_fast@1"), "--cells needs --check"),
    "no table": (_args("--check"), "name a TABLE"),
    "unknown table": (_args("--check", "nope"), "unknown table 'nope'; valid choices: fake"),
    "two tables, one out": (_args(*C, "other", "--out", "{tmp}/o"), "--out takes one"),
    "out exists": (_args(*C, "--out", "{tmp}"), "exists; give a new directory"),
    "out under a file": (_out_under_a_file, "is not writable"),
    "zero workers": (_args(*C, "--workers", "0"), "'0' is not an integer >= 1"),
    "bad envs per worker": (_args(*C, "--envs-per-worker", "x"), "not an integer"),
    "bad executor": (_args(*C, "--executor", "dask"), "invalid choice: 'dask'"),
    "no sweep_args": (_entry(sweep_args=None),
                      "entry of table 'fake' is damaged (no 'sweep_args')"),
    "no sha256": (_entry(episodes_sha256=None), "(no 'episodes_sha256')"),
    "short sha256": (_entry(episodes_sha256="abc"), "'episodes_sha256' is not 64 hex digits"),
    "no rows": (_entry(rows=None), "(no 'rows')"),
    "rows a bool": (_entry(rows=True), "'rows' is not a count >= 0"),
    "no cpu": (_entry(cpu=None), "(no 'cpu')"),
    "no dir": (_entry(dir=None), "(no 'dir')"),
    "dir escapes": (_entry(dir="../elsewhere"), "'dir' is not a relative directory name"),
    "sweep_args with out": (_entry(sweep_args=["--env", "x", "--out", "y"]), "without --out"),
    "sweep_args empty": (_entry(sweep_args=[]), "'sweep_args' is not a list of strings"),
    "entry not an object": (_write("manifest.json", '{"tables": {"fake": [1]}}'),
                            "entry of table 'fake' is damaged (not a JSON object)"),
    "run.json truncated, whole table": (_write(f"{TABLE}/run.json", '{"args": {"meth'),
                                        "cannot read"),
    "table folder missing": (_write(TABLE, None), "table directory"),
    "episodes.csv missing": (_write(f"{TABLE}/episodes.csv", None), "has no episodes.csv"),
    "run.json missing": (_write(f"{TABLE}/run.json", None), "has no run.json"),
    "run.json truncated": (_truncate_run_json, "cannot read"),
    "run.json a list": (_write(f"{TABLE}/run.json", "[1, 2]"), "is not a JSON object"),
    "run.json without a spec": (_write(f"{TABLE}/run.json", "{}"), "records no sweep spec"),
    "run.json bad methods": (_write(f"{TABLE}/run.json", '{"identity": {"spec": {"methods": 3}}}'),
                             "'methods' is not a list of names"),
    "manifest missing": (_write("manifest.json", None), "no manifest.json in"),
    "manifest not json": (_write("manifest.json", "{tables"), "cannot read"),
    "manifest without tables": (_write("manifest.json", '{"tables": []}'), "no 'tables' object"),
    "list a damaged entry": (lambda r, t: _entry(rows="18")(r, t)[:0] + ["--list"],
                             "'rows' is not a count"),
    "record a truncated run.json": (lambda r, t: _truncate_run_json(r, t)[:0] + ["--record", TABLE],
                                    "cannot read"),
    "record a missing table": (_args("--record", "nope"), "table directory"),
    "record outside results": (_args("--record", "../x"), "invalid table name '../x'"),
    "sweep fails in the rerun": (_unknown_env(), "IMPACT/Nope-v0"),
    "sweep fails after the scratch": (_unknown_env("--cells", "fake_fast@1"), "IMPACT/Nope-v0"),
}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return record_fake_table(tmp_path_factory.mktemp("recorded") / "results")


def _scratch() -> set[str]:
    return {p.name for p in Path(tempfile.gettempdir()).glob(f"reproduce_{TABLE}_*")}


@pytest.mark.parametrize("name", list(CASES))
def test_bad_input_is_one_line_exit_2_and_changes_nothing(recorded: Path, tmp_path: Path,
                                                          capsys, name: str) -> None:
    setup, message = CASES[name]
    results = Path(shutil.copytree(recorded, tmp_path / "results"))
    work = tmp_path / "work"
    work.mkdir()
    args = setup(results, work)
    before, scratch = snapshot(results), _scratch()
    code, out, err = reproduce(results, capsys, *args)
    assert code == 2, out + err
    assert message in err, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "library versions here" not in out or name.startswith("sweep fails")
    assert snapshot(results) == before and _scratch() == scratch
    assert [p.name for p in work.iterdir()] == []  # no --out left behind
