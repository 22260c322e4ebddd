"""Task-space impedance law: gravity, stiffness, damping, null-space projection, Coriolis."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.fake_dynamics import ConstantArmDynamics

from impact_control.config import ImpedanceConfig
from impact_control.errors import InvalidArgumentError
from impact_control.impedance import CartesianImpedance
from impact_control.jacobian import regularized_wrench_map
from impact_control.lie import matrix_to_quat, so3_exp

K = np.array([400.0, 400.0, 400.0, 30.0, 30.0, 30.0])
D = np.array([40.0, 40.0, 40.0, 10.95, 10.95, 10.95])


def _setup(q: np.ndarray, dq: np.ndarray, config: ImpedanceConfig | None = None):
    dyn = ConstantArmDynamics(seed=11)
    dyn.update(q, dq)
    imp = CartesianImpedance(config or ImpedanceConfig())
    wmap = regularized_wrench_map(dyn.jacobian, imp.config.nullspace_pinv_damping)
    return dyn, imp, wmap


def _total(imp, dyn, q, dq, pos, quat, wmap, w_ff=None) -> np.ndarray:
    return imp.compute(dyn, q, dq, pos, quat, wmap, w_ff).copy() + imp.tau_gravity


def test_zero_error_zero_velocity_gives_gravity() -> None:
    q, dq = np.full(7, 0.1), np.zeros(7)
    dyn, imp, wmap = _setup(q, dq)
    imp.set_posture(q)
    quat = matrix_to_quat(dyn.rot_ee_world)
    tau = _total(imp, dyn, q, dq, dyn.pos_ee_world, quat, wmap)
    np.testing.assert_allclose(tau, dyn.gravity, atol=1e-12)
    np.testing.assert_allclose(imp.pose_error, 0.0, atol=1e-12)


def test_position_and_orientation_error_give_k_times_e() -> None:
    q, dq = np.full(7, -0.2), np.zeros(7)
    dyn, imp, wmap = _setup(q, dq)
    imp.set_posture(q)
    e_pos, e_rot = np.array([0.01, -0.02, 0.005]), np.array([0.02, 0.0, -0.03])
    quat_d = matrix_to_quat(so3_exp(e_rot) @ dyn.rot_ee_world)
    tau = _total(imp, dyn, q, dq, dyn.pos_ee_world + e_pos, quat_d, wmap)
    np.testing.assert_allclose(imp.pose_error, np.concatenate([e_pos, e_rot]), atol=1e-12)
    wrench = np.linalg.pinv(dyn.jacobian.T) @ (tau - dyn.gravity)
    np.testing.assert_allclose(wrench, K * np.concatenate([e_pos, e_rot]), atol=1e-9)
    assert wrench[0] == pytest.approx(4.0)  # 400 N/m * 1 cm


def test_damping_opposes_tcp_velocity() -> None:
    q, dq = np.zeros(7), np.array([0.3, -0.1, 0.2, 0.05, -0.4, 0.1, 0.2])
    dyn, imp, wmap = _setup(
        q,
        dq,
        ImpedanceConfig(nullspace_stiffness_nm_per_rad=0.0, nullspace_damping_nms_per_rad=0.0),
    )
    imp.set_posture(q)
    quat = matrix_to_quat(dyn.rot_ee_world)
    tau = _total(imp, dyn, q, dq, dyn.pos_ee_world, quat, wmap)
    twist = dyn.jacobian @ dq
    np.testing.assert_allclose(imp.wrench_imp_world, -D * twist, atol=1e-12)
    expected = dyn.jacobian.T @ (-D * twist) + dyn.coriolis_matrix @ dq + dyn.gravity
    np.testing.assert_allclose(tau, expected, atol=1e-12)


@pytest.mark.parametrize("damping, rel_tol", [(1e-4, 1e-6), (0.02, 0.05)])
def test_nullspace_torque_produces_no_task_wrench(damping: float, rel_tol: float) -> None:
    """Static projector N = I - J^T (J^+)^T: the least-squares wrench of N tau_0 vanishes."""
    q, dq = np.full(7, 0.3), np.array([0.1, 0.0, -0.2, 0.1, 0.0, 0.3, -0.1])
    dyn, imp, wmap = _setup(q, dq, ImpedanceConfig(nullspace_pinv_damping=damping))
    imp.set_posture(np.zeros(7))
    imp.compute(dyn, q, dq, dyn.pos_ee_world, matrix_to_quat(dyn.rot_ee_world), wmap)
    tau0 = imp.tau_posture
    np.testing.assert_allclose(tau0, 10.0 * (0.0 - q) - 2 * np.sqrt(10.0) * dq, atol=1e-12)
    tau_null = imp.tau_null(dyn.jacobian)
    pinv_t = np.linalg.pinv(dyn.jacobian.T)
    assert np.linalg.norm(pinv_t @ tau_null) <= rel_tol * np.linalg.norm(pinv_t @ tau0)
    assert np.linalg.norm(tau_null) > 0.1 * np.linalg.norm(tau0)  # the posture torque survives


def test_feedforward_wrench_is_added_through_jacobian_transpose() -> None:
    q, dq = np.full(7, 0.05), np.zeros(7)
    dyn, imp, wmap = _setup(q, dq)
    imp.set_posture(q)
    quat, pos = matrix_to_quat(dyn.rot_ee_world), dyn.pos_ee_world + 0.01
    w_ff = np.array([1.0, 2.0, 24.5, 0.1, -0.2, 0.3])
    base = _total(imp, dyn, q, dq, pos, quat, wmap)
    with_ff = _total(imp, dyn, q, dq, pos, quat, wmap, w_ff)
    np.testing.assert_allclose(with_ff - base, dyn.jacobian.T @ w_ff, atol=1e-12)


def test_coriolis_and_gravity_switches() -> None:
    q, dq = np.zeros(7), np.array([0.5, -0.5, 0.2, 0.1, 0.3, -0.2, 0.4])
    results = {}
    for flags in [(True, True), (False, True), (True, False)]:
        cfg = ImpedanceConfig(compensate_gravity=flags[0], compensate_coriolis=flags[1])
        dyn, imp, wmap = _setup(q, dq, cfg)
        imp.set_posture(q)
        quat = matrix_to_quat(dyn.rot_ee_world)
        results[flags] = _total(imp, dyn, q, dq, dyn.pos_ee_world, quat, wmap)
    np.testing.assert_allclose(results[(True, True)] - results[(False, True)], dyn.gravity)
    np.testing.assert_allclose(
        results[(True, True)] - results[(True, False)], dyn.coriolis_matrix @ dq, atol=1e-12
    )


def test_defaults_and_validation() -> None:
    cfg = ImpedanceConfig()
    assert cfg.nullspace_damping == pytest.approx(2 * np.sqrt(10.0))
    np.testing.assert_allclose(CartesianImpedance(cfg).stiffness, K)
    np.testing.assert_allclose(CartesianImpedance(cfg).damping, D)
    with pytest.raises(InvalidArgumentError):
        ImpedanceConfig(stiffness_translational_n_per_m=(400.0, 400.0))
    with pytest.raises(InvalidArgumentError):
        ImpedanceConfig(damping_rotational_nms_per_rad=(1.0, -1.0, 1.0))
    with pytest.raises(InvalidArgumentError):
        ImpedanceConfig(nullspace_pinv_damping=0.0)
