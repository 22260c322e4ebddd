"""impact-eval reproduce: manifest, whole-table and per-cell checks, tamper detection, bad input.

Runs on the fake env of ``fixtures.eval_fake`` (milliseconds per episode) in subprocesses, with a
results directory of the test's own (``--results``).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from fixtures.eval_fake import ENV_ID, run_cli

SWEEP = ["--env", ENV_ID, "--method", "fake_fast,fake_slow", "--masses", "0.5,1,3",
         "--episodes", "3", "--workers", "2", "--envs-per-worker", "2"]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A results directory with one recorded table, ``fake`` (swept once per module)."""
    root = tmp_path_factory.mktemp("recorded") / "results"
    done = run_cli(*SWEEP, "--out", str(root / "fake"))
    assert done.returncode == 0, done.stderr
    rec = run_cli("reproduce", "--record", "fake", "--results", str(root))
    assert rec.returncode == 0, rec.stderr
    return root


@pytest.fixture()
def results(recorded: Path, tmp_path: Path) -> Path:
    """A copy of ``recorded`` of the test's own (tests change files in it)."""
    return Path(shutil.copytree(recorded, tmp_path / "results"))


def reproduce(results: Path, *args: str):
    return run_cli("reproduce", *args, "--results", str(results))


def test_manifest_records_command_versions_and_hash(results: Path) -> None:
    entry = json.loads((results / "manifest.json").read_text())["tables"]["fake"]
    assert entry["rows"] == 2 * 3 * 3
    assert entry["sweep_args"][:2] == ["--env", ENV_ID]
    assert "--out" not in entry["sweep_args"] and "--workers" not in entry["sweep_args"]
    assert entry["versions"]["mujoco"] and entry["git"]["sha"]
    assert len(entry["episodes_sha256"]) == 64
    listed = reproduce(results, "--list")
    assert listed.returncode == 0 and listed.stdout.startswith("fake: 18 episodes")


@pytest.mark.parametrize("extra", [[], ["--workers", "1"], ["--envs-per-worker", "1"]])
def test_whole_table_rerun_is_byte_identical(results: Path, extra: list[str]) -> None:
    done = reproduce(results, "--check", "fake", *extra)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "episodes.csv identical" in done.stdout


def test_cells_are_rerun_through_resume_and_compared(results: Path, tmp_path: Path) -> None:
    out = tmp_path / "rerun"
    done = reproduce(results, "--check", "fake", "--cells", "fake_slow@1,fake_fast@3",
                     "--out", str(out))
    assert done.returncode == 0, done.stdout + done.stderr
    runs = json.loads((out / "run.json").read_text())["invocations"]
    assert runs[-1]["resume"] and runs[-1]["episodes_run"] == 6  # the two cells only


def test_a_changed_row_is_reported_by_cell(results: Path) -> None:
    path = results / "fake" / "episodes.csv"
    lines = path.read_text().splitlines(keepends=True)
    i = next(k for k, line in enumerate(lines) if line.startswith("fake_slow,") and ",1.0," in line)
    fields = lines[i].split(",")
    fields[6] = "1" if fields[6] == "0" else "0"  # flip the outcome of one episode
    lines[i] = ",".join(fields)
    path.write_text("".join(lines))
    checked = reproduce(results, "--check", "fake", "--cells", "fake_slow@1")
    assert checked.returncode == 1, checked.stdout
    assert "differs: fake: fake_slow @ 1: 1/3 episodes differ (1 in outcome" in checked.stdout
    other = reproduce(results, "--check", "fake", "--cells", "fake_fast@0.5")
    assert other.returncode == 1  # the tampered row is copied, but the manifest's hash differs
    assert "DIFFERENT" in other.stdout


def _set_recorded_cpu(results: Path, cpu: dict) -> None:
    path = results / "manifest.json"
    manifest = json.loads(path.read_text())
    manifest["tables"]["fake"]["cpu"] = cpu
    path.write_text(json.dumps(manifest))


def _edit_first_row(results: Path, column: int, value: str) -> None:
    path = results / "fake" / "episodes.csv"
    lines = path.read_text().splitlines(keepends=True)
    fields = lines[1].split(",")
    fields[column] = value
    lines[1] = ",".join(fields)
    path.write_text("".join(lines))


def test_the_manifest_records_the_cpu(results: Path) -> None:
    entry = json.loads((results / "manifest.json").read_text())["tables"]["fake"]
    assert set(entry["cpu"]) == {"cpu_model", "simd"} and entry["cpu"]["simd"]


def test_on_another_cpu_floats_may_differ_but_outcomes_may_not(results: Path) -> None:
    _set_recorded_cpu(results, {"cpu_model": "Some Other CPU", "simd": "avx2"})
    _edit_first_row(results, 10, "123.456")  # energy_j: a float column
    floats = reproduce(results, "--check", "fake")
    assert floats.returncode == 0, floats.stdout + floats.stderr
    assert "DIFFERENT" in floats.stdout and "0 episode outcomes differ" in floats.stdout
    path = results / "fake" / "episodes.csv"
    row = path.read_text().splitlines()[1].split(",")
    _edit_first_row(results, 6, "0" if row[6] == "1" else "1")  # success
    outcome = reproduce(results, "--check", "fake")
    assert outcome.returncode == 1 and "1 episode outcomes differ" in outcome.stdout


def test_on_the_recording_cpu_any_byte_fails(results: Path) -> None:
    _edit_first_row(results, 10, "123.456")
    done = reproduce(results, "--check", "fake")
    assert done.returncode == 1 and "DIFFERENT" in done.stdout


@pytest.mark.parametrize("args,message", [
    (["--check", "nope"], "unknown table 'nope'; valid choices: fake"),
    (["--check", "fake", "--cells", "fake_fast@7"], "invalid cell 'fake_fast@7'"),
    (["--check", "fake", "--cells", "scripted@1"], "invalid cell 'scripted@1'"),
    (["fake", "--cells", "fake_fast@1"], "--cells needs --check"),
    ([], "name a TABLE"),
])
def test_bad_input_is_one_line_exit_2(results: Path, args: list[str], message: str) -> None:
    done = reproduce(results, *args)
    assert done.returncode == 2
    assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1
