"""impact-eval reproduce: manifest, whole-table and per-cell reruns, where the rerun goes.

In-process on the fake env of ``fixtures.eval_fake`` with a results directory of the test's own
(``--results``; ``fixtures.reproduce_fake``). The other-CPU rule and row naming:
test_reproduce_cpu.py; bad and damaged input: test_reproduce_inputs.py.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import tempfile
import threading
from pathlib import Path

import pytest
from fixtures.eval_fake import ENV_ID, run_cli
from fixtures.reproduce_fake import (
    ROWS,
    TABLE,
    manifest,
    record_fake_table,
    reproduce,
    snapshot,
)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A results directory with one recorded table, ``fake`` (swept once per module)."""
    return record_fake_table(tmp_path_factory.mktemp("recorded") / "results")


@pytest.fixture()
def results(recorded: Path, tmp_path: Path) -> Path:
    """A copy of ``recorded`` of the test's own (tests change files in it)."""
    return Path(shutil.copytree(recorded, tmp_path / "results"))


def _scratch_dirs() -> set[str]:
    return {p.name for p in Path(tempfile.gettempdir()).glob(f"reproduce_{TABLE}_*")}


def test_manifest_records_command_versions_cpu_and_hash(results: Path, capsys) -> None:
    entry = manifest(results)["tables"][TABLE]
    assert entry["rows"] == ROWS
    assert entry["sweep_args"][:2] == ["--env", ENV_ID]
    assert "--out" not in entry["sweep_args"] and "--workers" not in entry["sweep_args"]
    assert entry["versions"]["mujoco"] and entry["git"]["sha"]
    assert len(entry["episodes_sha256"]) == 64
    assert set(entry["cpu"]) == {"cpu_model", "simd"} and entry["cpu"]["simd"]
    code, out, _ = reproduce(results, capsys, "--list")
    assert code == 0 and out.startswith(f"fake: {ROWS} episodes")


@pytest.mark.parametrize("extra", [[], ["--envs-per-worker", "1"]])
def test_whole_table_check_is_identical_and_leaves_no_folder(results: Path, capsys,
                                                              extra: list[str]) -> None:
    before = _scratch_dirs()
    code, out, _ = reproduce(results, capsys, "--check", TABLE, *extra)
    assert code == 0, out
    assert "(the whole table): episodes.csv identical to the committed bytes" in out
    assert "0 rows differ" in out
    assert "kept in" not in out and "rerun in" not in out  # the temporary folder is gone
    assert _scratch_dirs() == before


def test_cells_are_rerun_through_resume_and_kept_with_out(results: Path, tmp_path: Path,
                                                          capsys) -> None:
    out_dir = tmp_path / "rerun"
    code, out, _ = reproduce(results, capsys, "--check", TABLE, "--cells",
                             "fake_slow@1,fake_fast@3", "--out", str(out_dir))
    assert code == 0, out
    assert f"rerun kept in {out_dir}" in out
    assert "(cells fake_fast@3,fake_slow@1)" in out
    runs = json.loads((out_dir / "run.json").read_text())["invocations"]
    assert runs[-1]["resume"] and runs[-1]["episodes_run"] == 6  # the two cells only


def test_rerun_without_check_is_kept_in_the_tables_tmp(results: Path, capsys) -> None:
    code, out, _ = reproduce(results, capsys, TABLE)
    kept = results / TABLE / "tmp" / "rerun"
    assert code == 0, out
    assert f"rerun kept in {kept}" in out and (kept / "episodes.csv").is_file()
    again, out, _ = reproduce(results, capsys, TABLE)  # replaces its own previous rerun
    assert again == 0 and f"rerun kept in {kept}" in out


def test_a_table_named_twice_is_rerun_once(results: Path, capsys) -> None:
    code, out, _ = reproduce(results, capsys, "--check", TABLE, TABLE)
    assert code == 0 and out.count("identical to the committed bytes") == 1


@pytest.mark.slow
def test_console_entry_point_checks_a_cell(results: Path) -> None:
    """The installed command's path (``python -m impact_eval``; ~10-30 s: a fresh interpreter
    imports the package), one cell."""
    done = run_cli("reproduce", "--check", TABLE, "--cells", "fake_fast@0.5", "--workers", "1",
                   "--results", str(results))
    assert done.returncode == 0, done.stdout + done.stderr
    assert "identical to the committed bytes" in done.stdout


@pytest.mark.slow
@pytest.mark.parametrize("extra", [["--workers", "2"],
                                   ["--workers", "2", "--envs-per-worker", "2"]])
def test_worker_processes_give_the_same_bytes(results: Path, capsys, extra: list[str]) -> None:
    """Worker processes (~20 s: each imports the package) rerun the same bytes."""
    code, out, _ = reproduce(results, capsys, "--check", TABLE, *extra)
    assert code == 0 and "identical to the committed bytes" in out, out


@pytest.mark.parametrize("keep", [False, True])
def test_sigterm_mid_rerun_leaves_no_folder(results: Path, tmp_path: Path, capsys,
                                            monkeypatch: pytest.MonkeyPatch, keep: bool) -> None:
    """``timeout`` (CI) sends SIGTERM: the temporary or --out folder is removed, exit 143."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    monkeypatch.setenv("IMPACT_FAKE_STEP_DELAY", "0.01")  # ~5 s of episodes: stopped at 0.5 s
    out_dir = tmp_path / "kept" / "rerun"
    before = signal.getsignal(signal.SIGTERM)  # SIG_DFL, or a session's Ray instance's
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGTERM))
    timer.start()
    try:
        with pytest.raises(SystemExit) as stopped:
            reproduce(results, capsys, "--check", TABLE, *(["--out", str(out_dir)] if keep else []))
    finally:
        timer.cancel()
    assert stopped.value.code == 128 + signal.SIGTERM
    err = [line for line in capsys.readouterr().err.splitlines() if "reproduce:" in line]
    assert len(err) == 1 and "fake: terminated (signal 15); the rerun folder was removed" in err[0]
    assert list(scratch.iterdir()) == [] and not (tmp_path / "kept").exists()
    assert signal.getsignal(signal.SIGTERM) is before  # the handler is restored


def _interrupted_sweep(argv: list[str]) -> int:
    """Stand-in for the rerun's sweep: a first row written, then Ctrl-C."""
    out = Path(argv[argv.index("--out") + 1])
    out.mkdir(parents=True, exist_ok=True)
    (out / "episodes.csv").write_text("method,param_value,episode\nfake_fast,0.5,0\n")
    raise KeyboardInterrupt


@pytest.mark.parametrize("mode", [["--check"], ["--check", "--cells", "fake_fast@1"],
                                  ["--check", "--out", "OUT"], []])
def test_ctrl_c_mid_rerun_says_nothing_is_kept_and_leaves_nothing(
        results: Path, tmp_path: Path, capsys, monkeypatch: pytest.MonkeyPatch,
        mode: list[str]) -> None:
    """Ctrl-C in the sweep (any mode: temporary folder, --cells, --out, the table's tmp/rerun):
    one stderr line that does not offer a --resume there is nothing for, exit 130, and the
    rerun folder is gone (the results tree is as it was)."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    monkeypatch.setattr("impact_eval.reproduce.run_sweep_command", _interrupted_sweep)
    out_dir = tmp_path / "kept" / "rerun"
    before = snapshot(results)
    with pytest.raises(SystemExit) as stopped:
        reproduce(results, capsys, TABLE, *[str(out_dir) if m == "OUT" else m for m in mode])
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert stopped.value.code == 130 and len(err) == 1, captured
    assert err[0].startswith("impact-eval reproduce: fake: interrupted; the rerun folder was "
                             "removed and nothing is kept")
    assert "--resume" not in err[0] and "Traceback" not in captured.out + captured.err
    assert list(scratch.iterdir()) == [] and not (tmp_path / "kept").exists()
    assert snapshot(results) == before


def test_ctrl_c_after_a_kept_rerun_finished_names_its_folder(
        results: Path, tmp_path: Path, capsys, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C while the finished rerun is compared: its --out folder is kept and the line
    says so (not "removed")."""
    def interrupted(*_: object) -> int:
        raise KeyboardInterrupt

    monkeypatch.setattr("impact_eval.reproduce.judge", interrupted)
    out_dir = tmp_path / "rerun"
    with pytest.raises(SystemExit) as stopped:
        reproduce(results, capsys, "--check", TABLE, "--out", str(out_dir))
    err = [line for line in capsys.readouterr().err.splitlines() if "reproduce:" in line]
    assert stopped.value.code == 130  # (the sweep's progress bar is the other stderr output)
    assert err == [f"impact-eval reproduce: fake: interrupted; the finished rerun is kept in "
                   f"{out_dir}, not compared"]
    assert (out_dir / "episodes.csv").read_bytes() == (results / TABLE / "episodes.csv"
                                                       ).read_bytes()


def test_ctrl_c_before_a_rerun_offers_no_resume(results: Path, capsys,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    def interrupted(*_: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr("impact_eval.reproduce.committed_problem", interrupted)
    code, _, err = reproduce(results, capsys, "--check", TABLE)
    assert code == 130
    assert err == "impact-eval reproduce: interrupted; no rerun was under way, nothing to resume\n"
