"""``impact-eval --executor ray``: every sweep task (a lockstep batch of one cell, or a carried
method's whole cell, ``chain.py``) is a Ray task.

The driver keeps about two tasks per cluster CPU in flight (``ray_window``), each asking for one
CPU, and takes their results as they finish (``ray.wait``), submitting the next; a run that
stops on an error drops the tasks in flight, it does not cancel them (``ray_window`` says why).
It alone writes ``episodes.csv`` (through the same sink as the local
executor, and the file is sorted when the run ends, so both executors write the same bytes).

Exactly once: a task returns its rows only when its whole batch has ended, so when its worker
dies Ray reruns the task (``RAY_MAX_RETRIES``) and no row of the lost attempt ever reached the
driver. A task that raises is not retried: the sweep stops with a one-line error, and
``--resume`` continues it (with either executor) from the rows already written.

Workers keep their envs and policies between tasks, as local workers do (``Worker``); a Ray
worker process runs one task at a time.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import islice

from impact_envs.parallel import (
    ray_session,
    ray_task_options,
    ray_window,
    single_threaded_torch,
)
from impact_eval.sweep_config import EpisodeBatch, RowSink, SweepConfig, SweepError
from impact_eval.sweep_worker import Worker

_WORKERS: dict[SweepConfig, Worker] = {}
"""This Ray worker process's ``Worker`` (one sweep at a time; a new sweep replaces it)."""


def run_task(cfg: SweepConfig, task: EpisodeBatch) -> list[dict[str, object]]:
    """Body of one Ray task: run ``task`` and return its CSV rows (in a Ray worker)."""
    single_threaded_torch()
    worker = _WORKERS.get(cfg)
    if worker is None:
        for old in _WORKERS.values():
            old.close()
        _WORKERS.clear()
        worker = _WORKERS[cfg] = Worker(cfg)
    rows: list[dict[str, object]] = []
    worker.run(task, rows.append)
    return rows


def run_on_ray(cfg: SweepConfig, tasks: Sequence[EpisodeBatch], sink: RowSink) -> None:
    """Run ``tasks`` on Ray; ``sink(row)`` is called in this process for every episode."""
    with ray_session(cfg.options.ray_address) as ray:
        remote = ray.remote(run_task).options(**ray_task_options())
        cfg_ref = ray.put(cfg)
        queue = iter(tasks)
        pending = [remote.remote(cfg_ref, task) for task in islice(queue, ray_window(ray))]
        while pending:
            finished, pending = ray.wait(pending, num_returns=1)
            pending += [remote.remote(cfg_ref, task) for task in islice(queue, 1)]
            for row in _rows(ray, finished[0]):
                sink(row)


def _rows(ray: object, ref: object) -> list[dict[str, object]]:
    """A finished task's rows, or a one-line ``SweepError``."""
    from ray import exceptions

    try:
        return ray.get(ref)  # type: ignore[attr-defined]
    except exceptions.RayTaskError as exc:
        cause = exc.cause if exc.cause is not None else exc
        msg = " ".join(str(cause).split())[:300]
        raise SweepError(f"worker failed: {type(cause).__name__}: {msg}; rerun with --resume "
                         "after fixing it") from None
    except exceptions.RayError as exc:
        msg = " ".join(str(exc).split())[:300]
        raise SweepError(f"a Ray task was lost ({type(exc).__name__}: {msg}); rerun with "
                         "--resume") from None
