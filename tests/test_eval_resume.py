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
from test_eval_cli import sweep_args
from test_eval_fake import REPO, cli_env, run_cli


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
