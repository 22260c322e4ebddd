"""What the -v1 rerun changed (impact_experiments/version_flips.py), over a small git
repository of the test's own: the pairing, the report (each side's env version and CPU), and
its refusals: a --before that is not a version change, a bad --before, --results or --out
(one stderr line, exit 2, nothing written)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from impact_experiments.version_flips import main, report, table_flips

ROWS = "a,IMPACT/Hammer-vVER,1,0,True,True\na,IMPACT/Hammer-vVER,1,1,{},True\n"
HEAD = "method,env_id,param_value,episode,success,success_once\n"


def _git(repo: Path, *args: str) -> None:
    subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=repo,
                   check=True, capture_output=True)


def _commit_table(repo: Path, version: int, rows: str, cpu: dict, entry: dict | None = None,
                  tag: str | None = None) -> None:
    """Commit results/t (rows of ``version``) and a manifest entry (default: as recorded,
    with ``env_version`` from v1 on; ``entry`` replaces it, ``{}`` for none)."""
    table = repo / "results" / "t"
    table.mkdir(parents=True, exist_ok=True)
    (table / "episodes.csv").write_text(HEAD + rows.replace("VER", str(version)))
    if entry is None:
        entry = {"sweep_args": ["--env", f"IMPACT/Hammer-v{version}"], "cpu": cpu}
        if version:
            entry["env_version"] = version
    tables = {"t": entry} if entry else {}
    (repo / "results" / "manifest.json").write_text(json.dumps({"tables": tables}))
    _git(repo, "add", "-A")
    _git(repo, "commit", "-qm", f"v{version}")
    if tag:
        _git(repo, "tag", tag)


@pytest.fixture()
def repo(tmp_path: Path) -> Path:
    """A repository whose table t ran -v0 at tag ``before`` (on Intel) and -v1 now (AMD)."""
    _git(tmp_path, "init", "-q")
    _commit_table(tmp_path, 0, ROWS.format("False"), {"cpu_model": "Intel", "simd": "avx512"},
                  tag="before")
    _commit_table(tmp_path, 1, ROWS.format("True"), {"cpu_model": "AMD EPYC", "simd": "avx2"},
                  tag="after")
    return tmp_path


def _refused(capsys: pytest.CaptureFixture[str], *argv: str) -> str:
    """Run ``version_flips ARGV``: it must exit 2 with one stderr line and print nothing."""
    with pytest.raises(SystemExit) as info:
        main(list(argv))
    captured = capsys.readouterr()
    err = captured.err.splitlines()
    assert info.value.code == 2 and len(err) == 1 and captured.out == "", captured
    assert err[0].startswith("version_flips: error: ")
    return err[0]


def test_version_flips_pairs_episodes_and_counts_outcome_changes() -> None:
    before = HEAD + ("a,IMPACT/Hammer-v0,1,0,True,True\na,IMPACT/Hammer-v0,1,1,False,True\n"
                     "b,IMPACT/Hammer-v0,1,0,True,True\n")
    after = HEAD + ("a,IMPACT/Hammer-v1,1,0,True,True\na,IMPACT/Hammer-v1,1,1,True,True\n"
                    "b,IMPACT/Hammer-v1,2,0,True,True\n")
    r = table_flips(before, after)
    assert (r["rows"], r["missing"], r["flips"]) == (3, 2, 1)
    assert r["methods"] == {"a": (1, 2)}  # b has no episode on both sides
    assert r["cells"] == {("a", "1"): (1, 2, 2)}  # the one cell whose successes moved


def test_report_names_each_sides_version_and_cpu(repo: Path, capsys) -> None:
    lines = report(repo / "results", "before").splitlines()
    assert lines[0].startswith("Rows of each table rerun on -v1 against its -v0 rows at before")
    assert "successes per method, v0 -> v1 | recorded on, v0 -> v1 |" in lines[2]
    assert lines[-2] == "| t | 2 | 0 | 1 | a 1->2 | Intel avx512 -> AMD EPYC avx2 |"
    assert lines[-1] == "| all | 2 | 0 | 1 | | |"
    out = repo / "flips.md"
    assert main(["--before", "before", "--results", str(repo / "results"), "--cells",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert text == out.read_text() and text.startswith(
        "Cells whose successes moved from the -v0 rows at before to the -v1 rerun:")


@pytest.mark.parametrize("rev", ["after", "HEAD"])
def test_a_revision_on_the_same_version_is_refused(repo: Path, capsys, rev: str) -> None:
    """The -v1 tables against themselves: not a version change, so not "0 flips"."""
    line = _refused(capsys, "--before", rev, "--results", str(repo / "results"), "--cells")
    assert line == (f"version_flips: error: --before {rev} is not a version change for t: its "
                    "rows there ran -v1, now -v1; give a revision whose t ran an earlier version")


@pytest.mark.parametrize("entry", [
    {"sweep_args": ["--env", "IMPACT/Hammer-v1"]},  # recorded without env_version: the id
    {},  # not in the manifest there: its rows' env_id
])
def test_the_version_before_is_read_without_env_version(repo: Path, capsys, entry: dict) -> None:
    _commit_table(repo, 1, ROWS.format("True"), {}, entry=entry, tag="v1_unversioned")
    _commit_table(repo, 1, ROWS.format("False"), {"cpu_model": "AMD EPYC", "simd": "avx2"})
    line = _refused(capsys, "--before", "v1_unversioned", "--results", str(repo / "results"))
    assert "its rows there ran -v1, now -v1" in line


def test_rows_of_mixed_versions_cannot_be_told_and_are_refused(repo: Path, capsys) -> None:
    mixed = "a,IMPACT/Hammer-v0,1,0,True,True\na,IMPACT/Hammer-v1,1,1,True,True\n"
    _commit_table(repo, 1, mixed, {}, entry={}, tag="mixed")
    _commit_table(repo, 1, ROWS.format("True"), {"cpu_model": "AMD EPYC", "simd": "avx2"})
    line = _refused(capsys, "--before", "mixed", "--results", str(repo / "results"))
    assert "its rows there ran an env version that cannot be told, now -v1" in line


def test_a_bad_revision_or_manifest_there_is_one_line(repo: Path, capsys) -> None:
    results = str(repo / "results")
    line = _refused(capsys, "--before", "no_such_rev", "--results", results)
    assert "cannot read results/manifest.json at --before no_such_rev" in line
    (repo / "results" / "manifest.json").write_text("{not json")
    _git(repo, "commit", "-qam", "damaged")
    (repo / "results" / "manifest.json").write_text(
        json.dumps({"tables": {"t": {"sweep_args": ["--env", "IMPACT/Hammer-v1"],
                                     "env_version": 1}}}))
    line = _refused(capsys, "--before", "HEAD", "--results", results)
    assert line.startswith("version_flips: error: cannot read results/manifest.json at "
                           "--before HEAD: ")


def test_a_bad_results_is_one_line(tmp_path: Path, capsys) -> None:
    line = _refused(capsys, "--before", "HEAD", "--results", str(tmp_path / "missing"))
    assert line == f"version_flips: error: no manifest.json in {tmp_path / 'missing'}"
    (tmp_path / "manifest.json").write_text("[1, 2]")
    line = _refused(capsys, "--before", "HEAD", "--results", str(tmp_path))
    assert line.startswith(f"version_flips: error: cannot read {tmp_path / 'manifest.json'}")


@pytest.mark.parametrize("where", ["a_directory", "missing/flips.md", "a_file/flips.md"])
def test_an_out_that_cannot_be_written_is_one_line_and_nothing_is_written(
        repo: Path, capsys, where: str) -> None:
    (repo / "a_directory").mkdir()
    (repo / "a_file").write_text("x")
    before = sorted(p.name for p in repo.rglob("*") if ".git" not in p.parts)
    line = _refused(capsys, "--before", "before", "--results", str(repo / "results"),
                    "--out", str(repo / where))
    assert line.startswith(f"version_flips: error: cannot write --out {repo / where}: ")
    assert sorted(p.name for p in repo.rglob("*") if ".git" not in p.parts) == before


def test_a_manifest_without_a_current_table_is_one_line(repo: Path, capsys) -> None:
    """Nothing rerun on the current version: refused, not an empty table of "0 flips"."""
    _commit_table(repo, 0, ROWS.format("True"), {})
    line = _refused(capsys, "--before", "before", "--results", str(repo / "results"))
    assert line.endswith("is recorded on its env's current version (env_version); nothing to "
                         "compare")
