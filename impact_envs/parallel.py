"""Process setup shared by the parallel runners: impact-eval's local workers, and Ray tasks of
``impact-eval`` and ``impact-collect`` (``--executor ray``, the optional ``[ray]`` extra).

Every worker runs single-threaded (one env per core; the internal model's small matmuls gain
nothing from a second thread and the numerics stay independent of the core count). Ray is
imported only when asked for.
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
from collections.abc import Iterator
from types import ModuleType

from impact_control.errors import InvalidArgumentError

THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
"""Thread-count variables read by OpenMP (torch), NumPy's OpenBLAS and MKL when they load."""

FORWARDED_ENV = ("IMPACT_CHECKPOINTS", "IMPACT_TRUST_SB3", "MUJOCO_GL")
"""Variables of the driver that Ray tasks see too (where the driver has them): the checkpoint
root, the SB3 trust flag and the rendering backend. A local worker inherits them anyway."""

EXECUTORS = ("local", "ray")
"""``--executor`` choices: this machine's processes, or a Ray cluster (local or remote)."""

RAY_INSTALL_HINT = "pip install -e '.[ray]'"

RAY_MAX_RETRIES = 3
"""Times Ray reruns a task whose worker process died (a task that raises is not retried)."""


@contextlib.contextmanager
def single_threaded_children() -> Iterator[None]:
    """Processes started inside (and the forkserver, if it starts here) see one thread each.

    NumPy's OpenBLAS sizes its thread pool when NumPy is imported, which in a worker happens
    while the worker function is unpickled, before any of its code runs; so the variables must
    already be in the environment the worker inherits. Without them each worker had a second,
    busy BLAS thread (the internal model's SGD matmuls) competing for the 2 cores.
    """
    saved = {k: os.environ.get(k) for k in THREAD_ENV}
    os.environ.update(dict.fromkeys(THREAD_ENV, "1"))
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def single_threaded_torch() -> None:
    """One intra-op and one inter-op thread for torch in this process.

    The forkserver may have imported torch (one thread per core) before the worker starts, so
    the variables alone do not suffice. One thread also keeps the network's numerics
    independent of the machine's core count.
    """
    import torch

    torch.set_num_threads(1)
    with contextlib.suppress(RuntimeError):  # set once per process; fine if already set
        torch.set_num_interop_threads(1)


def import_ray() -> ModuleType:
    """The ``ray`` module, or a one-line error saying how to install it."""
    try:
        import ray
    except ImportError:
        raise InvalidArgumentError(
            f"--executor ray needs Ray, which is not installed; install it with "
            f"{RAY_INSTALL_HINT} (or use --executor local)") from None
    return ray


def check_executor(executor: str, ray_address: str | None) -> None:
    """One-line errors for an unknown executor, a Ray address without Ray, or Ray missing."""
    if executor not in EXECUTORS:
        raise InvalidArgumentError(
            f"invalid executor {executor!r}; valid choices: {', '.join(EXECUTORS)}")
    if ray_address is not None and executor != "ray":
        raise InvalidArgumentError("--ray-address needs --executor ray")
    if executor == "ray":
        import_ray()
        address = ray_address if ray_address is not None else os.environ.get("RAY_ADDRESS")
        if address:
            probe_ray_address(address)


RAY_PROBE_TIMEOUT_S = 5.0
"""How long ``probe_ray_address`` waits for the cluster's port to accept a connection."""


def probe_ray_address(address: str, timeout_s: float = RAY_PROBE_TIMEOUT_S) -> None:
    """One-line error unless ``HOST:PORT`` (or ``ray://HOST:PORT``) accepts a TCP connection
    within ``timeout_s``: checked before any output exists, as ``ray.init`` would otherwise
    retry for minutes. ``auto`` and ``local`` are left to Ray (it answers at once)."""
    if address in ("auto", "local"):
        return
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise InvalidArgumentError(
            f"invalid Ray address {address!r}; valid: HOST:PORT (e.g. 10.0.0.1:6379), "
            "ray://HOST:PORT, auto or local")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s):
            pass
    except OSError as exc:
        raise InvalidArgumentError(
            f"cannot reach the Ray cluster at {address} within {timeout_s:g} s "
            f"({type(exc).__name__}: {exc.strerror or exc}); start it (ray start --head) or "
            "fix --ray-address / $RAY_ADDRESS") from None


def ray_task_options() -> dict[str, object]:
    """Options of every Ray task: one CPU, retried when its worker dies, one thread each."""
    env = dict.fromkeys(THREAD_ENV, "1")
    env |= {k: os.environ[k] for k in FORWARDED_ENV if k in os.environ}
    return {"num_cpus": 1, "max_retries": RAY_MAX_RETRIES, "runtime_env": {"env_vars": env}}


RAY_TASKS_PER_CPU = 2
"""Ray tasks a driver keeps in flight per cluster CPU: every CPU busy while the driver takes
results, and few enough to leave running when a run stops early."""


def ray_window(ray: ModuleType) -> int:
    """How many tasks a driver keeps in flight (``RAY_TASKS_PER_CPU`` per cluster CPU, read
    once at the start).

    Tasks a run no longer needs are never ``ray.cancel``-ed: in Ray 2.x a cancellation that
    races the reply of a task just finishing aborts the driver process (``Check failed: it !=
    submissible_tasks_.end()`` in ``task_manager.cc``; it killed a pytest worker in our CI,
    cf. ray-project/ray#54738). They are dropped instead: at most this window of tasks runs
    on, until it ends or the driver's Ray session does (a session the driver started is shut
    down when the run ends)."""
    return RAY_TASKS_PER_CPU * max(1, int(ray.cluster_resources().get("CPU", 1)))


@contextlib.contextmanager
def ray_session(address: str | None) -> Iterator[ModuleType]:
    """Ray, connected: the session already open in this process (e.g. a test's
    ``ray.init(num_cpus=2)``), else ``ray.init(address)`` (None: ``$RAY_ADDRESS`` or a new
    local instance), shut down again on exit."""
    ray = import_ray()
    if ray.is_initialized():
        yield ray
        return
    try:
        ray.init(address=address, include_dashboard=False, logging_level=logging.WARNING)
    except (ConnectionError, RuntimeError, ValueError) as exc:
        where = address or os.environ.get("RAY_ADDRESS") or "a new local instance"
        msg = " ".join(str(exc).split())[:200]
        raise InvalidArgumentError(f"cannot start or reach Ray ({where}): {msg}") from None
    try:
        yield ray
    finally:
        ray.shutdown()
