"""``MujocoArm`` (MuJoCo-computed arm model) against the Pinocchio model on the FR3."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from impact_control.controller import ImpactController
from impact_control.dynamics import ARM_JOINTS, ROBOT_XML, PinocchioArm
from impact_control.errors import InvalidArgumentError
from impact_envs.robot.mujoco_arm import MujocoArm, full_mass_matrix

FINGER = 0.02


@pytest.fixture(scope="module")
def arms() -> tuple[MujocoArm, PinocchioArm]:
    model = mujoco.MjModel.from_xml_path(str(ROBOT_XML))
    qpos = model.qpos0.copy()
    qpos[7:9] = FINGER  # the fingers where the Pinocchio model locks them
    return MujocoArm(model, ARM_JOINTS, "tcp", qpos), PinocchioArm(finger_opening_m=FINGER)


def _states(pin_arm: PinocchioArm, n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    qs = rng.uniform(pin_arm.q_lower + 0.05, pin_arm.q_upper - 0.05, size=(n, 7))
    return [(q, rng.normal(0.0, 0.8, 7)) for q in qs]


MUJOCO_4 = int(mujoco.__version__.split(".")[0]) >= 4


def test_equals_mujocos_own_forward_pass(arms):
    """The private-data computation is MuJoCo's: identical to ``mj_forward`` on a copy."""
    mj_arm, pin_arm = arms
    model, data = mj_arm.model, mujoco.MjData(mj_arm.model)
    for q, _ in _states(pin_arm, 5, seed=6):
        mj_arm.update(q, np.zeros(7))
        data.qpos[:] = mj_arm.data.qpos
        mujoco.mj_forward(model, data)
        full = np.zeros((model.nv, model.nv))
        full_mass_matrix(model, data, full)
        np.testing.assert_array_equal(mj_arm.mass_matrix, full[:7, :7])
        np.testing.assert_array_equal(mj_arm.gravity, data.qfrc_bias[:7])
        np.testing.assert_array_equal(mj_arm.pos_ee_world, data.site_xpos[model.site("tcp").id])


@pytest.mark.skipif(not MUJOCO_4, reason="MuJoCo 3.x compiles this model's inertias to within "
                    "1.5e-8 of Pinocchio's, not 1e-8 (measured with 3.9, the robosuite extra's)")
def test_fk_jacobian_mass_and_gravity_agree_with_pinocchio_to_1e_8(arms):
    mj_arm, pin_arm = arms
    for q, dq in _states(pin_arm, 25, seed=3):
        mj_arm.update(q, dq)
        pin_arm.update(q, dq)
        for name in ("pos_ee_world", "rot_ee_world", "jacobian", "mass_matrix", "gravity"):
            np.testing.assert_allclose(getattr(mj_arm, name), getattr(pin_arm, name),
                                       atol=1e-8, rtol=0, err_msg=name)


def test_coriolis_products_agree_with_pinocchio(arms):
    """C dq exactly, C^T dq through a central difference of M (|error| ~1e-8 Nm); 1e-7 covers
    MuJoCo 3.x's compiled inertias too."""
    mj_arm, pin_arm = arms
    for q, dq in _states(pin_arm, 25, seed=4):
        mj_arm.update(q, dq)
        pin_arm.update(q, dq)
        np.testing.assert_allclose(mj_arm.coriolis_matrix @ dq, pin_arm.coriolis_matrix @ dq,
                                   atol=1e-7)
        np.testing.assert_allclose(mj_arm.coriolis_matrix.T @ dq,
                                   pin_arm.coriolis_matrix.T @ dq, atol=1e-6)
    mj_arm.update(q, np.zeros(7))
    assert not mj_arm.coriolis_matrix.any()


def test_the_controller_gives_the_same_torques_on_either_model(arms):
    mj_arm, _ = arms
    ctrls = [ImpactController(dyn) for dyn in (mj_arm, PinocchioArm(finger_opening_m=FINGER))]
    q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])
    rng = np.random.default_rng(5)
    for c in ctrls:
        c.reset(q0)
    target = np.array([0.45, 0.05, 0.35]), np.array([0.0, 1.0, 0.0, 0.0])
    for _ in range(60):
        q, dq = q0 + rng.normal(0, 0.01, 7), rng.normal(0, 0.1, 7)
        tau_meas = rng.normal(0, 2.0, 7)
        taus = [c.compute(q, dq, tau_meas, *target) for c in ctrls]
        np.testing.assert_allclose(taus[0], taus[1], atol=1e-6)


def test_bad_model_names_are_one_line_errors():
    model = mujoco.MjModel.from_xml_path(str(ROBOT_XML))
    with pytest.raises(InvalidArgumentError, match="not in the MuJoCo model"):
        MujocoArm(model, ARM_JOINTS, "no_such_site")
    with pytest.raises(InvalidArgumentError, match="7 arm joints"):
        MujocoArm(model, ARM_JOINTS[:6], "tcp")
