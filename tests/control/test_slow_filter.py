"""Clipped slow-wrench filter: ramp + exponential timing, per-tick clipping, rate signal."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impact_envs.control.config import ControllerConfig, SlowWrenchConfig
from impact_envs.control.presets import preset_config
from impact_envs.control.slow_filter import SlowWrenchFilter, step_response_time_s
from impact_envs.errors import InvalidArgumentError

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
