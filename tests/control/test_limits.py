"""Torque saturation and libfranka-style torque-rate limiting."""

from __future__ import annotations

import numpy as np
import pytest

from impact_control.config import LimitsConfig
from impact_control.errors import InvalidArgumentError
from impact_control.limits import (
    TorqueLimiter,
    libfranka_limits,
    limit_rate_kernel,
    saturate_kernel,
)

TAU_MAX = np.array([87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0])


def test_limit_rate_clamps_only_large_changes() -> None:
    last = np.array([0.0, 1.0, -1.0, 5.0, 0.0, 0.0, 0.0])
    desired = np.array([0.5, 3.0, -4.0, 5.2, -0.99, 1.0, -1.0])
    out = np.empty(7)
    limit_rate_kernel(desired, last, 1.0, out)
    np.testing.assert_allclose(out, [0.5, 2.0, -2.0, 5.2, -0.99, 1.0, -1.0])


def test_saturate_to_fr3_limits() -> None:
    tau = np.array([100.0, -100.0, 50.0, -87.0, 13.0, -20.0, 11.9])
    out = np.empty(7)
    saturate_kernel(tau, TAU_MAX, out)
    np.testing.assert_allclose(out, [87, -87, 50, -87, 12, -12, 11.9])


def test_limiter_defaults_are_fr3() -> None:
    limiter = TorqueLimiter(LimitsConfig(), dt_s=0.001)
    np.testing.assert_array_equal(limiter.tau_max, TAU_MAX)
    assert limiter.max_delta_nm == pytest.approx(1.0)


CLIP_1000 = LimitsConfig(torque_rate_max_nm_per_s=1000.0, rate_limiter="per_tick_clip")
"""The per-tick clip at 1000 Nm/s (the limiter of the tables before 2026-11-26): 1 Nm/tick."""


def test_default_limits_are_libfranka_s() -> None:
    assert LimitsConfig() == libfranka_limits()


def test_limiter_ramps_a_step_at_1nm_per_tick_then_saturates() -> None:
    limiter = TorqueLimiter(CLIP_1000, dt_s=0.001)
    gravity = np.zeros(7)
    request = np.full(7, 50.0)
    history = np.array([limiter.apply(request, gravity).copy() for _ in range(60)])
    np.testing.assert_allclose(history[9, :4], 10.0)  # 10 ticks -> 10 Nm
    np.testing.assert_allclose(history[49:, :4], 50.0)
    np.testing.assert_allclose(history[11:, 4:], 12.0)  # wrist saturated at 12 Nm
    assert np.max(np.abs(np.diff(history, axis=0))) <= 1.0 + 1e-12


def test_limiter_rate_limits_command_without_gravity() -> None:
    limiter = TorqueLimiter(LimitsConfig(), dt_s=0.001)
    gravity = np.array([0.0, 30.0, 0.0, -20.0, 0.0, 1.0, 0.0])
    out = limiter.apply(np.zeros(7), gravity)  # gravity passes at once, like libfranka
    np.testing.assert_allclose(out, gravity)


def test_limiter_state_follows_saturated_output() -> None:
    limiter = TorqueLimiter(LimitsConfig(), dt_s=0.001)
    for _ in range(200):
        out = limiter.apply(np.full(7, 200.0), np.zeros(7))
    np.testing.assert_allclose(out, TAU_MAX)
    out = limiter.apply(np.zeros(7), np.zeros(7))
    np.testing.assert_allclose(out, TAU_MAX - 1.0)  # from the saturated value, not from 200


def test_limiter_reset() -> None:
    limiter = TorqueLimiter(CLIP_1000, dt_s=0.001)
    limiter.reset(np.full(7, 5.0))
    np.testing.assert_allclose(limiter.apply(np.zeros(7), np.zeros(7)), 4.0)
    limiter.reset()
    np.testing.assert_allclose(limiter.apply(np.full(7, 3.0), np.zeros(7)), 1.0)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"torque_max_nm": (87.0,) * 6},
        {"torque_max_nm": (87.0,) * 6 + (-1.0,)},
        {"torque_rate_max_nm_per_s": 0.0},
        {"torque_rate_max_nm_per_s": float("nan")},
    ],
)
def test_limits_config_validation(kwargs: dict) -> None:
    with pytest.raises(InvalidArgumentError):
        LimitsConfig(**kwargs)


def _libfranka_limit_rate(max_rate: float, cmd: list[float], last: list[float]) -> list[float]:
    """libfranka's limitRate (command_saturation.cpp), transcribed to Python floats."""
    return [lst + max(min((c - lst) / 1e-3, max_rate), -max_rate) * 1e-3
            for c, lst in zip(cmd, last, strict=True)]


def test_libfranka_limits_are_libfranka_constants() -> None:
    from impact_control.limits import libfranka_limits

    cfg = libfranka_limits()
    assert cfg.torque_rate_max_nm_per_s == 1000.0 - 1e-3  # kMaxTorqueRate = 1000 - kLimitEps
    assert cfg.rate_limiter == "libfranka"
    assert cfg.torque_max_nm == tuple(TAU_MAX)


def test_libfranka_rate_limiter_is_bit_identical_to_limit_rate() -> None:
    from impact_control.limits import libfranka_limits

    rng = np.random.default_rng(3)
    limiter = TorqueLimiter(libfranka_limits(), dt_s=0.001)
    last = [0.0] * 7
    for _ in range(2000):  # steps up to +-3 Nm: mostly rate-limited, some not; no saturation
        cmd = (np.asarray(last) + rng.uniform(-3.0, 3.0, 7)).clip(-11.0, 11.0)
        expected = _libfranka_limit_rate(1000.0 - 1e-3, cmd.tolist(), last)
        out = limiter.apply(cmd, np.zeros(7))
        assert out.tolist() == expected  # exact, float for float
        last = expected


def test_libfranka_rate_limiter_never_exceeds_the_robots_rate() -> None:
    from impact_control.limits import libfranka_limits

    limiter = TorqueLimiter(libfranka_limits(), dt_s=0.001)
    gravity = np.zeros(7)
    outs = [limiter.apply(np.full(7, 10.0 * (-1) ** (k // 30)), gravity).copy()
            for k in range(300)]
    rates = np.abs(np.diff(np.asarray(outs), axis=0)) / 1e-3
    assert rates.max() < 1000.0  # the robot's discontinuity reflex threshold
    assert rates.max() > 999.99


def test_libfranka_rate_limiter_needs_a_1khz_controller() -> None:
    from impact_control.config import ControllerConfig
    from impact_control.limits import libfranka_limits

    with pytest.raises(InvalidArgumentError, match="kDeltaT"):
        ControllerConfig(dt_s=0.002, limits=libfranka_limits())
    with pytest.raises(InvalidArgumentError, match="per_tick_clip"):
        LimitsConfig(rate_limiter="franka")


AUTHORS_SIM = LimitsConfig(torque_rate_max_nm_per_s=500.0, rate_limiter="per_tick_clip",
                           rate_limit_includes_gravity=True)
"""The authors' simulation: 0.5 Nm per 1 ms tick on the command with gravity."""


def test_rate_limit_of_0_5_nm_per_tick_with_gravity() -> None:
    """After reset the previous command is 0: a gravity torque of (10, -3, 0.2, 0, ...) Nm
    with nothing else is reached at 0.5 Nm per tick (20 ticks, 6 ticks, at once); without
    gravity in the bound (authors_real, libfranka) it passes at once."""
    limiter = TorqueLimiter(AUTHORS_SIM, dt_s=0.001)
    gravity = np.array([10.0, -3.0, 0.2, 0.0, 0.0, 0.0, 0.0])
    history = np.array([limiter.apply(np.zeros(7), gravity).copy() for _ in range(25)])
    np.testing.assert_allclose(history[:, 0], np.minimum(0.5 * np.arange(1, 26), 10.0))
    np.testing.assert_allclose(history[:, 1], np.maximum(-0.5 * np.arange(1, 26), -3.0))
    np.testing.assert_allclose(history[:, 2], 0.2)
    real = TorqueLimiter(LimitsConfig(torque_rate_max_nm_per_s=500.0,
                                      rate_limiter="per_tick_clip"), dt_s=0.001)
    np.testing.assert_allclose(real.apply(np.full(7, 2.0), gravity), gravity + 0.5)


def test_rate_limit_with_gravity_measures_from_the_unsaturated_command() -> None:
    """The authors keep the rate-limited command (no saturation in their controller; the
    actuators clip): 20 Nm requested on a 12 Nm wrist joint, then 0: the output leaves 12 Nm
    only once the remembered command, 20 - 0.5 k, is below it."""
    limiter = TorqueLimiter(AUTHORS_SIM, dt_s=0.001)
    limiter.gravity_rate.last_with_gravity[:] = 20.0
    out = limiter.apply(np.zeros(7), np.zeros(7))
    assert out[4] == 12.0 and limiter.gravity_rate.last_with_gravity[4] == 19.5
    for _ in range(16):
        out = limiter.apply(np.zeros(7), np.zeros(7))
    assert out[4] == 11.5  # 20 - 0.5 x 17
    limiter.reset()
    assert not limiter.gravity_rate.last_with_gravity.any()


def test_rate_limit_with_gravity_needs_the_per_tick_clip() -> None:
    with pytest.raises(InvalidArgumentError, match="valid: rate_limiter='per_tick_clip'"):
        LimitsConfig(rate_limit_includes_gravity=True)
