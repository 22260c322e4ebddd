"""``evaluate``: impact-eval's sweep for a policy object, from Python.

Runs in this process (one worker; the policy object needs no importable module), with the
same planning, seeds, resume, CSV and plots as the CLI, and returns the episodes table.
"""

from __future__ import annotations

import math
import re
import sys
from collections.abc import Callable, Sequence
from numbers import Real
from pathlib import Path

import gymnasium as gym
import numpy as np
import pandas as pd

from impact_control.controller import CONTROLLERS
from impact_control.errors import CheckpointError, ImpactError, InvalidArgumentError, check_choice
from impact_control.policy import Policy
from impact_control.presets import PRESETS
from impact_envs.envs.arguments import coerce_options
from impact_envs.envs.options import ObservationOptions
from impact_envs.tasks.bins import edge_text
from impact_eval.grid import format_value
from impact_eval.methods import MethodSpec, temporary_method
from impact_eval.spec import RunOptions, SweepSpec, values_from_text


class EvaluationError(ImpactError):
    """``evaluate`` ran, but every episode of some cell raised (the CLI exits 1 there)."""


PolicySource = Policy | Callable[[str, gym.Env], Policy]
"""A policy (``reset(n_envs)``, ``act(batched obs) -> (B, 10)``) or a factory
``(env_id, env) -> Policy`` called once."""


def _check_policy_object(policy: object, what: str) -> None:
    """One-line error unless ``policy`` has callable ``reset`` and ``act`` (an instance)."""
    if isinstance(policy, type):
        raise InvalidArgumentError(
            f"{what} is the class {policy.__name__}, not a policy; pass an instance "
            f"({policy.__name__}(...)) or a factory (env_id, env) -> policy")
    missing = [m for m in ("reset", "act") if not callable(getattr(policy, m, None))]
    if missing:
        raise InvalidArgumentError(
            f"{what} {type(policy).__name__} lacks {' and '.join(missing)}; a policy needs "
            "reset(n_envs) and act(batched obs) -> (B, 10) (impact_control.policy)")


def _check_int(name: str, value: object, low: int) -> int:
    """``value`` as an int >= ``low`` (bools and floats refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise InvalidArgumentError(f"invalid {name} {value!r}; valid: an integer >= {low}")
    return int(value)


def grid_or_bins(values: object) -> tuple[str | None, str | None]:
    """``values`` as ``(grid, mass_bins)`` request text: numbers give a grid, ``(lo, hi)``
    pairs give bins (``bins.parse_bins`` then checks their order and overlap)."""
    if (isinstance(values, (Sequence, np.ndarray)) and not isinstance(values, (str, bytes))
            and len(values) and all(isinstance(v, (tuple, list)) for v in values)):
        if any(len(v) != 2 for v in values):
            raise InvalidArgumentError(
                f"invalid bins {values!r}; valid: (lo, hi) pairs, e.g. [(0.1, 0.3), (0.3, 0.5)]")
        edges = [check_values(list(v)) for v in values]
        return None, ",".join(f"{edge_text(lo)}-{edge_text(hi)}" for lo, hi in edges)
    return ",".join(format_value(v) for v in check_values(values)), None


def check_values(values: object) -> list[float]:
    """``values`` as a non-empty list of finite real numbers (strings and bools refused)."""
    if isinstance(values, (str, bytes)) or not isinstance(values, (Sequence, np.ndarray)):
        raise InvalidArgumentError(
            f"invalid values {values!r}; valid: a sequence of numbers, e.g. [0.2, 2.5, 5.0]")
    numbers = []
    for v in list(values):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (Real, np.number)) or not (
                math.isfinite(float(v))):
            raise InvalidArgumentError(
                f"invalid value {v!r} in values; valid: finite real numbers, e.g. [0.2, 2.5]")
        numbers.append(float(v))
    if not numbers:
        raise InvalidArgumentError("values is empty; give at least one parameter value")
    return numbers


def _check_name(name: object) -> str:
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_.\-]+", name):
        raise InvalidArgumentError(
            f"invalid name {name!r}; valid: letters, digits, '_', '.', '-' (no comma or space)")
    return name


def _policy_factory(policy: object) -> Callable[[str, gym.Env], Policy]:
    """The method's factory for ``policy`` (an instance or a factory), checked: one-line
    errors for None, a class, or an object without ``reset``/``act`` (also for what a factory
    returns, when impact-eval's pre-flight builds it before anything is written)."""
    if policy is None:
        raise InvalidArgumentError(
            "invalid policy None; valid: an object with reset/act or a factory "
            "(env_id, env) -> policy")
    is_factory = callable(policy) and not isinstance(policy, type) and not hasattr(policy, "act")
    if not is_factory:
        _check_policy_object(policy, "policy")

    def build(env_id: str, env: gym.Env) -> Policy:
        built = policy(env_id, env) if is_factory else policy  # type: ignore[operator]
        _check_policy_object(built, "the policy factory returned")
        check_fits_env(built, env_id, env)
        return built  # type: ignore[return-value]

    return build


def check_fits_env(policy: object, env_id: str, env: gym.Env) -> None:
    """One line, before anything is written, when the policy says what it observes and the
    env does not give it: a diffusion-policy checkpoint (its observation keys, sizes and
    cameras, ``compat.check_policy_env``) or a policy with ``required_observations`` (the
    scripted experts: the object's and goal's poses, hidden in the image modes)."""
    spaces = getattr(env.observation_space, "spaces", {})
    dp = sys.modules.get("impact_envs.policies.diffusion.policy")
    if dp is not None and isinstance(policy, dp.DiffusionPolicy):
        from impact_envs.policies.diffusion.compat import check_policy_env

        try:
            check_policy_env(policy, env_id, env, "given to evaluate()")
        except CheckpointError as exc:
            raise CheckpointError(f"{exc} (evaluate's observation= argument makes the env's "
                                  "ObservationOptions)") from None
        return
    keys = getattr(policy, "required_observations", None) or ()
    missing = [k for k in keys if k not in spaces]
    if missing:
        mode = getattr(getattr(env.unwrapped, "observation_options", None), "obs_mode", None)
        raise InvalidArgumentError(
            f"policy {type(policy).__name__} needs the observation entries "
            f"{', '.join(missing)}, which the env's obs_mode {mode!r} does not give; valid: "
            "evaluate(..., observation='state' or 'state+rgb')")


def _raise_if_all_crashed(out: Path) -> None:
    """``EvaluationError`` when every episode of some cell raised (the CLI's exit 1)."""
    from impact_eval.sweep_command import crashed_cells

    crashed = crashed_cells(out)
    if crashed:
        raise EvaluationError(
            f"every episode raised in {len(crashed)} cell(s): {'; '.join(crashed[:3])}"
            f"{' ...' if len(crashed) > 3 else ''} (rows in {out / 'episodes.csv'})")


def _check_robot_set(robot_set: object) -> tuple[str, ...]:
    """``robot_set`` as a tuple of ``FIELD=VALUE`` strings (one line if it is not a list of
    strings; the fields are checked by ``prepare``)."""
    if isinstance(robot_set, str) or not all(isinstance(s, str) for s in robot_set):  # type: ignore[union-attr]
        raise InvalidArgumentError(
            f"invalid robot_set {robot_set!r}; valid: a list of 'FIELD=VALUE' strings, e.g. "
            "['realism=fr3']")
    return tuple(robot_set)  # type: ignore[arg-type]


def evaluate(
    policy: PolicySource,
    env_id: str,
    values: Sequence[float],
    out: str | Path,
    *,
    episodes: int = 20,
    controller: str = "impact",
    controller_preset: str = "default",
    name: str = "custom",
    param: str | None = None,
    seed: int = 0,
    envs_per_worker: int = 4,
    resume: bool = False,
    observation: ObservationOptions | dict | str | None = None,
    robot_set: Sequence[str] = (),
) -> pd.DataFrame:
    """Evaluate ``policy`` on ``env_id`` over ``values`` of the env's sweep parameter.

    Args:
        policy: The policy, or a factory of it (see ``PolicySource``).
        env_id: A registered env id (``"IMPACT/Hammer-v2"``; ``"module:ID"`` imports module).
        values: Parameter values, e.g. masses [kg]; each is one cell of ``episodes`` episodes.
            Or mass bins as ``(lo, hi)`` pairs [kg], ``[lo, hi)`` each: every episode draws
            its mass in its bin from its seed (``impact-eval --mass-bins``; the env's mass
            only, ``bins.check_bin_param``).
        out: Output directory: ``episodes.csv``, ``summary.csv``, ``run.json``, ``plots/``.
        episodes: Episodes per value (paired seeds, as the CLI's).
        controller: ``"impact"`` or ``"impedance"``.
        controller_preset: The controller's preset, one of ``impact_control.presets.PRESETS``
            (``"default"``, ``"paper"``, ``"authors_sim"``, ``"authors_real"``;
            docs/presets.md, "Presets").
        name: The method's name in the CSV and plots; not a built-in method's name. It is
            registered for this call only.
        param: The parameter to sweep (default: the env's first).
        seed: Base seed of the episode seeds.
        envs_per_worker: Episodes run in lockstep (the batch size of ``policy.act``).
        resume: Continue an interrupted run in ``out``; every argument must be the same
            (controller and preset included), else the call is refused.
        observation: What the env observes (``ObservationOptions``, a dict of its fields or
            an ``obs_mode`` string; default the state). A policy that says what it needs (a
            diffusion-policy checkpoint, a scripted expert) is checked against it before
            anything is written: a camera checkpoint needs e.g. ``"rgb"``.
        robot_set: ``FIELD=VALUE`` changes of the simulated robot (``RobotOptions``), as
            ``impact-eval --robot-set``, e.g. ``["realism=fr3"]``.

    Returns:
        The episodes table (one row per episode, the columns of ``episodes.csv``).

    Raises:
        InvalidArgumentError: Bad input (one line naming the valid choices), nothing written.
        EvaluationError: Every episode of some cell raised (a broken policy or env); the
            rows are in ``out/episodes.csv``, as the CLI's exit 1.
    """
    from impact_eval.execute import execute
    from impact_eval.prepare import prepare

    build = _policy_factory(policy)
    grid, mass_bins = grid_or_bins(values)
    check_choice("controller", controller, CONTROLLERS)
    check_choice("controller_preset", controller_preset, PRESETS)
    if not isinstance(env_id, str):
        raise InvalidArgumentError(f"invalid env_id {env_id!r}; valid: a registered env id")
    points, highs = values_from_text(grid, mass_bins)
    spec = SweepSpec(
        env_id=env_id, methods=(_check_name(name),), values=points, bin_highs=highs,
        param=param, episodes=_check_int("episodes", episodes, 1),
        seed=_check_int("seed", seed, 0), robot_overrides=_check_robot_set(robot_set))
    run = RunOptions(out=Path(out), workers=1, resume=bool(resume),
                     envs_per_worker=_check_int("envs_per_worker", envs_per_worker, 1))
    options = coerce_options("observation", observation, ObservationOptions)
    method = MethodSpec(name, controller, build, "evaluate() policy object",
                        preset=controller_preset,
                        observation=options if options.uses_images else None)
    with temporary_method(method):
        plan = prepare(spec, run)
        call = [f"policy={name}", f"controller={controller}",
                f"controller_preset={controller_preset}"]
        if method.observation is not None:
            call.append(f"observation={method.observation!r}")
        execute(plan, command=[sys.argv[0], "impact_eval.evaluate", *call])
    _raise_if_all_crashed(Path(out))
    return pd.read_csv(Path(out) / "episodes.csv", keep_default_na=False)
