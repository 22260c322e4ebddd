"""Clipped slow-wrench filter: ramp + exponential timing, per-tick clipping, rate signal."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impact_control.config import ControllerConfig, SlowWrenchConfig
from impact_control.errors import InvalidArgumentError
from impact_control.presets import preset_config
from impact_control.slow_filter import SlowWrenchFilter, step_response_time_s

DT = 0.001
PAPER = preset_config("paper").slow_wrench
"""The paper's filter (eta 2 / 1 per s, clip 10 N / 1 Nm): the numbers below are its timing."""


def _run(filt: SlowWrenchFilter, wrench: np.ndarray, ticks: int) -> np.ndarray:
    return np.array([filt.update(wrench).copy() for _ in range(ticks)])


def test_large_force_step_is_ramp_then_exponential() -> None:
    cfg = PAPER
    filt = SlowWrenchFilter(cfg, DT)
    step = np.array([0.0, 0.0, 30.0, 0.0, 0.0, 0.0])
    traj = _run(filt, step, 3000)[:, 2]
    # Ramp at eta * clip = 20 N/s: exactly 0.02 N per tick while the gap exceeds 10 N.
    np.testing.assert_allclose(traj[:1000], 0.02 * np.arange(1, 1001), atol=1e-9)
    # Then gap_k = 10 (1 - eta dt)^(k - 1000): time constant 1 / eta = 0.5 s.
    assert 30.0 - traj[1499] == pytest.approx(10.0 * (1.0 - 0.002) ** 500, rel=1e-9)
    assert 30.0 - traj[1499] == pytest.approx(10.0 * math.exp(-1.0), rel=2e-3)
    # Analytic continuous-time crossing of 90 % matches the recursion within 2 ticks.
    t90 = step_response_time_s(30.0, 0.9, cfg)
    k90 = int(np.argmax(traj >= 27.0))
    assert abs(k90 * DT - t90) <= 0.002


def test_small_step_is_pure_exponential_per_axis() -> None:
    filt = SlowWrenchFilter(PAPER, DT)
    step = np.array([4.0, 0.0, 0.0, 0.5, 0.0, 0.0])
    traj = _run(filt, step, 1000)
    assert traj[499, 0] == pytest.approx(4.0 * (1 - (1 - 0.002) ** 500), rel=1e-12)
    assert traj[999, 3] == pytest.approx(0.5 * (1 - (1 - 0.001) ** 1000), rel=1e-12)  # eta 1/s


def test_clipping_bounds_every_per_tick_change() -> None:
    filt = SlowWrenchFilter(PAPER, DT)
    rng = np.random.default_rng(3)
    prev = filt.wrench_slow_world.copy()
    max_step = np.array([0.02, 0.02, 0.02, 0.001, 0.001, 0.001])
    for _ in range(500):
        cur = filt.update(rng.normal(scale=200.0, size=6)).copy()
        assert np.all(np.abs(cur - prev) <= max_step + 1e-15)
        prev = cur


def test_slow_rate_definition() -> None:
    filt = SlowWrenchFilter(PAPER, DT)
    filt.update(np.array([0.0, 0.0, 50.0, 0.0, 0.0, 0.0]))
    assert filt.slow_rate == pytest.approx(1.0)  # one axis at max slew
    np.testing.assert_allclose(filt.rate_world[:3], [0.0, 0.0, 20.0])
    filt.reset()
    filt.update(np.array([50.0, -50.0, 50.0, 0.0, 0.0, 0.0]))
    assert filt.slow_rate == pytest.approx(math.sqrt(3.0))
    filt.reset()
    filt.update(np.array([1.2, 0.0, 1.6, 9.0, 9.0, 9.0]))  # torque axes do not count
    assert filt.slow_rate == pytest.approx(2.0 * 2.0 / 20.0)


def test_reset_sets_initial_value() -> None:
    filt = SlowWrenchFilter(SlowWrenchConfig(), DT)
    filt.reset(np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3]))
    out = filt.update(np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3]))
    np.testing.assert_allclose(out, [1.0, 2.0, 3.0, 0.1, 0.2, 0.3])
    assert filt.slow_rate == 0.0


def test_config_validation() -> None:
    with pytest.raises(InvalidArgumentError):
        SlowWrenchConfig(clip_force_n=0.0)
    with pytest.raises(InvalidArgumentError):
        ControllerConfig(dt_s=1.0)  # eta * dt >= 1 would overshoot


def test_leak_multiplies_by_1_minus_0_01_dt_after_each_update() -> None:
    """From w_slow = 5 N toward 0 (gap inside the clip): w_k = 5 ((1 - eta dt)(1 - leak dt))^k."""
    cfg = SlowWrenchConfig(rate_force_per_s=2.0, leak_per_s=0.01)
    filt = SlowWrenchFilter(cfg, DT)
    filt.reset(np.array([5.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
    traj = _run(filt, np.zeros(6), 1000)[:, 0]
    k = np.arange(1, 1001)
    np.testing.assert_allclose(traj, 5.0 * ((1 - 2.0 * DT) * (1 - 0.01 * DT)) ** k, rtol=1e-12)
    held = SlowWrenchFilter(SlowWrenchConfig(leak_per_s=0.01), DT)
    held.reset(np.array([0.0, 0.0, 40.0, 0.0, 0.0, 0.0]))  # a steady 40 N load
    out = _run(held, np.array([0.0, 0.0, 40.0, 0.0, 0.0, 0.0]), 20000)[-1, 2]
    assert out == pytest.approx(40.0 * 20.0 / (20.0 + 0.01), rel=1e-6)  # the leak's bias


def test_norm_clamps_bound_force_and_torque_of_w_slow() -> None:
    cfg = SlowWrenchConfig(force_norm_max_n=120.0, torque_norm_max_nm=50.0)
    filt = SlowWrenchFilter(cfg, DT)
    big = np.array([300.0, 0.0, 400.0, 60.0, 80.0, 0.0])  # |f| 500 N, |m| 100 Nm
    traj = _run(filt, big, 3000)  # the force ramps at 200 N/s per axis into the bound
    assert np.linalg.norm(traj[-1, :3]) == pytest.approx(120.0, rel=1e-12)
    assert np.max(np.linalg.norm(traj[:, :3], axis=1)) <= 120.0 * (1 + 1e-12)
    filt.reset(big)  # from beyond both bounds: clamped on the first tick, direction kept
    out = filt.update(big)
    np.testing.assert_allclose(out, [72.0, 0.0, 96.0, 30.0, 40.0, 0.0], rtol=1e-12)


def test_tcp_frame_clips_on_tcp_axes_and_reports_the_world_wrench() -> None:
    """A TCP turned 90 deg about world z: a 30 N step along world x is a step along TCP -y
    (x_world = -y_tcp), clipped there at 10 N: w_slow's first tick is 10 x 0.02 along world x."""
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    filt = SlowWrenchFilter(SlowWrenchConfig(frame="tcp"), DT)
    out = filt.update(np.array([30.0, 0.0, 0.0, 0.0, 0.0, 0.0]), rot)
    np.testing.assert_allclose(out, [0.2, 0.0, 0.0, 0.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(filt.wrench_slow_kept, [0.0, -0.2, 0.0, 0.0, 0.0, 0.0],
                               atol=1e-15)
    with pytest.raises(InvalidArgumentError, match="valid: the TCP rotation"):
        filt.update(np.zeros(6))
    with pytest.raises(InvalidArgumentError, match="valid choices: world, tcp"):
        SlowWrenchConfig(frame="base")


def test_the_options_layout_and_flag_slot_agree() -> None:
    from impact_control.slow_filter_options import (
        SLOW_FILTER_EXTRA_LAYOUT,
        options_on,
        unpack_slow_filter_extra,
    )

    size = SLOW_FILTER_EXTRA_LAYOUT.size()
    ext = np.zeros(size)
    x = unpack_slow_filter_extra(ext)
    assert x.wrench_in.base is not None and sum(v.shape[0] for v in x) == size
    x.on[0] = 1.0
    assert options_on(ext)
    assert not options_on(SlowWrenchFilter(SlowWrenchConfig(), DT).state.extra)
    assert options_on(SlowWrenchFilter(SlowWrenchConfig(leak_per_s=0.01), DT).state.extra)
