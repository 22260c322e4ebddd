"""The IMPACT envs' constructor arguments, resolved and checked: the task reference, the
controller config of ``controller_preset``, the initial task parameters, one-line errors."""

from __future__ import annotations

import importlib

from impact_envs.control.config import ControllerConfig
from impact_envs.control.controller import CONTROLLERS
from impact_envs.control.presets import PRESETS, preset_config, preset_name
from impact_envs.errors import InvalidArgumentError, check_choice
from impact_envs.tasks.base import Task

REWARD_TYPES = ("sparse", "dense")
"""``"sparse"``: 1.0 on steps where the task is accomplished, else 0.0 (default);
``"dense"``: the task's shaped ``dense_reward`` in [0, 1] (docs/envs.md)."""


def load_task(ref: str) -> Task:
    """A task instance from ``"module:TaskClass"`` (the generic env's ``task`` argument)."""
    module, _, name = ref.partition(":")
    try:
        task_cls = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError, ValueError) as exc:
        raise InvalidArgumentError(f"cannot load task {ref!r}: {exc}; valid: "
                                   "'module:TaskClass' of an importable Task") from None
    if not (isinstance(task_cls, type) and issubclass(task_cls, Task)):
        raise InvalidArgumentError(f"task {ref!r} is not a Task subclass")
    return task_cls()


def controller_config(preset: str | ControllerConfig) -> tuple[ControllerConfig, str]:
    """The env's controller config and its preset name: the named preset, or a
    ``ControllerConfig`` as given (named after the preset it equals, else "custom")."""
    if isinstance(preset, ControllerConfig):
        return preset, preset_name(preset)
    return preset_config(preset), preset


def check_args(controller: str, reward_type: str, controller_preset: str | ControllerConfig,
               render_mode: str | None, render_modes: list[str]) -> None:
    """One-line errors naming the valid choices."""
    check_choice("controller", controller, CONTROLLERS)
    check_choice("reward_type", reward_type, REWARD_TYPES)
    if not isinstance(controller_preset, ControllerConfig):
        check_choice("controller_preset", controller_preset, PRESETS)
    if render_mode is not None:
        check_choice("render_mode", render_mode, render_modes)


def initial_params(task: Task, object_mass: float | None,
                   task_params: dict[str, float] | None) -> dict[str, float]:
    """The task's defaults, then the ``object_mass`` shorthand, then ``task_params``."""
    params = {p.name: p.default for p in task.params}
    if object_mass is not None:
        params[task.param("object_mass").name] = task.param("object_mass").validate(
            object_mass)
    for name, value in (task_params or {}).items():
        params[name] = task.param(name).validate(value)
    return params
