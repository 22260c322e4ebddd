"""Collection attempts: their seeds and parameters, in batches run in lockstep, recorded."""

from __future__ import annotations

from collections.abc import Generator, Iterator
from dataclasses import dataclass
from typing import Protocol

import gymnasium as gym
import numpy as np

from impact_control.errors import ImpactError
from impact_control.policy import stack_obs
from impact_envs.tasks.bins import mass_info_key
from impact_learn.collect_config import CollectConfig


class CollectionError(ImpactError):
    """A collection run failed, not its input: a batch failed on Ray, or an attempt did not
    repeat its own rollout (the stored episodes are kept)."""


class Expert(Protocol):
    """The scripted-expert interface collection relies on."""

    def reset(self, n_envs: int, object_mass_kg: np.ndarray) -> None:
        """Start ``n_envs`` episodes; ``object_mass_kg`` ``(n_envs,)`` is privileged info."""
        ...

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Return ``(B, 10)`` actions for the batched observation."""
        ...


@dataclass(frozen=True)
class EpisodeResult:
    """One finished attempt.

    Attributes:
        obs: ``{key: (T, d_key)}`` observations before each action.
        actions: ``(T, 10)`` expert actions.
        success: ``info["is_success"]`` held at some step.
        param: Parameter value the env reports (``info[param_name]``), else the requested
            value, else NaN.
    """

    obs: dict[str, np.ndarray]
    actions: np.ndarray
    success: bool
    param: float


@dataclass(frozen=True)
class AttemptSpec:
    """Reset settings of a batch of attempts.

    Attributes:
        seeds: Env reset seed per attempt.
        params: Parameter value per attempt, passed as reset option ``param_name`` (None: the
            env's default).
        param_name: Reset-option name of the randomized parameter (e.g. ``object_mass``).
    """

    seeds: list[int]
    params: list[float | None]
    param_name: str


@dataclass(frozen=True)
class AttemptBatch:
    """Consecutive attempts run together: their indices and their reset settings."""

    ids: list[int]
    spec: AttemptSpec


def _reset_all(
    envs: list[gym.Env], attempts: AttemptSpec
) -> tuple[list[dict], np.ndarray, np.ndarray]:
    """Reset every env.

    Returns:
        Observations, object masses for the expert [kg] (NaN if unknown) and the parameter
        values the envs report (``info[param_name]``, else the requested value, else NaN).
    """
    obs_list, masses, params = [], [], []
    for env, seed, param in zip(envs, attempts.seeds, attempts.params, strict=True):
        options = {} if param is None else {attempts.param_name: param}
        obs, info = env.reset(seed=seed, options=options)
        obs_list.append(obs)
        requested = np.nan if param is None else param
        params.append(float(info.get(attempts.param_name, requested)))
        mass_key = mass_info_key(env)  # the task's declared mass (Calligraphy: tool_mass)
        mass_default = params[-1] if attempts.param_name == mass_key else np.nan
        masses.append(float(info.get(mass_key, mass_default)))
    return obs_list, np.asarray(masses), np.asarray(params)


def run_attempts(
    envs: list[gym.Env],
    expert: Expert,
    attempts: AttemptSpec,
    post_success_steps: int,
) -> list[EpisodeResult]:
    """Run one attempt per env in lockstep until every attempt has ended.

    An attempt ends on termination, truncation, or ``post_success_steps`` steps after the
    first step whose ``info["is_success"]`` is true (envs need not terminate on success).

    Args:
        envs: One env per attempt.
        expert: Batched scripted expert (reset for ``len(envs)`` envs).
        attempts: Seeds and parameter values of the attempts.
        post_success_steps: Steps recorded after the first success [policy steps].

    Returns:
        One result per env, in the order of ``envs``.
    """
    obs_list, masses, params = _reset_all(envs, attempts)
    expert.reset(len(envs), object_mass_kg=masses)
    traj_obs: list[list[dict]] = [[] for _ in envs]
    traj_act: list[list[np.ndarray]] = [[] for _ in envs]
    success_step = [-1] * len(envs)
    active = [True] * len(envs)
    while any(active):
        actions = np.asarray(expert.act(stack_obs(obs_list)), dtype=np.float32)
        for i, env in enumerate(envs):
            if not active[i]:
                continue
            traj_obs[i].append(obs_list[i])
            traj_act[i].append(actions[i])
            obs_list[i], _, terminated, truncated, info = env.step(actions[i])
            step = len(traj_act[i])
            if success_step[i] < 0 and info.get("is_success", False):
                success_step[i] = step
            ended = success_step[i] >= 0 and step - success_step[i] >= post_success_steps
            active[i] = not (terminated or truncated or ended)
    return [
        _result(traj_obs[i], traj_act[i], success_step[i] >= 0, params[i]) for i in range(len(envs))
    ]


def _result(
    obs: list[dict[str, np.ndarray]], actions: list[np.ndarray], success: bool, param: float
) -> EpisodeResult:
    return EpisodeResult(
        obs={k: np.stack([_flat(o[k]) for o in obs]) for k in obs[0]},
        actions=np.stack(actions),
        success=success,
        param=float(param),
    )


def _flat(value: np.ndarray) -> np.ndarray:
    """A state entry as a flat vector; an image ``(H, W, C)`` as it is."""
    value = np.asarray(value)
    return value if value.ndim == 3 else np.ravel(value)


def attempt_seed(base_seed: int, attempt: int) -> int:
    """Env reset seed of attempt ``attempt``."""
    return int(np.random.SeedSequence([base_seed, attempt]).generate_state(1)[0])


def attempt_param(cfg: CollectConfig, attempt: int) -> float | None:
    """Randomized parameter of attempt ``attempt`` (None: the env's default)."""
    if cfg.param_range is not None:
        rng = np.random.default_rng(np.random.SeedSequence([cfg.seed, attempt, 1]))
        return float(rng.uniform(*cfg.param_range))
    if cfg.param_list is not None:
        return float(cfg.param_list[attempt % len(cfg.param_list)])
    return cfg.param


def attempt_batches(cfg: CollectConfig, first: int, param_name: str) -> Iterator[AttemptBatch]:
    """Batches of ``n_envs`` consecutive attempts from ``first`` up to the attempt limit."""
    for start in range(first, cfg.attempt_limit, cfg.n_envs):
        ids = list(range(start, min(start + cfg.n_envs, cfg.attempt_limit)))
        spec = AttemptSpec([attempt_seed(cfg.seed, k) for k in ids],
                           [attempt_param(cfg, k) for k in ids], param_name)
        yield AttemptBatch(ids, spec)


def run_screened(
    envs: list[gym.Env],
    expert: Expert,
    attempts: AttemptSpec,
    post_success_steps: int,
) -> list[EpisodeResult]:
    """``run_attempts`` with the cameras of ``CameraView`` envs rendering only the episodes
    that are kept: every attempt runs first without images, then the successful ones run
    again, from their seeds, with them. The results equal ``run_attempts``'s (a failed
    attempt's images were never stored), at the cost of a state rollout per attempt instead of
    rendering every step of every attempt, failures included (their 60 s on HammerBasket).
    Envs without cameras run once, as ``run_attempts``.

    Raises:
        CollectionError: a successful attempt did not succeed again with its cameras on (the
            rollout is not a function of its seed); nothing is stored from it.
    """
    views = [env for env in envs if hasattr(env, "rendering")]
    if not views:
        return run_attempts(envs, expert, attempts, post_success_steps)
    for view in views:
        view.rendering = False
    try:
        screened = run_attempts(envs, expert, attempts, post_success_steps)
    finally:
        for view in views:
            view.rendering = True
    kept = [i for i, result in enumerate(screened) if result.success]
    if not kept:
        return screened
    again = AttemptSpec([attempts.seeds[i] for i in kept], [attempts.params[i] for i in kept],
                        attempts.param_name)
    results = list(screened)
    for i, result in zip(kept, run_attempts(envs[:len(kept)], expert, again, post_success_steps),
                         strict=True):
        if not result.success or len(result.actions) != len(screened[i].actions):
            raise CollectionError(
                f"attempt with seed {attempts.seeds[i]} succeeded in {len(screened[i].actions)} "
                f"steps without cameras but not again with them (success={result.success}, "
                f"{len(result.actions)} steps): the rollout is not a function of its seed")
        results[i] = result
    return results


def local_batch_results(
    envs: list[gym.Env], expert: Expert, batches: Iterator[AttemptBatch], post_success_steps: int
) -> Generator[tuple[AttemptBatch, list[EpisodeResult]], None, None]:
    """Run each batch in this process when it is asked for (``run_screened``)."""
    for batch in batches:
        n = len(batch.ids)
        yield batch, run_screened(envs[:n], expert, batch.spec, post_success_steps)
