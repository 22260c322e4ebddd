"""Fixtures of the FCI tests: a simulator serving on 127.0.0.1:1337 for one test; the
one-client lock's name private to this test session."""

from __future__ import annotations

import os

import pytest
from franka_servers import HERE, serving, simulator_python


@pytest.fixture(autouse=True)
def _private_lock_names(monkeypatch):
    """The one-client lock is one name per robot for the whole machine (connection.py): test
    sessions run side by side (pytest -n, two checkouts) would refuse each other's in-process
    runs. Each session gets names of its own; CLI subprocesses keep the real ones."""
    from impact_franka import connection

    monkeypatch.setattr(connection, "LOCK_PREFIX", f"impact-robot-test{os.getpid()}")


@pytest.fixture()
def franky_sim():
    """franky-sim serving on 127.0.0.1:1337 for one test (a fresh arm pose each time)."""
    python = simulator_python()
    with serving([python, "-m", "franky_sim.run_server", "-s", "mujoco", "--hostname",
                   "127.0.0.1"]) as host:
        yield host


@pytest.fixture()
def franka_sim():
    """franka-sim 1.1.7 on 127.0.0.1:1337 with its communication-constraint and motion-limit
    checks on (tests/franka/franka_sim_server.py), for one test."""
    python = simulator_python("IMPACT_FRANKA_SIM_PYTHON")
    with serving([python, str(HERE.joinpath("franka_sim_server.py"))]) as host:
        yield host

