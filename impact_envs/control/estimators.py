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

from impact_envs.control.config import EstimatorConfig
from impact_envs.control.jacobian import regularized_wrench_map
from impact_envs.control.protocols import ArmDynamics


class WrenchEstimator(Protocol):
    """Common interface: ``update`` once per tick after ``dynamics.update(q, dq)``."""

    wrench_world: np.ndarray
    tau_residual: np.ndarray

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


def _bias_torque(
    dq: np.ndarray, dynamics: ArmDynamics, with_friction: bool, coriolis_transposed: bool
) -> np.ndarray:
    """Return h = C dq + g + tau_fric, or (``coriolis_transposed``) C^T dq - g - tau_fric [Nm]."""
    if coriolis_transposed:
        h = dq @ dynamics.coriolis_matrix  # C^T dq
        h -= dynamics.gravity
        if with_friction:
            h -= dynamics.joint_friction(dq)
        return h
    h = dynamics.coriolis_matrix @ dq
    h += dynamics.gravity
    if with_friction:
        h += dynamics.joint_friction(dq)
    return h


class ResidualEstimator:
    """Paper's estimator: tau_res = tau_meas - (M ddq_hat + C dq + g + tau_fric).

    ddq_hat is the backward finite difference of dq passed through a first-order low-pass with
    time constant T (zero-order-hold discretisation, per-tick gain a = 1 - exp(-dt / T)). To keep
    the residual consistent (same delay on every term) the rest of the residual,
    tau_meas - C dq - g - tau_fric, goes through the *same* filter, so
    tau_res = LP(tau_meas - C dq - g - tau_fric) - M LP(ddq_fd) ~ LP(tau_meas - tau_model)
    (exact while M varies slowly compared with T). Both filter states start at 0 after
    ``reset``, so the estimate rises from 0 with time constant T instead of spiking.

    Attributes:
        ddq_hat: Filtered joint acceleration (7,) [rad/s^2].
        tau_residual: Filtered residual tau_res (7,) [Nm].
        wrench_world: Last estimate (6,) [N, Nm].
    """

    def __init__(self, config: EstimatorConfig, dt_s: float, n_joints: int = 7) -> None:
        """Create the estimator for control period ``dt_s`` [s]."""
        self.config = config
        self.dt_s = dt_s
        self.alpha = 1.0 - math.exp(-dt_s / config.lowpass_time_constant_s)
        n = n_joints
        # Both filters run on one stacked vector [ddq (n); tau_meas - C dq - g - tau_fric (n)].
        self._lp = np.zeros(2 * n)
        self._raw = np.zeros(2 * n)
        self._gain = np.concatenate([np.full(n, self.alpha / dt_s), np.full(n, self.alpha)])
        self.ddq_hat = self._lp[:n]
        self._tau_lp = self._lp[n:]
        self._raw_dq, self._raw_tau = self._raw[:n], self._raw[n:]
        self.tau_residual = np.zeros(n)
        self.wrench_world = np.zeros(6)
        self._dq_prev = np.zeros(n)
        self._tmp = np.zeros(n)
        self._started = False

    def reset(self) -> None:
        """Zero both filters and forget the previous velocity."""
        self._lp.fill(0.0)
        self.tau_residual.fill(0.0)
        self.wrench_world.fill(0.0)
        self._started = False

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
        if self._started:
            np.subtract(dq, self._dq_prev, out=self._raw_dq)  # dt * finite-difference ddq
        else:
            self._raw_dq.fill(0.0)
            self._started = True
        self._dq_prev[:] = dq
        raw_tau, tmp = self._raw_tau, self._tmp
        np.subtract(tau_meas, dynamics.gravity, out=raw_tau)
        np.dot(dynamics.coriolis_matrix, dq, out=tmp)
        raw_tau -= tmp
        if self.config.include_joint_friction:
            raw_tau -= dynamics.joint_friction(dq)
        # lp <- (1 - a) lp + a raw  (the 1/dt of the finite difference is folded into the gain)
        self._lp *= 1.0 - self.alpha
        self._raw *= self._gain
        self._lp += self._raw
        np.dot(dynamics.mass_matrix, self.ddq_hat, out=tmp)
        np.subtract(self._tau_lp, tmp, out=self.tau_residual)
        if wrench_map is None:
            wrench_map = regularized_wrench_map(dynamics.jacobian, self.config.regularization)
        np.dot(wrench_map, self.tau_residual, out=self.wrench_world)
        return self.wrench_world


class MomentumObserver:
    """Generalized-momentum observer (De Luca & Mattone 2005; Haddadin et al. 2017).

    p = M dq; r_k = K_O (p_k - p_0 - S_k), S_k = S_{k-1} + dt (tau_meas + C^T dq - g - tau_fric
    + r_{k-1}). Then r -> tau_ext (on the robot) with per-tick dynamics
    r_k = r_{k-1} + K_O dt (tau_ext - r_{k-1}), i.e. a first-order low-pass with time constant
    1 / K_O. No acceleration, no M^-1. tau_res = -r gives the libfranka sign.

    Attributes:
        r: Observer residual (estimate of tau_ext ON the robot) (7,) [Nm].
        tau_residual: -r (7,) [Nm], same convention as ``ResidualEstimator``.
        wrench_world: Last estimate (6,) [N, Nm].
    """

    def __init__(self, config: EstimatorConfig, dt_s: float, n_joints: int = 7) -> None:
        """Create the observer for control period ``dt_s`` [s]."""
        self.config = config
        self.dt_s = dt_s
        self.gain = config.momentum_gain_per_s
        self.r = np.zeros(n_joints)
        self.tau_residual = np.zeros(n_joints)
        self.wrench_world = np.zeros(6)
        self._p0 = np.zeros(n_joints)
        self._sum = np.zeros(n_joints)
        self._p = np.zeros(n_joints)
        self._started = False

    def reset(self) -> None:
        """Forget p_0, the integral and the residual."""
        self.r.fill(0.0)
        self._sum.fill(0.0)
        self.tau_residual.fill(0.0)
        self.wrench_world.fill(0.0)
        self._started = False

    def update(
        self,
        q: np.ndarray,
        dq: np.ndarray,
        tau_meas: np.ndarray,
        dynamics: ArmDynamics,
        wrench_map: np.ndarray | None = None,
    ) -> np.ndarray:
        """Advance one tick and return the wrench estimate (6,) [N, Nm] (see ResidualEstimator)."""
        np.dot(dynamics.mass_matrix, dq, out=self._p)
        if not self._started:
            self._p0[:] = self._p
            self._started = True
        else:
            beta = _bias_torque(dq, dynamics, self.config.include_joint_friction, True)
            beta += tau_meas
            beta += self.r
            beta *= self.dt_s
            self._sum += beta
            np.subtract(self._p, self._p0, out=self.r)
            self.r -= self._sum
            self.r *= self.gain
        np.negative(self.r, out=self.tau_residual)
        if wrench_map is None:
            wrench_map = regularized_wrench_map(dynamics.jacobian, self.config.regularization)
        np.dot(wrench_map, self.tau_residual, out=self.wrench_world)
        return self.wrench_world


def make_estimator(config: EstimatorConfig, dt_s: float, n_joints: int = 7) -> WrenchEstimator:
    """Build the estimator named by ``config.kind``."""
    if config.kind == "momentum":
        return MomentumObserver(config, dt_s, n_joints)
    return ResidualEstimator(config, dt_s, n_joints)
