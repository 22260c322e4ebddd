"""The numba chain kernel reproduces Pinocchio (the controller's model) on the same pin.Model."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from impact_control.chain_dynamics import ChainParams
from impact_control.dynamics import ModelPerturbation, PinocchioArm
from impact_control.errors import InvalidArgumentError


def _states(arm: PinocchioArm, n: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield rng.uniform(arm.q_lower, arm.q_upper), rng.normal(0.0, 1.0, 7)


@pytest.mark.parametrize("perturbation", [None, ModelPerturbation(1.2, 0.2, seed=3)])
def test_kernel_matches_pinocchio(perturbation):
    arm = PinocchioArm(perturbation=perturbation)
    model, data = arm.model, arm.model.createData()
    for q, dq in _states(arm, 10, seed=0):
        arm.update(q, dq)
        jac = pin.computeFrameJacobian(model, data, q, arm._tcp, pin.LOCAL_WORLD_ALIGNED)
        placement = pin.updateFramePlacement(model, data, arm._tcp)
        np.testing.assert_allclose(arm.pos_ee_world, placement.translation, atol=1e-12)
        np.testing.assert_allclose(arm.rot_ee_world, placement.rotation, atol=1e-12)
        np.testing.assert_allclose(arm.jacobian, jac, atol=1e-12)
        np.testing.assert_allclose(arm.mass_matrix, pin.crba(model, data, q), atol=1e-12)
        np.testing.assert_allclose(arm.gravity, pin.computeGeneralizedGravity(model, data, q),
                                   atol=1e-11)
        coriolis = pin.computeCoriolisMatrix(model, data, q, dq)
        # C is not unique; the controller only forms C dq and C^T dq
        np.testing.assert_allclose(arm.coriolis_matrix @ dq, coriolis @ dq, atol=1e-11)
        np.testing.assert_allclose(arm.coriolis_matrix.T @ dq, coriolis.T @ dq, atol=1e-11)


def test_coriolis_matrix_is_half_mass_matrix_derivative():
    """M'(q, dq) = C + C^T, checked by a central difference of M along dq."""
    arm = PinocchioArm()
    for q, dq in _states(arm, 5, seed=1):
        h = 1e-6
        arm.update(q + h * dq, dq)
        m_plus = arm.mass_matrix.copy()
        arm.update(q - h * dq, dq)
        m_minus = arm.mass_matrix.copy()
        arm.update(q, dq)
        m_dot = (m_plus - m_minus) / (2.0 * h)
        np.testing.assert_allclose(arm.coriolis_matrix + arm.coriolis_matrix.T, m_dot, atol=1e-7)


def test_coriolis_skipped_when_not_needed():
    arm = PinocchioArm()
    arm.need_coriolis = False
    arm.coriolis_matrix[:] = 7.0
    arm.update(np.full(7, 0.1), np.ones(7))
    assert np.all(arm.coriolis_matrix == 7.0)


def test_non_serial_model_rejected():
    model = pin.buildSampleModelHumanoidRandom()
    with pytest.raises(InvalidArgumentError, match="serial RZ chain"):
        ChainParams.from_pinocchio(model, 0)
