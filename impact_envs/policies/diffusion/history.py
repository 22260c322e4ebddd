"""Per-env observation history of a diffusion policy: the last ``To`` states and images."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import torch

from impact_control.errors import InvalidArgumentError


class ObservationHistory:
    """The last ``n_steps`` flat states (float32) and camera images (uint8) of ``n_envs`` envs.

    A fresh env (``reset`` / ``mark_fresh``) fills its whole history with its first
    observation, as the training windows repeat an episode's first step.

    Args:
        n_envs: Number of envs.
        n_steps: To, observations kept per env.
        state_dim: Size of the flat state.
        image_keys: Observation keys of the images kept (none for a state-based policy).
    """

    def __init__(self, n_envs: int, n_steps: int, state_dim: int,
                 image_keys: Sequence[str] = ()) -> None:
        self.n_steps = n_steps
        self.state = torch.zeros(n_envs, n_steps, state_dim)
        self.image_keys = tuple(image_keys)
        self.images: dict[str, torch.Tensor] = {}  # allocated at the first push (size known)
        self.fresh = np.ones(n_envs, dtype=bool)

    def mark_fresh(self, indices: np.ndarray | list[int]) -> None:
        """Envs ``indices`` start a new episode."""
        self.fresh[indices] = True

    def push(self, state: torch.Tensor, obs: Mapping[str, np.ndarray]) -> None:
        """Append ``state`` ``(B, D)`` and ``obs``'s images ``(B, H, W, 3)`` as the newest step."""
        fresh = torch.from_numpy(self.fresh)
        self.state = _pushed(self.state, state, fresh)
        for key in self.image_keys:
            if key not in obs:
                raise InvalidArgumentError(
                    f"observation lacks image {key!r}; needs {', '.join(self.image_keys)} (make "
                    "the env with the checkpoint's ObservationOptions)")
            frame = torch.from_numpy(np.ascontiguousarray(obs[key], dtype=np.uint8))
            if key not in self.images or self.images[key].shape[2:] != frame.shape[1:]:
                self.images[key] = frame.unsqueeze(1).repeat(1, self.n_steps, 1, 1, 1)
            self.images[key] = _pushed(self.images[key], frame, fresh)
        self.fresh[:] = False

    def images_of(self, envs: torch.Tensor) -> dict[str, torch.Tensor]:
        """``{key: (len(envs), To, H, W, 3)}`` of envs ``envs``."""
        return {key: frames[envs] for key, frames in self.images.items()}


def _pushed(history: torch.Tensor, newest: torch.Tensor, fresh: torch.Tensor) -> torch.Tensor:
    """``history`` ``(B, To, ...)`` shifted by one step with ``newest`` ``(B, ...)`` last; the
    rows of ``fresh`` envs filled with ``newest`` entirely."""
    history = torch.roll(history, shifts=-1, dims=1)
    history[:, -1] = newest
    history[fresh] = newest[fresh].unsqueeze(1).expand(-1, history.shape[1],
                                                       *newest.shape[1:])
    return history
