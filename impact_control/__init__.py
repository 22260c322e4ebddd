"""The IMPACT controller and the FR3's dynamics, without a simulator (docs/controller.md).

The controller core (task-space impedance, wrench estimation, the slow-wrench filter, the
internal model; ``controller.ImpactController``), the arm model it runs on
(``dynamics.PinocchioArm``), the libfranka limits, the policy protocol and the rates. It
imports NumPy, numba and Pinocchio, never Gymnasium, MuJoCo or pandas, so a robot PC runs it
(``impact_franka``) without the benchmark. The controller classes are loaded on first access
(``from impact_control import ImpactController``); importing this package refreshes numba's
kernel cache (``jit_cache``).
"""

from __future__ import annotations

from typing import Any

from impact_control import jit_cache as _jit_cache
from impact_control.arm_model import ArmDynamics
from impact_control.config import (
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

__version__ = "0.1.0"

_LAZY = {"ImpactController", "ControllerSignals"}


def __getattr__(name: str) -> Any:
    """Load the controller classes on first access."""
    if name in _LAZY:
        from impact_control import controller

        return getattr(controller, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


_jit_cache.ensure_fresh_kernel_cache()
