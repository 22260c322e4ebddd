"""RLActions: a symmetric Box(-1, 1) over every IMPACT env, absolute and delta."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from impact_envs import ENV_IDS
from impact_envs.control.lie import quat_to_matrix
from impact_envs.errors import InvalidArgumentError
from impact_envs.wrappers import RLActions


@pytest.mark.parametrize("mode", ["absolute", "delta"])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_action_in_the_box_is_valid(env_id, mode, recwarn):
    env = RLActions(gym.make(env_id), mode=mode)
    check_env(env, skip_render_check=True)
    assert not [w for w in recwarn if "symmetric and normalized" in str(w.message)]
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    corners = rng.choice([-1.0, 1.0], size=(5, env.action_space.shape[0]))
    for a in [*corners, np.zeros(env.action_space.shape[0])]:
        obs, *_ = env.step(a.astype(np.float32))
        assert all(np.isfinite(v).all() for v in obs.values())
    env.close()


def test_absolute_mode_spans_the_workspace_box():
    env = RLActions(gym.make("IMPACT/Hammer-v0"))
    task = env.unwrapped.task
    a = np.concatenate([[-1.0, 1.0, 0.0], np.zeros(7)])
    np.testing.assert_allclose(env.action(a)[:3],
                               [task.workspace_low[0], task.workspace_high[1],
                                (task.workspace_low[2] + task.workspace_high[2]) / 2], rtol=1e-6)


def test_delta_mode_moves_the_target_by_the_scaled_step():
    env = RLActions(gym.make("IMPACT/Hammer-v0"), mode="delta", max_step_m=0.02,
                    max_turn_rad=0.1)
    env.reset(seed=0)
    base = env.unwrapped
    pos0, rot0 = base.target_pos_world, quat_to_matrix(base.target_quat_world)
    env.step(np.array([1.0, -0.5, 0.0, 0.0, 0.0, 1.0, -1.0], dtype=np.float32))
    np.testing.assert_allclose(base.target_pos_world - pos0, [0.02, -0.01, 0.0], atol=1e-6)
    turn = quat_to_matrix(base.target_quat_world) @ rot0.T  # world-frame rotation of the target
    assert np.degrees(np.arccos((np.trace(turn) - 1) / 2)) == pytest.approx(np.degrees(0.1),
                                                                              abs=1e-3)
    assert turn[1, 0] > 0  # about +z


def test_unknown_mode_is_one_line():
    with pytest.raises(InvalidArgumentError, match="valid choices: absolute, delta"):
        RLActions(gym.make("IMPACT/Hammer-v0"), mode="relative")


@pytest.mark.parametrize("algo", ["PPO", "SAC"])
def test_sb3_trains_a_few_hundred_steps(algo):
    sb3 = pytest.importorskip("stable_baselines3")
    env = RLActions(gym.make("IMPACT/Hammer-v0"), mode="delta")
    kwargs = {"n_steps": 64, "batch_size": 32} if algo == "PPO" else {"learning_starts": 32,
                                                                      "batch_size": 32}
    model = getattr(sb3, algo)("MultiInputPolicy", env, seed=0, device="cpu", **kwargs)
    model.learn(128)
    env.close()


def test_a_physics_blow_up_ends_the_episode_instead_of_raising(monkeypatch):
    """A PPO run on Disturbance (IMPACT, delta) hit "velocity blow-up" and the raise killed
    training; the wrapper turns it into a terminated episode with the reason in info."""
    from impact_envs.errors import SimulationError

    env = RLActions(gym.make("IMPACT/Disturbance-v0"), mode="delta")
    first, _ = env.reset(seed=0)

    def blow_up(*args, **kwargs):
        raise SimulationError("velocity blow-up at t=0.610 s")

    monkeypatch.setattr(env.unwrapped, "step", blow_up)
    obs, reward, terminated, truncated, info = env.step(np.zeros(7, dtype=np.float32))
    assert (reward, terminated, truncated) == (0.0, True, False)
    assert info["failure_reason"] == "unstable: velocity blow-up at t=0.610 s"
    for key in first:
        np.testing.assert_array_equal(obs[key], first[key])
