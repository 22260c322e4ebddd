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
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from impact_control.errors import ImpactError, InvalidArgumentError
from impact_control.policy import Policy
from impact_envs.parallel import single_threaded_children, single_threaded_torch
from impact_eval.bins import bin_param_name, draw_in_bin
from impact_eval.chain import chain_jobs, run_chain
from impact_eval.grid import episode_seed, format_value
from impact_eval.methods import MethodSpec, resolve_method
from impact_eval.rollout import EpisodeJob, LockstepBatch

RowSink = Callable[[dict[str, object]], None]


class SweepError(ImpactError):
    """The sweep could not finish (a worker died or failed outside an episode)."""


@dataclass(frozen=True)
class SweepConfig:
    """Everything a worker needs (picklable)."""

    env_id: str
    """Id as given on the CLI (may carry a ``module:`` prefix that registers it)."""
    canonical_env_id: str
    """``env.spec.id``, written to the CSV."""
    param_name: str
    policy_dt: float
    methods: tuple[str, ...]
    values: tuple[float, ...]
    episodes: int
    seed: int
    workers: int
    envs_per_worker: int
    controller_overrides: tuple[str, ...] = ()
    robot_overrides: tuple[str, ...] = ()
    """``--robot-set FIELD=VALUE`` on every method's robot (``RobotOptions`` fields)."""
    """``SECTION.FIELD=VALUE`` changes of the controller config (ablations; empty: paper's)."""
    video_episodes: int = 0
    """Record the first this many episodes of every cell as MP4 (``--video``)."""
    video_dir: str = ""
    """Where the videos go (``OUT/videos``)."""
    executor: str = "local"
    """``local`` (this machine's processes, ``workers`` of them) or ``ray`` (``sweep_ray``)."""
    ray_address: str | None = None
    """Ray cluster to join (``--ray-address``; None: ``$RAY_ADDRESS`` or a new local one)."""
    bin_highs: tuple[float, ...] = ()
    """``--mass-bins``: each bin's upper edge, ``values`` holding the lower edges (``bins.py``);
    empty: ``values`` is a grid of fixed values."""

    @property
    def row_param_name(self) -> str:
        """``param_name`` as the rows carry it (``object_mass_bin`` for a bin sweep)."""
        return bin_param_name(self.param_name) if self.bin_highs else self.param_name

    def job(self, value_index: int, episode: int) -> EpisodeJob:
        """Episode ``episode`` of the cell at ``values[value_index]``: its paired seed, and in a
        bin sweep the mass it draws in its bin."""
        value = self.values[value_index]
        seed = episode_seed(self.seed, value_index, episode)
        if not self.bin_highs:
            return EpisodeJob(value, seed, episode)
        return EpisodeJob(value, seed, episode,
                          draw_in_bin(value, self.bin_highs[value_index], seed))


@dataclass(frozen=True)
class EpisodeBatch:
    """Up to ``envs_per_worker`` episodes of one (method, value) in lockstep, or a chain."""

    method: str
    value: float
    jobs: tuple[EpisodeJob, ...]
    """The episodes whose rows the task writes."""
    chain: tuple[EpisodeJob, ...] = ()
    """Carried methods: the cell's episodes 0 to the last of ``jobs``, in order on one env, the
    controller state carried from each into the next (``chain.py``); the rest are reruns."""


def plan_tasks(cfg: SweepConfig, done: set[tuple[str, str, int]]) -> list[EpisodeBatch]:
    """Tasks for every cell not in ``done`` (keys as ``csvio.row_key``).

    Ordered value-major, then episode block, then method, so that an interrupted sweep leaves
    paired results (all methods at the same values and seeds). A carried method's cell is one
    task, in the first block (``chain.chain_jobs``).
    """
    tasks = []
    size = cfg.envs_per_worker
    carried = {m for m in cfg.methods if _carried(m)}
    for vi, value in enumerate(cfg.values):
        for start in range(0, cfg.episodes, size):
            for method in cfg.methods:
                if method not in carried:
                    tasks.append(EpisodeBatch(method, value, tuple(
                        cfg.job(vi, e) for e in range(start, min(start + size, cfg.episodes))
                        if (method, format_value(value), e) not in done)))
                elif start == 0:
                    chain, todo = chain_jobs(cfg, vi, method, done)
                    tasks.append(EpisodeBatch(method, value, todo, chain))
    return [task for task in tasks if task.jobs]


def _carried(method: str) -> bool:
    """Whether ``method`` runs its cells as carried chains (an unregistered name: no; the CLI
    and ``evaluate`` refuse those before planning)."""
    try:
        return resolve_method(method).carry
    except InvalidArgumentError:
        return False


class Worker:
    """Per-process state: envs per controller and one policy per method, built on first use."""

    def __init__(self, cfg: SweepConfig) -> None:
        from impact_eval.envs import import_env_module

        import_env_module(cfg.env_id)
        self.cfg = cfg
        self.envs: dict[tuple, list[object]] = {}
        self.policies: dict[str, Policy] = {}
        self.warm: dict[tuple[str, float], object] = {}

    def _envs(self, spec: MethodSpec, n: int) -> list[object]:
        """At least ``n`` envs of the method's (controller, preset)."""
        from impact_eval.envs import method_env

        envs = self.envs.setdefault(spec.env_key, [])
        while len(envs) < n:
            envs.append(method_env(self.cfg.env_id, spec, self.cfg.controller_overrides,
                                   render=self.cfg.video_episodes > 0,
                                   robot_overrides=self.cfg.robot_overrides))
        return envs

    def _policy(self, method: str) -> Policy:
        if method not in self.policies:
            spec = resolve_method(method)
            env = self._envs(spec, 1)[0]
            self.policies[method] = spec.build(self.cfg.canonical_env_id, env)
        return self.policies[method]

    def run(self, task: EpisodeBatch, sink: RowSink,
            heartbeat: Callable[[], None] | None = None) -> None:
        """Run one task; ``sink`` receives each full CSV row as its episode ends."""
        spec = resolve_method(task.method)
        if spec.carry:
            run_chain(self, spec, task, sink, heartbeat)
            return
        envs = self._envs(spec, len(task.jobs))
        snapshot = self._warm_snapshot(spec, task.value) if spec.warm else None
        for env in envs:
            warm_start = getattr(env.unwrapped, "warm_start", None)  # type: ignore[attr-defined]
            if callable(warm_start):
                warm_start(snapshot)
        batch = LockstepBatch(envs, self._policy(task.method), self.cfg.param_name,
                              self.cfg.policy_dt, self._videos(task))

        def on_finish(i: int, metrics: dict[str, object]) -> None:
            sink(self.row(task.method, task.jobs[i], metrics))

        batch.run(task.jobs, on_finish, heartbeat)

    def row(self, method: str, job: EpisodeJob, metrics: dict[str, object]) -> dict[str, object]:
        """The CSV row of ``job``'s finished episode."""
        return {"method": method, "env_id": self.cfg.canonical_env_id,
                "param_name": self.cfg.row_param_name, "param_value": job.value, "seed": job.seed,
                "episode": job.episode, **metrics}

    def _videos(self, task: EpisodeBatch) -> dict[int, object]:
        """The task's episodes to record (episode index < ``video_episodes``), by batch index."""
        if not self.cfg.video_episodes:
            return {}
        from impact_eval.video import EpisodeVideo, video_path

        root = Path(self.cfg.video_dir)
        return {i: EpisodeVideo(video_path(root, task.method, self.cfg.param_name,
                                           format_value(job.value), job.episode))
                for i, job in enumerate(task.jobs) if job.episode < self.cfg.video_episodes}

    def _warm_snapshot(self, spec: MethodSpec, value: float) -> object:
        """The cell's warm-up snapshot (``warm.warm_up``), computed once per worker."""
        from impact_eval.warm import warm_up

        key = (spec.name, value)
        if key not in self.warm:
            self.warm[key] = warm_up(self._envs(spec, 1)[0], self._policy(spec.name),
                                     self.cfg.param_name, self.cfg.policy_dt, self.cfg.seed,
                                     self.cfg.values.index(value), value)
        return self.warm[key]

    def close(self) -> None:
        """Close every env."""
        for envs in self.envs.values():
            for env in envs:
                env.close()  # type: ignore[attr-defined]


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
        n = min(cfg.workers, len(tasks))
        if cfg.executor == "ray":
            from impact_eval.sweep_ray import run_on_ray

            run_on_ray(cfg, tasks, counted)
        elif n <= 1:
            _run_inline(cfg, tasks, counted)
        else:
            _run_parallel(cfg, tasks, counted, n)
    finally:
        bar.close()
    return total
