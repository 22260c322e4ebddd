"""Env look-up and validation: registered ids, the swept parameter, control and policy periods."""

from __future__ import annotations

import importlib
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import gymnasium as gym
import numpy as np

from impact_control.errors import ImpactError, InvalidArgumentError
from impact_control.overrides import apply_overrides
from impact_control.presets import CUSTOM, Preset, resolve_preset
from impact_envs.versions import check_not_retired, preset_revision
from impact_eval.grid import plain_number

DEFAULT_PARAM_NAME = "object_mass"
"""Parameter swept when the env does not declare ``param_name``."""

DEFAULT_NAMESPACE = "IMPACT"


def import_env_module(env_id: str) -> str:
    """Import the module that registers ``env_id``; returns the id without a ``module:`` prefix.

    ``impact_envs`` is always imported (it registers the ``IMPACT/*`` envs); an id written as
    ``"package.module:Namespace/Name-v0"`` also imports ``package.module``, as ``gym.make`` does.
    """
    importlib.import_module("impact_envs")
    if ":" not in env_id:
        return env_id
    module, bare_id = env_id.split(":", 1)
    try:
        importlib.import_module(module)
    except ImportError as exc:
        raise InvalidArgumentError(f"cannot import env module {module!r}: {exc}") from None
    return bare_id


def env_choices(bare_id: str) -> list[str]:
    """Registered ids to suggest: the requested namespace's (or IMPACT's) ids."""
    namespace = bare_id.split("/", 1)[0] if "/" in bare_id else DEFAULT_NAMESPACE
    ids = sorted(i for i in gym.registry if i.startswith(f"{namespace}/"))
    return ids or sorted(i for i in gym.registry if i.startswith(f"{DEFAULT_NAMESPACE}/"))


def check_env_id(env_id: str) -> str:
    """Raise a one-line ``InvalidArgumentError`` unless ``env_id`` is registered; return bare id."""
    bare_id = import_env_module(env_id)
    check_not_retired(bare_id)
    if bare_id not in gym.registry:
        choices = ", ".join(env_choices(bare_id)) or "(none registered)"
        raise InvalidArgumentError(f"unknown env id {env_id!r}; valid choices: {choices}")
    return bare_id


def check_masses(env_id: str, masses: Sequence[float]) -> None:
    """One-line ``InvalidArgumentError`` for a mass outside the range of ``env_id``'s mass
    (``Task.mass_param``; checked before a run writes anything)."""
    env = gym.make(env_id)
    try:
        task = env.unwrapped.task
        declared = task.mass_param()
        if declared is None:
            raise InvalidArgumentError(f"{env_id} declares no mass; valid: an env with one")
        for mass in masses:
            declared.validate(mass)
    finally:
        env.close()


def with_impedance_of(preset: str, impedance_from: str | None, overrides: Sequence[str],
                      revision: int) -> Preset:
    """Preset ``preset`` of ``revision`` with the impedance section of ``impedance_from``
    (None: its own), then ``overrides``; ``"custom"`` where that changed its config."""
    if impedance_from is None:
        return resolve_preset(preset, overrides, revision=revision)
    base = resolve_preset(preset, revision=revision).config
    impedance = resolve_preset(impedance_from, revision=revision).config.impedance
    config = apply_overrides(replace(base, impedance=impedance), list(overrides))
    return Preset(CUSTOM if overrides or config != base else preset, config)


def make_env(env_id: str, controller: str, overrides: Sequence[str] = (),
             preset: str = "default", render: bool = False,
             observation: object | None = None, robot: object | None = None,
             robot_overrides: Sequence[str] = (), impedance_from: str | None = None) -> gym.Env:
    """``gym.make(env_id, controller=controller, controller_preset=preset)``, errors turned
    into ``ImpactError``; ``observation`` and ``robot`` (an ``ObservationOptions``, a
    ``RobotOptions``) are passed when given.

    IMPACT envs end an episode at success (``terminate_on_success=True``): success is then
    final, and a sweep does not spend the remaining steps of solved episodes. ``overrides``
    (``SECTION.FIELD=VALUE``, ``control.overrides``) change the controller's config from the
    preset's values, for ablations; ``robot_overrides`` (``FIELD=VALUE``,
    ``RobotOptions`` fields, e.g. ``realism=fr3``) change the robot on top of ``robot``.
    ``impedance_from`` (a preset name) replaces the impedance section of the preset with that
    preset's (``MethodSpec.demo_impedance``), before the overrides; a changed config is
    passed as a ``"custom"`` preset, as with overrides.
    Envs outside the IMPACT namespace (plugins) get the preset
    argument only when it is not ``"default"``, so a plugin env that cannot take it fails in one
    line instead of silently running another configuration.
    """
    extra: dict[str, object] = {}
    # A preset by its name (the env resolves it once, and run.json's env spec records the
    # name); with overrides, the resolved Preset, its name "custom" travelling with it.
    resolved = with_impedance_of(preset, impedance_from, overrides, preset_revision(env_id))
    if env_id.split(":")[-1].startswith("IMPACT/"):
        extra["terminate_on_success"] = True
        extra["controller_preset"] = resolved if resolved.name == CUSTOM else resolved.name
    elif resolved.name == CUSTOM:  # an env of another namespace takes a name or a config
        extra["controller_preset"] = resolved.config
    elif preset != "default":
        extra["controller_preset"] = preset
    if observation is not None:
        extra["observation"] = observation  # an ObservationOptions (camera methods)
    if robot_overrides:
        from impact_envs.envs.options import apply_robot_overrides

        robot = apply_robot_overrides(robot, robot_overrides)  # type: ignore[arg-type]
    if robot is not None:
        extra["robot"] = robot  # a RobotOptions (the *_authors methods' torque reading)
    try:
        if render:
            extra["render_mode"] = "rgb_array"
        return gym.make(env_id, controller=controller, **extra)
    except ImpactError:
        raise
    except Exception as exc:  # noqa: BLE001 - env construction failed: report it in one line
        msg = " ".join(str(exc).split())[:160]
        raise InvalidArgumentError(
            f"cannot make {env_id} with controller={controller!r}: {type(exc).__name__}: {msg}"
        ) from None


@dataclass(frozen=True)
class EnvInfo:
    """What the sweep needs to know about an env, read once in the parent."""

    env_id: str
    param_name: str
    policy_dt: float
    control_dt: float | None
    max_episode_steps: int | None
    spec_json: str
    param_names: tuple[str, ...] = ()


def task_params(env: gym.Env) -> tuple[object, ...]:
    """The ``TaskParam``s the env's task declares (name, default, range, unit); none for an
    env without a task (a plugin's)."""
    return tuple(getattr(getattr(env.unwrapped, "task", None), "params", ()))


def describe_env(env: gym.Env, requested: str | None = None) -> EnvInfo:
    """Read parameter name, periods [s] and the serialised spec of a built env.

    The swept parameter is ``requested`` (``--param``) when the env's task declares it (IMPACT
    tasks accept every declared parameter as a reset option), else the env's first one.
    """
    base = env.unwrapped
    default_name = getattr(base, "param_name", None) or DEFAULT_PARAM_NAME
    declared = tuple(p.name for p in task_params(env))
    names = declared or (str(default_name),)
    param_name = requested if requested in names else default_name
    policy_dt = getattr(base, "policy_dt", None) or getattr(base, "dt", None)
    if policy_dt is None and env.metadata.get("render_fps"):
        policy_dt = 1.0 / float(env.metadata["render_fps"])
    if policy_dt is None or not math.isfinite(float(policy_dt)) or policy_dt <= 0:
        policy_dt = math.nan
    control_dt = getattr(base, "control_dt", None) or getattr(
        getattr(base, "sim", None), "dt", None
    )
    try:
        spec_json = env.spec.to_json() if env.spec is not None else "null"
    except (ValueError, TypeError):
        spec_json = json.dumps(
            {"id": env.spec.id if env.spec else None, "note": "not serialisable"}
        )
    return EnvInfo(
        env_id=env.spec.id if env.spec is not None else "",
        param_name=str(param_name),
        policy_dt=float(policy_dt),
        control_dt=None if control_dt is None else float(control_dt),
        max_episode_steps=env.spec.max_episode_steps if env.spec is not None else None,
        spec_json=spec_json,
        param_names=names,
    )


def check_param(info: EnvInfo, requested: str | None) -> None:
    """Raise unless ``requested`` (``--param``) is ``None`` or one of the env's parameters."""
    valid = info.param_names or (info.param_name,)
    if requested is not None and requested not in valid:
        raise InvalidArgumentError(
            f"unknown parameter {requested!r} for {info.env_id}; valid choices: {', '.join(valid)}"
        )


def probe_values(env: gym.Env, param_name: str, values: Sequence[float]) -> None:
    """Reset once per value: the env must accept it and report it back in ``info``.

    Raises:
        InvalidArgumentError: the env rejected a value or reported a different one.
    """
    for value in values:
        try:
            _, info = env.reset(seed=0, options={param_name: value})
        except Exception as exc:  # noqa: BLE001 - a rejected value is bad input
            shown = plain_number(value)  # as typed: 0.00001, not 1e-05
            msg = " ".join(str(exc).split())[:160].replace(f"={float(value)!r}", f"={shown}")
            raise InvalidArgumentError(
                f"{param_name}={shown} rejected by {env.spec.id if env.spec else env}: {msg}"
            ) from None
        reported = info.get(param_name)
        if reported is not None and not math.isclose(
            float(reported), value, rel_tol=1e-6, abs_tol=1e-9
        ):
            raise InvalidArgumentError(
                f"env ignored {param_name}={value} (info reports {reported}); "
                "does it read reset(options=...)?"
            )


def precompile_kernels(env: gym.Env) -> None:
    """Run one policy step so that every per-tick numba kernel is compiled (or loaded) in
    this process before any sweep worker starts: numba caches them on disk, so the workers
    of a sweep on a fresh machine load them (about 1.5 s each) instead of each compiling
    them (about 18 s each, docs/eval.md). A plugin env's failure here is left to the sweep."""
    try:
        env.reset(seed=0)
        env.step(env.action_space.sample())
    except Exception:  # noqa: BLE001, S110 - only a warm-up: the sweep reports real failures
        pass


def method_env(env_id: str, spec: object, overrides: Sequence[str] = (),
               render: bool = False, robot_overrides: Sequence[str] = ()) -> gym.Env:
    """``make_env`` for a method: its controller, preset (with its demos' impedance where it
    has ``demo_impedance``), observation and robot, wrapped in
    ``impact_envs.wrappers.RLActions`` when the method acts in one of its modes (an SB3 model
    trained on the wrapper)."""
    env = make_env(env_id, spec.controller, overrides, spec.preset, render,
                   spec.observation_for(env_id), getattr(spec, "robot", None), robot_overrides,
                   spec.impedance_preset(env_id))
    if spec.action_mode is None:
        return env
    from impact_envs.wrappers import RLActions

    if spec.action_mode == "absolute" and _is_unit_box(env.action_space, 10):
        return env  # the env's own space already is the model's
    return RLActions(env, mode=spec.action_mode)


def _is_unit_box(space: gym.Space, n: int) -> bool:
    """Whether ``space`` is ``Box(-1, 1, (n,))``."""
    return (isinstance(space, gym.spaces.Box) and space.shape == (n,)
            and bool(np.all(space.low == -1.0)) and bool(np.all(space.high == 1.0)))
