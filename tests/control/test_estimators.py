"""Wrench estimators on synthetic data generated from a known external wrench."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.fake_dynamics import ConstantArmDynamics

from impact_control.config import EstimatorConfig
from impact_control.estimators import (
    MomentumObserver,
    ResidualEstimator,
    make_estimator,
)
from impact_control.jacobian import regularized_wrench_map

DT = 0.001
# Wrench acting ON the robot (e.g. a contact pushing back); the estimate must be its negative.
W_EXT_ON_ROBOT = np.array([3.0, -8.0, -24.5, 0.4, -0.2, 0.3])


def _synthetic(
    dyn: ConstantArmDynamics, ticks: int, w_ext_on_robot: np.ndarray, accel: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(q, dq, tau_meas) with constant acceleration satisfying
    M ddq + C dq + g + b dq = tau + J^T w_ext exactly at every tick."""
    q, dq = np.zeros(7), np.full(7, 0.05)
    out = []
    for _ in range(ticks):
        tau = (
            dyn.mass_matrix @ accel
            + dyn.coriolis_matrix @ dq
            + dyn.gravity
            + dyn.joint_friction(dq)
            - dyn.jacobian.T @ w_ext_on_robot
        )
        out.append((q.copy(), dq.copy(), tau))
        q = q + DT * dq
        dq = dq + DT * accel
    return out


def _run(estimator, dyn, data) -> np.ndarray:
    wrenches = []
    for q, dq, tau in data:
        dyn.update(q, dq)
        wrenches.append(estimator.update(q, dq, tau, dyn).copy())
    return np.array(wrenches)


@pytest.mark.parametrize("kind", ["residual", "momentum"])
def test_recovers_wrench_exactly_without_noise(kind: str) -> None:
    dyn = ConstantArmDynamics(seed=1)
    accel = np.array([0.5, -0.3, 0.2, 0.1, -0.4, 0.6, 0.2])
    data = _synthetic(dyn, 2500, W_EXT_ON_ROBOT, accel)
    lam = 1e-7  # negligible regularisation: exact inverse of J^T on its row space
    est = make_estimator(EstimatorConfig(kind=kind, regularization=lam), DT)
    w = _run(est, dyn, data)
    np.testing.assert_allclose(w[-1], -W_EXT_ON_ROBOT, atol=1e-6)
    # With the paper's lambda the estimate equals the closed-form regularized solution.
    est = make_estimator(EstimatorConfig(kind=kind), DT)
    w = _run(est, dyn, data)
    map_ = regularized_wrench_map(dyn.jacobian, 0.02)
    expected = map_ @ (-dyn.jacobian.T @ W_EXT_ON_ROBOT)
    np.testing.assert_allclose(w[-1], expected, atol=1e-6)


@pytest.mark.parametrize("kind", ["residual", "momentum"])
def test_payload_sign_convention(kind: str) -> None:
    """Holding m = 2.5 kg at rest: the payload pulls the robot down, w_hat_z = +m g."""
    dyn = ConstantArmDynamics(seed=2)
    mg = 2.5 * 9.81
    data = _synthetic(dyn, 1500, np.array([0, 0, -mg, 0, 0, 0.0]), np.zeros(7))
    est = make_estimator(EstimatorConfig(kind=kind, regularization=1e-7), DT)
    w = _run(est, dyn, data)
    np.testing.assert_allclose(w[-1], [0, 0, mg, 0, 0, 0], atol=1e-6)


def test_residual_filter_time_constant() -> None:
    """A wrench step appears through the 0.0495 s first-order low-pass."""
    dyn = ConstantArmDynamics(seed=3)
    data = _synthetic(dyn, 200, W_EXT_ON_ROBOT, np.zeros(7))
    cfg = EstimatorConfig(regularization=1e-7)
    w = _run(ResidualEstimator(cfg, DT), dyn, data)
    alpha = 1.0 - np.exp(-DT / cfg.lowpass_time_constant_s)
    k = 49  # 50 ticks ~ one time constant
    np.testing.assert_allclose(w[k], -W_EXT_ON_ROBOT * (1 - (1 - alpha) ** (k + 1)), atol=1e-6)
    assert w[k][2] / -W_EXT_ON_ROBOT[2] == pytest.approx(1 - np.exp(-0.05 / 0.0495), abs=0.01)


def test_momentum_observer_first_order_step_response() -> None:
    dyn = ConstantArmDynamics(seed=4)
    gain = 50.0
    data = _synthetic(dyn, 200, W_EXT_ON_ROBOT, np.array([0.2, 0.1, -0.3, 0.0, 0.5, 0.1, -0.2]))
    obs = MomentumObserver(EstimatorConfig(kind="momentum", momentum_gain_per_s=gain), DT)
    tau_ext = dyn.jacobian.T @ W_EXT_ON_ROBOT
    for k, (q, dq, tau) in enumerate(data):
        dyn.update(q, dq)
        obs.update(q, dq, tau, dyn)
        # r_k = tau_ext (1 - (1 - K_O dt)^k): exact discrete first-order response.
        np.testing.assert_allclose(obs.r, tau_ext * (1 - (1 - gain * DT) ** k), atol=1e-9)
        if k == 20:  # t = 1 / K_O
            ratio = obs.r / tau_ext
            np.testing.assert_allclose(ratio, 1 - np.exp(-1.0), atol=0.01)


@pytest.mark.parametrize("kind", ["residual", "momentum"])
def test_with_sensor_noise(kind: str) -> None:
    dyn = ConstantArmDynamics(seed=5)
    rng = np.random.default_rng(0)
    data = _synthetic(dyn, 3000, W_EXT_ON_ROBOT, np.zeros(7))
    noisy = [
        (q, dq + rng.normal(scale=1e-3, size=7), tau + rng.normal(scale=0.1, size=7))
        for q, dq, tau in data
    ]
    est = make_estimator(EstimatorConfig(kind=kind), DT)
    w = _run(est, dyn, noisy)[1000:]
    exact = regularized_wrench_map(dyn.jacobian, 0.02) @ (-dyn.jacobian.T @ W_EXT_ON_ROBOT)
    np.testing.assert_allclose(w.mean(axis=0), exact, atol=0.05)  # unbiased
    assert np.abs(w - exact).max() < 1.5  # no tick off by more than 1.5 N / 1.5 Nm


@pytest.mark.parametrize("kind", ["residual", "momentum"])
def test_reset_restarts_from_zero(kind: str) -> None:
    dyn = ConstantArmDynamics(seed=6)
    data = _synthetic(dyn, 300, W_EXT_ON_ROBOT, np.zeros(7))
    est = make_estimator(EstimatorConfig(kind=kind), DT)
    _run(est, dyn, data)
    est.reset()
    q, dq, tau = data[0]
    dyn.update(q, dq)
    first = est.update(q, dq, tau, dyn)
    assert np.linalg.norm(first) < 0.1 * np.linalg.norm(W_EXT_ON_ROBOT)


def test_precomputed_map_gives_same_result() -> None:
    dyn = ConstantArmDynamics(seed=7)
    data = _synthetic(dyn, 50, W_EXT_ON_ROBOT, np.zeros(7))
    a, b = ResidualEstimator(EstimatorConfig(), DT), ResidualEstimator(EstimatorConfig(), DT)
    for q, dq, tau in data:
        dyn.update(q, dq)
        wa = a.update(q, dq, tau, dyn).copy()
        wb = b.update(q, dq, tau, dyn, wrench_map=regularized_wrench_map(dyn.jacobian, 0.02))
        np.testing.assert_allclose(wa, wb, rtol=1e-12, atol=1e-12)


def test_regularized_map_is_least_squares_solution() -> None:
    rng = np.random.default_rng(8)
    jac, r, lam = rng.normal(size=(6, 7)), rng.normal(size=7), 0.3
    w = regularized_wrench_map(jac, lam) @ r
    grad = jac @ (jac.T @ w - r) + lam**2 * w  # gradient of the LS objective / 2
    np.testing.assert_allclose(grad, 0.0, atol=1e-12)
