"""The controller's state carried from one episode into the next (``ImpactEnv.carry_controller``).

The paper's authors run their benchmark with the controller activated once per (controller,
mass bin) launch: the scene reset between episodes does not reset it, so its estimator and
observer filters, slow-wrench filter, payload model, rate limiter, null-space posture and
internal model carry over the bin's episodes (``../shared/reference/authors_impact.md``).
Our envs reset the controller at every ``reset``; ``controller_carry(env)`` captures its whole
state at the end of an episode and ``apply_carry`` writes it back after the next episode's
``controller.reset``, *into* the live arrays (as ``envs/state.py`` does), so every view the
numba kernels and the closed loop hold stays valid.

Everything is carried except what the env itself sets per episode (``EPISODE_VIEWS``): the
target filter's state. In the authors' runs the controller keeps ticking through the scene
reset while the reset's target is commanded, and the filter puts weight 0.9 on the new target
every tick, so within a few ticks it holds that target and nothing of the last episode; our
episodes start with no tick between the scene reset and the first action, at the target the
env sets (the TCP's start pose), which is what a fresh filter starts from. The arm model
(``env.dynamics``) is not controller state: it is recomputed from the new pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from impact_control.controller import ImpactController
from impact_control.errors import InvalidArgumentError
from impact_control.internal_model import ModelSnapshot
from impact_envs.envs.env_parts import EnvParts
from impact_envs.envs.state import _shape_errors, state_identity

EPISODE_VIEWS = ("target_filter",)
"""Controller state the env sets per episode: kept as ``controller.reset`` left it when a
carry is applied (``episode_views``)."""


@dataclass(frozen=True)
class ControllerCarry:
    """A copy of an env's whole controller state (``controller_carry``; ``apply_carry``)."""

    arrays: dict[str, np.ndarray]
    """``ImpactController.state_arrays()`` (every kernel buffer), copied."""
    python: dict[str, Any]
    """``ImpactController.python_state()`` (replay sampler, divergence count)."""
    model: ModelSnapshot
    """``internal_model.snapshot()``: network weights and replay samples."""
    identity: dict[str, str]
    """``state_identity`` of the env it was taken from: ``carry_controller`` refuses another."""


def episode_views(controller: ImpactController) -> dict[str, np.ndarray]:
    """The live views of ``EPISODE_VIEWS`` (parts of the controller's kernel buffers)."""
    return {"target_filter": controller.optional.target_filter.packed.buffer}


def controller_carry(env: EnvParts) -> ControllerCarry:
    """A copy of ``env``'s controller state now (e.g. at the end of an episode)."""
    ctrl = env.controller
    return ControllerCarry(
        arrays={k: v.copy() for k, v in ctrl.state_arrays().items()},
        python=ctrl.python_state(),
        model=ctrl.internal_model.snapshot(),
        identity=state_identity(env))


def check_carry(env: EnvParts, carry: object) -> None:
    """One-line ``InvalidArgumentError`` unless ``carry`` was taken from an env like ``env``
    (same identity: class, task, controller mode, preset, configuration, torque reading; the
    same arrays)."""
    if not isinstance(carry, ControllerCarry):
        raise InvalidArgumentError(
            f"carry_controller needs a ControllerCarry from controller_carry() or None, got "
            f"{type(carry).__name__}")
    mine = state_identity(env)
    if carry.identity != mine:
        keys = [k for k in mine if carry.identity.get(k) != mine[k]]
        raise InvalidArgumentError(
            f"carry_controller: the state is of another env ({', '.join(keys)} differ); "
            "carry it into an env made with the same arguments")
    ctrl = env.controller
    errors = _shape_errors(ctrl.state_arrays(), carry.arrays, "array")
    if set(carry.python) != set(ctrl.python_state()):
        errors.append("python state names differ")
    if errors:
        raise InvalidArgumentError(f"carry_controller: the state does not fit this env: "
                                   f"{errors[0]}")


def apply_carry(env: EnvParts, carry: ControllerCarry) -> None:
    """After ``controller.reset``: overwrite the controller's state with ``carry``'s, except
    ``EPISODE_VIEWS`` (kept as the reset left them)."""
    ctrl = env.controller
    fresh = {k: v.copy() for k, v in episode_views(ctrl).items()}
    ctrl.internal_model.restore(carry.model)
    for name, live in ctrl.state_arrays().items():
        np.copyto(live, carry.arrays[name])
    ctrl.load_python_state({**carry.python, "is_reset": True})
    for name, live in episode_views(ctrl).items():
        np.copyto(live, fresh[name])
