"""Frozen configuration dataclasses of the controller core, with the ``default`` preset.

``impact_envs.control.presets.preset_config("paper")`` gives the paper-literal table; the
fields where the two differ are listed in ``presets.DEPARTURES``.

Every field names its unit; wrenches and Cartesian gains are ordered (force/translation x, y, z;
torque/rotation x, y, z) in the world (= robot base) frame. Sources of the defaults are listed
in docs/controller.md ("paper" = hyper-parameter table of the IMPACT appendix).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from impact_envs.errors import InvalidArgumentError, check_choice

ESTIMATOR_KINDS = ("residual", "momentum")
"""Valid values of ``EstimatorConfig.kind``."""


def _check_positive(name: str, values: float | tuple[float, ...], allow_zero: bool = False) -> None:
    """Raise ``InvalidArgumentError`` unless every value is finite and > 0 (or >= 0)."""
    seq = values if isinstance(values, tuple) else (values,)
    for v in seq:
        ok = math.isfinite(v) and (v >= 0.0 if allow_zero else v > 0.0)
        if not ok:
            bound = ">= 0" if allow_zero else "> 0"
            raise InvalidArgumentError(f"invalid {name} {values!r}; valid: finite values {bound}")


def _check_len(name: str, values: tuple[float, ...], n: int) -> None:
    if len(values) != n:
        raise InvalidArgumentError(f"invalid {name} {values!r}; valid: a tuple of {n} floats")


@dataclass(frozen=True)
class ImpedanceConfig:
    """Task-space impedance, null-space posture and model compensation terms.

    Attributes:
        stiffness_translational_n_per_m: Diagonal of K for position error [N/m] (paper: 400).
        stiffness_rotational_nm_per_rad: Diagonal of K for orientation error [Nm/rad] (paper: 30).
        damping_translational_ns_per_m: Diagonal of D for TCP linear velocity [N s/m] (paper: 40).
        damping_rotational_nms_per_rad: Diagonal of D for TCP angular velocity [Nm s/rad]
            (paper: 10.95 = 2 sqrt(30)).
        nullspace_stiffness_nm_per_rad: Joint stiffness k_n toward the posture q_null that
            ``reset`` records [Nm/rad] (own choice: 10).
        nullspace_damping_nms_per_rad: Joint damping d_n of the posture task [Nm s/rad];
            ``None`` means 2 sqrt(k_n) (Franka example convention).
        nullspace_pinv_damping: Damping of the pseudo-inverse in N = I - J^T (J^+)^T
            [units of J]. Equal to the estimator's lambda by default so one regularized solve
            per tick serves both.
        compensate_gravity: Add g(q) of the controller model (the simulation has none built in).
        compensate_coriolis: Add C(q, dq) dq (as the Franka example does).
    """

    stiffness_translational_n_per_m: tuple[float, float, float] = (400.0, 400.0, 400.0)
    stiffness_rotational_nm_per_rad: tuple[float, float, float] = (30.0, 30.0, 30.0)
    damping_translational_ns_per_m: tuple[float, float, float] = (40.0, 40.0, 40.0)
    damping_rotational_nms_per_rad: tuple[float, float, float] = (10.95, 10.95, 10.95)
    nullspace_stiffness_nm_per_rad: float = 10.0
    nullspace_damping_nms_per_rad: float | None = None
    nullspace_pinv_damping: float = 0.02
    compensate_gravity: bool = True
    compensate_coriolis: bool = True

    def __post_init__(self) -> None:
        for name in (
            "stiffness_translational_n_per_m",
            "stiffness_rotational_nm_per_rad",
            "damping_translational_ns_per_m",
            "damping_rotational_nms_per_rad",
        ):
            values = tuple(float(v) for v in getattr(self, name))
            _check_len(name, values, 3)
            _check_positive(name, values, allow_zero=True)
            object.__setattr__(self, name, values)
        k_n, d_n = self.nullspace_stiffness_nm_per_rad, self.nullspace_damping_nms_per_rad
        _check_positive("nullspace_stiffness_nm_per_rad", k_n, allow_zero=True)
        if d_n is not None:
            _check_positive("nullspace_damping_nms_per_rad", d_n, allow_zero=True)
        _check_positive("nullspace_pinv_damping", self.nullspace_pinv_damping)

    @property
    def nullspace_damping(self) -> float:
        """Resolved null-space damping d_n [Nm s/rad] (2 sqrt(k_n) when unset)."""
        if self.nullspace_damping_nms_per_rad is None:
            return 2.0 * math.sqrt(self.nullspace_stiffness_nm_per_rad)
        return self.nullspace_damping_nms_per_rad


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
        _check_positive("regularization", self.regularization)
        _check_positive("momentum_gain_per_s", self.momentum_gain_per_s)
        _check_positive("lowpass_time_constant_s", self.lowpass_time_constant_s)


@dataclass(frozen=True)
class SlowWrenchConfig:
    """Clipped first-order filter producing w_slow, the internal model's training target.

    Attributes:
        rate_force_per_s: eta of the force axes [1/s]; per-tick gain eta * dt (default 20,
            a 50 ms time constant; paper: 2.0, docs/controller.md "Presets").
        rate_torque_per_s: eta of the torque axes [1/s] (paper: 1.0).
        clip_force_n: Per-axis clip of (w_ext - w_slow) on force axes [N] (paper: 10).
        clip_torque_nm: Per-axis clip on torque axes [Nm] (paper: 1).
    """

    rate_force_per_s: float = 20.0
    rate_torque_per_s: float = 1.0
    clip_force_n: float = 10.0
    clip_torque_nm: float = 1.0

    def __post_init__(self) -> None:
        _check_positive("rate_force_per_s", self.rate_force_per_s)
        _check_positive("rate_torque_per_s", self.rate_torque_per_s)
        _check_positive("clip_force_n", self.clip_force_n)
        _check_positive("clip_torque_nm", self.clip_torque_nm)

    @property
    def max_force_slew_n_per_s(self) -> float:
        """Largest per-axis force rate of w_slow, eta_f * clip_f [N/s] (default 200, paper 20)."""
        return self.rate_force_per_s * self.clip_force_n


@dataclass(frozen=True)
class InternalModelConfig:
    """Internal model network, online learner, surprise gate and replay buffer.

    Attributes:
        history_length: Ticks L of per-tick features fed to the network (paper: 32).
        hidden_sizes: Widths of the tanh hidden layers (own choice: (64, 64)).
        learning_rate: Plain SGD step size on the normalized MSE (default 0.1; paper: 0.01).
        surprise_open_n: Gate opens when the force surprise reaches this value [N] (default
            2.5, 4.5x the largest excursion of the simulated estimator's force noise at
            rest, docs/controller.md "Presets"; paper: 5).
        surprise_release_n: Open gate closes when the force surprise falls below this [N]
            (own choice 0.5; equal to ``surprise_open_n`` gives the literal single threshold).
        slow_rate_max: Learning only while the slow-wrench rate (|dw_slow/dt|_force divided by
            eta_f * clip_f, dimensionless) is at most this (default 1.5: pauses only while
            w_slow slews on several force axes at once; paper: 0.2).
        update_every: Ticks between SGD steps while learning (own choice: 5).
        batch_size: Samples per SGD step: the current one plus replayed ones (own choice: 16).
        replay_capacity: FIFO capacity of the replay buffer [samples] (own choice: 256).
        replay_period: Ticks between stored quasi-steady samples (own choice: 10, i.e. 10 ms).
        seed: Seed of the weight initialisation and of replay sampling.
        wrench_feature: Feed the estimated wrench to the network (default True, as both
            presets). False zeroes those six inputs, so the model predicts from the robot's
            state (joints, gripper, TCP position) alone; an experiment, docs/results.md §1.
    """

    history_length: int = 32
    hidden_sizes: tuple[int, ...] = (64, 64)
    learning_rate: float = 0.1
    surprise_open_n: float = 2.5
    surprise_release_n: float = 0.5
    slow_rate_max: float = 1.5
    update_every: int = 5
    batch_size: int = 16
    replay_capacity: int = 256
    replay_period: int = 10
    seed: int = 0
    wrench_feature: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "hidden_sizes", tuple(int(h) for h in self.hidden_sizes))
        for name in ("history_length", "update_every", "batch_size", "replay_capacity"):
            if int(getattr(self, name)) < 1:
                raise InvalidArgumentError(f"invalid {name} {getattr(self, name)!r}; valid: >= 1")
        if self.replay_period < 1:
            raise InvalidArgumentError(f"invalid replay_period {self.replay_period!r}; valid: >= 1")
        if not self.hidden_sizes or min(self.hidden_sizes) < 1:
            raise InvalidArgumentError(
                f"invalid hidden_sizes {self.hidden_sizes!r}; valid: non-empty, all >= 1"
            )
        _check_positive("learning_rate", self.learning_rate)
        _check_positive("surprise_open_n", self.surprise_open_n)
        _check_positive("surprise_release_n", self.surprise_release_n, allow_zero=True)
        _check_positive("slow_rate_max", self.slow_rate_max)
        if self.surprise_release_n > self.surprise_open_n:
            raise InvalidArgumentError(
                f"invalid surprise_release_n {self.surprise_release_n!r}; "
                f"valid: 0 <= release <= surprise_open_n ({self.surprise_open_n})"
            )


@dataclass(frozen=True)
class LimitsConfig:
    """Torque saturation and torque-rate limits (FR3 / libfranka).

    Attributes:
        torque_max_nm: Symmetric per-joint torque bound [Nm] (FR3: 87 x4, 12 x3).
        torque_rate_max_nm_per_s: Bound on |d tau / dt| [Nm/s] (libfranka: 1000, i.e. 1 Nm/tick).
    """

    torque_max_nm: tuple[float, ...] = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
    torque_rate_max_nm_per_s: float = 1000.0

    def __post_init__(self) -> None:
        values = tuple(float(v) for v in self.torque_max_nm)
        _check_len("torque_max_nm", values, 7)
        _check_positive("torque_max_nm", values)
        object.__setattr__(self, "torque_max_nm", values)
        _check_positive("torque_rate_max_nm_per_s", self.torque_rate_max_nm_per_s)


def beyond_hardware_limits(limits: LimitsConfig) -> list[str]:
    """The settings of ``limits`` above the FR3's hardware limits (empty when within)."""
    fr3 = LimitsConfig()
    above = [f"limits.torque_max_nm[{i}]={v:g} > {hw:g} Nm"
             for i, (v, hw) in enumerate(zip(limits.torque_max_nm, fr3.torque_max_nm,
                                             strict=True)) if v > hw]
    if limits.torque_rate_max_nm_per_s > fr3.torque_rate_max_nm_per_s:
        above.append(f"limits.torque_rate_max_nm_per_s={limits.torque_rate_max_nm_per_s:g} > "
                     f"{fr3.torque_rate_max_nm_per_s:g} Nm/s")
    return above


@dataclass(frozen=True)
class ControllerConfig:
    """Top-level controller configuration.

    Attributes:
        dt_s: Control period [s] (paper: 1 kHz).
        impedance: Impedance law settings.
        estimator: External-wrench estimator settings.
        slow_wrench: Slow-wrench filter settings.
        internal_model: Internal model / online learning settings.
        limits: Torque and torque-rate limits.
    """

    dt_s: float = 0.001
    impedance: ImpedanceConfig = field(default_factory=ImpedanceConfig)
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    slow_wrench: SlowWrenchConfig = field(default_factory=SlowWrenchConfig)
    internal_model: InternalModelConfig = field(default_factory=InternalModelConfig)
    limits: LimitsConfig = field(default_factory=LimitsConfig)

    def __post_init__(self) -> None:
        _check_positive("dt_s", self.dt_s)
        fastest = max(
            self.slow_wrench.rate_force_per_s,
            self.slow_wrench.rate_torque_per_s,
            self.estimator.momentum_gain_per_s,
        )
        if fastest * self.dt_s >= 1.0:
            raise InvalidArgumentError(
                f"invalid dt_s {self.dt_s!r}; valid: dt_s * max(eta, K_O) < 1 (max rate {fastest})"
            )
