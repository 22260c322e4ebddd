"""Carried methods (``MethodSpec.carry``): a cell's episodes as one chain on one env.

The paper's authors run their benchmark with the controller activated once per (controller,
mass bin) launch: the scene reset between episodes does not reset it, so its state carries over
the bin's episodes (docs/eval.md, "Carried controller state"). A carried method's (method,
value) cell is one sweep task (``sweep.plan_tasks``): its episodes run in episode order on one
env, each alone (a batch of one, ``LockstepBatch``), and each starts with the controller state
the previous one left (``ImpactEnv.carry_controller``); episode 0 starts from a fresh
controller. An episode's start thus depends on the episodes before it in its cell and on
nothing else (not the worker, ``--envs-per-worker`` or the executor), so the rows are the same
bytes however the sweep is run.

Resume: a partly written cell is rerun from episode 0 up to its last missing episode, and only
the missing rows are written (the rerun episodes are deterministic: the same rows again).

``--end-early`` does not apply to a chain: an episode's end state is the next one's start, so
each runs its full length.

An episode that ends in an exception (``failure_reason`` ``unstable: ...`` or ``exception:
...``) passes nothing on: the next starts from a fresh controller, as a relaunched controller
would (a diverged state would otherwise fail every later episode of the cell).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Set
from typing import TYPE_CHECKING, Protocol

from impact_control.policy import Policy
from impact_eval.grid import format_value
from impact_eval.rollout import EpisodeJob, LockstepBatch
from impact_eval.sweep_config import EpisodeBatch, RowSink, SweepConfig

if TYPE_CHECKING:
    from impact_eval.methods import MethodSpec


class ChainWorker(Protocol):
    """What a chain uses of its worker (``sweep_worker.Worker``)."""

    cfg: SweepConfig

    def _envs(self, spec: MethodSpec, n: int) -> list[object]: ...

    def _policy(self, method: str) -> Policy: ...

    def _videos(self, task: EpisodeBatch) -> dict[int, object]: ...

    def row(self, method: str, job: EpisodeJob,
            metrics: dict[str, object]) -> dict[str, object]: ...

CRASHED = ("unstable", "exception")
"""``failure_reason`` prefixes of an episode that raised: it carries no state on."""

Jobs = tuple[EpisodeJob, ...]


def chain_jobs(cfg: SweepConfig, value_index: int, method: str,
               done: Set[tuple[str, str, int]]) -> tuple[Jobs, Jobs]:
    """(chain, to write) of a carried cell: every episode from 0 to the last one not in
    ``done`` (keys as ``csvio.row_key``), and those of them not in ``done``; both empty when
    the cell is complete."""
    jobs = [cfg.job(value_index, e) for e in range(cfg.spec.episodes)]
    value = cfg.spec.values[value_index]
    todo = tuple(j for j in jobs if (method, format_value(value), j.episode) not in done)
    if not todo:
        return (), ()
    return tuple(jobs[:todo[-1].episode + 1]), todo


def run_chain(worker: ChainWorker, spec: MethodSpec, task: EpisodeBatch, sink: RowSink,
              heartbeat: Callable[[], None] | None = None) -> None:
    """Run ``task.chain`` on one of ``worker``'s envs, carrying the controller state from each
    episode into the next; ``sink`` receives the rows of ``task.jobs``."""
    env = worker._envs(spec, 1)[0]
    base = env.unwrapped  # type: ignore[attr-defined]
    write = {job.episode for job in task.jobs}
    base.warm_start(None)
    base.carry_controller(None)  # episode 0: a fresh controller
    try:
        for job in task.chain:
            reason = _run_episode(worker, spec, task, env, job,
                                  sink if job.episode in write else None, heartbeat)
            crashed = reason is None or reason.startswith(CRASHED)
            base.carry_controller(None if crashed else base.controller_carry())
    finally:
        base.carry_controller(None)  # nothing pending for the worker's next task on this env


def _run_episode(worker: ChainWorker, spec: MethodSpec, task: EpisodeBatch, env: object,
                 job: EpisodeJob, sink: RowSink | None,
                 heartbeat: Callable[[], None] | None) -> str | None:
    """Run one episode of the chain alone; its row goes to ``sink`` (None: a rerun episode
    whose row is written already, and no video). Returns its ``failure_reason``."""
    reasons: list[str] = []

    def on_finish(_: int, metrics: dict[str, object]) -> None:
        reasons.append(str(metrics.get("failure_reason") or ""))
        if sink is not None:
            sink(worker.row(spec.name, job, metrics))

    videos = (worker._videos(dataclasses.replace(task, jobs=(job,), chain=()))
              if sink is not None else {})
    LockstepBatch([env], worker._policy(spec.name), worker.cfg.param_name,
                  worker.cfg.policy_dt, videos).run([job], on_finish, heartbeat)
    return reasons[0] if reasons else None
