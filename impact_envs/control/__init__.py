"""Controller core of IMPACT: NumPy, numba kernels and torch, no MuJoCo (see docs/controller.md).

Importing a submodule such as ``impact_envs.control.lie`` does not import torch; the
controller classes are loaded on first access (``from impact_envs.control import
ImpactController``).
"""

from __future__ import annotations

from typing import Any

from impact_envs.control.arm_model import ArmDynamics
from impact_envs.control.config import (
    ControllerConfig,
    EstimatorConfig,
    ImpedanceConfig,
    InternalModelConfig,
    LimitsConfig,
    SlowWrenchConfig,
)

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

_LAZY = {"ImpactController", "ControllerSignals"}


def __getattr__(name: str) -> Any:
    """Load the torch-dependent controller classes on first access."""
    if name in _LAZY:
        from impact_envs.control import controller

        return getattr(controller, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
