"""Diffusion model pieces shared by training and rollout: network, schedulers, loss, sampler.

Training noises actions with diffusers' ``DDPMScheduler.add_noise``; rollout denoises with
``DDIMScheduler`` (same ``alphas_cumprod``, ``cfg.num_inference_steps`` steps, eta = 0).
All tensors here live in normalized space (see normalizer.py).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import torch
from diffusers import DDIMScheduler, DDPMScheduler
from torch import nn

from impact_control.policy import ACTION_DIM
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.network import ConditionalUnet1D
from impact_envs.policies.diffusion.vision import ObservationEncoder, VisuomotorNet

DiffusionNet = ConditionalUnet1D | VisuomotorNet
"""A state-based policy's U-Net, or a visuomotor policy's encoder + U-Net."""


def make_network(cfg: DiffusionConfig, obs_dim: int) -> DiffusionNet:
    """Build the network for ``obs_dim``-dimensional states (plus ``cfg.vision``'s cameras),
    conditioned on ``To`` steps of them."""
    encoder = ObservationEncoder(cfg.vision, obs_dim) if cfg.vision is not None else None
    step_dim = encoder.out_dim if encoder is not None else obs_dim
    unet = ConditionalUnet1D(
        action_dim=ACTION_DIM,
        global_cond_dim=cfg.n_obs_steps * step_dim,
        down_dims=cfg.down_dims,
        kernel_size=cfg.kernel_size,
        n_groups=cfg.n_groups,
        step_embed_dim=cfg.diffusion_step_embed_dim,
    )
    return unet if encoder is None else VisuomotorNet(encoder, unet)


def encode(net: nn.Module, obs: torch.Tensor, images: Mapping[str, torch.Tensor],
           generator: torch.Generator | None = None) -> torch.Tensor:
    """The per-step condition ``(B, To, C)`` of a normalized state history ``obs``
    ``(B, To, D)``: the state itself, or with a ``VisuomotorNet`` the state and its images'
    features (random crops from ``generator`` while ``net`` is in training mode)."""
    if isinstance(net, VisuomotorNet):
        return net.encode(obs, images, generator)
    return obs


def make_train_scheduler(cfg: DiffusionConfig) -> DDPMScheduler:
    """DDPM scheduler used for ``add_noise`` during training (fixed_small variance)."""
    return DDPMScheduler(
        num_train_timesteps=cfg.num_train_timesteps,
        beta_schedule=cfg.beta_schedule,
        variance_type="fixed_small",
        clip_sample=cfg.clip_sample,
        prediction_type=cfg.prediction_type,
    )


def make_inference_scheduler(cfg: DiffusionConfig) -> DDIMScheduler:
    """DDIM scheduler with ``cfg.num_inference_steps`` steps already set."""
    scheduler = DDIMScheduler(
        num_train_timesteps=cfg.num_train_timesteps,
        beta_schedule=cfg.beta_schedule,
        clip_sample=cfg.clip_sample,
        set_alpha_to_one=True,
        steps_offset=0,
        prediction_type=cfg.prediction_type,
    )
    scheduler.set_timesteps(cfg.num_inference_steps)
    return scheduler


def diffusion_loss(
    net: nn.Module,
    scheduler: DDPMScheduler,
    obs: torch.Tensor,
    actions: torch.Tensor,
    generator: torch.Generator,
) -> torch.Tensor:
    """Denoising MSE of one batch.

    Args:
        net: The U-Net (or a ``VisuomotorNet``: its forward is its U-Net's).
        scheduler: Training scheduler (``add_noise``).
        obs: Per-step condition ``(B, To, C)``: the normalized state history, or ``encode``'s.
        actions: Normalized action sequence ``(B, Tp, 10)``.
        generator: Source of the noise and diffusion steps.

    Returns:
        Scalar loss (mean over batch, horizon and action dims).
    """
    batch = actions.shape[0]
    noise = torch.randn(actions.shape, generator=generator, dtype=actions.dtype)
    steps = torch.randint(scheduler.config.num_train_timesteps, (batch,), generator=generator).to(
        actions.device
    )
    noise = noise.to(actions.device)
    noisy = scheduler.add_noise(actions, noise, steps)
    pred = net(noisy, steps, obs.flatten(1))
    target = noise if scheduler.config.prediction_type == "epsilon" else actions
    return torch.nn.functional.mse_loss(pred, target)


@torch.no_grad()
def denoise(
    net: Callable[[torch.Tensor, torch.Tensor, torch.Tensor], torch.Tensor],
    scheduler: DDIMScheduler,
    obs: torch.Tensor,
    noise: torch.Tensor,
) -> torch.Tensor:
    """Run the reverse process from ``noise`` ``(B, Tp, 10)`` given ``obs`` ``(B, To, C)``
    (the per-step condition, as in ``diffusion_loss``).

    ``net`` is the U-Net or a traced copy of it (``inference.frozen_unet``).

    Returns:
        Normalized action sequence ``(B, Tp, 10)``.
    """
    cond = obs.flatten(1)
    sample = noise
    for step in scheduler.timesteps:
        pred = net(sample, step.to(sample.device), cond)
        sample = scheduler.step(pred, step, sample).prev_sample
    return sample
