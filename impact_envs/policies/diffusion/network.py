"""1-D temporal conditional U-Net with FiLM conditioning (Diffusion Policy's CNN backbone).

The network maps a noisy action sequence ``(B, T, A)``, a diffusion step ``(B,)`` and a global
condition ``(B, C)`` (the flattened observation history) to a prediction of the same shape as
the action sequence. Every residual block modulates its first convolution's output with a
per-channel scale and bias computed from ``[step embedding, condition]`` (FiLM).
"""

from __future__ import annotations

import math

import torch
from torch import nn


class SinusoidalStepEmbedding(nn.Module):
    """Transformer-style sinusoidal embedding of the (integer) diffusion step."""

    def __init__(self, dim: int) -> None:
        super().__init__()
        if dim % 2:
            raise ValueError(f"embedding dim must be even, got {dim}")
        self.dim = dim

    def forward(self, step: torch.Tensor) -> torch.Tensor:
        """Embed ``step`` ``(B,)`` into ``(B, dim)``: ``[sin(step * f_i), cos(step * f_i)]``."""
        half = self.dim // 2
        exponent = torch.arange(half, device=step.device, dtype=torch.float32) / max(half - 1, 1)
        freqs = torch.exp(-math.log(10000.0) * exponent)
        angles = step.float()[:, None] * freqs[None, :]
        return torch.cat([angles.sin(), angles.cos()], dim=-1)


class ConvNormAct(nn.Sequential):
    """Conv1d ('same' padding) -> GroupNorm -> Mish."""

    def __init__(self, c_in: int, c_out: int, kernel_size: int, n_groups: int) -> None:
        super().__init__(
            nn.Conv1d(c_in, c_out, kernel_size, padding=kernel_size // 2),
            nn.GroupNorm(n_groups, c_out),
            nn.Mish(),
        )


class FiLMResidualBlock(nn.Module):
    """Two ConvNormAct layers; the first one's output is FiLM-modulated by the condition."""

    def __init__(
        self, c_in: int, c_out: int, cond_dim: int, kernel_size: int, n_groups: int
    ) -> None:
        super().__init__()
        self.conv1 = ConvNormAct(c_in, c_out, kernel_size, n_groups)
        self.conv2 = ConvNormAct(c_out, c_out, kernel_size, n_groups)
        self.film = nn.Sequential(nn.Mish(), nn.Linear(cond_dim, 2 * c_out))
        self.skip = nn.Conv1d(c_in, c_out, 1) if c_in != c_out else nn.Identity()

    def forward(self, x: torch.Tensor, cond: torch.Tensor) -> torch.Tensor:
        """Apply the block to ``x`` ``(B, c_in, T)`` with ``cond`` ``(B, cond_dim)``."""
        scale, bias = self.film(cond).unsqueeze(-1).chunk(2, dim=1)  # (B, c_out, 1) each
        h = self.conv1(x) * scale + bias
        return self.conv2(h) + self.skip(x)


class ConditionalUnet1D(nn.Module):
    """Temporal U-Net over the action sequence with global FiLM conditioning.

    Args:
        action_dim: A, size of one action.
        global_cond_dim: C, size of the flattened observation history.
        down_dims: Channels per level; ``len(down_dims) - 1`` down-samplings by 2.
        kernel_size: Temporal kernel size (odd).
        n_groups: GroupNorm groups.
        step_embed_dim: Size of the diffusion-step embedding.
    """

    def __init__(
        self,
        action_dim: int,
        global_cond_dim: int,
        down_dims: tuple[int, ...] = (64, 128, 256),
        kernel_size: int = 5,
        n_groups: int = 8,
        step_embed_dim: int = 64,
    ) -> None:
        super().__init__()
        self.step_encoder = nn.Sequential(
            SinusoidalStepEmbedding(step_embed_dim),
            nn.Linear(step_embed_dim, 4 * step_embed_dim),
            nn.Mish(),
            nn.Linear(4 * step_embed_dim, step_embed_dim),
        )
        cond_dim = step_embed_dim + global_cond_dim

        def block(c_in: int, c_out: int) -> FiLMResidualBlock:
            return FiLMResidualBlock(c_in, c_out, cond_dim, kernel_size, n_groups)

        channels = (action_dim, *down_dims)
        n_levels = len(down_dims)
        self.down = nn.ModuleList()
        for level in range(n_levels):
            c_in, c_out = channels[level], channels[level + 1]
            last = level == n_levels - 1
            resample = nn.Identity() if last else nn.Conv1d(c_out, c_out, 3, stride=2, padding=1)
            self.down.append(nn.ModuleList([block(c_in, c_out), block(c_out, c_out), resample]))
        c_mid = down_dims[-1]
        self.mid = nn.ModuleList([block(c_mid, c_mid), block(c_mid, c_mid)])
        self.up = nn.ModuleList()
        for level in reversed(range(1, n_levels)):
            c_skip, c_out = down_dims[level], down_dims[level - 1]
            resample = nn.ConvTranspose1d(c_out, c_out, 4, stride=2, padding=1)
            self.up.append(nn.ModuleList([block(2 * c_skip, c_out), block(c_out, c_out), resample]))
        self.head = nn.Sequential(
            ConvNormAct(down_dims[0], down_dims[0], kernel_size, n_groups),
            nn.Conv1d(down_dims[0], action_dim, 1),
        )

    def forward(
        self, sample: torch.Tensor, timestep: torch.Tensor | int, global_cond: torch.Tensor
    ) -> torch.Tensor:
        """Predict noise (or the clean sample) for a noisy action sequence.

        Args:
            sample: Noisy actions ``(B, T, A)``.
            timestep: Diffusion step, ``(B,)`` or a scalar shared by the batch.
            global_cond: Flattened observation history ``(B, C)``.

        Returns:
            Prediction ``(B, T, A)``.
        """
        x = sample.transpose(1, 2)  # (B, A, T)
        if not isinstance(timestep, torch.Tensor):  # a tensor stays an input when traced
            timestep = torch.as_tensor(timestep, device=sample.device)
        steps = timestep.reshape(-1).expand(sample.shape[0])
        cond = torch.cat([self.step_encoder(steps), global_cond], dim=-1)
        skips = []
        for block1, block2, downsample in self.down:
            x = block2(block1(x, cond), cond)
            skips.append(x)
            x = downsample(x)
        for mid_block in self.mid:
            x = mid_block(x, cond)
        for block1, block2, upsample in self.up:
            x = torch.cat([x, skips.pop()], dim=1)
            x = upsample(block2(block1(x, cond), cond))
        return self.head(x).transpose(1, 2)
