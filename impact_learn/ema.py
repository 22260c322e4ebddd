"""Exponential moving average of model weights with Diffusion Policy's warm-up schedule.

The decay after ``k`` updates is ``1 - (1 + (k - 1) / inv_gamma) ** -power`` clamped into
``[min_decay, max_decay]`` (0 for the first two updates, so the average starts as a copy). With
power 0.75 the decay passes 0.999 after about 10k updates.
"""

from __future__ import annotations

import copy

import torch
from torch import nn


class EMA:
    """EMA copy of a model; ``update`` after every optimizer step.

    Args:
        model: The trained model (copied; the copy holds the averaged weights).
        power: Decay exponent (0.75).
        inv_gamma: Step scale of the warm-up [updates].
        min_decay: Lower bound of the decay.
        max_decay: Upper bound of the decay.
    """

    def __init__(
        self,
        model: nn.Module,
        power: float = 0.75,
        inv_gamma: float = 1.0,
        min_decay: float = 0.0,
        max_decay: float = 0.9999,
    ) -> None:
        self.model = copy.deepcopy(model).eval().requires_grad_(False)
        self.power, self.inv_gamma = power, inv_gamma
        self.min_decay, self.max_decay = min_decay, max_decay
        self.n_updates = 0

    def decay(self) -> float:
        """Decay applied by the next ``update``."""
        k = max(0, self.n_updates - 1)
        if k == 0:
            return 0.0
        value = 1.0 - (1.0 + k / self.inv_gamma) ** -self.power
        return float(min(max(value, self.min_decay), self.max_decay))

    @torch.no_grad()
    def update(self, model: nn.Module) -> None:
        """Blend ``model``'s trainable weights into the average; copy everything else."""
        decay = self.decay()
        source = dict(model.named_parameters())
        for name, avg in self.model.named_parameters():
            param = source[name]
            if param.requires_grad:
                avg.mul_(decay).add_(param.detach(), alpha=1.0 - decay)
            else:
                avg.copy_(param.detach())
        source_buffers = dict(model.named_buffers())
        for name, buf in self.model.named_buffers():
            buf.copy_(source_buffers[name])
        self.n_updates += 1
