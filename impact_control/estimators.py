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
from typing import NamedTuple, Protocol

import numpy as np
from numba import njit

from impact_control.arm_model import ArmDynamics, dynamics_arrays
from impact_control.errors import check_choice
from impact_control.jacobian import regularized_wrench_map
from impact_control.kernel_layout import Packed
from impact_control.kernel_math import mat_t_vec, mat_vec
from impact_control.stage_layout import Dim, Layout
from impact_control.validation import check_positive

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


# ------------------------------------------------------------------ named state and kernels
class ResidualState(NamedTuple):
    """Everything ``residual_update`` reads and writes (n joints).

    Attributes:
        alpha: Per-tick low-pass gain a = 1 - exp(-dt / T).
        gain: (2n,) per-row input gain: a / dt on the acceleration rows (the 1/dt of the
            velocity difference), a on the torque rows.
        started: (1,) 1 once a previous velocity exists.
        lowpass: (2n,) [ddq_hat (n) [rad/s^2]; LP(tau_meas - C dq - g - tau_fric) (n) [Nm]].
        raw: (2n,) this tick's filter inputs (before the gains).
        dq_prev: (n,) the previous velocity [rad/s].
        tau_residual: (n,) filtered residual tau_res [Nm].
        wrench: (6,) the estimate [N, Nm], world frame.
    """

    alpha: float
    gain: np.ndarray
    started: np.ndarray
    lowpass: np.ndarray
    raw: np.ndarray
    dq_prev: np.ndarray
    tau_residual: np.ndarray
    wrench: np.ndarray


class MomentumState(NamedTuple):
    """Everything ``momentum_update`` reads and writes (n joints).

    Attributes:
        gain_per_s: Observer gain K_O [1/s].
        dt_s: Control period [s].
        started: (1,) 1 once p_0 is recorded.
        r: (n,) observer residual (tau_ext on the robot) [Nm].
        p0: (n,) momentum at the start [kg m^2/s].
        integral: (n,) S_k [Nm s].
        p: (n,) this tick's momentum M dq.
        tau_residual: (n,) -r [Nm].
        wrench: (6,) the estimate [N, Nm], world frame.
    """

    gain_per_s: float
    dt_s: float
    started: np.ndarray
    r: np.ndarray
    p0: np.ndarray
    integral: np.ndarray
    p: np.ndarray
    tau_residual: np.ndarray
    wrench: np.ndarray


@njit(cache=True, inline="always")
def residual_update(dq, tau_meas, fric, dyn, wrench_map, st) -> None:
    """Residual estimator tick (estimators.py::ResidualEstimator); fric = 0 when not modelled."""
    _, mass, cor, grav, _, _ = dyn
    lp, raw, gain, dq_prev, tau_res = st.lowpass, st.raw, st.gain, st.dq_prev, st.tau_residual
    n = dq.shape[0]
    alpha = st.alpha
    for j in range(n):
        raw[j] = dq[j] - dq_prev[j] if st.started[0] != 0.0 else 0.0
        dq_prev[j] = dq[j]
    st.started[0] = 1.0
    mat_vec(cor, dq, tau_res)  # scratch: C dq
    for j in range(n):
        raw[n + j] = tau_meas[j] - grav[j] - tau_res[j] - fric[j]
    for j in range(2 * n):  # lp <- (1 - a) lp + a raw, the 1/dt of the difference in the gain
        lp[j] = lp[j] * (1.0 - alpha) + raw[j] * gain[j]
    mat_vec(mass, lp[:n], tau_res)
    for j in range(n):
        tau_res[j] = lp[n + j] - tau_res[j]
    mat_vec(wrench_map, tau_res, st.wrench)


@njit(cache=True, inline="always")
def momentum_update(dq, tau_meas, fric, dyn, wrench_map, st) -> None:
    """Momentum observer tick (estimators.py::MomentumObserver); fric = 0 when not modelled."""
    _, mass, cor, grav, _, _ = dyn
    r, p0, integral, p, tau_res = st.r, st.p0, st.integral, st.p, st.tau_residual
    gain, dt = st.gain_per_s, st.dt_s
    n = dq.shape[0]
    mat_vec(mass, dq, p)
    if st.started[0] == 0.0:
        for j in range(n):
            p0[j] = p[j]
        st.started[0] = 1.0
    else:
        mat_t_vec(cor, dq, tau_res)  # scratch: C^T dq
        for j in range(n):
            beta = (tau_res[j] - grav[j] - fric[j] + tau_meas[j] + r[j]) * dt
            integral[j] += beta
            r[j] = (p[j] - p0[j] - integral[j]) * gain
    for j in range(n):
        tau_res[j] = -r[j]
    mat_vec(wrench_map, tau_res, st.wrench)


class EstimatorState(NamedTuple):
    """The estimator stage of ``kernels.ControllerState``: ``momentum`` says which of the
    two states runs (the other has no joints: one kernel type either way)."""

    momentum: bool
    residual: ResidualState
    observer: MomentumState


class EstimatorScalars(NamedTuple):
    """The scalar parameters of both estimators and their joint counts (one is 0)."""

    momentum: bool
    alpha: float
    gain_per_s: float
    dt_s: float
    n_residual: int
    n_observer: int


_N_RES, _N_OBS = Dim.named("n_res"), Dim.named("n_obs")
ESTIMATOR_LAYOUT = Layout.of(EstimatorState, dict(
    residual=Layout.of(ResidualState, dict(
        gain=2 * _N_RES, started=1, lowpass=2 * _N_RES, raw=2 * _N_RES, dq_prev=_N_RES,
        tau_residual=_N_RES, wrench=6)),
    observer=Layout.of(MomentumState, dict(
        started=1, r=_N_OBS, p0=_N_OBS, integral=_N_OBS, p=_N_OBS, tau_residual=_N_OBS,
        wrench=6))), dims={"n_res": "sc.n_residual", "n_obs": "sc.n_observer"})
"""Both estimators' buffer (the one not running has no joints)."""
unpack_estimator = ESTIMATOR_LAYOUT.unpacker("unpack_estimator", __name__)


def make_estimator_state(config: EstimatorConfig, dt_s: float, n_joints: int,
                         momentum: bool) -> Packed:
    """The residual estimator's (``momentum`` False) or the momentum observer's state for
    ``config`` at period ``dt_s`` [s], packed (``unpack_estimator`` names it)."""
    alpha = 1.0 - math.exp(-dt_s / config.lowpass_time_constant_s)
    sc = EstimatorScalars(momentum, alpha, float(config.momentum_gain_per_s), float(dt_s),
                          0 if momentum else n_joints, n_joints if momentum else 0)
    packed = Packed(sc, np.zeros(ESTIMATOR_LAYOUT.size_for(sc)))
    gain = unpack_estimator(packed.buffer, sc)[0].residual.gain
    gain[:sc.n_residual], gain[sc.n_residual:] = alpha / dt_s, alpha
    return packed


class WrenchEstimator(Protocol):
    """Common interface: ``update`` once per tick after ``dynamics.update(q, dq)``."""

    wrench_world: np.ndarray
    tau_residual: np.ndarray

    def kernel_state(self) -> Packed:
        """This estimator as ``kernels.controller_tick`` takes it (``unpack_estimator``)."""
        ...

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
    args = (dq, np.asarray(tau_meas, dtype=np.float64), fric, dynamics_arrays(dynamics),
            np.asarray(wrench_map, dtype=np.float64), estimator.state)
    if isinstance(estimator, MomentumObserver):
        momentum_update(*args)
    else:
        residual_update(*args)
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
    is ``residual_update`` on ``state`` (``ResidualState``, packed: ``unpack_estimator``).

    Attributes:
        ddq_hat: Filtered joint acceleration (7,) [rad/s^2].
        tau_residual: Filtered residual tau_res (7,) [Nm].
        wrench_world: Last estimate (6,) [N, Nm].
    """

    def __init__(self, config: EstimatorConfig, dt_s: float, n_joints: int = 7) -> None:
        """Create the estimator for control period ``dt_s`` [s]."""
        self.config = config
        self.dt_s = dt_s
        self.packed = make_estimator_state(config, dt_s, n_joints, momentum=False)
        self.state = st = unpack_estimator(self.packed.buffer, self.packed.scalars)[0].residual
        self.alpha = st.alpha
        self.tau_residual, self.wrench_world = st.tau_residual, st.wrench
        self.ddq_hat = st.lowpass[:n_joints]

    def kernel_state(self) -> Packed:
        """This estimator as ``kernels.controller_tick`` takes it (``unpack_estimator``)."""
        return self.packed

    def reset(self) -> None:
        """Zero both filters and forget the previous velocity."""
        self.state.lowpass.fill(0.0)
        self.tau_residual.fill(0.0)
        self.wrench_world.fill(0.0)
        self.state.started[0] = 0.0

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
    ``momentum_update`` on ``state`` (``MomentumState``).

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
        self.packed = make_estimator_state(config, dt_s, n_joints, momentum=True)
        self.state = st = unpack_estimator(self.packed.buffer, self.packed.scalars)[0].observer
        self.r, self.tau_residual, self.wrench_world = st.r, st.tau_residual, st.wrench

    def kernel_state(self) -> Packed:
        """This observer as ``kernels.controller_tick`` takes it (``unpack_estimator``)."""
        return self.packed

    def reset(self) -> None:
        """Forget p_0, the integral and the residual."""
        for name in ("r", "integral", "tau_residual", "wrench", "started"):
            getattr(self.state, name).fill(0.0)

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
