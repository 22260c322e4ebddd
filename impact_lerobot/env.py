"""The wrapped envs LeRobot makes: ``gym.make("gym_impact/Hammer-v1", settings=...)``.

``register_envs`` registers one id per task under ``GYM_NAMESPACE`` (LeRobot 0.4.4's
``make_env`` calls ``gym.make(f"gym_{type}/{task}")``), whose entry point ``make_lerobot_env``
makes our env (``IMPACT/<task>``, ending an episode at success as ``impact-eval`` does) and
wraps it in ``LeRobotObservations``: LeRobot's observation keys, our Box action space, and an
``info`` holding our scalar entries (``is_success`` among them).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import register, registry

from impact_control.errors import InvalidArgumentError
from impact_envs.tasks.bins import draw_in_bin
from impact_lerobot.features import ObservationPlan, observation_plan
from impact_lerobot.settings import GYM_NAMESPACE, TASKS, PluginSettings, mass_param

SEED_RANGE = 2**31
"""A bin's mass without a reset seed comes from a seed drawn below this."""


def scalar_info(info: dict[str, Any]) -> dict[str, Any]:
    """``info``'s bools, numbers and strings: the per-tick traces and wrench vectors are left
    out (a vector env stacks each info entry across its envs, and the trace lengths differ
    between a step and a reset)."""
    return {k: v for k, v in info.items()
            if isinstance(v, (bool, int, float, str, np.bool_, np.number))}


class LeRobotObservations(gym.Wrapper):
    """One of our envs as LeRobot reads it.

    Args:
        env: Our env, made with the settings' controller, preset, mass and observation mode.
        plan: How its observation dict becomes LeRobot's (``features.observation_plan``).
        settings: The plugin settings the env was made with (a ``mass_bin`` is drawn here at
            every reset).
    """

    def __init__(self, env: gym.Env, plan: ObservationPlan, settings: PluginSettings) -> None:
        super().__init__(env)
        self.plan, self.settings = plan, settings
        self.observation_space = plan.space(env.observation_space)
        self._param = mass_param(settings.task_class).name
        self._seeds = np.random.default_rng()

    def episode_mass(self, seed: int | None) -> float | None:
        """The mass [kg] a reset with ``seed`` sets: drawn in ``mass_bin`` from the seed
        (from a fresh seed without one); None without a bin (the env's fixed mass)."""
        if self.settings.mass_bin is None:
            return None
        lo, hi = self.settings.mass_bin
        draw_seed = int(self._seeds.integers(SEED_RANGE)) if seed is None else seed
        return draw_in_bin(float(lo), float(hi), draw_seed)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        mass = self.episode_mass(seed)
        if mass is not None:
            options = {**(options or {}), self._param: mass}
        obs, info = self.env.reset(seed=seed, options=options)
        return self.plan.convert(obs), scalar_info(info)

    def step(self, action: np.ndarray):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return self.plan.convert(obs), reward, terminated, truncated, scalar_info(info)


def make_lerobot_env(task: str, settings: PluginSettings | None = None,
                     render_mode: str | None = None) -> LeRobotObservations:
    """Entry point of ``gym_impact/<task>``: our env for ``settings`` (None: the defaults for
    ``task``), wrapped for LeRobot; ``render_mode="rgb_array"`` for LeRobot's videos."""
    settings = PluginSettings(task=task) if settings is None else settings
    if not isinstance(settings, PluginSettings) or settings.task != task:
        raise InvalidArgumentError(f"invalid settings {settings!r} for {GYM_NAMESPACE}/{task}; "
                                   f"valid: a PluginSettings with task={task!r}")
    params = {} if settings.object_mass is None else {
        mass_param(settings.task_class).name: settings.object_mass}
    env = gym.make(settings.env_id, controller=settings.controller,
                   controller_preset=settings.controller_preset, task_params=params,
                   observation=settings.observation, render_mode=render_mode,
                   terminate_on_success=True)
    return LeRobotObservations(env, observation_plan(settings), settings)


def register_envs() -> tuple[str, ...]:
    """Register ``gym_impact/<task>`` for every task (a second call is a no-op); returns the
    ids."""
    ids = []
    for task in TASKS:
        gym_id = f"{GYM_NAMESPACE}/{task}"
        if gym_id not in registry:
            register(id=gym_id, entry_point=make_lerobot_env, disable_env_checker=True,
                     max_episode_steps=PluginSettings(task=task).steps, kwargs={"task": task})
        ids.append(gym_id)
    return tuple(ids)
