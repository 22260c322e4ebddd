"""IMPACT on a real FR3 through Franka's own client library, pylibfranka (extra ``[franka]``).

``fci.py``: the FCI conventions a runner must own (gravity added by the robot, link-side
``tau_J``, column-major ``O_T_EE``, the configuration meant for an FR3); ``runner.py``: the
1 kHz torque loop and its target sources; ``pick_place.py`` / ``gripper.py`` / ``poses.py``:
the taught pick-and-place task and the Franka Hand beside the loop; ``policy_loop.py``: a
policy at 30 Hz; ``cli.py`` / ``checks.py`` (every argument, before connecting) /
``commands.py`` / ``connection.py`` (the one-client lock, the connection watchdog) /
``session.py``: ``impact-robot``. Proven against
libfranka-protocol simulators on loopback (tests/franka/); docs/franka.md, docs/hardware.md.
"""

from __future__ import annotations

import importlib

_PUBLIC = {
    "run_loop": "impact_franka.runner", "hold": "impact_franka.runner",
    "HoldTarget": "impact_franka.runner", "TargetSource": "impact_franka.runner",
    "LoopReport": "impact_franka.runner", "PolicyTarget": "impact_franka.policy_loop",
    "PickPlaceTarget": "impact_franka.pick_place", "fr3_config": "impact_franka.fci",
    "FrankaError": "impact_franka.fci",
}
"""Where each public name lives; imported on first use, so ``import impact_franka`` stays
light (pylibfranka is imported only by the code that connects)."""

__all__ = sorted(_PUBLIC)


def __getattr__(name: str) -> object:
    if name not in _PUBLIC:
        raise AttributeError(f"module 'impact_franka' has no attribute {name!r}")
    return getattr(importlib.import_module(_PUBLIC[name]), name)
