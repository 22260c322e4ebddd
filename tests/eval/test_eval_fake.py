"""The fake env of the impact-eval tests (``fixtures.eval_fake``) behaves as documented."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from fixtures.eval_fake import BARE_ID, ENV_ID, MAX_STEPS


def test_fake_env_success_depends_on_mass_and_controller() -> None:
    rates = {}
    for controller in ("impedance", "impact"):
        env = gym.make(BARE_ID, controller=controller)
        for mass in (0.5, 8.0):
            wins = 0
            for seed in range(40):
                env.reset(seed=seed, options={"object_mass": mass})
                for _ in range(MAX_STEPS):
                    *_, term, trunc, info = env.step(np.ones(10, np.float32))
                    if term or trunc:
                        break
                wins += info["is_success"]
            rates[controller, mass] = wins / 40
    assert rates["impedance", 0.5] > rates["impedance", 8.0]
    assert rates["impact", 8.0] > rates["impedance", 8.0]


def test_a_preset_a_plugin_env_cannot_take_is_a_one_line_error() -> None:
    from impact_control.errors import InvalidArgumentError
    from impact_eval.envs import make_env

    make_env(ENV_ID, "impact").close()  # the default preset needs no argument
    with pytest.raises(InvalidArgumentError, match="controller_preset") as err:
        make_env(ENV_ID, "impact", preset="paper")  # not silently run with another config
    assert "\n" not in str(err.value)
