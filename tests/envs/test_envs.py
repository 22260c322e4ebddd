"""Invariants over every registered IMPACT environment."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from fixtures.rollouts import expert_rollout
from gymnasium.utils.env_checker import check_env

import impact_envs
from impact_control.errors import InvalidArgumentError
from impact_control.policy import stack_obs
from impact_envs.envs.options import RenderOptions, RobotOptions
from impact_envs.policies.experts import make_expert

ENV_IDS = impact_envs.ENV_IDS


def _hold_action(obs: dict[str, np.ndarray]) -> np.ndarray:
    return np.concatenate([obs["ee_pos"], obs["ee_rot6d"], [-1.0]]).astype(np.float32)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_gymnasium_check_env(env_id):
    env = gym.make(env_id)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_check_env(env_id):
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(env_id)
    sb3_check_env(env, warn=False)
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("controller", ["impact", "impedance"])
def test_same_seed_same_actions_identical_trajectories(env_id, controller):
    a = expert_rollout(gym.make(env_id, controller=controller), env_id, seed=7, steps=40)
    b = expert_rollout(gym.make(env_id, controller=controller), env_id, seed=7, steps=40)
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_observations_finite_and_in_space(env_id):
    env = gym.make(env_id)
    obs, info = env.reset(seed=0)
    assert info["is_success"] is False
    for _ in range(10):
        obs, reward, terminated, truncated, info = env.step(_hold_action(obs))
        assert env.observation_space.contains(obs)
        assert all(np.isfinite(v).all() for v in obs.values())
        assert isinstance(reward, float) and isinstance(terminated, bool)
    for key in ("is_success", "object_mass", "pose_error_m", "energy_j", "peak_torque_nm",
                "peak_robot_contact_force_n", "peak_object_contact_force_n",
                "supported_weight_n", "wrench_ext_world", "wrench_pred_world", "gate_open"):
        assert key in info
    env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_rgb_array_render(env_id):
    env = gym.make(env_id, render_mode="rgb_array", render=RenderOptions(width=64, height=48))
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (48, 64, 3) and frame.dtype == np.uint8 and frame.std() > 1.0
    env.close()
    env.close()  # closing twice is safe


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_reset_option_sets_parameter_and_mass_is_reported(env_id):
    env = gym.make(env_id)
    name = env.unwrapped.param_name
    _, info = env.reset(seed=0, options={name: 3.0})
    assert info[name] == 3.0
    _, info = env.reset(seed=0)  # back to the persistent value
    assert info[name] == env.unwrapped.task.param(name).default
    env.close()


def test_mass_is_set_from_nominal_not_compounded():
    env = gym.make("IMPACT/Hammer-v1").unwrapped
    body = env.task.mass.id
    for m in (2.0, 5.0, 2.0):
        env.reset(seed=0, options={"object_mass": m})
    assert env.sim.model.body_mass[body] == 2.0
    ratio = env.sim.model.body_inertia[body] / env.task.mass.nominal_inertia
    np.testing.assert_allclose(ratio, 2.0 / env.task.mass.nominal_mass)
    assert env.sim.model.body_subtreemass[body] == pytest.approx(2.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"controller": "pid"}, "valid choices: impedance, impact"),
        ({"controller_preset": "fast"}, "valid choices: default, paper"),
        ({"object_mass": -1.0}, "valid: 0.05 to 12.0 kg"),
        ({"render_mode": "depth"}, "valid choices: rgb_array"),
    ],
)
def test_bad_kwargs_give_one_line_errors(kwargs, match):
    with pytest.raises(InvalidArgumentError, match=match) as err:
        gym.make("IMPACT/Hammer-v1", **kwargs)
    assert "\n" not in str(err.value)


def test_bad_reset_option():
    env = gym.make("IMPACT/Hammer-v1")
    with pytest.raises(InvalidArgumentError, match="valid: object_mass"):
        env.reset(seed=0, options={"friction": 1.0})


@pytest.mark.parametrize("value", [True, np.bool_(False), "3", None, [2.0], np.array([2.0])])
def test_reset_option_must_be_a_real_number(value):
    env = gym.make("IMPACT/Hammer-v1")
    with pytest.raises(InvalidArgumentError, match="object_mass must be a real number") as err:
        env.reset(seed=0, options={"object_mass": value})
    assert "\n" not in str(err.value)
    _, info = env.reset(seed=0, options={"object_mass": np.float32(2.0)})  # numpy scalars count
    assert info["object_mass"] == 2.0


@pytest.mark.parametrize("shape", [(10, 1), (1, 10), (2, 5), (11,), (9,), ()])
def test_action_of_wrong_shape_is_refused_not_reshaped(shape):
    env = gym.make("IMPACT/Hammer-v1")
    env.reset(seed=0)
    with pytest.raises(InvalidArgumentError, match=r"\(10,\) array"):
        env.step(np.zeros(shape, dtype=np.float32))
    with pytest.raises(InvalidArgumentError, match=r"\(10,\) array of numbers"):
        env.step(["a"] * 10)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_registered_episode_length_matches_task(env_id):
    env = gym.make(env_id)
    assert env.spec.max_episode_steps == env.unwrapped.task.max_episode_steps
    env.close()


def test_expert_privileged_compensation_raises_targets_by_mg_over_k():
    expert = make_expert("IMPACT/Hammer-v1", compensation="privileged")
    with pytest.raises(InvalidArgumentError, match="object_mass_kg"):
        expert.reset(1)
    env = gym.make("IMPACT/Hammer-v1", object_mass=4.0)
    obs, _ = env.reset(seed=0)
    expert.reset(1, object_mass_kg=np.array([4.0]))
    plain = make_expert("IMPACT/Hammer-v1")
    plain.reset(1)
    for _ in range(200):  # until both are carrying
        a = expert.act(stack_obs([obs]))[0]
        b = plain.act(stack_obs([obs]))[0]
        obs, *_ = env.step(b)
        if expert.phase[0] == plain.phase[0] == 3:  # LIFT: holding the object
            assert a[2] - b[2] == pytest.approx(4.0 * 9.81 / 400.0)
            break
    else:
        pytest.fail("expert never reached the lift phase")


def test_expert_closed_loop_compensation_finds_the_sag_without_the_mass():
    """Under plain impedance (K_z = 400 N/m) a 4 kg hammer sags m g / K = 9.8 cm; the
    closed-loop expert, told no mass, lifts it and carries it with an offset near that sag."""
    env = gym.make("IMPACT/Hammer-v1", object_mass=4.0, controller="impedance")
    obs, _ = env.reset(seed=0)
    expert = make_expert("IMPACT/Hammer-v1", compensation="closed_loop")
    expert.reset(1)
    offsets = []
    for _ in range(400):
        action = expert.act(stack_obs([obs]))[0]
        obs, *_ = env.step(action)
        if expert.phase[0] == 4:  # CARRY: the hammer is up
            offsets.append(expert.offset_z[0])
    env.close()
    sag_m = 4.0 * 9.81 / 400.0
    assert len(offsets) > 10
    assert offsets[-1] == pytest.approx(sag_m, rel=0.25)
    with pytest.raises(InvalidArgumentError, match="valid choices: none, closed_loop"):
        make_expert("IMPACT/Hammer-v1", compensation="psychic")




@pytest.mark.parametrize("env_id", ENV_IDS)
def test_dense_reward_grows_along_the_expert_and_is_1_on_success(env_id):
    """Shaped reward in [0, 1]; on a solved expert episode its later half beats its start."""
    env = gym.make(env_id, reward_type="dense", terminate_on_success=True)
    expert = make_expert(env_id)
    obs, _ = env.reset(seed=5)
    expert.reset(1)
    rewards = []
    for _ in range(env.spec.max_episode_steps):
        obs, reward, terminated, _, info = env.step(expert.act(stack_obs([obs]))[0])
        rewards.append(reward)
        assert 0.0 <= reward <= 1.0
        assert (reward == 1.0) == info["is_success"]
        if terminated:
            break
    assert np.mean(rewards[len(rewards) // 2:]) > np.mean(rewards[:10])
    env.close()
    with pytest.raises(InvalidArgumentError, match="valid choices: sparse, dense"):
        gym.make(env_id, reward_type="shaped")


# name: (gym.make keyword arguments, part of the one-line message)
BAD_OPTIONS = {
    "grasp force a string": ({"robot": lambda: RobotOptions(grasp_force_n="70")},
                             "invalid grasp_force_n '70'"),
    "grasp force inf": ({"robot": lambda: RobotOptions(grasp_force_n=float("inf"))},
                        "invalid grasp_force_n inf"),
    "grasp force nan": ({"robot": lambda: RobotOptions(grasp_force_n=float("nan"))},
                        "invalid grasp_force_n nan"),
    "grasp force negative": ({"robot": lambda: RobotOptions(grasp_force_n=-1.0)},
                             "invalid grasp_force_n -1.0"),
    "sensor noise a string": ({"robot": lambda: RobotOptions(sensor_noise="yes")},
                              "invalid sensor_noise 'yes'"),
    "mass error a string": ({"robot": lambda: RobotOptions(model_mass_error="0")},
                            "invalid model_mass_error '0'"),
    "camera unknown": ({"render_mode": "rgb_array", "render": lambda: RenderOptions(camera="nope")},
                       "invalid camera 'nope'; valid choices: front, side, overview"),
    "camera not a string": ({"render": lambda: RenderOptions(camera=3)}, "invalid camera 3"),
    "render width zero": ({"render": lambda: RenderOptions(width=0)}, "invalid render width 0"),
    "render width fractional": ({"render": lambda: RenderOptions(width=2.5)},
                                "invalid render width 2.5"),
    "render height a string": ({"render": lambda: RenderOptions(height="240")},
                               "invalid render height '240'"),
    "render width huge": ({"render": lambda: RenderOptions(width=100000)},
                          "from 1 to 4096 px"),
    "render larger than the buffer": ({"render": lambda: RenderOptions(width=1000, height=900)},
                                      "at most 640x480 px"),
}


@pytest.mark.parametrize("case", sorted(BAD_OPTIONS))
def test_bad_robot_and_render_options_are_one_line(case):
    kwargs, message = BAD_OPTIONS[case]
    with pytest.raises(InvalidArgumentError) as err:
        gym.make("IMPACT/Hammer-v1", **{k: v() if callable(v) else v for k, v in kwargs.items()})
    assert message in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("options,seed,message", [
    ([("object_mass", 2.0)], None, "invalid reset options"),
    ("object_mass=2", None, "invalid reset options 'object_mass=2'"),
    (None, 1.5, "invalid seed 1.5"),
    (None, "0", "invalid seed '0'"),
])
def test_bad_reset_arguments_are_one_line(options, seed, message):
    env = gym.make("IMPACT/Hammer-v1")
    with pytest.raises(InvalidArgumentError) as err:
        env.reset(seed=seed, options=options)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_a_refused_first_reset_does_not_break_the_env():
    env = gym.make("IMPACT/Hammer-v1")
    with pytest.raises(InvalidArgumentError):
        env.reset(options={"object_mass": -1.0})
    env.reset(seed=0)
    obs, *_ = env.step(env.unwrapped.action_space.low)
    assert np.isfinite(obs["ee_pos"]).all()
