"""``RobotOptions.torque_reading``: the link-side torque sensor (default) or the applied
command (``"commanded"``, the paper authors' sim), checked with the physics: the commanded
reading is MuJoCo's ``qfrc_actuator`` exactly (the per-tick loop and ``read_sensors``), a force
on the hand at rest is recovered by the estimator in both readings (in the commanded one
together with the joint friction that holds part of it), and a moving arm's joint friction
shows in the commanded reading's estimate only."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import impact_envs  # noqa: F401 - registers the envs
from impact_control.errors import InvalidArgumentError
from impact_envs import RobotOptions
from impact_envs.loop import closed_loop
from impact_envs.robot.sim import FrankaSim

FORCE_N = np.array([10.0, -6.0, 15.0])
"""External force on the hand body's centre of mass [N] (``xfrc_applied``)."""


def _env(reading: str, **kwargs: Any) -> Any:
    return gym.make("IMPACT/Hammer-v1", robot={"torque_reading": reading}, **kwargs).unwrapped


def _hold(obs: dict[str, np.ndarray]) -> np.ndarray:
    """The action that holds the TCP where ``obs`` has it, hand open."""
    return np.concatenate([obs["ee_pos"], obs["ee_rot6d"], [-1.0]]).astype(np.float64)


@pytest.mark.parametrize("value", ["motor", "Commanded", "", 1, None])
def test_a_bad_reading_is_one_line_naming_both_choices(value: object) -> None:
    for make in (lambda: RobotOptions(torque_reading=value),
                 lambda: FrankaSim("hammer_scene.xml", ("hammer",), torque_reading=value)):
        with pytest.raises(InvalidArgumentError) as err:
            make()
        message = str(err.value)
        assert "\n" not in message and f"invalid torque_reading {value!r}" in message
        assert "valid choices: link_side, commanded" in message


def test_gym_make_takes_the_reading_in_a_dict() -> None:
    assert _env("commanded").sim.torque_reading == "commanded"
    assert gym.make("IMPACT/Hammer-v1").unwrapped.sim.torque_reading == "link_side"
    with pytest.raises(InvalidArgumentError, match="valid choices: link_side, commanded"):
        gym.make("IMPACT/Hammer-v1", robot={"torque_reading": "sensor"})


def _known_commands(env: Any, seed: int) -> list[tuple[np.ndarray, ...]]:
    """Reset, then a few ticks of known torques (gravity + a pattern, joint 1 over its limit):
    per tick (command, reading q/dq/tau, noise draws, true q, qfrc_actuator/_damper, friction)."""
    env.reset(seed=seed)
    sim = env.sim
    rows, z_rng = [], np.random.default_rng(5)
    for k in range(6):
        tau = sim.data.qfrc_bias[sim.arm_dof] + 3.0 * np.sin(np.arange(7) + k)
        tau[0] = 200.0  # beyond the 87 Nm limit: the drives clip it
        sim.apply(tau, -1.0)
        sim.step()
        z = z_rng.standard_normal(21)
        q, dq, tau_meas = sim.read_sensors(None, z)
        rows.append((np.clip(tau, -sim.torque_limits, sim.torque_limits), q, dq, tau_meas, z,
                     sim.data.qpos[sim.arm_qpos].copy(),
                     sim.data.qfrc_actuator[sim.arm_dof].copy(),
                     sim.data.qfrc_damper[sim.arm_dof].copy(), sim.frictionloss_torque().copy()))
    return rows


def test_commanded_reading_is_the_applied_torque_exactly() -> None:
    env = _env("commanded")  # sensor_noise on
    rows = _known_commands(env, 3)
    for cmd, q, _, tau, _, q_true, actuator, _, friction in rows:
        np.testing.assert_array_equal(tau, actuator)
        np.testing.assert_array_equal(tau, cmd)  # the command after the drives' clip
        assert tau[0] == 87.0 and np.abs(friction).max() > 1.0
        assert np.abs(q - q_true).max() > 0.0  # encoder noise stays
    assert np.abs(rows[-1][7]).max() > 0.1  # the arm moves: damping, not read
    arrays = env.sim.loop_arrays()  # what the per-tick kernel reads
    assert arrays.noise_stds[2] == 0.0 and arrays.noise_stds[0] == 1e-5
    assert not arrays.tau_bias.any() and not arrays.qfrc_damper_arm.any()
    assert not env.sim.frictionloss_reader()().any()
    *_, actuator, damper, friction = _known_commands(env, 4)[-1]
    np.testing.assert_array_equal(env.sim.true_joint_torque(), actuator + damper + friction)


def test_link_side_reading_adds_damping_friction_bias_and_noise() -> None:
    env = gym.make("IMPACT/Hammer-v1").unwrapped
    bias = None
    for _, _, _, tau, z, _, actuator, damper, friction in _known_commands(env, 3):
        bias = env.sim.state_arrays()["tau_bias"]
        np.testing.assert_allclose(tau, actuator + damper + friction + bias + 0.05 * z[14:],
                                   rtol=0, atol=1e-12)
        assert np.abs(tau - actuator).max() > 0.1  # damping and friction of the moving arm
    assert bias is not None and np.abs(bias).max() > 0.0


def _capture_plans(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    """Every ``StepPlan`` the closed loop makes, kept (its ``sensed`` holds the last tick's
    reading, its ``taus`` the torques applied)."""
    plans: list[Any] = []
    real = closed_loop.StepPlan

    def keep(*args: Any) -> Any:
        plans.append(real(*args))
        return plans[-1]

    monkeypatch.setattr(closed_loop, "StepPlan", keep)
    return plans


@pytest.mark.parametrize("reading", ["commanded", "link_side"])
def test_the_loop_reads_the_applied_torque_when_commanded(
        reading: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The last tick's reading was taken after the tick before it was stepped: in the
    commanded reading it is that tick's applied torque, exactly; link-side it is not."""
    plans = _capture_plans(monkeypatch)
    env = _env(reading)
    obs, _ = env.reset(seed=1)
    action = _hold(obs)
    for k in range(8):
        action[1] += 0.01 * k  # moving: damping and friction in the link-side reading
        env.step(action)
    assert len(plans) == 8
    for k, plan in enumerate(plans):
        tau_read, tau_prev = plan.sensed[14:], plan.taus[-2]
        if reading == "commanded":
            np.testing.assert_array_equal(tau_read, tau_prev)
        elif k > 0:  # moving (measured: 1.1-1.4 Nm, joint 1's 1.14 Nm Coulomb friction)
            assert np.abs(tau_read - tau_prev).max() > 0.5


def _jacobian_com(sim: FrankaSim, body: int) -> np.ndarray:
    """(3, 7) Jacobian of ``body``'s centre of mass over the arm's joints."""
    jac = np.zeros((3, sim.model.nv))
    mujoco.mj_jacBodyCom(sim.model, sim.data, jac, None, body)
    return jac[:, sim.arm_dof]


def _pushed_at_rest(reading: str) -> tuple[np.ndarray, np.ndarray, float]:
    """Hold a pose, push the hand with ``FORCE_N`` and settle: (estimate, expected estimate,
    largest joint speed). Expected: the estimator's wrench map applied to the joint torques
    the reading leaves unexplained, i.e. the push and, in the commanded reading, the
    damping and the Coulomb friction of the joints."""
    env = _env(reading, controller="impedance")
    obs, _ = env.reset(seed=0)
    sim, action = env.sim, _hold(obs)
    hand = sim.model.body("hand").id
    sim.data.xfrc_applied[hand, :3] = FORCE_N
    for _ in range(75):
        _, _, _, _, info = env.step(action)
    unexplained = _jacobian_com(sim, hand).T @ FORCE_N
    if reading == "commanded":
        unexplained = unexplained + sim.data.qfrc_damper[sim.arm_dof] + sim.frictionloss_torque()
    expected = -env.controller.estimator_map @ unexplained
    return info["wrench_ext_world"], expected, float(np.abs(sim.data.qvel[sim.arm_dof]).max())


@pytest.mark.parametrize("reading", ["link_side", "commanded"])
def test_a_force_on_the_hand_at_rest_is_recovered(reading: str) -> None:
    """Measured (seed 0, 75 steps): estimate - expected at most 0.12 N / 0.016 Nm in both;
    the link-side force 0.15 N from -FORCE_N, the commanded one 6.6 N off it: the static
    friction of the joints holds that part of the push (and reads as external)."""
    estimate, expected, speed = _pushed_at_rest(reading)
    assert speed < 0.01  # at rest
    np.testing.assert_allclose(estimate[:3], expected[:3], atol=0.3)
    np.testing.assert_allclose(estimate[3:], expected[3:], atol=0.05)
    off = np.linalg.norm(estimate[:3] + FORCE_N)
    if reading == "link_side":
        assert off < 0.4
    else:
        assert off > 3.0


def _moving_estimates(reading: str) -> tuple[np.ndarray, np.ndarray]:
    """Swing the TCP 0.3 m along y and back in free space: per step the estimated force and
    the TCP velocity (finite difference of the observed position)."""
    env = _env(reading, controller="impedance")
    obs, _ = env.reset(seed=1)
    action, forces, positions = _hold(obs), [], []
    y0 = action[1]
    for k in range(45):
        action[1] = y0 + 0.3 * np.sin(np.pi * k / 45)
        obs, _, _, _, info = env.step(action)
        forces.append(info["wrench_ext_world"][:3].copy())
        positions.append(obs["ee_pos"].astype(np.float64))
    return np.array(forces)[10:], np.gradient(np.array(positions), axis=0)[10:]


def test_joint_friction_of_a_moving_arm_shows_only_in_the_commanded_estimate() -> None:
    """Measured (seed 1): mean |force| 0.18 N link-side, 7.9 N commanded; the commanded one
    points along the motion in all 25 fast steps (the estimate is minus the force on the
    robot, and damping and friction oppose the motion)."""
    link_side, _ = _moving_estimates("link_side")
    commanded, velocity = _moving_estimates("commanded")
    assert np.linalg.norm(link_side, axis=1).mean() < 0.5
    assert np.linalg.norm(commanded, axis=1).mean() > 4.0
    moving = np.linalg.norm(velocity, axis=1) > 0.3 * np.linalg.norm(velocity, axis=1).max()
    along = np.einsum("ij,ij->i", commanded[moving], velocity[moving])
    assert (along > 0).mean() > 0.9


def test_a_state_of_the_other_reading_is_refused() -> None:
    source, target = _env("commanded"), gym.make("IMPACT/Hammer-v1").unwrapped
    source.reset(seed=2)
    target.reset(seed=2)
    with pytest.raises(InvalidArgumentError, match="torque_reading"):
        target.set_state(source.get_state())
    same = _env("commanded")
    same.reset(seed=4)
    same.set_state(source.get_state())  # the same reading restores
