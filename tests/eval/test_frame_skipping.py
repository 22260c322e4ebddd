"""Rendering only the frames a camera policy reads (issue 56, item 1): a visuomotor diffusion
policy announces which envs' next images it will read (``frames_read_next``), the sweep's
lockstep rollout tells the others to skip rendering (``ImpactEnv.skip_next_images``), and
the episode is the same, bit for bit, as with every frame rendered."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch

import impact_envs  # noqa: F401 - registers the envs
from impact_envs.policies.diffusion.config import DiffusionConfig, ImageEncoderConfig
from impact_envs.policies.diffusion.model import make_network
from impact_envs.policies.diffusion.normalizer import AffineMap, Normalizer
from impact_envs.policies.diffusion.policy import DiffusionPolicy
from impact_eval.rollout import frames_unread, skip_images

ENV_ID = "IMPACT/Hammer-v1"
STATE_KEYS = ("ee_pos", "gripper_width")
OBS = {"obs_mode": "rgb", "cameras": ("overview", "wrist"), "image_width": 24,
       "image_height": 24, "shadows": False}
STEPS = 20


def _policy() -> DiffusionPolicy:
    """An untrained visuomotor DP (identity normalization): its actions depend on every pixel
    it reads, so a zero frame read where a rendered one belonged would change them."""
    vision = ImageEncoderConfig(image_keys=("overview_rgb", "wrist_rgb"), channels=(8,),
                                n_groups=4, keypoints=4, feature_dim=8)
    cfg = DiffusionConfig(obs_keys=STATE_KEYS, n_obs_steps=2, horizon=16, n_action_steps=8,
                          down_dims=(16, 32), num_inference_steps=2, vision=vision)
    torch.manual_seed(0)
    dims = {"ee_pos": 3, "gripper_width": 1}
    net = make_network(cfg, sum(dims.values()))

    def identity(dim: int) -> AffineMap:
        return AffineMap(torch.ones(dim), torch.zeros(dim))

    return DiffusionPolicy(cfg, net, Normalizer(identity(4), identity(10)), dims)


def _episode(skipping: bool) -> tuple[list[np.ndarray], list[bool], list[np.ndarray]]:
    env = gym.make(ENV_ID, observation=OBS)
    policy = _policy()
    policy.reset(1)
    policy.seed_envs([3])
    obs, _ = env.reset(seed=3)
    actions, rendered, positions = [], [], []
    try:
        for _ in range(STEPS):
            action = policy.act({k: v[None] for k, v in obs.items()})[0]
            if skipping and frames_unread(policy, 1)[0]:
                skip_images(env)
            obs, _, _, _, info = env.step(action)
            actions.append(action)
            rendered.append(bool(info["images_rendered"]))
            positions.append(obs["ee_pos"].copy())
    finally:
        env.close()
    return actions, rendered, positions


def test_skipping_unread_frames_changes_no_action_and_no_state() -> None:
    every, all_rendered, pos_every = _episode(skipping=False)
    skipped, rendered, pos_skipped = _episode(skipping=True)
    assert all(all_rendered)
    # replans at steps 0, 8, 16 read observations 7-8 and 15-16 (and the reset's)
    assert [i for i, r in enumerate(rendered) if r] == [6, 7, 14, 15]
    assert all(np.array_equal(a, b) for a, b in zip(every, skipped, strict=True))
    assert all(np.array_equal(a, b) for a, b in zip(pos_every, pos_skipped, strict=True))


def test_a_skipped_observation_holds_zero_images_and_reset_always_renders() -> None:
    env = gym.make(ENV_ID, observation=OBS)
    try:
        obs, _ = env.reset(seed=0)
        hold = np.concatenate([obs["ee_pos"], obs["ee_rot6d"], [-1.0]]).astype(np.float32)
        env.unwrapped.skip_next_images()
        obs, *_, info = env.step(hold)
        assert not info["images_rendered"] and not obs["overview_rgb"].any()
        env.unwrapped.skip_next_images()
        obs, info = env.reset(seed=0)
        assert info["images_rendered"] and obs["overview_rgb"].any()
    finally:
        env.close()


def test_a_state_policy_reads_no_frames_and_a_policy_without_the_hook_skips_none() -> None:
    assert not frames_unread(object(), 3).any()
    state = DiffusionPolicy.__new__(DiffusionPolicy)
    state.cfg, state.n_envs = DiffusionConfig(), 2
    assert not state.frames_read_next().any()
