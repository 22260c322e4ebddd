"""IMPACT inside robosuite (optional extra, its own environment: docs/robosuite.md).

``import impact_robosuite`` registers the arm controller types ``"IMPACT"`` and
``"IMPACT_IMPEDANCE"`` with robosuite; ``controller_config("impact" | "impedance" | "osc")``
gives a ready composite-controller config for ``robosuite.make(..., controller_configs=...)``.
"""

from impact_envs import _gl  # noqa: F401, I001 - first: the headless GL backend before mujoco loads
from impact_robosuite.registry import METHODS, controller_config, register

register()

__all__ = ["METHODS", "controller_config", "register"]
