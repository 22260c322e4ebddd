"""The LeRobot policy adapter's side that needs no LeRobot: a batch of our observations laid
out as ``lerobot-eval`` lays out each env's (through the plugin's wrapper and LeRobot's
``preprocess_observation`` conventions), and the one-line refusals of the ``lerobot_*``
methods. The loaded checkpoint's rows are checked in the LeRobot venv (docs/lerobot.md)."""

from __future__ import annotations

import importlib.util

import gymnasium as gym
import numpy as np
import pytest

from impact_control.errors import CheckpointError
from impact_eval.methods import resolve_method
from impact_lerobot import PluginSettings, make_lerobot_env, observation_plan
from impact_lerobot.policy import LEROBOT_MISSING, load_lerobot_policy

HAS_LEROBOT = importlib.util.find_spec("lerobot") is not None


def _two_envs(settings: PluginSettings) -> tuple[list[dict], list[dict]]:
    """Our observation and the wrapper's (what ``lerobot-eval`` gets), for two seeds."""
    ours, theirs = [], []
    for seed in (1, 2):
        env = gym.make(settings.env_id, observation=settings.observation)
        ours.append(env.reset(seed=seed)[0])
        env.close()
        wrapped = make_lerobot_env(settings.task, settings)
        theirs.append(wrapped.reset(seed=seed)[0])
        wrapped.close()
    return ours, theirs


@pytest.mark.parametrize("obs_mode", ["state", "state+rgb"])
def test_policy_batch_is_what_lerobot_eval_feeds(obs_mode: str) -> None:
    settings = PluginSettings(task="Hammer-v1", obs_mode=obs_mode, image_width=32,
                              image_height=24)
    plan = observation_plan(settings)
    ours, theirs = _two_envs(settings)
    batch = plan.policy_batch({k: np.stack([o[k] for o in ours]) for k in ours[0]})
    vectors = {"observation.state": "agent_pos",
               "observation.environment_state": "environment_state"}
    for name, key in vectors.items():
        assert batch[name].dtype == np.float32
        np.testing.assert_array_equal(batch[name], np.stack([t[key] for t in theirs]))
    cameras = [k for k in batch if k.startswith("observation.images.")]
    assert len(cameras) == (2 if obs_mode == "state+rgb" else 0)
    for name in cameras:
        camera = name.rsplit(".", 1)[1]
        frames = np.stack([t["pixels"][camera] for t in theirs])  # B x H x W x 3, uint8
        assert batch[name].shape == (2, 3, 24, 32)
        np.testing.assert_array_equal(
            batch[name], frames.transpose(0, 3, 1, 2).astype(np.float32) / 255.0)


@pytest.mark.skipif(HAS_LEROBOT, reason="LeRobot is installed: its absence cannot be tested")
def test_lerobot_methods_without_lerobot_are_one_line(tmp_path) -> None:
    with pytest.raises(CheckpointError) as err:
        load_lerobot_policy(tmp_path, "IMPACT/Hammer-v1")
    assert str(err.value) == LEROBOT_MISSING and "\n" not in str(err.value)
    for name in ("lerobot_dp", "lerobot_dp_impact"):
        spec = resolve_method(name)
        assert spec.controller == ("impedance" if name == "lerobot_dp" else "impact")
        with pytest.raises(CheckpointError):
            spec.build("IMPACT/Hammer-v1", None)
