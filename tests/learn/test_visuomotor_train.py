"""Visuomotor Diffusion Policy: training on an image store, export, rollout, checks."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from safetensors.torch import load_file

from impact_control.errors import CheckpointError, InvalidArgumentError
from impact_envs.policies.diffusion.config import DiffusionConfig, ImageEncoderConfig
from impact_envs.policies.diffusion.policy import DiffusionPolicy
from impact_envs.policies.diffusion.vision import VisuomotorNet
from impact_learn.dataset import EpisodeMeta, ImageSpec, ReplayWriter
from impact_learn.train import RunOptions, train

torch.set_num_threads(1)
SIZE = 16
VISION = ImageEncoderConfig(image_keys=("overview_rgb", "wrist_rgb"), channels=(8, 8),
                            keypoints=4, feature_dim=8)
CFG = DiffusionConfig(obs_keys=("ee_pos", "gripper_width"), down_dims=(16, 32),
                      diffusion_step_embed_dim=16, num_inference_steps=4, batch_size=8,
                      vision=VISION)
DIMS = {"ee_pos": 3, "gripper_width": 1, "overview_rgb": ImageSpec((SIZE, SIZE, 3), "uint8"),
        "wrist_rgb": ImageSpec((SIZE, SIZE, 3), "uint8")}
OBSERVATION = {"obs_mode": "rgb", "cameras": ["overview", "wrist"], "image_width": SIZE,
               "image_height": SIZE, "shadows": False}


def _image_of(goal: np.ndarray) -> np.ndarray:
    """A dark image with one bright pixel where ``goal``'s x, y fall (the state lacks it)."""
    image = np.zeros((SIZE, SIZE, 3), np.uint8)
    row, col = (np.clip((goal[:2] + 0.3) / 0.6 * (SIZE - 1), 0, SIZE - 1)).astype(int)
    image[row, col] = 255
    return image


def write_image_store(path, n_episodes: int = 4, length: int = 10) -> None:
    """Reach demos whose goal is seen only in the images."""
    rng = np.random.default_rng(0)
    attrs = {"env_id": "Synthetic-v0", "param_name": "object_mass", "observation": OBSERVATION}
    writer = ReplayWriter(path, DIMS, attrs)
    rot6d = np.tile([1, 0, 0, 0, 1, 0], (length, 1)).astype(np.float32)
    for ep in range(n_episodes):
        goal = rng.uniform(-0.3, 0.3, 3)
        pos = np.linspace(0, 1, length + 1)[:, None] * goal
        image = np.broadcast_to(_image_of(goal), (length, SIZE, SIZE, 3))
        obs = {"ee_pos": pos[:-1], "gripper_width": np.zeros((length, 1)),
               "overview_rgb": image, "wrist_rgb": 255 - image}
        actions = np.concatenate([pos[1:], rot6d, np.ones((length, 1))], axis=1)
        writer.append_episode(obs, actions, EpisodeMeta(0.2, ep, True, ep))


@pytest.fixture
def store(tmp_path):
    path = tmp_path / "rgb.zarr"
    write_image_store(path)
    return path


def _opts(steps: int, resume: bool = False) -> RunOptions:
    return RunOptions(steps=steps, checkpoint_every=2, val_every=2, val_fraction=0.25,
                      resume=resume, progress=False)


def _obs(n: int, goal_seen: np.ndarray) -> dict[str, np.ndarray]:
    image = np.stack([_image_of(goal_seen)] * n)
    return {"ee_pos": np.zeros((n, 3), np.float32), "gripper_width": np.zeros((n, 1), np.float32),
            "overview_rgb": image, "wrist_rgb": 255 - image}


def test_train_export_and_rollout(store, tmp_path):
    out = tmp_path / "run"
    train(CFG, store, out, _opts(4))
    policy = DiffusionPolicy.load(out / "policy")
    assert isinstance(policy.net, VisuomotorNet) and policy.cfg.vision == VISION
    weights = load_file(str(out / "policy" / "model.safetensors"))
    assert any(k.startswith("encoder.cameras.wrist_rgb.") for k in weights)
    assert any(k.startswith("unet.") for k in weights)
    assert json.loads((out / "policy" / "config.json").read_text())["vision"]["keypoints"] == 4
    policy.reset(2)
    actions = policy.act(_obs(2, np.array([0.2, -0.1, 0.0])))
    assert actions.shape == (2, 10) and np.isfinite(actions).all()
    again = DiffusionPolicy.load(out / "policy")
    again.reset(2)
    assert np.array_equal(again.act(_obs(2, np.array([0.2, -0.1, 0.0]))), actions)


def test_images_change_the_actions(store, tmp_path):
    """The condition carries the images: another image gives other actions, same noise."""
    train(CFG, store, tmp_path / "run", _opts(4))
    a, b = (DiffusionPolicy.load(tmp_path / "run" / "policy") for _ in range(2))
    a.reset(1)
    b.reset(1)
    seen_a = a.act(_obs(1, np.array([0.25, 0.25, 0.0])))
    seen_b = b.act(_obs(1, np.array([-0.25, -0.25, 0.0])))
    assert not np.array_equal(seen_a, seen_b)


def test_resume_is_bit_exact(store, tmp_path):
    train(CFG, store, tmp_path / "full", _opts(4))
    train(CFG, store, tmp_path / "split", _opts(2))
    train(CFG, store, tmp_path / "split", _opts(4, resume=True))
    full = load_file(str(tmp_path / "full" / "train_state" / "tensors.safetensors"))
    split = load_file(str(tmp_path / "split" / "train_state" / "tensors.safetensors"))
    assert full.keys() == split.keys()
    assert all(torch.equal(full[k], split[k]) for k in full)


def test_bad_inputs_are_one_line(store, tmp_path):
    no_camera = DiffusionConfig(**{**CFG.to_dict(), "vision": {"image_keys": ["side_rgb"]}})
    with pytest.raises(InvalidArgumentError, match="valid image keys: overview_rgb, wrist_rgb"):
        train(no_camera, store, tmp_path / "a", _opts(2))
    with pytest.raises(InvalidArgumentError, match="unknown vision keys"):
        DiffusionConfig.from_dict({"vision": {"keypointz": 3}})
    with pytest.raises(InvalidArgumentError, match="vision.keypoints"):
        DiffusionConfig.from_dict({"vision": {"keypoints": "many"}})
    train(CFG, store, tmp_path / "run", _opts(2))
    policy = DiffusionPolicy.load(tmp_path / "run" / "policy")
    policy.reset(1)
    obs = _obs(1, np.zeros(3))
    del obs["wrist_rgb"]
    with pytest.raises(InvalidArgumentError, match="lacks image 'wrist_rgb'"):
        policy.act(obs)


def test_state_config_file_has_no_vision_entry():
    assert "vision" not in DiffusionConfig().to_dict()
    assert DiffusionConfig.from_dict(CFG.to_dict()) == CFG


def test_checkpoint_refuses_other_cameras(store, tmp_path):
    """A visuomotor checkpoint on an env rendering other cameras is one line, before a step."""
    import gymnasium as gym

    import impact_envs  # noqa: F401 - registers the envs
    from impact_envs.envs.options import ObservationOptions
    from impact_envs.policies.diffusion.compat import check_policy_env

    train(CFG, store, tmp_path / "run", _opts(2))
    policy = DiffusionPolicy.load(tmp_path / "run" / "policy")
    policy.meta["dataset"]["attrs"]["env_id"] = "IMPACT/Hammer-v1"
    env = gym.make("IMPACT/Hammer-v1", observation=ObservationOptions(
        obs_mode="rgb", cameras=("overview", "wrist"), image_width=SIZE, image_height=SIZE))
    try:
        with pytest.raises(CheckpointError, match="shadows=False"):
            check_policy_env(policy, "IMPACT/Hammer-v1", env, "run")
    finally:
        env.close()
