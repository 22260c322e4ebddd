"""The IMPACT envs' constructor arguments, resolved and checked: the task reference, the
controller config of ``controller_preset``, the initial task parameters, one-line errors."""

from __future__ import annotations

import dataclasses
import difflib
import importlib
import inspect
from collections.abc import Mapping
from typing import TypeVar

from impact_control.controller import CONTROLLERS
from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.presets import Preset, as_preset
from impact_envs.envs.options import ObservationOptions, RenderOptions, RobotOptions
from impact_envs.tasks.base import Task
from impact_envs.versions import parse, pins

Options = TypeVar("Options", RobotOptions, RenderOptions, ObservationOptions)

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


def version_pins(task: Task, env_version: int | None) -> tuple[str, int]:
    """(robot profile when ``RobotOptions.realism`` is unset, controller preset revision) of
    ``task``'s env at ``env_version`` (None: its current version; ``versions.pins``). A task
    outside the built-in families has one version (``env_version`` must be None)."""
    parsed = parse(task.env_id)
    if parsed is None and env_version is not None:
        raise InvalidArgumentError(f"invalid env_version {env_version!r} for {task.env_id}; "
                                   "valid: None (it has one version)")
    return pins(None if parsed is None else parsed[0], env_version)


def pinned_options(task: Task, env_version: int | None, controller_preset: object,
                   robot: object, render: object, observation: object
                   ) -> tuple[Preset, RobotOptions, RenderOptions, ObservationOptions]:
    """The env's preset and option arguments resolved as its version pins them
    (``version_pins``): the preset at the version's revision, an unset robot profile as the
    version's."""
    profile, revision = version_pins(task, env_version)
    preset = as_preset(controller_preset, revision)  # type: ignore[arg-type]
    robot_opts, render_opts, obs_opts = env_options(robot, render, observation)
    return preset, robot_opts.with_default_realism(profile), render_opts, obs_opts


def check_args(controller: str, reward_type: str, render_mode: str | None,
               render_modes: list[str]) -> None:
    """One-line errors naming the valid choices (the preset's: ``presets.as_preset``)."""
    check_choice("controller", controller, CONTROLLERS)
    check_choice("reward_type", reward_type, REWARD_TYPES)
    if render_mode is not None:
        check_choice("render_mode", render_mode, render_modes)


def initial_params(task: Task, object_mass: float | None,
                   task_params: Mapping[str, float] | None) -> dict[str, float]:
    """The task's defaults, then the ``object_mass`` shorthand (the task's mass,
    ``Task.mass_param``: Calligraphy's ``tool_mass``), then ``task_params``.

    One-line errors: ``task_params`` not a mapping, a key that is not one of the task's
    parameters, a bad value, and ``object_mass`` given by both routes with two different
    values (equal values pass; which route would win is not the user's to guess)."""
    if task_params is not None and not isinstance(task_params, Mapping):
        raise InvalidArgumentError(
            f"invalid task_params {task_params!r} ({type(task_params).__name__}); valid: a "
            f"dict of task parameters ({', '.join(p.name for p in task.params)})")
    params = {p.name: p.default for p in task.params}
    given = {name: task.param(name).validate(value)
             for name, value in (task_params or {}).items()}
    if object_mass is not None:
        declared = task.mass_param()
        if declared is None:
            raise InvalidArgumentError(
                f"object_mass given, and {task.name} declares no mass; valid: task_params of "
                f"{', '.join(p.name for p in task.params)}")
        name, mass = declared.name, declared.validate(object_mass)
        if given.get(name, mass) != mass:
            raise InvalidArgumentError(
                f"object_mass given twice with different values: object_mass={object_mass!r} "
                f"and task_params[{name!r}]={task_params[name]!r}; valid: one "  # type: ignore[index]
                "of them, or both equal")
        params[name] = mass
    params.update(given)
    return params


def constructor_keywords(cls: type) -> list[str]:
    """The keywords named by the ``__init__`` of ``cls`` and of its base classes."""
    valid: list[str] = []
    for klass in cls.__mro__:
        if "__init__" in vars(klass):
            parameters = inspect.signature(vars(klass)["__init__"]).parameters.values()
            valid += [p.name for p in parameters if p.name != "self" and p.name not in valid
                      and p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)]
    return valid


def refuse_unknown_keywords(cls: type, unknown: Mapping[str, object]) -> None:
    """One-line error naming the keywords ``cls`` takes (and the closest one) if ``unknown``
    (the keywords no ``__init__`` named) is not empty: ``gym.make``'s keyword arguments reach
    the env's constructor, and Python's own ``TypeError`` names no valid keyword."""
    if not unknown:
        return
    valid = constructor_keywords(cls)
    close = difflib.get_close_matches(str(next(iter(unknown))), valid, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise InvalidArgumentError(
        f"unknown keyword argument(s) {', '.join(map(repr, unknown))} for {cls.__name__}"
        f"{hint}; valid: {', '.join(valid)}")


OPTION_ARGUMENTS: dict[str, tuple[type, str | None]] = {
    "robot": (RobotOptions, None),
    "render": (RenderOptions, None),
    "observation": (ObservationOptions, "obs_mode"),
}
"""The env's grouped option arguments: their class and the field a plain string sets
(``observation="rgb"`` is ``ObservationOptions(obs_mode="rgb")``; None: no string form)."""


def coerce_options(argument: str, value: object, cls: type[Options]) -> Options:
    """``value`` as an instance of ``cls``: None gives the defaults, an instance is kept, a
    mapping gives ``cls(**mapping)`` and, where the argument has one, a string sets its main
    field. Unknown keys and other types are one-line errors naming the valid ones."""
    string_field = OPTION_ARGUMENTS[argument][1]
    fields = [f.name for f in dataclasses.fields(cls)]
    if value is None:
        return cls()
    if isinstance(value, cls):
        return value
    if isinstance(value, Mapping):
        unknown = [k for k in value if k not in fields]
        if unknown:
            raise InvalidArgumentError(
                f"invalid {argument} key(s) {', '.join(map(repr, unknown))}; valid keys of "
                f"{cls.__name__}: {', '.join(fields)}")
        return cls(**value)
    if string_field is not None and isinstance(value, str):
        return cls(**{string_field: value})
    forms = f"{cls.__name__}(...) or a dict of its fields ({', '.join(fields)})"
    if string_field is not None:
        forms += f" or a {string_field} string"
    raise InvalidArgumentError(f"invalid {argument} {value!r} ({type(value).__name__}); "
                               f"valid: {forms}, from impact_envs")


def env_options(robot: object, render: object, observation: object
                ) -> tuple[RobotOptions, RenderOptions, ObservationOptions]:
    """The env's ``robot``, ``render`` and ``observation`` arguments as option instances."""
    return (coerce_options("robot", robot, RobotOptions),
            coerce_options("render", render, RenderOptions),
            coerce_options("observation", observation, ObservationOptions))
