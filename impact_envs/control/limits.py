"""Torque saturation and torque-rate limiting (FR3 bounds, libfranka ``limitRate`` semantics)."""

from __future__ import annotations

import numpy as np

from impact_envs.control.config import LimitsConfig


def limit_rate(
    tau_desired: np.ndarray,
    tau_last: np.ndarray,
    max_delta_nm: float,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Clamp each joint's change per tick: |tau - tau_last| <= max_delta_nm.

    Args:
        tau_desired: Requested torque (7,) [Nm].
        tau_last: Torque commanded on the previous tick (7,) [Nm].
        max_delta_nm: Largest change per tick [Nm] (rate limit [Nm/s] times dt [s]).
        out: Optional output array (may alias ``tau_desired``).

    Returns:
        The rate-limited torque (7,) [Nm].
    """
    if out is None:
        out = np.empty_like(tau_desired, dtype=float)
    np.subtract(tau_desired, tau_last, out=out)
    np.minimum(out, max_delta_nm, out=out)
    np.maximum(out, -max_delta_nm, out=out)
    out += tau_last
    return out


def saturate(tau: np.ndarray, tau_max: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Clamp each joint torque to [-tau_max, tau_max] [Nm]."""
    if out is None:
        out = np.empty_like(tau, dtype=float)
    np.minimum(tau, tau_max, out=out)
    np.maximum(out, -tau_max, out=out)
    return out


class TorqueLimiter:
    """Stateful torque-rate limiter followed by saturation.

    Like libfranka, the rate limit is applied to the torque *without* gravity (libfranka's
    ``tau_J_d`` excludes gravity, which the robot adds itself); gravity is then added and the
    total is saturated. The rate-limited state is re-synchronised with what was actually sent,
    so saturation cannot make the two diverge.
    """

    def __init__(self, config: LimitsConfig, dt_s: float) -> None:
        """Create the limiter.

        Args:
            config: Limits.
            dt_s: Control period [s]; the per-tick bound is ``torque_rate_max_nm_per_s * dt_s``.
        """
        self.tau_max = np.asarray(config.torque_max_nm, dtype=float)
        self.max_delta_nm = config.torque_rate_max_nm_per_s * dt_s
        self._last_no_gravity = np.zeros(len(config.torque_max_nm))
        self.output = np.zeros(len(config.torque_max_nm))

    def reset(self, tau_no_gravity: np.ndarray | None = None) -> None:
        """Set the previously commanded torque without gravity (default 0) [Nm]."""
        if tau_no_gravity is None:
            self._last_no_gravity.fill(0.0)
        else:
            self._last_no_gravity[:] = tau_no_gravity

    def apply(self, tau_no_gravity: np.ndarray, tau_gravity: np.ndarray) -> np.ndarray:
        """Rate-limit ``tau_no_gravity``, add ``tau_gravity``, saturate.

        Args:
            tau_no_gravity: Requested torque excluding gravity compensation (7,) [Nm].
            tau_gravity: Gravity compensation torque (7,) [Nm] (zeros if not compensated).

        Returns:
            The torque to apply (7,) [Nm]; an internal buffer, overwritten on the next call.
        """
        out = self.output
        limit_rate(tau_no_gravity, self._last_no_gravity, self.max_delta_nm, out=out)
        out += tau_gravity
        saturate(out, self.tau_max, out=out)
        np.subtract(out, tau_gravity, out=self._last_no_gravity)
        return out
