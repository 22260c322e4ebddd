"""The controller's configuration: ``ControllerConfig`` gathers the frozen config of each stage,
defined in the stage's own module (``ImpedanceConfig`` in impedance.py, ``EstimatorConfig`` in
estimators.py, ``SlowWrenchConfig`` in slow_filter.py, ``InternalModelConfig`` in
internal_model/config.py, ``LimitsConfig`` in limits.py) and re-exported here. The defaults are
the ``default`` preset.

``impact_control.presets.preset_config("paper")`` gives the paper-literal table; the
fields where the two differ are listed in ``presets.DEPARTURES``.

Every field names its unit; wrenches and Cartesian gains are ordered (force/translation x, y, z;
torque/rotation x, y, z) in the world (= robot base) frame. Sources of the defaults are listed
in docs/controller.md ("paper" = hyper-parameter table of the IMPACT appendix).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from impact_control.contact_guard import ContactGuardConfig
from impact_control.errors import InvalidArgumentError
from impact_control.estimators import ESTIMATOR_KINDS, EstimatorConfig
from impact_control.impedance import ImpedanceConfig
from impact_control.internal_model.config import InternalModelConfig
from impact_control.joint_limits import JointLimitConfig
from impact_control.limits import (
    LIBFRANKA_DELTA_T_S,
    LimitsConfig,
    beyond_hardware_limits,
    libfranka_limits,
)
from impact_control.payload_model import PayloadModelConfig
from impact_control.saturation_release import SaturationReleaseConfig
from impact_control.slow_filter import SlowWrenchConfig
from impact_control.target_filter import TargetFilterConfig
from impact_control.validation import check_positive
from impact_control.wrench_observer import WrenchObserverConfig

__all__ = ["ESTIMATOR_KINDS", "ContactGuardConfig", "ControllerConfig", "EstimatorConfig",
           "ImpedanceConfig", "InternalModelConfig", "JointLimitConfig", "LimitsConfig",
           "PayloadModelConfig", "SaturationReleaseConfig", "SlowWrenchConfig",
           "TargetFilterConfig", "WrenchObserverConfig", "beyond_hardware_limits",
           "libfranka_limits"]


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
        guard: Contact guard and bounds on the feedforward wrench (``contact_guard.py``).
        target_filter: EMA of the target pose (``target_filter.py``; off but in the
            authors' presets, as are the three below: ``optional_stages.py``).
        observer: Wrench observer with the low-pass after the solve, replacing the estimator
            when enabled (``wrench_observer.py``).
        payload: Scalar payload model along TCP z, whose output is then the feedforward
            instead of the internal model's (``payload_model.py``).
        joint_limits: Joint-limit repulsion (``joint_limits.py``).
        saturation_release: Saturated-lift release: the feedforward scaled down while a
            joint stays at its torque bound and the lift does not rise
            (``saturation_release.py``; on in ``default``, issue 37 item 5).
    """

    dt_s: float = 0.001
    impedance: ImpedanceConfig = field(default_factory=ImpedanceConfig)
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    slow_wrench: SlowWrenchConfig = field(default_factory=SlowWrenchConfig)
    internal_model: InternalModelConfig = field(default_factory=InternalModelConfig)
    limits: LimitsConfig = field(default_factory=LimitsConfig)
    guard: ContactGuardConfig = field(default_factory=ContactGuardConfig)
    target_filter: TargetFilterConfig = field(default_factory=TargetFilterConfig)
    observer: WrenchObserverConfig = field(default_factory=WrenchObserverConfig)
    payload: PayloadModelConfig = field(default_factory=PayloadModelConfig)
    joint_limits: JointLimitConfig = field(default_factory=JointLimitConfig)
    saturation_release: SaturationReleaseConfig = field(
        default_factory=SaturationReleaseConfig)

    def __post_init__(self) -> None:
        check_positive("dt_s", self.dt_s)
        fastest = max(
            self.slow_wrench.rate_force_per_s,
            self.slow_wrench.rate_torque_per_s,
            self.estimator.momentum_gain_per_s,
        )
        if fastest * self.dt_s >= 1.0:
            raise InvalidArgumentError(
                f"invalid dt_s {self.dt_s!r}; valid: dt_s * max(eta, K_O) < 1 (max rate {fastest})"
            )
        if self.observer.enabled and self.estimator.kind != "residual":
            raise InvalidArgumentError(
                f"invalid estimator.kind {self.estimator.kind!r} with observer.enabled (the "
                "observer takes the residual estimator's place); valid: 'residual'")
        if self.limits.rate_limiter == "libfranka" and self.dt_s != LIBFRANKA_DELTA_T_S:
            raise InvalidArgumentError(
                f"invalid dt_s {self.dt_s!r} with limits.rate_limiter='libfranka'; valid: "
                f"{LIBFRANKA_DELTA_T_S} (libfranka's kDeltaT), or rate_limiter='per_tick_clip'"
            )
