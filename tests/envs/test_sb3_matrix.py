"""SB3 PPO and SAC with default hyper-parameters on every env, both controllers, both action
modes (slow: 20,000 steps each; ``IMPACT_SB3_STEPS`` shortens it)."""

from __future__ import annotations

import os

import gymnasium as gym
import pytest

from impact_envs import ENV_IDS
from impact_envs.wrappers import RLActions

STEPS = int(os.environ.get("IMPACT_SB3_STEPS", "20000"))


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["absolute", "delta"])
@pytest.mark.parametrize("controller", ["impact", "impedance"])
@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("algo", ["PPO", "SAC"])
def test_default_sb3_runs_without_an_exception(algo, env_id, controller, mode):
    sb3 = pytest.importorskip("stable_baselines3")
    env = RLActions(gym.make(env_id, controller=controller, reward_type="dense"), mode=mode)
    getattr(sb3, algo)("MultiInputPolicy", env, seed=0, device="cpu").learn(STEPS)
    env.close()
