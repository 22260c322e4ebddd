"""Visuomotor observation encoder: one small ResNet per camera (GroupNorm, spatial softmax).

Diffusion Policy's vision recipe (Chi et al.) sized for a CPU: per camera, a ResNet-style
trunk (3x3 stem with stride 2, one residual block per stage, GroupNorm instead of BatchNorm so
that small batches and EMA weights behave), a spatial softmax that turns each of ``keypoints``
feature maps into the expected image coordinates of its activation (robomimic's pooling), and a
linear layer to ``feature_dim`` features. Images are cropped first: a random crop per sample and
observation step while training (``module.train()``; DP's augmentation), the centre crop
otherwise. The per-step features of all cameras are concatenated after the normalized
low-dimensional state; the result conditions the denoising U-Net as the state alone does.

No pretrained weights: the trunks start from PyTorch's default initialization (seeded by the
caller, e.g. ``torch.manual_seed(cfg.seed)``).
"""

from __future__ import annotations

from collections.abc import Mapping

import torch
from torch import nn

from impact_control.errors import InvalidArgumentError
from impact_envs.policies.diffusion.config import ImageEncoderConfig


class ResidualBlock2d(nn.Module):
    """Two 3x3 conv + GroupNorm layers with a skip connection (1x1 conv when shapes change)."""

    def __init__(self, c_in: int, c_out: int, stride: int, n_groups: int) -> None:
        super().__init__()
        self.body = nn.Sequential(
            nn.Conv2d(c_in, c_out, 3, stride=stride, padding=1, bias=False),
            nn.GroupNorm(n_groups, c_out), nn.ReLU(),
            nn.Conv2d(c_out, c_out, 3, padding=1, bias=False), nn.GroupNorm(n_groups, c_out))
        self.skip: nn.Module = nn.Identity()
        if stride != 1 or c_in != c_out:
            self.skip = nn.Sequential(nn.Conv2d(c_in, c_out, 1, stride=stride, bias=False),
                                      nn.GroupNorm(n_groups, c_out))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.relu(self.body(x) + self.skip(x))


class SpatialSoftmax(nn.Module):
    """``(B, C, H, W)`` -> ``(B, 2 K)``: the expected (x, y) in [-1, 1] of each of K maps."""

    def __init__(self, c_in: int, keypoints: int) -> None:
        super().__init__()
        self.project = nn.Conv2d(c_in, keypoints, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        maps = self.project(x)
        b, k, h, w = maps.shape
        attention = torch.softmax(maps.flatten(2), dim=-1)  # (B, K, H*W)
        ys, xs = torch.meshgrid(torch.linspace(-1.0, 1.0, h, device=x.device),
                                torch.linspace(-1.0, 1.0, w, device=x.device), indexing="ij")
        grid = torch.stack([xs.flatten(), ys.flatten()], dim=-1)  # (H*W, 2)
        return (attention @ grid).reshape(b, 2 * k)


class ImageEncoder(nn.Module):
    """One camera's trunk: ``(B, 3, h, w)`` float in [-1, 1] -> ``(B, feature_dim)``."""

    def __init__(self, cfg: ImageEncoderConfig) -> None:
        super().__init__()
        c0, g = cfg.channels[0], cfg.n_groups
        layers: list[nn.Module] = [nn.Conv2d(3, c0, 3, stride=2, padding=1, bias=False),
                                   nn.GroupNorm(g, c0), nn.ReLU()]
        for i, c_out in enumerate(cfg.channels):
            layers.append(ResidualBlock2d(cfg.channels[max(i - 1, 0)], c_out,
                                          1 if i == 0 else 2, g))
        self.trunk = nn.Sequential(*layers)
        self.pool = SpatialSoftmax(cfg.channels[-1], cfg.keypoints)
        self.out = nn.Linear(2 * cfg.keypoints, cfg.feature_dim)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.out(self.pool(self.trunk(x)))


def crop(images: torch.Tensor, size: tuple[int, int], random: bool,
         generator: torch.Generator | None = None) -> torch.Tensor:
    """Crop ``images`` ``(N, C, H, W)`` to ``size``: at a random place per image (drawn from
    ``generator``, or torch's global generator when None) if ``random``, else in the centre."""
    n, _, h, w = images.shape
    ch, cw = size
    if not random:
        top, left = (h - ch) // 2, (w - cw) // 2
        return images[:, :, top:top + ch, left:left + cw]
    tops = torch.randint(h - ch + 1, (n,), generator=generator)
    lefts = torch.randint(w - cw + 1, (n,), generator=generator)
    rows = (tops[:, None] + torch.arange(ch))[:, None, :, None]  # (N, 1, ch, 1)
    cols = (lefts[:, None] + torch.arange(cw))[:, None, None, :]  # (N, 1, 1, cw)
    index = torch.arange(n)[:, None, None, None]
    return images.permute(0, 2, 3, 1)[index, rows, cols].squeeze(1).permute(0, 3, 1, 2)


class ObservationEncoder(nn.Module):
    """State and camera images of ``To`` steps -> the per-step condition of the U-Net.

    Args:
        cfg: Encoder hyper-parameters (``cfg.image_keys`` are the cameras).
        state_dim: Size of the normalized low-dimensional state (0: images only).
    """

    def __init__(self, cfg: ImageEncoderConfig, state_dim: int) -> None:
        super().__init__()
        self.cfg, self.state_dim = cfg, state_dim
        self.cameras = nn.ModuleDict({k: ImageEncoder(cfg) for k in cfg.image_keys})

    @property
    def out_dim(self) -> int:
        """Features per observation step: the state, then ``feature_dim`` per camera."""
        return self.state_dim + len(self.cfg.image_keys) * self.cfg.feature_dim

    def forward(self, state: torch.Tensor, images: Mapping[str, torch.Tensor],
                generator: torch.Generator | None = None) -> torch.Tensor:
        """Encode ``state`` ``(B, To, D)`` and ``images[key]`` ``(B, To, H, W, 3)`` uint8 into
        ``(B, To, out_dim)``. Random crops (from ``generator``) only in training mode."""
        b, t = state.shape[:2]
        parts = [state]
        for key, encoder in self.cameras.items():
            if key not in images:
                raise InvalidArgumentError(
                    f"missing image {key!r}; valid keys: {', '.join(self.cfg.image_keys)}")
            x = images[key].reshape(b * t, *images[key].shape[2:]).permute(0, 3, 1, 2)
            x = x.float() / 127.5 - 1.0
            size = self.cfg.crop_size(x.shape[2], x.shape[3])
            x = crop(x, size, self.training, generator)
            parts.append(encoder(x).reshape(b, t, -1))
        return torch.cat(parts, dim=-1)


class VisuomotorNet(nn.Module):
    """A visuomotor policy's network: the camera encoder and the denoising U-Net, trained
    together (one optimizer, one EMA, one checkpoint: ``encoder.*`` and ``unet.*``).

    ``encode`` turns the normalized state history and its images into the condition; the call
    then denoises exactly as the state-based U-Net does (``net(sample, step, cond)``).
    """

    def __init__(self, encoder: ObservationEncoder, unet: nn.Module) -> None:
        super().__init__()
        self.encoder, self.unet = encoder, unet

    def encode(self, state: torch.Tensor, images: Mapping[str, torch.Tensor],
               generator: torch.Generator | None = None) -> torch.Tensor:
        """``(B, To, D)`` state and ``(B, To, H, W, 3)`` uint8 images -> ``(B, To, C)``."""
        return self.encoder(state, images, generator)

    def forward(self, sample: torch.Tensor, timestep: torch.Tensor | int,
                global_cond: torch.Tensor) -> torch.Tensor:
        """The U-Net's prediction for an already encoded condition ``(B, To * C)``."""
        return self.unet(sample, timestep, global_cond)
