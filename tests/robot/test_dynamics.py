"""Pinocchio (controller model) and MuJoCo (simulator) agree on the same MJCF."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from impact_control.dynamics import ROBOT_XML, ModelPerturbation, PinocchioArm
from impact_control.errors import InvalidArgumentError
from impact_envs.robot.mujoco_arm import full_mass_matrix

FINGER = 0.02


@pytest.fixture(scope="module")
def mj():
    model = mujoco.MjModel.from_xml_path(str(ROBOT_XML))
    return model, mujoco.MjData(model)


def _random_configs(arm: PinocchioArm, n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(arm.q_lower + 0.05, arm.q_upper - 0.05, size=(n, 7))


def _set(model, data, q, dq):
    data.qpos[:7] = q
    data.qpos[7:9] = FINGER
    data.qvel[:] = 0.0
    data.qvel[:7] = dq
    mujoco.mj_forward(model, data)


@pytest.mark.skipif(int(mujoco.__version__.split(".")[0]) < 4, reason="MuJoCo 3.x compiles the "
                    "inertias to within 1.5e-8 of Pinocchio's (3.9, the robosuite extra's)")
def test_kinematics_and_dynamics_agree(mj):
    model, data = mj
    arm = PinocchioArm(finger_opening_m=FINGER)
    site = model.site("tcp").id
    rng = np.random.default_rng(1)
    for q in _random_configs(arm, 20):
        dq = rng.normal(0.0, 0.5, 7)
        arm.update(q, dq)
        _set(model, data, q, dq)
        np.testing.assert_allclose(arm.pos_ee_world, data.site_xpos[site], atol=1e-9)
        np.testing.assert_allclose(arm.rot_ee_world, data.site_xmat[site].reshape(3, 3),
                                   atol=1e-9)
        jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
        mujoco.mj_jacSite(model, data, jacp, jacr, site)
        np.testing.assert_allclose(arm.jacobian, np.vstack([jacp, jacr])[:, :7], atol=1e-9)
        full = np.zeros((model.nv, model.nv))
        full_mass_matrix(model, data, full)
        np.testing.assert_allclose(arm.mass_matrix, full[:7, :7], atol=1e-9)
        np.testing.assert_allclose(arm.nonlinear, data.qfrc_bias[:7], atol=1e-8)
        np.testing.assert_allclose(arm.coriolis_matrix @ dq + arm.gravity, data.qfrc_bias[:7],
                                   atol=1e-8)
        _set(model, data, q, np.zeros(7))
        np.testing.assert_allclose(arm.gravity, data.qfrc_bias[:7], atol=1e-9)


def test_armature_in_mass_matrix():
    arm = PinocchioArm()
    arm.update(np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.78]), np.zeros(7))
    # link 7's own inertia about its axis is ~6e-5 kg m^2; the 0.074 rotor armature dominates
    assert 0.074 < arm.mass_matrix[6, 6] < 0.08


def test_perturbation_changes_gravity_proportionally():
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.78])
    nominal, heavy = PinocchioArm(), PinocchioArm(perturbation=ModelPerturbation(1.1))
    nominal.update(q, np.zeros(7))
    heavy.update(q, np.zeros(7))
    np.testing.assert_allclose(heavy.gravity, 1.1 * nominal.gravity, rtol=1e-9, atol=1e-12)


def test_invalid_perturbation_message():
    with pytest.raises(InvalidArgumentError, match="link_mass_scale"):
        ModelPerturbation(link_mass_scale=0.0)
