"""Diffusion model pieces shared by training and rollout: network, schedulers, loss, sampler.

Training noises actions with diffusers' ``DDPMScheduler.add_noise``; rollout denoises with
``DDIMScheduler`` (same ``alphas_cumprod``, ``cfg.num_inference_steps`` steps, eta = 0).
All tensors here live in normalized space (see normalizer.py).
"""

from __future__ import annotations

from collections.abc import Callable

import torch
from diffusers import DDIMScheduler, DDPMScheduler

from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.network import ConditionalUnet1D
from impact_envs.policies.interface import ACTION_DIM


def make_network(cfg: DiffusionConfig, obs_dim: int) -> ConditionalUnet1D:
    """Build the U-Net for ``obs_dim``-dimensional states, conditioned on ``To`` of them."""
    return ConditionalUnet1D(
        action_dim=ACTION_DIM,
        global_cond_dim=cfg.n_obs_steps * obs_dim,
        down_dims=cfg.down_dims,
        kernel_size=cfg.kernel_size,
        n_groups=cfg.n_groups,
        step_embed_dim=cfg.diffusion_step_embed_dim,
    )


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
    net: ConditionalUnet1D,
    scheduler: DDPMScheduler,
    obs: torch.Tensor,
    actions: torch.Tensor,
    generator: torch.Generator,
) -> torch.Tensor:
    """Denoising MSE of one batch.

    Args:
        net: The U-Net.
        scheduler: Training scheduler (``add_noise``).
        obs: Normalized observation history ``(B, To, D_obs)``.
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
    """Run the reverse process from ``noise`` ``(B, Tp, 10)`` given ``obs`` ``(B, To, D)``.

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
