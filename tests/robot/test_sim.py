"""MuJoCo adapter: torque sensing is consistent with rigid-body dynamics; the hand holds 10 kg."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from impact_control.dynamics import PinocchioArm
from impact_control.errors import InvalidArgumentError
from impact_control.ik import HOME_Q, solve_ik
from impact_envs.robot.noise import SensorNoise
from impact_envs.robot.sim import FrankaSim
from impact_envs.tasks.base import BodyMass, refresh_constants

R_DOWN = np.diag([1.0, -1.0, -1.0])


def _hold(sim: FrankaSim, q_des: np.ndarray, gripper: float, ticks: int) -> None:
    """Joint PD around q_des plus MuJoCo's exact bias (a perfect-model reference controller)."""
    kp = np.array([600.0] * 4 + [100.0] * 3)
    kd = np.array([50.0] * 4 + [10.0] * 3)
    for _ in range(ticks):
        q, dq = sim.arm_state()
        tau = kp * (q_des - q) - kd * dq + sim.data.qfrc_bias[sim.arm_dof]
        sim.apply(tau, gripper)
        sim.step()


def test_torque_sensor_matches_rigid_body_residual_under_known_force():
    sim = FrankaSim("hammer_scene.xml", ("hammer",), noise=SensorNoise.off())
    arm = PinocchioArm(finger_opening_m=0.04)
    sim.reset_robot(HOME_Q, 0.04, np.random.default_rng(0))
    mujoco.mj_forward(sim.model, sim.data)
    force = np.array([5.0, -3.0, 8.0])
    hand = sim.model.body("hand").id
    sim.data.xfrc_applied[hand, :3] = force  # at the hand body's COM
    rng = np.random.default_rng(0)
    for _ in range(200):
        sim.apply(rng.normal(0.0, 2.0, 7) + sim.data.qfrc_bias[sim.arm_dof], -1.0)
        sim.step()
    q, dq = sim.arm_state()
    tau = sim.true_joint_torque()
    arm.update(q, dq)
    qacc = sim.data.qacc[sim.arm_dof]
    residual = tau - (arm.mass_matrix @ qacc + arm.nonlinear)
    jac = np.zeros((3, sim.model.nv))
    mujoco.mj_jacBodyCom(sim.model, sim.data, jac, None, hand)
    # fingers are free DOFs in the simulator: compare on the arm joints only
    np.testing.assert_allclose(residual, -(jac[:, sim.arm_dof].T @ force), atol=0.05)


def test_noise_statistics_match_configuration():
    noise = SensorNoise(q_std_rad=1e-4, dq_std_rad_s=2e-3, tau_std_nm=0.1, tau_bias_std_nm=0.0)
    sim = FrankaSim("hammer_scene.xml", ("hammer",), noise=noise)
    rng = np.random.default_rng(0)
    sim.reset_robot(HOME_Q, 0.04, rng)
    mujoco.mj_forward(sim.model, sim.data)
    true_tau = sim.true_joint_torque()
    samples = np.array([np.concatenate(sim.read_sensors(rng)) for _ in range(4000)])
    std = samples.std(axis=0)
    np.testing.assert_allclose(std[:7], 1e-4, rtol=0.1)
    np.testing.assert_allclose(std[7:14], 2e-3, rtol=0.1)
    np.testing.assert_allclose(std[14:], 0.1, rtol=0.1)
    np.testing.assert_allclose(samples[:, 14:].mean(axis=0), true_tau, atol=0.01)


def test_gripper_holds_10kg_hammer_without_slip():
    sim = FrankaSim("hammer_scene.xml", ("hammer",), grasp_force_n=70.0,
                    noise=SensorNoise.off())
    mass = BodyMass(sim.model, "hammer")
    mass.set(sim.model, 10.0)
    refresh_constants(sim)
    arm = PinocchioArm()
    hammer = sim.model.body("hammer").id
    com = np.array([0.4 + 0.099, 0.15, 0.0125])
    sim.data.qpos[9:12] = [0.4, 0.15, 0.0125]
    q_grasp = solve_ik(arm, com, R_DOWN)
    sim.reset_robot(q_grasp, 0.04, np.random.default_rng(0))
    mujoco.mj_forward(sim.model, sim.data)
    np.testing.assert_allclose(sim.data.xipos[hammer], com, atol=1e-6)
    _hold(sim, q_grasp, 1.0, 500)
    assert sim.gripper_width() == pytest.approx(0.025, abs=1e-3)
    q_up = solve_ik(arm, com + [0.0, 0.0, 0.2], R_DOWN, q_grasp)
    for k in range(1, 1501):
        a = min(1.0, k / 1000)
        _hold(sim, (1 - a) * q_grasp + a * q_up, 1.0, 1)
    offset0 = sim.data.xipos[hammer] - sim.tcp_pose()[0]
    _hold(sim, q_up, 1.0, 2000)
    offset1 = sim.data.xipos[hammer] - sim.tcp_pose()[0]
    assert sim.data.xipos[hammer][2] > 0.1  # lifted well off the table (PD sags under 10 kg)
    assert np.linalg.norm(offset1 - offset0) < 1e-3  # < 1 mm slip in 2 s
    assert np.abs(sim.tau_applied[:4]).max() < 87.0 and np.abs(sim.tau_applied[4:]).max() < 12.0


def test_grasp_force_validation():
    with pytest.raises(InvalidArgumentError, match="grasp_force_n"):
        FrankaSim("hammer_scene.xml", ("hammer",), grasp_force_n=-1.0)


def test_push_into_contact_reads_the_tables_normal_under_a_pressing_hand():
    """The finger pads held 3.4 cm into the table (and nothing else touching the robot): the
    contact's normal is vertical, so a force on the TCP pushes into the table by its
    downward part and a horizontal force hardly at all; the measure is linear in the wrench
    (issue 54's metric)."""
    sim = FrankaSim("hammer_scene.xml", ("hammer",), noise=SensorNoise.off())
    arm = PinocchioArm()
    assert sim.push_into_contact(np.array([0.0, 0.0, -10.0, 0, 0, 0])) == 0.0  # no contact
    spot = np.array([0.45, 0.3, 0.0])  # clear of the hammer and the basket
    q_press = solve_ik(arm, spot + [0.0, 0.0, -0.02], R_DOWN)
    sim.reset_robot(solve_ik(arm, spot + [0.0, 0.0, 0.05], R_DOWN), 0.0,
                    np.random.default_rng(0))
    _hold(sim, q_press, 1.0, 1500)
    m, d = sim.model, sim.data
    robot_contacts = [(m.geom(d.contact[i].geom[0]).name, m.geom(d.contact[i].geom[1]).name)
                      for i in range(d.ncon)
                      if not m.geom(d.contact[i].geom[1]).name.startswith("hammer")]
    assert robot_contacts and all(a == "table" and b.endswith("_pad") for a, b in robot_contacts)
    assert sim.contact_forces()[0] > 50.0
    down = sim.push_into_contact(np.array([0.0, 0.0, -10.0, 0.0, 0.0, 0.0]))
    assert down == pytest.approx(10.0, rel=0.05)
    assert sim.push_into_contact(np.array([0.0, 0.0, 25.0, 0.0, 0.0, 0.0])) == pytest.approx(
        -2.5 * down, rel=1e-9)
    assert abs(sim.push_into_contact(np.array([10.0, -10.0, 0.0, 0.0, 0.0, 0.0]))) < 1.0
    twist = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0])
    assert sim.push_into_contact(twist) == pytest.approx(-sim.push_into_contact(-twist),
                                                         rel=1e-9)
