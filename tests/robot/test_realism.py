"""Robot profiles (``RobotOptions(realism=...)``, robot/realism.py): resolution and bad input,
each imperfection measured on the simulator, and the estimator's view of a robot at rest."""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import impact_envs  # noqa: F401 - registers the envs
from impact_control.dynamics import ModelPerturbation, PinocchioArm
from impact_control.errors import InvalidArgumentError
from impact_control.ik import HOME_Q
from impact_envs.envs.options import RobotOptions
from impact_envs.robot.noise import SensorNoise
from impact_envs.robot.realism import PROFILES, Realism
from impact_envs.robot.sim import FrankaSim


def test_ideal_is_the_robot_of_every_earlier_result() -> None:
    ideal = RobotOptions().resolved_realism()
    assert ideal == PROFILES["ideal"] == Realism()
    assert ideal.tau_offset_std_nm == SensorNoise().tau_bias_std_nm  # today's 0.02 Nm
    assert not ideal.perturbs_model and ideal.delay_ticks == 0 and ideal.encoder_step_rad == 0


def test_an_explicit_field_overrides_the_profile() -> None:
    fr3 = RobotOptions(realism="fr3").resolved_realism()
    assert fr3.delay_ticks == 1 and fr3.perturbs_model and fr3.tau_offset_std_nm > 0.1
    own = RobotOptions(realism="fr3", delay_ticks=0, model_link_mass_std=0.0).resolved_realism()
    assert own.delay_ticks == 0 and own.model_link_mass_std == 0.0
    assert own.model_com_std_m == fr3.model_com_std_m  # the rest stays the profile's


@pytest.mark.parametrize(("options", "message"), [
    ({"realism": "real"}, "invalid realism 'real'; valid choices: ideal, fr3"),
    ({"realism": 3}, "invalid realism 3; valid choices: ideal, fr3"),
    ({"delay_ticks": 2}, "invalid delay_ticks 2; valid: an integer from 0 to 1"),
    ({"delay_ticks": True}, "invalid delay_ticks True"),
    ({"tau_offset_std_nm": -0.1}, "invalid tau_offset_std_nm -0.1; valid: a number from 0"),
    ({"command_loss_rate": float("nan")}, "invalid command_loss_rate nan"),
    ({"encoder_step_rad": "1e-5"}, "invalid encoder_step_rad '1e-5'"),
])
def test_bad_realism_is_one_line(options, message) -> None:
    with pytest.raises(InvalidArgumentError) as err:
        RobotOptions(**options)
    assert message in str(err.value) and "\n" not in str(err.value)


def _sim(**kwargs) -> FrankaSim:
    sim = FrankaSim("hammer_scene.xml", ("hammer",), **kwargs)
    sim.reset_robot(HOME_Q, 0.04, np.random.default_rng(0))
    mujoco.mj_forward(sim.model, sim.data)
    return sim


def test_a_delayed_command_reaches_the_drives_one_tick_later() -> None:
    sim = _sim(noise=SensorNoise.off(), delay_ticks=1)
    first, second = np.full(7, 1.5), np.full(7, -2.0)
    sim.apply(first, -1.0)
    np.testing.assert_array_equal(sim.tau_applied, 0.0)  # nothing was pending at reset
    sim.apply(second, -1.0)
    np.testing.assert_array_equal(sim.tau_applied, first)
    np.testing.assert_array_equal(sim.data.ctrl[sim.arm_act], first)
    now = _sim(noise=SensorNoise.off())
    now.apply(first, -1.0)
    np.testing.assert_array_equal(now.tau_applied, first)


def test_encoder_steps_quantize_the_position_reading() -> None:
    step = 1e-3
    sim = _sim(noise=SensorNoise(q_step_rad=step))
    q, _, _ = sim.read_sensors(np.random.default_rng(1))
    true_q, _ = sim.arm_state()
    np.testing.assert_allclose(q / step, np.round(q / step), atol=1e-9)
    assert np.abs(q - true_q).max() <= step / 2 + 5 * 1e-5  # half a step and the noise


def test_offsets_drift_as_a_random_walk() -> None:
    """2,000 walks of 25 s in steps of 1/30 s: the offset's change has std drift * sqrt(25)."""
    drift, rng = 0.01, np.random.default_rng(2)
    sim = _sim(noise=SensorNoise(tau_bias_std_nm=0.0), offset_drift_nm_per_sqrt_s=drift)
    ends = []
    for _ in range(2000 // 7 + 1):
        sim.reset_robot(HOME_Q, 0.04, rng)
        start = sim.state_arrays()["tau_bias"].copy()
        for _ in range(750):
            sim.drift_offsets(1.0 / 30.0, rng)
        ends.append(sim.state_arrays()["tau_bias"] - start)
    std = float(np.std(np.concatenate(ends)))
    assert std == pytest.approx(drift * 5.0, rel=0.05)
    still = _sim(noise=SensorNoise(tau_bias_std_nm=0.0))
    still.drift_offsets(25.0, rng)
    np.testing.assert_array_equal(still.state_arrays()["tau_bias"], 0.0)


def test_a_lost_command_leaves_the_last_torque_on_the_drives() -> None:
    """Half the commands lost: every lost tick applies exactly the torque of the tick before,
    and the share of repeated ticks is about the loss rate."""
    env = gym.make("IMPACT/Hammer-v1", robot=RobotOptions(command_loss_rate=0.5,
                                                          sensor_noise=False))
    env.reset(seed=0)
    u = env.unwrapped
    action = np.concatenate([u.dynamics.pos_ee_world + [0.0, 0.0, 0.05],
                             [1.0, 0.0, 0.0, 0.0, -1.0, 0.0], [-1.0]])
    repeated = []
    original = u.loop.run

    def run(targets):
        trace = original(targets)
        repeated.extend(np.all(trace.taus[1:] == trace.taus[:-1], axis=1))
        return trace

    u.loop.run = run
    for _ in range(10):
        env.step(action)
    assert 0.35 < np.mean(repeated) < 0.65
    env.close()


def test_the_model_errors_are_a_fixed_robot_per_seed() -> None:
    exact = PinocchioArm()
    errors = ModelPerturbation(link_mass_noise=0.05, com_noise_m=0.005, inertia_noise=0.1,
                               seed=3)
    one, same, other = (PinocchioArm(perturbation=p) for p in
                        (errors, errors, ModelPerturbation(link_mass_noise=0.05, seed=4)))
    for arm in (exact, one, same, other):
        arm.update(HOME_Q, np.zeros(7))
    np.testing.assert_array_equal(one.gravity, same.gravity)
    assert 0.05 < np.abs(one.gravity - exact.gravity).max() < 3.0  # [Nm]
    assert np.abs(other.gravity - one.gravity).max() > 0.01


def test_an_fr3_at_rest_shows_the_reported_wrench_offsets() -> None:
    """Issue 39's acceptance: under ``realism="fr3"``, at rest at 5 poses without contact and
    under plain impedance, the estimated external force is 0.5-3 N and differs between poses
    (franka_ros issue 404 reports (1.40, -0.37, 1.72) N at rest). Ideal: under 0.3 N."""
    from impact_experiments.rest_offsets import rest_wrenches

    forces = np.array([w[:3] for w in rest_wrenches("fr3", 11)])
    norms = np.linalg.norm(forces, axis=1)
    assert np.all((norms > 0.5) & (norms < 3.0)), norms
    assert np.linalg.norm(forces - forces.mean(axis=0), axis=1).max() > 0.2  # pose-dependent
    ideal = np.array([w[:3] for w in rest_wrenches("ideal", 11)])
    assert np.linalg.norm(ideal, axis=1).max() < 0.3
