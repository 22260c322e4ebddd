"""``impact-collect --executor ray``: each batch of ``n_envs`` attempts is a Ray task (a shard).

The driver keeps about two batches per cluster CPU in flight (``ray_window``) and merges the
shards in attempt order: it waits for the oldest batch, hands it to the store, submits the next.
So the store holds exactly the episodes a local run stores (same attempts, same order, same
``n_attempts``); batches still running when enough demos are stored do not count (they are
dropped, not cancelled: ``ray_window`` says why). Shards
travel through Ray's object store, so the workers need no shared filesystem. A batch whose
worker dies is rerun by Ray (``RAY_MAX_RETRIES``); one that raises stops the run, and
``--resume`` continues from the episodes stored.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Generator, Iterator

import gymnasium as gym

from impact_envs.parallel import (
    ray_session,
    ray_task_options,
    ray_window,
    single_threaded_torch,
)
from impact_learn.collect_config import CollectConfig
from impact_learn.collect_run import (  # noqa: F401 - CollectionError: its old home
    AttemptBatch,
    AttemptSpec,
    CollectionError,
    EpisodeResult,
    Expert,
    run_screened,
)

_STATE: dict[CollectConfig, tuple[list[gym.Env], Expert]] = {}
"""This Ray worker's envs and expert (one collection at a time; a new one replaces them)."""


def run_batch(cfg: CollectConfig, make_env: Callable[[], gym.Env],
              make_expert: Callable[[], Expert], spec: AttemptSpec) -> list[EpisodeResult]:
    """Body of one Ray task: run a batch of attempts in lockstep (in a Ray worker)."""
    single_threaded_torch()
    if cfg not in _STATE:
        for envs, _ in _STATE.values():
            for env in envs:
                env.close()
        _STATE.clear()
        _STATE[cfg] = ([], make_expert())
    envs, expert = _STATE[cfg]
    envs += [make_env() for _ in range(len(spec.seeds) - len(envs))]
    return run_screened(envs[: len(spec.seeds)], expert, spec, cfg.post_success_steps)


def ray_batch_results(
    cfg: CollectConfig,
    make_env: Callable[[], gym.Env],
    make_expert: Callable[[], Expert],
    batches: Iterator[AttemptBatch],
) -> Generator[tuple[AttemptBatch, list[EpisodeResult]], None, None]:
    """Each batch with its results, in attempt order, computed on Ray ahead of the caller."""
    with ray_session(cfg.ray_address) as ray:
        remote = ray.remote(run_batch).options(**ray_task_options())
        refs = [ray.put(x) for x in (cfg, make_env, make_expert)]
        window = ray_window(ray)
        in_flight: deque = deque()
        for batch in batches:
            in_flight.append((batch, remote.remote(*refs, batch.spec)))
            if len(in_flight) >= window:
                yield _oldest(ray, in_flight)
        while in_flight:
            yield _oldest(ray, in_flight)


def _oldest(ray: object, in_flight: deque) -> tuple[AttemptBatch, list[EpisodeResult]]:
    """Wait for the oldest batch in flight; a task that failed is a one-line error."""
    from ray import exceptions

    batch, ref = in_flight.popleft()
    try:
        return batch, ray.get(ref)  # type: ignore[attr-defined]
    except exceptions.RayError as exc:
        cause = getattr(exc, "cause", None) or exc
        msg = " ".join(str(cause).split())[:300]
        raise CollectionError(
            f"attempts {batch.ids[0]}..{batch.ids[-1]} failed on Ray ({type(cause).__name__}: "
            f"{msg}); the episodes stored so far are kept: rerun with --resume") from None
