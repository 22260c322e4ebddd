"""Make ``"IMPACT"`` and ``"IMPACT_IMPEDANCE"`` arm controller types of robosuite.

robosuite 1.5 builds arm controllers in ``controller_factory.arm_controller_factory``, a fixed
chain of names with no registry; ``register()`` wraps that function once so the two names
build an ``ImpactArmController`` and every other name goes to robosuite as before: robosuite's
own arguments (``ROBOSUITE_ARGS``) are passed as they are, our keys become its ``ArmOptions``,
and other keys are dropped (robosuite's config dicts carry keys for OSC, such as ``kp`` or
``interpolation``, that mean nothing here).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from robosuite.controllers.parts import controller_factory

from impact_control.errors import InvalidArgumentError, check_choice
from impact_robosuite.arm_controller import ArmOptions, ImpactArmController

CONTROLLER_TYPES = {"IMPACT": "impact", "IMPACT_IMPEDANCE": "impedance"}
"""robosuite ``type`` -> our controller mode."""
CONFIG_DIR = Path(__file__).resolve().parent / "configs"
METHODS = ("osc", "impedance", "impact", "impact_paper")
"""What ``controller_config`` builds: robosuite's default OSC_POSE, ours without and with the
internal model (``default`` preset), and IMPACT with the paper's table read literally
(``paper`` preset, docs/controller.md)."""

ROBOSUITE_ARGS = frozenset({"sim", "ref_name", "joint_indexes", "actuator_range", "part_name",
                            "naming_prefix", "lite_physics"})
"""What robosuite's factory gives every arm controller."""
_OPTIONS = frozenset(f.name for f in dataclasses.fields(ArmOptions)) - {"mode"}
_ACCEPTED = ROBOSUITE_ARGS | _OPTIONS


def _factory(original):
    def arm_controller_factory(name, params):
        if name not in CONTROLLER_TYPES:
            return original(name, params)
        given = {k: v for k, v in params.items() if k in ROBOSUITE_ARGS}
        options = ArmOptions(mode=CONTROLLER_TYPES[name],
                             **{k: v for k, v in params.items() if k in _OPTIONS})
        return ImpactArmController(**given, options=options)

    arm_controller_factory.impact_original = original
    return arm_controller_factory


def register() -> None:
    """Install the two controller types (idempotent)."""
    current = controller_factory.arm_controller_factory
    if not hasattr(current, "impact_original"):
        controller_factory.arm_controller_factory = _factory(current)


def controller_config(method: str, robot: str = "Panda", **arm_options: object) -> dict:
    """robosuite composite-controller config of ``method`` (``METHODS``) for ``robot``;
    ``arm_options`` override the arm part's settings (e.g. ``goal_update_mode``)."""
    from robosuite import load_composite_controller_config

    check_choice("method", method, METHODS)
    name = "impact" if method == "impact_paper" else method
    path = None if method == "osc" else str(CONFIG_DIR / f"{name}.json")
    config = load_composite_controller_config(controller=path, robot=robot)
    arm = config["body_parts"]["right"]
    if method == "impact_paper":
        arm["preset"] = "paper"
    unknown = set(arm_options) - _ACCEPTED - {"gripper"}
    if method != "osc" and unknown:
        raise InvalidArgumentError(f"unknown arm options {sorted(unknown)}; valid: "
                                   f"{', '.join(sorted(_ACCEPTED))}")
    arm.update(arm_options)
    return config
