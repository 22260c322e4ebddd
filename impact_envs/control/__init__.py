"""Controller core of IMPACT: pure NumPy / torch, no MuJoCo (see docs/controller.md)."""

from __future__ import annotations

from impact_envs.control.config import (
    ControllerConfig,
    EstimatorConfig,
    ImpedanceConfig,
    InternalModelConfig,
    LimitsConfig,
    SlowWrenchConfig,
)
from impact_envs.control.controller import ControllerSignals, ImpactController
from impact_envs.control.protocols import ArmDynamics

__all__ = [
    "ArmDynamics",
    "ControllerConfig",
    "ControllerSignals",
    "EstimatorConfig",
    "ImpactController",
    "ImpedanceConfig",
    "InternalModelConfig",
    "LimitsConfig",
    "SlowWrenchConfig",
]
