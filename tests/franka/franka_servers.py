"""Shared by the FCI tests: libfranka-protocol simulators on 127.0.0.1:1337 (and the
hand on :1338), each in a virtualenv of its own named by an environment variable (.ci/run
sets them), started and stopped by PID for one test."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import time
from pathlib import Path
from unittest import mock

import pytest

HERE = Path(__file__).resolve().parent
FRANKY_NICE = 5
"""franky-sim (no communication checks: a late answer costs nothing) runs below the client;
franka-sim keeps the default priority, its own timing checks depend on it."""
SIM_BUDGET_MS = 10.0
"""Per-tick compute budget [ms] of every loop run against a simulator except the test of the
budget monitor itself: the simulator's physics shares this machine's cores with the client
(CI: 2 cores, other jobs beside), so a tick's compute time here says nothing about an FR3's
PC. The robot's 0.8 ms default is measured by
``python -m impact_experiments.tick_latency``, not here;
10 ms is the largest ``--budget-ms`` accepts and still stops a loop that has hung."""
SIM_BUDGET = ["--budget-ms", f"{SIM_BUDGET_MS:g}"]
"""``SIM_BUDGET_MS`` as ``impact-robot`` arguments."""


def assert_no_abort_by_the_robot_s_rule(report: dict) -> None:
    """The robot's rule for lost commands, checked from both sides on a run under franka-sim
    (which enforces it): it aborts the motion with ``communication_constraints_violation`` at
    20 cycles unanswered in a row (libfranka's docs/network_requirements.rst), not at any
    success rate. Our count from the robot's clock must agree with the simulator's verdict.
    The success rate itself depends on this host's load (0.95-0.99 idle; 0.88 and 0.77 on CI's
    2 shared cores, with single 3-12 ms stalls of the loop thread), so only its range is
    checked."""
    assert report["robot_errors"] == ""
    assert 0 <= report["lost_in_a_row_max"] < 20
    assert 0.0 < report["command_success_rate_min"] <= 1.0


FORCE_AFTER_S = 5.0
"""When the scene's force arrives [s on the robot's clock after the torque loop starts]."""


def franky_scene_with_force(*options: str, flag: Path):
    """franky-sim with a force (``options``: ``--load-kg`` / ``--push-n``) that arrives
    ``FORCE_AFTER_S`` into the torque loop: ``flag_at_loop_start(flag)`` starts the count."""
    return franky_scene(*options, "--flag", str(flag), "--after-s", f"{FORCE_AFTER_S:g}")


@contextlib.contextmanager
def flag_at_loop_start(flag: Path):
    """Create ``flag`` as ``impact_franka``'s torque loop starts (the robot has accepted torque
    control), so the scene server's ``--after-s`` counts from there on the simulated clock,
    not from a wall-clock timer that a loaded host's slow imports would shift."""
    from impact_franka import runner

    original = runner._start_torque_control

    def start(robot: object, plf: object) -> object:
        active = original(robot, plf)
        flag.touch()
        return active

    with mock.patch.object(runner, "_start_torque_control", start):
        yield


def simulator_python(variable: str = "IMPACT_FRANKY_SIM_PYTHON") -> str:
    path = os.environ.get(variable, "")
    if not path or not os.path.exists(path):
        pytest.skip(f"simulator not given ({variable}); .ci/run sets it")
    pytest.importorskip("pylibfranka")
    return path


def port_open(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(0.2)
        return s.connect_ex(("127.0.0.1", port)) == 0


@contextlib.contextmanager
def serving(argv: list[str], nice: int = 0):
    """A libfranka-protocol server (``argv``, a simulator's python) on 127.0.0.1:1337, stopped
    by PID (its process group) afterwards; ``nice`` lowers its priority (a real robot is
    hardware of its own: its simulator should not take the CPU from the 1 kHz client)."""
    if port_open(1337):
        pytest.fail("127.0.0.1:1337 is taken: another robot server is running")
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True, preexec_fn=lambda: os.nice(nice))
    try:
        deadline = time.monotonic() + 60.0
        while not port_open(1337):
            if proc.poll() is not None or time.monotonic() > deadline:
                pytest.fail(f"{argv[1:]} did not start serving on 127.0.0.1:1337")
            time.sleep(0.2)
        yield "127.0.0.1"
    finally:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def franky_scene(*options: str):
    """franky-sim with tests/franka/franky_scene_server.py's ``options`` (a payload, a push,
    a pick-and-place scene) on 127.0.0.1:1337/1338."""
    return serving([simulator_python(), str(HERE / "franky_scene_server.py"), *options],
                   nice=FRANKY_NICE)
