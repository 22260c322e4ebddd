"""``impact-eval --executor ray`` (``impact_eval/sweep_ray.py``) against the local executor, on a
2-CPU Ray instance started in this process (skipped without the ``[ray]`` extra)."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from fixtures.eval_fake import REPO, cli_env, run_cli, sweep_args

from impact_eval.cli import main
from impact_eval.prepare import prepare
from impact_eval.spec import RunOptions, SweepSpec
from impact_eval.sweep import plan_tasks

pytest.importorskip("ray")


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The sweep run by the local executor (2 worker processes): its episodes.csv."""
    out = tmp_path_factory.mktemp("local") / "run"
    proc = run_cli(*sweep_args(out, "--workers", "2"))
    assert proc.returncode == 0, proc.stderr
    return out / "episodes.csv"


def test_ray_executor_writes_the_local_executors_bytes(ray_local, reference, tmp_path):
    out = tmp_path / "ray"
    assert main(sweep_args(out, "--executor", "ray")) == 0
    assert (out / "episodes.csv").read_bytes() == reference.read_bytes()


def test_a_worker_killed_mid_task_is_retried_and_each_episode_arrives_once(ray_local, tmp_path):
    from impact_eval.sweep_ray import run_on_ray

    spec = SweepSpec(env_id="fixtures.eval_fake:ImpactTest/Fake-v0",
                     methods=("fake_fast", "fake_impact"), values=(0.5, 3.0), episodes=4, seed=3)
    options = RunOptions(out=tmp_path / "unused", workers=2, envs_per_worker=2, executor="ray")
    cfg = prepare(spec, options).config
    tasks = plan_tasks(cfg, set())
    (ray_local / "fired").unlink(missing_ok=True)
    (ray_local / "arm").touch()  # the first worker to reach step 3 of an episode SIGKILLs itself
    rows: list[dict[str, object]] = []
    try:
        run_on_ray(cfg, tasks, rows.append)
    finally:
        (ray_local / "arm").unlink()
    assert (ray_local / "fired").exists(), "no worker was killed"
    keys = [(r["method"], r["param_value"], r["episode"]) for r in rows]
    assert len(keys) == len(set(keys)) == sum(len(t.jobs) for t in tasks) == 16


@pytest.mark.slow  # ~100 s; the in-process retry test above covers a killed worker
def test_a_killed_worker_leaves_the_file_identical(ray_local, reference, tmp_path):
    (ray_local / "fired").unlink(missing_ok=True)
    (ray_local / "arm").touch()
    try:
        assert main(sweep_args(tmp_path / "ray", "--executor", "ray")) == 0
    finally:
        (ray_local / "arm").unlink()
    assert (ray_local / "fired").exists(), "no worker was killed"
    assert (tmp_path / "ray" / "episodes.csv").read_bytes() == reference.read_bytes()


def _cut(reference: Path, out: Path, rows: int) -> None:
    """``out`` as an interrupted run of the reference: its first ``rows`` rows (and run.json)."""
    out.mkdir()
    shutil.copy(reference.parent / "run.json", out / "run.json")
    lines = reference.read_text().splitlines(keepends=True)
    (out / "episodes.csv").write_text("".join(lines[: rows + 1]))


@pytest.mark.parametrize("executor", ["local", "ray"])
def test_resume_works_across_executors(ray_local, reference, tmp_path, capsys, executor):
    out = tmp_path / "cut"
    _cut(reference, out, 17)
    extra = ("--executor", executor) if executor == "ray" else ("--workers", "1")
    assert main(sweep_args(out, *extra, "--resume")) == 0
    assert "(17 already done, 45 in total)" in capsys.readouterr().out
    assert (out / "episodes.csv").read_bytes() == reference.read_bytes()


@pytest.mark.slow  # ~30 s; --runslow
def test_sigkilled_ray_driver_resumes_to_the_same_file(ray_local, reference, tmp_path):
    out = tmp_path / "killed"
    env = {**cli_env(), "IMPACT_FAKE_STEP_DELAY": "0.01"}  # slow, same results
    cmd = [sys.executable, "-m", "impact_eval", *sweep_args(out, "--executor", "ray")]
    child = subprocess.Popen(cmd, env=env, cwd=REPO, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL, start_new_session=True)
    csv = out / "episodes.csv"
    try:
        deadline = time.monotonic() + 120
        while (not csv.exists() or csv.read_bytes().count(b"\n") < 9) and \
                time.monotonic() < deadline:
            assert child.poll() is None, "sweep ended before it could be killed"
            time.sleep(0.05)
        os.kill(child.pid, signal.SIGKILL)
        child.wait()
    finally:  # the driver's own Ray instance (raylet, agents) goes with its process group
        with contextlib.suppress(ProcessLookupError):
            os.killpg(child.pid, signal.SIGKILL)
    done = csv.read_bytes().count(b"\n") - 1
    assert 8 <= done < 45, "the kill did not land mid-run"
    assert main(sweep_args(out, "--executor", "ray", "--resume")) == 0
    assert csv.read_bytes() == reference.read_bytes()


def test_bad_executor_input_is_one_line(tmp_path, capsys):
    assert main(sweep_args(tmp_path / "a", "--executor", "dask")) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "valid choices: local, ray" in err
    assert main(sweep_args(tmp_path / "b", "--ray-address", "10.0.0.1:6379")) == 2
    assert "--ray-address needs --executor ray" in capsys.readouterr().err
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def _free_loopback_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]  # closed again: nothing listens there


@pytest.mark.parametrize("address,message", [
    ("127.0.0.1:{port}", "cannot reach the Ray cluster at 127.0.0.1:{port} within 5 s"),
    ("ray://127.0.0.1:{port}", "cannot reach the Ray cluster at ray://127.0.0.1:{port}"),
    ("127.0.0.1", "invalid Ray address '127.0.0.1'; valid: HOST:PORT"),
    ("127.0.0.1:99999", "invalid Ray address '127.0.0.1:99999'"),
    (":6379", "invalid Ray address ':6379'"),
    ("127.0.0.1:http", "invalid Ray address '127.0.0.1:http'"),
])
def test_an_unreachable_or_malformed_ray_address_is_refused_before_any_output(
        tmp_path, capsys, monkeypatch, address, message):
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    port = _free_loopback_port()
    address, message = address.format(port=port), message.format(port=port)
    t0 = time.monotonic()
    out = tmp_path / "out"
    assert main(sweep_args(out, "--executor", "ray", "--ray-address", address)) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not out.exists() and time.monotonic() - t0 < 60


@pytest.mark.slow
def test_a_driver_joins_a_two_node_cluster_by_address(reference, tmp_path, monkeypatch):
    from ray.cluster_utils import Cluster

    monkeypatch.setenv("PYTHONPATH", cli_env()["PYTHONPATH"])  # the nodes' workers import it
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    try:
        cluster.add_node(num_cpus=1)
        cluster.wait_for_nodes()
        out = tmp_path / "cluster"
        proc = run_cli(*sweep_args(out, "--executor", "ray", "--ray-address", cluster.address))
        assert proc.returncode == 0, proc.stderr
    finally:
        cluster.shutdown()
    assert (out / "episodes.csv").read_bytes() == reference.read_bytes()
