"""Training windows of a demonstration store: DP-style window indices and the sampler."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import torch


def window_indices(
    episode_ends: np.ndarray, episodes: Sequence[int], n_obs_steps: int, horizon: int
) -> tuple[np.ndarray, np.ndarray]:
    """Global step indices of every training window, with DP-style edge padding.

    There is one window per step t of each episode: observations t-To+1..t and actions
    t-To+1..t-To+Tp, clamped into the episode (repeat the first step before the start, the
    last step after the end). Action To-1 of a window is the one taken at the current step t.

    Returns:
        ``obs_idx`` ``(W, To)`` and ``act_idx`` ``(W, Tp)`` int64 indices into the N axis.
    """
    starts = np.concatenate([[0], episode_ends[:-1]])
    obs_rows, act_rows = [], []
    for ep in episodes:
        start, end = int(starts[ep]), int(episode_ends[ep])
        t = np.arange(start, end)[:, None]
        first = t - (n_obs_steps - 1)
        obs_rows.append(np.clip(first + np.arange(n_obs_steps), start, end - 1))
        act_rows.append(np.clip(first + np.arange(horizon), start, end - 1))
    if not obs_rows:
        return np.zeros((0, n_obs_steps), np.int64), np.zeros((0, horizon), np.int64)
    return np.concatenate(obs_rows).astype(np.int64), np.concatenate(act_rows).astype(np.int64)


@dataclass(frozen=True)
class Batch:
    """Training windows.

    Attributes:
        obs: Normalized state history ``(B, To, D_obs)``.
        actions: Normalized action sequences ``(B, Tp, 10)``.
        images: ``{image_key: (B, To, H, W, 3) uint8}`` of a visuomotor policy; empty for a
            state-based one.
    """

    obs: torch.Tensor
    actions: torch.Tensor
    images: Mapping[str, torch.Tensor] = field(default_factory=dict)


class WindowSampler:
    """Random or indexed access to normalized training windows.

    Args:
        obs: Normalized flat observations ``(N, D_obs)``.
        actions: Normalized actions ``(N, 10)``.
        obs_idx: ``(W, To)`` from ``window_indices``.
        act_idx: ``(W, Tp)`` from ``window_indices``.
        images: ``{image_key: (N, H, W, 3) uint8}`` gathered with the observation steps
            (kept as uint8: a 200-demo two-camera store at 96 x 96 is 2.3 GB in memory).
    """

    def __init__(
        self, obs: torch.Tensor, actions: torch.Tensor, obs_idx: np.ndarray, act_idx: np.ndarray,
        images: Mapping[str, torch.Tensor] | None = None,
    ) -> None:
        self.obs, self.actions = obs, actions
        self.images = dict(images or {})
        self.obs_idx = torch.as_tensor(obs_idx, dtype=torch.long)
        self.act_idx = torch.as_tensor(act_idx, dtype=torch.long)

    def __len__(self) -> int:
        return int(self.obs_idx.shape[0])

    def get(self, windows: torch.Tensor) -> Batch:
        """The windows of ids ``windows`` ``(B,)``."""
        steps = self.obs_idx[windows]
        images = {key: frames[steps] for key, frames in self.images.items()}
        return Batch(self.obs[steps], self.actions[self.act_idx[windows]], images)

    def sample(self, batch_size: int, generator: torch.Generator) -> Batch:
        """Draw ``batch_size`` windows uniformly with replacement."""
        return self.get(torch.randint(len(self), (batch_size,), generator=generator))
