"""The policy protocol every method in IMPACT implements.

A policy acts on a *batch* of observations so that evaluation can step many environments in
lockstep and run one batched network call per step. Observations are the env's ``Dict``
observation stacked along a leading batch axis: ``{key: array (B, *shape)}``. Actions are
``(B, 10)`` float32: TCP target position [m, world], rot6d of the TCP target orientation
(first two columns of R, column-major), gripper command in [-1 (open), +1 (closed)].
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np

ACTION_DIM = 10
"""Length of an action: position (3) + rot6d (6) + gripper (1)."""


@runtime_checkable
class Policy(Protocol):
    """Batched, stateful policy: ``reset`` before each batch of episodes, ``act`` every step."""

    def reset(self, n_envs: int) -> None:
        """Clear internal state (observation history, action queue, phase) for ``n_envs`` envs."""
        ...

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Return actions ``(B, 10)`` float32 for the batched observation ``obs``."""
        ...


@runtime_checkable
class SeededPolicy(Policy, Protocol):
    """Optional hook: a policy with per-episode randomness (e.g. diffusion noise) that the
    evaluator seeds per episode, so an episode's actions do not depend on the batch it ran in.
    ``impact_eval.rollout`` calls it after ``reset``."""

    def seed_envs(self, episode_seeds: Sequence[int]) -> None:
        """Seed env ``i``'s randomness with ``episode_seeds[i]``."""
        ...


@runtime_checkable
class FinishingPolicy(Policy, Protocol):
    """Optional hook: told which envs of the batch ended, so it can stop computing their
    actions (``impact_eval.rollout`` calls it as each episode ends)."""

    def finish_envs(self, indices: Sequence[int]) -> None:
        """Envs ``indices`` of the current batch have ended."""
        ...


@runtime_checkable
class FrameReadingPolicy(Policy, Protocol):
    """Optional hook: a camera policy that reads only some frames (a diffusion policy reads its
    last ``n_obs_steps`` observations when it replans, every ``n_action_steps``). Before each
    step ``impact_eval.rollout`` asks which envs' next observation it will read and tells the
    other envs to skip rendering it (``ImpactEnv.skip_next_images``): the images then hold
    zeros, which the policy never reads. Actions are the same, bit for bit, as with every
    frame rendered (``tests/eval/test_frame_skipping.py``)."""

    def frames_read_next(self) -> np.ndarray:
        """``(B,)`` bool: whether env ``i``'s next observation's images will be read."""
        ...


def stack_obs(obs_list: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Stack per-env Dict observations into one batched dict ``{key: (B, ...)}``."""
    return {k: np.stack([o[k] for o in obs_list]) for k in obs_list[0]}
