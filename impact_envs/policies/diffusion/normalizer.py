"""Affine min-max normalization of observations and actions to ``[-1, 1]``.

Observation dimensions are min-max normalized and never clipped (a state outside the training
range maps outside ``[-1, 1]``). Actions (position 3, rot6d 6, gripper 1): position and gripper
are min-max normalized, rot6d is left as-is (already in ``[-1, 1]``), following Diffusion
Policy's normalizer for robomimic absolute actions. A dimension whose range is below
``range_eps`` is treated as constant and mapped to 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from impact_control.errors import CheckpointError

ACTION_POS = slice(0, 3)
ACTION_ROT6D = slice(3, 9)
ACTION_GRIPPER = slice(9, 10)


@dataclass(frozen=True)
class AffineMap:
    """``y = x * scale + offset`` per dimension; the inverse is ``x = (y - offset) / scale``.

    Attributes:
        scale: ``(D,)`` float32.
        offset: ``(D,)`` float32.
    """

    scale: torch.Tensor
    offset: torch.Tensor

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Normalize ``x`` ``(..., D)``."""
        return x * self.scale.to(x) + self.offset.to(x)

    def inverse(self, y: torch.Tensor) -> torch.Tensor:
        """Un-normalize ``y`` ``(..., D)``."""
        return (y - self.offset.to(y)) / self.scale.to(y)

    @property
    def dim(self) -> int:
        """Number of dimensions D."""
        return int(self.scale.shape[0])


def fit_minmax(data: np.ndarray, range_eps: float = 1e-4) -> AffineMap:
    """Fit a map of each column of ``data`` ``(N, D)`` onto ``[-1, 1]``.

    Columns whose range is below ``range_eps`` get scale 1 and are centred on 0.
    """
    data = np.asarray(data, dtype=np.float64)
    lo, hi = data.min(axis=0), data.max(axis=0)
    span = hi - lo
    constant = span < range_eps
    scale = np.where(constant, 1.0, 2.0 / np.where(constant, 1.0, span))
    offset = np.where(constant, -(lo + hi) / 2.0, -1.0 - scale * lo)
    return AffineMap(
        torch.as_tensor(scale, dtype=torch.float32), torch.as_tensor(offset, dtype=torch.float32)
    )


def fit_action_map(actions: np.ndarray, range_eps: float = 1e-4) -> AffineMap:
    """Fit the action map: min-max for position and gripper, identity for rot6d."""
    actions = np.asarray(actions)
    if actions.ndim != 2 or actions.shape[1] != 10:
        raise ValueError(f"actions must be (N, 10), got {actions.shape}")
    fitted = fit_minmax(actions, range_eps)
    scale, offset = fitted.scale.clone(), fitted.offset.clone()
    scale[ACTION_ROT6D] = 1.0
    offset[ACTION_ROT6D] = 0.0
    return AffineMap(scale, offset)


@dataclass(frozen=True)
class Normalizer:
    """Observation and action maps of one training set (stored with the checkpoint).

    Attributes:
        obs: Map of the flat observation vector (one step, D_obs).
        action: Map of one action (10).
    """

    obs: AffineMap
    action: AffineMap

    @classmethod
    def fit(cls, obs: np.ndarray, actions: np.ndarray, range_eps: float = 1e-4) -> Normalizer:
        """Fit on observations ``(N, D_obs)`` and actions ``(N, 10)``."""
        return cls(fit_minmax(obs, range_eps), fit_action_map(actions, range_eps))

    def state_dict(self) -> dict[str, torch.Tensor]:
        """Flat ``{name: tensor}`` dict for safetensors."""
        out = {}
        for group in ("obs", "action"):
            amap: AffineMap = getattr(self, group)
            out[f"{group}.scale"] = amap.scale.contiguous()
            out[f"{group}.offset"] = amap.offset.contiguous()
        return out

    @classmethod
    def from_state_dict(cls, tensors: dict[str, torch.Tensor]) -> Normalizer:
        """Inverse of ``state_dict``; raises CheckpointError on missing or bad entries."""
        maps = {}
        for group in ("obs", "action"):
            try:
                scale = tensors[f"{group}.scale"].float()
                offset = tensors[f"{group}.offset"].float()
            except KeyError as exc:
                raise CheckpointError(f"normalizer is missing entry {exc.args[0]!r}") from None
            if scale.shape != offset.shape or scale.ndim != 1 or bool((scale == 0).any()):
                raise CheckpointError(f"normalizer entries for {group!r} are malformed")
            maps[group] = AffineMap(scale, offset)
        if maps["action"].dim != 10:
            raise CheckpointError(f"normalizer action dim is {maps['action'].dim}, expected 10")
        return cls(maps["obs"], maps["action"])
