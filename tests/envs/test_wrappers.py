"""RLActions: a symmetric Box(-1, 1) over every IMPACT env, absolute and delta."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from impact_control.errors import InvalidArgumentError
from impact_control.lie import quat_to_matrix
from impact_envs import ENV_IDS
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
    env = RLActions(gym.make("IMPACT/Hammer-v1"))
    task = env.unwrapped.task
    a = np.concatenate([[-1.0, 1.0, 0.0], np.zeros(7)])
    np.testing.assert_allclose(env.action(a)[:3],
                               [task.workspace_low[0], task.workspace_high[1],
                                (task.workspace_low[2] + task.workspace_high[2]) / 2], rtol=1e-6)


def test_delta_mode_moves_the_target_by_the_scaled_step():
    env = RLActions(gym.make("IMPACT/Hammer-v1"), mode="delta", max_step_m=0.02,
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
        RLActions(gym.make("IMPACT/Hammer-v1"), mode="relative")


@pytest.mark.parametrize("algo", ["PPO", "SAC"])
def test_sb3_trains_a_few_hundred_steps(algo):
    sb3 = pytest.importorskip("stable_baselines3")
    env = RLActions(gym.make("IMPACT/Hammer-v1"), mode="delta")
    kwargs = {"n_steps": 64, "batch_size": 32} if algo == "PPO" else {"learning_starts": 32,
                                                                      "batch_size": 32}
    model = getattr(sb3, algo)("MultiInputPolicy", env, seed=0, device="cpu", **kwargs)
    model.learn(128)
    env.close()


def test_a_physics_blow_up_ends_the_episode_instead_of_raising(monkeypatch):
    """A PPO run on Disturbance (IMPACT, delta) hit "velocity blow-up" and the raise killed
    training; the wrapper turns it into a terminated episode with the reason in info."""
    from impact_control.errors import SimulationError

    env = RLActions(gym.make("IMPACT/Disturbance-v1"), mode="delta")
    first, _ = env.reset(seed=0)

    def blow_up(*args, **kwargs):
        raise SimulationError("velocity blow-up at t=0.610 s")

    monkeypatch.setattr(env.unwrapped, "step", blow_up)
    obs, reward, terminated, truncated, info = env.step(np.zeros(7, dtype=np.float32))
    assert (reward, terminated, truncated) == (0.0, True, False)
    assert info["failure_reason"] == "unstable: velocity blow-up at t=0.610 s"
    for key in first:
        np.testing.assert_array_equal(obs[key], first[key])


# name: (mode, action, part of the one-line message); the env state must not change
BAD_ACTIONS = {
    "absolute too long": ("absolute", np.zeros(11), "shape (11,)"),
    "absolute too short": ("absolute", np.zeros(7), "shape (7,)"),
    "absolute batched": ("absolute", np.zeros((1, 10)), "shape (1, 10)"),
    "absolute scalar": ("absolute", 0.5, "shape ()"),
    "absolute +inf": ("absolute", np.r_[np.inf, np.zeros(9)], "not finite"),
    "absolute nan": ("absolute", np.r_[np.zeros(9), np.nan], "not finite"),
    "absolute strings": ("absolute", np.array(["0"] * 10), "dtype <U1"),
    "absolute bools": ("absolute", np.ones(10, dtype=bool), "dtype bool"),
    "absolute None": ("absolute", None, "dtype object"),
    "delta ten values": ("delta", np.zeros(10), "shape (10,)"),
    "delta six values": ("delta", np.zeros(6), "shape (6,)"),
    "delta -inf": ("delta", np.r_[-np.inf, np.zeros(6)], "not finite"),
    "delta nan": ("delta", np.full(7, np.nan), "not finite"),
    "delta list of lists": ("delta", [[0.0] * 7], "shape (1, 7)"),
}


@pytest.mark.parametrize("case", sorted(BAD_ACTIONS))
def test_bad_actions_are_one_line_and_change_nothing(case):
    mode, action, message = BAD_ACTIONS[case]
    env = RLActions(gym.make("IMPACT/Hammer-v1"), mode=mode)
    env.reset(seed=0)
    base = env.unwrapped
    before = (base.target_pos_world.copy(), base.sim.data.time)
    with pytest.raises(InvalidArgumentError) as err:
        env.step(action)
    assert message in str(err.value) and "\n" not in str(err.value)
    assert np.array_equal(base.target_pos_world, before[0]) and base.sim.data.time == before[1]


def test_finite_actions_outside_the_box_are_clipped():
    env = RLActions(gym.make("IMPACT/Hammer-v1"))
    a = np.r_[[5.0, -7.0, 0.0], np.zeros(7)]
    b = np.r_[[1.0, -1.0, 0.0], np.zeros(7)]
    np.testing.assert_array_equal(env.action(a), env.action(b))


@pytest.mark.parametrize("kwargs,message", [
    ({"max_step_m": float("nan")}, "invalid max_step_m nan"),
    ({"max_step_m": -0.01}, "invalid max_step_m -0.01"),
    ({"max_step_m": 0.0}, "invalid max_step_m 0.0"),
    ({"max_step_m": "0.02"}, "invalid max_step_m '0.02'"),
    ({"max_turn_rad": float("inf")}, "invalid max_turn_rad inf"),
    ({"max_turn_rad": True}, "invalid max_turn_rad True"),
])
def test_bad_wrapper_arguments_are_one_line(kwargs, message):
    with pytest.raises(InvalidArgumentError) as err:
        RLActions(gym.make("IMPACT/Hammer-v1"), mode="delta", **kwargs)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_a_non_impact_env_is_one_line():
    with pytest.raises(InvalidArgumentError, match="RLActions wraps an IMPACT env.*Pendulum"):
        RLActions(gym.make("Pendulum-v1"))
