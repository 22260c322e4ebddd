"""Training data: demonstration store -> normalizer, train/held-out window samplers."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from diffusers import DDPMScheduler

from impact_control.errors import InvalidArgumentError
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.model import make_train_scheduler
from impact_envs.policies.diffusion.normalizer import ACTION_POS, Normalizer
from impact_envs.policies.diffusion.policy import GRIPPER_DIM
from impact_learn.dataset import ACTION_KEY, ReplayData, load_replay
from impact_learn.windows import WindowSampler, window_indices


@dataclass(frozen=True)
class TrainData:
    """Everything the training loop reads.

    Attributes:
        normalizer: Fitted on the training episodes.
        train: Sampler over training windows.
        val: Sampler over held-out windows, or None when no episode is held out.
        obs_dims: ``{obs_key: d_key}`` of ``cfg.obs_keys``.
        scheduler: DDPM scheduler for ``add_noise``.
        info: Dataset description stored with the exported policies.
        fingerprints: Content digest of each array the run reads (``--resume`` compares them).
    """

    normalizer: Normalizer
    train: WindowSampler
    val: WindowSampler | None
    obs_dims: dict[str, int]
    scheduler: DDPMScheduler
    info: dict[str, Any]
    fingerprints: dict[str, str]


def split_episodes(n_episodes: int, val_fraction: float, seed: int) -> tuple[list, list]:
    """Deterministic random split into (train, held-out) episode ids.

    At least one episode is held out when ``val_fraction > 0`` and there are two or more.
    """
    if n_episodes < 1:
        raise InvalidArgumentError("the dataset holds no episodes")
    n_val = int(round(val_fraction * n_episodes))
    if val_fraction > 0 and n_episodes >= 2:
        n_val = min(max(n_val, 1), n_episodes - 1)
    order = np.random.default_rng(seed).permutation(n_episodes)
    return sorted(order[n_val:].tolist()), sorted(order[:n_val].tolist())


def _check_gripper(cfg: DiffusionConfig, gripper: np.ndarray) -> None:
    """``binary_gripper`` executes only the sign of the gripper command: refuse graded demos."""
    if cfg.binary_gripper and not np.all(np.isin(gripper, (-1.0, 1.0))):
        raise InvalidArgumentError(
            "the demos' gripper command takes values other than -1 and +1, but binary_gripper "
            'is on; set "binary_gripper": false in the --config file'
        )


def _images(cfg: DiffusionConfig, replay: ReplayData, path: Path) -> dict[str, torch.Tensor]:
    """The ``(N, H, W, 3)`` uint8 frames of ``cfg.vision``'s cameras (none without vision)."""
    if cfg.vision is None:
        return {}
    keys = cfg.vision.image_keys
    stored = sorted(k for k, a in replay.data.items() if a.ndim == 4)
    missing = [k for k in keys if k not in stored]
    if missing:
        valid = ", ".join(stored) or "none (a state store: impact-collect --obs-mode rgb)"
        raise InvalidArgumentError(
            f"{path} holds no images {missing}; valid image keys: {valid}")
    wrong = [k for k in keys
             if replay.data[k].dtype != np.uint8 or replay.data[k].shape[-1] != 3]
    if wrong:
        raise InvalidArgumentError(
            f"images {wrong} of {path} are not RGB uint8 (H, W, 3); valid: '<camera>_rgb' keys")
    return {k: torch.from_numpy(replay.data[k]) for k in keys}


def _actions_in_frame(cfg: DiffusionConfig, replay: ReplayData, path: Path) -> np.ndarray:
    """The store's actions in the config's ``action_xyz`` frame: as recorded (absolute TCP
    targets), or with each step's recorded TCP position subtracted (``delta_measured``)."""
    actions = np.asarray(replay.data[ACTION_KEY], dtype=np.float32)
    if cfg.action_xyz == "absolute":
        return actions
    if "ee_pos" not in replay.data:
        raise InvalidArgumentError(
            f"{path}: action_xyz {cfg.action_xyz!r} needs the store's ee_pos; it has "
            f"{sorted(replay.data)}")
    actions = actions.copy()
    actions[:, ACTION_POS] -= np.asarray(replay.data["ee_pos"], dtype=np.float32)
    return actions


def load_train_data(cfg: DiffusionConfig, path: Path, val_fraction: float) -> TrainData:
    """Load ``path``, split episodes, fit the normalizer on the training part."""
    replay = load_replay(path)  # every chunk checked; NaN/inf in a state or action refused
    obs = replay.obs_matrix(cfg.obs_keys)
    actions = _actions_in_frame(cfg, replay, path)
    _check_gripper(cfg, np.asarray(actions[:, GRIPPER_DIM]))
    train_eps, val_eps = split_episodes(replay.n_episodes, val_fraction, cfg.seed)
    starts = np.concatenate([[0], replay.episode_ends[:-1]])
    rows = np.concatenate([np.arange(starts[e], replay.episode_ends[e]) for e in train_eps])
    normalizer = Normalizer.fit(obs[rows], actions[rows], cfg.range_eps)
    obs_n = normalizer.obs.forward(torch.from_numpy(obs))
    act_n = normalizer.action.forward(torch.from_numpy(np.asarray(actions, np.float32)))

    images = _images(cfg, replay, path)

    def sampler(episodes: list) -> WindowSampler:
        idx = window_indices(replay.episode_ends, episodes, cfg.n_obs_steps, cfg.horizon)
        return WindowSampler(obs_n, act_n, *idx, images=images)

    info = {
        "path": str(path),
        "n_episodes": replay.n_episodes,
        "n_steps": int(obs.shape[0]),
        "val_episodes": val_eps,
        "attrs": replay.attrs,
    }
    return TrainData(
        normalizer=normalizer,
        train=sampler(train_eps),
        val=sampler(val_eps) if val_eps else None,
        obs_dims={k: int(replay.data[k].shape[1]) for k in cfg.obs_keys},
        scheduler=make_train_scheduler(cfg),
        info=info,
        fingerprints=_fingerprints(replay, cfg),
    )


def _fingerprints(replay: ReplayData, cfg: DiffusionConfig) -> dict[str, str]:
    """Fingerprints of the arrays training reads: observations, cameras, actions, episodes."""
    images = cfg.vision.image_keys if cfg.vision is not None else ()
    names = [f"data/{k}" for k in (*cfg.obs_keys, *images, ACTION_KEY)] + ["meta/episode_ends"]
    return {name: replay.fingerprints[name] for name in names}
