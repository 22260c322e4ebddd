"""A full snapshot of an IMPACT env: simulator, arm model, controller, internal model, task.

``capture(env)`` copies everything that carries an episode from one step to the next;
``restore(env, state)`` writes it back *into the env's own arrays*, so every view the loop,
the controller and the simulator hold stays valid (a plain ``copy.deepcopy`` of an env broke
them: the copy ran but no longer actuated). Restoring a captured state and replaying the
same actions reproduces the trajectory bit for bit (tests/envs/test_env_state.py).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_envs.envs.env_parts import EnvParts

ENV_FIELDS = ("_params", "_episode_params", "_target_pos", "_target_quat", "_gripper_cmd",
              "_step_count", "_success_once", "_q_meas", "_dq_meas", "_warm", "_carry")
"""ImpactEnv attributes that change during an episode."""


@dataclass
class EnvState:
    """What ``ImpactEnv.get_state`` returns (all copies; restore with ``set_state``)."""

    model: mujoco.MjModel
    data: mujoco.MjData
    arrays: dict[str, np.ndarray]
    weights: dict[str, np.ndarray]
    learner: dict[str, Any]
    task: dict[str, Any]
    env: dict[str, Any]
    rng: np.random.Generator
    identity: dict[str, str]
    """What the state belongs to (``state_identity``): ``set_state`` refuses another."""


def state_identity(env: EnvParts) -> dict[str, str]:
    """Env class, task, controller mode, preset, the full controller configuration and the
    torque reading (``RobotOptions.torque_reading``: a link-side state carries a sensor bias
    and estimator filters that a commanded reading would continue wrongly, and vice versa)."""
    return {"env": f"{type(env).__module__}.{type(env).__qualname__}",
            "task": str(env.task.name), "controller": str(env.controller_mode),
            "preset": str(env.controller_preset), "config": repr(env.controller.config),
            "torque_reading": str(env.sim.torque_reading)}


def _shape_errors(expected: dict[str, Any], given: object, what: str) -> list[str]:
    """Differences in names, shapes and dtypes between live arrays and a state's copies."""
    if not isinstance(given, dict) or set(given) != set(expected):
        return [f"{what} names differ"]
    errors = []
    for name, live in expected.items():
        copy_ = given[name]
        shape, dtype = tuple(live.shape), live.dtype
        if tuple(getattr(copy_, "shape", ())) != shape or getattr(copy_, "dtype", None) != dtype:
            errors.append(f"{what} {name}: {tuple(getattr(copy_, 'shape', ()))} "
                          f"{getattr(copy_, 'dtype', type(copy_).__name__)} for {shape} {dtype}")
    return errors


def check_state(env: EnvParts, state: object) -> None:
    """``InvalidArgumentError`` (one line) unless ``state`` is a snapshot of an env like
    ``env``: same identity, and every array of the same name, shape and dtype."""
    if not isinstance(state, EnvState):
        raise InvalidArgumentError(
            f"set_state needs an EnvState from get_state(), got {type(state).__name__}")
    ident = getattr(state, "identity", None)
    mine = state_identity(env)
    if ident != mine:
        keys = [k for k in mine if not isinstance(ident, dict) or ident.get(k) != mine[k]]
        shown = {k: (ident or {}).get(k) if isinstance(ident, dict) else None
                 for k in keys if k != "config"}
        raise InvalidArgumentError(
            f"set_state: the state is of another env ({', '.join(keys)} differ: state "
            f"{shown}, env { {k: mine[k] for k in keys if k != 'config'} }); "
            "restore it into an env made with the same arguments")
    errors = _shape_errors(_model_arrays(env.sim.model), _model_arrays(state.model), "model")
    errors += _shape_errors(_live_arrays(env), state.arrays, "array")
    net = env.controller.internal_model.net.state_dict()
    errors += _shape_errors(net, state.weights, "weight")
    if not isinstance(state.env, dict) or set(state.env) != set(ENV_FIELDS):
        errors.append("env fields differ")
    if not isinstance(state.task, dict):
        errors.append("task fields are not a dict")
    if not isinstance(state.rng, np.random.Generator):
        errors.append("rng is not a numpy Generator")
    if errors:
        raise InvalidArgumentError(f"set_state: the state does not fit this env: {errors[0]}"
                                   f"{f' (and {len(errors) - 1} more)' if len(errors) > 1 else ''}")


def _model_arrays(model: object) -> dict[str, np.ndarray]:
    """Every non-empty numeric array of an MjModel, by name."""
    if not isinstance(model, mujoco.MjModel):
        return {}
    arrays = {}
    for name in dir(model):
        if not name.startswith("_"):
            value = getattr(model, name, None)
            if isinstance(value, np.ndarray) and value.size:
                arrays[name] = value
    return arrays


def _live_arrays(env: EnvParts) -> dict[str, np.ndarray]:
    """Every array (by name) whose contents carry state between ticks, as the live objects:
    what the controller, the simulator and the arm model each declare (``state_arrays``)."""
    return {**{f"controller.{k}": v for k, v in env.controller.state_arrays().items()},
            **{f"sim.{k}": v for k, v in env.sim.state_arrays().items()},
            **{f"dynamics.{k}": v for k, v in env.dynamics.state_arrays().items()}}


def _copy_model(dst: mujoco.MjModel, src: mujoco.MjModel) -> None:
    """Copy every numeric array of ``src`` into ``dst`` (same scene: per-episode parameters
    such as masses, inertias, goal positions and frictions are model fields)."""
    for name, value in _model_arrays(src).items():
        np.copyto(getattr(dst, name), value)


def capture(env: EnvParts) -> EnvState:
    """A deep copy of ``env``'s episode state."""
    im = env.controller.internal_model
    return EnvState(
        model=copy.deepcopy(env.sim.model),
        data=copy.deepcopy(env.sim.data),
        arrays={k: v.copy() for k, v in _live_arrays(env).items()},
        weights={k: v.copy() for k, v in im.net.state_dict().items()},
        learner=env.controller.python_state(),
        task=copy.deepcopy(env.task.__dict__),
        env=copy.deepcopy({k: getattr(env, k, None) for k in ENV_FIELDS}),
        rng=copy.deepcopy(env.np_random),
        identity=state_identity(env),
    )


def restore(env: EnvParts, state: EnvState) -> None:
    """Write ``state`` into ``env`` in place (an env of the same task and settings).

    Everything is checked first (``check_state``): a refused state leaves ``env`` as it was.
    """
    check_state(env, state)
    sim = env.sim
    _copy_model(sim.model, state.model)
    mujoco.mj_copyData(sim.data, sim.model, state.data)
    for name, live in _live_arrays(env).items():
        np.copyto(live, state.arrays[name])
    ctrl = env.controller
    im = ctrl.internal_model
    im.net.load_state_dict(state.weights)
    ctrl.load_python_state(state.learner)
    env.task.__dict__.update(copy.deepcopy(state.task))
    for key, value in copy.deepcopy(state.env).items():
        setattr(env, key, value)
    env.np_random = copy.deepcopy(state.rng)
