"""``DiffusionConfig.action_xyz="delta_measured"``: the authors' action convention, trained on
offsets from each step's recorded TCP position and executed on the measured one."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from fixtures.reach_demos import write_dataset

from impact_control.errors import InvalidArgumentError
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_experiments.dp_inference_cost import random_policy
from impact_learn.dataset import EpisodeMeta, ReplayWriter, load_replay
from impact_learn.train_data import load_train_data

torch.set_num_threads(1)
CFG = DiffusionConfig(down_dims=(16, 32), diffusion_step_embed_dim=16, num_inference_steps=4)
DELTA = DiffusionConfig(**{**CFG.to_dict(), "action_xyz": "delta_measured"})


def test_config_keeps_old_files_and_refuses_unknown_frames():
    assert "action_xyz" not in CFG.to_dict()  # absolute: shipped config files unchanged
    assert DiffusionConfig.from_dict(DELTA.to_dict()) == DELTA
    with pytest.raises(InvalidArgumentError, match="absolute.*delta_measured"):
        DiffusionConfig(action_xyz="relative")


def test_training_targets_are_offsets_from_the_recorded_tcp(tmp_path):
    path = tmp_path / "demo.zarr"
    write_dataset(path, n_episodes=4, length=10)
    replay = load_replay(path)
    absolute = load_train_data(CFG, path, val_fraction=0.0)
    delta = load_train_data(DELTA, path, val_fraction=0.0)
    recorded = torch.from_numpy(np.asarray(replay.data["action"], np.float32))
    ee = np.asarray(replay.data["ee_pos"], np.float32)
    expected = recorded.clone()
    expected[:, :3] -= torch.from_numpy(ee)
    # the min-max map was fitted on the offsets: they span [-1, 1] exactly, per axis
    scaled = delta.normalizer.action.forward(expected)[:, :3]
    torch.testing.assert_close(scaled.amin(0), -torch.ones(3), atol=1e-5, rtol=0)
    torch.testing.assert_close(scaled.amax(0), torch.ones(3), atol=1e-5, rtol=0)
    # the absolute map spans the positions, ten steps' worth of offsets: far wider
    assert (absolute.normalizer.action.scale[:3] < delta.normalizer.action.scale[:3] / 3).all()
    assert torch.equal(absolute.normalizer.action.scale[3:], delta.normalizer.action.scale[3:])


def test_policy_adds_the_measured_tcp_at_each_executed_step(monkeypatch):
    policy = random_policy(DELTA)
    offsets = np.zeros((2, DELTA.n_action_steps, 10), np.float32)
    offsets[:, :, :3] = [0.01, -0.02, 0.03]
    monkeypatch.setattr(policy, "predict_chunk", lambda envs: offsets[: len(envs)])
    policy.reset(2)
    rng = np.random.default_rng(0)
    for _ in range(3):  # one chunk: every step meets the TCP measured at that step
        obs = {k: rng.uniform(-1, 1, (2, d)).astype(np.float32)
               for k, d in policy.obs_dims.items()}
        actions = policy.act(obs)
        np.testing.assert_allclose(actions[:, :3], obs["ee_pos"] + offsets[0, 0, :3],
                                   atol=1e-7)


def test_a_store_without_the_tcp_position_is_one_line(tmp_path):
    path = tmp_path / "no_ee.zarr"
    writer = ReplayWriter(path, {"goal_pos": 3}, {"env_id": "Synthetic-v0",
                                                  "param_name": "object_mass"})
    actions = np.zeros((6, 10), np.float32)
    writer.append_episode({"goal_pos": np.zeros((6, 3), np.float32)}, actions,
                          EpisodeMeta(0.2, 0, True, 0))
    cfg = DiffusionConfig(**{**DELTA.to_dict(), "obs_keys": ["goal_pos"]})
    with pytest.raises(InvalidArgumentError, match="needs the store's ee_pos") as err:
        load_train_data(cfg, path, val_fraction=0.0)
    assert "\n" not in str(err.value)
