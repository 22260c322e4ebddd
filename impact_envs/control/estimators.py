"""External-wrench estimators from joint torques: residual least squares and momentum observer.

Sign convention (libfranka ``O_F_ext_hat_K``): the returned wrench is the one the robot applies
to the environment. With the dynamics M ddq + C dq + g = tau + J^T w_ext (w_ext acting ON the
robot), the torque residual is tau_res = -J^T w_ext and the estimate is w_hat = -w_ext; a held
payload of mass m gives w_hat_z = +m g. Both estimators map tau_res to a wrench with the
regularized least squares w_hat = (J J^T + lambda^2 I)^-1 J tau_res.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numba import njit

from impact_envs.control.arm_model import ArmDynamics, dynamics_arrays
from impact_envs.control.jacobian import regularized_wrench_map
from impact_envs.control.kernel_layout import _next
from impact_envs.control.kernel_math import mat_t_vec, mat_vec
from impact_envs.control.validation import check_positive
from impact_envs.errors import check_choice

ESTIMATOR_KINDS = ("residual", "momentum")
"""Valid values of ``EstimatorConfig.kind``."""


@dataclass(frozen=True)
class EstimatorConfig:
    """External-wrench estimator.

    Attributes:
        kind: ``"residual"`` (paper: tau_meas - tau_model with a filtered acceleration) or
            ``"momentum"`` (generalized-momentum observer, De Luca / Haddadin).
        regularization: lambda of the regularized least squares w = (J J^T + lambda^2 I)^-1 J r
            [units of J] (paper: 0.02).
        momentum_gain_per_s: Observer gain K_O [1/s]; the residual is a first-order low-pass of
            the external joint torque with time constant 1/K_O (own choice: 50, i.e. 20 ms).
        lowpass_time_constant_s: Time constant of the first-order low-pass applied to the
            finite-difference acceleration and, identically, to the torque residual [s]
            (paper: 0.0495).
        include_joint_friction: Add ``dynamics.joint_friction(dq)`` to the model torque. Turn off
            when ``tau_measured`` is already link-side (friction subtracted by the sensor).
    """

    kind: str = "residual"
    regularization: float = 0.02
    momentum_gain_per_s: float = 50.0
    lowpass_time_constant_s: float = 0.0495
    include_joint_friction: bool = True

    def __post_init__(self) -> None:
        check_choice("estimator kind", self.kind, ESTIMATOR_KINDS)
        check_positive("regularization", self.regularization)
        check_positive("momentum_gain_per_s", self.momentum_gain_per_s)
        check_positive("lowpass_time_constant_s", self.lowpass_time_constant_s)


# ---------------------------------------------------------------- buffer layout and kernel
def residual_size(n: int) -> int:
    """Length of a residual-estimator buffer for ``n`` joints."""
    return 8 + 8 * n


@njit(cache=True)
def residual_views(buf):
    """(par [a, started], lp [ddq_hat; tau_lp], raw, gain, dq_prev, tau_res, wrench)."""
    n = (buf.shape[0] - 8) // 8
    par, o = _next(buf, 0, 2)
    lp, o = _next(buf, o, 2 * n)
    raw, o = _next(buf, o, 2 * n)
    gain, o = _next(buf, o, 2 * n)
    dq_prev, o = _next(buf, o, n)
    tau_res, o = _next(buf, o, n)
    wrench, o = _next(buf, o, 6)
    return par, lp, raw, gain, dq_prev, tau_res, wrench


def momentum_size(n: int) -> int:
    """Length of a momentum-observer buffer for ``n`` joints."""
    return 9 + 5 * n


@njit(cache=True)
def momentum_views(buf):
    """(par [K_O, dt, started], r, p0, integral, p, tau_res, wrench)."""
    n = (buf.shape[0] - 9) // 5
    par, o = _next(buf, 0, 3)
    r, o = _next(buf, o, n)
    p0, o = _next(buf, o, n)
    integral, o = _next(buf, o, n)
    p, o = _next(buf, o, n)
    tau_res, o = _next(buf, o, n)
    wrench, o = _next(buf, o, 6)
    return par, r, p0, integral, p, tau_res, wrench


@njit(cache=True)
def residual_update(dq, tau_meas, fric, dyn, wrench_map, buf) -> None:
    """Residual estimator tick (estimators.py::ResidualEstimator); fric = 0 when not modelled."""
    _, mass, cor, grav, _, _ = dyn
    par, lp, raw, gain, dq_prev, tau_res, wrench = residual_views(buf)
    n = dq.shape[0]
    alpha = par[0]
    for j in range(n):
        raw[j] = dq[j] - dq_prev[j] if par[1] != 0.0 else 0.0
        dq_prev[j] = dq[j]
    par[1] = 1.0
    mat_vec(cor, dq, tau_res)  # scratch: C dq
    for j in range(n):
        raw[n + j] = tau_meas[j] - grav[j] - tau_res[j] - fric[j]
    for j in range(2 * n):  # lp <- (1 - a) lp + a raw, the 1/dt of the difference in the gain
        lp[j] = lp[j] * (1.0 - alpha) + raw[j] * gain[j]
    mat_vec(mass, lp[:n], tau_res)
    for j in range(n):
        tau_res[j] = lp[n + j] - tau_res[j]
    mat_vec(wrench_map, tau_res, wrench)


@njit(cache=True)
def momentum_update(dq, tau_meas, fric, dyn, wrench_map, buf) -> None:
    """Momentum observer tick (estimators.py::MomentumObserver); fric = 0 when not modelled."""
    _, mass, cor, grav, _, _ = dyn
    par, r, p0, integral, p, tau_res, wrench = momentum_views(buf)
    gain, dt = par[0], par[1]
    n = dq.shape[0]
    mat_vec(mass, dq, p)
    if par[2] == 0.0:
        for j in range(n):
            p0[j] = p[j]
        par[2] = 1.0
    else:
        mat_t_vec(cor, dq, tau_res)  # scratch: C^T dq
        for j in range(n):
            beta = (tau_res[j] - grav[j] - fric[j] + tau_meas[j] + r[j]) * dt
            integral[j] += beta
            r[j] = (p[j] - p0[j] - integral[j]) * gain
    for j in range(n):
        tau_res[j] = -r[j]
    mat_vec(wrench_map, tau_res, wrench)


RESIDUAL, MOMENTUM = 0, 1
"""``kernel_kind`` of the two estimators (selects the kernel in ``kernels.controller_tick``)."""


class WrenchEstimator(Protocol):
    """Common interface: ``update`` once per tick after ``dynamics.update(q, dq)``."""

    wrench_world: np.ndarray
    tau_residual: np.ndarray
    kernel_kind: int
    buffer: np.ndarray

    def reset(self) -> None:
        """Forget all filter / observer state."""
        ...

    def update(
        self,
        q: np.ndarray,
        dq: np.ndarray,
        tau_meas: np.ndarray,
        dynamics: ArmDynamics,
        wrench_map: np.ndarray | None = None,
    ) -> np.ndarray:
        """Return the estimated wrench (6,) [N, Nm] (robot-on-environment, world frame)."""
        ...


def _run_kernel(
    estimator: ResidualEstimator | MomentumObserver,
    dq: np.ndarray,
    tau_meas: np.ndarray,
    dynamics: ArmDynamics,
    wrench_map: np.ndarray | None,
) -> np.ndarray:
    """Shared body of both ``update`` methods: friction, wrench map, then the stage kernel."""
    dq = np.asarray(dq, dtype=np.float64)
    cfg = estimator.config
    if cfg.include_joint_friction:
        fric = np.asarray(dynamics.joint_friction(dq), dtype=np.float64)
    else:
        fric = np.zeros_like(dq)
    if wrench_map is None:
        wrench_map = regularized_wrench_map(dynamics.jacobian, cfg.regularization)
    kernel = residual_update if estimator.kernel_kind == RESIDUAL else (
        momentum_update
    )
    kernel(dq, np.asarray(tau_meas, dtype=np.float64), fric, dynamics_arrays(dynamics),
           np.asarray(wrench_map, dtype=np.float64), estimator.buffer)
    return estimator.wrench_world


class ResidualEstimator:
    """Paper's estimator: tau_res = tau_meas - (M ddq_hat + C dq + g + tau_fric).

    ddq_hat is the backward finite difference of dq passed through a first-order low-pass with
    time constant T (zero-order-hold discretisation, per-tick gain a = 1 - exp(-dt / T)). To keep
    the residual consistent (same delay on every term) the rest of the residual,
    tau_meas - C dq - g - tau_fric, goes through the *same* filter, so
    tau_res = LP(tau_meas - C dq - g - tau_fric) - M LP(ddq_fd) ~ LP(tau_meas - tau_model)
    (exact while M varies slowly compared with T). Both filter states start at 0 after
    ``reset``, so the estimate rises from 0 with time constant T instead of spiking. The tick
    is ``residual_update``; the arrays are views of ``buffer`` (``residual_views``).

    Attributes:
        ddq_hat: Filtered joint acceleration (7,) [rad/s^2].
        tau_residual: Filtered residual tau_res (7,) [Nm].
        wrench_world: Last estimate (6,) [N, Nm].
    """

    kernel_kind = RESIDUAL

    def __init__(self, config: EstimatorConfig, dt_s: float, n_joints: int = 7) -> None:
        """Create the estimator for control period ``dt_s`` [s]."""
        self.config = config
        self.dt_s = dt_s
        self.alpha = 1.0 - math.exp(-dt_s / config.lowpass_time_constant_s)
        n = n_joints
        self.buffer = np.zeros(residual_size(n))
        # Both filters run on one stacked vector [ddq (n); tau_meas - C dq - g - tau_fric (n)].
        (self._par, self._lp, _, gain, _, self.tau_residual, self.wrench_world) = (
            residual_views(self.buffer)
        )
        self._par[0] = self.alpha
        gain[:n], gain[n:] = self.alpha / dt_s, self.alpha
        self.ddq_hat = self._lp[:n]

    def reset(self) -> None:
        """Zero both filters and forget the previous velocity."""
        self._lp.fill(0.0)
        self.tau_residual.fill(0.0)
        self.wrench_world.fill(0.0)
        self._par[1] = 0.0  # started

    def update(
        self,
        q: np.ndarray,
        dq: np.ndarray,
        tau_meas: np.ndarray,
        dynamics: ArmDynamics,
        wrench_map: np.ndarray | None = None,
    ) -> np.ndarray:
        """Advance one tick and return the wrench estimate (6,) [N, Nm].

        Args:
            q: Joint positions (7,) [rad] (unused; the model is already updated).
            dq: Joint velocities (7,) [rad/s].
            tau_meas: Measured joint torques (7,) [Nm].
            dynamics: Model already updated at (q, dq).
            wrench_map: Optional precomputed (J J^T + lambda^2 I)^-1 J (6, 7).
        """
        return _run_kernel(self, dq, tau_meas, dynamics, wrench_map)


class MomentumObserver:
    """Generalized-momentum observer (De Luca & Mattone 2005; Haddadin et al. 2017).

    p = M dq; r_k = K_O (p_k - p_0 - S_k), S_k = S_{k-1} + dt (tau_meas + C^T dq - g - tau_fric
    + r_{k-1}). Then r -> tau_ext (on the robot) with per-tick dynamics
    r_k = r_{k-1} + K_O dt (tau_ext - r_{k-1}), i.e. a first-order low-pass with time constant
    1 / K_O. No acceleration, no M^-1. tau_res = -r gives the libfranka sign. The tick is
    ``momentum_update``; the arrays are views of ``buffer`` (``momentum_views``).

    Attributes:
        r: Observer residual (estimate of tau_ext ON the robot) (7,) [Nm].
        tau_residual: -r (7,) [Nm], same convention as ``ResidualEstimator``.
        wrench_world: Last estimate (6,) [N, Nm].
    """

    kernel_kind = MOMENTUM

    def __init__(self, config: EstimatorConfig, dt_s: float, n_joints: int = 7) -> None:
        """Create the observer for control period ``dt_s`` [s]."""
        self.config = config
        self.dt_s = dt_s
        self.gain = config.momentum_gain_per_s
        self.buffer = np.zeros(momentum_size(n_joints))
        (self._par, self.r, _, self._sum, _, self.tau_residual, self.wrench_world) = (
            momentum_views(self.buffer)
        )
        self._par[:2] = self.gain, dt_s

    def reset(self) -> None:
        """Forget p_0, the integral and the residual."""
        self.r.fill(0.0)
        self._sum.fill(0.0)
        self.tau_residual.fill(0.0)
        self.wrench_world.fill(0.0)
        self._par[2] = 0.0  # started

    def update(
        self,
        q: np.ndarray,
        dq: np.ndarray,
        tau_meas: np.ndarray,
        dynamics: ArmDynamics,
        wrench_map: np.ndarray | None = None,
    ) -> np.ndarray:
        """Advance one tick and return the wrench estimate (6,) [N, Nm] (see ResidualEstimator)."""
        return _run_kernel(self, dq, tau_meas, dynamics, wrench_map)


def make_estimator(config: EstimatorConfig, dt_s: float, n_joints: int = 7) -> WrenchEstimator:
    """Build the estimator named by ``config.kind``."""
    if config.kind == "momentum":
        return MomentumObserver(config, dt_s, n_joints)
    return ResidualEstimator(config, dt_s, n_joints)
