"""The wrench observer with the low-pass after the solve (wrench_observer.py): warm-up,
low-pass, norm clamps, TCP frame; values computed by hand."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.fake_dynamics import ConstantArmDynamics

from impact_control.arm_model import dynamics_arrays
from impact_control.errors import InvalidArgumentError
from impact_control.jacobian import regularized_wrench_map
from impact_control.wrench_observer import WrenchObserver, WrenchObserverConfig

LAMBDA = 0.02


def _setup(config: WrenchObserverConfig, wrench: np.ndarray):
    """An observer on the constant arm at rest whose torque reading carries ``wrench`` (the
    robot-on-environment sign: tau_meas = g + J^T w)."""
    dyn = ConstantArmDynamics(seed=3)
    dyn.update(np.zeros(7), np.zeros(7))
    wmap = regularized_wrench_map(dyn.jacobian, LAMBDA)
    tau = dyn.gravity + dyn.jacobian.T @ wrench
    raw = wmap @ (tau - dyn.gravity)  # what one solve gives (lambda biases it slightly)
    return WrenchObserver(config), dyn, wmap, tau, raw


def _tick(obs, dyn, wmap, tau) -> np.ndarray:
    return obs.update(np.zeros(7), tau, dynamics_arrays(dyn), wmap).copy()


def test_100_warmup_ticks_then_a_0_02_lowpass_of_the_solve() -> None:
    w = np.array([3.0, -2.0, 25.0, 0.3, -0.2, 0.1])
    obs, dyn, wmap, tau, raw = _setup(WrenchObserverConfig(enabled=True, frame="world"), w)
    for _ in range(100):
        assert not _tick(obs, dyn, wmap, tau).any()
    for _ in range(300):  # w_f = (1 - (1 - 0.02)^k) w_raw after k ticks
        out = _tick(obs, dyn, wmap, tau)
    np.testing.assert_allclose(out, (1.0 - 0.98 ** 300) * raw, rtol=1e-12, atol=1e-12)
    jac = dyn.jacobian  # the solve: (J J^T + lambda^2 I)^-1 J (tau - g), no M ddq term
    np.testing.assert_allclose(
        raw, np.linalg.solve(jac @ jac.T + LAMBDA**2 * np.eye(6), jac @ jac.T @ w), rtol=1e-10)
    obs.reset()  # warm-up again
    assert not _tick(obs, dyn, wmap, tau).any()


def test_norm_clamps_act_on_the_filtered_wrench_itself() -> None:
    """A 300 N / 90 Nm reading: the filtered force's norm rises to 120 N and stays there; the
    clamp rescales the filter's own state, so the next tick starts from 120 N."""
    w = np.array([0.0, 180.0, 240.0, 54.0, 0.0, 72.0])  # |f| = 300 N, |m| = 90 Nm
    cfg = WrenchObserverConfig(enabled=True, force_norm_max_n=120.0, torque_norm_max_nm=50.0,
                               warmup_ticks=0, frame="world")
    obs, dyn, wmap, tau, raw = _setup(cfg, w)
    for _ in range(400):
        out = _tick(obs, dyn, wmap, tau)
    assert np.linalg.norm(out[:3]) == pytest.approx(120.0, rel=1e-12)
    assert np.linalg.norm(out[3:]) == pytest.approx(50.0, rel=1e-12)
    before = obs.state.wrench_filtered.copy()
    out = _tick(obs, dyn, wmap, tau)
    expected = 0.98 * before[:3] + 0.02 * raw[:3]
    np.testing.assert_allclose(out[:3], expected * 120.0 / np.linalg.norm(expected), rtol=1e-12)


def test_tcp_frame_filter_is_the_rotated_world_filter_for_a_still_tcp() -> None:
    w = np.array([1.0, 2.0, 30.0, 0.1, 0.2, 0.3])
    world, dyn, wmap, tau, _ = _setup(WrenchObserverConfig(enabled=True, frame="world"), w)
    tcp = WrenchObserver(WrenchObserverConfig(enabled=True, frame="tcp"))
    for _ in range(150):
        a, b = _tick(world, dyn, wmap, tau), _tick(tcp, dyn, wmap, tau)
    np.testing.assert_allclose(b, a, atol=1e-12)
    rot = dyn.rot_ee_world
    np.testing.assert_allclose(tcp.state.wrench_filtered[:3], rot.T @ a[:3], atol=1e-12)


def test_bad_config_is_one_line() -> None:
    with pytest.raises(InvalidArgumentError, match=r"valid: \(0, 1\]"):
        WrenchObserverConfig(lowpass_alpha_per_tick=1.5)
    with pytest.raises(InvalidArgumentError, match="valid: an int >= 0"):
        WrenchObserverConfig(warmup_ticks=-1)
    with pytest.raises(InvalidArgumentError, match="valid choices: world, tcp"):
        WrenchObserverConfig(frame="base")
