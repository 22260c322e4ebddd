"""Torque saturation and torque-rate limiting (FR3 bounds, libfranka ``limitRate`` semantics)."""

from __future__ import annotations

import numpy as np

from impact_envs.control import kernels
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
        out: Optional float64 output array (may alias ``tau_desired``).

    Returns:
        The rate-limited torque (7,) [Nm].
    """
    tau_desired = np.asarray(tau_desired, dtype=np.float64)
    if out is None:
        out = np.empty_like(tau_desired)
    kernels.limit_rate(
        tau_desired, np.asarray(tau_last, dtype=np.float64), float(max_delta_nm), out
    )
    return out


def saturate(tau: np.ndarray, tau_max: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Clamp each joint torque to [-tau_max, tau_max] [Nm]."""
    tau = np.asarray(tau, dtype=np.float64)
    if out is None:
        out = np.empty_like(tau)
    kernels.saturate(tau, np.asarray(tau_max, dtype=np.float64), out)
    return out


class TorqueLimiter:
    """Stateful torque-rate limiter followed by saturation (``kernels.torque_limiter``).

    ``tau_max`` and ``output`` are views of ``buffer`` (layout: ``kernels.limiter_views``).

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
        self.buffer = np.zeros(kernels.limiter_size(len(config.torque_max_nm)))
        par, self.tau_max, self._last_no_gravity, self.output = kernels.limiter_views(self.buffer)
        self.tau_max[:] = config.torque_max_nm
        self.max_delta_nm = config.torque_rate_max_nm_per_s * dt_s
        par[0] = self.max_delta_nm

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
        kernels.torque_limiter(
            np.asarray(tau_no_gravity, dtype=np.float64),
            np.asarray(tau_gravity, dtype=np.float64),
            self.buffer,
        )
        return self.output
