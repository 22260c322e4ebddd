"""SIGKILL an impact-eval sweep mid-run, resume it, and compare with an uninterrupted run."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from fixtures.eval_fake import REPO, cli_env, run_cli, sweep_args

from impact_eval.cli import main


def _rows(path: Path) -> int:
    """Complete data rows in a CSV being written (0 if it does not exist yet)."""
    try:
        return max(0, path.read_bytes().count(b"\n") - 1)
    except FileNotFoundError:
        return 0


def _live_members(pgid: int) -> list[int]:
    """Non-zombie processes of process group ``pgid`` (Linux /proc)."""
    pids = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()
        if int(fields[2]) == pgid and fields[0] != "Z":
            pids.append(int(entry.name))
    return pids


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_sigkill_then_resume_equals_uninterrupted_run(tmp_path: Path) -> None:
    reference, killed = tmp_path / "reference", tmp_path / "killed"
    proc = run_cli(*sweep_args(reference, "--workers", "2"))
    assert proc.returncode == 0, proc.stderr
    total = _rows(reference / "episodes.csv")
    env = {**cli_env(), "IMPACT_FAKE_STEP_DELAY": "0.004"}  # slow, same results
    cmd = [sys.executable, "-m", "impact_eval", *sweep_args(killed, "--workers", "2")]
    child = subprocess.Popen(
        cmd,
        env=env,
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 60
        while _rows(killed / "episodes.csv") < 8 and time.monotonic() < deadline:
            assert child.poll() is None, "sweep ended before it could be killed"
            time.sleep(0.02)
        os.kill(child.pid, signal.SIGKILL)
        child.wait()
        done = _rows(killed / "episodes.csv")
        assert 8 <= done < total, "the kill did not land mid-run"
        deadline = time.monotonic() + 15  # orphaned workers notice and exit
        while _live_members(child.pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _live_members(child.pid), "workers outlived the killed parent"
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(child.pid, signal.SIGKILL)
    proc = run_cli(*sweep_args(killed, "--workers", "2", "--resume"))
    assert proc.returncode == 0, proc.stderr
    assert f"({done} already done, {total} in total)" in proc.stdout
    assert (killed / "episodes.csv").read_text() == (reference / "episodes.csv").read_text()


@pytest.mark.parametrize("change, message", [
    (("--method", "fake_fast"), "cannot resume: methods"),
    (("--episodes", "6"), "cannot resume: episodes was 5"),
    (("--masses", "0.5,3"), "cannot resume: values"),
    (("--seed", "12"), "cannot resume: seed"),
])
def test_resume_refuses_changes_that_mix_episode_counts(tmp_path, capsys, change, message):
    out = tmp_path / "run"
    args = sweep_args(out, "--workers", "1", masses="0.5,2")
    args[args.index("--method") + 1] = "fake_fast,fake_impact"
    assert main(args) == 0
    before = (out / "episodes.csv").read_bytes(), (out / "run.json").read_bytes()
    changed = [*args, "--resume"]
    changed[changed.index(change[0]) + 1] = change[1]
    capsys.readouterr()
    assert main(changed) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    if change[0] in ("--method", "--masses"):
        assert "pass --extend" in err
    assert ((out / "episodes.csv").read_bytes(), (out / "run.json").read_bytes()) == before


def test_extend_adds_methods_and_appended_values_with_full_cells(tmp_path, capsys):
    out, full = tmp_path / "run", tmp_path / "full"
    args = sweep_args(out, "--workers", "1", masses="0.5,2")
    args[args.index("--method") + 1] = "fake_fast,fake_impact"
    assert main(args) == 0
    grown = sweep_args(out, "--workers", "1", masses="0.5,2,3.5")
    assert main([*grown, "--resume"]) == 2  # growing needs --extend
    assert main([*sweep_args(out, "--workers", "1", masses="2,0.5,3.5"), "--extend"]) == 2
    assert "the grid must start with" in capsys.readouterr().err
    assert main([*grown, "--extend"]) == 0
    assert main(sweep_args(full, "--workers", "1", masses="0.5,2,3.5")) == 0
    assert (out / "episodes.csv").read_text() == (full / "episodes.csv").read_text()
    dropped = [*grown, "--extend"]
    dropped[dropped.index("--method") + 1] = "fake_fast,fake_slow"
    assert main(dropped) == 2
    assert "methods ['fake_impact'] of the run are missing" in capsys.readouterr().err
