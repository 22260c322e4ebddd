"""External-wrench estimators from joint torques: residual least squares and momentum observer.

Sign convention (libfranka ``O_F_ext_hat_K``): the returned wrench is the one the robot applies
to the environment. With the dynamics M ddq + C dq + g = tau + J^T w_ext (w_ext acting ON the
robot), the torque residual is tau_res = -J^T w_ext and the estimate is w_hat = -w_ext; a held
payload of mass m gives w_hat_z = +m g. Both estimators map tau_res to a wrench with the
regularized least squares w_hat = (J J^T + lambda^2 I)^-1 J tau_res.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from impact_envs.control import kernels
from impact_envs.control.arm_model import ArmDynamics, dynamics_arrays
from impact_envs.control.config import EstimatorConfig
from impact_envs.control.jacobian import regularized_wrench_map

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
    kernel = kernels.residual_update if estimator.kernel_kind == RESIDUAL else (
        kernels.momentum_update
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
    is ``kernels.residual_update``; the arrays are views of ``buffer`` (``residual_views``).

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
        self.buffer = np.zeros(kernels.residual_size(n))
        # Both filters run on one stacked vector [ddq (n); tau_meas - C dq - g - tau_fric (n)].
        (self._par, self._lp, _, gain, _, self.tau_residual, self.wrench_world) = (
            kernels.residual_views(self.buffer)
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
    ``kernels.momentum_update``; the arrays are views of ``buffer`` (``momentum_views``).

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
        self.buffer = np.zeros(kernels.momentum_size(n_joints))
        (self._par, self.r, _, self._sum, _, self.tau_residual, self.wrench_world) = (
            kernels.momentum_views(self.buffer)
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
