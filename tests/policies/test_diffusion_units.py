"""Unit tests of the Diffusion Policy building blocks: config, network, normalizer, EMA, data."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from impact_control.errors import InvalidArgumentError
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.model import make_inference_scheduler, make_network
from impact_envs.policies.diffusion.network import ConditionalUnet1D
from impact_envs.policies.diffusion.normalizer import Normalizer
from impact_learn.dataset import (
    EpisodeMeta,
    ReplayWriter,
    load_replay,
)
from impact_learn.ema import EMA
from impact_learn.windows import window_indices

torch.set_num_threads(1)


def test_config_json_round_trip(tmp_path):
    cfg = DiffusionConfig(horizon=32, down_dims=(32, 64), seed=7)
    cfg.to_json(tmp_path / "c.json")
    assert DiffusionConfig.from_json(tmp_path / "c.json") == cfg


@pytest.mark.parametrize(
    "changes",
    [
        {"horizon": 18},  # not divisible by 4
        {"n_action_steps": 16},  # > Tp - To + 1
        {"beta_schedule": "cosine"},
        {"prediction_type": "v"},
        {"kernel_size": 4},
        {"n_groups": 7},
    ],
)
def test_config_rejects_invalid(changes):
    with pytest.raises(InvalidArgumentError):
        dataclasses.replace(DiffusionConfig(), **changes)


def test_config_unknown_key():
    with pytest.raises(InvalidArgumentError, match="valid keys"):
        DiffusionConfig.from_dict({"horizons": 16})


@pytest.mark.parametrize("down_dims,horizon", [((64, 128, 256), 16), ((32, 64), 10), ((16,), 7)])
def test_network_shapes(down_dims, horizon):
    net = ConditionalUnet1D(10, 44, down_dims=down_dims, n_groups=8, step_embed_dim=32)
    x = torch.randn(3, horizon, 10)
    assert net(x, torch.tensor([0, 5, 99]), torch.randn(3, 44)).shape == (3, horizon, 10)
    assert net(x, 3, torch.randn(3, 44)).shape == (3, horizon, 10)


def test_network_size_matches_recipe():
    net = make_network(DiffusionConfig(), obs_dim=22)
    n_params = sum(p.numel() for p in net.parameters())
    assert 4.0e6 < n_params < 4.6e6  # dp.md: tiny net ~4.3 M


def test_ddim_timesteps():
    scheduler = make_inference_scheduler(DiffusionConfig())
    assert scheduler.timesteps.tolist() == list(range(90, -1, -10))


def test_normalizer_round_trip_and_ranges():
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(500, 5)).astype(np.float32)
    obs[:, 2] = 0.3  # constant dim
    actions = rng.uniform(-2, 2, size=(500, 10)).astype(np.float32)
    actions[:, 3:9] = rng.uniform(-1, 1, size=(500, 6))
    actions[:, 9] = rng.choice([-1.0, 1.0], size=500)
    norm = Normalizer.fit(obs, actions)
    obs_n = norm.obs.forward(torch.from_numpy(obs))
    assert obs_n.min() >= -1 - 1e-6 and obs_n.max() <= 1 + 1e-6
    assert torch.allclose(obs_n[:, 2], torch.zeros(500))
    act_n = norm.action.forward(torch.from_numpy(actions))
    assert torch.allclose(act_n[:, 3:9], torch.from_numpy(actions[:, 3:9]))  # rot6d as-is
    assert torch.allclose(act_n[:, 9], torch.from_numpy(actions[:, 9]))  # gripper -1/+1
    assert act_n[:, :3].min() >= -1 - 1e-6 and act_n[:, :3].max() <= 1 + 1e-6
    assert torch.allclose(norm.obs.inverse(obs_n), torch.from_numpy(obs), atol=1e-5)
    restored = Normalizer.from_state_dict(norm.state_dict())
    out_of_range = torch.full((1, 5), 10.0)
    assert torch.equal(restored.obs.forward(out_of_range), norm.obs.forward(out_of_range))
    assert restored.obs.forward(out_of_range).max() > 1  # never clipped


def test_ema_schedule_and_average():
    net = torch.nn.Linear(2, 1)
    ema = EMA(net, power=0.75, max_decay=0.9999)
    decays = []
    for _ in range(3):
        decays.append(ema.decay())
        ema.update(net)
    assert decays[:2] == [0.0, 0.0]
    assert decays[2] == pytest.approx(1 - 2**-0.75)
    ema.n_updates = 10_001
    assert ema.decay() == pytest.approx(0.999, abs=2e-4)
    with torch.no_grad():
        net.weight.add_(1.0)
    before = ema.model.weight.clone()
    d = ema.decay()
    ema.update(net)
    assert torch.allclose(ema.model.weight, d * before + (1 - d) * net.weight)


def test_window_indices_padding():
    ends = np.array([5, 8])
    obs_idx, act_idx = window_indices(ends, [0, 1], n_obs_steps=2, horizon=6)
    assert obs_idx.shape == (8, 2) and act_idx.shape == (8, 6)
    assert obs_idx[0].tolist() == [0, 0]  # first obs repeated
    assert act_idx[0].tolist() == [0, 0, 1, 2, 3, 4]
    assert act_idx[4].tolist() == [3, 4, 4, 4, 4, 4]  # last action repeated
    assert obs_idx[5].tolist() == [5, 5]  # second episode starts fresh
    assert act_idx[7].tolist() == [6, 7, 7, 7, 7, 7]
    assert (act_idx[:, 1] == np.arange(8)).all()  # action To-1 is the current step


def _episode(length: int, offset: float) -> tuple[dict, np.ndarray]:
    obs = {"a": np.full((length, 2), offset, np.float32), "b": np.arange(length)[:, None] * 1.0}
    return obs, np.full((length, 10), offset, np.float32)


def test_writer_append_resume_and_truncate(tmp_path):
    path = tmp_path / "d.zarr"
    attrs = {"env_id": "X", "param_name": "object_mass"}
    writer = ReplayWriter(path, {"a": 2, "b": 1}, attrs)
    writer.append_episode(*_episode(4, 1.0), EpisodeMeta(0.2, 11, True, 0))
    with pytest.raises(InvalidArgumentError):
        ReplayWriter(path, {"a": 2, "b": 1}, attrs)
    with pytest.raises(InvalidArgumentError, match="env_id"):
        ReplayWriter(path, {"a": 2, "b": 1}, {"env_id": "Y"}, append=True)
    writer = ReplayWriter(path, {"a": 2, "b": 1}, attrs, append=True)
    writer.root["data/a"].append(np.zeros((3, 2), np.float32))  # simulated crash mid-append
    writer = ReplayWriter(path, {"a": 2, "b": 1}, attrs, append=True)
    writer.append_episode(*_episode(3, 2.0), EpisodeMeta(5.0, 12, True, 3))
    replay = load_replay(path)
    assert replay.episode_ends.tolist() == [4, 7]
    assert replay.data["a"][:, 0].tolist() == [1, 1, 1, 1, 2, 2, 2]
    assert replay.data["action"].shape == (7, 10)
    assert replay.meta["episode_param"].tolist() == [0.2, 5.0]
    assert replay.meta["episode_attempt"].tolist() == [0, 3]
    assert replay.attrs["env_id"] == "X" and replay.attrs["format_version"] == 1
    assert replay.obs_matrix(["b", "a"]).shape == (7, 3)
    with pytest.raises(InvalidArgumentError, match="valid keys"):
        replay.obs_matrix(["c"])
