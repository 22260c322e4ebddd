"""Shared pytest configuration: the ``slow`` marker runs only with ``--runslow``; tests/ on
``sys.path`` so the test folders (which mirror the packages) import the shared helpers as
``fixtures.<module>`` (tests/fixtures/)."""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

TESTS = Path(__file__).resolve().parent
if str(TESTS) not in sys.path:
    sys.path.insert(0, str(TESTS))


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--runslow", action="store_true", default=False, help="run slow tests")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if config.getoption("--runslow"):
        return
    skip_slow = pytest.mark.skip(reason="slow: run with --runslow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip_slow)


@pytest.fixture(scope="session")
def ray_local(tmp_path_factory: pytest.TempPathFactory):
    """A 2-CPU Ray instance in this process (skipped without the ``[ray]`` extra). Its workers
    import the ``fixtures`` modules (the fake envs) and see a crash switch directory."""
    ray = pytest.importorskip("ray")
    crash_dir = tmp_path_factory.mktemp("ray_crash")
    env = {"PYTHONPATH": os.pathsep.join([str(TESTS), str(TESTS.parent)]),
           "IMPACT_FAKE_CRASH_DIR": str(crash_dir)}
    ray.init(num_cpus=2, include_dashboard=False, logging_level=logging.WARNING,
             runtime_env={"env_vars": env})
    yield crash_dir
    ray.shutdown()
