"""``evaluate``: impact-eval's sweep for a policy object, from Python.

Runs in this process (one worker; the policy object needs no importable module), with the
same planning, seeds, resume, CSV and plots as the CLI, and returns the episodes table.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import gymnasium as gym
import pandas as pd

from impact_envs.policies.interface import Policy
from impact_eval.grid import format_value
from impact_eval.methods import MethodSpec, register_method

PolicySource = Policy | Callable[[str, gym.Env], Policy]
"""A policy (``reset(n_envs)``, ``act(batched obs) -> (B, 10)``) or a factory
``(env_id, env) -> Policy`` called once."""


def evaluate(
    policy: PolicySource,
    env_id: str,
    values: Sequence[float],
    out: str | Path,
    *,
    episodes: int = 20,
    controller: str = "impact",
    name: str = "custom",
    param: str | None = None,
    seed: int = 0,
    envs_per_worker: int = 4,
    resume: bool = False,
) -> pd.DataFrame:
    """Evaluate ``policy`` on ``env_id`` over ``values`` of the env's sweep parameter.

    Args:
        policy: The policy, or a factory of it (see ``PolicySource``).
        env_id: A registered env id (``"IMPACT/Hammer-v0"``; ``"module:ID"`` imports module).
        values: Parameter values, e.g. masses [kg]; each is one cell of ``episodes`` episodes.
        out: Output directory: ``episodes.csv``, ``summary.csv``, ``run.json``, ``plots/``.
        episodes: Episodes per value (paired seeds, as the CLI's).
        controller: ``"impact"`` or ``"impedance"``.
        name: The method's name in the CSV and plots.
        param: The parameter to sweep (default: the env's first).
        seed: Base seed of the episode seeds.
        envs_per_worker: Episodes run in lockstep (the batch size of ``policy.act``).
        resume: Continue an interrupted run in ``out`` (same arguments).

    Returns:
        The episodes table (one row per episode, the columns of ``episodes.csv``).

    Raises:
        InvalidArgumentError: Bad input (one line naming the valid choices), nothing written.
    """
    from impact_eval.execute import execute
    from impact_eval.prepare import SweepRequest, prepare

    def build(env_id_: str, env: gym.Env) -> Policy:
        return policy(env_id_, env) if callable(policy) and not hasattr(policy, "act") else policy

    register_method(MethodSpec(name, controller, build, "evaluate() policy object"))
    request = SweepRequest(
        env_id=env_id, methods=name, grid=",".join(format_value(float(v)) for v in values),
        param=param, episodes=episodes, out=Path(out), workers=1,
        envs_per_worker=envs_per_worker, seed=seed, resume=resume,
    )
    plan = prepare(request)
    args = {"env": env_id, "method": name, "grid": request.grid, "param": param,
            "episodes": episodes, "out": str(out), "seed": seed, "controller": controller}
    execute(plan, command=[sys.argv[0], "impact_eval.evaluate"], args=args)
    return pd.read_csv(Path(out) / "episodes.csv", keep_default_na=False)
