"""Sweep engine: plan the (method, value, episode) grid and run it on process-parallel workers
(or on Ray: ``sweep_ray``, ``--executor ray``).

Each worker owns a few envs per controller and one policy per method, and runs tasks of up to
``envs_per_worker`` episodes of one (method, value) in lockstep (one batched ``policy.act`` per
step); a carried method's task is its whole cell, one episode after another (``chain.py``).
Workers stream each finished episode's row to the parent, the only writer of the CSV.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import queue
from collections.abc import Iterable, Sequence

from tqdm import tqdm

from impact_envs.parallel import single_threaded_children, single_threaded_torch
from impact_eval.chain import chain_jobs
from impact_eval.grid import format_value
from impact_eval.sweep_config import EpisodeBatch, RowSink, SweepConfig, SweepError
from impact_eval.sweep_worker import Worker, carried

__all__ = ["EpisodeBatch", "RowSink", "SweepConfig", "SweepError", "Worker", "plan_tasks",
           "run_sweep"]

def plan_tasks(cfg: SweepConfig, done: set[tuple[str, str, int]]) -> list[EpisodeBatch]:
    """Tasks for every cell not in ``done`` (keys as ``csvio.row_key``).

    Ordered value-major, then episode block, then method, so that an interrupted sweep leaves
    paired results (all methods at the same values and seeds). A carried method's cell is one
    task, in the first block (``chain.chain_jobs``).
    """
    tasks = []
    size = cfg.options.envs_per_worker
    carried_methods = {m for m in cfg.spec.methods if carried(m)}
    for vi, value in enumerate(cfg.spec.values):
        for start in range(0, cfg.spec.episodes, size):
            for method in cfg.spec.methods:
                if method not in carried_methods:
                    tasks.append(EpisodeBatch(method, value, tuple(
                        cfg.job(vi, e) for e in range(start, min(start + size, cfg.spec.episodes))
                        if (method, format_value(value), e) not in done)))
                elif start == 0:
                    chain, todo = chain_jobs(cfg, vi, method, done)
                    tasks.append(EpisodeBatch(method, value, todo, chain))
    return [task for task in tasks if task.jobs]


def _exit_if_orphaned() -> None:
    """Leave at once when the parent is gone (e.g. SIGKILLed): nobody would read our rows."""
    parent = mp.parent_process()
    if parent is not None and not parent.is_alive():
        os._exit(0)


def _worker_main(cfg: SweepConfig, tasks: mp.Queue, results: mp.Queue) -> None:
    """Worker process: pull tasks until a ``None`` sentinel, stream rows back."""
    single_threaded_torch()
    try:
        worker = Worker(cfg)
        while True:
            try:
                task = tasks.get(timeout=0.5)
            except queue.Empty:
                _exit_if_orphaned()
                continue
            if task is None:
                break

            def sink(row: dict[str, object]) -> None:
                _exit_if_orphaned()
                results.put(("row", row))

            worker.run(task, sink, _exit_if_orphaned)
            results.put(("done", None))
        worker.close()
    except Exception as exc:  # noqa: BLE001 - reported to the parent, which aborts the sweep
        results.put(("error", f"{type(exc).__name__}: {' '.join(str(exc).split())[:300]}"))


def _context() -> mp.context.BaseContext:
    """``forkserver`` where available (Linux), else ``spawn``; never plain ``fork``."""
    methods = mp.get_all_start_methods()
    return mp.get_context("forkserver" if "forkserver" in methods else "spawn")


def _run_inline(cfg: SweepConfig, tasks: Sequence[EpisodeBatch], sink: RowSink) -> None:
    """Run all tasks in this process (``--workers 1``)."""
    worker = Worker(cfg)
    try:
        for task in tasks:
            worker.run(task, sink)
    finally:
        worker.close()


def _run_parallel(cfg: SweepConfig, tasks: Sequence[EpisodeBatch], sink: RowSink, n: int) -> None:
    """Run tasks on ``n`` worker processes; the parent only collects rows."""
    ctx = _context()
    task_q, result_q = ctx.Queue(), ctx.Queue()
    for task in [*tasks, *[None] * n]:
        task_q.put(task)
    procs = [
        ctx.Process(target=_worker_main, args=(cfg, task_q, result_q), daemon=True)
        for _ in range(n)
    ]
    with single_threaded_children():
        for p in procs:
            p.start()
    try:
        _collect(procs, result_q, len(tasks), sink)
        for p in procs:
            p.join(timeout=10)
    finally:
        for p in procs:
            if p.is_alive():
                p.terminate()


def _collect(procs: Iterable[mp.Process], result_q: mp.Queue, n_tasks: int, sink: RowSink) -> None:
    """Forward rows to ``sink`` until every task reported done; fail fast on a dead worker."""
    remaining = n_tasks
    while remaining:
        try:
            kind, payload = result_q.get(timeout=1.0)
        except queue.Empty:
            dead = [p.exitcode for p in procs if p.exitcode not in (None, 0)]
            if dead:
                raise SweepError(
                    f"a worker died (exit code {dead[0]}); rerun with --resume"
                ) from None
            continue
        if kind == "row":
            sink(payload)
        elif kind == "done":
            remaining -= 1
        else:
            raise SweepError(f"worker failed: {payload}; rerun with --resume after fixing it")


def run_sweep(cfg: SweepConfig, tasks: Sequence[EpisodeBatch], sink: RowSink) -> int:
    """Run ``tasks``, calling ``sink(row)`` in this process for every finished episode.

    Returns:
        Number of episodes run.
    """
    total = sum(len(t.jobs) for t in tasks)
    bar = tqdm(total=total, unit="ep", desc=f"{cfg.canonical_env_id} sweep", mininterval=0.5)

    def counted(row: dict[str, object]) -> None:
        sink(row)
        bar.update(1)

    try:
        n = min(cfg.options.workers, len(tasks))
        if cfg.options.executor == "ray":
            from impact_eval.sweep_ray import run_on_ray

            run_on_ray(cfg, tasks, counted)
        elif n <= 1:
            _run_inline(cfg, tasks, counted)
        else:
            _run_parallel(cfg, tasks, counted, n)
    finally:
        bar.close()
    return total
